"""Is the reference a converged answer where the default is far off it and its step seemed not
to be the cause?  The numbers of docs/solvers.md, "Light loads: the reference is converged, the
default's error is its own" (2026-11-30).  Run from the repository:
``python docs/probes/skidding_step/spread.py [point ...]`` (points by index into POINTS, all by
default; about 1 minute per point on the shared machine, each other part about 1 minute).

For each point, several runs of the skidding tier, sensor noise off, 0.1 s settle + SPAN s of
accel_y, the RMS over each 0.2 s window and over the whole span:

- ``ref``: ``solver="reference"`` as shipped (RK4 at 1/32 of the internal sample, 0.52 us);
- ``ref h/2``: RK4 at half that step (``solver="rk4"``, ``rk4_step`` 0.26 us);
- ``ref +dy``, ``ref -dy``: the reference from the start state with the shaft's vertical
  displacement moved by +-1e-12 m (set on the model before its first step; the skidding tier has
  no random input of its own, so a perturbed start is the only way to draw another trajectory);
- ``x2`` .. ``x16``: the default at 2, 4, 8, 16 steps per output sample; ``x2 +dy``: the default
  from the perturbed start.

``ablate [point ...]``, ``start [point ...]``, ``lines [point ...]`` (points 0-2 by default):
the default with one approximation refined at a time, each solver from the other's state, the
lines at the ball pass (their docstrings).

Printed beside each run: when its accel_y first departs from the reference's by more than 10 %
of the reference's RMS (``departs``), and for the reference how often a ball's inner and outer
contacts close (contact force from 0 to > 0 between output samples, per ball per second) and the
share of samples with them open.  The output of every part is in ``spread.txt``.
"""
import importlib.util
import sys

import numpy as np

from bearing_sim_ros import Simulator, load_scene

_spec = importlib.util.spec_from_file_location("custom_bearings", "docs/probes/custom_bearings/probe.py")
custom = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(custom)
FS, scene, quiet = custom.FS, custom.scene, custom.quiet

SETTLE, SPAN, WINDOW = 0.1, 1.0, 0.2
DY = 1e-12   # m on the shaft's vertical displacement at the start

POINTS = [
    ("61820-size 8888 rpm 739 N", lambda: scene("61820-size", 8888, 739)),
    ("b6307_seed001", lambda: load_scene("b6307_seed001")),
    ("6-ball 4545 rpm 142 N", lambda: scene("6-ball", 4545, 142)),
    # controls: the step is the cause here (x2 -42 %), and a shipped scene within 0.1 %
    ("6000-size 55555 rpm 4662 N", lambda: scene("6000-size", 55555, 4662)),
    ("er16k_healthy", lambda: load_scene("er16k_healthy")),
]

RUNS = [   # label, Simulator keywords, start perturbation (m)
    ("ref", {"solver": "reference"}, 0.0),
    ("ref h/2", {"solver": "rk4", "rk4_step": 1.0 / (FS * 4 * 64)}, 0.0),
    ("ref +dy", {"solver": "reference"}, DY),
    ("ref -dy", {"solver": "reference"}, -DY),
    ("x2", {"oversample": 2}, 0.0),
    ("x2 +dy", {"oversample": 2}, DY),
    ("x4", {"oversample": 4}, 0.0),
    ("x8", {"oversample": 8}, 0.0),
    ("x16", {"oversample": 16}, 0.0),
]


def run(s, kwargs, dy):
    sim = Simulator(s, fidelity="skidding", seed=0, **kwargs)
    # before the first step: the split method evaluates its derivative and structure input from
    # the state at its first step (counters[3] == 0), so both solvers start consistently from it
    sim._model.x[1] += dy
    b = sim.advance(int(round((SETTLE + SPAN) * FS)))
    k = int(round(SETTLE * FS))
    return b.accel[k:, -1], b.contact_forces[k:]


def rms(y):
    return float(np.sqrt(np.mean(y ** 2)))


def windows(y):
    n = int(round(WINDOW * FS))
    return [rms(y[i:i + n]) for i in range(0, len(y) - n + 1, n)]


