"""Probe (2026-11-28): how far would eliminating the balls' fast modes move the bench's metrics?

Question: how much do the bench's outputs change when the balls' radial inertia (ball on its two
Hertz contacts, 30-63 kHz) or revolution inertia (ball against the cage-pocket spring) is made
much smaller, all else equal -- i.e. is a quasi-static treatment of those modes within 1 %?
The answer and the table: docs/solvers.md, "Measured: what eliminating the balls' fast modes
would cost"; every row: results.md beside this file.

The scale factors are ``physics.skidding.PROBE_SCALE_R`` / ``PROBE_SCALE_T`` of ``skidding.patch``
beside this file (the whole acceleration of rho, resp. theta', times S: inertia m_b / S, forces
unchanged), read into the parameter vector when a model is built.  Only explicit RK4 is used
("reference" = RK4 at 1/32 of an internal sample, or "rk4" at a finer fixed step), since the
default's Jacobian does not carry the factors.  Runs and metrics are the bench's
(bench._timed_run, bench.errors: settle 0.2 s, 0.5 s at 15 kHz, sensor noise off, seed 0).

Rerun (about 25 minutes on one core; finished runs are kept in QS_PROBE_OUT and skipped):

    git worktree add /tmp/qs HEAD && cd /tmp/qs   # once physics/skidding.py has moved on: the
    git apply docs/probes/quasi_static/skidding.patch   # commit that added this folder instead
    export PYTHONPATH=/tmp/qs NUMBA_CACHE_DIR=/tmp/numba_qs; P=/path/to/.venv/bin/python
    $P docs/probes/quasi_static/probe.py run --div 32 --only S=1
    $P docs/probes/quasi_static/probe.py run --div 128 --only S=1 Sr=4 Sr=16 St=4 St=16 Sr=St=16
    $P docs/probes/quasi_static/probe.py run --div 512 --only Sr=64
    $P docs/probes/quasi_static/probe.py report

(PYTHONPATH puts the patched package ahead of the venv's editable install of the main checkout:
``$P -c "import bearing_sim_ros; print(bearing_sim_ros.__file__)"`` from /tmp says which one.)
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from bearing_sim_ros import bench
from bearing_sim_ros.physics import skidding
from cached import cached_run   # this folder (the script's) is first on the import path

OUT = Path(os.environ.get("QS_PROBE_OUT", "/tmp/qs_probe"))
RATE, SETTLE, SECONDS = 15000.0, 0.2, 0.5          # bench.study(quick=False)
SETTINGS = [("S=1", 1.0, 1.0), ("Sr=4", 4.0, 1.0), ("Sr=16", 16.0, 1.0), ("Sr=64", 64.0, 1.0),
            ("St=4", 1.0, 4.0), ("St=16", 1.0, 16.0), ("St=64", 1.0, 64.0), ("Sr=St=16", 16.0, 16.0)]


def config(div: int, hs: float) -> bench.Config:
    if div == 32:
        return bench.Config("reference", "reference", "skidding", (("solver", "reference"),))
    return bench.Config(f"rk4 hs/{div}", "rk4", "skidding", (("solver", "rk4"), ("rk4_step", hs / div)))


def fname(isc: int, label: str, div: int) -> Path:
    return OUT / f"sc{isc}_{label.replace('=', '')}_d{div}.npz"


def run(args) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    hs = 1.0 / (4 * RATE)     # internal sample: 4 x the output rate (SkiddingModel.internal_rate)
    settings = [s for s in SETTINGS if args.only is None or s[0] in args.only]
    for isc in args.scen:
        sc = bench.SCENARIOS[isc]
        scene = sc.build()
        for div in args.div:
            for label, sr, st in settings:
                path = fname(isc, label, div)
                if path.exists():
                    continue
                skidding.PROBE_SCALE_R, skidding.PROBE_SCALE_T = sr, st
                cfg = config(div, hs)
                t0 = time.time()
                try:
                    cpu, batch = bench._timed_run(cfg, scene, RATE, SETTLE, SECONDS)
                except Exception as exc:          # RK4 beyond its stability limit
                    print(f"{sc.label} | {label} d{div}: FAILED {exc}", flush=True)
                    np.savez(path, failed=str(exc))
                    continue
                finally:
                    skidding.PROBE_SCALE_R = skidding.PROBE_SCALE_T = 1.0
                r = bench._as_run(batch, [cpu], SECONDS)
                ok = bool(np.all(np.isfinite(r.accel)))
                np.savez(path, accel=r.accel, cage_speed=r.cage_speed, cage_skid=r.cage_skid,
                         forces=batch.contact_forces, wall=time.time() - t0, finite=ok)
                print(f"{sc.label} | {label} d{div}: {time.time() - t0:.1f} s wall, finite={ok}, "
                      f"cage {r.cage_speed:.4f} rad/s, rms {np.sqrt(np.mean(r.accel ** 2)):.5g}", flush=True)


def load(isc, label, div):
    path = fname(isc, label, div)
    if not path.exists():
        return None
    run, z = cached_run(path)
    return "failed" if run is None else (run, z["forces"])


def mode_frequencies(scene, forces) -> tuple:
    """(radial, pocket) mode frequency (Hz) of the most loaded ball: radial on the two Hertz
    contacts in parallel, k = 1.5 K^(2/3) Q^(1/3) each (Q from the median over time of the largest
    load over the balls), and tangential on the pocket spring."""
    p = skidding.parameters(scene)
    nb = int(p[skidding.P_NB])
    qi = float(np.median(forces[:, :nb].max(axis=1)))
    qo = float(np.median(forces[:, nb:].max(axis=1)))
    kt = lambda k, q: 1.5 * k ** (2.0 / 3.0) * max(q, 0.0) ** (1.0 / 3.0)  # noqa: E731
    mb = p[skidding.P_MB]
    fr = math.sqrt((kt(p[skidding.P_KI], qi) + kt(p[skidding.P_KO], qo)) / mb) / (2 * math.pi)
    fp = math.sqrt(p[skidding.P_KC] / mb) / (2 * math.pi)
    return fr, fp, qi, qo


def divs_of(isc, label):
    return sorted(int(p.stem.rsplit("_d", 1)[1]) for p in OUT.glob(f"sc{isc}_{label.replace('=', '')}_d*.npz"))


def report(args) -> None:
    """Every (setting, step) against S=1 at its finest step (S=1 is the same at hs/32 and hs/128:
    the step check rows); the step check: each setting's coarser steps against its finest."""
    rows, lines = [], []
    for isc in args.scen:
        sc = bench.SCENARIOS[isc]
        scene = sc.build()
        bdivs = divs_of(isc, "S=1")
        if not bdivs:
            continue
        base, forces = load(isc, "S=1", bdivs[-1])
        fr, fp, qi, qo = mode_frequencies(scene, forces)
        lines.append(f"{sc.label}: max Qi {qi:.1f} N, Qo {qo:.1f} N -> radial mode {fr / 1e3:.1f} kHz, "
                     f"pocket mode {fp / 1e3:.1f} kHz")
        for label, _sr, _st in SETTINGS:
            divs = divs_of(isc, label)
            for div in divs:
                r = load(isc, label, div)
                if label == "S=1" and div == bdivs[-1]:
                    continue
                if r == "failed":
                    rows.append({"scenario": sc.label, "div": div, "setting": label, "failed": True})
                    continue
                e = bench.errors(r[0], base, scene, RATE)
                rows.append({"scenario": sc.label, "div": div, "setting": label + " vs S=1", **e})
            fin = load(isc, label, divs[-1]) if divs else None
            for div in divs[:-1]:
                r = load(isc, label, div)
                if r == "failed" or fin == "failed":
                    continue
                e = bench.errors(r[0], fin[0], scene, RATE)
                rows.append({"scenario": sc.label, "div": f"{div} vs {divs[-1]}", "setting": label, **e})
        a, b = divs_of(isc, "Sr=16"), divs_of(isc, "Sr=64")
        if a and b:
            ra, rb = load(isc, "Sr=16", a[-1]), load(isc, "Sr=64", b[-1])
            if "failed" not in (ra, rb):
                e = bench.errors(ra[0], rb[0], scene, RATE)
                rows.append({"scenario": sc.label, "div": f"{a[-1]}/{b[-1]}", "setting": "Sr=16 vs Sr=64", **e})
    print("\n".join(lines))
    print()
    print("| scenario | step hs/ | setting | rms % | lines % | cage % | skid pp | waveform % | error % |")
    print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in rows:
        if r.get("failed"):
            print(f"| {r['scenario']} | {r['div']} | {r['setting']} | diverged | | | | | |")
            continue
        print(f"| {r['scenario']} | {r['div']} | {r['setting']} | {100 * r['rms']:.3f} | {100 * r['lines']:.3f} | "
              f"{100 * r['cage']:.4f} | {r['skid']:.4f} | {100 * r['waveform']:.2f} | {100 * r['error']:.3f} |")
    (OUT / "report.json").write_text(json.dumps(rows, indent=1, default=float))


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=("run", "report"))
    ap.add_argument("--scen", type=int, nargs="*", default=list(range(len(bench.SCENARIOS))))
    ap.add_argument("--div", type=int, nargs="*", default=[32])
    ap.add_argument("--only", nargs="*", default=None, help="setting labels, e.g. S=1 Sr=16")
    args = ap.parse_args()
    (run if args.what == "run" else report)(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
