"""Kinematic tier: seed 001's 5-DOF model (inner race/shaft x, y; outer race/pedestal x, y; unit
resonator on the pedestal, vertical) with Hertz contacts of the balls at kinematic positions.

Balls sit where pure rolling puts them (cage speed from geometry), optionally with seeded
random slip (seed 001 Sec. 2.2); a ball is massless (where its centrifugal force is under
``CENTRIFUGAL_GATE`` of the heaviest ball's load, on small radial play under
``CENTRIFUGAL_SMALL_PLAY_GATE``: ``carries_centrifugal_force``; above, held against the outer
race by it: ``_ball_state``) and carries
Q = K (delta)^1.5 + c(delta) delta' with delta = (x_s - x_p) cos(theta) + (y_s - y_p) sin(theta)
- C_r + h - loss + gain (seed 000 eqs 4 and 10; K of both contacts in series, Hamrock-Brewe),
and Q >= 0 (a contact never pulls).  The damping c and the film thickness h are the skidding
tier's lubricated contact (module ``film``, ``contact_damping``): the squeeze films and the
structural damping of both contacts in series, and each ball's own film, which follows its load
(Q^-0.073) and the speed: a function of the ball's geometric interference alone (module
``film``'s film law, tabulated), so it is no state and costs a table look-up per ball.  Without
the damping the tier differed from the skidding reference by 7-42 % on the bench's scenes even
where nothing skids (the balls' landings went undamped); with one film for every ball (the most
loaded one's) by 2.2-24 % and 69 % at 600 rpm / 2000 N (a ball entering the load zone touched
late, through the loaded balls' thinner film); with each ball's own film by 0.8-30 % and 0.7 %
there (the skidding tier's films following the Hertz load too), at 0.73-0.82x the speed of the
shared film.  ``lubrication: {ehl_film: false, contact_damping_ratio: 0}`` gives seed 001's
Hertz-only contacts back (c = 0, h = 0), in both tiers.  Gravity on the shaft and the radial load
act on the shaft; the pedestal's own weight is static and an (AC-coupled, piezoelectric)
accelerometer does not see it.

Integrator: exponential time differencing with a parabolic residual (ETD3, a predictor-corrector
of the Adams type; Cox & Matthews 2002, Hochbruck & Ostermann 2010).  The structure plus the
bearing stiffness linearised at the static equilibrium form a linear system integrated exactly by
precomputed propagators (matrix exponentials); only the residual (Hertz minus its linearisation:
ball passes, defects, clearance) is explicit.  The stiff but linear parts (resonator, pedestal,
average bearing stiffness) therefore cost nothing in stability, and the step is limited only by
how well the residual is interpolated over a step.  Per step: the residual at the start (r_n),
a predictor that extrapolates it linearly from r_{n-1}, r_n; the residual at the predicted end
(r*); the corrector integrates the parabola through r_{n-1}, r_n, r* exactly.  Two residual
evaluations per step, as the former ETD2 (linear interpolation of r_n, r*), whose hold
attenuated the forcing by sinc^2(f h): 19 % at the 3.8 kHz resonator at h = 1/15 kHz, the
largest error of the tier.  The parabola brings x2 (30 kHz steps) below the former x4.  It is
third order with Hertz-only contacts; the damped contacts' kinks (a ball's force clamped at zero
as it lifts off, its squeeze film starting on approach) make it about second order (waveform
error 0.6 % at x2 on the healthy ER-16K, 0.25 % without the damping).

Event sub-steps: a defect's impact can be shorter than a step, and no parabola over the step
follows it.  A step at whose end a ball is inside a defect, and the AFTER_STEPS steps after it
(the structure rings after the impact), are done again in one sub-step per chain sample, with
the same ETD3 and their own propagators.  At one step per output sample that makes the defect
scenes as accurate as plain ETD3 at two, and at two (the default) 4-8x more accurate on the
defect lines, for 3-9 % of the steps sub-stepped on a race defect (30 % on seed 004's ball
defect, which meets a race 16 % of the time).  Where a ball's load leaves and returns over a few
chain samples only (a fast pit's edge), the impacts' heights would beat with the pit's phase on
that grid (false envelope lines at 60 kHz - N BPFO): there the sub-steps are 4-16 per chain
sample, every one of them in the chain at its rate (``KinematicModel.fine_event_speed``,
docs/kinematic_fast_pits.md); the shipped scenes' edges are long enough for one.

Steps and output: ``oversample`` steps per output sample; the accelerometer chain gets
``chain_oversample`` (default >= 4) samples per output sample, the ones inside a step from the
exact solution of the linear part with the corrector's interpolant (dense output, a few
multiply-adds), so the chain runs at the skidding tier's rate whatever the step.
"""
from __future__ import annotations

import contextlib
import functools
import math

import numpy as np
from numba import njit

from . import KinematicSnapshot, TierOutput
from .blas import single_threaded_blas
from .defects import (D_ANGLE, D_BALL, D_DEPTH, D_HALF, D_HMAX_I, D_HMAX_O, D_KIND, D_PROFILE,
                      D_RAMP_I, D_RAMP_O, D_RHO_I, D_RHO_O, D_WANDER, DEFECT_COLUMNS, KIND_BALL,
                      KIND_INNER, _profile_drop, active_defect_table, wander_reach,
                      waviness_gain, wrap)
from .film import (FILM_EXP_Q, FILM_EXP_U, FILM_LAW_A, FILM_LOAD_FLOOR, FILM_TABLE_PER_U,
                   FILM_TABLE_U_MAX, FILM_TABLE_U_MIN, film_coefficient,
                   film_law_table, squeeze_film_coefficient, structural_damping_coefficient)
from .rng import uniform
from ..catalog import G
from .structure import secant_stiffness, structure_system

NSTATE = 10   # xs, ys, xp, yp, yr, vxs, vys, vxp, vyp, vyr
ANCHOR_STEPS = 4096   # re-anchor the rotated cage direction to cos/sin this often
NINPUT = 4    # residual bearing force on the pedestal (x, y); external force on the shaft (x, y)
X_BLOCK = (0, 2, 5, 7)          # xs, xp, vxs, vxp: the horizontal block of the state
Y_BLOCK = (1, 3, 4, 6, 8, 9)    # ys, yp, yr, vys, vyp, vyr: the vertical block
AFTER_STEPS = 3      # event sub-steps go on this many steps after a ball was last inside a defect
                     # (the structure rings after the impact; 1, 2, 3: inner-race lines 1.8, 0.7,
                     # 0.3 % at x1)
CORRECTOR_NODES = (1.0, 0.0, -1.0)   # residual at the step end (predicted), start, previous start
PREDICTOR_NODES = (0.0, -1.0)
DEFAULT_OVERSAMPLE = 2  # steps per output sample where the bearing mode is stiff: ETD3 with event
                        # sub-steps.  x1 is 1.35-1.7x faster and as accurate on light loads, but
                        # 0.4-2.9 % off in RMS where the bearing mode is stiff (ER-16K at 500 N
                        # and up, the healthy CWRU scene; README, "Kinematic tier: speed ...")
SOFT_MODE_FRACTION = 0.1  # oversample=None takes one step per output sample while the bearing mode
                          # stays below this fraction of the output rate (1.5 kHz at 15 kHz: the
                          # ER-16K at 200 N and less, 0.07 % RMS; the 6307, 0.35 %, x2's worst); above
                          # it, DEFAULT_OVERSAMPLE (test/test_kinematic_speed.py bearing-mode)
FINE_EVENTS = (4, 16)  # event sub-steps per chain sample where a defect's edge is short on the
                       # chain grid: the fewest powers of two in this range that put FINE_RESOLVE
                       # sub-steps on the edge (``KinematicModel.fine_events``;
                       # docs/kinematic_fast_pits.md: 4 takes the 61820's 2 mm pit's beat from x315
                       # to x4.2, its 0.5 mm pit's from x3 870 to x164, 16 to x12)
FINE_RESOLVE = 10.0    # sub-steps on the shortest edge
FINE_EDGE = 4.4       # chain samples: a ball that unloads fully over a shorter edge gets them
FINE_PARTIAL = 0.25   # a defect that takes this share of the ball's deflection but not all of it,
FINE_CROSSING = 3.0   # crossed in fewer chain samples than this, gets them too
CHAIN_OVERSAMPLE = 4   # accelerometer chain rate / output rate at least (the skidding tier's rate,
                       # so that a switch of tiers keeps the chain and the signal has no seam)

# geometry vector layout; then the balls' contact damping (``contact_damping``) and films
# (``film_law``):
# structural damping (N s/m per delta^0.5); each contact's share of the deflection; the squeeze
# films 6 pi eta R_x R_y (N s) of both contacts and their product; the film law's length lambda
# per |shaft speed|^FILM_W_EXP (m; 0 without film), the inner contact's share of a ball's film,
# the Hertz deflection at the film's load floor (m); roughness (m); then the balls' centrifugal
# force per shaft speed^2 (N s^2), the outer contact's deflection under it per |shaft
# speed|^(4/3) (m) and a massless ball's (both contacts in series) likewise (m); the inner and
# outer contacts' Hertz constant K_i (N/m^1.5) and K_o^(-2/3) (m N^(-2/3)); the inner contact's own film law's length per |shaft
# speed|^FILM_W_EXP (m; 0 without film) and its Hertz deflection at the load floor (m); the outer
# contact's film coefficient per |shaft speed|^0.68 (m N^0.073); 1 / a_i (``contact_damping``);
# 1 where the balls carry their centrifugal force, 0 where they are massless (``CENTRIFUGAL_GATE``,
# decided at each linearisation); the shaft speed (rad/s, > 0; 0 = not built) at which the held
# balls' law (``held_ball_table``) was tabulated; after NGEO, the
# inner contact's law under the centrifugal force (``centrifugal_law_table``), then that table
(P_NB, P_K, P_CR, P_RB, P_RI, P_RO, P_CAGE, P_SPIN, P_SLIP, P_GRAV,
 P_CDW, P_AI, P_AO, P_SQI, P_SQO, P_SQIO, P_LAM, P_SHI, P_DFLOOR, P_ROUGH,
 P_FCW, P_DCW, P_DKW, P_KI, P_KO, P_LAMI, P_DFLOORI, P_CO, P_INV_AI, P_CFON, P_XW, NGEO) = range(32)
P_CTAB = NGEO
CTAB_CELLS = 1024     # cells of the inner contact's law over v = sqrt(1 - delta_c / delta), 0..1
                      # (four values per node: 4 (CTAB_CELLS + 1) entries)
P_XTAB = P_CTAB + 4 * (CTAB_CELLS + 1)
XTAB_CELLS = 8192     # cells of a held ball's law above its inner contact's load floor, over y =
                      # s / (1 + s), s the interference past the floor's in units of delta_c (nine
                      # values per node, ``held_ball_table``).  Linear: 1024 cells left 3e-5 of a
                      # loaded ball's load, a ripple as the balls cross the cells that took the
                      # quiet preloaded 6000-size to +33 % (8192: 4e-7, -2.6 %)
P_YTAB = P_XTAB + 9 * (XTAB_CELLS + 1)
YTAB_CELLS = 512      # cells of it from the inner contact's touch to its load floor (six values)
XTAB_DSPEED = 0.01    # the relative speed step of the table's speed slopes (central differences)
XTAB_REACH = 0.25     # |ln(speed / the table's)| up to which the table is followed (quadratic in
                      # it: 1e-4 of a ball's load at 10 %); beyond, the two passes (``_ball_state``)
GEO_SIZE = P_YTAB + 6 * (YTAB_CELLS + 1)
# The balls carry their centrifugal force F_c = m_b (D_m / 2) w_c^2 (``_ball_state``) only where
# F_c / Q_max (Q_max = 5 W / Z, W ``fidelity.bearing_load``) is at least this at the operating
# point; below it they stay massless (the code before the force, kept as it was).  Against the
# skidding tier's reference (docs/fidelity_rms_gap.md, "With the centrifugal force", the table by
# F_c / Q_max): every point at 0.014 and above got closer with the force (light load 17-98 % ->
# 0.6-6.3 %, b6307_seed001 34 -> 12 %, ER-16K 5000 rpm / 200 N 2.5 -> 0.003 %), all but two at
# 0.0053 and below got 0.4-2.4 points further off, and the force costs the kernel 1.6-2.4x.  Every
# shipped ER-16K and 6205 scene is at 0.0002-0.0053, so stays massless, bit for bit.  Measured in
# between since ("The gate measured between 0.005 and 0.015" there): the side follows the radial
# play, not the ratio (small play: closer at 29 of 30 points from 0.0012 up; the ER-16K's: on
# either side up to 0.025), so no value of this is better supported than 0.01.
CENTRIFUGAL_GATE = 0.01
# ... and on a bearing of small radial play (C_r / D <= CENTRIFUGAL_SMALL_PLAY) from
# F_c / Q_max CENTRIFUGAL_SMALL_PLAY_GATE up: there the massless balls were 0.3-40 % low on
# accel_y and the force closer at 56 of 60 points on the ER-16K and the 6205 up to C_r / D 0.0043,
# at 4 of 12 at 0.0057 (docs/fidelity_rms_gap.md, "Where in the play"), and, checked on fresh
# bearings with other balls (4.762, 6.35 and 25.4 mm; C_r 10-74 um: the play relative to the
# ball, not C_r; "Fresh bearings" there), at 7 of 8 small-play points, further off at none by more
# than 1 point, while large play (0.0063-0.0079) stayed closer massless at 4-5 of 7.  0.005 lies
# between the plays measured on either side (0.0043 and 0.0057, the ER-16K's own: its scenes stay
# massless); 0.0012 is the lowest ratio at which the force had been measured closer on small play
# before the fresh points (the 6000-size at 3500 rpm / 100 N), the upper end of the bracket they
# were to place it in: at 0.0004-0.001 they were mixed (closer at 2 of 4), and at 0.0002 the 6205
# (its calibration point, its shipped scenes) was further off, so those stay massless.  No play
# or a preload (C_r <= 0) counts as small play: with the held balls' law exact (``held_ball_table``)
# the force was closer at all 8 preloaded and zero-play points from 0.002 to 0.005 (the 6000-size
# at -2 and 0 um, the 6-ball at -2 and 0 um; docs/probes/centrifugal_gate/preload_table.txt):
# accel_y -70 to -1.5 % massless against -33 to +4.3 % (the 6000-size at 0 um the one further off
# on accel_y, -1.55 -> +4.33 %, where its accel_x went -31 -> -1.9 %).  Left to CENTRIFUGAL_GATE
# alone before, as the two-pass law made a quiet preloaded 6000-size ten times too loud.
CENTRIFUGAL_SMALL_PLAY = 0.005
CENTRIFUGAL_SMALL_PLAY_GATE = 0.0012
# the speed (relative) by which the shaft must move from the last decision before the gate is
# decided again between load relinearisations (F_c goes as the speed squared: 10 % of speed is
# about 20 % of the ratio)
CENTRIFUGAL_SPEED_STEP = 0.1
# the film law (module ``film``): lambda^(1 + a) = C |w|^0.68 K^-0.073
FILM_W_EXP = FILM_EXP_U / (1.0 + FILM_LAW_A)
FILM_TABLE = film_law_table()       # a global array: numba compiles it in as a constant
LOG_FILM_LOAD_FLOOR = math.log(FILM_LOAD_FLOOR)
# ``_film_law``'s entries from delta_c on for massless balls (no force), and its whole tuple
# without a film for them
NO_FORCE = (0.0, 0.0, math.inf, 0.0, 0.0, 0.0, math.inf, 0.0, 0.0) + (0.0,) * 7
NO_FILM = (0.0, 0.0, 0.0, math.inf, 0.0, 0.0) + NO_FORCE