def closures(q):
    """How often a ball's inner and outer contacts close (force from 0 to > 0 between output
    samples), per ball per second, and the share of samples with the contact open."""
    nb = q.shape[1] // 2
    said = []
    for name, f in (("inner", q[:, :nb]), ("outer", q[:, nb:])):
        closed = f > 0.0
        closes = np.count_nonzero(closed[1:] & ~closed[:-1]) / nb / (len(f) / FS)
        said.append(f"{name} closes {closes:.1f} /ball/s, open {1 - closed.mean():.1%}")
    return ", ".join(said)


def point(label, make):
    s = quiet(make())
    print(f"# {label}: accel_y RMS (m/s^2) per {WINDOW} s window after {SETTLE} s, and over {SPAN} s", flush=True)
    ref_y = None
    span = {}
    for name, kwargs, dy in RUNS:
        y, q = run(s, kwargs, dy)
        if ref_y is None:
            ref_y = y
            extra = "  " + closures(q)
        else:
            off = np.nonzero(np.abs(y - ref_y) > 0.1 * rms(ref_y))[0]
            extra = f"  departs {off[0] / FS * 1e3 + SETTLE * 1e3:.1f} ms" if off.size else "  departs never"
        w = windows(y)
        span[name] = rms(y)
        print(f"  {name:8s} windows {' '.join(f'{v:9.4g}' for v in w)}  span {span[name]:9.4g}{extra}", flush=True)
    refs = np.array([span[n] for n, _, _ in RUNS if n.startswith("ref")])
    mean, lo, hi = refs.mean(), refs.min(), refs.max()
    print(f"  references over {SPAN} s: mean {mean:.4g}, {lo / mean - 1:+.2%} .. {hi / mean - 1:+.2%}; "
          + "  ".join(f"{n} {span[n] / mean - 1:+.2%}" for n, _, _ in RUNS if not n.startswith("ref")),
          flush=True)


def ablate(label, make):
    """Which of the default's approximations errs: the default at 2 steps per output sample with
    one of them refined at a time (the method's own knobs, set on the model before its first
    step as the step check does), 0.1 s settle + 0.2 s, accel_y RMS against the reference's.
    ``balls/k``: the balls and cage in k ROS2 sub-steps per structure step (the structure's
    exact propagation and its input's hold unchanged); ``events x4``: 4x the event sub-steps;
    ``whole ROS2``: no split, the whole state (structure included) by ROS2 at that step.  Last,
    the reference and the default with the squeeze-film damping removed from both (the split's
    linear part carries the bearing's stiffness only: its damping is in the held input)."""
    from bearing_sim_ros.physics.integrators import ROS2, SplitROS2
    from bearing_sim_ros.physics.skidding import P_SQI, P_SQO

    s = quiet(make())
    n, k = int(round((SETTLE + WINDOW) * FS)), int(round(SETTLE * FS))

    def rms_with(method=None, oversample=2, squeeze_film=True, **kwargs):
        sim = Simulator(s, fidelity="skidding", seed=0, oversample=oversample, **kwargs)
        if method is not None:
            sim._model._set_step(oversample, method)
        if not squeeze_film:   # as skidding.speed_study's --no-squeeze-film does
            sim._model.p[P_SQI] = sim._model.p[P_SQO] = 0.0
        return rms(sim.advance(n).accel[k:, -1]), sim

    ref, sim = rms_with(solver="reference", oversample=None)
    print(f"# {label}: reference {ref:.4g} m/s^2 over {WINDOW} s", flush=True)
    d = sim._model.decimation
    variants = [("x2", None, 2), ("x2 balls/4", SplitROS2(per_sample=2 / d, ball_substeps=4), 2),
                ("x2 balls/16", SplitROS2(per_sample=2 / d, ball_substeps=16), 2),
                ("x2 events x4", SplitROS2(per_sample=2 / d, event_substeps=24), 2),
                ("x2 events x16", SplitROS2(per_sample=2 / d, event_substeps=96), 2),
                ("x8", None, 8), ("x8 balls/4", SplitROS2(per_sample=8 / d, ball_substeps=4), 8),
                ("x8 events x4", SplitROS2(per_sample=8 / d, event_substeps=24), 8),
                ("x16", None, 16), ("x32", None, 32),
                ("whole ROS2 x8", ROS2(per_sample=8 / d), 8), ("whole ROS2 x16", ROS2(per_sample=16 / d), 16),
                ("whole ROS2 x32", ROS2(per_sample=32 / d), 32)]
    for name, method, m in variants:
        try:
            v = f"{rms_with(method, m)[0] / ref - 1:+8.2%}"
        except Exception as e:   # a variant beyond what its method integrates: say so, go on
            v = f"{type(e).__name__}"
        print(f"  {name:16s} {v}", flush=True)
    ref0 = rms_with(solver="reference", oversample=None, squeeze_film=False)[0]
    print(f"  without the squeeze film (reference and default): reference {ref0:.4g} m/s^2  " + "  ".join(
        f"x{m} {rms_with(None, m, squeeze_film=False)[0] / ref0 - 1:+.2%}" for m in (2, 4, 8, 16)), flush=True)


