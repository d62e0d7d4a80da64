"""The simulator: a scene advanced in output-rate batches (no ROS here).

    sim = Simulator(load_scene("er16k_outer_race"), sample_rate=15000.0)
    b = sim.advance(150)                                      # 10 ms at the operating point
    b = sim.advance(150, shaft_speed=167.55, radial_load=(0.0, -50.0))

A tier (kinematic or skidding) steps the bearing at an internal rate that is an integer multiple
of the output rate; the accelerometer chain turns the sensor-mount acceleration into output
samples (sensor resonance, linear-phase anti-aliasing FIR, decimation, noise, clipping).  The
physics runs ``lookahead`` internal steps ahead of the output so that the FIR's group delay is
compensated exactly: sample k of the output is the acquisition of time t0 + k / sample_rate.

Speed and load commands take effect from the start of the next ``advance`` and move linearly
over that call (a ramp, never a step), so the published signal has no unphysical jump.
Advancing in chunks gives the same samples as one long advance with the same commands and seed.
"""
from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass, field

import numpy as np

from numba import njit

from . import physics  # noqa: F401 - sets numba's cache folder before _ramp below asks for it
from .compile_notice import Notice
from .errors import UserError, short_repr
from .physics.integrators import check_rk4_step
from .scene import RPM, Scene, _load_and_weight_error, _operating_point_error, load_scene

SOLVERS = ("default", "rk4", "reference")
FIDELITIES = ("auto", "kinematic", "skidding")
# output sample rates (Hz) that the API, the node's ``sample_rate`` parameter and
# ``bearing-sim render --sample-rate`` accept: one range, so that what renders offline also runs live
SAMPLE_RATE_RANGE = (1000.0, 200000.0)
# the longest signal (s) that the node's duration and record_max_duration, `bearing-sim render
# --duration` and `run --duration` accept: 31 years, a guard against a typo (1e12) that would
# otherwise run until the disk is full
DURATION_MAX_S = 1.0e9
# the most internal samples of the sensor chain (``chain_oversample`` per output sample) that one
# ``advance`` computes: every series of the call is held in memory at once, up to about 450 bytes
# per internal sample (the skidding tier, 9 balls: measured), so this is at most about 2 GB, 70 s of
# signal at 15 kHz.  advance(10**12) died with a MemoryError (or worse, the OOM killer) before;
# longer signals go in chunks, which give the same samples (``Simulator.max_advance``)
MAX_ADVANCE_INTERNAL = 2 ** 22
# the slowest rate the physics runs at (Hz): the tiers' steps and the sensor chain's anti-aliasing
# were made and measured at 15 kHz.  Below it the tiers run at the smallest whole multiple of the
# output rate that reaches it (``physics_rate_factor``) and the chain decimates to the output: a
# step as long as a 1 kHz sample missed the defect impacts, and a chain at 4 kHz folded the 3.8
# kHz pedestal resonance down into the band (0-400 Hz at 1 kHz: the skidding tier 25x and the
# kinematic one 3.5x the 15 kHz run's vertical level)
PHYSICS_RATE_MIN = 15000.0


def physics_rate_factor(sample_rate: float) -> int:
    """Physics samples per output sample: 1 at ``PHYSICS_RATE_MIN`` and above, else the smallest
    whole number that takes ``sample_rate`` (Hz) to it."""
    return max(1, math.ceil(PHYSICS_RATE_MIN / float(sample_rate) - 1e-9))


# seeds that the API, ``bearing-sim render --seed`` and the node's ``seed`` parameter (an int64,
# kept to 31 bits) accept: one range, so that a render's seed also runs live
SEED_RANGE = (0, 2 ** 31 - 1)


def _whole_number(value) -> bool:
    """Whether ``value`` is a Python or numpy integer and not a bool (``True`` is an int, but
    ``advance(True)`` or ``seed=True`` is a mistake, not 1)."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def _real_number(value) -> bool:
    """Whether ``value`` is a Python or numpy real number and not a bool or a string."""
    return isinstance(value, (numbers.Real, np.floating, np.integer)) and not isinstance(value, (bool, np.bool_))


def _finite_float(value) -> float | None:
    """``float(value)`` of a real number, None where that is no finite number: NaN, an infinity,
    an int beyond float's range (10**400, whose float() is an OverflowError)."""
    try:
        f = float(value)
    except OverflowError:
        return None
    return f if math.isfinite(f) else None


def _plain(value) -> str:
    """A number as an error line says it: a float's plain repr (not numpy's ``np.float64(nan)``),
    an int shortened (``errors.short_repr``: 10**400 has 401 digits)."""
    return short_repr(int(value)) if isinstance(value, (int, np.integer)) else repr(float(value))


# integration steps per output sample that the API, ``bearing-sim render --oversample`` and the
# node's ``oversample`` parameter (where 0 means each tier's own) accept
OVERSAMPLE_ALLOWED = "1, 2 or a multiple of 4 up to 64"
# at most this many where fidelity auto may switch tiers at run time: above it the kinematic
# tier's sensor chain runs faster than the skidding tier's, and a switch needs the same chain
AUTO_OVERSAMPLE_MAX = 4


