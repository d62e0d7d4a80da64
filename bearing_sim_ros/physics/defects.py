"""Local defects and race waviness as a loss (or gain) of ball-race interference.

Both tiers use the same tables and the same kernel, so a defect means the same thing in each.

Geometry.  A ball (radius r) rolling into a pit of width w on a race meets the pit's edges.  At
an arc distance s from the nearer edge the ball centre can drop by

    drop(s) = rho - sqrt(rho^2 - s^2),     rho = R_x = 1 / (1/r +- 1/R_race)

(the effective radius of the contact in the rolling direction: "+" for the convex inner race,
"-" for the concave outer race), and never deeper than the pit itself.  It reduces to the
flat-race sagitta r - sqrt(r^2 - s^2).  The same expression holds for a pit on the ball meeting
either race.  Seed 000's H_i / H_o (eqs 5-9) are sagittas of the same kind, but measure the
distance l from the edge where the ball enters (l = 0.5 D sin(phi), phi the angle turned since
it entered), so their drop grows across the whole pit and falls back to 0 in one jump at the
exit edge; for the ER-16K's 0.6 mm pits that is 57.4 um (inner) and 37.8 um (outer) at the exit
edge, against 14.3 and 9.4 um at the middle here.  A ball bridges a pit: it sinks from both
edges at once and climbs out along the exit edge as it went in, so the distance here is to the
nearer edge.  Impact amplitudes are therefore not comparable with seed 000's Figs 10-13; the
fault frequencies are.
Seed 001 Sec. 3.3 gives simpler depth functions; all are available (``profile``):

    geometric    the expression above (default)
    rectangular  the largest drop over the whole width (seed 001 H1, "crack")
    half_sine    largest drop x sin(pi * position) (seed 001 H2)
    piecewise    linear entry ramp, flat, linear exit (seed 001 H3)
    auto         seed 001's choice from ball/defect size ratio and the defect's aspect ratio
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from numba import njit

from .rng import uniform

KIND_INNER, KIND_OUTER, KIND_BALL = 0, 1, 2
PROFILE_CODES = {"geometric": 0, "rectangular": 1, "half_sine": 2, "piecewise": 3}
KIND_CODES = {"inner": KIND_INNER, "outer": KIND_OUTER, "ball": KIND_BALL}

# columns of the defect table (float64, one row per defect)
D_KIND, D_HALF, D_DEPTH, D_ANGLE, D_PROFILE, D_BALL, D_RHO_I, D_RHO_O, D_HMAX_I, D_HMAX_O, D_RAMP_I, D_RAMP_O = range(12)
# ball defects with a wandering spin axis: spin turns between latitude draws (0 = fixed axis),
# seed of the draws, and the reach of the contact ellipse in sin(latitude) (full / ramp width)
D_WANDER, D_WSEED, D_WREACH, D_WRAMP = range(12, 16)
# the defect's index in the scene: its latitude draws' stream, the same whichever of the scene's
# defects are present yet (a defect with an onset is left out of the table before it)
D_INDEX = 16
DEFECT_COLUMNS = 17
WANDER_STREAM = 3000           # rng stream of scene defect k's latitude draws: WANDER_STREAM + k
NOMINAL_BALL_LOAD = 100.0      # N: ball load for the contact ellipse when the caller gives none (yet)


def resolve_profile(defect, ball_diameter: float) -> str:
    """Seed 001 Sec. 3.3: the depth function from the ball/defect size ratio eta_bd = d / width
    and the aspect ratio eta_d = length / width."""
    if defect.profile != "auto":
        return defect.profile
    eta_bd = ball_diameter / defect.width
    eta_d = defect.length / defect.width
    if eta_bd >= 10.0:          # a crack: the ball bridges it at once
        return "rectangular"
    if eta_bd > 1.0 and eta_d <= 1.0:
        return "half_sine"
    return "piecewise"


def _sag(rho: float, s: float, depth: float) -> float:
    if s >= rho:
        return depth
    return min(depth, rho - math.sqrt(rho * rho - s * s))


def defect_table(defects, bearing, seed: int = 0, ball_load: float | None = None) -> np.ndarray:
    """Pack scene defects into the float table the kernels read.

    Half-span D_HALF is an angle on the defect's own body: on the race (rad about the bearing
    axis) for race defects, on the ball (rad about the ball centre) for a ball defect.
    ``seed`` draws the latitudes of a wandering ball defect; ``ball_load`` (N, default
    NOMINAL_BALL_LOAD) sizes the contact ellipse that the defect must lie within to be met.
    """
    r = 0.5 * bearing.ball_diameter
    ri = 0.5 * bearing.inner_race_diameter
    ro = 0.5 * bearing.outer_race_diameter
    rho_i = r * ri / (r + ri)
    rho_o = r * ro / (ro - r)
    table = np.zeros((len(defects), DEFECT_COLUMNS))
    for k, d in enumerate(defects):
        kind = KIND_CODES[d.kind]
        body_radius = {KIND_INNER: ri, KIND_OUTER: ro, KIND_BALL: r}[kind]
        half = 0.5 * d.width / body_radius
        row = table[k]
        row[D_KIND] = kind
        row[D_HALF] = half
        row[D_DEPTH] = d.depth
        row[D_ANGLE] = d.angle
        row[D_PROFILE] = PROFILE_CODES[resolve_profile(d, bearing.ball_diameter)]
        row[D_BALL] = d.ball
        row[D_INDEX] = k
        row[D_RHO_I] = rho_i
        row[D_RHO_O] = rho_o
        # largest drop: at the middle of the pit
        row[D_HMAX_I] = _sag(rho_i, 0.5 * d.width, d.depth)
        row[D_HMAX_O] = _sag(rho_o, 0.5 * d.width, d.depth)
        # arc length over which the geometric drop reaches its largest value (piecewise ramps)
        for col, rho, hmax in ((D_RAMP_I, rho_i, row[D_HMAX_I]), (D_RAMP_O, rho_o, row[D_HMAX_O])):
            row[col] = min(0.5 * d.width, math.sqrt(max(2.0 * rho * hmax - hmax * hmax, 0.0)))
        wander = getattr(d, "wander_turns", 0.0)
        if kind == KIND_BALL and wander > 0.0:
            # the defect (axial extent `length`) is met while its centre lies within the contact
            # ellipse's transverse semi-axis a (+ half its length) of the rolling track
            load = NOMINAL_BALL_LOAD if ball_load is None else max(float(ball_load), 1e-3)
            a = max(bearing.inner_contact.a_coeff, bearing.outer_contact.a_coeff) * load ** (1.0 / 3.0)
            row[D_WANDER] = wander
            row[D_WSEED] = seed
            row[D_WREACH] = min((a + 0.5 * d.length) / r, 1.0)
            row[D_WRAMP] = max(min(d.length, a) / r, 1e-9)
    return table


# a growing defect's size changes in steps of this much signal (s): the tiers take the defect
# table per call, so each change splits an advance; 10 ms is the live node's batch
GROWTH_UPDATE = 0.01


def scaled_defect(defect, size: float):
    """``defect`` at ``size`` (0-1] of its full extent: width, length and depth scale together,
    as a spall that grows from a small shallow pit."""
    if size >= 1.0:
        return defect
    return dataclasses.replace(defect, width=defect.width * size, length=defect.length * size,
                               depth=defect.depth * size)


def active_defect_table(defects, sizes, bearing, seed: int = 0, ball_load: float | None = None) -> np.ndarray:
    """The defect table (:func:`defect_table`) of the defects present at ``sizes`` (one factor
    0-1 per scene defect, None = all at full size): each at its size, a defect of size 0 left
    out.  Rows keep the defect's index in the scene (``D_INDEX``)."""
    if sizes is None:
        return defect_table(defects, bearing, seed, ball_load)
    table = defect_table([scaled_defect(d, s) if s > 0.0 else d for d, s in zip(defects, sizes)],
                         bearing, seed, ball_load)
    return np.ascontiguousarray(table[np.asarray(sizes, dtype=float) > 0.0])