def start(label, make):
    """Whether the default's level depends on where it starts: each solver continued 0.2 s from
    the other's state after 0.1 s (``adopt_state``, as a tier switch hands a state over),
    accel_y RMS over the last 0.1 s."""
    s = quiet(make())
    solvers = {"ref": {"solver": "reference"}, "x2": {"oversample": 2}, "x8": {"oversample": 8}}
    print(f"# {label}: accel_y RMS over 0.1 s, after 0.1 s from the state of another solver at 0.1 s", flush=True)
    for a in ("ref", "x2"):
        first = Simulator(s, fidelity="skidding", seed=0, **solvers[a])
        first.advance(int(round(0.1 * FS)))
        said = []
        for b in solvers:
            then = Simulator(s, fidelity="skidding", seed=0, **solvers[b])
            then._model.adopt_state(first._model)
            said.append(f"{b} {rms(then.advance(int(round(0.2 * FS))).accel[int(round(0.1 * FS)):, -1]):.4g}")
        print(f"  from {a}'s state: " + "  ".join(said), flush=True)


def lines(label, make):
    """Where the default's excess lies: the amplitude (m/s^2) of accel_y's lines at 1-3 x BPFO
    over 0.1-0.3 s, at the nearest 5 Hz bin (no taper: levels to compare between runs, not exact
    line heights), and the least inner and outer contact force over the window (N)."""
    s = quiet(make())
    bpfo = abs(s.fault_frequencies()["bpfo"])
    print(f"# {label}: lines of accel_y at 1-3 x BPFO ({bpfo:.1f} Hz), 0.1-0.3 s", flush=True)
    k, n = int(round(SETTLE * FS)), int(round((SETTLE + WINDOW) * FS))
    for name, kwargs in (("ref", {"solver": "reference"}), ("x2", {"oversample": 2}), ("x8", {"oversample": 8}),
                         ("x32", {"oversample": 32})):
        b = Simulator(s, fidelity="skidding", seed=0, **kwargs).advance(n)
        y = b.accel[k:, -1]
        amp = np.abs(np.fft.rfft(y)) * 2 / len(y)
        f = np.fft.rfftfreq(len(y), 1 / FS)
        at = [amp[int(np.argmin(np.abs(f - h * bpfo)))] for h in (1, 2, 3)]
        q = b.contact_forces[k:]
        nb = q.shape[1] // 2
        print(f"  {name:4s} RMS {rms(y):.4g}  " + "  ".join(f"{h}x {v:.3g}" for h, v in zip((1, 2, 3), at))
              + f"  least inner force {q[:, :nb].min():.3g} N, outer {q[:, nb:].min():.3g} N", flush=True)


if __name__ == "__main__":
    args = sys.argv[1:]
    parts = {"ablate": ablate, "start": start, "lines": lines}
    if args[:1] and args[0] in parts:
        for i in args[1:] or range(3):
            parts[args[0]](*POINTS[int(i)])
    else:
        for i in args or range(len(POINTS)):
            point(*POINTS[int(i)])