class DefaultStepWarning(UserWarning):
    """The skidding tier's default solver runs at a step its step check could not bring within
    its target (``physics.skidding.STEP_CHECK_TARGET``: capped at ``STEP_CHECK_MAX`` steps per
    sample, or at ``AUTO_OVERSAMPLE_MAX`` under fidelity auto), or at its own step where the check
    did not run (a tier switch) on a bearing where that step was measured off its reference
    (``STEP_CONTACT_LIMIT``): the message says by how much and what to set instead."""


def oversample_allowed(value) -> bool:
    """Whether ``value`` is one of ``OVERSAMPLE_ALLOWED``."""
    return _whole_number(value) and (value in (1, 2) or (value % 4 == 0 and 4 <= value <= 64))


class OversampleForAuto(UserError):
    """``oversample`` above ``AUTO_OVERSAMPLE_MAX`` where fidelity auto chooses the tier.
    ``worded`` lets a caller name the two in its own words (the CLI's ``--oversample``)."""

    def __init__(self, value):
        self.value = value
        super().__init__(self.worded("oversample", "fidelity"))

    def worded(self, oversample_name: str, fidelity_name: str, zero: str = "") -> str:
        """``zero``: what 0 means where the caller takes it (the node's "each tier's own")."""
        also = f"0 ({zero}), " if zero else ""
        return (f"{oversample_name} = {self.value!r}: with {fidelity_name} auto allowed values are {also}1, 2 "
                f"or {AUTO_OVERSAMPLE_MAX} (or choose {fidelity_name} kinematic or skidding)")


class OversampleWithOwnStep(UserError):
    """``oversample`` where only the skidding tier runs, with its "rk4" or "reference" solver: that
    solver keeps its own step (``rk4_step`` s; 1/32 of an internal sample), so the setting would do
    nothing.  ``worded`` lets a caller name the two in its own words (the CLI's ``--oversample``)."""

    def __init__(self, value, solver: str):
        self.value = value
        self.solver = solver
        super().__init__(self.worded("oversample", "solver"))

    def worded(self, oversample_name: str, solver_name: str) -> str:
        return (f"{oversample_name} = {self.value!r}: {solver_name} {self.solver} keeps its own step; "
                f"{oversample_name} applies to the kinematic tier and {solver_name} default only")


@dataclass
class Batch:
    """``n`` output samples.  Times in s, accelerations m/s^2, forces N, speeds rad/s.

    t0: time of sample 0 (s since the start); index0: its index since the start; sample_rate: Hz.
    accel: (n, axes) m/s^2, one column per ``accel_channels`` name ("accel_x", "accel_y": the
    scene's ``sensor.axes``).  contact_forces: (n, 2 Nb) N, each ball's inner then outer contact
    force, named by ``contact_channels`` ("inner_00".., "outer_00"..).  cage_speed: (n,) rad/s.
    shaft_speed (n,) rad/s and radial_load (n, 2) N (x, y; y up): the operating point in use at
    each sample, a command's ramp included.  tier: the tier that ran ("kinematic" | "skidding").
    extras: the skidding tier's further series (``ball_skid``, ``cage_skid`` (n,) %;
    ``slip_inner``, ``slip_outer`` (n, Nb) m/s; ``friction_inner``, ``friction_outer`` (n, Nb) N),
    empty for the kinematic tier; NaN in the rows of a batch that the kinematic tier computed
    before a switch.  Every array is the batch's own.
    """

    t0: float                      # time of sample 0 (s since the start of the simulation)
    index0: int                    # absolute index of sample 0
    sample_rate: float             # Hz
    accel: np.ndarray              # (n, axes) float64
    accel_channels: tuple
    contact_forces: np.ndarray     # (n, 2 Nb): inner_00.., outer_00..
    contact_channels: tuple
    cage_speed: np.ndarray         # (n,)
    shaft_speed: np.ndarray        # (n,) shaft speed in use
    radial_load: np.ndarray        # (n, 2) load in use (x, y)
    tier: str
    extras: dict = field(default_factory=dict)   # e.g. ball_skid, cage_skid (n,) for the skidding tier

    def __eq__(self, other):
        """Whether ``other`` is a batch with the same samples bit for bit (NaN where this one has
        NaN), times, channels and tier: the check of a seed's reproducibility.  The generated
        comparison asked numpy for the truth value of whole arrays and raised a ValueError."""
        if not isinstance(other, Batch):
            return NotImplemented

        def same(a, b) -> bool:
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
                a, b = np.asarray(a), np.asarray(b)
                floats = a.dtype.kind == "f" and b.dtype.kind == "f"
                return a.shape == b.shape and np.array_equal(a, b, equal_nan=floats)
            return a == b

        mine, theirs = dict(vars(self)), dict(vars(other))
        extras, other_extras = mine.pop("extras"), theirs.pop("extras")
        return (mine.keys() == theirs.keys() and all(same(v, theirs[k]) for k, v in mine.items())
                and extras.keys() == other_extras.keys() and all(same(v, other_extras[k]) for k, v in extras.items()))

    @property
    def n(self) -> int:
        """Samples in the batch."""
        return self.accel.shape[0]

    @property
    def times(self) -> np.ndarray:
        """(n,) time of each sample (s since the start)."""
        return (self.index0 + np.arange(self.n)) / self.sample_rate


def contact_channel_names(balls: int) -> tuple:
    return tuple(f"inner_{j:02d}" for j in range(balls)) + tuple(f"outer_{j:02d}" for j in range(balls))