class DefectSchedule:
    """When a scene's defects appear and how they grow, on the grid of output samples at
    ``sample_rate`` (Hz).  A defect with ``onset`` (s) is absent before the first sample at or
    after it; with ``growth`` (s) it then grows in steps every ``GROWTH_UPDATE`` from
    ``GROWTH_UPDATE / growth`` of its size to its full size at ``onset + growth``.  Sizes are
    functions of the sample index alone, so chunking does not change them."""

    def __init__(self, defects, sample_rate: float):
        self.defects = tuple(defects)
        rate = float(sample_rate)
        self._onsets = [math.ceil(d.onset * rate - 1e-9) for d in self.defects]
        self._update = max(1, int(round(GROWTH_UPDATE * rate)))
        self._growth = [d.growth * rate for d in self.defects]
        self.static = all(o == 0 and g == 0.0 for o, g in zip(self._onsets, self._growth))

    @property
    def onset_samples(self) -> tuple:
        """Each defect's first output sample (0 for a defect there from the start)."""
        return tuple(self._onsets)

    def size(self, k: int, index: int) -> float:
        """Size (0-1) of defect k at output sample ``index``."""
        since = index - self._onsets[k]
        if since < 0:
            return 0.0
        grow = self._growth[k]
        if grow <= 0.0:
            return 1.0
        return min(1.0, (since // self._update + 1) * self._update / grow)

    def sizes(self, index: int) -> tuple:
        """Sizes of every defect at output sample ``index``."""
        return tuple(self.size(k, index) for k in range(len(self.defects)))

    def next_change(self, index: int) -> int | None:
        """The first output sample after ``index`` at which a size changes (None: never)."""
        best = None
        for k in range(len(self.defects)):
            onset = self._onsets[k]
            if index < onset:
                nxt = onset
            elif self.size(k, index) < 1.0:
                nxt = onset + ((index - onset) // self._update + 1) * self._update
            else:
                continue
            best = nxt if best is None else min(best, nxt)
        return best


def has_wandering_defect(table) -> bool:
    """Whether the defect table holds a ball defect with a wandering spin axis (the only rows
    the contact ellipse's ball load changes)."""
    return bool(np.any(table[:, D_WANDER] > 0.0)) if table.shape[0] else False


@njit(cache=True, inline="always")
def wander_reach(table, k, ball_spin):
    """How much of ball defect k's interference loss applies (0..1) at the ball's spin angle
    (rad): 1 for a fixed spin axis.  With a wandering axis the defect's latitude, as
    s = sin(latitude), is a linear interpolation of independent uniform draws on [-1, 1]
    (isotropic axis) made every D_WANDER spin turns, hashed from (seed, the defect's index in the
    scene, turn index), so it is a function of the spin angle alone (chunk-invariant, the same in
    both tiers).  The loss applies fully while |s| < reach - ramp, fades linearly to 0 at
    |s| = reach (the defect sliding out of the contact ellipse)."""
    turns = table[k, D_WANDER]
    if turns <= 0.0:
        return 1.0
    q = ball_spin / (2.0 * math.pi * turns)
    kq = math.floor(q)
    f = q - kq
    seed = np.int64(table[k, D_WSEED])
    stream = WANDER_STREAM + np.int64(table[k, D_INDEX])
    ki = np.int64(kq)
    s0 = 2.0 * uniform(seed, stream, np.uint64(ki)) - 1.0
    s1 = 2.0 * uniform(seed, stream, np.uint64(ki + 1)) - 1.0
    g = (table[k, D_WREACH] - abs(s0 + (s1 - s0) * f)) / table[k, D_WRAMP]
    return 0.0 if g <= 0.0 else (1.0 if g >= 1.0 else g)


def waviness_table(waviness) -> np.ndarray:
    """Rows (race 0 inner / 1 outer, order, amplitude m, phase rad)."""
    table = np.zeros((len(waviness), 4))
    for k, w in enumerate(waviness):
        table[k] = (0 if w.race == "inner" else 1, w.order, w.amplitude, w.phase)
    return table


@njit(cache=True, inline="always")
def wrap(angle):
    """Angle wrapped to [-pi, pi).  floor, not %, which compiles to a slow fmod."""
    return angle - 2.0 * math.pi * math.floor((angle + math.pi) * (0.5 / math.pi))


@njit(cache=True, inline="always")
def _profile_drop(profile, u, half, radius, rho, hmax, ramp, depth):
    """Drop of a ball at angle u from the defect centre (|u| < half) on a body of ``radius``."""
    s = (half - abs(u)) * radius                    # arc distance from the nearer edge, m
    if profile == 0:                                # geometric
        if s >= rho:
            return depth
        g = rho - math.sqrt(rho * rho - s * s)
        return g if g < depth else depth
    if profile == 1:                                # rectangular
        return hmax
    if profile == 2:                                # half-sine
        return hmax * math.sin(0.5 * math.pi * (u + half) / half)
    f = s / ramp if ramp > 0.0 else 1.0            # piecewise: ramp, flat, ramp
    return hmax * (f if f < 1.0 else 1.0)


@njit(cache=True, inline="always")
def _profile_slope(profile, u, half, radius, rho, hmax, ramp, depth):
    """d drop / d u of :func:`_profile_drop` (m/rad); at the centre of a pit (u = 0), where the
    geometric and piecewise profiles have a kink, the slope for u > 0."""
    s = (half - abs(u)) * radius
    ds_du = -radius if u >= 0.0 else radius
    if profile == 0:                                # geometric
        if s >= rho:
            return 0.0
        root = math.sqrt(rho * rho - s * s)
        return ds_du * s / root if rho - root < depth else 0.0
    if profile == 2:                                # half-sine
        return hmax * math.cos(0.5 * math.pi * (u + half) / half) * (0.5 * math.pi / half)
    if profile == 3 and ramp > 0.0 and s < ramp:    # piecewise, on a ramp
        return ds_du * hmax / ramp
    return 0.0                                      # rectangular, or on the flat


@njit(cache=True)
def interference_loss(table, j, theta, shaft_angle, ball_spin, r_inner, r_outer, r_ball):
    """Total loss of interference (m) of ball ``j`` at revolution angle ``theta`` (rad) from every
    defect in ``table``; ``shaft_angle`` turns inner-race defects, ``ball_spin`` (rad) turns a
    ball defect (spin angle of the ball relative to the cage).

    Returns (loss_inner_contact, loss_outer_contact): split so the skidding tier can apply each
    to its own contact; the kinematic tier adds them.
    """
    li, lo, _dli, _dlo = interference_loss_slope(table, j, theta, shaft_angle, ball_spin, r_inner,
                                                 r_outer, r_ball)
    return li, lo


@njit(cache=True)
def interference_loss_slope(table, j, theta, shaft_angle, ball_spin, r_inner, r_outer, r_ball):
    """:func:`interference_loss` and the race defects' slopes of the two losses along ``theta``
    (m/rad): (loss_i, loss_o, dloss_i/dtheta, dloss_o/dtheta).  A ball defect turns with the
    ball's spin, not with theta, and adds no slope."""
    loss_i = 0.0
    loss_o = 0.0
    slope_i = 0.0
    slope_o = 0.0
    for k in range(table.shape[0]):
        kind = int(table[k, D_KIND])
        half = table[k, D_HALF]
        prof = int(table[k, D_PROFILE])
        depth = table[k, D_DEPTH]
        if kind == 1:                                        # outer race: fixed
            u = wrap(theta - table[k, D_ANGLE])
            if abs(u) < half:
                loss_o += _profile_drop(prof, u, half, r_outer, table[k, D_RHO_O],
                                        table[k, D_HMAX_O], table[k, D_RAMP_O], depth)
                slope_o += _profile_slope(prof, u, half, r_outer, table[k, D_RHO_O],
                                          table[k, D_HMAX_O], table[k, D_RAMP_O], depth)
        elif kind == 0:                                      # inner race: turns with the shaft
            u = wrap(theta - table[k, D_ANGLE] - shaft_angle)
            if abs(u) < half:
                loss_i += _profile_drop(prof, u, half, r_inner, table[k, D_RHO_I],
                                        table[k, D_HMAX_I], table[k, D_RAMP_I], depth)
                slope_i += _profile_slope(prof, u, half, r_inner, table[k, D_RHO_I],
                                          table[k, D_HMAX_I], table[k, D_RAMP_I], depth)
        elif j == int(table[k, D_BALL]):                     # ball: meets outer at 0, inner at pi
            psi = ball_spin + table[k, D_ANGLE]
            u = wrap(psi)
            if abs(u) < half:
                loss_o += wander_reach(table, k, ball_spin) * _profile_drop(
                    prof, u, half, r_ball, table[k, D_RHO_O], table[k, D_HMAX_O], table[k, D_RAMP_O], depth)
            u = wrap(psi - math.pi)
            if abs(u) < half:
                loss_i += wander_reach(table, k, ball_spin) * _profile_drop(
                    prof, u, half, r_ball, table[k, D_RHO_I], table[k, D_HMAX_I], table[k, D_RAMP_I], depth)
    return loss_i, loss_o, slope_i, slope_o


@njit(cache=True)
def waviness_gain(table, theta, shaft_angle):
    """Extra interference (m) from race waviness at ball angle ``theta`` (seed 003): positive
    amplitude moves the race surface towards the ball."""
    gain = 0.0
    for k in range(table.shape[0]):
        phi = theta - shaft_angle if table[k, 0] == 0 else theta
        gain += table[k, 2] * math.cos(table[k, 1] * phi + table[k, 3])
    return gain

