"""Probe (2026-11-28, the second): is the error of a quasi-static ball-radial treatment made where a
ball meets a race defect, or everywhere?

Variant: S_r = 16 (see probe.py) on every ball except those "near" a race defect (|angle from the
defect centre| < half-width + dt x relative angular speed; ``physics.skidding.PROBE_NEAR_DT`` = dt
of ``skidding.patch``), which keep full inertia.  dt = 0: only inside the pit; 2e-4 / 1e-3 s: + the
angle travelled in 0.2 / 1 ms, on both sides.  The kernel counts the near balls per right-hand-side
evaluation over the timed 0.5 s: the near fraction.  Ball defects are not localised.

References (S=1 and Sr=16 everywhere, RK4 at hs/128) are probe.py's runs, copied from its output
folder (/tmp/qs_probe): run probe.py first.  In the patched worktree of probe.py's docstring:

    $P docs/probes/quasi_static/probe_local.py run [--checks] [--scen 6 2 1 3] [--extra]
    $P docs/probes/quasi_static/probe_local.py report      # the table of results_local.md
"""
from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from bearing_sim_ros import bench
from bearing_sim_ros.physics import skidding
from bearing_sim_ros.physics.defects import D_HALF, D_KIND, KIND_BALL, KIND_INNER
from cached import cached_run   # this folder (the script's) is first on the import path

OUT = Path(os.environ.get("QS_LOCAL_OUT", "/tmp/qs_local"))
SRC = Path(os.environ.get("QS_PROBE_OUT", "/tmp/qs_probe"))   # probe.py's runs
RATE, SETTLE, SECONDS, DIV = 15000.0, 0.2, 0.5, 128
SR = 16.0
# label, S_r, near dt (s; < 0: S_r everywhere)
VARIANTS = [("pit", SR, 0.0), ("0.2ms", SR, 2e-4), ("1ms", SR, 1e-3)]
# extra margin, run on CWRU only (run --scen 6 --extra): does the waveform residual shrink further?
EXTRA = [("5ms", SR, 5e-3)]
CHECKS = [("S1check", 1.0, -1.0),      # must equal the probe's S=1 bit for bit
          ("alwaysnear", SR, 10.0)]   # every ball near: must equal S=1 bit for bit


def fname(isc, label):
    return OUT / f"sc{isc}_{label}_d{DIV}.npz"


def copy_refs(isc):
    for lab in ("S1", "Sr16"):
        dst = fname(isc, lab)
        if not dst.exists():
            shutil.copy(SRC / f"sc{isc}_{lab}_d{DIV}.npz", dst)


def run_one(isc, label, sr, dt):
    path = fname(isc, label)
    if path.exists():
        return
    sc = bench.SCENARIOS[isc]
    scene = sc.build()
    hs = 1.0 / (4 * RATE)
    cfg = bench.Config(f"rk4 hs/{DIV}", "rk4", "skidding", (("solver", "rk4"), ("rk4_step", hs / DIV)))
    skidding.PROBE_SCALE_R, skidding.PROBE_NEAR_DT = sr, dt
    t0 = time.time()
    try:
        sim = cfg.simulator(scene, RATE, 0)
        sim.advance(int(SETTLE * RATE))            # as bench._timed_run
        p = sim._model.p
        p[skidding.P_NCNT] = p[skidding.P_NTOT] = 0.0
        batch = sim.advance(int(SECONDS * RATE))
        near = p[skidding.P_NCNT] / max(p[skidding.P_NTOT], 1.0)
    finally:
        skidding.PROBE_SCALE_R, skidding.PROBE_NEAR_DT = 1.0, -1.0
    r = bench._as_run(batch, [1.0], SECONDS)
    ok = bool(np.all(np.isfinite(r.accel)))
    np.savez(path, accel=r.accel, cage_speed=r.cage_speed, cage_skid=r.cage_skid,
             forces=batch.contact_forces, wall=time.time() - t0, finite=ok, near=near)
    print(f"{sc.label} | {label}: {time.time() - t0:.1f} s wall, finite={ok}, near {near:.4f}", flush=True)


