"""The kinematic tier's centrifugal gate measured between F_c / Q_max 0.004 and 0.02 (and a few
points below, and the two catalog bearings with each other's radial clearance): the tables of
docs/fidelity_rms_gap.md, "The gate measured between 0.005 and 0.015".  Run from the repository:
``python docs/probes/centrifugal_gate/probe.py [--seeds N] [--settle S] [--only BEARING]`` (with
``--seeds 3`` about 6 minutes on 2 cores once compiled, most of it the skidding reference; its
runs are cached in $CENTRIFUGAL_GATE_CACHE, default /tmp/centrifugal_gate_probe, so a second run
takes seconds).  probe.txt is its output with ``--seeds 3``.

Each operating point is healthy, sensor noise off, measured as ``bearing-sim bench
--calibrate-fidelity`` measures (seed 1, 0.6 s after 0.3 s of settling, 15 kHz): the skidding
tier's ``solver="reference"`` against the kinematic tier with massless balls
(``physics.kinematic.CENTRIFUGAL_GATE`` set to inf in this process) and with the balls held out
by their centrifugal force (the gate set to 0).  Both axes the scenes' sensors read (accel_x
horizontal, accel_y vertical, the load's direction); the mean cage speed's error beside them.
``--seeds N`` repeats the kinematic runs at seeds 1..N (the reference at seed 1) and gives the
spread of the errors; ``--settle S`` moves the window (``--settle 0.9``: 0.9-1.5 s); ``--only
BEARING`` keeps one bearing's points ("ER-16K", "6205", "61820-size", "6000-size").
"""
import hashlib
import importlib.util
import math
import os
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

import bearing_sim_ros.physics.kinematic as kinematic
from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.fidelity import bearing_load, clearance_ratio
from bearing_sim_ros.limits import RPM, InputLimits
from bearing_sim_ros.scene import shipped_scenes

_spec = importlib.util.spec_from_file_location("custom_bearings", "docs/probes/custom_bearings/probe.py")
custom = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(custom)

FS, SETTLE, SECONDS, SEED = 15000.0, 0.3, 0.6, 1
CACHE = Path(os.environ.get("CENTRIFUGAL_GATE_CACHE", "/tmp/centrifugal_gate_probe"))

# (bearing, rpm, downward load N): each bearing at two or three loads, the speeds put F_c / Q_max
# at about 0.004-0.02 on each load (the ratio goes as speed^2 / load)
POINTS = [
    ("ER-16K", 3000, 200), ("ER-16K", 3500, 200), ("ER-16K", 4000, 200), ("ER-16K", 4500, 200),
    ("ER-16K", 5000, 200),
    ("ER-16K", 1600, 50), ("ER-16K", 1900, 50), ("ER-16K", 2200, 50), ("ER-16K", 2500, 50), ("ER-16K", 2900, 50),
    ("ER-16K", 7000, 1000), ("ER-16K", 8000, 1000), ("ER-16K", 9200, 1000), ("ER-16K", 10500, 1000),
    ("ER-16K", 12000, 1000),
    ("6205", 2000, 200), ("6205", 2500, 200), ("6205", 3000, 200),
    ("6205", 6000, 1000), ("6205", 8000, 1000), ("6205", 9500, 1000),
    ("61820-size", 1200, 300), ("61820-size", 1520, 300), ("61820-size", 1900, 300),
    ("61820-size", 4000, 3000), ("61820-size", 5000, 3000), ("61820-size", 6300, 3000),
    ("6000-size", 7000, 100), ("6000-size", 10000, 100), ("6000-size", 13000, 100),
    ("6000-size", 25000, 1000), ("6000-size", 34000, 1000), ("6000-size", 43000, 1000),
]
# below 0.004, where the force helped the small-clearance bearings above: how far down it keeps
# helping them (the ER-16K's 2000 rpm / 200 N, 0.0023, and the 6205's 1750 rpm / 2000 N, 0.0002,
# are calibration points)
BELOW = [
    ("ER-16K", 2000, 200), ("6205", 1750, 2000), ("6205", 5000, 2000), ("6205", 3000, 1000), ("6205", 4500, 1000),
    ("6205", 1000, 200), ("6205", 1500, 200), ("61820-size", 2000, 3000), ("61820-size", 3000, 3000),
    ("61820-size", 600, 300), ("61820-size", 900, 300), ("6000-size", 3500, 100), ("6000-size", 5000, 100),
    ("6000-size", 15000, 1000),
]
# the two catalog bearings (the same 7.94 mm balls) with each other's radial clearance: whether the
# ER-16K's different answer is its clearance (the 6205's support, 1e7 N/m, takes k_s C_r = 450 N at
# 45 um, so its points here are at 1000 and 2000 N)
SWAPPED = [
    ("ER-16K@10um", 3000, 200), ("ER-16K@10um", 4000, 200), ("ER-16K@10um", 5000, 200),
    ("ER-16K@10um", 1900, 50), ("ER-16K@10um", 2500, 50), ("ER-16K@10um", 8000, 1000), ("ER-16K@10um", 10500, 1000),
    ("6205@45um", 6000, 1000), ("6205@45um", 8000, 1000), ("6205@45um", 9500, 1000),
    ("6205@45um", 8000, 2000), ("6205@45um", 11000, 2000),
]
LARGE_PLAY = 0.005      # radial clearance over ball diameter: the ER-16K's 0.0057 against 0.0008-0.0013
SHIPPED_BASE = {"ER-16K": "er16k_skidding", "6205": "b6205_ball_outer"}


