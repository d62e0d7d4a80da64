"""Probe (2026-11-28, the third): is the balls' radial mode what holds the default solver at two
steps per output sample?

In the stiff limit of that mode (S_r = 16 / 64 on the rho acceleration, full inertia for balls
within D_HALF + 0.2 ms of travel of a race defect: PROBE_NEAR_DT = 2e-4; see probe.py and
probe_local.py), with the default solver's W Jacobian carrying the same per-ball factor (via
aux[:, X_PAD], ``skidding.patch``), is the default (SplitROS2) within 1 % at one step per output
sample (oversample 1)?  Errors (bench.errors) against probe.py's S=1 reference runs
(QS_PROBE_OUT, /tmp/qs_probe: sc{i}_S1_d32.npz, read only; run ``probe.py run --div 32 --only S=1``
first).  Bench settings: settle 0.2 s, 0.5 s at 15 kHz, seed 0, sensor noise off.  Also ``nball``:
x1 with the balls and cage in k ROS2 sub-steps per structure step (``sim._model.nball = k``).

In the patched worktree of probe.py's docstring:

    $P docs/probes/quasi_static/probe_default.py run [--scen 4 7 6 2 1 3 0 5]    # ~1 min
    $P docs/probes/quasi_static/probe_default.py ref --scen 2 7 1 6    # each model's own RK4 (~6 min)
    $P docs/probes/quasi_static/probe_default.py nball --nball 2 [--scen 4 3 7 2]
    $P docs/probes/quasi_static/probe_default.py report
    # S=1 against the unpatched code: run ``unmod`` with PYTHONPATH at an unpatched checkout and
    # another NUMBA_CACHE_DIR, then ``compare`` in the patched one (both with --out DIR)
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

OUT = Path(os.environ.get("QS_DEFAULT_OUT", "/tmp/qs_default"))
REF = Path(os.environ.get("QS_PROBE_OUT", "/tmp/qs_probe"))
LOCAL = Path(os.environ.get("QS_LOCAL_OUT", "/tmp/qs_local"))      # probe_local.py's runs   # probe.py's runs
RATE, SETTLE, SECONDS = 15000.0, 0.2, 0.5
NEAR_DT = 2e-4
# label, S_r, near dt
SETTINGS = [("S1", 1.0, -1.0), ("Sr16loc", 16.0, NEAR_DT), ("Sr64loc", 64.0, NEAR_DT)]
OVERSAMPLES = (1, 2)


def cfg_of(os_):
    return bench.Config(f"default x{os_}", "skidding default", "skidding",
                        (("solver", "default"), ("oversample", os_)))


def fname(out, isc, label, os_):
    return out / f"sc{isc}_{label}_x{os_}.npz"


def rk4_cfg(div):
    hs = 1.0 / (4 * RATE)
    return bench.Config(f"rk4 hs/{div}", "rk4", "skidding", (("solver", "rk4"), ("rk4_step", hs / div)))


def own_ref(isc, label):
    """The model's own fine-step RK4 solution (S_r localized): from the earlier probes where they
    exist (healthy scenes: localized == everywhere), else from this probe's 'ref' command."""
    healthy = not bench.SCENARIOS[isc].build().defects
    cands = {"S1": [REF / f"sc{isc}_S1_d32.npz"],
             "Sr16loc": ([REF / f"sc{isc}_Sr16_d128.npz"] if healthy else [])
             + [LOCAL / f"sc{isc}_0.2ms_d128.npz", OUT / f"ref_sc{isc}_Sr16loc_d128.npz"],
             "Sr64loc": ([REF / f"sc{isc}_Sr64_d512.npz"] if healthy else [])
             + [OUT / f"ref_sc{isc}_Sr64loc_d512.npz"]}[label]
    for c in cands:
        if c.exists():
            return cached_run(c)[0]
    return None