def run(args):
    OUT.mkdir(parents=True, exist_ok=True)
    for isc in args.scen:
        copy_refs(isc)
        vs = VARIANTS if bench.SCENARIOS[isc].build().defects else VARIANTS[:1]   # healthy: one
        for label, sr, dt in vs + (EXTRA if args.extra else []):
            run_one(isc, label, sr, dt)
    if args.checks:
        for label, sr, dt in CHECKS:
            run_one(2, label, sr, dt)


def load(isc, label):
    run, z = cached_run(fname(isc, label))
    return run, (float(z["near"]) if "near" in z else None)


def analytic_near(scene, cage, dt):
    """Expected near fraction: each race defect covers 2 (half + dt x rel) of 2 pi for each ball."""
    p = skidding.parameters(scene)
    skidding.PROBE_PARAMS.clear()
    from bearing_sim_ros.physics.defects import defect_table
    tab = defect_table(scene.defects, scene.bearing)
    ws = 2 * math.pi * scene.shaft_hz
    tot = 0.0
    for row in tab:
        if int(row[D_KIND]) == KIND_BALL:
            continue
        rel = abs(ws - cage) if int(row[D_KIND]) == KIND_INNER else abs(cage)
        tot += min(1.0, (row[D_HALF] + dt * rel) / math.pi)
    del p
    return tot, tab


def report(args):
    print("| scenario | variant | rms % | lines % | cage % | waveform % | error % | near frac (analytic) |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for isc in args.scen:
        sc = bench.SCENARIOS[isc]
        scene = sc.build()
        base, _ = load(isc, "S1")
        labels = [("Sr16", "Sr=16 everywhere", -1.0)] + [(l, f"Sr=16 except {l}", dt) for l, _s, dt in VARIANTS + EXTRA]
        if isc == 2:
            labels += [(l, f"check {l}", dt) for l, _s, dt in CHECKS]
        for lab, name, dt in labels:
            if not fname(isc, lab).exists():
                continue
            r, near = load(isc, lab)
            e = bench.errors(r, base, scene, RATE)
            an, tab = analytic_near(scene, base.cage_speed, dt) if dt >= 0 else (0.0, None)
            nr = "-" if near is None else f"{near:.4f}"
            same = " (bit-identical to S=1)" if np.array_equal(r.accel, base.accel) else ""
            print(f"| {sc.label} | {name}{same} | {100 * e['rms']:.3f} | {100 * e['lines']:.3f} | "
                  f"{100 * e['cage']:.4f} | {100 * e['waveform']:.2f} | {100 * e['error']:.3f} | {nr} ({an:.4f}) |")
        if scene.defects:
            _, tab = analytic_near(scene, base.cage_speed, 0.0)
            ws = 2 * math.pi * scene.shaft_hz
            for row in tab:
                rel = abs(ws - base.cage_speed) if int(row[D_KIND]) == KIND_INNER else abs(base.cage_speed)
                print(f"|  {sc.label}: defect kind {int(row[D_KIND])} half {row[D_HALF] * 1e3:.2f} mrad, rel speed "
                      f"{rel:.1f} rad/s -> 0.2 ms {rel * 2e-4 * 1e3:.1f} mrad, 1 ms {rel * 1e-3 * 1e3:.1f} mrad, "
                      f"spacing {2 * math.pi / scene.bearing.balls * 1e3:.0f} mrad | | | | | | | |")
        # localized vs everywhere: does the rest change?
        sr16, _ = load(isc, "Sr16")
        for l, _s, _dt in VARIANTS:
            if fname(isc, l).exists():
                r, _ = load(isc, l)
                if np.array_equal(r.accel, sr16.accel):
                    print(f"|  {sc.label}: {l} bit-identical to Sr=16 everywhere | | | | | | | |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=("run", "report"))
    ap.add_argument("--scen", type=int, nargs="*", default=[6, 2, 1, 3])
    ap.add_argument("--extra", action="store_true", help="also the EXTRA margins")
    ap.add_argument("--checks", action="store_true", help="also the identity checks on scenario 2")
    args = ap.parse_args()
    (run if args.what == "run" else report)(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
