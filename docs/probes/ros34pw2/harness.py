"""Probe harness: ROS34PW2 in place of ROS2 for the balls and cage of the default split solver.

    export PYTHONPATH=<a worktree with skidding.patch applied> NUMBA_CACHE_DIR=<a cache of its own>
    P=/work/main/.venv/bin/python
    $P probe/harness.py ref   [--scen 4 3 1 2 7 6]       # references (cached in OUT/ref_sc{i}.npz)
    $P probe/harness.py bits  [--scen 4 2]              # patched engine at ROS2 vs the unpatched engine
    $P probe/harness.py run   [--scen ...] [--rounds 3] # errors and CPU time, interleaved
    $P probe/harness.py report
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics as stats
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bearing_sim_ros import bench                       # noqa: E402
from bearing_sim_ros.physics import integrators         # noqa: E402
from tableaus import engine_form                        # noqa: E402

OUT = Path(os.environ.get("PROBE_OUT", str(Path(__file__).resolve().parent / "out")))
RATE, SETTLE, SECONDS, SEED = 15000.0, 0.2, 0.5, 0


def tab(name):
    if name == "ros2":           # the engine's own ROS2 arrays (bit-for-bit check)
        kind, a, b, c, g, gamma = integrators.ROS2().arrays()
        return dict(a=a, g=g, b=b, c=np.ascontiguousarray(c, dtype=float),
                    tt=np.array([gamma, -gamma]), gamma=gamma)
    T = engine_form(name)
    out = {}
    for k in ("a", "g"):
        out[k] = np.ascontiguousarray(np.tril(T[k], -1))      # round-off above the diagonal: 0
    for k in ("b", "c", "tt"):
        out[k] = np.ascontiguousarray(T[k], dtype=float)
    out["gamma"] = float(T["gamma"])
    return out


def stage_props(m, c, spath):
    """Transposed held-input propagators (Phi(c_i h), G0(c_i h)) of every stage, for the step and
    for the event sub-step (the patched engine's ``spath`` 1: the structure's exact path)."""
    from bearing_sim_ros.physics.skidding import propagators, structure_system
    A, B, _c, _d = structure_system(m.scene, m.kb)
    out = []
    for h in (m.hstep, m.hstep / m.nsub):
        ph = np.zeros((c.size, 10, 10))
        g0 = np.zeros((c.size, 4, 10))
        for i, ci in enumerate(c):
            if ci > 0.0:
                P, G0, _g1, _g2 = propagators(A, B, h, ci * h)
                ph[i], g0[i] = P.T, G0.T
        out += [np.ascontiguousarray(ph), np.ascontiguousarray(g0)]
    return tuple(out) + (int(spath),)


def make_sim(scene, os_, method):
    """method: 'orig' (the unpatched engine) or a tableau name for the patched engine, with
    '+exact' for the structure on its exact held-input path at the stages (else the straight one)."""
    cfg = bench.Config(f"default x{os_}", "skidding default", "skidding",
                       (("solver", "default"), ("oversample", os_)))
    sim = cfg.simulator(scene, RATE, SEED)
    if method != "orig":
        # "NAME[+exact][/SUB]": NAME's tableau in plain steps (the structure at its stages on the
        # straight path, or its exact held-input path), SUB's (default NAME's) in event sub-steps
        # (always the straight path there)
        main, _, sub = method.partition("/")
        name, _, path = main.partition("+")
        m = sim._model
        m.probe_tab = tab(name)
        assert m.nball == 1
        m.probe_path = stage_props(m, m.probe_tab["c"], path == "exact")
        ts = tab(sub or name)
        m.probe_sub = (ts["a"], ts["g"], ts["b"], ts["c"], ts["tt"], ts["gamma"])
    return sim


def ref_path(isc):
    return OUT / f"ref_sc{isc}.npz"


def reference(isc):
    p = ref_path(isc)
    if p.exists():
        z = np.load(p)
        return bench.Run(accel=z["accel"], cage_speed=float(z["cage_speed"]), cage_skid=float(z["cage_skid"]),
                         cpu=1.0, repeats=[])
    sc = bench.SCENARIOS[isc]
    t0 = time.time()
    cpu, batch = bench._timed_run(bench.reference_config(), sc.build(), RATE, SETTLE, SECONDS, SEED)
    r = bench._as_run(batch, [cpu], SECONDS)
    np.savez(p, accel=r.accel, cage_speed=r.cage_speed, cage_skid=r.cage_skid, cpu=cpu)
    print(f"{sc.label}: reference in {time.time() - t0:.0f} s wall", flush=True)
    return r


def timed(scene, os_, method):
    sim = make_sim(scene, os_, method)
    sim.advance(int(SETTLE * RATE))
    m = sim._model
    if method != "orig":
        m.probe_cnt[:] = 0.0
    t0 = time.thread_time()
    batch = sim.advance(int(SECONDS * RATE))
    cpu = time.thread_time() - t0
    cnt = m.probe_cnt.copy() if method != "orig" else None
    return cpu, batch, cnt


SETTINGS = [("orig", 1), ("orig", 2), ("ros34pw2", 1), ("ros34pw2", 2), ("ros34pw2+exact", 1),
            ("ros34pw2+exact", 2), ("ros34pw2/ros2", 1), ("ros34pw2+exact/ros2", 1),
            ("ros34pw2+exact/ros2", 2), ("ra3pw", 1), ("ros2", 1), ("ros2", 2), ("ros2+exact", 1)]


def cmd_run(scens, rounds):
    for isc in scens:
        sc = bench.SCENARIOS[isc]
        scene = sc.build()
        ref = reference(isc)
        for meth, os_ in SETTINGS:       # compile / warm up outside the timing
            make_sim(scene, os_, meth).advance(30)
        cpus = {s: [] for s in SETTINGS}
        res = {}
        for _ in range(rounds):
            for s in SETTINGS:
                if s[0] in ("ros2", "ros2+exact") and _ > 0:
                    continue                 # the patched engine at ROS2: once (events, overhead)
                cpu, batch, cnt = timed(scene, s[1], s[0])
                cpus[s].append(cpu)
                if s not in res:
                    run = bench._as_run(batch, [cpu], SECONDS)
                    ok = bool(np.all(np.isfinite(run.accel)))
                    err = bench.errors(run, ref, scene, RATE) if ok else {"error": float("nan")}
                    res[s] = dict(err={k: float(v) for k, v in err.items()}, finite=ok,
                                  hash=hashlib.sha1(np.ascontiguousarray(batch.accel).tobytes()).hexdigest()[:12],
                                  steps=None if cnt is None else float(cnt[0]),
                                  sub=None if cnt is None else float(cnt[1]))
        for s in SETTINGS:
            res[s]["cpu_med"] = stats.median(cpus[s])
            res[s]["cpus"] = cpus[s]
        rec = {f"{m}_x{o}": v for (m, o), v in res.items()}
        (OUT / f"run_sc{isc}.json").write_text(json.dumps(rec, indent=1))
        base = res[("orig", 2)]["cpu_med"]
        print(f"== {sc.label}")
        for s in SETTINGS:
            r = res[s]
            ev = "" if r["steps"] is None else f" substepped {r['sub'] / max(r['steps'], 1):.1%} of {r['steps']:.0f}"
            print(f"  {s[0]:>20} x{s[1]}: error {r['err']['error']:.2%} (rms {r['err'].get('rms', 0):.2%} "
                  f"lines {r['err'].get('lines', 0):.2%} cage {r['err'].get('cage', 0):.3%})  cpu {r['cpu_med'] * 1e3:.1f} ms "
                  f"({r['cpu_med'] / base:.2f}x orig x2) hash {r['hash']}{ev}", flush=True)


def cmd_bits(scens, seconds=0.3):
    for isc in scens:
        sc = bench.SCENARIOS[isc]
        scene = sc.build()
        for os_ in (1, 2):
            a = make_sim(scene, os_, "orig").advance(int(seconds * RATE)).accel
            b = make_sim(scene, os_, "ros2").advance(int(seconds * RATE)).accel
            h = lambda x: hashlib.sha1(np.ascontiguousarray(x).tobytes()).hexdigest()[:12]
            print(f"{sc.label} x{os_}: orig {h(a)} patched-ROS2 {h(b)} max|diff| {np.max(np.abs(a - b)):.3e} "
                  f"(max|a| {np.max(np.abs(a)):.3e})", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["ref", "bits", "run"])
    ap.add_argument("--scen", type=int, nargs="+", default=[4, 3, 1, 2, 7, 6])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--settings", nargs="+", default=None)
    a = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    if a.cmd == "ref":
        for isc in a.scen:
            reference(isc)
    elif a.cmd == "bits":
        cmd_bits(a.scen)
    else:
        cmd_run(a.scen, a.rounds)


if __name__ == "__main__":
    main()
