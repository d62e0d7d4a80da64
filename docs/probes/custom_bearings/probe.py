"""Bearings other than the shipped ones: the numbers of README "Limitations" ("Bearings of other
sizes and speeds").  Four custom bearings typed into scenes as a user would (README "A bearing of
your own"); run from the repository: ``python docs/probes/custom_bearings/probe.py [part ...]``,
parts ``alias``, ``band``, ``rms``, ``fidelity``, ``step``, ``shipped_step`` (all by default; a few minutes on 2 cores).
"""
import math
import sys
from dataclasses import replace

import numpy as np

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.analysis.envelope import diagnose, envelope_spectrum, line_at
from bearing_sim_ros.fidelity import select_tier
from bearing_sim_ros.limits import RPM, InputLimits
from bearing_sim_ros.scene import scene_from_dict, shipped_scenes

BEARINGS = {   # geometry (mm, um) and a structure of a plausible size for each (kg, N/m, N s/m)
    "6000-size": ({"balls": 7, "ball_diameter_mm": 4.762, "pitch_diameter_mm": 18.0, "radial_clearance_um": 4.0,
                   "width_mm": 8.0}, (0.3, 2e6, 300), (0.8, 5e7, 1500)),
    "6-ball": ({"balls": 6, "ball_diameter_mm": 6.35, "pitch_diameter_mm": 22.0, "radial_clearance_um": 5.0,
                "width_mm": 9.0}, (0.5, 3e6, 400), (1.5, 8e7, 2000)),
    "6220-size": ({"balls": 10, "ball_diameter_mm": 25.4, "pitch_diameter_mm": 140.0, "radial_clearance_um": 15.0,
                   "width_mm": 34.0}, (60.0, 5e7, 2e4), (150.0, 2e9, 1e5)),
    "61820-size": ({"balls": 20, "ball_diameter_mm": 7.938, "pitch_diameter_mm": 112.5, "radial_clearance_um": 10.0,
                    "width_mm": 13.0}, (10.0, 1e7, 4000), (20.0, 5e8, 2e4)),
}
FS = 15000.0


def scene(which, rpm, load, defects=()):
    geometry, shaft, pedestal = BEARINGS[which]
    part = lambda m, k, c: {"mass": m, "stiffness": k, "damping": c}  # noqa: E731
    return scene_from_dict({
        "name": which, "bearing": dict(geometry, name=which),
        "structure": {"shaft": part(*shaft), "pedestal": part(*pedestal),
                      "resonator": {"mass": 0.05 if geometry["balls"] in (10, 20) else 0.02,
                                    "frequency_hz": {10: 3500, 20: 3800}.get(geometry["balls"], 4000),
                                    "damping_ratio": 0.04}},
        "operating_point": {"shaft_speed_rpm": rpm, "radial_load": [0.0, -float(load)]},
        "lubrication": {"viscosity": 0.04, "pressure_viscosity": 2.0e-8},
        "sensor": {"noise_density": 3.4e-5, "range": 49033}, "defects": [dict(d) for d in defects]})


def quiet(s):
    """``s`` without sensor noise."""
    return replace(s, sensor=replace(s.sensor, noise_density=0.0))


def signal(s, tier, seconds, skip, oversample=None, **kwargs):
    sim = Simulator(s, fidelity=tier, seed=0, oversample=oversample, **kwargs)
    return sim.advance(int(seconds * FS)).accel[int(skip * FS):, -1]


def alias():
    """The kinematic tier's event sub-steps at one per chain sample: lines at the beat of the
    pit's position on that grid (60 kHz mod BPFO) where balls cross a pit in few chain samples."""
    outer = lambda w: [{"kind": "outer", "width_mm": w, "depth_mm": 0.2, "clock": 6}]  # noqa: E731
    for label, s, seconds in [("61820-size 2 mm pit 2000 rpm 1853 N", scene("61820-size", 2000, 1853, outer(2.0)), 2.0),
                              ("61820-size 0.5 mm pit 7111 rpm 1853 N", scene("61820-size", 7111, 1853, outer(0.5)), 1.0),
                              *((name, load_scene(name), 2.0) for name in ("er16k_outer_race", "er16k_inner_race",
                                                                          "cwru_6205_or007_6"))]:
        ff = s.fault_frequencies()
        kind = s.defects[0].kind
        f0 = ff["bpfo" if kind == "outer" else "bpfi"]
        b = s.bearing
        w_rel = abs(b.cage_speed(s.shaft_speed) - (s.shaft_speed if kind == "inner" else 0.0))
        crossing = s.defects[0].width / (w_rel * 0.5 * b.pitch_diameter) * 4 * FS
        beat = abs(60000.0 - round(60000.0 / f0) * f0)
        print(f"{label}: crossed in {crossing:.1f} chain samples, {kind} line {f0:.1f} Hz, beat {beat:.1f} Hz")
        for tier, oversample in (("kinematic", None), ("kinematic", 16), ("skidding", None)):
            y = signal(s, tier, seconds, 0.2, oversample)
            f, spec = envelope_spectrum(y, FS, max_freq=3000, segment=None)
            verdict = diagnose(y, FS, ff)
            print(f"  {tier} x{oversample or 'default'}: RMS {np.sqrt(np.mean(y ** 2)):.3g} m/s^2, line "
                  f"x{line_at(f, spec, f0).prominence:.0f}, at the beat x{line_at(f, spec, beat).prominence:.1f}, "
                  f"verdict {verdict['verdict']} {({k: round(v) for k, v in verdict['scores'].items()})}")