def build(which, rpm, load):
    """The healthy scene of ``which`` (a shipped bearing by its scene, "@<C_r>um" appended for
    another radial clearance, or a custom_bearings one) at
    ``rpm`` and ``load`` (N, downwards), sensor noise off."""
    which, _at, clearance = which.partition("@")
    if which in SHIPPED_BASE:
        s = load_scene(SHIPPED_BASE[which])
        s = replace(s, defects=(), shaft_speed=rpm * RPM, radial_load=(0.0, -float(load)))
        if clearance:       # "@10um": the bearing with that radial clearance
            s = replace(s, bearing=s.bearing.with_clearance(float(clearance.removesuffix("um")) * 1e-6))
    else:
        s = custom.scene(which, rpm, load)
    return custom.quiet(s)


def run(s, tier, gate=None, seed=SEED, **kwargs):
    """(accel x, accel y RMS in m/s^2, mean cage speed in rad/s, whether the balls carried F_c)
    over SECONDS after SETTLE; ``gate`` replaces ``CENTRIFUGAL_GATE`` and the small-play gate
    ``CENTRIFUGAL_SMALL_PLAY_GATE`` for this run (inf: massless balls, 0: the force everywhere)."""
    names = ("CENTRIFUGAL_GATE", "CENTRIFUGAL_SMALL_PLAY_GATE")
    saved = {n: getattr(kinematic, n) for n in names}
    if gate is not None:
        for n in names:
            setattr(kinematic, n, gate)
    try:
        sim = Simulator(s, sample_rate=FS, fidelity=tier, seed=seed, **kwargs)
        sim.advance(int(SETTLE * FS))
        batch = sim.advance(int(SECONDS * FS))
        held = sim.centrifugal
    finally:
        for n, v in saved.items():
            setattr(kinematic, n, v)
    a = batch.accel
    return (float(np.sqrt(np.mean(a[:, 0] ** 2))), float(np.sqrt(np.mean(a[:, -1] ** 2))),
            float(np.mean(batch.cage_speed)), held)


def reference(s):
    """``run`` of the skidding reference, cached by the scene and the window."""
    key = hashlib.sha1(repr((s, FS, SETTLE, SECONDS, SEED)).encode()).hexdigest()[:16]
    path = CACHE / f"{key}.npy"
    if path.exists():
        return tuple(np.load(path))
    out = run(s, "skidding", solver="reference")[:3]
    CACHE.mkdir(parents=True, exist_ok=True)
    np.save(path, np.array(out))
    return out


