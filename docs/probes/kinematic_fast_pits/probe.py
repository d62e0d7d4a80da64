"""The kinematic tier's false envelope lines on fast pits (docs/kinematic_fast_pits.md): where a
ball's load leaves and returns within a few chain samples, the event sub-steps (one per chain
sample) see it at a few nodes only, and the impact's height beats with the pit's phase on that grid.

For each case: the pit's profile, the crossing and the edge (the travel over which the pit's drop
grows from 0 to the most loaded ball's Hertz deflection, film left out) in chain samples at 60 kHz,
then for the kinematic tier at its default step, with its event sub-steps alone on a 240 kHz grid
(a throwaway built here, not in the package), at ``oversample`` 16 and 32, and for the skidding
tier: the envelope line at the beat of the 60 kHz grid with the fault line and at the fault line,
their height ratio, the impacts' energy against the grid phase, the RMS and its difference from
the skidding tier's, the waveform's difference from the default's, the envelope verdict.  1.2 s
at 15 kHz, the first 0.2 s left out.  Run from the repository (a few minutes on 2 cores):
``python docs/probes/kinematic_fast_pits/probe.py [case ...]`` (case names below; all by default).
"""
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np

# the custom bearings' scenes, typed as a user would (docs/probes/custom_bearings/probe.py)
_spec = importlib.util.spec_from_file_location(
    "custom_bearings_probe", Path(__file__).resolve().parents[1] / "custom_bearings" / "probe.py")
_custom = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_custom)
scene = _custom.scene

from bearing_sim_ros import Simulator, load_scene  # noqa: E402
from bearing_sim_ros.analysis.envelope import diagnose, envelope_spectrum, line_at  # noqa: E402
from bearing_sim_ros.physics.defects import (D_DEPTH, D_HALF, D_HMAX_O, D_HMAX_I, D_PROFILE,  # noqa: E402
                                             D_RAMP_O, D_RAMP_I, D_RHO_O, D_RHO_I, _profile_drop,
                                             defect_table)
from bearing_sim_ros.scene import load_yaml, scene_from_dict  # noqa: E402

FS = 15000.0
GRID = 60000.0        # the chain's rate at the default step: one event sub-step per chain sample
SECONDS, SKIP = 1.2, 0.2
PROFILES = {0: "geometric", 1: "rectangular", 2: "half_sine", 3: "piecewise"}


def pit(width, depth=0.2, profile=None, kind="outer"):
    d = {"kind": kind, "width_mm": width, "depth_mm": depth, "clock": 6}
    if profile:
        d["profile"] = profile
    return [d]


def shipped(name, profile=None, rpm=None, load=None):
    """A shipped scene, its pit's profile, speed or load changed as a user's scene file would."""
    s = load_scene(name)
    raw = load_yaml(s.source_text)
    for d in raw["defects"]:
        if profile:
            d["profile"] = profile
    if rpm is not None:
        raw["operating_point"]["shaft_speed_rpm"] = rpm
    if load is not None:
        raw["operating_point"]["radial_load"] = [0.0, -float(load)]
    return scene_from_dict(raw, name=name)


CASES = {
    "61820-2mm": lambda: scene("61820-size", 2000, 1853, pit(2.0)),
    "61820-2mm-185N": lambda: scene("61820-size", 2000, 185, pit(2.0)),
    "61820-2mm-500rpm": lambda: scene("61820-size", 500, 1853, pit(2.0)),
    "61820-0.5mm-7111rpm": lambda: scene("61820-size", 7111, 1853, pit(0.5)),
    "er16k-outer": lambda: shipped("er16k_outer_race"),
    "er16k-outer-6400rpm": lambda: shipped("er16k_outer_race", rpm=6400),
    "er16k-outer-half_sine": lambda: shipped("er16k_outer_race", profile="half_sine"),
    "er16k-inner": lambda: shipped("er16k_inner_race"),
    "cwru-outer": lambda: shipped("cwru_6205_or007_6"),
}


def edge_and_crossing(s, q_max):
    """(profile name, crossing, edge) of the scene's first (race) defect, in chain samples at
    GRID: the pit's angular width, and the angle over which its drop grows from 0 to the Hertz
    deflection of a ball of ``q_max`` N, over the balls' angular speed against that race."""
    b = s.bearing
    row = defect_table(s.defects, b)[0]
    inner = s.defects[0].kind == "inner"
    radius = 0.5 * (b.inner_race_diameter if inner else b.outer_race_diameter)
    rho, hmax, ramp = ((row[D_RHO_I], row[D_HMAX_I], row[D_RAMP_I]) if inner
                       else (row[D_RHO_O], row[D_HMAX_O], row[D_RAMP_O]))
    half = row[D_HALF]
    delta = (q_max / b.combined_stiffness) ** (2.0 / 3.0)
    u = np.linspace(half, 0.0, 20001)[1:]
    drop = np.array([_profile_drop(int(row[D_PROFILE]), x, half, radius, rho, hmax, ramp, row[D_DEPTH])
                     for x in u])
    reach = np.flatnonzero(drop >= delta)
    edge = (half - u[reach[0]]) if reach.size else half
    w_rel = abs(b.cage_speed(s.shaft_speed) - (s.shaft_speed if inner else 0.0))
    per_sample = w_rel / GRID
    return PROFILES[int(row[D_PROFILE])], 2 * half / per_sample, edge / per_sample, delta


