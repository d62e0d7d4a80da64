"""Does the skidding tier's default solver get closer to its reference if the split's linear
structure part carries the bearing's damping cb as well as its stiffness kb?  The numbers of
docs/solvers.md, "Bearing damping in the split's linear part" (2026-11-30).

The change is NOT in the package: apply it first, from the repository,
``git apply docs/probes/structure_damping/structure_damping.patch``, then
``python docs/probes/structure_damping/probe.py [points] [bench] [cost]`` (all by default; points
about 1 minute, bench about 3 minutes, cost about 1 minute on the shared 2-core machine, plus one
compilation of the kernels after the patch), and ``git checkout -- bearing_sim_ros`` to undo it.

The patch: ``skidding.STRUCTURE_DAMPING`` (False: the shipped split) puts a linearised bearing
damping cb (2x2, N s/m, on the shaft-pedestal relative velocity) into the structure's matrix A
beside kb and adds cb (v_s - v_p) back into the held input as kb d is, so the model is unchanged
and only the split moves.  cb: per cage position (the 8 of ``_mean_pedestal_force``) each ball at
its quasi-static radius, its inner and outer contacts (tangent stiffness 1.5 K delta^0.5, damping
structural + squeeze film as ``_rhs`` has them) in series, massless: c_eff = (c_i k_o^2 + c_o
k_i^2) / (k_i + k_o)^2 along the ball's direction, averaged.  ``OPEN_SQUEEZE_SHARE`` adds that
share of an open inner contact's one-sided squeeze film (outer closed); ``DAMPING_SCALE``
multiplies cb (a diagnostic: the model stays the same whatever cb is).

- ``points``: hM's three light-load points (docs/probes/skidding_step/spread.py), sensor noise
  off, 0.1 s settle + 0.2 s, accel_y RMS against a fresh ``solver="reference"`` run, at 2, 4, 8
  steps per output sample, shipped split against the variants.
- ``bench``: the bench's eight scenarios (``bench.SCENARIOS``) in the bench's own window (0.2 s
  settle + 0.5 s) and metrics (``bench.errors``: rms, and error = max(rms, lines, cage)) against
  a fresh reference, at x2 and x1, shipped split against cb in the linear part.
- ``cost``: CPU time of the simulating thread per output sample, shipped split and cb
  alternating in this process (5 each, median), as a ratio.
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

POINTS = [
    ("61820-size 8888 rpm 739 N", lambda: scene("61820-size", 8888, 739)),
    ("b6307_seed001", lambda: load_scene("b6307_seed001")),
    ("6-ball 4545 rpm 142 N", lambda: scene("6-ball", 4545, 142)),
]
# label: (STRUCTURE_DAMPING, OPEN_SQUEEZE_SHARE, DAMPING_SCALE)
VARIANTS = {
    "shipped": (False, 0.0, 1.0),
    "cb": (True, 0.0, 1.0),
    "cb+open/2": (True, 0.5, 1.0),
    "cb x10": (True, 0.0, 10.0),
    "cb x100": (True, 0.0, 100.0),
}


def setting(name):
    sk.STRUCTURE_DAMPING, sk.OPEN_SQUEEZE_SHARE, sk.DAMPING_SCALE = VARIANTS[name]


def rms(y):
    return float(np.sqrt(np.mean(y ** 2)))


def accel(s, settle, span, **kwargs):
    sim = Simulator(s, fidelity="skidding", seed=0, **kwargs)
    b = sim.advance(int(round((settle + span) * FS)))
    return b.accel[int(round(settle * FS)):, -1], sim


def points():
    for label, make in POINTS:
        s = quiet(make())
        setting("shipped")
        ref = rms(accel(s, 0.1, 0.2, solver="reference")[0])
        print(f"# {label}: reference {ref:.5g} m/s^2 (0.1 s + 0.2 s), accel_y RMS against it", flush=True)
        for m in (2, 4, 8):
            cells = []
            for name in VARIANTS:
                if m != 2 and name in ("cb x10", "cb x100"):
                    continue
                setting(name)
                y, sim = accel(s, 0.1, 0.2, oversample=m)
                cells.append(f"{name} {rms(y) / ref - 1:+.2%}")
                if m == 2 and name in ("cb", "cb+open/2"):
                    cb = sim._model.cb
                    print(f"  {name}: cb xx {cb[0, 0]:.0f} xy {cb[0, 1]:.0f} yy {cb[1, 1]:.0f} N s/m"
                          f" (kb yy {sim._model.kb[1, 1]:.3g} N/m)", flush=True)
            print(f"  x{m}: " + "  ".join(cells), flush=True)
    setting("shipped")


def bench_part():
    settle, seconds = 0.2, 0.5
    print(f"# bench scenarios, {settle} s + {seconds} s, bench.errors against a fresh reference: rms / error", flush=True)
    for sc in bench.SCENARIOS:
        s = sc.build()
        setting("shipped")
        ref = bench.run_config(bench.reference_config(), s, FS, settle, seconds, 1)
        cells = []
        for m in (2, 1):
            for name in ("shipped", "cb"):
                setting(name)
                cfg = bench.Config(f"x{m}", "skidding default", "skidding", (("oversample", m),))
                e = bench.errors(bench.run_config(cfg, s, FS, settle, seconds, 1), ref, s, FS)
                cells.append(f"x{m} {name} {e['rms']:.2%} / {e['error']:.2%}")
        print(f"  {sc.label:34s} " + "  ".join(cells), flush=True)
    setting("shipped")


def cost():
    """CPU s of this thread per output sample, shipped and cb alternating, 5 each, median."""
    cases = [("ER-16K healthy 2000 rpm 200 N", bench.SCENARIOS[3].build()),
             ("6205 ball+outer 1750 rpm 2000 N", bench.SCENARIOS[7].build()),
             ("6-ball 4545 rpm 142 N", quiet(scene("6-ball", 4545, 142)))]
    n_settle, n = int(0.1 * FS), int(1.0 * FS)
    print("# cost per output sample, cb / shipped (CPU time of the thread, alternating, median of 5)", flush=True)
    for label, s in cases:
        for m in (2, 1):
            times = {"shipped": [], "cb": []}
            for _ in range(5):
                for name in ("shipped", "cb"):
                    setting(name)
                    sim = Simulator(s, fidelity="skidding", seed=0, oversample=m)
                    sim.advance(n_settle)
                    t = time.thread_time()
                    sim.advance(n)
                    times[name].append((time.thread_time() - t) / n)
            a, b = statistics.median(times["shipped"]), statistics.median(times["cb"])
            print(f"  {label:34s} x{m}: cb / shipped {b / a:.3f}", flush=True)
    setting("shipped")


def instant():
    """Is the quasi-static cb the damping the structure actually meets?  The shipped split at x2,
    0.1 s settle, then 0.1 s one output sample at a time: from the step's per-ball table (tangent
    stiffnesses, dampings, direction) the same series c_eff summed over the balls with both
    contacts closed, in xx and yy; its mean, 99th percentile and maximum (``points`` prints cb)."""
    setting("shipped")
    for label, make in POINTS[1:]:
        s = quiet(make())
        sim = Simulator(s, fidelity="skidding", seed=0, oversample=2)
        sim.advance(int(0.1 * FS))
        m = sim._model
        rows = []
        for _ in range(int(0.1 * FS)):
            sim.advance(1)
            a = m._aux0
            ki, ko, ci, co, c, sn = (a[:, k] for k in (sk.X_KTI, sk.X_KTO, sk.X_CI, sk.X_CO, sk.X_C, sk.X_S))
            both = (ki > 0) & (ko > 0)
            ce = np.where(both, (ci * ko ** 2 + co * ki ** 2) / np.where(both, ki + ko, 1.0) ** 2, 0.0)
            rows.append([np.sum(ce * c * c), np.sum(ce * sn * sn)])
        rows = np.array(rows)
        st = s.structure
        print(f"# {label}: instantaneous series damping xx / yy (N s/m): mean {rows[:, 0].mean():.0f} / "
              f"{rows[:, 1].mean():.0f}, p99 {np.percentile(rows[:, 0], 99):.0f} / {np.percentile(rows[:, 1], 99):.0f}, "
              f"max {rows[:, 0].max():.0f} / {rows[:, 1].max():.0f}; structure: shaft {st.shaft_damping:g}, "
              f"pedestal {st.pedestal_damping:g} N s/m, masses {st.shaft_mass:g} / {st.pedestal_mass:g} kg", flush=True)


if __name__ == "__main__":
    parts = sys.argv[1:] or ["points", "bench", "cost", "instant"]
    for part in parts:
        {"points": points, "bench": bench_part, "cost": cost, "instant": instant}[part]()
