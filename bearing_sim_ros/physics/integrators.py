"""Time integrators of the skidding tier: small classes that carry their tableau and say what
they are; one stepping engine (``skidding._engine``) runs all of them.

Each method is a :class:`Method` with

* ``kind``: how the engine uses it: ``EXPLICIT`` (an explicit Runge-Kutta tableau ``a``, ``b``,
  ``c`` on the whole state), ``ROSENBROCK`` (a linearly implicit Rosenbrock-W tableau on the whole
  state: each stage solves ``W k_i = f(t + c_i h, y + h sum_j a_ij k_j) + sum_j g_ij k_j`` with
  ``W = I - gamma h J``; any approximation ``J`` of the Jacobian keeps the order of a W-method,
  so the engine uses a cheap block-structured one) or ``SPLIT`` (the same Rosenbrock-W tableau
  on the balls and the cage, the linear structure propagated exactly; see :class:`SplitROS2`);
* ``step(sample_spacing)``: the fixed step (s) the method takes for a given internal sample
  spacing.  The engine keeps a global step grid (step k ends at k * step from the start of the
  simulation), evaluates the right-hand side at a sample time directly when the grid hits it, and
  otherwise interpolates the state with a cubic Hermite polynomial and evaluates there.

The layout follows ``scipy/integrate/_ivp/rk.py``: the tableau is data on the class, the engine
is generic.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import UserError, short_repr

EXPLICIT = 0
ROSENBROCK = 1
SPLIT = 2

RK4_DEFAULT_STEP = 1.0e-5          # s, seed 000's fixed step
RK4_STEP_RANGE = (1.0e-9, 1.0e-3)  # s, what ``rk4_step`` / ``--rk4-step`` accept


def check_rk4_step(rk4_step) -> None:
    """``rk4_step`` (s, or None: the method's own) within ``RK4_STEP_RANGE``, else one line
    (``UserError``) naming it: the Simulator asks at once, whatever tier it starts on, and the
    skidding tier again, as its own API."""
    lo, hi = RK4_STEP_RANGE
    if rk4_step is not None and not (isinstance(rk4_step, numbers.Real) and not isinstance(rk4_step, bool)
                                     and lo <= rk4_step <= hi):
        raise UserError(f"rk4_step = {short_repr(rk4_step)}: allowed range is [{lo:g}, {hi:g}] s")


class Method:
    """Base class: a fixed-step method.  ``order``: classical order; ``stages``: right-hand-side
    evaluations per step."""

    name = "abstract"
    kind = EXPLICIT
    order = 0
    a = np.zeros((0, 0))
    b = np.zeros(0)
    c = np.zeros(0)
    g = np.zeros((0, 0))
    gamma = 0.0

    def __init__(self, step: float | None = None, per_sample: float = 1):
        self._step = step
        self.per_sample = float(per_sample)

    @property
    def stages(self) -> int:
        return self.b.size

    def step(self, sample_spacing: float) -> float:
        """The step (s) for an internal sample spacing (s): ``step`` if given, else the sample
        spacing divided by ``per_sample`` (a fraction means several samples per step)."""
        if self._step is not None:
            return float(self._step)
        return sample_spacing / self.per_sample

    def arrays(self):
        """(kind, a, b, c, g, gamma) as contiguous float arrays for the engine."""
        s = self.stages
        g = self.g if self.g.size else np.zeros((s, s))
        return (self.kind, np.ascontiguousarray(self.a, dtype=float), np.ascontiguousarray(self.b, dtype=float),
                np.ascontiguousarray(self.c, dtype=float), np.ascontiguousarray(g, dtype=float), float(self.gamma))


class RK4(Method):
    """The classic fourth-order Runge-Kutta method (Kutta 1901), as in seed 000 Sec. 3.1 (fixed
    step 1e-5 s).  Explicit: its stability interval on the negative real axis is about 2.79 / h
    and it is unstable on most of the imaginary axis beyond 2.83 / h, so the ball's radial mode
    (tens of kHz) and the ball-cage springs (~35 kHz) put 1e-5 s at or beyond its limit."""

    name = "rk4"
    kind = EXPLICIT
    order = 4
    a = np.array([[0.0, 0.0, 0.0, 0.0],
                  [0.5, 0.0, 0.0, 0.0],
                  [0.0, 0.5, 0.0, 0.0],
                  [0.0, 0.0, 1.0, 0.0]])
    b = np.array([1.0, 2.0, 2.0, 1.0]) / 6.0
    c = np.array([0.0, 0.5, 0.5, 1.0])


class ROS2(Method):
    """Two-stage, second-order, L-stable Rosenbrock-W method ROS2 (Verwer, Spee, Blom and
    Hundsdorfer, SIAM J. Sci. Comput. 20 (1999) 1456-1480), gamma = 1 + 1/sqrt(2):

        W = I - gamma h J
        W k1 = f(t, y)
        W k2 = f(t + h, y + h k1) - 2 k1
        y_new = y + h (3/2 k1 + 1/2 k2)

    The engine's general form is ``W k_i = f(t + c_i h, y + h sum_j a_ij k_j) + sum_j g_ij k_j``,
    ``y_new = y + h sum_i b_i k_i``.  ROS2 keeps order 2 for ANY matrix J (a W-method), so J may
    be an approximation: the skidding tier gives it only the stiff per-ball couplings (contact
    stiffness and damping, traction slopes, ball-cage springs, cage) in an arrow-shaped block
    form that costs a 3x3 solve per ball and a scalar for the cage.  L-stability removes the
    ball-radial and ball-cage modes (30-60 kHz, far above the output band) in one step instead of
    ringing them, and the stiff traction slope near zero slip is harmless."""

    name = "ros2"
    kind = ROSENBROCK
    order = 2
    gamma = 1.0 + 1.0 / math.sqrt(2.0)
    a = np.array([[0.0, 0.0], [1.0, 0.0]])
    g = np.array([[0.0, 0.0], [-2.0, 0.0]])
    b = np.array([1.5, 0.5])
    c = np.array([0.0, 1.0])


class SplitROS2(ROS2):
    """ROS2 on the balls and the cage, exponential integration of the structure (the default).

    The structure (shaft, pedestal, resonator: linear springs, dampers and masses) plus the
    bearing's quasi-static stiffness linearised at the operating point is a linear system; it is
    propagated exactly by matrix exponentials (as the kinematic tier does, ETD of Cox and
    Matthews 2002), with the rest of the ball forces as an input that follows the parabola
    through its values at the last two grid points and the step's end (linearly after a step
    with events, where the input has a kink).  A ramp alone passes a force at frequency f with
    a relative error of about (pi f h)^2 / 3, 6 % at the resonator's 4 kHz at two samples per
    step, which was most of the default's error on the healthy scenes (docs/solvers.md).  The
    balls and the cage see the structure's displacement as a given function over the step and
    take one ROS2 step with the per-ball block Jacobian (the stiff ball-radial, ball-cage and
    traction couplings).  Per step:

        x* = Phi x_n + G0 u_n                      structure predictor (input held)
        ROS2 step of the balls/cage with the structure going linearly from x_n to x*
        u' = ball forces at (z_{n+1}, x*)          two right-hand-side evaluations in all
        x_{n+1} = x* + G1 (u' - u_n)               corrector (input ramped, plus the
                  + G2 (u' - 2 u_n + u_{n-1}) / 2  parabola's term after a plain step)

    The exact linear part keeps the structural modes (pedestal, shaft on its bearing, the unit
    resonator at several kHz) free of numerical damping or phase error at any step, which an
    L-stable method applied to them would not; the ball and cage modes (30-60 kHz) are removed
    by ROS2's L-stability.  Samples between grid points: the structure's exact response to the
    ramped input at that time (precomputed sub-step propagators).

    Event-aware: a step in which a ball is inside a defect (its depth profile, with edges, under
    a contact that the defect changes: one that would be closed without it, unless that contact
    stays open at both ends by more than ``skidding.OPEN_GAP_MARGIN`` times its gap's change: a
    ball in free flight over a deep pit) is redone in ``event_substeps`` sub-steps per internal
    sample (a step of two samples in twice as many).
    Without that the method converges only to first order there (a smooth method across a kink),
    and the impacts, which make the defect's envelope line, come out wrong.  A step in which a
    ball-race or ball-pocket contact opens or closes (the load handing over from ball to ball, a
    lightly loaded ball touching and leaving a race; seen at the step's end or at its second
    stage's point, so that a contact that closes and opens again inside the step counts) is
    sub-stepped too: from an open contact that closes during the step, W would leave the step
    explicit in the contact's stiffness (without any redo, two samples per step went 38 % and
    230 % off in RMS at 200 and 2000 N).  Such steps are 0.9-7 % of all on the bench scenes
    (README, "Solvers", "Event sub-steps"); a step of one sample used to be redone once
    instead, with each ball's Jacobian from the stiffer end of the step, which left 1.1 % error
    at 2000 N where sub-steps leave 0.5 %.  6 sub-steps per internal sample rather than 4 bring
    the ER-16K inner-race line from 0.97 to 0.53 % off at two samples per step (8: 0.33 %) for 6-25 % more
    work (25 % on the ball+outer scene, whose 2 mm ball pit is under a contact in a fifth of the
    steps; docs/solvers.md, "The first step").  The first ``skidding.START_STEPS`` steps after
    the state is set are sub-stepped whatever happens in them.
    """

    name = "split-ros2"
    kind = SPLIT

    def __init__(self, step: float | None = None, per_sample: float = 1, event_substeps: int = 6,
                 ball_substeps: int = 1):
        super().__init__(step, per_sample)
        self.event_substeps = int(event_substeps)
        self.ball_substeps = int(ball_substeps)


def method_for(solver: str, rk4_step: float | None, reference_per_sample: int = 32,
               default_per_sample: float = 1.0) -> Method:
    """The method behind a ``solver=`` name; ``default_per_sample``: steps of the default per
    internal sample (a fraction: several samples per step)."""
    if solver == "rk4":
        return RK4(step=RK4_DEFAULT_STEP if rk4_step is None else float(rk4_step))
    if solver == "reference":
        return RK4(per_sample=reference_per_sample)
    if solver == "default":
        return SplitROS2(per_sample=default_per_sample)
    raise ValueError(solver)