def run_one(out, isc, label, sr, dt, os_, probe=True, nball=1, div=None):
    path = fname(out, isc, label, os_) if div is None else out / f"ref_sc{isc}_{label}_d{div}.npz"
    if nball != 1:
        path = out / f"sc{isc}_{label}_x{os_}_nball{nball}.npz"
    if path.exists():
        return
    sc = bench.SCENARIOS[isc]
    scene = sc.build()
    if probe:
        skidding.PROBE_SCALE_R, skidding.PROBE_NEAR_DT = sr, dt
    t0 = time.time()
    try:
        sim = (cfg_of(os_) if div is None else rk4_cfg(div)).simulator(scene, RATE, 0)
        if nball != 1:
            sim._model.nball = nball       # balls/cage in nball ROS2 steps per structure step
        sim.advance(int(SETTLE * RATE))
        p = sim._model.p
        if probe:
            for k in (skidding.P_NSTEP, skidding.P_NEVT, skidding.P_NREDO, skidding.P_NCNT, skidding.P_NTOT):
                p[k] = 0.0
        c0, th0 = time.process_time(), time.thread_time()
        batch = sim.advance(int(SECONDS * RATE))
        cpu, thr = time.process_time() - c0, time.thread_time() - th0
        cnt = ([p[skidding.P_NSTEP], p[skidding.P_NEVT], p[skidding.P_NREDO],
                p[skidding.P_NCNT] / max(p[skidding.P_NTOT], 1.0)] if probe else [0, 0, 0, 0])
        failed = ""
    except Exception as exc:
        print(f"{sc.label} | {label} x{os_}: FAILED {exc!r}", flush=True)
        np.savez(path, failed=repr(exc))
        return
    finally:
        if probe:
            skidding.PROBE_SCALE_R, skidding.PROBE_NEAR_DT = 1.0, -1.0
    r = bench._as_run(batch, [cpu], SECONDS)
    ok = bool(np.all(np.isfinite(r.accel)))
    nsamp = int(SECONDS * RATE)
    np.savez(path, accel=r.accel, cage_speed=r.cage_speed, cage_skid=r.cage_skid,
             forces=batch.contact_forces, cpu=cpu, thr=thr, us=cpu / nsamp * 1e6, usthr=thr / nsamp * 1e6,
             nstep=cnt[0], nevt=cnt[1], nredo=cnt[2], near=cnt[3], finite=ok, failed=failed,
             wall=time.time() - t0)
    print(f"{sc.label} | {label} x{os_}: {time.time() - t0:.1f} s wall, finite={ok}, "
          f"{cpu / nsamp * 1e6:.1f} us/sample, steps {cnt[0]:.0f} event {cnt[1]:.0f} redo {cnt[2]:.0f}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["run", "report", "unmod", "compare", "ref", "nball"])
    ap.add_argument("--scen", type=int, nargs="+", default=[4, 7, 6, 2, 1, 3, 0, 5])
    ap.add_argument("--out", default=str(OUT))
    ap.add_argument("--os", type=int, nargs="+", default=list(OVERSAMPLES))
    ap.add_argument("--nball", type=int, default=2)
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.cmd == "run":
        for isc in a.scen:
            for label, sr, dt in SETTINGS:
                for os_ in a.os:
                    run_one(out, isc, label, sr, dt, os_)
    elif a.cmd == "ref":            # own-model RK4 references: Sr16loc hs/128, Sr64loc hs/512
        for isc in a.scen:
            for label, sr, dt in SETTINGS[1:]:
                if own_ref(isc, label) is None:
                    run_one(out, isc, label, sr, dt, 0, div=128 if sr <= 16 else 512)
    elif a.cmd == "nball":          # x1 with the balls in 2 sub-steps per structure step
        for isc in a.scen:
            for label, sr, dt in SETTINGS:
                run_one(out, isc, label, sr, dt, 1, nball=a.nball)
    elif a.cmd == "unmod":          # the unpatched code (PYTHONPATH at an unpatched checkout): no probe attributes
        for isc in a.scen:
            for os_ in a.os:
                run_one(out, isc, "unmod", 1.0, -1.0, os_, probe=False)
    elif a.cmd == "compare":        # S1 here vs unmod in --out
        for isc in a.scen:
            for os_ in a.os:
                x, _ = cached_run(fname(OUT, isc, "S1", os_))
                u, _ = cached_run(fname(out, isc, "unmod", os_))
                zx, zu = np.load(fname(OUT, isc, "S1", os_)), np.load(fname(out, isc, "unmod", os_))
                same = (np.array_equal(x.accel, u.accel) and np.array_equal(zx["forces"], zu["forces"])
                        and x.cage_speed == u.cage_speed and x.cage_skid == u.cage_skid)
                print(f"sc{isc} x{os_}: S1 bit-identical to unmodified: {same}")
    else:
        print("| scenario | run | error % | rms % | lines % | cage % | event steps % (redo %) | us/sample "
              "| vs own-model RK4: error (rms / lines) % |")
        print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for isc in a.scen:
            sc = bench.SCENARIOS[isc]
            scene = sc.build()
            ref, _ = cached_run(REF / f"sc{isc}_S1_d32.npz")
            variants = [(os_, label, fname(out, isc, label, os_)) for os_ in a.os for label, _s, _d in SETTINGS]
            variants += [(f"1 nball{nb}", label, out / f"sc{isc}_{label}_x1_nball{nb}.npz") for nb in (2, 4, 8) for label, _s, _d in SETTINGS]
            for os_, label, path in variants:
                if not path.exists():
                    continue
                run, zz = cached_run(path)
                if run is None or not bool(zz["finite"]):
                    print(f"| {sc.label} | x{os_} {label} | FAILED/NaN | | | | | |")
                    continue
                e = bench.errors(run, ref, scene, RATE)
                own = own_ref(isc, label)
                if own is None:
                    ocol = "-"
                else:
                    eo = bench.errors(run, own, scene, RATE)
                    ocol = f"{100 * eo['error']:.2f} ({100 * eo['rms']:.2f} / {100 * eo['lines']:.2f})"
                print(f"| {sc.label} | x{os_} {label} | {100 * e['error']:.2f} | {100 * e['rms']:.2f} | "
                      f"{100 * e['lines']:.2f} | {100 * e['cage']:.3f} | "
                      f"{100 * zz['nevt'] / max(zz['nstep'], 1):.1f} ({100 * zz['nredo'] / max(zz['nstep'], 1):.1f}) | "
                      f"{float(zz['us']):.1f} | {ocol} |")


if __name__ == "__main__":
    sys.exit(main())
