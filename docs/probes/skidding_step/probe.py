"""The skidding tier's default solver against its reference on bearings other than the shipped
ones, and what predicts its error: the numbers of docs/solvers.md, "The default's step follows
the ball pass" (2026-11-30).  Run from the repository:
``python docs/probes/skidding_step/probe.py [part ...]``, parts ``grid`` (the four custom
bearings of docs/probes/custom_bearings at 0.1-1 x their speed limit and 0.02-1 x their load
limit, about 15 minutes on 2 cores) and ``shipped`` (config/scenes and the bench's scenes at their
operating points, about 5 minutes) and ``sixteen`` (oversample 16 and 32 where 8 was
furthest off, against the references ``grid`` printed) and ``check`` (the default at the step its
step check chooses, every point of ``grid`` and ``shipped``, against the references of
measured.txt: docs/solvers.md, "The default's step chosen by measuring", about 3 minutes).  Every run is healthy unless the scene has defects, sensor
noise off, accel_y RMS over 0.2 s after 0.1 s of settling; ``oversample`` is given explicitly,
so the figures are the fixed steps' whatever the default chooses.
"""
import importlib.util
import math
import sys

import numpy as np

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.bench import SCENARIOS, CALIBRATION_POINTS
from bearing_sim_ros.limits import RPM, InputLimits
from bearing_sim_ros.physics.kinematic import bearing_mode_hz
from bearing_sim_ros.physics.structure import structure_system
from bearing_sim_ros.scene import shipped_scenes

_spec = importlib.util.spec_from_file_location("custom_bearings", "docs/probes/custom_bearings/probe.py")
custom = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(custom)
BEARINGS, FS, scene, quiet = custom.BEARINGS, custom.FS, custom.scene, custom.quiet

SETTLE, SECONDS = 0.1, 0.2


def rms_of(sim):
    y = sim.advance(int((SETTLE + SECONDS) * FS)).accel[int(SETTLE * FS):, -1]
    return float(np.sqrt(np.mean(y ** 2)))


def features(s, sim):
    """The candidate predictors at the scene's operating point: the outer race's ball-pass
    frequency over the output rate (ball passes per output sample), the bearing mode (Hz) of the
    structure linearised where the skidding tier starts, and the most loaded ball's radial
    contact frequency (Hz, inner and outer Hertz contacts in series against the ball's mass)."""
    m = sim._model
    bpfo = abs(s.fault_frequencies()["bpfo"])
    mode = bearing_mode_hz(structure_system(s, m.kb)[0], s.structure)
    return {"bpfo_per_sample": bpfo / FS, "mode_hz": mode, "contact_hz": m.contact_frequency()}


def row(label, s):
    s = quiet(s)
    out = {}
    for m in (2, 4, 8):
        sim = Simulator(s, fidelity="skidding", seed=0, oversample=m)
        if m == 2:
            f = features(s, sim)
        out[m] = rms_of(sim)
    ref = rms_of(Simulator(s, fidelity="skidding", seed=0, solver="reference"))
    err = "  ".join(f"x{m} {out[m] / ref - 1:+7.2%}" for m in out)
    print(f"{label:44s} ref {ref:9.4g}  {err}  ball passes/sample {f['bpfo_per_sample']:.4f}  "
          f"mode {f['mode_hz']:6.0f} Hz  contact {f['contact_hz'] / 1e3:5.1f} kHz", flush=True)


def grid_points():
    """(label, scene) of the four custom bearings at 0.1-1 x their speed limit and 0.02-1 x their
    load limit."""
    for which in BEARINGS:
        lim = InputLimits(scene(which, 1000, 0).bearing, scene(which, 1000, 0).shaft_weight)
        for fs in (0.1, 0.25, 0.5, 1.0):
            for fl in (0.02, 0.1, 0.5, 1.0):
                rpm = math.floor(fs * lim.max_speed / RPM)
                load = math.floor(fl * (lim.max_load - lim.shaft_weight - 1))
                yield f"{which} {rpm} rpm {load} N", scene(which, rpm, load)


def shipped_points():
    """(label, scene) of config/scenes and the bench's scenes at their operating points."""
    for name in shipped_scenes():
        yield name, load_scene(name)
    for sc in {sc.label: sc for sc in SCENARIOS + CALIBRATION_POINTS}.values():
        yield "bench " + sc.label, sc.build()


def grid():
    for label, s in grid_points():
        row(label, s)


def shipped():
    for label, s in shipped_points():
        row(label, s)


def sixteen():
    for which, rpm, load, ref in [("6000-size", 55555, 466, 8.98), ("6000-size", 55555, 2331, 22.54),
                                  ("6000-size", 55555, 4662, 34.27), ("6000-size", 27777, 93, 3.791),
                                  ("6-ball", 45454, 710, 19.68), ("6-ball", 4545, 7106, 0.3749)]:
        s = quiet(scene(which, rpm, load))
        print(f"{which} {rpm} rpm {load} N: " + "  ".join(
            f"x{m} {rms_of(Simulator(s, fidelity='skidding', seed=0, oversample=m)) / ref - 1:+.2%}"
            for m in (16, 32)), flush=True)


def check():
    """The default with no ``oversample``: the steps per sample its check chose, the check's
    estimates, the construction time and the error against measured.txt's reference (the same
    noise-off accel_y RMS), and whether it warned."""
    import re
    import time
    import warnings
    from pathlib import Path

    refs = {}
    for line in (Path(__file__).parent / "measured.txt").read_text().splitlines():
        m = re.match(r"(.+?)\s+ref\s+(\S+)\s+x2", line)
        if m:
            refs[m[1].strip()] = float(m[2])
    points = list(grid_points()) + list(shipped_points())
    for label, s in points:
        s = quiet(s)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t0 = time.perf_counter()
            sim = Simulator(s, fidelity="skidding", seed=0)
            built = time.perf_counter() - t0
        est = " ".join(f"x{m} {e:.2%}" for m, e in sim._model.step_estimates.items()) or "not checked"
        print(f"{label:44s} x{sim.oversample:<2d} {rms_of(sim) / refs[label] - 1:+7.2%}  built {built:5.2f} s  "
              f"screen {sim._model.step_screen:.3f}  estimates {est}"
              f"{'  WARNS' if caught else ''}", flush=True)


if __name__ == "__main__":
    parts = {"grid": grid, "shipped": shipped, "sixteen": sixteen, "check": check}
    for part in sys.argv[1:] or parts:
        parts[part]()