def grid_modulation(y, f0, grid):
    """How much the impacts' energy follows the pit's phase on a grid of ``grid`` Hz: y cut into
    periods of the fault line (1 / f0 s each, one impact in each), each period's energy e_k, fit
    by a + sum_n (b_n cos + c_n sin)(2 pi n phi_k), n = 1..3, with phi_k = frac(grid k / f0) the
    grid phase of impact k (the phase offset is in the fit); returns the fitted modulation's RMS
    over a and the spread std(e) / mean(e) of all periods.  Floor-independent, unlike a line's
    prominence."""
    per = FS / f0
    n = int(len(y) / per) - 1
    e = np.array([np.sum(y[int(round(k * per)):int(round((k + 1) * per))] ** 2) / per for k in range(n)])
    phi = np.mod(grid * np.arange(n) / f0, 1.0)
    cols = [np.ones(n)] + [f(2 * np.pi * h * phi) for h in (1, 2, 3) for f in (np.cos, np.sin)]
    a = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(a, e, rcond=None)
    fitted = a[:, 1:] @ coef[1:]
    return float(np.sqrt(np.mean(fitted ** 2)) / coef[0]), float(np.std(e) / np.mean(e))


class _FinerEvents:
    """Throwaway, in this probe only: the kinematic model built with ``chain_oversample`` 16 at
    the default step, so that its event sub-steps fall on a 240 kHz grid (the chain runs there too)
    while its plain steps stay one or two per sample."""

    def __enter__(self):
        import bearing_sim_ros.physics.kinematic as kin
        self.kin, self.cls = kin, kin.KinematicModel
        cls = self.cls

        def build(*args, **kwargs):
            kwargs.setdefault("chain_oversample", 16)
            return cls(*args, **kwargs)
        kin.KinematicModel = build
        return self

    def __exit__(self, *exc):
        self.kin.KinematicModel = self.cls


def run(name):
    s = CASES[name]()
    ff = s.fault_frequencies()
    kind = s.defects[0].kind
    f0 = ff["bpfo" if kind == "outer" else "bpfi"]
    beat = abs(GRID - round(GRID / f0) * f0)
    rows = {}
    for label, tier, oversample in (("kin", "kinematic", None), ("kin events/240k", "kinematic", None),
                                    ("kin x16", "kinematic", 16), ("kin x32", "kinematic", 32),
                                    ("skid", "skidding", None)):
        if label == "kin events/240k":
            with _FinerEvents():
                sim = Simulator(s, fidelity=tier, seed=0, oversample=oversample)
        else:
            sim = Simulator(s, fidelity=tier, seed=0, oversample=oversample)
        batch = sim.advance(int(SECONDS * FS))
        y = batch.accel[int(SKIP * FS):, -1]
        f, spec = envelope_spectrum(y, FS, max_freq=3000, segment=None)
        at_beat, at_f0 = line_at(f, spec, beat), line_at(f, spec, f0)
        if label == "kin":
            q_max = float(np.max(batch.contact_forces))
            y_kin = y
        rows[label] = (float(np.sqrt(np.mean(y ** 2))), at_beat.prominence, at_f0.prominence,
                       at_beat.height / at_f0.height, *grid_modulation(y - y.mean(), f0, GRID),
                       float(np.sqrt(np.mean((y - y_kin) ** 2) / np.mean(y_kin ** 2))),
                       diagnose(y, FS, ff)["verdict"])
    profile, crossing, edge, delta = edge_and_crossing(s, q_max)
    print(f"{name}: {profile}, {s.shaft_speed * 30 / math.pi:.0f} rpm, {-s.radial_load[1]:.0f} N, "
          f"ball load {q_max:.0f} N (delta {delta * 1e6:.1f} um); crossed in {crossing:.1f}, edge "
          f"{edge:.2f} chain samples; {kind} line {f0:.1f} Hz, beat {beat:.1f} Hz")
    skid_rms = rows["skid"][0]
    for label, (r, pb, pf, ratio, mod, spread, diff, verdict) in rows.items():
        print(f"  {label}: beat x{pb:.1f}, fault line x{pf:.0f}, beat/fault height {ratio:.2%}; impact "
              f"energy against the 60 kHz phase {mod:.2%} (spread {spread:.1%}); RMS {r:.4g} m/s^2 "
              f"({r / skid_rms - 1:+.1%} vs skidding); waveform off kin by {diff:.2%}; verdict {verdict}")
    sys.stdout.flush()


if __name__ == "__main__":
    for case in sys.argv[1:] or CASES:
        run(case)