@njit(cache=True, inline="always")
def ball_geometry(geo, cj, sj, dtab, wtab, seed, slip_cache, shaft_angle, cage_angle, spin_angle,
                  cage_cos, cage_sin, margin_i, margin_o, margin_b, eps, gc, gs, goff):
    """Where each ball is and how much interference it has lost, at one instant.

    ``cage_cos, cage_sin`` = cos, sin of ``cage_angle`` (the caller advances them by rotation).
    Fills gc, gs (cos, sin of each ball's angle), goff (clearance + defect loss - waviness gain,
    m) so that the ball's deflection is ``dx * gc + dy * gs - goff``, and eps (each ball's slip
    angle).  It depends only on the angles, so one call serves every force evaluation at that
    instant.  Returns True if a ball is inside a defect or within ``margin_*`` (rad: how far an
    inner-race, outer-race or ball defect moves against the balls in one step) of one that is
    narrower than that, so that it may cross it within the step.

    Random slip (seed 001): each ball is offset by a linear interpolation of uniform(-1, 1)
    knots one ball spacing apart in cage angle, times ``slip * spacing``.  The knots are hashed
    from (seed, ball, knot index), so the offset depends only on where the cage is
    (chunk-invariant); ``slip_cache`` (nb, 3: knot index, value there, value at the next)
    avoids re-hashing until the cage passes a knot.

    Defects: every defect's interference loss (:func:`~.defects.interference_loss`), with a race
    defect tested only against the ball nearest to it and that ball's two neighbours (a defect
    is narrower than half the ball spacing, scene validation, and slip moves a ball by a few
    percent of it), so that the cost is per defect, not per ball; written out here because the
    kernel calls this inline at every step, an array-taking call costs more than its arithmetic,
    and it also says whether a ball is near a defect."""
    nb = int(geo[P_NB])
    cr = geo[P_CR]
    spacing = 2.0 * math.pi / nb
    inv_spacing = nb / (2.0 * math.pi)
    slip_amp = geo[P_SLIP] * spacing
    fq = 0.0
    near = False
    if slip_amp > 0.0:
        qk = cage_angle * inv_spacing
        kq = math.floor(qk)
        fq = qk - kq
        if slip_cache[0, 0] != kq:      # the cage passed a knot: hash the new ones
            for j in range(nb):
                ki = np.int64(kq)
                slip_cache[j, 0] = kq
                slip_cache[j, 1] = 2.0 * uniform(seed, 1000 + j, np.uint64(ki)) - 1.0
                slip_cache[j, 2] = 2.0 * uniform(seed, 1000 + j, np.uint64(ki + 1)) - 1.0
    for j in range(nb):
        c = cage_cos * cj[j] - cage_sin * sj[j]
        sn = cage_sin * cj[j] + cage_cos * sj[j]
        if slip_amp > 0.0:
            a = slip_cache[j, 1]
            e = slip_amp * (a + (slip_cache[j, 2] - a) * fq)
            eps[j] = e
            ce = 1.0 - 0.5 * e * e
            c, sn = c * ce - sn * e, sn * ce + c * e
        gc[j] = c
        gs[j] = sn
        goff[j] = cr
    n_def = dtab.shape[0]
    if n_def > 0:
        r_in, r_out, r_ball = geo[P_RI], geo[P_RO], geo[P_RB]
        # each race defect is tested against the ball nearest to it and its neighbours only
        for kd in range(n_def):
            kind = int(dtab[kd, D_KIND])
            half = dtab[kd, D_HALF]
            prof = int(dtab[kd, D_PROFILE])
            depth = dtab[kd, D_DEPTH]
            if kind == KIND_BALL:
                j = int(dtab[kd, D_BALL])
                psi = spin_angle + dtab[kd, D_ANGLE]
                # a wandering spin axis: the defect is met only near the rolling track
                reach = wander_reach(dtab, kd, spin_angle) if dtab[kd, D_WANDER] > 0.0 else 1.0
                # a defect narrower than a step's travel may be crossed within the step
                reach_near = half + (margin_b if 2.0 * half < margin_b else 0.0)
                uu = wrap(psi)
                if abs(uu) < reach_near:
                    near = True
                    if abs(uu) < half:
                        goff[j] += reach * _profile_drop(prof, uu, half, r_ball, dtab[kd, D_RHO_O],
                                                         dtab[kd, D_HMAX_O], dtab[kd, D_RAMP_O], depth)
                uu = wrap(psi - math.pi)
                if abs(uu) < reach_near:
                    near = True
                    if abs(uu) < half:
                        goff[j] += reach * _profile_drop(prof, uu, half, r_ball, dtab[kd, D_RHO_I],
                                                         dtab[kd, D_HMAX_I], dtab[kd, D_RAMP_I], depth)
                continue
            inner = kind == KIND_INNER
            centre = dtab[kd, D_ANGLE] + (shaft_angle if inner else 0.0)
            rel = wrap(centre - cage_angle)
            nearest = int(math.floor(rel * inv_spacing + 0.5))
            margin = margin_i if inner else margin_o
            reach_near = half + (margin if 2.0 * half < margin else 0.0)
            for dj in range(-1, 2):
                # nearest + dj lies in [-nb/2 - 1, nb/2 + 1]: one wrap by nb, not an
                # integer division (three per defect per step cost ~20 ns)
                j = nearest + dj
                if j < 0:
                    j += nb
                elif j >= nb:
                    j -= nb
                uu = rel - (nearest + dj) * spacing - eps[j]
                if abs(uu) < reach_near:
                    near = True
                    if abs(uu) < half:
                        if inner:
                            goff[j] += _profile_drop(prof, -uu, half, r_in, dtab[kd, D_RHO_I],
                                                     dtab[kd, D_HMAX_I], dtab[kd, D_RAMP_I], depth)
                        else:
                            goff[j] += _profile_drop(prof, -uu, half, r_out, dtab[kd, D_RHO_O],
                                                     dtab[kd, D_HMAX_O], dtab[kd, D_RAMP_O], depth)
    if wtab.shape[0] > 0:
        for j in range(nb):
            goff[j] -= waviness_gain(wtab, cage_angle + j * spacing + eps[j], shaft_angle)
    return near


@njit(cache=True, inline="always")
def _rotate(c, s, dth):
    """(cos, sin) of angle + dth from those of angle; dth small (< 0.1 rad): Taylor to 5th
    order, relative error below 1e-9 per call and renormalised at every chunk start."""
    d2 = dth * dth
    cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0))
    sd = dth * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0)))
    return c * cd - s * sd, s * cd + c * sd