@njit(cache=True)
def _ramp(speed, load, s0, s1, l0x, l0y, l1x, l1y):
    """Shaft speed (rad/s) and load (N, x and y) in use at each of the n output samples of a
    batch over which they move linearly from (s0, l0) to (s1, l1): row k at k / n of the way."""
    n = speed.shape[0]
    for k in range(n):
        f = k / n
        speed[k] = s0 + (s1 - s0) * f
        load[k, 0] = l0x + (l1x - l0x) * f
        load[k, 1] = l0y + (l1y - l0y) * f


def _auto_reselects(scene, requested_fidelity: str) -> bool:
    """Whether the tier is chosen anew at each operating point: auto asked for by the caller and
    by the scene."""
    return requested_fidelity == "auto" and scene.fidelity == "auto"


def reselect_tier(scene, requested_fidelity: str, selection, operating_point, new_operating_point):
    """The tier selection at ``new_operating_point`` ((shaft speed rad/s, (x, y) load N)) for a
    simulator now at ``operating_point`` with ``selection``, or None when the choice cannot change
    (a tier asked for by the caller or the scene, or the same operating point).  Shared by
    ``Simulator.maybe_switch_tier`` and callers that must know the tiers of a run in advance."""
    if not _auto_reselects(scene, requested_fidelity):
        return None
    (s0, l0), (s1, l1) = operating_point, new_operating_point
    if s1 == s0 and l1[0] == l0[0] and l1[1] == l0[1]:
        return None             # same operating point: same choice
    from .fidelity import select_tier

    return select_tier(scene, "auto", s1, np.asarray(l1), selection.tolerance, current=selection.tier)


