"""Probe (2026-11-28, the fifth): with the default solver's W carrying S_t (the revolution
inertia factor) too, does S_t = 4 / 16 bring the default at oversample 1 down?  I.e. is its x1
error the balls' pocket mode (35 kHz) or the W-method's order on the forced response?

In the patched worktree of probe.py's docstring, after probe.py's S=1, St and Sr=St=16 runs:

    $P docs/probes/quasi_static/probe_pocket.py run [--scen 4 3 7 2] [--os 1 2]
    $P docs/probes/quasi_static/probe_pocket.py report
Output: QS_POCKET_OUT (/tmp/qs5_pocket).  References: QS_PROBE_OUT's S=1 (d32) and, as the model's
own RK4, its St4/St16/SrSt16 d128 runs (SrSt16 is S_r everywhere: = localized on healthy scenes only).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from bearing_sim_ros import bench
from bearing_sim_ros.physics import skidding
from cached import cached_run   # this folder (the script's) is first on the import path

OUT = Path(os.environ.get("QS_POCKET_OUT", "/tmp/qs5_pocket"))
REF = Path(os.environ.get("QS_PROBE_OUT", "/tmp/qs_probe"))
RATE, SETTLE, SECONDS = 15000.0, 0.2, 0.5
# label, S_r, S_t, near dt, own-model reference file label
SETTINGS = [("S1", 1.0, 1.0, -1.0, "S1_d32"), ("St4", 1.0, 4.0, -1.0, "St4_d128"),
            ("St16", 1.0, 16.0, -1.0, "St16_d128"), ("St16Sr16loc", 16.0, 16.0, 2e-4, "SrSt16_d128")]


def run_one(isc, label, sr, st, dt, os_):
    path = OUT / f"sc{isc}_{label}_x{os_}.npz"
    if path.exists():
        return
    scene = bench.SCENARIOS[isc].build()
    skidding.PROBE_SCALE_R, skidding.PROBE_SCALE_T, skidding.PROBE_NEAR_DT = sr, st, dt
    t0 = time.time()
    try:
        cfg = bench.Config(f"default x{os_}", "skidding default", "skidding",
                           (("solver", "default"), ("oversample", os_)))
        sim = cfg.simulator(scene, RATE, 0)
        sim.advance(int(SETTLE * RATE))
        p = sim._model.p
        for k in (skidding.P_NSTEP, skidding.P_NEVT, skidding.P_NREDO):
            p[k] = 0.0
        c0 = time.process_time()
        batch = sim.advance(int(SECONDS * RATE))
        cpu = time.process_time() - c0
        cnt = [p[skidding.P_NSTEP], p[skidding.P_NEVT], p[skidding.P_NREDO]]
    except Exception as exc:
        print(f"sc{isc} {label} x{os_}: FAILED {exc!r}", flush=True)
        np.savez(path, failed=repr(exc))
        return
    finally:
        skidding.PROBE_SCALE_R, skidding.PROBE_SCALE_T, skidding.PROBE_NEAR_DT = 1.0, 1.0, -1.0
    r = bench._as_run(batch, [cpu], SECONDS)
    ok = bool(np.all(np.isfinite(r.accel)))
    np.savez(path, accel=r.accel, cage_speed=r.cage_speed, cage_skid=r.cage_skid, forces=batch.contact_forces,
             us=cpu / (SECONDS * RATE) * 1e6, nstep=cnt[0], nevt=cnt[1], nredo=cnt[2], finite=ok, failed="")
    print(f"sc{isc} {label} x{os_}: {time.time() - t0:.1f} s wall, finite={ok}, "
          f"{cpu / (SECONDS * RATE) * 1e6:.1f} us/sample", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["run", "report"])
    ap.add_argument("--scen", type=int, nargs="+", default=[4, 3, 7, 2])
    ap.add_argument("--os", type=int, nargs="+", default=[1, 2])
    a = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    if a.cmd == "run":
        for isc in a.scen:
            for os_ in a.os:
                for label, sr, st, dt, _ in SETTINGS:
                    run_one(isc, label, sr, st, dt, os_)
        return
    print("| scenario | run | error % (rms / lines) vs S=1 | cage % | ev % | us/sample | vs own-model RK4 (rms / lines) % |")
    print("| --- | --- | --- | ---: | ---: | ---: | --- |")
    for isc in a.scen:
        scene = bench.SCENARIOS[isc].build()
        ref, _ = cached_run(REF / f"sc{isc}_S1_d32.npz")
        for os_ in a.os:
            for label, _sr, _st, _dt, own in SETTINGS:
                path = OUT / f"sc{isc}_{label}_x{os_}.npz"
                if not path.exists():
                    continue
                run, z = cached_run(path)
                if run is None or not bool(z["finite"]):
                    print(f"| sc{isc} | x{os_} {label} | FAILED/NaN | | | | |")
                    continue
                e = bench.errors(run, ref, scene, RATE)
                oc = "-"
                op = REF / f"sc{isc}_{own}.npz"
                if op.exists() and not (label == "St16Sr16loc" and scene.defects):
                    o, _ = cached_run(op)
                    eo = bench.errors(run, o, scene, RATE)
                    oc = f"{100 * eo['error']:.2f} ({100 * eo['rms']:.2f} / {100 * eo['lines']:.2f})"
                print(f"| {bench.SCENARIOS[isc].label} | x{os_} {label} | {100 * e['error']:.2f} "
                      f"({100 * e['rms']:.2f} / {100 * e['lines']:.2f}) | {100 * e['cage']:.3f} | "
                      f"{100 * z['nevt'] / max(z['nstep'], 1):.1f} | {float(z['us']):.1f} | {oc} |")


if __name__ == "__main__":
    sys.exit(main())