def shipped_ratios():
    """F_c / Q_max of every shipped scene at its operating point (which side of the gate it is)."""
    out = []
    for name in shipped_scenes():
        s = load_scene(name)
        out.append(f"{name} {kinematic.centrifugal_ratio(s, s.radial_load, s.shaft_speed):.4f}")
    print("shipped scenes, F_c / Q_max: " + ", ".join(out), flush=True)


def main(seeds=1, only=None):
    shipped_ratios()
    table(POINTS, seeds, only)
    print("\nbelow 0.004:")
    table(BELOW, seeds, only)
    print("\nthe ER-16K and the 6205 with each other's radial clearance:")
    table(SWAPPED, seeds, only)


def table(points, seeds, only):
    """Print the markdown table of ``points`` (those of bearing ``only`` if given)."""
    print(f"window: seed {SEED}, {SECONDS} s after {SETTLE} s, {FS:.0f} Hz, sensor noise off, healthy; errors "
          f"kinematic / reference - 1 (massless -> with F_c); W the balls' share of the load, C0 the static rating"
          + (f"; errors as mean [min, max] over seeds 1..{seeds}" if seeds > 1 else ""))
    print("| point | F_c / Q_max | W / C0 | C_r / D | reference RMS x, y (m/s^2) | accel_y error | accel_x error "
          "| cage speed error |")
    print("|---|---|---|---|---|---|---|---|")
    better = {}     # large play or small -> [points where the force's |error| is smaller: y, x; points]
    for which, rpm, load in points:
        if only and which.partition("@")[0] != only:
            continue
        s = build(which, rpm, load)
        ratio = kinematic.centrifugal_ratio(s, s.radial_load, s.shaft_speed)
        w = bearing_load(s, s.radial_load)
        c0 = InputLimits(s.bearing, s.shaft_weight).static_capacity
        rx, ry, rc = reference(s)
        errs = {}
        for label, gate in (("massless", math.inf), ("force", 0.0)):
            rows = []
            for seed in range(1, seeds + 1):
                kx, ky, kc, held = run(s, "kinematic", gate, seed=seed)
                assert held == (label == "force"), (which, rpm, load, label, held)
                rows.append((ky / ry - 1.0, kx / rx - 1.0, kc / rc - 1.0))
            errs[label] = np.array(rows)

        def cell(col, fmt="{:+.2%}"):
            parts = []
            for label in ("massless", "force"):
                e = errs[label][:, col]
                text = fmt.format(e.mean())
                if seeds > 1:
                    text += f" [{fmt.format(e.min())}, {fmt.format(e.max())}]"
                parts.append(text)
            return " -> ".join(parts)

        print(f"| {which} {rpm} rpm {load} N | {ratio:.4f} | {w / c0:.3f} | {clearance_ratio(s):.4f} | "
              f"{rx:.4g}, {ry:.4g} | {cell(0)} | {cell(1)} | {cell(2, '{:+.3%}')} |", flush=True)
        smaller = np.abs(errs["force"].mean(0)) < np.abs(errs["massless"].mean(0))
        count = better.setdefault(clearance_ratio(s) >= LARGE_PLAY, [0, 0, 0])
        count[0] += int(smaller[0])
        count[1] += int(smaller[1])
        count[2] += 1
    for large, (y, x, n) in sorted(better.items()):
        print(f"C_r / D {'at least' if large else 'below'} {LARGE_PLAY}: the force's error smaller at {y} of {n} "
              f"points on accel_y, {x} of {n} on accel_x")


if __name__ == "__main__":
    args = sys.argv[1:]
    if "--settle" in args:      # a later window: whether a point's figures are the window's
        SETTLE = float(args[args.index("--settle") + 1])
    main(int(args[args.index("--seeds") + 1]) if "--seeds" in args else 1,
         args[args.index("--only") + 1] if "--only" in args else None)