class Simulator:
    """Advance a bearing scene in output-rate batches.

    scene: a :class:`~bearing_sim_ros.scene.Scene` or a shipped name / YAML path.
    sample_rate: output rate (Hz).  fidelity: "auto" | "kinematic" | "skidding".
    seed: the kinematic tier's random slip, a wandering ball defect's latitudes and the sensor
    noise (the skidding tier has no random slip: there a seed changes only those two).
    solver: "default" | "rk4" | "reference" (skidding tier).
    rk4_step: step of the "rk4" solver (s).  oversample: integration steps per physics sample
    (the accuracy knob: 1, 2 or a multiple of 4 up to 64; by default each tier's own: the
    kinematic tier takes 1 while its bearing mode stays below a tenth of ``physics_rate``, else
    ``physics.kinematic.DEFAULT_OVERSAMPLE`` = 2, chosen again when the load moves it; the skidding
    tier's "default" solver ``physics.skidding.DEFAULT_OVERSAMPLE`` = 2; "rk4" and "reference"
    keep their steps).  tolerance: the relative error allowed to the kinematic tier where
    fidelity is auto (1e-4 - 1; default: the scene's ``fidelity.tolerance``).

    ``physics_rate`` (Hz) is the output rate from ``PHYSICS_RATE_MIN`` = 15 kHz on; below it, the
    smallest whole multiple of the output rate that reaches 15 kHz (``physics_per_sample`` physics
    samples per output sample), so that a lower output rate gets the same physics, decimated by
    the sensor chain, not a coarser one.

    ``sample_rate`` is any real number in ``SAMPLE_RATE_RANGE`` (15001 Hz too), wider than the node's
    ``sample_rate`` and ``bearing-sim render --sample-rate`` (multiples of 100 Hz at render's 10 ms
    tables): their rule, ``messages.batching_error``, is that a published table (``batch_duration``
    s) holds a whole number of samples, and here the caller chooses each batch's samples (``n`` of
    ``advance``); a batch's times are ``(index0 + k) / sample_rate`` s, not stamps rounded to the ns.
    """

    def __init__(self, scene, sample_rate: float = 15000.0, fidelity: str = "auto", seed: int = 0,
                 solver: str = "default", rk4_step: float | None = None, oversample: int | None = None,
                 tolerance: float | None = None):
        if not isinstance(scene, Scene):
            scene = load_scene(scene)
        lo, hi = SAMPLE_RATE_RANGE
        if not (_real_number(sample_rate) and lo <= sample_rate <= hi):
            raise UserError(f"sample_rate = {short_repr(sample_rate)}: allowed range is [{lo:g}, {hi:g}] Hz")
        # a str first: `in` compares an array element-wise, numpy's 'truth value ... ambiguous'
        if not (isinstance(fidelity, str) and fidelity in FIDELITIES):
            raise UserError(f"fidelity = {short_repr(fidelity)}: allowed values are {', '.join(FIDELITIES)}")
        if not (isinstance(solver, str) and solver in SOLVERS):
            raise UserError(f"solver = {short_repr(solver)}: allowed values are {', '.join(SOLVERS)}")
        if oversample is not None and not oversample_allowed(oversample):
            raise UserError(f"oversample = {short_repr(oversample)}: allowed values are {OVERSAMPLE_ALLOWED}")
        if not (_whole_number(seed) and SEED_RANGE[0] <= seed <= SEED_RANGE[1]):
            raise UserError(f"seed = {short_repr(seed)}: expected a whole number in [{SEED_RANGE[0]}, {SEED_RANGE[1]}]")
        if tolerance is not None:
            from .scene import TOLERANCE_RANGE

            lo, hi = TOLERANCE_RANGE
            if not (_real_number(tolerance) and lo <= tolerance <= hi):
                raise UserError(f"tolerance = {short_repr(tolerance)}: allowed range is [{lo:g}, {hi:g}] "
                                f"(a relative error, as the scene's fidelity.tolerance)")
        # here, not only in the skidding tier: where fidelity auto starts on the kinematic tier, a
        # NaN or negative step was taken without a word and refused at the first switch to the
        # skidding tier, in the middle of a run
        check_rk4_step(rk4_step)
        self.scene = scene
        self.bearing = scene.bearing
        self.sample_rate = float(sample_rate)
        # the tiers run at the physics rate and the sensor chain decimates from it to the output
        self.physics_per_sample = physics_rate_factor(self.sample_rate)
        self.physics_rate = self.sample_rate * self.physics_per_sample
        self.seed = int(seed)
        self.solver = solver
        self.rk4_step = rk4_step
        self.requested_fidelity = fidelity
        self._shaft_speed = float(scene.shaft_speed)
        self._radial_load = np.array(scene.radial_load, dtype=float)
        self.index = 0                       # absolute index of the next output sample
        self.tier_switches = 0
        self.last_tier_switch = None         # (time s, old tier, new tier) of the latest switch

        from .fidelity import select_tier

        request = scene.fidelity if fidelity == "auto" else fidelity
        if request == "auto" and oversample is not None and oversample > AUTO_OVERSAMPLE_MAX:
            raise OversampleForAuto(oversample)
        # as `bearing-sim render` says them: settings that would silently do nothing
        if rk4_step is not None and solver != "rk4":
            raise UserError(f"rk4_step = {short_repr(rk4_step)}: applies to solver='rk4' only (given solver={solver!r})")
        if request == "kinematic" and solver != "default":
            raise UserError(f"solver = {short_repr(solver)}: applies to the skidding tier only, and "
                            + ("fidelity='kinematic'" if fidelity == "kinematic"
                               else f"scene {scene.name}'s fidelity.tier: kinematic")
                            + " runs the kinematic tier")
        self.selection = select_tier(scene, request, self._shaft_speed, self._radial_load,
                                     float(tolerance) if tolerance is not None else scene.fidelity_tolerance)
        self.tier = self.selection.tier
        # only the kinematic tier and the default solver take it: with no kinematic tier to run,
        # "rk4" and "reference" would ignore it
        if oversample is not None and solver != "default" and self.tier == "skidding" and not self.can_switch_tiers:
            raise OversampleWithOwnStep(oversample, solver)
        self._oversample = None if oversample is None else int(oversample)
        from .physics.defects import DefectSchedule

        # defects that appear or grow: their sizes follow the physics, which runs ahead of the
        # output by the sensor chain's lookahead (``_physics_index``: its next output sample);
        # the sizes in force are the running tier's ``defect_sizes``
        self._defect_schedule = DefectSchedule(scene.defects, self.sample_rate)
        self._physics_index = 0
        # on a cold cache: one line on stderr from the commands while the tier's kernels compile,
        # here and in the first advance (its main kernel), and their time after it
        self._compiling = Notice()
        with self._compiling.within(self._tier_kernels):
            self._model = self._build_model(self.tier, self._defect_schedule.sizes(0))
            self._build_chain()

    def __copy__(self):
        """An independent simulator that continues from here bit for bit, as ``copy.deepcopy``
        (and pickle) give: a shallow copy shared the tier's and the sensor chain's buffers, and
        advancing one broke the other."""
        import copy

        return copy.deepcopy(self)

    # ---- construction ---------------------------------------------------------------------
    def _tier_kernels(self) -> str:
        """What a compilation for the running tier is said to compile."""
        return f"the {self.tier} tier's kernels"

    def _build_model(self, tier: str, defect_sizes: tuple, ellipse_ball_load: float | None = None,
                     takes_over_from=None, runs: bool = True):
        """The ``tier``'s model at the present operating point with the defects at
        ``defect_sizes``; ``ellipse_ball_load`` (N) from the tier it takes over from, so that a
        wandering ball defect meets the races as often after a switch as before (None: the new
        model's own most loaded ball); ``takes_over_from``: that tier's model, whose state the
        new one continues from (``adopt_state``).  ``runs`` False: a throwaway whose signal
        nobody gets (``prepare_switches``), which warns of nothing."""
        if tier == "kinematic":
            from .physics.kinematic import KinematicModel

            model = KinematicModel(self.scene, self.physics_rate, self._oversample, self.seed,
                                   self._shaft_speed, self._radial_load, defect_sizes=defect_sizes,
                                   ellipse_ball_load=ellipse_ball_load)
            if takes_over_from is not None:
                model.adopt_state(takes_over_from)
            return model
        from .physics.skidding import STEP_CHECK_MAX, SkiddingModel

        # the default's step check (at its own step only: ``oversample`` None) where the model
        # starts the signal; a tier switch has no time for it, a throwaway no use.  Where fidelity
        # auto may switch tiers it takes at most AUTO_OVERSAMPLE_MAX, as the user may
        check = None
        if runs and takes_over_from is None:
            check = AUTO_OVERSAMPLE_MAX if self.can_switch_tiers else STEP_CHECK_MAX
        # the skidding tier takes the state over as it is built: it then needs no equilibrium
        model = SkiddingModel(self.scene, self.physics_rate, self.seed, self._shaft_speed,
                              self._radial_load, solver=self.solver, rk4_step=self.rk4_step,
                              oversample=self._oversample, defect_sizes=defect_sizes,
                              ellipse_ball_load=ellipse_ball_load, takes_over_from=takes_over_from,
                              step_check=check)
        # a divergence is told at the signal's time (the physics runs ahead of the output)
        model.start_time = self._physics_index / self.sample_rate
        if model.step_warning and runs:
            # what the step check could not fix (capped, or not run at a tier switch)
            warnings.warn(model.step_warning, DefaultStepWarning, stacklevel=2)
        return model

    def _build_chain(self):
        from .physics.sensor import AccelerometerChain

        # internal samples per output sample: the sensor chain's rate, which both tiers share (at
        # least 4 per physics sample, whatever ``oversample``, the integration steps, is)
        self.chain_oversample = int(round(self._model.internal_rate / self.sample_rate))
        self.chain = AccelerometerChain(self.scene.sensor, self.sample_rate, self.chain_oversample,
                                        self.seed)
        self.accel_channels = tuple(f"accel_{a}" for a in self.scene.sensor.axes)
        self.contact_channels = contact_channel_names(self.bearing.balls)
        cols = self.chain.axis_columns
        self._columns = None if cols == [0, 1] else cols     # None: the chain's output as it is
        # run the physics ahead by the FIR group delay; keep the per-output-sample series that
        # belong to those future samples (rows of _pending) until their time comes
        self._pending = self._series(0)
        ahead = self.chain.lookahead_samples
        if ahead:
            s, (lx, ly) = self._shaft_speed, self._radial_load
            self._pending = self._run(ahead, s, s, lx, ly, lx, ly, None)

    # ---- stepping ---------------------------------------------------------------------------
    @property
    def shaft_speed(self) -> float:
        """The shaft speed (rad/s) of the latest command (the scene's until an ``advance`` gives
        one): where the latest ramp ends.  The batch's ``shaft_speed`` has what each sample had."""
        return self._shaft_speed

    @property
    def radial_load(self) -> tuple:
        """The (x, y) load (N) of the latest command, as ``shaft_speed``."""
        return tuple(self._radial_load)

    @property
    def oversample(self) -> int | None:
        """Integration steps per physics sample (an output sample from 15 kHz on,
        ``physics_rate``) of the running tier (the constructor's
        ``oversample``, else the tier's default, which for the kinematic tier follows the bearing
        mode at the load); None for the skidding tier's "rk4" and
        "reference" solvers, whose steps are set in seconds.  The sensor chain's rate is
        ``chain_oversample``."""
        if self.tier == "skidding":
            return self._model.oversample if self.solver == "default" else None
        return self._model.decimation

    @property
    def step_warning(self) -> str:
        """The running tier's ``DefaultStepWarning`` text (the skidding tier's default at a step
        its step check could not bring within its target, or did not check at a tier switch),
        "" where there is none: the one line warned when that model was built, kept for
        ``/diagnostics`` (``recording.render.tier_values``), which outlives a terminal."""
        return getattr(self._model, "step_warning", "")

    @property
    def centrifugal(self) -> bool | None:
        """Whether the kinematic tier's balls carry their centrifugal force (True) or are massless
        (False), as decided at its last linearisation by F_c / Q_max
        (``physics.kinematic.carries_centrifugal_force``: F_c = m_b (D_m / 2) w_c^2 in N, Q_max =
        5 W / Z) against ``CENTRIFUGAL_GATE`` (0.01), and on a bearing of small radial play (0 <
        C_r / D <= ``CENTRIFUGAL_SMALL_PLAY``, 0.005) against ``CENTRIFUGAL_SMALL_PLAY_GATE``
        (0.0012); None for the skidding tier, whose balls always have their mass."""
        if self.tier == "skidding":
            return None
        return self._model.centrifugal

    @property
    def max_advance(self) -> int:
        """The most output samples one ``advance`` takes: ``MAX_ADVANCE_INTERNAL`` internal samples
        of the sensor chain (a memory bound; longer signals go in chunks, the same samples)."""
        return max(1, MAX_ADVANCE_INTERNAL // self.chain_oversample)

    @property
    def time(self) -> float:
        """Time of the next output sample (s)."""
        return self.index / self.sample_rate

    def _series(self, rows: int) -> dict:
        """Empty per-output-sample series: contact forces (N), cage and shaft speed (rad/s),
        load (N, x and y)."""
        return {"forces": np.empty((rows, 2 * self.bearing.balls)), "cage_speed": np.empty(rows),
                "shaft_speed": np.empty(rows), "load": np.empty((rows, 2))}

    def _run(self, n, s0, s1, l0x, l0y, l1x, l1y, index0):
        """Step the tier by ``n`` output samples' worth (speed in rad/s and load in N ramped
        from the first to the second value) and feed the accelerometer chain.  Returns the
        series of every row: the pending ones first, then the n new ones (views of one new
        array per series, so that a batch never shares memory with a later one); with
        ``index0`` (absolute output index), also the chain's n output samples (n, 2).  Where a
        defect appears or grows inside the n samples, the tier runs up to that sample, takes the
        new sizes and runs on (the ramp continues across)."""
        m = self.chain_oversample
        pend = self._pending
        p = pend["cage_speed"].shape[0]
        series = self._series(p + n)
        for key, val in series.items():
            val[:p] = pend[key]
        acc = self.chain.input_view(n * m)
        extras = {}
        start = self._physics_index
        done = 0
        whole = self._defect_schedule.static        # the usual case: one call, as given
        while done < n:
            if whole:
                end = n
                sa, la, sb, lb = s0, (l0x, l0y), s1, (l1x, l1y)
                rows, seg_acc = slice(p, None), acc
            else:
                sizes = self._defect_schedule.sizes(start + done)
                change = self._defect_schedule.next_change(start + done)
                end = n if change is None else min(n, change - start)
                if sizes != self._model.defect_sizes:
                    self._model.set_defect_sizes(sizes)
                # the ramp's values at the segment's ends, the call's own at its ends
                sa, la = self._on_ramp(done, n, s0, s1, l0x, l0y, l1x, l1y)
                sb, lb = self._on_ramp(end, n, s0, s1, l0x, l0y, l1x, l1y)
                rows, seg_acc = slice(p + done, p + end), acc[done * m:end * m]
            # the tier gives one row per physics sample; an output sample is every k-th
            k = self.physics_per_sample
            if hasattr(self._model, "advance_into"):       # writes into the buffers: no copies
                if k == 1:
                    self._model.advance_into((end - done) * m, sa, sb, la, lb, seg_acc,
                                             series["forces"][rows], series["cage_speed"][rows])
                else:
                    forces = np.empty(((end - done) * k, series["forces"].shape[1]))
                    cage = np.empty((end - done) * k)
                    self._model.advance_into((end - done) * m, sa, sb, la, lb, seg_acc, forces, cage)
                    series["forces"][rows] = forces[::k]
                    series["cage_speed"][rows] = cage[::k]
            else:
                out = self._model.advance((end - done) * m, sa, sb, np.array(la), np.array(lb))
                seg_acc[:] = out.accel
                nb = self.bearing.balls
                series["forces"][rows, :nb] = out.inner_force[::k]
                series["forces"][rows, nb:] = out.outer_force[::k]
                series["cage_speed"][rows] = out.cage_speed[::k]
                for key, val in out.extras.items():
                    extras.setdefault(key, []).append(val[::k])
            done = end
        for key, parts in extras.items():
            old = pend.get("x_" + key)
            if old is None and p:
                # the tier that has them took over now: the pending rows, the first of this
                # call's output, were computed by the other one, which has no such series.  NaN
                # keeps every row on its own sample (without it, every batch after a switch to
                # the skidding tier carried the values of the samples ``p`` later)
                old = np.full((p, *parts[0].shape[1:]), np.nan)
            if old is not None:
                parts.insert(0, old)
            series["x_" + key] = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=0)
        self._physics_index = start + n
        _ramp(series["shaft_speed"][p:], series["load"][p:], s0, s1, l0x, l0y, l1x, l1y)
        accel = self.chain.commit(n * m, index0)
        return series if index0 is None else (series, accel)

    @staticmethod
    def _on_ramp(k, n, s0, s1, l0x, l0y, l1x, l1y):
        """Speed and (x, y) load at k / n of the way along a call's ramp (its own values at its
        ends, so that a call that is not split runs exactly as given)."""
        if k == 0:
            return s0, (l0x, l0y)
        if k == n:
            return s1, (l1x, l1y)
        f = k / n
        return s0 + (s1 - s0) * f, (l0x + (l1x - l0x) * f, l0y + (l1y - l0y) * f)

    def _command(self, shaft_speed, radial_load) -> tuple:
        """The operating point that ``advance``, ``switch_ahead`` and ``maybe_switch_tier`` are
        given, checked: (speed rad/s, (x, y) N) as floats, the latest command's where one is None;
        else a one-line UserError naming the argument, its value and what is allowed."""
        # numbers only: float('167') and float(True) would take a string or a bool for one
        if shaft_speed is not None and not _real_number(shaft_speed):
            raise UserError(f"shaft_speed = {short_repr(shaft_speed)}: expected a number, rad/s")
        if radial_load is None:
            lx, ly = (float(v) for v in self._radial_load)
        else:
            # exactly two numbers, not anything numpy makes two of: [[0, -50]] and a (2, 1) array
            # were taken as (0, -50), and a ragged [[0], -50] was numpy's ValueError
            if isinstance(radial_load, np.ndarray):
                two = radial_load.shape == (2,) and radial_load.dtype.kind in "iuf"
            else:
                two = isinstance(radial_load, (list, tuple)) and len(radial_load) == 2 \
                    and all(_real_number(v) for v in radial_load)
            if not two:
                raise UserError(f"radial_load = {short_repr(radial_load)}: expected two numbers (x, y), N")
            lx, ly = radial_load
        s = self._shaft_speed if shaft_speed is None else _finite_float(shaft_speed)
        if s is None:
            raise UserError(f"shaft_speed = {_plain(shaft_speed)} rad/s: must be a finite number")
        if _finite_float(lx) is None or _finite_float(ly) is None:
            raise UserError(f"radial_load = ({_plain(lx)}, {_plain(ly)}) N: must be finite numbers")
        lx, ly = float(lx), float(ly)
        # the bearing's own limits, as a scene's operating point and profile and the live node's
        # inputs have them (InputLimits: n*dm and 2 x C0; never beyond 60 000 rpm and 1 MN, where
        # the model's output is not a number); the model's pure rolling and elastic contacts do
        # not hold beyond them (until 2026-11-29 only those wide bounds: 900 kN on an ER-16K ran)
        error = _operating_point_error(self.bearing, s, (lx, ly), "shaft_speed",
                                       f"{s:g} rad/s ({s / RPM:g} rpm)", "radial_load") or \
            _load_and_weight_error(self.bearing, (lx, ly), "radial_load", self.scene.structure.shaft_mass,
                                   self.scene.gravity, "the scene's structure.shaft_mass")
        if error:
            raise UserError(error)
        return s, (lx, ly)

    def advance(self, n: int, shaft_speed: float | None = None, radial_load=None) -> Batch:
        """Advance by ``n`` output samples (1 - ``max_advance``) and return them as a :class:`Batch`.
        ``shaft_speed`` (rad/s, not rpm) and ``radial_load`` (N, (x, y), y up) replace the operating
        point; the change is ramped over this call, and shows in the samples the sensor chain's
        lookahead later (19 samples at 15 kHz: the physics runs that far ahead of the output).
        Chunks give the same samples as one call at the same operating point (a command ramps
        over the call that gives it, so where it falls is part of the run).  A bad argument, or an
        operating point beyond the bearing's limits, is a one-line UserError."""
        if not (_whole_number(n) and n > 0):
            raise UserError(f"n = {short_repr(n)}: expected a whole number of samples > 0")
        if n > self.max_advance:
            raise UserError(f"n = {short_repr(n)}: at most {self.max_advance} samples ({self.max_advance / self.sample_rate:g} s) "
                            f"per advance at {self.sample_rate:g} Hz ({MAX_ADVANCE_INTERNAL} internal samples, about "
                            f"2 GB of arrays); advance in chunks of up to sim.max_advance, which give the same samples")
        s0 = self._shaft_speed
        l0x, l0y = self._radial_load
        s1, (l1x, l1y) = self._command(shaft_speed, radial_load)
        n = int(n)
        with self._compiling.within(self._tier_kernels):    # a switch's new tier too
            self._maybe_switch_tier(s1, (l1x, l1y))
            series, accel = self._run(n, s0, s1, l0x, l0y, l1x, l1y, self.index)
        self._compiling.finish()
        self._pending = {k: v[n:] for k, v in series.items()}
        self._shaft_speed = s1
        self._radial_load = np.array([l1x, l1y])
        batch = Batch(
            t0=self.index / self.sample_rate,
            index0=self.index,
            sample_rate=self.sample_rate,
            accel=accel if self._columns is None else accel[:, self._columns],
            accel_channels=self.accel_channels,
            contact_forces=series["forces"][:n],
            contact_channels=self.contact_channels,
            cage_speed=series["cage_speed"][:n],
            shaft_speed=series["shaft_speed"][:n],
            radial_load=series["load"][:n],
            tier=self.tier,
            extras={k[2:]: v[:n] for k, v in series.items() if k.startswith("x_")},
        )
        self.index += n
        return batch

    @property
    def defect_sizes(self) -> tuple:
        """Size of each of the scene's defects (0 = not there yet, 1 = full size) at the latest
        output sample (``index - 1``; at sample 0 before the first advance); a scene's
        ``onset_s`` and ``growth_s`` move them.  The physics runs ahead of the output by the
        sensor chain's lookahead and may be there already."""
        return self.defect_sizes_at(self.index - 1)

    def defect_sizes_at(self, sample: int) -> tuple:
        """Size of each of the scene's defects at output sample ``sample`` (sample 0 for a
        negative one): what the signal holds there, e.g. at the last sample a node has published
        while it computes ahead."""
        if not _whole_number(sample):
            raise UserError(f"sample = {short_repr(sample)}: expected a whole number (an output sample index)")
        return self._defect_schedule.sizes(max(int(sample), 0))

    @property
    def defect_onsets_s(self) -> tuple:
        """Each of the scene's defects' onset in signal time (s): its first output sample's
        time, the scene's ``onset_s`` rounded up to the sample grid (0 for one there from the
        start)."""
        return tuple(k / self.sample_rate for k in self._defect_schedule.onset_samples)

    # ---- fidelity -----------------------------------------------------------------------------
    def maybe_switch_tier(self, shaft_speed: float, radial_load) -> bool:
        """With ``fidelity="auto"``, re-select the tier for a new operating point (rad/s; (x, y) N,
        checked as ``advance`` checks them) and switch without a discontinuity (the new tier
        starts from the old one's state)."""
        return self._maybe_switch_tier(*self._command(shaft_speed, radial_load))

    def _maybe_switch_tier(self, shaft_speed: float, radial_load: tuple) -> bool:
        """``maybe_switch_tier`` of an operating point already checked (``_command``)."""
        sel = reselect_tier(self.scene, self.requested_fidelity, self.selection,
                            (self._shaft_speed, self._radial_load), (shaft_speed, radial_load))
        if sel is None:
            return False
        if sel.tier == self.tier:
            self.selection = sel
            return False
        old, old_tier = self._model, self.tier
        self.tier = sel.tier
        self.selection = sel
        new = self._build_model(sel.tier, old.defect_sizes, old.ellipse_ball_load, takes_over_from=old)
        if int(round(new.internal_rate / self.sample_rate)) != self.chain_oversample:
            raise RuntimeError("tiers must share the internal rate to switch without a seam")
        self._model = new
        self.tier_switches += 1
        self.last_tier_switch = (self.time, old_tier, sel.tier)
        return True

    def switch_ahead(self, shaft_speed: float, radial_load) -> bool:
        """Whether advancing to this operating point (rad/s; (x, y) N) switches the tier: the
        live node then starts the batch where it has the most time before the next publication
        (the new tier's set-up: about 8 ms to the skidding tier, several times a batch's work).
        The arguments are checked as ``advance`` checks them."""
        sel = reselect_tier(self.scene, self.requested_fidelity, self.selection,
                            (self._shaft_speed, self._radial_load), self._command(shaft_speed, radial_load))
        return sel is not None and sel.tier != self.tier

    @property
    def can_switch_tiers(self) -> bool:
        """Whether ``fidelity="auto"`` may change the tier at run time: asked for by the caller
        and by the scene, and the scene does not need the skidding tier for its outputs."""
        from .fidelity import needs_skidding

        return _auto_reselects(self.scene, self.requested_fidelity) and not needs_skidding(self.scene)

    def load_kernels(self) -> None:
        """Load (on a cold cache: compile) the rest of the running tier's kernels now, those that
        its first ``advance`` would load (the sensor chain's output), by advancing a copy by one
        sample; on a cold cache the commands' line ``the ... tier's kernels compiled in N s`` is
        said here.  The live node calls it before its start line and before ``prepare_switches``,
        whose background tier's lines then follow it instead of coming before it.  Nothing of
        this simulator changes (the copy is independent: ``__copy__``)."""
        import copy

        from .physics.skidding import SolverDiverged

        twin = copy.deepcopy(self)      # its notice is a copy of this one's: said once, by it
        try:
            twin.advance(1)
        except SolverDiverged:
            pass        # the kernels are loaded all the same; the real run says the divergence
        twin._compiling.finish()        # nothing where its advance said it
        self._compiling = twin._compiling

    def prepare_switches(self) -> None:
        """Load (on a cold cache: compile) the other tier's kernels now, by handing a copy of the
        running tier's state to a throwaway model of the other one and running it for a few
        samples, so that a switch at run time costs only that tier's set-up (about 8 ms to the
        skidding tier, 2 ms back) instead of also loading its kernels (25 ms more when
        cached, 10-15 s on a cold cache).  Nothing of this simulator changes.  A no-op where the
        tier cannot switch."""
        if not self.can_switch_tiers:
            return
        import copy

        other = "skidding" if self.tier == "kinematic" else "kinematic"
        notice = Notice()           # its own: the node runs this beside its start
        with notice.within(f"the {other} tier's kernels", " in the background, for a switch of tier"):
            # the hand-over too (it reads the old tier's films); from a copy, which it may update
            # (its step's warning, if any, is said when a switch builds the tier that runs: the
            # node under auto on the kinematic tier said it of a tier it never ran)
            model = self._build_model(other, self._model.defect_sizes, self._model.ellipse_ball_load,
                                      takes_over_from=copy.deepcopy(self._model), runs=False)
            w, load = self._shaft_speed, self._radial_load.copy()
            from .physics.skidding import SolverDiverged

            try:
                model.advance(8 * self.chain_oversample, w, w, load, load)     # 8 output samples
            except SolverDiverged:
                pass        # the kernels are loaded all the same; the throwaway's signal is nothing
        notice.finish()

    # ---- state for the JointState topic ----------------------------------------------------
    def snapshot(self):
        """Angles and speeds of shaft, cage and balls (see ``physics.KinematicSnapshot``) at the
        time of the next output sample (``time``, the end of the latest batch: the stamp of the
        ``state`` message), not where the physics is: it runs ahead by the sensor chain's
        lookahead (19 samples, 1.3 ms at 15 kHz, a 12 degree turn of the shaft at 1600 rpm).  The
        shaft's and the cage's angles are taken back by the integral of their speeds over those
        samples (trapezoids over the per-sample series the simulator holds for them; exact at a
        steady speed); each ball is taken back with the cage (a ball moves against its pocket by
        far less than a sample's turn) and its speed moved by the cage's change."""
        snap = self._model.snapshot()
        ahead = self._pending["shaft_speed"]
        if ahead.size == 0:
            return snap
        cage_ahead = self._pending["cage_speed"]
        dt = 1.0 / self.sample_rate

        def back(series, now):
            # integral over [time, time + ahead.size * dt] of the speed, trapezoids per sample
            return dt * (series.sum() - 0.5 * series[0] + 0.5 * now)

        cage_back = back(cage_ahead, snap.cage_speed)
        cage_change = cage_ahead[0] - snap.cage_speed
        return type(snap)(snap.shaft_angle - back(ahead, snap.shaft_speed), float(ahead[0]),
                          snap.cage_angle - cage_back, float(cage_ahead[0]),
                          snap.ball_angles - cage_back, snap.ball_speeds + cage_change)