def band():
    """The envelope band 2-5 kHz: an inner-race line inside it is not demodulated."""
    for rpm in (10000, 20000, 30000, 40000, 50000):
        s = scene("6000-size", rpm, 300, [{"kind": "inner", "width_mm": 1.0, "depth_mm": 0.1}])
        verdict = diagnose(signal(s, "kinematic", 1.0, 0.2), FS, s.fault_frequencies())
        print(f"6000-size inner pit {rpm} rpm 300 N: BPFI {s.fault_frequencies()['bpfi']:.0f} Hz, verdict "
              f"{verdict['verdict']} {({k: round(v) for k, v in verdict['scores'].items()})}")


def rms():
    """The tiers' RMS at the speed limit under 2 x C0 (healthy, 0.2 s after 0.1 s): the kinematic
    tier against the skidding tier's reference solver and its default one (docs/fidelity_rms_gap.md)."""
    for which in BEARINGS:
        limits = InputLimits(scene(which, 1000, 0).bearing, scene(which, 1000, 0).shaft_weight)
        s = scene(which, math.floor(limits.max_speed / RPM), math.floor(limits.max_load - limits.shaft_weight - 1))
        sel = select_tier(s, "auto", s.shaft_speed, s.radial_load, s.fidelity_tolerance)
        k, ref, r = (np.sqrt(np.mean(signal(s, tier, 0.3, 0.1, **kw) ** 2)) for tier, kw in
                     (("kinematic", {}), ("skidding", {"solver": "reference"}), ("skidding", {})))
        print(f"{which} {s.shaft_speed / RPM:.0f} rpm {-s.radial_load[1]:.0f} N: RMS kinematic {k:.3g}, skidding "
              f"reference {ref:.3g} m/s^2 ({k / ref - 1:+.0%}), skidding default solver {r:.3g} ({r / ref - 1:+.0%} "
              f"off its reference); auto: {sel.tier}, estimate {sel.estimated_error:.2%}")


def fidelity():
    """The fidelity estimate against the skidding tier's cage skid (mean over 1 s after 0.5 s)."""
    for which, rpm, load in [("6000-size", 50000, 10), ("6000-size", 30000, 50), ("6000-size", 3000, 20),
                             ("6220-size", 1000, 200), ("6220-size", 3000, 1000), ("6220-size", 6000, 5000),
                             ("61820-size", 8000, 10), ("61820-size", 8000, 200), ("61820-size", 3000, 50),
                             ("6-ball", 40000, 300), ("6-ball", 10000, 100)]:
        s = scene(which, rpm, load)
        sel = select_tier(s, "auto", s.shaft_speed, s.radial_load, s.fidelity_tolerance)
        cage = Simulator(s, fidelity="skidding", seed=0).advance(int(1.5 * FS)).cage_speed[int(0.5 * FS):]
        skid = 1.0 - cage.mean() / s.bearing.cage_speed(s.shaft_speed)
        print(f"{which} {rpm} rpm {load} N: skid index {sel.skid_index:.3g}, estimate {sel.estimated_error:.2%}, "
              f"skidding tier's cage skid {skid:.2%} (x{sel.estimated_error / skid:.2f}); auto: {sel.tier}")


def step_errors(s, label):
    """Print the kinematic tier's default step against 32 steps per sample on ``s`` (1 s after
    0.2 s): the waveform's error (RMS of the difference over the reference's RMS) and the RMS
    value's (the metric of README "Kinematic tier: speed and accuracy")."""
    runs = {}
    for oversample in (None, 1, 2, 4, 32):
        sim = Simulator(s, fidelity="kinematic", seed=0, oversample=oversample)
        y = sim.advance(int(1.2 * FS)).accel[int(0.2 * FS):, -1]
        runs[oversample] = (y, sim.oversample, sim._model.bearing_mode)
    ref = runs.pop(32)[0]
    error = {k: np.sqrt(np.mean((y - ref) ** 2) / np.mean(ref ** 2)) for k, (y, _o, _m) in runs.items()}
    rms = {k: abs(np.sqrt(np.mean(y ** 2) / np.mean(ref ** 2)) - 1) for k, (y, _o, _m) in runs.items()}
    print(f"{label}: bearing mode {runs[None][2]:.0f} Hz, default x{runs[None][1]}; waveform error x1 "
          f"{error[1]:.2%}, x2 {error[2]:.2%}, x4 {error[4]:.2%}; RMS error x1 {rms[1]:.2%}, x2 {rms[2]:.2%}, "
          f"x4 {rms[4]:.2%}")


def step():
    """The kinematic tier's default step (x1 below a bearing mode of 1.5 kHz, else x2) on these
    bearings, sensor noise off (``step_errors``)."""
    outer = [{"kind": "outer", "width_mm": 0.5, "depth_mm": 0.1, "clock": 6}]
    for which, rpm, load, defects in [("6000-size", 3000, 300, []), ("6000-size", 3000, 3000, []),
                                      ("6-ball", 3000, 500, outer), ("6220-size", 1500, 150000, []),
                                      ("61820-size", 1500, 30000, [])]:
        step_errors(quiet(scene(which, rpm, load, defects)), f"{which} {rpm} rpm {load} N{' outer pit' if defects else ''}")


def shipped_step():
    """The same on the shipped scenes at their operating points, sensor noise off: the comparison
    README's item makes.  Scenes with ``random_slip`` (the CWRU defect scenes, seed 001's 6307)
    draw their slip per step, so their waveforms differ at every step count (no convergence)."""
    for name in shipped_scenes():
        step_errors(quiet(load_scene(name)), name)


if __name__ == "__main__":
    parts = {"alias": alias, "band": band, "rms": rms, "fidelity": fidelity, "step": step,
             "shipped_step": shipped_step}
    for name in sys.argv[1:] or parts:
        parts[name]()
