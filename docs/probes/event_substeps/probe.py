"""What would a larger default event sub-step count cost and change?  The numbers of
docs/solvers.md, "Event sub-steps: 6, 12, 24, 48 per internal sample, measured" (2026-11-30).
Run from the repository: ``python docs/probes/event_substeps/probe.py [--oversample M]
[--counts 6,12,...] [--scenes i,j,...] [points] [bench] [cost] [share]`` (all parts at x2 with
N = 6, 12, 24, 48 by default, about 3 minutes on the shared 2-core machine; ``--oversample``
and ``--counts`` apply to points, bench and share, ``--scenes`` picks indices of
``bench.SCENARIOS`` for the bench part; the output in ``probe.txt`` beside it).

Nothing in the package changes: the count is set by wrapping ``skidding.method_for`` (the
function ``SkiddingModel._set_step`` builds its method with) so that the default's ``SplitROS2``
gets ``event_substeps = N`` before ``_linearise`` reads it (``self.nsub = event_substeps * kk``).
The reference (RK4) is untouched.  N = 6 is the shipped default.

- ``points``: hM's three light-load points (docs/probes/skidding_step/spread.py, its point
  definitions), sensor noise off, 0.1 s settle + 0.2 s, accel_y RMS against a fresh
  ``solver="reference"`` run, at x2 (2 steps per output sample; ``--oversample``), signed.
- ``bench``: the bench's eight scenarios (``bench.SCENARIOS``) in the bench's own window (0.2 s
  settle + 0.5 s) and metrics (``bench.errors``: rms of accel_y, and error = max(rms, lines,
  cage)) against a fresh reference, at x2 (as docs/probes/structure_damping/probe.py does; the
  N = 6 column is the README's x2 column).
- ``cost``: CPU time of the simulating thread per output sample over 1 s after 0.1 s settle, x2
  with the four counts and x4 with N = 6 and 12 alternating in this process (5 rounds, median),
  as a ratio to x2 with N = 6, on the eight bench scenes and the three points.
- ``share``: the share of x2 steps that are sub-stepped (an event), 0.2 s after 0.1 s settle,
  read from the kernel's own ``counters[3]`` (1 after a sub-stepped step, 2 after a plain one)
  after each output sample (advance(1): the last of the sample's M steps is read), N = 6 and
  N = 48.
"""
import importlib.util
import statistics
import sys
import time

import numpy as np

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros import bench
import bearing_sim_ros.physics.skidding as sk

_spec = importlib.util.spec_from_file_location("custom_bearings", "docs/probes/custom_bearings/probe.py")
custom = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(custom)
FS, scene, quiet = custom.FS, custom.scene, custom.quiet
# its accel_y helpers (loading it sets nothing: its variants need its patch, not applied here)
_spec = importlib.util.spec_from_file_location("structure_damping", "docs/probes/structure_damping/probe.py")
damping = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(damping)
rms, accel = damping.rms, damping.accel

POINTS = [   # spread.py's first three
    ("61820-size 8888 rpm 739 N", lambda: scene("61820-size", 8888, 739)),
    ("b6307_seed001", lambda: load_scene("b6307_seed001")),
    ("6-ball 4545 rpm 142 N", lambda: scene("6-ball", 4545, 142)),
]
COUNTS = (6, 12, 24, 48)
M = 2   # steps per output sample
SCENES = None   # indices into bench.SCENARIOS for the bench part (all: None)
COST = [(2, 6), (2, 12), (2, 24), (2, 48), (4, 6), (4, 12)]   # (M, N), ratios to the first

_shipped_method_for = sk.method_for
_count = [6]


def _method_for(*args, **kwargs):
    method = _shipped_method_for(*args, **kwargs)
    if hasattr(method, "event_substeps"):
        method.event_substeps = _count[0]
    return method


sk.method_for = _method_for


def setting(n):
    _count[0] = n