@njit(cache=True, inline="always")
def _film_law(geo, w):
    """The balls' law at shaft speed ``w`` (rad/s), a tuple: the massless ball's film law, lambda
    (m), 1 / lambda (1/m), the film factor phi at the load floor, the u = interference / lambda
    below which a ball's film is the floor's, and lambda's inner and outer contact shares (m)
    (0, 0, 0, inf, 0, 0 without a film); the centrifugal force's: the outer contact's deflection
    under it delta_c (m), the force F_c (N), and the outer contact's film under F_c (m; inf
    without a film or a force); the inner contact's own film law, lambda_i (m), 1 / lambda_i, its
    phi and u at the load floor; the outer contact's film coefficient (m N^0.073) and its film (m)
    under F_c alone; the interferences (m) at which the inner contact touches and at which it
    carries the load floor, 1 / delta_c (1/m; 0 without a force, or where ``held_ball_table`` is
    not built or |ln(|w| / its speed)| is above XTAB_REACH) and 1 / their difference (1/m), the
    inner film there and the outer one (m), and ln(|w| / the table's speed) (0 at that speed or
    without the table) (``_ball_state``).
    A few logs and exps: per speed, not per ball.  Massless balls (``geo[P_CFON]`` 0,
    ``CENTRIFUGAL_GATE``): the massless film law alone, two logs and two exps as before the force,
    and no force (0, 0, inf, ...: ``NO_FORCE``)."""
    if geo[P_CFON] == 0.0:
        lam = geo[P_LAM]
        if lam <= 0.0 or w == 0.0:
            return NO_FILM
        lam *= math.exp(FILM_W_EXP * math.log(abs(w)))
        t_f = geo[P_DFLOOR] / lam
        phi_f = math.exp(-FILM_LAW_A * math.log(t_f))
        lam_i = lam * geo[P_SHI]
        return (lam, 1.0 / lam, phi_f, t_f - phi_f, lam_i, lam - lam_i) + NO_FORCE
    fc = geo[P_FCW] * w * w
    dc = 0.0
    if w != 0.0 and fc > 0.0:
        dc = geo[P_DCW] * math.exp(4.0 / 3.0 * math.log(abs(w)))
    lam = geo[P_LAM]
    if lam <= 0.0 or w == 0.0:
        return (0.0, 0.0, 0.0, math.inf, 0.0, 0.0, dc, fc, math.inf, 0.0, 0.0, 0.0, math.inf, 0.0, 0.0,
                0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    lw = math.log(abs(w))
    lam *= math.exp(FILM_W_EXP * lw)
    t_f = geo[P_DFLOOR] / lam
    phi_f = math.exp(-FILM_LAW_A * math.log(t_f))
    lam_i = lam * geo[P_SHI]
    ho_c = math.inf
    if fc > 0.0:
        # the film of a contact under F_c: lambda t^-a at a massless ball's deflection under F_c
        # (floored as the film law floors the load), the outer contact's share of it
        t_c = max(geo[P_DKW] * math.exp(4.0 / 3.0 * lw), geo[P_DFLOOR]) / lam
        ho_c = (lam - lam_i) * math.exp(-FILM_LAW_A * math.log(t_c))
    lin = geo[P_LAMI] * math.exp(FILM_W_EXP * lw)
    t_fi = geo[P_DFLOORI] / lin
    phi_fi = math.exp(-FILM_LAW_A * math.log(t_fi))
    c_o = geo[P_CO] * math.exp(FILM_EXP_U * lw)
    # the outer contact's film under F_c alone (at the load floor at least, as every film) for a
    # ball whose inner contact carries nothing; its deflection there is delta_c
    lf = math.log(max(fc, FILM_LOAD_FLOOR))
    ho_f = c_o * math.exp(FILM_EXP_Q * lf)
    # ``held_ball_table``'s two breaks: where the inner contact touches (its film at the load
    # floor, the outer contact under F_c alone) and where it carries the load floor (its
    # deflection there and the outer contact's at the floor + F_c); the table's speed offset, 0
    # at its own speed (no look-up of the slopes there)
    hi_fl = lin * phi_fi
    b0 = dc - ho_f - hi_fl
    lq = math.log(FILM_LOAD_FLOOR + fc)
    ho_fl = c_o * math.exp(FILM_EXP_Q * lq)
    b_fl = geo[P_DFLOORI] + geo[P_KO] * math.exp(2.0 / 3.0 * lq) - hi_fl - ho_fl
    xw = geo[P_XW]
    ell = lw - math.log(xw) if xw > 0.0 and abs(w) != xw else 0.0
    # 1 / delta_c 0 says: no table here (not built, or the speed beyond its reach): two passes
    inv_dc = 1.0 / dc if dc > 0.0 and xw > 0.0 and abs(ell) <= XTAB_REACH else 0.0
    return (lam, 1.0 / lam, phi_f, t_f - phi_f, lam_i, lam - lam_i, dc, fc, ho_c,
            lin, 1.0 / lin, phi_fi, t_fi - phi_fi, c_o, ho_f, b0, b_fl, inv_dc, 1.0 / (b_fl - b0),
            hi_fl, ho_fl, ell)


@njit(cache=True, inline="always")
def _film_factor(u, phi_f, u_f):
    """A ball's film over lambda at interference u lambda (module ``film``: phi = t^-a, t - t^-a
    = u): the load floor's ``phi_f`` below ``u_f``, else a cubic from FILM_TABLE (four loads,
    three multiply-adds), or two fixed-point iterations outside the table (far from contact onset,
    where they contract by 1e-4 or better)."""
    if u < u_f:
        return phi_f
    if u >= FILM_TABLE_U_MAX:             # phi = (u + phi)^-a
        p = math.exp(-FILM_LAW_A * math.log(u))
        return math.exp(-FILM_LAW_A * math.log(u + p))
    if u < FILM_TABLE_U_MIN:              # t = (t - u)^(-1/a), phi = t - u
        t = math.exp(math.log(-u) / -FILM_LAW_A)
        return math.exp(math.log(t - u) / -FILM_LAW_A) - u
    x = (u - FILM_TABLE_U_MIN) * FILM_TABLE_PER_U
    k = int(x)
    s = x - k
    return FILM_TABLE[k, 0] + s * (FILM_TABLE[k, 1] + s * (FILM_TABLE[k, 2] + s * FILM_TABLE[k, 3]))


@njit(cache=True, inline="always")
def inner_contact_load(geo, kc, delta, dc):
    """The inner contact's Hertz load (N) of a ball whose two contacts together are compressed
    by ``delta`` (m: the ring-to-ring interference plus films) while its centrifugal force F_c
    holds it against the outer race, compressed there by ``dc`` = (F_c / K_o)^(2/3) (m) at least.
    The ball sits where its contacts balance, Q_o = Q_i + F_c, delta_i + delta_o = delta: 0 up
    to delta = dc, then rising from 0 (stiffer at the start than the series law, the outer
    contact being loaded already), and K delta^1.5 (the series law, K = ``kc``) as F_c -> 0 or
    delta -> inf.  The law is K delta^1.5 g(v), v = sqrt(1 - dc / delta), g tabulated per
    bearing (``centrifugal_law_table``: it depends on K_o / K_i only) and interpolated linearly:
    a division, a root and a look-up per ball, no iteration."""
    if delta <= dc:
        return 0.0
    return kc * delta * math.sqrt(delta) * _centrifugal_split(geo, delta, dc)[0]


@njit(cache=True, inline="always")
def _centrifugal_split(geo, delta, dc):
    """For delta > dc: g(v), the outer contact's deflection (m) and the factors (e / e(1))^-a and
    (1 + q)^-0.073 of its film (``centrifugal_law_table``), from one look-up (no root, no power):
    ``inner_contact_load`` is g K delta^1.5."""
    if dc <= 0.0:
        return 1.0, delta * geo[P_AO], 1.0, 0.0
    x = math.sqrt(1.0 - dc / delta) * CTAB_CELLS
    k = int(x)
    if k >= CTAB_CELLS:
        return 1.0, delta * geo[P_AO], 1.0, 0.0
    i = P_CTAB + 4 * k
    s = x - k
    g0 = geo[i]
    e0 = geo[i + 1]
    h0 = geo[i + 2]
    p0 = geo[i + 3]
    return (g0 + s * (geo[i + 4] - g0), delta * (e0 + s * (geo[i + 5] - e0)),
            h0 + s * (geo[i + 6] - h0), p0 + s * (geo[i + 7] - p0))


@njit(cache=True, inline="always")
def _ball_state(geo, kc, law, base):
    """One ball at geometric interference ``base`` (m: ring to ring, less clearance and defects),
    through its films (``law``: ``_film_law``) and held against the outer race by its centrifugal
    force F_c: (the deflection d (m) that sets its damping, its inner-contact Hertz load (N) where
    d > 0, its inner and outer films (m)).

    Without a film: ``inner_contact_load`` of the interference, d = interference - delta_c (the
    inner contact's share of it).  With the films, each contact's follows its own load (the outer
    contact's Q_i + F_c, as in the skidding tier): the quasi-static balance (each contact's film
    at its own load) tabulated per bearing and speed (``held_ball_table``) and looked up, no
    iteration: across a gap (short of b_0, where the inner contact touches with its film at the
    load floor and the outer one carries F_c alone) it is explicit, the gap b_0 - base; from b_0
    to b_fl (where the inner contact carries the load floor) and above, the inner interference g
    and both films are interpolated linearly (YTAB_CELLS and XTAB_CELLS cells; one division
    above b_fl), off the table's speed followed to second order in ln(speed).  At the table's
    speed within 4e-5 of each ball's load from 0.01 F_c up (4e-7 on balls above F_c) and at 10 %
    from it within 1e-4, where two passes (``_two_passes``, the law before the table) were 25-62
    % off on balls whose inner contact carries less than F_c and 0.2 % on loaded ones (which took
    a quiet preloaded bearing's RMS ten times too high: docs/fidelity_rms_gap.md, "Light preload:
    which tier was wrong"); and the kernel takes 0.4-0.8x the time it took with the two passes
    (whose film laws take logs and exps on loaded balls).  Without the table (no force, not built, or the speed beyond
    XTAB_REACH of it) the two passes, which give the massless ball's law without a force (its
    films follow one load).  d = g / a_i in contact (a_i the inner contact's share of a
    massless ball's deflection: the series law's deflection as F_c -> 0), g across a gap (all of
    it the inner contact's)."""
    dc = law[6]
    if law[0] == 0.0:
        return base - dc, inner_contact_load(geo, kc, base, dc), 0.0, 0.0
    b0 = law[15]
    b_fl = law[16]
    inv_dc = law[17]
    ell = law[21]
    if inv_dc == 0.0:
        g, hi, ho = _two_passes(geo, law, base)
    elif base > b_fl:
        # above the inner contact's load floor: g - g_fl over (base - b_fl), both films' change
        # over delta_c, on y = s / (1 + s), s = (base - b_fl) / delta_c
        s = (base - b_fl) * inv_dc
        x = s / (1.0 + s) * XTAB_CELLS
        k = min(int(x), XTAB_CELLS - 1)
        f = x - k
        i = P_XTAB + 9 * k
        a = _held_entry(geo, i, 9, 3, f, ell)
        b = _held_entry(geo, i + 1, 9, 3, f, ell)
        c = _held_entry(geo, i + 2, 9, 3, f, ell)
        g = geo[P_DFLOORI] + (base - b_fl) * a
        hi = law[19] + dc * b
        ho = law[20] + dc * c
    elif base > b0:
        # touching, under the load floor: the inner film is the floor's; g over (base - b_0) and
        # the outer film's change over delta_c, linear in base
        x = (base - b0) * law[18] * YTAB_CELLS
        k = min(int(x), YTAB_CELLS - 1)
        f = x - k
        i = P_YTAB + 6 * k
        a = _held_entry(geo, i, 6, 2, f, ell)
        c = _held_entry(geo, i + 1, 6, 2, f, ell)
        g = (base - b0) * a
        hi = law[9] * law[11]
        ho = law[14] + dc * c
    else:
        # apart from the inner race: the inner film at the load floor, the outer under F_c alone
        return base - b0, 0.0, law[9] * law[11], law[14]
    hz = 0.0
    if g > 0.0:
        hz = geo[P_KI] * g * math.sqrt(g)
    # in contact, the series law's deflection; across a gap the whole gap is the inner contact's
    # (``contact_damping``), as it was for the massless ball
    return (g * geo[P_INV_AI] if g > 0.0 else g), hz, hi, ho


@njit(cache=True, inline="always")
def _held_entry(geo, i, stride, cols, f, ell):
    """One column of ``held_ball_table`` at f (0-1) of the way through the cell whose entry is
    geo[i] (``stride`` values per node, ``cols`` columns each of value, slope and half curvature
    in ell = ln(|w| / the table's speed)): linear in f, to second order in ell (not read at ell 0)."""
    v = geo[i] + f * (geo[i + stride] - geo[i])
    if ell != 0.0:
        j = i + cols
        k = j + cols
        v += ell * (geo[j] + f * (geo[j + stride] - geo[j]) + ell * (geo[k] + f * (geo[k + stride] - geo[k])))
    return v


@njit(cache=True, inline="always")
def _two_passes(geo, law, base):
    """A held ball's inner-contact interference g (m, negative across a gap) and its inner and
    outer films (m) at interference ``base`` (m) in two cheap passes instead of an iteration
    (``_ball_state``): (1) the films of a massless ball (the outer one at most F_c's) and
    ``inner_contact_load`` give Q_i; (2) the outer contact's deflection and film at Q_i + F_c
    from it, and the inner contact's own film law (module ``film``, in units of its lambda_i)
    gives its interference g (exact for a given outer contact).  Within 0.1-0.9 % of the most
    loaded ball's load of the quasi-static law on the bearings of docs/fidelity_rms_gap.md, and
    the ball touches where that law says (pass 1 alone: 0.3-2.6 %, and the ball touched up to
    0.9 um late, which took b6307_seed001's RMS 22 % above the reference), but 25-62 % off on a
    ball whose inner contact carries less than F_c: the law only where ``held_ball_table`` is not,
    and the start of ``_quasi_static_ball``'s Newton steps."""
    lam, inv_lam, phi_f, u_f, lam_i, lam_o, dc, fc, ho_c, lin, inv_lin, phi_fi, u_fi, c_o, ho_f = law[:15]
    phi = _film_factor(base * inv_lam, phi_f, u_f)
    ho = lam_o * phi
    capped = ho > ho_c
    delta = base + lam_i * phi + (ho_c if capped else ho)
    if delta <= dc:
        # pass 1 leaves the inner contact unloaded: the outer one carries F_c (per speed)
        ho = ho_f
        do = dc
    else:
        # the outer film c_o Q_o^-0.073 at Q_o = Q_i + F_c without a power: where pass 1 took the
        # massless film, delta is the massless ball's deflection, whose own ^-a is phi / lambda^-a,
        # so the film is lambda_o phi (e / e(1))^-a; where it took F_c's, F_c's film times
        # (1 + q)^-0.073 (both from the table; the same value where they meet)
        _g, do, ehat, pq = _centrifugal_split(geo, delta, dc)
        ho = ho_f * pq if capped else ho * ehat
    u = (base + ho - do) * inv_lin
    phi_i = _film_factor(u, phi_fi, u_fi)
    return lin * (u + phi_i), lin * phi_i, ho


@njit(cache=True)
def _quasi_static_ball(geo, law, base):
    """A held ball's inner-contact interference g (m), inner and outer films (m) at interference
    ``base`` (m, past the inner contact's touch) at the quasi-static balance, each contact's film
    at its own load (Q_o = Q_i + F_c): from the two passes, Newton steps on Q_i = G(Q_i), G the
    inner load that pass 2 gives for an outer contact at Q_i + F_c, each followed by G at its
    result, until Q_i moves by less than 1e-14 of Q_i + F_c (3-5 steps; the films' own law,
    ``_film_factor``, as the kernel's).  For ``held_ball_table`` only: two logs and four exps a
    step, which in the kernel cost it 3.2-4.7x (docs/fidelity_rms_gap.md, "Light preload")."""
    fc, lin, inv_lin, phi_fi, u_fi, c_o = law[7], law[9], law[10], law[11], law[12], law[13]
    g, hi, ho = _two_passes(geo, law, base)
    hz = geo[P_KI] * g * math.sqrt(g) if g > 0.0 else 0.0
    for _ in range(60):
        qo = hz + fc
        lq = math.log(qo)
        do = geo[P_KO] * math.exp(2.0 / 3.0 * lq)
        h3 = c_o * math.exp(FILM_EXP_Q * max(lq, LOG_FILM_LOAD_FLOOR))
        u3 = (base + h3 - do) * inv_lin
        phi3 = _film_factor(u3, phi_fi, u_fi)
        t3 = u3 + phi3
        q3 = 0.0
        if t3 > 0.0:
            gq = geo[P_KI] * lin * t3 * math.sqrt(lin * t3)
            # dG/dQ_i: the outer contact's deflection and film move against the inner's
            dtdu = 1.0 if u3 < u_fi else 1.0 / (1.0 + FILM_LAW_A * phi3 / t3)
            dho = FILM_EXP_Q * h3 if lq > LOG_FILM_LOAD_FLOOR else 0.0
            slope = 1.5 * gq / t3 * dtdu * (dho - 2.0 / 3.0 * do) / (qo * lin)
            q3 = max(hz + (gq - hz) / (1.0 - slope), 0.0)
        lq = math.log(q3 + fc)
        do = geo[P_KO] * math.exp(2.0 / 3.0 * lq)
        ho = c_o * math.exp(FILM_EXP_Q * max(lq, LOG_FILM_LOAD_FLOOR))
        u3 = (base + ho - do) * inv_lin
        phi3 = _film_factor(u3, phi_fi, u_fi)
        g = lin * (u3 + phi3)
        hi = lin * phi3
        last = hz
        hz = geo[P_KI] * g * math.sqrt(g) if g > 0.0 else 0.0
        if abs(hz - last) <= 1e-14 * (hz + fc):
            break
    return g, hi, ho


@njit(cache=True)
def _held_ball_columns(geo, w, above, below):
    """``held_ball_table``'s values at shaft speed ``w`` (rad/s) on its nodes: into above
    (XTAB_CELLS + 1, 3) the inner interference's excess over the floor's per (base - b_fl) and
    both films' change from the floor's over delta_c, at y = k / XTAB_CELLS; into below
    (YTAB_CELLS + 1, 2) the inner interference per (base - b_0) and the outer film's change from
    F_c's over delta_c, at k / YTAB_CELLS of the way from b_0 to b_fl (``_ball_state``)."""
    law = _film_law(geo, w)
    dc, b0, b_fl, hi_fl, ho_fl, ho_f = law[6], law[15], law[16], law[19], law[20], law[14]
    for k in range(XTAB_CELLS + 1):
        # the far end stands for y = 1, s = inf (the loaded balls' limit)
        y = max(k, 0.01) / XTAB_CELLS if k < XTAB_CELLS else 1.0 - 0.25 / XTAB_CELLS
        s = y / (1.0 - y)
        g, hi, ho = _quasi_static_ball(geo, law, b_fl + s * dc)
        above[k, 0] = (g - geo[P_DFLOORI]) / (s * dc)
        above[k, 1] = (hi - hi_fl) / dc
        above[k, 2] = (ho - ho_fl) / dc
    # node 0's interference slope from nodes 1 and 2: at a few 1e-13 m from the floor, what the
    # film law's table leaves of the difference (1e-6 of a film: 6e-13 m) is not the slope
    above[0, 0] = 2.0 * above[1, 0] - above[2, 0]
    for k in range(YTAB_CELLS + 1):
        t = max(k, 0.01) / YTAB_CELLS
        g, hi, ho = _quasi_static_ball(geo, law, b0 + t * (b_fl - b0))
        below[k, 0] = g / (t * (b_fl - b0))
        below[k, 1] = (ho - ho_f) / dc


@njit(cache=True, inline="always")
def hertz_force(geo, kc, gc, gs, goff, law, dx, dy, q_out):
    """Force of the balls on the shaft's race, reacted by the pedestal (N, x and y) for a
    shaft-pedestal offset (dx, dy) m, each ball through its films (``law``: ``_film_law``) and
    held out by its centrifugal force (``_ball_state``); each ball's inner-contact load (N) goes to
    q_out (its outer contact carries F_c more).  The balls' centrifugal forces on the outer race,
    evenly spaced, sum to zero (see ``advance_kernel``).  Massless balls (``geo[P_CFON]`` 0): one
    load through both contacts and one film, as before the force."""
    fx = 0.0
    fy = 0.0
    if geo[P_CFON] == 0.0:
        lam, inv_lam, phi_f, u_f = law[0], law[1], law[2], law[3]
        for j in range(gc.shape[0]):
            base = dx * gc[j] + dy * gs[j] - goff[j]
            delta = base + lam * _film_factor(base * inv_lam, phi_f, u_f)
            if delta > 0.0:
                qj = kc * delta * math.sqrt(delta)
                q_out[j] = qj
                fx += qj * gc[j]
                fy += qj * gs[j]
            else:
                q_out[j] = 0.0
        return fx, fy
    for j in range(gc.shape[0]):
        d, hz, _hi, _ho = _ball_state(geo, kc, law, dx * gc[j] + dy * gs[j] - goff[j])
        qj = hz if d > 0.0 else 0.0
        q_out[j] = qj
        fx += qj * gc[j]
        fy += qj * gs[j]
    return fx, fy


@njit(cache=True)
def bearing_force(geo, cj, sj, dtab, wtab, seed, dx, dy, shaft_angle, cage_angle, spin_angle, q_out,
                  shaft_speed=0.0):
    """Force of the balls on the pedestal at one instant (convenience for set-up code), through
    their films at ``shaft_speed`` (rad/s; none at 0)."""
    nb = int(geo[P_NB])
    gc = np.empty(nb)
    gs = np.empty(nb)
    goff = np.empty(nb)
    eps = np.zeros(nb)
    cache = np.full((nb, 3), np.nan)
    ball_geometry(geo, cj, sj, dtab, wtab, seed, cache, shaft_angle, cage_angle, spin_angle,
                  math.cos(cage_angle), math.sin(cage_angle), 0.0, 0.0, 0.0, eps, gc, gs, goff)
    return hertz_force(geo, geo[P_K], gc, gs, goff, _film_law(geo, shaft_speed), dx, dy, q_out)


@functools.lru_cache(maxsize=None)
def _lagrange(nodes: tuple) -> np.ndarray:
    """Inverse Vandermonde of ``nodes`` (in steps): coefficient j of the interpolant = sum_i
    inv[j, i] u(node_i).  The nodes are the scheme's, a handful of tuples: computed once each
    (read-only), not at every relinearisation."""
    inv = np.linalg.inv(np.array([[t ** j for j in range(len(nodes))] for t in nodes]))
    inv.flags.writeable = False
    return inv


@njit(cache=True)
def mean_bearing_force(geo, cj, sj, dx, dy, shaft_speed, positions):
    """``bearing_force`` (no defects, no waviness) averaged over ``positions`` cage angles
    evenly spaced over one ball spacing: the quasi-static load-deflection law, (fx, fy) N on the
    pedestal.  One compiled call: the linearisation's root finder evaluates it ~20 times, and a
    load that moves by 20 % every batch (a rotating unbalance) relinearises at every batch."""
    nb = int(geo[P_NB])
    step = 2 * np.pi / nb / positions          # the cage angles of np.linspace(0, 2 pi / nb, n, False)
    q = np.zeros(nb)
    empty = np.zeros((0, DEFECT_COLUMNS))
    no_waviness = np.zeros((0, 4))
    fx = 0.0
    fy = 0.0
    for k in range(positions):
        f0, f1 = bearing_force(geo, cj, sj, empty, no_waviness, 0, dx, dy, 0.0, k * step, 0.0, q, shaft_speed)
        fx += f0
        fy += f1
    return fx / positions, fy / positions


@njit(cache=True, inline="always")
def _ball_load(kc, cdw, ai, ao, sqi, sqo, sqio, hri, hro, delta, rate):
    """Load of one massless ball (N, >= 0: a contact never pulls) at deflection ``delta`` (m)
    approached at ``rate`` (m/s): Hertz plus the damping of its two contacts in series,
    structural and squeeze film (``contact_damping``); across a gap, the inner contact's squeeze
    film on approach.  ``_held_ball_load`` for a ball held out by its centrifugal force."""
    if delta > 0.0:
        sq = math.sqrt(delta)
        c = cdw * sq
        if sqio > 0.0:
            c += sqio / (sqi * (ao * delta + hro) + sqo * (ai * delta + hri))
        return max(kc * delta * sq + c * rate, 0.0)
    if rate > 0.0 and sqio > 0.0:
        return sqio / (sqi * hro + sqo * (hri - delta)) * rate
    return 0.0


@njit(cache=True, inline="always")
def _held_ball_load(cdw, ai, ao, sqi, sqo, sqio, hri, hro, delta, hz, rate):
    """Inner-contact load of one ball (N, >= 0: a contact never pulls) at deflection ``delta``
    (m; ``_ball_state``'s d, the series law's deflection as F_c -> 0) approached at ``rate``
    (m/s), its Hertz load ``hz`` (N) where delta > 0: Hertz plus the damping of its two contacts
    in series, structural and squeeze film (``contact_damping``); across a gap, the inner
    contact's squeeze film on approach."""
    if delta > 0.0:
        sq = math.sqrt(delta)
        c = cdw * sq
        if sqio > 0.0:
            c += sqio / (sqi * (ao * delta + hro) + sqo * (ai * delta + hri))
        return max(hz + c * rate, 0.0)
    if rate > 0.0 and sqio > 0.0:
        return sqio / (sqi * hro + sqo * (hri - delta)) * rate
    return 0.0


@njit(cache=True, inline="always")
def _residual(geo, kc, kbx, kby, gc, gs, goff, dx, dy, dvx, dvy, wc, cdw, ai, ao, sqi, sqo, sqio, law,
              rough):
    """Residual bearing force (N, x and y): the balls' forces on the pedestal at the
    shaft-pedestal offset (dx, dy) m and its rate (dvx, dvy) m/s, the balls turning at ``wc``
    rad/s, each through its own film (``law``: ``_film_law``; plus ``rough`` m of roughness in
    the squeeze films), minus the linearised bearing's."""
    fx = 0.0
    fy = 0.0
    # approach rate of ball j: d/dt (dx cos + dy sin) with its angle turning at wc
    rc = dvx + wc * dy
    rs = dvy - wc * dx
    if geo[P_CFON] == 0.0:
        # massless balls (``CENTRIFUGAL_GATE``): as before the force
        lam, inv_lam, phi_f, u_f, lam_i, lam_o = law[0], law[1], law[2], law[3], law[4], law[5]
        for j in range(gc.shape[0]):
            c = gc[j]
            s = gs[j]
            base = dx * c + dy * s - goff[j]
            phi = _film_factor(base * inv_lam, phi_f, u_f)
            rate = rc * c + rs * s
            qj = _ball_load(kc, cdw, ai, ao, sqi, sqo, sqio, lam_i * phi + rough, lam_o * phi + rough,
                            base + lam * phi, rate)
            fx += qj * c
            fy += qj * s
        return fx - kbx * dx, fy - kby * dy
    for j in range(gc.shape[0]):
        c = gc[j]
        s = gs[j]
        base = dx * c + dy * s - goff[j]
        dl, hz, hi, ho = _ball_state(geo, kc, law, base)
        qj = _held_ball_load(cdw, ai, ao, sqi, sqo, sqio, hi + rough, ho + rough, dl, hz, rc * c + rs * s)
        fx += qj * c
        fy += qj * s
    return fx - kbx * dx, fy - kby * dy


@njit(cache=True, inline="always")
def _free_response(px, py, ex, ey, a0, a1, a2, a3, b0, b1, b2, b3, b4, b5, exn, eyn, dex, dey):
    """The x and y blocks after one step of their propagators px, py, plus the external force
    (value exn, eyn at the step start, change dex, dey over it; exact for a linear ramp)."""
    return (px[0, 0] * a0 + px[0, 1] * a1 + px[0, 2] * a2 + px[0, 3] * a3 + ex[0, 0] * exn + ex[1, 0] * dex,
            px[1, 0] * a0 + px[1, 1] * a1 + px[1, 2] * a2 + px[1, 3] * a3 + ex[0, 1] * exn + ex[1, 1] * dex,
            px[2, 0] * a0 + px[2, 1] * a1 + px[2, 2] * a2 + px[2, 3] * a3 + ex[0, 2] * exn + ex[1, 2] * dex,
            px[3, 0] * a0 + px[3, 1] * a1 + px[3, 2] * a2 + px[3, 3] * a3 + ex[0, 3] * exn + ex[1, 3] * dex,
            (py[0, 0] * b0 + py[0, 1] * b1 + py[0, 2] * b2 + py[0, 3] * b3 + py[0, 4] * b4
             + py[0, 5] * b5 + ey[0, 0] * eyn + ey[1, 0] * dey),
            (py[1, 0] * b0 + py[1, 1] * b1 + py[1, 2] * b2 + py[1, 3] * b3 + py[1, 4] * b4
             + py[1, 5] * b5 + ey[0, 1] * eyn + ey[1, 1] * dey),
            (py[2, 0] * b0 + py[2, 1] * b1 + py[2, 2] * b2 + py[2, 3] * b3 + py[2, 4] * b4
             + py[2, 5] * b5 + ey[0, 2] * eyn + ey[1, 2] * dey),
            (py[3, 0] * b0 + py[3, 1] * b1 + py[3, 2] * b2 + py[3, 3] * b3 + py[3, 4] * b4
             + py[3, 5] * b5 + ey[0, 3] * eyn + ey[1, 3] * dey),
            (py[4, 0] * b0 + py[4, 1] * b1 + py[4, 2] * b2 + py[4, 3] * b3 + py[4, 4] * b4
             + py[4, 5] * b5 + ey[0, 4] * eyn + ey[1, 4] * dey),
            (py[5, 0] * b0 + py[5, 1] * b1 + py[5, 2] * b2 + py[5, 3] * b3 + py[5, 4] * b4
             + py[5, 5] * b5 + ey[0, 5] * eyn + ey[1, 5] * dey))


@njit(cache=True, inline="always")
def _predicted_offset(wx, wy, r, ca0, ca1, ca2, ca3, cb0, cb1, cb3, cb4, rx, rxp, ry, ryp):
    """Shaft-pedestal offset (m, x and y) and its rate (m/s, x and y) at the step end with the
    residual extrapolated linearly from the step start (rx, ry) and the previous node (rxp,
    ryp): predictor rows r + 3, r + 4 of the weights."""
    return ((ca0 + wx[r + 3, 0] * rx + wx[r + 4, 0] * rxp) - (ca1 + wx[r + 3, 1] * rx + wx[r + 4, 1] * rxp),
            (cb0 + wy[r + 3, 0] * ry + wy[r + 4, 0] * ryp) - (cb1 + wy[r + 3, 1] * ry + wy[r + 4, 1] * ryp),
            (ca2 + wx[r + 3, 2] * rx + wx[r + 4, 2] * rxp) - (ca3 + wx[r + 3, 3] * rx + wx[r + 4, 3] * rxp),
            (cb3 + wy[r + 3, 3] * ry + wy[r + 4, 3] * ryp) - (cb4 + wy[r + 3, 4] * ry + wy[r + 4, 4] * ryp))


@njit(cache=True, inline="always")
def _corrected(wx, wy, r, ca0, ca1, ca2, ca3, cb0, cb1, cb2, cb3, cb4, cb5, rxs, rx, rxp, rys, ry, ryp):
    """The blocks at the step end: free response plus the parabola through the residual at the
    predicted end (rxs, rys), the start (rx, ry) and the previous node (rxp, ryp), integrated
    exactly (corrector rows r, r + 1, r + 2 of the weights)."""
    return (ca0 + wx[r, 0] * rxs + wx[r + 1, 0] * rx + wx[r + 2, 0] * rxp,
            ca1 + wx[r, 1] * rxs + wx[r + 1, 1] * rx + wx[r + 2, 1] * rxp,
            ca2 + wx[r, 2] * rxs + wx[r + 1, 2] * rx + wx[r + 2, 2] * rxp,
            ca3 + wx[r, 3] * rxs + wx[r + 1, 3] * rx + wx[r + 2, 3] * rxp,
            cb0 + wy[r, 0] * rys + wy[r + 1, 0] * ry + wy[r + 2, 0] * ryp,
            cb1 + wy[r, 1] * rys + wy[r + 1, 1] * ry + wy[r + 2, 1] * ryp,
            cb2 + wy[r, 2] * rys + wy[r + 1, 2] * ry + wy[r + 2, 2] * ryp,
            cb3 + wy[r, 3] * rys + wy[r + 1, 3] * ry + wy[r + 2, 3] * ryp,
            cb4 + wy[r, 4] * rys + wy[r + 1, 4] * ry + wy[r + 2, 4] * ryp,
            cb5 + wy[r, 5] * rys + wy[r + 1, 5] * ry + wy[r + 2, 5] * ryp)


# without numba's runtime (NRT): its atomic reference counts on the arrays that the inlined helpers
# take cost ~40 % of the kernel's time (AMD host: 342 -> 202 ns per output sample on the healthy
# ER-16K without them, the same results bit for bit); the kernel allocates nothing
@njit(cache=True, fastmath={"contract"}, _nrt=False)
def advance_kernel(x, ang, trig, step, hist, geom, n, m, d, s0, s1, l0x, l0y, l1x, l1y, h, geo, cj, sj,
                   dtab, wtab, seed, slip_cache, kbx, kby, px, py, wx, wy, ex, ey, cx, cy, feed,
                   dense_x, dense_y, psx, psy, wsx, wsy, esx, esy, sub_mode, r_fine, fine_speed, pfx,
                   pfy, wfx, wfy, efx, efy, out_acc, out_q, out_cage):
    """ETD3 over ``n`` steps of ``h`` s (see the module docstring).

    x: state (10,); ang: (shaft, cage, ball spin) angles; trig: (cos, sin) of the cage angle;
    step: (2,) int64 steps taken since t = 0, and of those the ones done in sub-steps;
    hist: (5,) residual (x, y) at the previous step's start, 1.0 if that is valid (0.0 after a
    start, a relinearisation or a tier switch), 1.0 if ``geom`` is, steps since a ball was last
    inside a defect at a step end; geom: (4, Nb) the balls' geometry at the current time (cos,
    sin of each ball's angle, clearance + loss - gain, slip angle), kept from the previous chunk so that a chunk
    boundary cannot change a bit of it (it is computed once, at the first step or a switch).
    Speed and load ramp linearly from (s0, l0) to (s1, l1).  The x block of the state is (xs, xp, vxs, vxp), the y
    block (ys, yp, yr, vys, vyp, vyr) (they decouple: see ``_linearise``); px (4, 4), py (6, 6):
    their propagators; wx (5, 4), wy (5, 6): what the residual does to each block, rows:
    corrector weights of the residual at the step end (predicted), start, previous start, then
    predictor weights of the residual at the start, previous start; ex (2, 4), ey (2, 6): the
    external force's (value at the step start, change over the step); cx (4,), cy (6,), feed (2,):
    sensor-mount acceleration = c . block + feed * residual; dense_x (d, 4 + 3 + 2), dense_y
    (d, 6 + 3 + 2): the same at d - 1 points inside the step (row s at s / d of the step; row 0
    unused): state, residual at the three corrector nodes, external force.

    Event sub-steps (``sub_mode`` 1, with d > 1): a step at whose end a ball is inside a defect
    (or which a narrow defect may cross within a step), and the AFTER_STEPS steps after it, are
    done again as d sub-steps of h / d, one per chain sample: an impact shorter than a step, and
    the structure's ringing after it, are what a parabola over the step cannot follow.  psx, psy,
    esx, esy: the sub-step's propagators as px, py, ex, ey; wsx (10, 4), wsy (10, 6): its
    weights as wx, wy, then those of the first sub-step, whose previous node is the previous
    step's start (d sub-steps back).

    Finer event sub-steps (``r_fine`` > 1): where the step's faster end turns the shaft faster
    than ``fine_speed`` (rad/s; ``KinematicModel.fine_event_speed``: a defect's edge is short on
    the chain grid there), the step is done again as d r_fine sub-steps of h / (d r_fine) instead,
    with the propagators pfx, pfy, wfx, wfy, efx, efy as psx .. esy (the first sub-step's
    previous node d r_fine sub-steps back); every r_fine-th node goes to out_acc, so the chain
    keeps its rate.  Elsewhere the sub-steps are the ones above, bit for bit.

    Writes d acceleration samples per step to out_acc (n * d, 2) and, every m-th step, the ball
    loads at the step start to out_q (n // m, 2 Nb: the inner contacts, then the outer ones, the
    same values for massless balls, F_c more where the balls carry it) and the cage speed to
    out_cage.

    fastmath "contract" only (no reassociation, no finite-math assumptions): the compiler may fuse
    a * b + c into one FMA instruction.  15-20 % faster (the step is a chain of multiply-adds);
    results move by ~1e-12 relative (FMA rounds once), far below the float32 of the published
    samples, and stay deterministic: the same compiled code gives the same bits, chunked or not.

    Why the body spells everything out (states as scalars, Hertz sums inline): every call of a
    compiled function that takes arrays passes each array's struct (and, with numba's runtime,
    which this kernel runs without, counted a reference on each), and states kept in arrays are
    stored and reloaded at every step (the compiler cannot prove that the output arrays do not
    alias them); both cost more than the arithmetic.
    """
    nb = int(geo[P_NB])
    kc = geo[P_K]
    gc = geom[0]
    gs = geom[1]
    goff = geom[2]
    eps = geom[3]
    grav = geo[P_GRAV]
    r_cage = geo[P_CAGE]
    r_spin = geo[P_SPIN]
    cdw = geo[P_CDW]
    ai = geo[P_AI]
    ao = geo[P_AO]
    sqi = geo[P_SQI]
    sqo = geo[P_SQO]
    sqio = geo[P_SQIO]
    rough = geo[P_ROUGH]
    # the film law at the speeds of the last start and end nodes, kept while the speed does not
    # change (a step's start is the last step's end)
    wf0 = wf1 = math.nan
    law0 = law1 = _film_law(geo, 0.0)
    held = geo[P_CFON] != 0.0           # the balls carry their centrifugal force (CENTRIFUGAL_GATE)
    inv_n = 1.0 / n
    dex = (l1x - l0x) * inv_n           # change of the external force over one step (N)
    dey = (l1y - l0y) * inv_n
    fdx = feed[0]
    fdy = feed[1]
    # how far a defect moves against the balls in one step (rad), at the faster end of the ramp
    sub_steps = sub_mode > 0 and d > 1 and dtab.shape[0] > 0
    wmax = max(abs(s0), abs(s1)) * h
    margin_i = abs(1.0 - r_cage) * wmax if sub_steps else 0.0
    margin_o = abs(r_cage) * wmax if sub_steps else 0.0
    margin_b = abs(r_spin) * wmax if sub_steps else 0.0
    hs = h / d
    inv_d = 1.0 / d
    hf = h / (d * r_fine)           # the finer sub-steps (where fine_speed is passed)
    inv_df = 1.0 / (d * r_fine)
    # the state as scalars: x block (xs, xp, vxs, vxp), y block (ys, yp, yr, vys, vyp, vyr)
    a0, a1, a2, a3 = x[0], x[2], x[5], x[7]
    b0, b1, b2, b3, b4, b5 = x[1], x[3], x[4], x[6], x[8], x[9]
    rxp = hist[0]
    ryp = hist[1]
    have_prev = hist[2] != 0.0
    # cos/sin of the cage angle advance by rotation (no trig per step) and are re-anchored to
    # the angle every ANCHOR_STEPS steps counted from t = 0, so chunking cannot change them
    cage_cos = trig[0]
    cage_sin = trig[1]
    shaft_angle, cage_angle, spin_angle = ang[0], ang[1], ang[2]
    steps = step[0]
    n_sub = step[1]
    if hist[3] == 0.0:
        ball_geometry(geo, cj, sj, dtab, wtab, seed, slip_cache, shaft_angle, cage_angle, spin_angle,
                      cage_cos, cage_sin, 0.0, 0.0, 0.0, eps, gc, gs, goff)
        hist[3] = 1.0
    o = -1                  # row of out_q / out_cage being written
    until_record = 0        # steps until the next recorded one (no integer division per step)
    since_near = int(hist[4])     # steps since a ball was last inside a defect at a step end
    for i in range(n):
        f0 = i * inv_n
        f1 = (i + 1) * inv_n
        w0 = s0 + (s1 - s0) * f0
        w1 = s0 + (s1 - s0) * f1
        # residual bearing force (Hertz minus its linearisation) at the start of the step
        record = until_record == 0
        if record:
            o += 1
            until_record = m
        until_record -= 1
        dx = a0 - a1
        dy = b0 - b1
        dvx = a2 - a3
        dvy = b3 - b4
        if w0 != wf0:
            law0 = law1 if w0 == wf1 else _film_law(geo, w0)
            wf0 = w0
        wc = r_cage * w0
        rc = dvx + wc * dy      # the balls' approach rate as in _residual
        rs = dvy - wc * dx
        fx = 0.0
        fy = 0.0
        if held:
            fc = law0[7]
            for j in range(nb):
                c = gc[j]
                s = gs[j]
                base = dx * c + dy * s - goff[j]
                dl, hz, hi, ho = _ball_state(geo, kc, law0, base)
                qj = _held_ball_load(cdw, ai, ao, sqi, sqo, sqio, hi + rough, ho + rough, dl, hz,
                                     rc * c + rs * s)
                fx += qj * c
                fy += qj * s
                if record:
                    out_q[o, j] = qj
                    out_q[o, nb + j] = qj + fc
        else:
            # massless balls (``CENTRIFUGAL_GATE``): as before the force
            lam, inv_lam, phi_f, u_f, lam_i, lam_o = (law0[0], law0[1], law0[2], law0[3], law0[4],
                                                      law0[5])
            for j in range(nb):
                c = gc[j]
                s = gs[j]
                base = dx * c + dy * s - goff[j]
                phi = _film_factor(base * inv_lam, phi_f, u_f)
                qj = _ball_load(kc, cdw, ai, ao, sqi, sqo, sqio, lam_i * phi + rough, lam_o * phi + rough,
                                base + lam * phi, rc * c + rs * s)
                fx += qj * c
                fy += qj * s
                if record:
                    out_q[o, j] = qj
                    out_q[o, nb + j] = qj
        rx = fx - kbx * dx
        ry = fy - kby * dy
        if not have_prev:
            rxp = rx
            ryp = ry
            have_prev = True
        if record:
            out_cage[o] = r_cage * w0
        # sensor-mount acceleration at the start of the step
        k = i * d
        out_acc[k, 0] = cx[0] * a0 + cx[1] * a1 + cx[2] * a2 + cx[3] * a3 + fdx * rx
        out_acc[k, 1] = (cy[0] * b0 + cy[1] * b1 + cy[2] * b2 + cy[3] * b3 + cy[4] * b4
                         + cy[5] * b5 + fdy * ry)
        # free response over the step plus the external force (exact for its linear ramp)
        exn = l0x + (l1x - l0x) * f0
        eyn = l0y + (l1y - l0y) * f0 - grav
        ca0, ca1, ca2, ca3, cb0, cb1, cb2, cb3, cb4, cb5 = _free_response(
            px, py, ex, ey, a0, a1, a2, a3, b0, b1, b2, b3, b4, b5, exn, eyn, dex, dey)
        # predictor (residual extrapolated linearly from the last two starts): only the
        # shaft-pedestal offset and its rate are needed, for the residual at the step end
        dx, dy, dvx, dvy = _predicted_offset(wx, wy, 0, ca0, ca1, ca2, ca3, cb0, cb1, cb3, cb4,
                                             rx, rxp, ry, ryp)
        # angles and ball geometry at the end of the step (trapezoid on the linear speed ramp)
        start_angles = (shaft_angle, cage_angle, spin_angle, cage_cos, cage_sin)
        dth = 0.5 * (w0 + w1) * h
        shaft_angle += dth
        cage_angle += r_cage * dth
        spin_angle += r_spin * dth
        steps += 1
        anchor = steps % ANCHOR_STEPS == 0
        if anchor:
            cage_cos = math.cos(cage_angle)
            cage_sin = math.sin(cage_angle)
        else:
            cage_cos, cage_sin = _rotate(cage_cos, cage_sin, r_cage * dth)
        near = ball_geometry(geo, cj, sj, dtab, wtab, seed, slip_cache, shaft_angle, cage_angle,
                             spin_angle, cage_cos, cage_sin, margin_i, margin_o, margin_b, eps, gc,
                             gs, goff)
        # residual at the predicted end of the step
        if w1 != wf1:
            wf1 = w1
            law1 = _film_law(geo, w1)
        rxs, rys = _residual(geo, kc, kbx, kby, gc, gs, goff, dx, dy, dvx, dvy, r_cage * w1, cdw, ai, ao,
                             sqi, sqo, sqio, law1, rough)
        # sub-steps where a ball is inside a defect at the step end, and in the AFTER_STEPS
        # steps after (the ball leaves the defect, the structure rings after the impact)
        since_near = 0 if near else min(since_near + 1, 1000)
        if sub_steps and since_near <= AFTER_STEPS:
            # the step again as d sub-steps, one per chain sample, or d r_fine where a defect's
            # edge is short on the chain grid (its impacts would beat with the pit's phase there)
            n_sub += 1
            if r_fine > 1 and max(abs(w0), abs(w1)) > fine_speed:
                ns = d * r_fine
                stride = r_fine
                inv_s = inv_df
                hsub = hf
                qsx, qsy, qwx, qwy, qex, qey = pfx, pfy, wfx, wfy, efx, efy
            else:
                ns = d
                stride = 1
                inv_s = inv_d
                hsub = hs
                qsx, qsy, qwx, qwy, qex, qey = psx, psy, wsx, wsy, esx, esy
            kw = k              # the chain sample last written, and sub-steps until the next
            until_write = stride
            shaft_angle, cage_angle, spin_angle, cage_cos, cage_sin = start_angles
            rsx = rx
            rsy = ry
            rqx = rxp           # residual at the previous node: the previous step's start
            rqy = ryp
            first = 5           # first sub-step: weight rows for that node, d sub-steps back
            for sd in range(ns):
                g0 = (i + sd * inv_s) * inv_n
                g1 = (i + (sd + 1) * inv_s) * inv_n
                v0 = s0 + (s1 - s0) * g0
                v1 = s0 + (s1 - s0) * g1
                if sd > 0:
                    # residual and acceleration at the sub-step's start
                    if v0 != wf0:
                        law0 = law1 if v0 == wf1 else _film_law(geo, v0)
                        wf0 = v0
                    rsx, rsy = _residual(geo, kc, kbx, kby, gc, gs, goff, a0 - a1, b0 - b1, a2 - a3,
                                         b3 - b4, r_cage * v0, cdw, ai, ao, sqi, sqo, sqio, law0,
                                         rough)
                    until_write -= 1
                    if until_write == 0:         # a chain sample: every stride-th node
                        until_write = stride
                        kw += 1
                        out_acc[kw, 0] = cx[0] * a0 + cx[1] * a1 + cx[2] * a2 + cx[3] * a3 + fdx * rsx
                        out_acc[kw, 1] = (cy[0] * b0 + cy[1] * b1 + cy[2] * b2 + cy[3] * b3
                                          + cy[4] * b4 + cy[5] * b5 + fdy * rsy)
                exs = l0x + (l1x - l0x) * g0
                eys = l0y + (l1y - l0y) * g0 - grav
                dexs = dex * inv_s
                deys = dey * inv_s
                ca0, ca1, ca2, ca3, cb0, cb1, cb2, cb3, cb4, cb5 = _free_response(
                    qsx, qsy, qex, qey, a0, a1, a2, a3, b0, b1, b2, b3, b4, b5, exs, eys, dexs, deys)
                dx, dy, dvx, dvy = _predicted_offset(qwx, qwy, first, ca0, ca1, ca2, ca3, cb0, cb1,
                                                     cb3, cb4, rsx, rqx, rsy, rqy)
                dth = 0.5 * (v0 + v1) * hsub
                shaft_angle += dth
                cage_angle += r_cage * dth
                spin_angle += r_spin * dth
                if anchor and sd == ns - 1:
                    cage_cos = math.cos(cage_angle)
                    cage_sin = math.sin(cage_angle)
                else:
                    cage_cos, cage_sin = _rotate(cage_cos, cage_sin, r_cage * dth)
                ball_geometry(geo, cj, sj, dtab, wtab, seed, slip_cache, shaft_angle, cage_angle,
                              spin_angle, cage_cos, cage_sin, 0.0, 0.0, 0.0, eps, gc, gs, goff)
                if v1 != wf1:
                    wf1 = v1
                    law1 = _film_law(geo, v1)
                rxs, rys = _residual(geo, kc, kbx, kby, gc, gs, goff, dx, dy, dvx, dvy, r_cage * v1, cdw,
                                     ai, ao, sqi, sqo, sqio, law1, rough)
                a0, a1, a2, a3, b0, b1, b2, b3, b4, b5 = _corrected(
                    qwx, qwy, first, ca0, ca1, ca2, ca3, cb0, cb1, cb2, cb3, cb4, cb5, rxs, rsx, rqx,
                    rys, rsy, rqy)
                rqx = rsx
                rqy = rsy
                first = 0
            rxp = rx
            ryp = ry
            continue
        # acceleration inside the step (dense output) from the corrector's residual interpolant
        for sd in range(1, d):
            out_acc[k + sd, 0] = (dense_x[sd, 0] * a0 + dense_x[sd, 1] * a1 + dense_x[sd, 2] * a2
                                  + dense_x[sd, 3] * a3 + dense_x[sd, 4] * rxs + dense_x[sd, 5] * rx
                                  + dense_x[sd, 6] * rxp + dense_x[sd, 7] * exn + dense_x[sd, 8] * dex)
            out_acc[k + sd, 1] = (dense_y[sd, 0] * b0 + dense_y[sd, 1] * b1 + dense_y[sd, 2] * b2
                                  + dense_y[sd, 3] * b3 + dense_y[sd, 4] * b4 + dense_y[sd, 5] * b5
                                  + dense_y[sd, 6] * rys + dense_y[sd, 7] * ry + dense_y[sd, 8] * ryp
                                  + dense_y[sd, 9] * eyn + dense_y[sd, 10] * dey)
        # corrector: the residual interpolated by the parabola through the predicted end, the
        # start and the previous start
        a0, a1, a2, a3, b0, b1, b2, b3, b4, b5 = _corrected(
            wx, wy, 0, ca0, ca1, ca2, ca3, cb0, cb1, cb2, cb3, cb4, cb5, rxs, rx, rxp, rys, ry, ryp)
        rxp = rx
        ryp = ry
    x[0], x[2], x[5], x[7] = a0, a1, a2, a3
    x[1], x[3], x[4], x[6], x[8], x[9] = b0, b1, b2, b3, b4, b5
    ang[0], ang[1], ang[2] = shaft_angle, cage_angle, spin_angle
    step[0] = steps
    step[1] = n_sub
    hist[0] = rxp
    hist[1] = ryp
    hist[2] = 1.0 if have_prev else 0.0
    hist[4] = since_near
    trig[0] = cage_cos
    trig[1] = cage_sin


def contact_damping(scene, ball_load: float) -> np.ndarray:
    """The geometry vector's contact-damping entries (P_CDW .. P_SQIO) for a scene whose most
    loaded ball carries ``ball_load`` N: the skidding tier's contact damping (module ``film``)
    for a massless ball, whose two contacts carry the same load in series.

    Hertz splits a ball's deflection as delta_i = a_i delta, a_i = (K / K_i)^(2/3) (a_i + a_o =
    1).  The squeeze films, 6 pi eta R_x R_y / (|delta_i| + h + roughness) at each contact as the
    skidding tier has them, act in series: c = c_i c_o / (c_i + c_o), one division per ball.
    Across a gap the ball rests on the outer race (it is flung there) and the whole gap is the
    inner contact's, on approach only, so c is continuous where the ball touches: a jump there
    made the tier's integrator first order.  (For a loaded ball the Kelvin-Voigt pair passes slow
    motion with c = a_i^2 c_i + a_o^2 c_o instead; with a_i = a_o and equal films the two agree,
    and on the shipped bearings within 10 %.)  The structural part, 2 zeta sqrt(m_b k_t) per
    contact in series likewise, goes as delta^0.25; here as delta^0.5 scaled to match at the most
    loaded ball (continuous, zero where the ball touches, and no root per ball beyond Hertz's)."""
    b = scene.bearing
    lub = scene.lubrication
    ic, oc = b.inner_contact, b.outer_contact
    k = b.combined_stiffness
    a_i = (k / ic.stiffness) ** (2.0 / 3.0)
    a_o = (k / oc.stiffness) ** (2.0 / 3.0)
    # structural: c_h,i = cd_i delta_i^0.25 in series with c_h,o at the reference deflection
    q_ref = max(ball_load, FILM_LOAD_FLOOR)
    delta_ref = (q_ref / k) ** (2.0 / 3.0)
    ch_i = structural_damping_coefficient(ic, lub, b.ball_mass) * (a_i * delta_ref) ** 0.25
    ch_o = structural_damping_coefficient(oc, lub, b.ball_mass) * (a_o * delta_ref) ** 0.25
    ch = ch_i * ch_o / (ch_i + ch_o) if ch_i + ch_o > 0.0 else 0.0
    sq_i = squeeze_film_coefficient(ic, lub)
    sq_o = squeeze_film_coefficient(oc, lub)
    return np.array([ch / math.sqrt(delta_ref), a_i, a_o, sq_i, sq_o, sq_i * sq_o])


def film_law(scene) -> np.ndarray:
    """The geometry vector's film entries (P_LAM .. P_ROUGH) for a scene.  Each ball's films fill
    part of the clearance, as in the skidding tier, and follow its own Hertz load (h ~ Q^-0.073:
    an unloaded ball's is 2.3x that of a 1000 N one) and the speed (h ~ u^0.68, u = r_o w_cage
    the entrainment speed of pure rolling, at both contacts): the film law of module ``film``,
    whose length lambda = (C K^-0.073)^(1 / (1 + a)) |w|^FILM_W_EXP with h = C |w|^0.68 Q^-0.073
    the film of both contacts together."""
    b = scene.bearing
    lub = scene.lubrication
    k = b.combined_stiffness
    # h = C u^0.68 Q^-0.073 with u = r_o * cage speed ratio * |w|: C per |w|^0.68
    c_i = film_coefficient(b.inner_contact, lub, b.effective_modulus)
    c_o = film_coefficient(b.outer_contact, lub, b.effective_modulus)
    per_speed = (0.5 * b.outer_race_diameter * b.cage_speed(1.0)) ** FILM_EXP_U
    lam = ((c_i + c_o) * per_speed * k ** FILM_EXP_Q) ** (1.0 / (1.0 + FILM_LAW_A)) if lub.ehl_film else 0.0
    return np.array([lam, c_i / (c_i + c_o), (FILM_LOAD_FLOOR / k) ** (2.0 / 3.0), lub.surface_roughness])


def centrifugal_law_table(stiffness_ratio: float) -> np.ndarray:
    """g(v), e(v), (e(v) / e(1))^-a, (1 + q)^-0.073 on v = k / CTAB_CELLS, k = 0 .. CTAB_CELLS,
    interleaved (g0, e0, ..., g1, ...): a ball's inner-contact load over the series law, Q_i / (K
    delta^1.5), its outer contact's share of the deflection, delta_o / delta, and the two factors
    of its outer contact's film (``_ball_state``), with v = sqrt(1 - delta_c / delta)
    (``inner_contact_load``), for
    ``stiffness_ratio`` = (K_o / K_i)^(2/3) = r.  With q = Q_i / F_c the balance Q_o = Q_i + F_c
    gives delta / delta_c = x = (1 + q)^(2/3) + r q^(2/3), explicit in q, and g = (q^(2/3) (1 + r)
    / x)^1.5: x is solved for q by bisection on log q (to machine precision, once per bearing).
    g goes from 0 (v = 0, as v^3) to 1 (v = 1: no centrifugal force, or a load far above it), e
    = (1 + q)^(2/3) / x from 1 to 1 / (1 + r) (the series law's share); the last factor is 0 at
    v = 1, where it is not used."""
    r = float(stiffness_ratio)
    v = np.arange(CTAB_CELLS + 1) / CTAB_CELLS
    x = 1.0 / np.maximum(1.0 - v[:-1] ** 2, 1e-300)
    lo = np.full(x.shape, -60.0)
    hi = np.full(x.shape, 60.0)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        q = np.exp(mid)
        above = (1.0 + q) ** (2.0 / 3.0) + r * q ** (2.0 / 3.0) > x
        hi = np.where(above, mid, hi)
        lo = np.where(above, lo, mid)
    q = np.exp(0.5 * (lo + hi))
    x = (1.0 + q) ** (2.0 / 3.0) + r * q ** (2.0 / 3.0)
    g = (q ** (2.0 / 3.0) * (1.0 + r) / x) ** 1.5
    e = (1.0 + q) ** (2.0 / 3.0) / x
    g[0], e[0], q[0] = 0.0, 1.0, 0.0
    ehat = (e * (1.0 + r)) ** -FILM_LAW_A
    p = (1.0 + q) ** FILM_EXP_Q
    return np.column_stack([np.append(g, 1.0), np.append(e, 1.0 / (1.0 + r)), np.append(ehat, 1.0),
                            np.append(p, 0.0)]).ravel()


def centrifugal_force(bearing, speed: float) -> float:
    """A ball's centrifugal force F_c = m_b (D_m / 2) w_c^2 (N) at shaft speed ``speed`` (rad/s),
    w_c the pure-rolling cage speed (seed 000 eq. 31)."""
    return bearing.ball_mass * 0.5 * bearing.pitch_diameter * bearing.cage_speed(abs(speed)) ** 2


def centrifugal_ratio(scene, load, speed: float) -> float:
    """F_c / Q_max at the radial ``load`` (N, x and y) and shaft ``speed`` (rad/s): a ball's
    centrifugal force (``centrifugal_force``) over 5 W / Z, W the load the balls carry
    (``fidelity.bearing_load``, the shaft's weight in) and Z the balls: what ``CENTRIFUGAL_GATE``
    is compared with, and what docs/fidelity_rms_gap.md sorts its points by."""
    from ..fidelity import bearing_load

    b = scene.bearing
    return centrifugal_force(b, speed) / (5.0 * max(bearing_load(scene, load), 1e-3) / b.balls)


def carries_centrifugal_force(scene, load, speed: float) -> bool:
    """Whether the kinematic tier's balls carry their centrifugal force at the radial ``load`` (N,
    x and y) and shaft ``speed`` (rad/s): F_c / Q_max (``centrifugal_ratio``) at least
    ``CENTRIFUGAL_GATE``, or at least ``CENTRIFUGAL_SMALL_PLAY_GATE`` on a bearing whose radial
    play over its ball diameter is at most ``CENTRIFUGAL_SMALL_PLAY`` (none or a preload too)."""
    ratio = centrifugal_ratio(scene, load, speed)
    b = scene.bearing
    small_play = b.radial_clearance <= CENTRIFUGAL_SMALL_PLAY * b.ball_diameter
    return bool(ratio >= CENTRIFUGAL_GATE or (small_play and ratio >= CENTRIFUGAL_SMALL_PLAY_GATE))


def centrifugal_law(scene) -> np.ndarray:
    """The geometry vector's entries from P_FCW up to P_CFON, then from P_CTAB on: F_c per shaft speed^2 (N s^2), F_c =
    m_b (D_m / 2) w_c^2 with w_c the pure-rolling cage speed (seed 000 eq. 31, the skidding
    tier's, with its balls at the cage's speed); the outer contact's Hertz deflection under it,
    (F_c / K_o)^(2/3), and a massless ball's, (F_c / K)^(2/3), per |shaft speed|^(4/3) (m); K_i,
    K_o^(-2/3); the inner contact's own film law (module ``film``: lambda_i^(1 + a) = C_i
    K_i^-0.073, per |w|^FILM_W_EXP, 0 without film) and its Hertz deflection at the load floor;
    the outer contact's film coefficient C_o per |w|^0.68 (h_o = C_o Q_o^-0.073, as
    ``film_law``'s); 1 / a_i = (K_i / K)^(2/3); then ``centrifugal_law_table`` of the bearing's K_o / K_i.  The balls' own weight (m_b g, which
    the skidding tier has too) is left out: it is 0.2 % of F_c on b6307_seed001 at 1500 rpm."""
    bearing, lub = scene.bearing, scene.lubrication
    fcw = centrifugal_force(bearing, 1.0)
    ko, ki = bearing.outer_contact.stiffness, bearing.inner_contact.stiffness
    k = bearing.combined_stiffness
    per_speed = (0.5 * bearing.outer_race_diameter * bearing.cage_speed(1.0)) ** FILM_EXP_U
    c_i = film_coefficient(bearing.inner_contact, lub, bearing.effective_modulus) * per_speed
    c_o = film_coefficient(bearing.outer_contact, lub, bearing.effective_modulus) * per_speed
    lam_i = (c_i * ki ** FILM_EXP_Q) ** (1.0 / (1.0 + FILM_LAW_A)) if lub.ehl_film else 0.0
    return np.concatenate([[fcw, (fcw / ko) ** (2.0 / 3.0), (fcw / k) ** (2.0 / 3.0), ki,
                            ko ** (-2.0 / 3.0), lam_i, (FILM_LOAD_FLOOR / ki) ** (2.0 / 3.0), c_o,
                            (ki / k) ** (2.0 / 3.0)],
                           centrifugal_law_table((ko / ki) ** (2.0 / 3.0))])


def held_ball_table(geo: np.ndarray, speed: float) -> None:
    """Tabulate in ``geo`` (from P_XTAB on, and P_XW) a held ball's quasi-static balance (each
    contact's film at its own load, Q_o = Q_i + F_c: ``_quasi_static_ball``, converged Newton
    steps) at shaft speed ``speed`` (rad/s), for ``_ball_state`` to look up.  The balance is one
    ball's, so the table is per bearing and speed (not load), as ``centrifugal_law_table``.  Its
    pieces break where the law does, at the inner contact's touch b_0 and its load floor b_fl
    (the inner film's law changes there; both from ``_film_law`` at any speed); each holds
    dimensionless values that stay bounded, then their slopes and half curvatures in ln |w| (from
    tables at +-XTAB_DSPEED), with which the kernel follows the speed between rebuilds
    (``KinematicModel._follow_held_table``: at a linearisation or an ``advance`` whose speed has
    moved by more than ``CENTRIFUGAL_SPEED_STEP`` of the table's).  3 x 8706 balances, 20-40 ms (a load's
    relinearisation does not rebuild it).  Nothing without films or without a force
    (``_ball_state`` takes its two passes there)."""
    w = abs(float(speed))
    geo[P_XW] = 0.0
    geo[P_XTAB:] = 0.0
    if w == 0.0 or geo[P_LAM] <= 0.0 or geo[P_FCW] <= 0.0:
        return
    above = np.empty((3, XTAB_CELLS + 1, 3))
    below = np.empty((3, YTAB_CELLS + 1, 2))
    for j, f in enumerate((1.0, 1.0 + XTAB_DSPEED, 1.0 - XTAB_DSPEED)):
        _held_ball_columns(geo, w * f, above[j], below[j])
    # value, slope and half the curvature in ell = ln(|w| / speed) from the three speeds
    lp, lm = math.log1p(XTAB_DSPEED), math.log1p(-XTAB_DSPEED)
    for cols, lo, hi in ((above, P_XTAB, P_YTAB), (below, P_YTAB, geo.size)):
        dp, dm = cols[1] - cols[0], cols[2] - cols[0]
        curv = (dp / lp - dm / lm) / (lp - lm)
        geo[lo:hi] = np.concatenate([cols[0], dp / lp - curv * lp, curv], axis=1).ravel()
    geo[P_XW] = w


@njit(cache=True)
def _ball_films(geo, geom, dx, dy, shaft_speed):
    """Each ball's film (m, inner and outer contact) at the shaft-pedestal offset (dx, dy) m,
    the balls' geometry ``geom`` and the shaft speed (rad/s)."""
    law = _film_law(geo, shaft_speed)
    nb = geom.shape[1]
    out = np.empty((nb, 2))
    if geo[P_CFON] == 0.0:
        # massless balls: one film at one load, as before the force
        inv_lam, phi_f, u_f, lam_i, lam_o = law[1], law[2], law[3], law[4], law[5]
        for j in range(nb):
            phi = _film_factor((dx * geom[0, j] + dy * geom[1, j] - geom[2, j]) * inv_lam, phi_f, u_f)
            out[j, 0] = lam_i * phi
            out[j, 1] = lam_o * phi
        return out
    for j in range(nb):
        _d, _hz, out[j, 0], out[j, 1] = _ball_state(geo, geo[P_K], law,
                                                    dx * geom[0, j] + dy * geom[1, j] - geom[2, j])
    return out


def _blocks(A, B, tau, h):
    """exp(A h tau) and E_j(tau), j = 0 .. 2, for a step of h s (tau in units of h): Van Loan's
    block exponential (``KinematicModel._propagators``)."""
    from scipy.linalg import expm

    order = len(CORRECTOR_NODES)
    nz = NSTATE + order * NINPUT
    Z = np.zeros((nz, nz))
    Z[:NSTATE, :NSTATE] = A * h
    Z[:NSTATE, NSTATE:NSTATE + NINPUT] = B * h
    for j in range(order - 1):
        r0 = NSTATE + j * NINPUT
        Z[r0:r0 + NINPUT, r0 + NINPUT:r0 + 2 * NINPUT] = np.eye(NINPUT)
    E = expm(tau * Z)
    return E[:NSTATE, :NSTATE], [E[:NSTATE, NSTATE + j * NINPUT:NSTATE + (j + 1) * NINPUT]
                                  * math.factorial(j) for j in range(order)]


def _weights(Es, corrector, predictor):
    """What the residual at each corrector node, then each predictor node, adds (``_blocks``'s
    E_j combined by the Lagrange basis of the nodes, in steps)."""
    order = len(CORRECTOR_NODES)
    vc, vp = _lagrange(corrector), _lagrange(predictor)
    wc = [sum(Es[j] * vc[j, i] for j in range(order)) for i in range(order)]
    wp = [sum(Es[j] * vp[j, i] for j in range(len(predictor))) for i in range(len(predictor))]
    return wc + wp


def _sub_step_propagators(A, B, h, sub):
    """The kernel's event sub-step propagators (psx, psy, wsx, wsy, esx, esy) for sub-steps of
    h / sub s; the first sub-step's previous node is the previous step's start, ``sub`` sub-steps
    back."""
    xb, yb = list(X_BLOCK), list(Y_BLOCK)
    phs, Ess = _blocks(A, B, 1.0, h / sub)
    ws = (_weights(Ess, CORRECTOR_NODES, PREDICTOR_NODES)
          + _weights(Ess, CORRECTOR_NODES[:2] + (-float(sub),), PREDICTOR_NODES[:1] + (-float(sub),)))
    return (np.ascontiguousarray(phs[np.ix_(xb, xb)]), np.ascontiguousarray(phs[np.ix_(yb, yb)]),
            np.ascontiguousarray([wi[xb, 0] for wi in ws]), np.ascontiguousarray([wi[yb, 1] for wi in ws]),
            np.ascontiguousarray([Ess[0][xb, 2], Ess[1][xb, 2]]),
            np.ascontiguousarray([Ess[0][yb, 3], Ess[1][yb, 3]]))


def bearing_mode_hz(A: np.ndarray, structure) -> float:
    """The highest mode (Hz) of a linearised structure's system matrix ``A`` below its unit
    resonator: the bearing's.  The stiffer the bearing (the load), the higher it is and the less
    one step per output sample follows it."""
    freqs = np.abs(np.linalg.eigvals(A).imag) / (2 * math.pi)
    if structure.has_resonator:
        freqs = freqs[freqs < 0.9 * structure.resonator_hz]
    return float(freqs.max()) if freqs.size else 0.0


class KinematicModel:
    """The kinematic tier (see module docstring).  ``internal_rate`` in Hz."""

    name = "kinematic"

    def __init__(self, scene, output_rate: float, oversample: int | None, seed: int, shaft_speed: float,
                 radial_load, chain_oversample: int | None = None, event_substeps: bool = True,
                 defect_sizes=None, ellipse_ball_load=None, centrifugal: bool | None = None):
        """``oversample``: integration steps per output sample; None picks 1 or
        ``DEFAULT_OVERSAMPLE`` from the bearing mode at each linearisation (``step_for_mode``);
        ``chain_oversample``: samples per output sample handed to the accelerometer chain (a
        multiple of every ``oversample`` used; default ``max(oversample, CHAIN_OVERSAMPLE)``),
        the extra ones by dense output; ``defect_sizes``: one factor (0-1) per scene defect, None =
        all at full size (``set_defect_sizes``); ``ellipse_ball_load`` (N): the ball load that sizes
        a wandering ball defect's contact ellipse, None = the most loaded ball's static load at the
        set-up (a tier switch passes the old tier's on); ``centrifugal``: None = the balls carry
        their centrifugal force where ``carries_centrifugal_force`` says (``CENTRIFUGAL_GATE``, and
        on small radial play ``CENTRIFUGAL_SMALL_PLAY_GATE``), True or False = always or never (for
        measuring the gate)."""
        self.scene = scene
        self.output_rate = float(output_rate)
        self.auto_oversample = oversample is None
        largest = DEFAULT_OVERSAMPLE if self.auto_oversample else int(oversample)
        chain = chain_oversample or max(largest, CHAIN_OVERSAMPLE)
        if chain % largest:
            raise ValueError(f"chain_oversample {chain} is not a multiple of oversample {largest}")
        self.chain_per_sample = chain
        self.internal_rate = self.output_rate * chain
        self._set_step(largest)
        self.seed = int(seed)
        self.event_substeps = bool(event_substeps)
        b = scene.bearing
        st = scene.structure
        nb = b.balls
        self.geo = np.zeros(GEO_SIZE)
        self.geo[P_NB] = nb
        self.geo[P_K] = b.combined_stiffness
        self.geo[P_CR] = b.radial_clearance
        self.geo[P_RB] = 0.5 * b.ball_diameter
        self.geo[P_RI] = 0.5 * b.inner_race_diameter
        self.geo[P_RO] = 0.5 * b.outer_race_diameter
        self.geo[P_CAGE] = b.cage_speed(1.0)        # pure-rolling speeds per shaft rad/s
        self.geo[P_SPIN] = b.ball_spin_speed(1.0)
        self.geo[P_SLIP] = scene.random_slip
        self.geo[P_GRAV] = st.shaft_mass * G if scene.gravity else 0.0
        self.geo[P_LAM:P_FCW] = film_law(scene)       # the damping entries: at the linearisation
        law = centrifugal_law(scene)
        self.geo[P_FCW:P_CFON] = law[:P_CFON - P_FCW]
        self.geo[P_CTAB:P_XTAB] = law[P_CFON - P_FCW:]
        # whether the balls carry their centrifugal force (CENTRIFUGAL_GATE): decided at each
        # linearisation, and again where the speed moves (``_needs_relinearising``)
        self.centrifugal = False
        self._forced_centrifugal = centrifugal
        self._gate_speed = math.nan
        # the contacts' shares of a massless ball's deflection (``contact_damping`` sets them again,
        # the same): ``_ball_state`` reads a_i from the first linearisation on
        self.geo[P_AI] = (b.combined_stiffness / b.inner_contact.stiffness) ** (2.0 / 3.0)
        self.geo[P_AO] = (b.combined_stiffness / b.outer_contact.stiffness) ** (2.0 / 3.0)
        a = 2.0 * np.pi * np.arange(nb) / nb
        self.cj, self.sj = np.cos(a), np.sin(a)
        self.defect_sizes = None if defect_sizes is None else tuple(defect_sizes)
        # final table after the equilibrium (below)
        self.dtab = active_defect_table(scene.defects, self.defect_sizes, b)
        from .defects import waviness_table

        self.wtab = waviness_table(scene.waviness)
        self.angles = np.zeros(3)   # shaft, cage, ball spin (rad)
        self.slip_cache = np.full((nb, 3), np.nan)
        self.trig = np.array([1.0, 0.0])              # cos, sin of the cage angle
        self.step = np.zeros(2, dtype=np.int64)         # steps since t = 0, of them in sub-steps
        # previous residual (x, y), valid flags, steps since a ball was last inside a defect
        self.hist = np.array([0.0, 0.0, 0.0, 0.0, 1000.0])
        self.geom = np.zeros((4, nb))                 # ball geometry at the current time
        self.x = np.zeros(NSTATE)
        self._lin_load = None
        self._lin_speed = float(shaft_speed)      # rad/s, of the films at the linearisation
        self._linearise(np.asarray(radial_load, dtype=float), float(shaft_speed), initial=True)
        # a wandering ball defect is met within the contact ellipse of the most loaded ball at the
        # set-up; kept: later loads and tier switches do not move the ellipse
        self.ellipse_ball_load = (self.static_ball_load if ellipse_ball_load is None
                                  else float(ellipse_ball_load))
        self.dtab = active_defect_table(scene.defects, self.defect_sizes, b, seed=self.seed,
                                        ball_load=self.ellipse_ball_load)
        self.fine_speed, self.fine_events = self.fine_event_speed()
        self._balance_at_start(np.asarray(radial_load, dtype=float), float(shaft_speed))

    def _balance_at_start(self, load: np.ndarray, speed: float) -> None:
        """Start at rest where the balls' forces at their places at t = 0 balance the load, as
        the kernel computes them (each ball's film and defects; the damping of the approach that
        the turning balls see): the equilibrium of the averaged law (``_equilibrium``), which the
        linearisation needs, differs from it by up to a ball pass's share of the load, and a
        start there rang the structure (1.1 m/s^2 RMS over the first 10 ms of the healthy ER-16K
        at 10 rpm, where the signal is then nil; 1.3 against 1.0 m/s^2 vertical at 1600 rpm).  The
        averaged equilibrium is kept where the balance is not found (none: the balls' forces
        cannot hold the load)."""
        geo, geom = self.geo, self.geom
        # the balls' geometry at t = 0, as the kernel's first step takes it (and then keeps)
        ball_geometry(geo, self.cj, self.sj, self.dtab, self.wtab, self.seed, self.slip_cache,
                      self.angles[0], self.angles[1], self.angles[2], self.trig[0], self.trig[1],
                      0.0, 0.0, 0.0, geom[3], geom[0], geom[1], geom[2])
        self.hist[3] = 1.0
        law = _film_law(geo, speed)
        wc = geo[P_CAGE] * speed

        def at_start(d):
            # the kernel's residual with no linearised part taken off: the balls' whole force
            return np.array(_residual(geo, geo[P_K], 0.0, 0.0, geom[0], geom[1], geom[2], d[0], d[1], 0.0, 0.0,
                                      wc, geo[P_CDW], geo[P_AI], geo[P_AO], geo[P_SQI], geo[P_SQO],
                                      geo[P_SQIO], law, geo[P_ROUGH]))

        z, found = self._static_balance(load, at_start, self.x[:4].copy())
        if found:
            self.x[:4] = z
            self.x[4] = z[3]          # the resonator spring carries no static load

    def set_defect_sizes(self, sizes) -> None:
        """Take the scene's defects at ``sizes`` (one factor 0-1 each) from the next step on: a
        defect that appears or grows (``physics.defects.DefectSchedule``)."""
        self.defect_sizes = tuple(sizes)
        self.dtab = active_defect_table(self.scene.defects, self.defect_sizes, self.scene.bearing,
                                        seed=self.seed, ball_load=self.ellipse_ball_load)
        self.hist[2] = 0.0       # the residual jumps with the defects: restart its history
        self.hist[3] = 0.0       # and the balls' geometry (their defect losses) is recomputed
        self.fine_speed, self.fine_events = self.fine_event_speed()

    # ---- linearisation and propagators ---------------------------------------------------------
    def _set_step(self, oversample: int):
        """Integration steps per output sample: the step h (s) and the chain samples per step."""
        self.decimation = int(oversample)
        self.dense = self.chain_per_sample // self.decimation     # chain samples per integration step
        self.h = 1.0 / (self.output_rate * self.decimation)

    def step_for_mode(self, mode_hz: float) -> int:
        """Steps per output sample for a bearing mode (Hz): one while the mode stays below
        ``SOFT_MODE_FRACTION`` of the output rate, where one step per sample errs no more than
        two elsewhere (README, "Kinematic tier: speed and accuracy"), else ``DEFAULT_OVERSAMPLE``."""
        return 1 if mode_hz < SOFT_MODE_FRACTION * self.output_rate else DEFAULT_OVERSAMPLE

    def _mean_force(self, d: np.ndarray) -> np.ndarray:
        """Bearing force on the pedestal averaged over one ball spacing of cage angle (no
        defects, no slip): the quasi-static load-deflection law."""
        return np.array(mean_bearing_force(self._static_geo(), self.cj, self.sj, float(d[0]), float(d[1]),
                                           self._lin_speed, 12))

    def _static_geo(self) -> np.ndarray:
        """The geometry vector without slip: itself inside ``_without_slip`` (the linearisation's
        static laws), else a copy."""
        if self.geo[P_SLIP] == 0.0:
            return self.geo
        geo = self.geo.copy()
        geo[P_SLIP] = 0.0
        return geo

    @contextlib.contextmanager
    def _without_slip(self):
        """The balls' random slip at 0 in the geometry vector itself for the block, put back
        after: the linearisation's static laws take none (``_static_geo``), and a copy of the
        vector for each of their 20-70 evaluations cost 0.4-0.5 ms per linearisation once the
        held balls' table (``held_ball_table``, 650 KB) lived in it; a load that moves by 20 %
        every batch relinearises at every one."""
        slip = self.geo[P_SLIP]
        self.geo[P_SLIP] = 0.0
        try:
            yield
        finally:
            self.geo[P_SLIP] = slip

    def ball_films(self, shaft_speed: float) -> np.ndarray:
        """(Nb, 2): each ball's film thickness (m) at its inner and outer contact, at the
        current state and a shaft speed (rad/s): the kernel's film law (``_film_law``)."""
        if self.hist[3] == 0.0:          # the balls' geometry is not current: compute it
            ball_geometry(self.geo, self.cj, self.sj, self.dtab, self.wtab, self.seed, self.slip_cache,
                          self.angles[0], self.angles[1], self.angles[2], self.trig[0], self.trig[1],
                          0.0, 0.0, 0.0, self.geom[3], self.geom[0], self.geom[1], self.geom[2])
            self.hist[3] = 1.0
        return _ball_films(self.geo, self.geom, self.x[0] - self.x[2], self.x[1] - self.x[3],
                           float(shaft_speed))

    def _equilibrium(self, load: np.ndarray) -> np.ndarray:
        """Static positions (xs, ys, xp, yp) under the load (+ shaft weight), by the averaged
        load-deflection law (``_mean_force``)."""
        ext = load + np.array([0.0, -self.geo[P_GRAV]])
        scale = max(np.linalg.norm(ext), 1.0)
        # guess: the bearing takes the load through its stiffest ball, pedestal spring in series
        k_guess = self.geo[P_K] * 2.0
        dmag = (scale / k_guess) ** (2.0 / 3.0) + max(self.geo[P_CR], 0.0)
        direction = ext / scale if np.linalg.norm(ext) > 0 else np.array([0.0, -1.0])
        # the pedestal spring (never 0: scene._pedestal_error) takes the load, the bearing in series
        xp0 = ext / self.scene.structure.pedestal_stiffness
        return self._static_balance(load, self._mean_force, np.concatenate([xp0 + direction * dmag, xp0]))[0]

    def _static_balance(self, load: np.ndarray, bearing_force_of, guess: np.ndarray):
        """(positions (xs, ys, xp, yp), found) where the shaft and pedestal springs balance the
        load (+ shaft weight) and the bearing force ``bearing_force_of(shaft - pedestal offset)``
        (N on the pedestal), from ``guess`` (m)."""
        from scipy.optimize import fsolve

        st = self.scene.structure
        ext = load + np.array([0.0, -self.geo[P_GRAV]])
        ks, kp = st.shaft_stiffness, st.pedestal_stiffness
        scale = max(np.linalg.norm(ext), 1.0)

        def residual(z):
            xs, xp = z[:2] * 1e-6, z[2:] * 1e-6
            fb = bearing_force_of(xs - xp)
            return np.concatenate([(ks * xs + fb - ext) / scale, (kp * xp - fb) / scale])

        z, _info, ier, _msg = fsolve(residual, guess * 1e6, full_output=True, xtol=1e-12)
        return z * 1e-6, ier == 1 and bool(np.all(np.isfinite(z)))

    def _linearise(self, load: np.ndarray, speed: float, initial: bool = False):
        """The static equilibrium under ``load`` (N) at shaft ``speed`` (rad/s), the contact
        damping at its most loaded ball and the propagators of the structure with the bearing
        linearised there, each ball through its film at that speed."""
        with single_threaded_blas():
            self._linearise_on_one_thread(load, speed, initial)

    def centrifugal_ratio(self, load, speed: float) -> float:
        """F_c / Q_max of this scene at ``load`` (N) and ``speed`` (rad/s): ``centrifugal_ratio``,
        what ``carries_centrifugal_force`` compares with its gates."""
        return centrifugal_ratio(self.scene, load, speed)

    def _decide_centrifugal(self, load, speed: float) -> bool:
        """Whether the balls carry their centrifugal force at ``load`` (N) and ``speed`` (rad/s):
        ``carries_centrifugal_force`` (or as the constructor forced it)."""
        if self._forced_centrifugal is not None:
            return bool(self._forced_centrifugal)
        return carries_centrifugal_force(self.scene, load, speed)

    def _linearise_on_one_thread(self, load: np.ndarray, speed: float, initial: bool):
        self._lin_speed = speed
        # the balls' law first: the equilibrium, the damping and the propagators follow it
        self.centrifugal = self._decide_centrifugal((float(load[0]), float(load[1])), speed)
        self.geo[P_CFON] = 1.0 if self.centrifugal else 0.0
        self._gate_speed = abs(speed)
        self._follow_held_table(speed)
        with self._without_slip():
            eq = self._equilibrium(load)
            d0 = eq[:2] - eq[2:]
            q = np.zeros(int(self.geo[P_NB]))
            bearing_force(self._static_geo(), self.cj, self.sj, np.zeros((0, DEFECT_COLUMNS)),
                          np.zeros((0, 4)), 0, d0[0], d0[1], 0.0, 0.0, 0.0, q, speed)
            self.static_ball_load = float(q.max())      # N, most loaded ball at the equilibrium
            self.geo[P_CDW:P_LAM] = contact_damping(self.scene, self.static_ball_load)
            kb = secant_stiffness(self._mean_force, d0)       # of the averaged load-deflection law
        self.kb = kb
        # linearised bearing between shaft and pedestal: force on pedestal kb (s - p).  Only its
        # diagonal goes into the linear part (the residual takes the rest, so the model is the
        # same): then the horizontal and the vertical blocks of the state decouple, and the
        # off-diagonal term is ~1e-15 of the diagonal for any vertical load anyway.
        self.kbx, self.kby = float(kb[0, 0]), float(kb[1, 1])
        A, b_forces, _, _ = structure_system(self.scene, np.diag([self.kbx, self.kby]))
        # this tier's inputs: the residual bearing force (acting -on the shaft, +on the pedestal)
        # and the external force on the shaft; b_forces takes forces on shaft x, y, pedestal x, y
        to_forces = np.array([[-1.0, 0.0, 1.0, 0.0],
                              [0.0, -1.0, 0.0, 1.0],
                              [1.0, 0.0, 0.0, 0.0],
                              [0.0, 1.0, 0.0, 0.0]])
        B = b_forces @ to_forces
        self.bearing_mode = bearing_mode_hz(A, self.scene.structure)
        if self.auto_oversample:
            self._set_step(self.step_for_mode(self.bearing_mode))
        rows = [7, 9 if self.scene.structure.has_resonator else 8]
        self._propagators(A, B, A[rows], B[rows])
        self.fine_speed, self.fine_events = self.fine_event_speed()
        self.hist[2] = 0.0       # the residual's definition changed: restart its history
        self._lin_load = (float(load[0]), float(load[1]))
        if initial:
            self.x[:4] = eq
            self.x[4] = eq[3]          # the resonator spring carries no static load

    def _propagators(self, A, B, C, D):
        """Propagators of x' = A x + B u over one step h, with u (residual x, y; external x, y)
        interpolated by a polynomial: Van Loan's block exponential gives
        E_j(tau) = int_0^tau exp(A h (tau - s)) B h s^j ds (s in steps), j = 0, 1, 2, and the
        weights of the residual at the corrector / predictor nodes follow from the Lagrange
        basis.  The kernel gets the x and y blocks separately; C, D: acceleration rows."""
        self.A, self.B, self.C, self.D = A, B, C, D      # kept for tests and studies
        order = len(CORRECTOR_NODES)
        blocks = functools.partial(_blocks, A, B, h=self.h)
        weights = _weights
        vc = _lagrange(CORRECTOR_NODES)
        phi, Es = blocks(1.0)
        xb, yb = list(X_BLOCK), list(Y_BLOCK)
        # the blocks must decouple (diagonal kb, resonator on y only)
        assert not np.any(phi[np.ix_(xb, yb)]) and not np.any(phi[np.ix_(yb, xb)])
        w = weights(Es, CORRECTOR_NODES, PREDICTOR_NODES)   # rows of wx / wy, in the kernel's order
        # event sub-steps: one per chain sample; the finer ones (r per chain sample) when a
        # defect's edge first needs them (``_fine_propagators``)
        d = self.dense
        self.psx, self.psy, self.wsx, self.wsy, self.esx, self.esy = _sub_step_propagators(A, B, self.h, d)
        self.fine = {}
        self.px = np.ascontiguousarray(phi[np.ix_(xb, xb)])
        self.py = np.ascontiguousarray(phi[np.ix_(yb, yb)])
        self.wx = np.ascontiguousarray([wi[xb, 0] for wi in w])
        self.wy = np.ascontiguousarray([wi[yb, 1] for wi in w])
        self.ex = np.ascontiguousarray([Es[0][xb, 2], Es[1][xb, 2]])
        self.ey = np.ascontiguousarray([Es[0][yb, 3], Es[1][yb, 3]])
        # acceleration: x axis reads the pedestal, y the resonator (or the pedestal); the external
        # force acts on the shaft and reaches neither directly
        assert D[0, 2] == D[0, 3] == D[1, 2] == D[1, 3] == 0.0
        assert not np.any(C[0, yb]) and not np.any(C[1, xb])
        self.cx = np.ascontiguousarray(C[0, xb])
        self.cy = np.ascontiguousarray(C[1, yb])
        self.feed = np.array([D[0, 0], D[1, 1]])
        self.dense_x = np.zeros((d, 4 + order + 2))
        self.dense_y = np.zeros((d, 6 + order + 2))
        for sd in range(1, d):
            tau = sd / d
            phi_t, Et = blocks(tau)
            basis = [sum(vc[j, i] * tau ** j for j in range(order)) for i in range(order)]
            node = [C @ sum(Et[j] * vc[j, i] for j in range(order)) + D * basis[i] for i in range(order)]
            cphi = C @ phi_t
            self.dense_x[sd] = np.concatenate([cphi[0, xb], [nd[0, 0] for nd in node],
                                               [(C @ Et[0])[0, 2], (C @ Et[1])[0, 2]]])
            self.dense_y[sd] = np.concatenate([cphi[1, yb], [nd[1, 1] for nd in node],
                                               [(C @ Et[0])[1, 3], (C @ Et[1])[1, 3]]])

    def _fine_propagators(self, r: int):
        """The propagators (pfx, pfy, wfx, wfy, efx, efy) of r event sub-steps per chain sample
        (h / (d r) each), computed at the current linearisation the first time a batch may need
        them (a step faster than ``fine_speed``), so that a scene whose edges are long computes
        none."""
        if r not in self.fine:
            self.fine[r] = _sub_step_propagators(self.A, self.B, self.h, self.dense * r)
        return self.fine[r]

    def fine_event_speed(self) -> tuple:
        """(shaft speed (rad/s) above which the event sub-steps are finer than one per chain
        sample, inf where none needs them; how many per chain sample there: ``fine_events``)
        (README, "Limitations", and docs/kinematic_fast_pits.md).

        The balls' load leaves and returns at a pit's edges; where that takes a few chain samples
        only, the impacts' heights depend on where the edge falls on the chain grid and beat with
        it.  For each defect (a ball defect: at both of its contacts), with delta the Hertz
        deflection (m) of the most loaded ball at the linearisation (film left out) and the drop
        at the defect's centre: where the drop reaches delta (the ball unloads fully), the edge is
        the travel from the defect's border to where the drop is delta, and the finer sub-steps
        start where it is shorter than FINE_EDGE chain samples; where the drop reaches
        FINE_PARTIAL of delta but not delta, where the whole defect is crossed in fewer than
        FINE_CROSSING chain samples.  Travel over the speed of the defect against the balls
        (race: the cage's, relative; ball defect: the spin) gives the shaft speed.  The limits
        leave every shipped scene on the chain grid (the ER-16K's edges of 5.7-7.0 chain samples,
        CWRU's pits that never unload the ball, crossed in 6.1, seed 001's crack, 8.4).

        How many: the fewest of FINE_EVENTS's powers of two that put FINE_RESOLVE sub-steps on the
        shortest such edge (where the ball does not unload fully: half the crossing) at the speed
        of the linearisation (or at ``fine_speed``, if that is higher): one number per
        linearisation, so that a step's sub-steps do not depend on how the run is chunked."""
        if not self.event_substeps or self.dtab.shape[0] == 0:
            return math.inf, 1
        geo = self.geo
        delta = self.inner_gap(self.static_ball_load, self._lin_speed)
        chain_step = 1.0 / self.internal_rate          # s
        speed = math.inf
        shortest = math.inf          # rad per (rad/s of the shaft): the shortest edge's travel time
        for row in self.dtab:
            kind, half, prof, depth = int(row[D_KIND]), row[D_HALF], int(row[D_PROFILE]), row[D_DEPTH]
            if kind == KIND_BALL:
                contacts = ((geo[P_RB], abs(geo[P_SPIN]), row[D_RHO_O], row[D_HMAX_O], row[D_RAMP_O]),
                            (geo[P_RB], abs(geo[P_SPIN]), row[D_RHO_I], row[D_HMAX_I], row[D_RAMP_I]))
            elif kind == KIND_INNER:
                contacts = ((geo[P_RI], abs(1.0 - geo[P_CAGE]), row[D_RHO_I], row[D_HMAX_I], row[D_RAMP_I]),)
            else:
                contacts = ((geo[P_RO], abs(geo[P_CAGE]), row[D_RHO_O], row[D_HMAX_O], row[D_RAMP_O]),)
            for radius, rate, rho, hmax, ramp in contacts:
                def drop(inward):
                    # the drop (m) at ``inward`` rad from the defect's border
                    return _profile_drop(prof, half - inward, half, radius, rho, hmax, ramp, depth)
                top = drop(half)
                if top >= delta:
                    lo, hi = 0.0, half        # the drop grows inward (every profile): bisect
                    for _ in range(60):
                        mid = 0.5 * (lo + hi)
                        lo, hi = (lo, mid) if drop(mid) >= delta else (mid, hi)
                    travel, limit, edge = hi, FINE_EDGE, hi
                elif top >= FINE_PARTIAL * delta:
                    travel, limit, edge = 2.0 * half, FINE_CROSSING, half
                else:
                    continue
                speed = min(speed, travel / (rate * chain_step * limit))
                shortest = min(shortest, edge / rate)
        if speed == math.inf:
            return speed, 1
        edge_samples = shortest / (max(abs(self._lin_speed), speed) * chain_step)   # chain samples
        r = FINE_EVENTS[0]
        while r < FINE_EVENTS[1] and edge_samples * r < FINE_RESOLVE:
            r *= 2
        return speed, r

    def inner_gap(self, ball_load: float, shaft_speed: float) -> float:
        """The interference (m) that a drop must take away to lift a ball carrying ``ball_load``
        N at its inner contact off that race at ``shaft_speed`` rad/s (film left out): the ball
        stays against the outer race (its centrifugal force F_c), so it is delta - delta_c with
        delta / delta_c = (1 + q)^(2/3) + r q^(2/3), q = Q_i / F_c (``centrifugal_law_table``),
        the series law's (Q / K)^(2/3) without F_c or for massless balls (``CENTRIFUGAL_GATE``)."""
        geo = self.geo
        fc = geo[P_FCW] * shaft_speed ** 2
        if fc <= 0.0 or geo[P_CFON] == 0.0:
            return (ball_load / geo[P_K]) ** (2.0 / 3.0)
        b = self.scene.bearing
        r = (b.outer_contact.stiffness / b.inner_contact.stiffness) ** (2.0 / 3.0)
        q = ball_load / fc
        dc = geo[P_DCW] * abs(shaft_speed) ** (4.0 / 3.0)
        return dc * ((1.0 + q) ** (2.0 / 3.0) + r * q ** (2.0 / 3.0) - 1.0)

    def _follow_held_table(self, speed: float) -> None:
        """Tabulate the held balls' law (``held_ball_table``) at ``speed`` (rad/s) where they carry
        F_c and it is not built or the speed has moved by more than ``CENTRIFUGAL_SPEED_STEP`` of
        the table's (in between, the kernel follows the speed by the table's slopes; the table
        depends on the speed alone, so a load's relinearisation keeps it); dropped for massless
        balls (not read)."""
        geo, w = self.geo, abs(float(speed))
        if not self.centrifugal:
            if geo[P_XW] != 0.0:
                held_ball_table(geo, 0.0)
            return
        xw = geo[P_XW]
        if xw == 0.0 or (w > 0.0 and abs(w - xw) > CENTRIFUGAL_SPEED_STEP * xw):
            held_ball_table(geo, w)

    def _needs_relinearising(self, lx: float, ly: float, speed: float) -> bool:
        """Has the load (N) moved by more than 20 % of the one linearised at (10 N at least), or
        the balls' law to take changed (``carries_centrifugal_force``)?  The gate is decided again only
        where the speed (rad/s) moved by more than ``CENTRIFUGAL_SPEED_STEP`` of the one it was
        last decided at (F_c goes as its square; a load that moves the ratio relinearises
        anyway), so that a speed that wanders about the gate does not relinearise at every
        call."""
        rx, ry = self._lin_load
        if math.hypot(lx - rx, ly - ry) > 0.2 * max(math.hypot(rx, ry), 10.0):
            return True
        w = abs(speed)
        if abs(w - self._gate_speed) <= CENTRIFUGAL_SPEED_STEP * self._gate_speed:
            return False
        self._gate_speed = w
        return self._decide_centrifugal((lx, ly), w) != self.centrifugal

    # ---- TierModel interface --------------------------------------------------------------------
    def advance(self, n_steps, speed0, speed1, load0, load1) -> TierOutput:
        nb = int(self.geo[P_NB])
        n_out = n_steps // (self.dense * self.decimation)
        acc = np.empty((n_steps, 2))
        q = np.empty((n_out, 2 * nb))
        cage = np.empty(n_out)
        self.advance_into(n_steps, speed0, speed1, load0, load1, acc, q, cage)
        # a massless ball presses on both races alike; one held out by F_c, F_c more on the outer
        return TierOutput(accel=acc, inner_force=q[:, :nb], outer_force=q[:, nb:], cage_speed=cage)

    def advance_into(self, n_steps, speed0, speed1, load0, load1, acc, forces, cage) -> None:
        """``advance`` writing into the caller's arrays (no allocation): acc (n_steps, 2) m/s^2,
        forces (n_steps / chain oversample, 2 Nb) N (inner contacts, then outer), cage (same rows)
        rad/s; speeds in rad/s, loads (x, y) in N."""
        l1x, l1y = float(load1[0]), float(load1[1])
        if self._needs_relinearising(l1x, l1y, float(speed1)):
            self._linearise(np.array([l1x, l1y]), float(speed1))
        else:
            self._follow_held_table(float(speed1))
        d = self.dense
        fine_speed, r_fine = self.fine_speed, self.fine_events
        if self.event_substeps and d > 1 and max(abs(speed0), abs(speed1)) > fine_speed:
            pf = self._fine_propagators(r_fine)
        else:
            pf = (self.psx, self.psy, self.wsx, self.wsy, self.esx, self.esy)     # not read
        advance_kernel(self.x, self.angles, self.trig, self.step, self.hist, self.geom, n_steps // d,
                       self.decimation, d, float(speed0), float(speed1), float(load0[0]),
                       float(load0[1]), l1x, l1y, self.h, self.geo, self.cj, self.sj,
                       self.dtab, self.wtab, self.seed, self.slip_cache, self.kbx, self.kby,
                       self.px, self.py, self.wx, self.wy, self.ex, self.ey, self.cx, self.cy,
                       self.feed, self.dense_x, self.dense_y, self.psx, self.psy, self.wsx, self.wsy,
                       self.esx, self.esy, int(self.event_substeps), r_fine, fine_speed, *pf,
                       acc, forces, cage)
        self._last_speed = float(speed1)

    def adopt_state(self, other) -> None:
        """Continue from another tier's state (same ``x`` layout and ``angles``): the switch
        of fidelity tiers keeps positions, velocities and angles, so the signal has no seam."""
        self.x[:] = other.x
        self.angles[:] = other.angles
        self.step[:] = getattr(other, "step", self.step)
        self.trig[:] = (math.cos(self.angles[1]), math.sin(self.angles[1]))
        self.hist[2] = 0.0       # no previous residual of this tier's kind
        self.hist[3] = 0.0       # and the balls' geometry is recomputed for the new angles
        self._last_speed = getattr(other, "_last_speed", self.scene.shaft_speed)

    def snapshot(self) -> KinematicSnapshot:
        nb = int(self.geo[P_NB])
        w = getattr(self, "_last_speed", self.scene.shaft_speed)
        cage = self.angles[1]
        balls = cage + 2 * np.pi * np.arange(nb) / nb
        return KinematicSnapshot(self.angles[0], w, cage, self.geo[P_CAGE] * w,
                                 balls, np.full(nb, self.geo[P_CAGE] * w))