def points():
    for label, make in POINTS:
        s = quiet(make())
        setting(6)
        ref = rms(accel(s, 0.1, 0.2, solver="reference")[0])
        cells = []
        for n in COUNTS:
            setting(n)
            y, sim = accel(s, 0.1, 0.2, oversample=M)
            assert sim._model.nsub == n * sim._model.kk, (sim._model.nsub, n)
            cells.append(f"{n} {rms(y) / ref - 1:+.2%}")
        print(f"# {label}: reference {ref:.5g} m/s^2 (0.1 s + 0.2 s); x{M} with N event sub-steps: "
              + "  ".join(cells), flush=True)
    setting(6)


def bench_part():
    settle, seconds = 0.2, 0.5
    print(f"# bench scenarios, {settle} s + {seconds} s, bench.errors against a fresh reference, x{M}: "
          "rms / error (signed rms in brackets)", flush=True)
    for i, sc in enumerate(bench.SCENARIOS):
        if SCENES is not None and i not in SCENES:
            continue
        s = sc.build()
        setting(6)
        ref = bench.run_config(bench.reference_config(), s, FS, settle, seconds, 1)
        rr = rms(ref.accel)
        cells = []
        for n in COUNTS:
            setting(n)
            cfg = bench.Config(f"x{M}", "skidding default", "skidding", (("oversample", M),))
            r = bench.run_config(cfg, s, FS, settle, seconds, 1)
            e = bench.errors(r, ref, s, FS)
            cells.append(f"{n}: {e['rms']:.2%} / {e['error']:.2%} ({rms(r.accel) / rr - 1:+.2%})")
        print(f"  {sc.label:34s} " + "  ".join(cells), flush=True)
    setting(6)


def cases():
    return [(sc.label, sc.build()) for sc in bench.SCENARIOS] + [(label, quiet(make())) for label, make in POINTS]


def cost():
    n_settle, n = int(0.1 * FS), int(1.0 * FS)
    print("# cost per output sample, (M, N) / (x2, 6) (CPU time of the thread, 1 s after 0.1 s, "
          "the settings alternating, median of 5)", flush=True)
    for label, s in cases():
        times = {c: [] for c in COST}
        for _ in range(5):
            for m, c in COST:
                setting(c)
                sim = Simulator(s, fidelity="skidding", seed=0, oversample=m)
                sim.advance(n_settle)
                t = time.thread_time()
                sim.advance(n)
                times[(m, c)].append((time.thread_time() - t) / n)
        base = statistics.median(times[COST[0]])
        print(f"  {label:34s} x2 N=6 {base * 1e6:.1f} us/sample  " + "  ".join(
            f"x{m} N={c}: {statistics.median(times[(m, c)]) / base:.3f}" for m, c in COST[1:]), flush=True)
    setting(6)


def share():
    n_settle, n = int(0.1 * FS), int(0.2 * FS)
    print(f"# share of x{M} steps sub-stepped (an event), 0.2 s after 0.1 s, the last of each sample's {M} steps read", flush=True)
    for label, s in cases():
        cells = []
        for c in (6, 48):
            setting(c)
            sim = Simulator(s, fidelity="skidding", seed=0, oversample=M)
            sim.advance(n_settle)
            m = sim._model
            seen = []
            for _ in range(n):
                k0 = m.counters[0]
                sim.advance(1)
                assert m.counters[0] - k0 == M, (m.counters[0] - k0)
                seen.append(m.counters[3] == 1)
            cells.append(f"N={c} {np.mean(seen):.1%}")
        print(f"  {label:34s} " + "  ".join(cells), flush=True)
    setting(6)


if __name__ == "__main__":
    args = sys.argv[1:]
    if "--oversample" in args:
        i = args.index("--oversample")
        M = int(args[i + 1])
        del args[i:i + 2]
    if "--counts" in args:
        i = args.index("--counts")
        COUNTS = tuple(int(v) for v in args[i + 1].split(","))
        del args[i:i + 2]
    if "--scenes" in args:
        i = args.index("--scenes")
        SCENES = {int(v) for v in args[i + 1].split(",")}
        del args[i:i + 2]
    parts = args or ["points", "bench", "cost", "share"]
    for part in parts:
        {"points": points, "bench": bench_part, "cost": cost, "share": share}[part]()
