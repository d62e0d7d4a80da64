"""Skidding tier: seed 000's (3 Nb + 5)-DOF deep-groove ball bearing with slip.

Degrees of freedom (state vector ``y``; SI units, angles counterclockwise from +x looking along
the shaft, the shaft turning counterclockwise for positive speed):

    y[0:10]   shaft/inner race x, y; pedestal/outer race x, y; unit resonator y; their velocities
              (the kinematic tier's ``x`` layout: [xs, ys, xp, yp, yr, vxs, vys, vxp, vyp, vyr])
    y[10:12]  cage angle phi_c (rad) and speed (rad/s)
    y[12+6j:] ball j: revolution angle theta (rad), radial position rho of its centre from the
              outer-race centre (m), spin angle psi relative to its orbital frame (rad, positive in
              the direction of the pure-rolling spin, i.e. BSF > 0), revolution speed
              theta' (rad/s), radial speed rho' (m/s), absolute angular velocity Omega (rad/s,
              counterclockwise; pure rolling has Omega < 0 when the cage turns counterclockwise)

The shaft angle follows the commanded speed (seed 000 assumption 4).

Forces (seed 000 Sec. 2, with the corrections of PHYSICS_NOTES):

* Hertz at each contact separately (catalog ``inner_contact`` / ``outer_contact`` stiffness,
  Hamrock-Brewe): Q = K delta^1.5 with the interferences (eqs 3, 4, 10)
      delta_i = e + R_m - C_r/2 - rho + h_i - loss_i,   delta_o = rho - R_m - C_r/2 + h_o - loss_o
  where e = (x_s - x_p) cos(theta) + (y_s - y_p) sin(theta) is the shaft offset towards the
  ball, loss_* the defect interference losses of ``defects.interference_loss`` (every kind and
  depth profile, inner and outer contact separately) and the waviness gain of each race.
* EHL film (eqs 12-16, ``lubrication.ehl_film``): the Hamrock-Dowson minimum film thickness
  h = 3.63 U^0.68 G^0.49 W^-0.073 (1 - exp(-0.68 k)) R_x of each contact separates the solids, so
  it enters the interference as +h (a reduced clearance, as seed 001 treats the film; eq. 13's
  minus sign would open the clearance instead).  h is evaluated at every integrator grid point
  from the Hertz load and the entrainment speed and held over the step; since h falls with load
  as Q^-0.073, the contact is the film and Hertz springs in series, k = k_H k_oil / (k_H + k_oil)
  with k_oil = -dQ/dh = Q / (0.073 h) (eqs 14-16).
* Damping (eqs 14, 17-18): in the contact a structural part c_h = 2 zeta sqrt(m_b k_t) (k_t =
  1.5 K delta^0.5 the tangent stiffness, zeta = ``contact_damping_ratio``), and, with the film,
  the squeeze-film damping of the lubricant around the contact on approach, c_oil = dW/du =
  6 pi eta R_x R_y / (|delta| + h + roughness) (Reynolds' squeeze film of an ellipsoid on a
  plane, module ``film``; |delta| the gap, or the interference in contact: the damping is
  largest where a ball touches and falls as it is pressed in), in parallel (eq. 17's inlet
  term c_r; a series film damper as eq. 17 writes it would be short-circuited by the stiff
  film).  In a flooded groove it is of the order of the critical damping of the ball on its
  contact, so a ball leaving the load zone or meeting a race lands without rattling, as wet
  impacts at Stokes numbers near 1 do.  The contact force never pulls (Q >= 0).
* Traction (eqs 21-23): slip velocities of the ball surface against each race
      dv_i = rho theta' - (r_b - delta_i/2) Omega - (rho - e - r_b + delta_i/2) omega_s
      dv_o = rho theta' + (r_b - delta_o/2) Omega
  (rho - e - r_b: the inner-race radius at the contact, measured from the shaft centre, so the
  clearance, the shaft offset and a ball inside an inner-race pit all enter the kinematics; each
  body's rolling radius gives up half the contact deflection, where eq. 21 takes the whole inner
  deflection off the ball, 0.5 d - delta_in: 1.9 um of 3.97 mm at 200 N, 0.05 % of the spin)
  and f = -Q mu(dv) with mu(v) = sign(v) [(A + B|v|) exp(-C|v|) + D] the traction curve (eq. 23;
  NOT times the viscosity: eq. 24 is dimensionally wrong).  Its jump A + D at zero slip is
  regularised as (A + D) v / sqrt(v^2 + v_c^2) (``creep_velocity`` v_c); the rest is continuous.
* Ball-cage pocket (eqs 26-29): a spring k_c (``cage_stiffness``) on the arc R_m (theta - phi_c -
  2 pi j / Nb) beyond the pocket clearance, with a contact damping of ratio
  ``pocket_damping_ratio``; friction mu(r_b (Omega - theta')) |F_pocket| at the pocket face,
  radial on the ball with a torque on its spin.
* Lubricant drag (eq. 30, Harris' form in SI: eq. 30 as printed has d for d^2 and a stray g):
  F_v = c_v pi xi d^2 (D_m theta')^1.95 / 32 against the revolution.
* Centrifugal and Coriolis terms from the polar coordinates (eq. 31), gravity on balls and shaft,
  reactions of normal and traction forces on both races (eqs 20, 25, 33), cage rotation (eq. 35)
  with ``cage_drag`` (N m s) against its speed.  The ball's own inertia about its centre enters
  only the spin equation (Newton in polar coordinates; eq. 34's J_m = J_b + m r^2 mixes the two).

Outputs: sensor-mount acceleration (pedestal x; resonator y, else pedestal y) at the start of
every internal sample; ball loads, slip velocities and traction forces, cage speed and the skid
ratios (eqs 37-38) at every 4th:

    cage_skid = 100 (w_ct - w_c) / w_ct                 w_ct = omega_s (1 - gamma) / 2
    ball_skid = 100 mean_j (w_bt - w_bj) / w_bt          w_bt = omega_s D_m / (2 d) (1 - gamma^2)

with w_bj = theta'_j - Omega_j the spin of ball j in its orbital frame (the ball-spin frequency of
a defect on the ball), averaged over ALL balls (the paper plots one ball over time, i.e. through
loaded and unloaded zone).  The denominators are regularised as w_t / (w_t^2 + w_ref^2) with
w_ref = 0.01 rad/s so that a standing shaft gives 0 instead of a division by zero.

Solvers: see :mod:`.integrators`.  ``"rk4"``: classic RK4 at 1e-5 s (seed 000; it diverges on
this model: the squeeze film and the cage on its pocket springs need <= 3e-6 s); ``"reference"``:
RK4 at 1/32 of the internal sample spacing; ``"default"``: :class:`~.integrators.SplitROS2`, the
structure propagated exactly, balls and cage by ROS2 Rosenbrock-W with a block Jacobian of the
stiff per-ball couplings and the forcing's time column, one step per internal sample, event
sub-steps where a ball is inside a defect under a contact or a contact opens or closes.  Engines:
:func:`_engine` (explicit RK, whole-state Rosenbrock) and :func:`_engine_split`.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from numba import njit

from ..catalog import G
from ..errors import API_SETTINGS, SettingNames, UserError
from ..limits import RPM
from . import KinematicSnapshot, TierOutput
from .blas import single_threaded_blas
from .defects import (D_ANGLE, D_BALL, D_KIND, KIND_BALL, KIND_INNER, active_defect_table,
                      has_wandering_defect, interference_loss, interference_loss_slope, waviness_gain, waviness_table)
from .film import (FILM_EXP_Q, FILM_EXP_U, FILM_LOAD_FLOOR, film_coefficient,
                   squeeze_film_coefficient, structural_damping_coefficient)
from .integrators import EXPLICIT, SPLIT, check_rk4_step, method_for
from .structure import secant_stiffness, structure_system

# compile options of every kernel here: cached; FMA contraction (a * b + c may become one
# instruction: ~1e-16 relative, and the same compiled code gives the same bits, chunked or not);
# numpy's error model, where a division by zero gives inf or nan (the engines' finiteness checks
# report it as a divergence) instead of a test and branch at every division to raise
# ZeroDivisionError.  Together 10-16 % of the step (measured on the bench scenes).
KERNEL = dict(cache=True, fastmath={"contract"}, error_model="numpy")
# the kernels that run at every step also run without numba's runtime (NRT), whose reference
# counts on every array argument of a compiled call (and on many array assignments inside one) are
# atomic instructions, the hottest ones in a perf profile of the step: without them the healthy
# ER-16K step at two samples per step takes 1.70 instead of 2.98 us (AMD host), with bit for bit
# the same results.  Such a kernel cannot allocate: the model allocates each engine's work arrays
# once (:func:`split_work`, :func:`engine_work`) and passes them in.  (A compiled wrapper that
# allocated them per call made the first compilation 12 -> 17 s, presumably because LLVM inlined
# the whole engine into it and optimised it again.)
STEP_KERNEL = dict(KERNEL, _nrt=False)

NS0 = 12            # structure (10) + cage (2)
NBV = 6             # per-ball state entries
B_TH, B_R, B_PSI, B_W, B_V, B_OM = range(NBV)

# parameter vector layout
(P_NB, P_RB, P_RM, P_CR, P_KI, P_KO, P_MB, P_JB, P_MS, P_KS, P_CS, P_MP, P_KP, P_CP, P_MR, P_KR,
 P_CRS, P_HASRES, P_KC, P_CPK, P_CCD, P_JC, P_CDI, P_CDO, P_TA, P_TB, P_TC, P_TD, P_VC, P_DRAG,
 P_G, P_WS, P_RI, P_RO, P_HCI, P_HCO, P_FILM, P_QMIN, P_CAGER, P_SPINR, P_CDRAG, P_DM, P_SQI,
 P_SQO, P_ROUGH, NPAR) = range(46)

# per-ball auxiliary values from a right-hand-side evaluation (for the Jacobian; the contacts'
# deflections X_DI, X_DO, negative where open, for their films and the events).  X_PAD keeps a
# row a whole number of 16 bytes: with 27 columns the default's step took 10 % longer than
# with 26 or 28 (back-to-back timings on the bench scenes)
(X_KTI, X_KTO, X_CI, X_CO, X_QI, X_QO, X_MUI, X_MUO, X_DMUI, X_DMUO, X_FT, X_DMUP, X_CIN, X_DRAGD,
 X_MUP, X_SFT, X_SARC, X_C, X_S, X_DEDTH, X_DLI, X_DLO, X_LOSSI, X_LOSSO, X_DI, X_DO, X_PAD,
 NAUX) = range(28)
# per-ball diagnostics: contact loads (N), slip velocities (m/s), traction forces on the ball (N)
(D_QI, D_QO, D_SLI, D_SLO, D_FI, D_FO, NDG) = range(7)
# film table columns: film thickness inner / outer (m), drag factor (N s^2/rad^2), and the values
# at the last exact evaluation: film thicknesses (m), and the reciprocals of the entrainment
# speeds (s/m, 0: none yet), loads (1/N) and revolution speed (s/rad), so that the test against
# them at every step multiplies instead of divides
(F_HI, F_HO, F_DRAG, F_HI0, F_HO0, F_IUI0, F_IUO0, F_IQI0, F_IQO0, F_IW0, NFILM) = range(11)
# ramp: chunk start time, duration, speed 0/1, load 0/1 (x, y), shaft angle at chunk start
(R_T0, R_T, R_S0, R_S1, R_L0X, R_L0Y, R_L1X, R_L1Y, R_A0, NRAMP) = range(10)

W_REF = 0.01        # rad/s: regularises the skid-ratio denominators at standstill
DEFAULT_OVERSAMPLE = 2   # steps of the default solver per output sample (one per two internal
                         # samples): 0.05-0.4 % bench error at 1.2-1.8x the speed of 4; 1 is not
                         # within 1 % at 2000 N (README, "Speed against error")
# the most loaded ball's radial contact frequency (Hz, ``contact_frequency``) times the default's
# own step (s) above which the default was measured 0.3-50 % off its reference in RMS on small
# bearings (docs/solvers.md, "Small bearings: the default's step against its reference"); the
# shipped and bench scenes are at 1.16 at most (34.8 kHz at 15 kHz output), the custom bearings
# 0.3-1.2 % off at 1.20-1.21 and 1-50 % from 1.35 up.  Below it the default can be off too (up to
# 9 % at 1.11-1.15): no threshold of any candidate measured separated those from the shipped scenes.
# The step check below replaced the warning it gave at the start; it stays where the check does
# not run (a tier switch to the skidding tier)
STEP_CONTACT_LIMIT = 1.2
# the default's step check (``SkiddingModel``, docs/solvers.md "The default's step chosen by
# measuring", 2026-11-30): where the default runs at its own step and the contact frequency times
# that step exceeds STEP_CHECK_SCREEN, a throwaway copy of the model runs STEP_CHECK_SETTLE +
# STEP_CHECK_WINDOW s at 2, 4, 8 ... steps per output sample and the coarsest whose second-order
# (Richardson) estimate |RMS_M - RMS_2M| x 4/3 is within STEP_CHECK_TARGET of RMS_2M is taken.
# The screen is taken at the start state, where the shipped and bench scenes are at 1.044 at most
# (ER-16K under 2000 N, 31.3 kHz; b6205 0.93): they are not checked, so they keep their step and
# pay nothing; the 6-ball bearing at 710 N, 3-9 % off at x2, is at 1.09.  On the measured points
# the estimate followed the error against the reference (6000-size at 55 555 rpm / 4662 N: 3.6 %
# at x8 against -3.5 %, 0.9 % at x16 against -0.87 %); of the settles (0-20 ms) and windows (5-40
# ms) tried, 10 + 20 ms was among the shortest that left no checked point above 1 %
STEP_CHECK_SCREEN = 1.07
STEP_CHECK_TARGET = 0.005       # relative RMS error (0.5 %)
STEP_CHECK_MAX = 16             # the most steps per output sample the check takes (8x the default's cost)
STEP_CHECK_SETTLE = 0.01        # s run before the window (the start state's first transient)
STEP_CHECK_WINDOW = 0.02        # s over which the RMS is compared


# ---------------------------------------------------------------------------------------------
# force model
@njit(inline="always", **KERNEL)
def _traction(v, ta, tb, tc, td, vc):
    """Traction coefficient mu(v) (signed, odd in v) and its slope dmu/dv (s/m), eq. 23 with the
    jump A + D at zero slip regularised over ``vc``."""
    a = abs(v)
    x = tc * a
    if x < 0.0625:
        # exp(-x) by its Taylor series (the slips are small: x < 0.02 at most contacts on the
        # bench scenes), truncation below x^10 / 10! < 3e-19, within 1 ulp of math.exp: no libm
        # call, which also spills every live register (5-8 % of the default's step)
        ex = 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x * (
            1.0 / 720.0 - x * (1.0 / 5040.0 - x * (1.0 / 40320.0 - x * (1.0 / 362880.0)))))))))
    else:
        ex = math.exp(-x)
    g = (ta + tb * a) * ex - ta                   # continuous part, 0 at 0
    dg = tb * ex - tc * (ta + tb * a) * ex
    mu = g if v >= 0.0 else -g
    dmu = dg
    jump = ta + td
    if jump != 0.0:
        den = 1.0 / math.sqrt(v * v + vc * vc)
        mu += jump * v * den
        dmu += jump * vc * vc * den * den * den
    return mu, dmu


@njit(inline="always", **KERNEL)
def _inputs(ramp, t):
    """Shaft speed (rad/s), shaft angle (rad) and external load (N) at time t: linear ramp over
    the chunk, held before and after it."""
    t0 = ramp[R_T0]
    tt = ramp[R_T]
    s0 = ramp[R_S0]
    s1 = ramp[R_S1]
    tau = t - t0
    if tau <= 0.0:
        frac = 0.0
        ang = ramp[R_A0] + s0 * tau
    elif tau >= tt:
        frac = 1.0
        ang = ramp[R_A0] + 0.5 * (s0 + s1) * tt + s1 * (tau - tt)
    else:
        frac = tau / tt
        ang = ramp[R_A0] + s0 * tau + 0.5 * (s1 - s0) * tau * tau / tt
    ws = s0 + (s1 - s0) * frac
    fx = ramp[R_L0X] + (ramp[R_L1X] - ramp[R_L0X]) * frac
    fy = ramp[R_L0Y] + (ramp[R_L1Y] - ramp[R_L0Y]) * frac
    return ws, ang, fx, fy


@njit(**KERNEL)
def _defect_losses(dtab, y, p, sh_ang, scr):
    """Interference losses (m) of every ball from every defect: scr[:, 0] inner contact,
    scr[:, 1] outer contact, and their slopes along the ball angle (m/rad) scr[:, 3], scr[:, 4].
    Only the balls that can be inside a defect are evaluated (with
    ``defects.interference_loss_slope``): for a race defect the ball nearest to it and the two
    next to it (a defect is at most half a ball spacing wide and a ball stays within its pocket),
    for a ball defect that ball; so the cost is per defect, not per ball."""
    nb = int(p[P_NB])
    spacing = 2.0 * math.pi / nb
    for j in range(nb):
        scr[j, 0] = 0.0
        scr[j, 1] = 0.0
        scr[j, 2] = 0.0
        scr[j, 3] = 0.0
        scr[j, 4] = 0.0
    phic = y[10]
    for k in range(dtab.shape[0]):
        kind = int(dtab[k, D_KIND])
        if kind == KIND_BALL:
            scr[int(dtab[k, D_BALL]), 2] = 1.0
            continue
        centre = dtab[k, D_ANGLE] + (sh_ang if kind == KIND_INNER else 0.0)
        near = int(math.floor((centre - phic) / spacing + 0.5))
        for dj in range(-1, 2):
            scr[(near + dj) % nb, 2] = 1.0
    for j in range(nb):
        if scr[j, 2] > 0.0:
            b = NS0 + NBV * j
            th = y[b + B_TH]
            # with the slopes along the ball's angle (race defects; a ball defect turns with psi
            # instead): the pit's edges force the stiff radial mode, so the Jacobian needs them
            li, lo, dli, dlo = interference_loss_slope(dtab, j, th, sh_ang, y[b + B_PSI], p[P_RI],
                                                       p[P_RO], p[P_RB])
            scr[j, 0] = li
            scr[j, 1] = lo
            scr[j, 3] = dli
            scr[j, 4] = dlo


@njit(**STEP_KERNEL)
def _rhs(y, f, ws, sh_ang, fx_ext, fy_ext, p, dtab, wti, wto, film, aux, dg, scr, frc):
    """Time derivative ``f`` of the state ``y`` (see module docstring) at shaft speed ``ws``
    (rad/s), shaft angle ``sh_ang`` (rad) and external force (fx_ext, fy_ext) on the shaft (N).
    Fills ``aux`` (nb, NAUX: stiffnesses, loads, traction slopes for the Jacobian) and ``dg``
    (nb, NDG: loads, slips and traction forces) and ``frc`` (the balls' forces on the shaft, x and
    y, and on the pedestal, N); ``scr`` (nb, 3) is scratch."""
    nb = int(p[P_NB])
    rb = p[P_RB]
    rm = p[P_RM]
    half_cr = 0.5 * p[P_CR]
    ki = p[P_KI]
    ko = p[P_KO]
    mb = p[P_MB]
    jb = p[P_JB]
    kc = p[P_KC]
    cpk = p[P_CPK]
    ccd = p[P_CCD]
    cdi = p[P_CDI]
    cdo = p[P_CDO]
    ta = p[P_TA]
    tb = p[P_TB]
    tc = p[P_TC]
    td = p[P_TD]
    vc = p[P_VC]
    grav = p[P_G]
    sqz_i = p[P_SQI]
    sqz_o = p[P_SQO]
    rough = p[P_ROUGH]
    spacing = 2.0 * math.pi / nb
    imb = 1.0 / mb
    ijb = 1.0 / jb
    has_def = dtab.shape[0] > 0
    has_wi = wti.shape[0] > 0
    has_wo = wto.shape[0] > 0
    dx = y[0] - y[2]
    dy = y[1] - y[3]
    dvx = y[5] - y[7]
    dvy = y[6] - y[8]
    phic = y[10]
    wc = y[11]
    fsx = 0.0
    fsy = 0.0
    fpx = 0.0
    fpy = 0.0
    torque = 0.0
    if has_def:
        _defect_losses(dtab, y, p, sh_ang, scr)
    # cos/sin of each ball angle from the cage's (one cos/sin per call) and the ball's small
    # offset from its pocket centre (Taylor series, error < eps^6/720 for |eps| < 0.05 rad)
    cphi = math.cos(phic)
    sphi = math.sin(phic)
    for j in range(nb):
        b = NS0 + NBV * j
        th = y[b + B_TH]
        r = y[b + B_R]
        w = y[b + B_W]
        v = y[b + B_V]
        om = y[b + B_OM]
        cj = p[NPAR + j]
        sj = p[NPAR + nb + j]
        cb = cphi * cj - sphi * sj
        sb = sphi * cj + cphi * sj
        eps = th - phic - j * spacing
        if abs(eps) < 0.05:
            e2 = eps * eps
            ce = 1.0 - e2 * (0.5 - e2 * (1.0 / 24.0))
            se = eps * (1.0 - e2 * (1.0 / 6.0 - e2 * (1.0 / 120.0)))
        else:
            ce = math.cos(eps)
            se = math.sin(eps)
        c = cb * ce - sb * se
        s = sb * ce + cb * se
        e = dx * c + dy * s
        edot = dvx * c + dvy * s + w * (dy * c - dx * s)
        di = e + rm - half_cr - r + film[j, F_HI]
        do = r - rm - half_cr + film[j, F_HO]
        if has_def:
            di -= scr[j, 0]
            do -= scr[j, 1]
        if has_wi:
            di += waviness_gain(wti, th, sh_ang)
        if has_wo:
            do += waviness_gain(wto, th, sh_ang)
        # Hertz + structural damping in the contact, + squeeze-film damping of the lubricant
        # between ball and race on approach (in contact and across a small gap); never pulling
        qi = 0.0
        kti = 0.0
        ci = 0.0
        rate = edot - v                              # approach rate of ball and inner race
        if di > 0.0:
            sq = math.sqrt(di)
            kti = 1.5 * ki * sq
            ci = cdi * math.sqrt(sq)
            qi = ki * di * sq + ci * rate
        if sqz_i > 0.0 and (di > 0.0 or rate > 0.0):
            csq = sqz_i / (abs(di) + film[j, F_HI] + rough)
            qi += csq * rate
            ci += csq
        if qi <= 0.0:
            qi = 0.0
            kti = 0.0
            ci = 0.0
        qo = 0.0
        kto = 0.0
        co = 0.0
        if do > 0.0:
            sq = math.sqrt(do)
            kto = 1.5 * ko * sq
            co = cdo * math.sqrt(sq)
            qo = ko * do * sq + co * v
        if sqz_o > 0.0 and (do > 0.0 or v > 0.0):
            csq = sqz_o / (abs(do) + film[j, F_HO] + rough)
            qo += csq * v
            co += csq
        if qo <= 0.0:
            qo = 0.0
            kto = 0.0
            co = 0.0
        # traction at both races (force on the ball, along e_t)
        # rolling radii at the deformed contacts: each body takes half the deflection (seed 000
        # eq. 21 takes the whole inner deflection off the ball, 0.5 d - delta_in)
        hdi = 0.5 * di if di > 0.0 else 0.0
        hdo = 0.5 * do if do > 0.0 else 0.0
        sli = r * w - (rb - hdi) * om - (r - rb - e + hdi) * ws
        slo = r * w + (rb - hdo) * om
        mui = 0.0
        dmui = 0.0
        muo = 0.0
        dmuo = 0.0
        if qi > 0.0:
            mui, dmui = _traction(sli, ta, tb, tc, td, vc)
        if qo > 0.0:
            muo, dmuo = _traction(slo, ta, tb, tc, td, vc)
        fi = -qi * mui
        fo = -qo * muo
        # ball-cage pocket: tangential force on the ball, friction at the pocket face
        arc = rm * eps                 # angles are unwrapped: ball and cage stay together
        ft = 0.0
        cin = 0.0
        if arc > cpk:
            ft = -kc * (arc - cpk) - ccd * rm * (w - wc)
            cin = 1.0
            if ft > 0.0:
                ft = 0.0
                cin = 0.0
        elif arc < -cpk:
            ft = -kc * (arc + cpk) - ccd * rm * (w - wc)
            cin = 1.0
            if ft < 0.0:
                ft = 0.0
                cin = 0.0
        aft = abs(ft)
        mup = 0.0
        dmup = 0.0
        if aft > 0.0:
            mup, dmup = _traction(rb * (om - w), ta, tb, tc, td, vc)
        fric = aft * mup
        fr = fric if arc >= 0.0 else -fric        # radial on the ball
        # lubricant drag against the revolution (factor frozen over the step)
        fdrag = -film[j, F_DRAG] * w * abs(w)
        # equations of motion of the ball (polar coordinates about the outer-race centre)
        f[b + B_TH] = w
        f[b + B_R] = v
        f[b + B_PSI] = w - om
        ir = 1.0 / r
        f[b + B_W] = ((fi + fo + ft + fdrag) * imb - 2.0 * v * w - grav * c) * ir
        f[b + B_V] = r * w * w + (qi - qo + fr) * imb - grav * s
        f[b + B_OM] = ((rb - hdo) * fo - (rb - hdi) * fi - rb * fric) * ijb
        # reactions: on the shaft -Q_i e_r - f_i e_t, on the pedestal +Q_o e_r - f_o e_t
        fsx += -qi * c + fi * s
        fsy += -qi * s - fi * c
        fpx += qo * c + fo * s
        fpy += qo * s - fo * c
        torque -= ft * rm
        a = aux[j]
        a[X_KTI] = kti
        a[X_KTO] = kto
        a[X_CI] = ci
        a[X_CO] = co
        a[X_QI] = qi
        a[X_QO] = qo
        a[X_MUI] = mui
        a[X_MUO] = muo
        a[X_DMUI] = dmui
        a[X_DMUO] = dmuo
        a[X_FT] = aft
        a[X_DMUP] = dmup
        a[X_CIN] = cin
        a[X_DRAGD] = 2.0 * film[j, F_DRAG] * abs(w)
        a[X_MUP] = mup
        a[X_SFT] = 1.0 if ft > 0.0 else (-1.0 if ft < 0.0 else 0.0)
        a[X_SARC] = 1.0 if arc >= 0.0 else -1.0
        a[X_C] = c
        a[X_S] = s
        a[X_DEDTH] = dy * c - dx * s           # d e / d theta: the inner contact moves with the ball
        a[X_DLI] = scr[j, 3] if has_def else 0.0
        a[X_DLO] = scr[j, 4] if has_def else 0.0
        # a defect's loss where it changes a contact: one that would be closed without it (a pit
        # passing a ball that does not touch that race changes nothing, and is not an event);
        # and the contacts' deflections, negative where open (the films; the events: _step_event)
        a[X_LOSSI] = scr[j, 0] if has_def and di + scr[j, 0] > 0.0 else 0.0
        a[X_LOSSO] = scr[j, 1] if has_def and do + scr[j, 1] > 0.0 else 0.0
        a[X_DI] = di
        a[X_DO] = do
        a[X_PAD] = 0.0                # written, so that the table is the same in every run
        d = dg[j]
        d[D_QI] = qi
        d[D_QO] = qo
        d[D_SLI] = sli
        d[D_SLO] = slo
        d[D_FI] = fi
        d[D_FO] = fo
    # structure (seed 000 eq. 33) with the unit resonator on the pedestal's y
    for k in range(5):
        f[k] = y[5 + k]
    f[5] = (-p[P_KS] * y[0] - p[P_CS] * y[5] + fx_ext + fsx) / p[P_MS]
    f[6] = (-p[P_KS] * y[1] - p[P_CS] * y[6] + fy_ext - p[P_WS] + fsy) / p[P_MS]
    fres = 0.0
    if p[P_HASRES] > 0.0:
        fres = p[P_KR] * (y[4] - y[3]) + p[P_CRS] * (y[9] - y[8])
        f[9] = -fres / p[P_MR]
    else:
        f[9] = 0.0
    f[7] = (-p[P_KP] * y[2] - p[P_CP] * y[7] + fpx) / p[P_MP]
    f[8] = (-p[P_KP] * y[3] - p[P_CP] * y[8] + fpy + fres) / p[P_MP]
    f[10] = wc
    f[11] = (torque - p[P_CDRAG] * wc) / p[P_JC]
    frc[0] = fsx
    frc[1] = fsy
    frc[2] = fpx
    frc[3] = fpy


@njit(inline="always", **KERNEL)
def _entrainment(y, b, e, ws, rb):
    """Entrainment (mean surface) speeds (m/s) of the inner and outer contact of the ball at
    state offset b, relative to the moving contacts."""
    r = y[b + B_R]
    w = y[b + B_W]
    om = y[b + B_OM]
    ui = 0.5 * abs(-rb * (om - w) + (r - rb - e) * ws - (r - rb) * w)
    uo = 0.5 * abs(rb * (om - w) - (r + rb) * w)
    return ui, uo


@njit(inline="always", **KERNEL)
def _film_exact(p, coef, u, q):
    if p[P_FILM] <= 0.0 or u <= 1e-9:
        return 0.0
    return coef * math.exp(FILM_EXP_U * math.log(u) + FILM_EXP_Q * math.log(max(q, p[P_QMIN])))


@njit(inline="always", **KERNEL)
def _film_target(film, j, col_h0, col_u0, col_q0, p, coef, u, q):
    """One contact's Hamrock-Dowson film at entrainment speed u and load q: a second-order Taylor
    step of h ~ u^0.68 Q^-0.073 from the last exact value while u and Q stay within 2 % / 5 % of
    it, else exactly."""
    q = max(q, p[P_QMIN])
    iu0 = film[j, col_u0]
    if p[P_FILM] <= 0.0:
        return 0.0
    if iu0 > 0.0 and u > 1e-9:
        x = u * iu0 - 1.0
        z = q * film[j, col_q0] - 1.0
        if abs(x) < 0.02 and abs(z) < 0.05:
            return film[j, col_h0] * (1.0 + x * (FILM_EXP_U + 0.5 * FILM_EXP_U * (FILM_EXP_U - 1.0) * x)) \
                * (1.0 + z * (FILM_EXP_Q + 0.5 * FILM_EXP_Q * (FILM_EXP_Q - 1.0) * z))
    h = _film_exact(p, coef, u, q)
    film[j, col_h0] = h
    film[j, col_u0] = 1.0 / u if u > 1e-9 else 0.0
    film[j, col_q0] = 1.0 / q
    return h


@njit(inline="always", **KERNEL)
def _film_contact(film, j, col_h, col_h0, col_u0, col_q0, p, coef, k, u, d):
    """Update one contact's film thickness from its Hertz deflection d (m, 0 out of contact) and
    stiffness k (N/m^1.5): the film and the Hertz spring are in series and carry the Hertz load
    (the contact's dampers act in parallel and do not thin it).  The film is held over a step, and
    one that followed its load one step late would be a loop of gain 0.11 h / d, unstable where
    the ball begins to touch (d < 0.11 h); so it takes the Newton step of the fixed point
    h = h(Q(d + dh)), stable at any gain and the whole step where the gain is small."""
    h = film[j, col_h]
    q = k * d * math.sqrt(d)
    target = _film_target(film, j, col_h0, col_u0, col_q0, p, coef, u, q)
    if d > 0.0 and q > p[P_QMIN]:
        film[j, col_h] = h + (target - h) * d / (d - 1.5 * FILM_EXP_Q * h)
    else:
        film[j, col_h] = target


@njit(inline="always", **KERNEL)
def _drag_factor(film, j, p, w):
    """Drag factor F_v / (w |w|) at revolution speed w, refreshed when w moved by 2 %."""
    iw0 = film[j, F_IW0]
    if iw0 > 0.0 and abs(abs(w) * iw0 - 1.0) < 0.02:
        return
    aw = abs(w) if abs(w) > 1e-3 else 1e-3
    film[j, F_DRAG] = p[P_DRAG] * math.exp(1.95 * math.log(p[P_DM]) - 0.05 * math.log(aw))
    film[j, F_IW0] = 1.0 / aw


@njit(inline="always", **KERNEL)
def _film_update(y, ws, p, film, aux, from_aux):
    """Film thickness of every contact (Hamrock-Dowson, eq. 12) and drag factor of every ball at
    one grid point.  Hertz deflections from ``aux`` (the last right-hand-side evaluation, at the
    end of the step) if ``from_aux``, else from the geometry (with the current film)."""
    nb = int(p[P_NB])
    rb = p[P_RB]
    rm = p[P_RM]
    half_cr = 0.5 * p[P_CR]
    dx = y[0] - y[2]
    dy = y[1] - y[3]
    for j in range(nb):
        b = NS0 + NBV * j
        th = y[b + B_TH]
        r = y[b + B_R]
        _drag_factor(film, j, p, y[b + B_W])
        if from_aux:       # direction of the ball at the end of the step (the last evaluation)
            e = dx * aux[j, X_C] + dy * aux[j, X_S]
        else:
            e = dx * math.cos(th) + dy * math.sin(th)
        ui, uo = _entrainment(y, b, e, ws, rb)
        if from_aux:
            di = max(aux[j, X_DI], 0.0)
            do = max(aux[j, X_DO], 0.0)
        else:
            di = max(e + rm - half_cr - r + film[j, F_HI], 0.0)
            do = max(r - rm - half_cr + film[j, F_HO], 0.0)
            film[j, F_IUI0] = 0.0          # force exact values
            film[j, F_IUO0] = 0.0
        _film_contact(film, j, F_HI, F_HI0, F_IUI0, F_IQI0, p, p[P_HCI], p[P_KI], ui, di)
        _film_contact(film, j, F_HO, F_HO0, F_IUO0, F_IQO0, p, p[P_HCO], p[P_KO], uo, do)


@njit(inline="always", **KERNEL)
def _static_loads(p, y, j, sh_ang, dtab, wti, wto, film, r):
    """Hertz loads (N) of ball j at radius r at its inner and outer contact, with the film, the
    defects' interference losses and the waviness, the rest of ``y`` fixed and no damping; and
    the cos / sin of the ball's angle: the quasi-static contact law of the set-up."""
    b = NS0 + NBV * j
    th = y[b + B_TH]
    c = math.cos(th)
    s = math.sin(th)
    e = (y[0] - y[2]) * c + (y[1] - y[3]) * s
    di = e + p[P_RM] - 0.5 * p[P_CR] - r + film[j, F_HI]
    do = r - p[P_RM] - 0.5 * p[P_CR] + film[j, F_HO]
    if dtab.shape[0] > 0:
        li, lo = interference_loss(dtab, j, th, sh_ang, y[b + B_PSI], p[P_RI], p[P_RO], p[P_RB])
        di -= li
        do -= lo
    if wti.shape[0] > 0:
        di += waviness_gain(wti, th, sh_ang)
    if wto.shape[0] > 0:
        do += waviness_gain(wto, th, sh_ang)
    qi = p[P_KI] * di * math.sqrt(di) if di > 0.0 else 0.0
    qo = p[P_KO] * do * math.sqrt(do) if do > 0.0 else 0.0
    return qi, qo, c, s


@njit(**KERNEL)
def _ball_radial_force(p, y, j, sh_ang, dtab, wti, wto, film, r):
    """Quasi-static radial force (N, outward) on ball j at radius r with the rest of ``y`` fixed:
    Hertz (with film), centrifugal, gravity.  Decreasing in r."""
    qi, qo, _c, s = _static_loads(p, y, j, sh_ang, dtab, wti, wto, film, r)
    w = y[NS0 + NBV * j + B_W]
    return qi - qo + p[P_MB] * r * w * w - p[P_MB] * p[P_G] * s


@njit(**KERNEL)
def _settle_balls(p, y, sh_ang, dtab, wti, wto, film):
    """Put every ball at its quasi-static radius (bisection on the monotone radial force); a ball
    with no radial force at all (free in the clearance) goes to the middle of its free range."""
    nb = int(p[P_NB])
    span = abs(p[P_CR]) + abs(y[0] - y[2]) + abs(y[1] - y[3]) + 1e-4
    for j in range(nb):
        b = NS0 + NBV * j
        lo = p[P_RM] - span
        hi = p[P_RM] + span
        # bracket of the zero-force band: first root from below and from above
        a_lo, a_hi = lo, hi
        for _ in range(80):
            mid = 0.5 * (a_lo + a_hi)
            if _ball_radial_force(p, y, j, sh_ang, dtab, wti, wto, film, mid) > 0.0:
                a_lo = mid
            else:
                a_hi = mid
        b_lo, b_hi = lo, hi
        for _ in range(80):
            mid = 0.5 * (b_lo + b_hi)
            if _ball_radial_force(p, y, j, sh_ang, dtab, wti, wto, film, mid) >= 0.0:
                b_lo = mid
            else:
                b_hi = mid
        y[b + B_R] = 0.5 * (a_hi + b_lo)
        y[b + B_V] = 0.0


@njit(**KERNEL)
def _quasi_static_forces(p, y, sh_ang, dtab, wti, wto, film, out):
    """Settle the balls and return the bearing forces (N) on the shaft (out[0:2]) and on the
    pedestal (out[2:4]) without traction: the quasi-static load-deflection law."""
    nb = int(p[P_NB])
    _settle_balls(p, y, sh_ang, dtab, wti, wto, film)
    out[:] = 0.0
    for j in range(nb):
        qi, qo, c, s = _static_loads(p, y, j, sh_ang, dtab, wti, wto, film, y[NS0 + NBV * j + B_R])
        out[0] -= qi * c
        out[1] -= qi * s
        out[2] += qo * c
        out[3] += qo * s


# ---------------------------------------------------------------------------------------------
# Rosenbrock-W: the block Jacobian, factorised once per step, applied once per stage
# per-ball workspace: LU of the reduced 3x3 (no pivoting: the matrix is I plus h-scaled damping,
# stiffness and traction terms of the right signs, its pivots stay >= 1) with its pivots stored as
# reciprocals, the position couplings of the right-hand side and the cage column.  Divisions are
# written as products with reciprocals taken once (1 / m_b, 1 / (m_b rho), 1 / J_b, the pivots)
# throughout the step's kernels: numba keeps each "/" a hardware division (no fast-math), and
# those were 8-10 % of the default's step (bench scenes, AMD host; the results move by rounding)
(W_L10, W_L20, W_L21, W_IU00, W_U01, W_U02, W_IU11, W_U12, W_IU22, W_THTH, W_THR, W_THPH, W_RR,
 W_OMR, W_ZC0, W_ZC1, W_ZC2, W_COEF, W_DCTH, W_RTH, W_OMTH, W_RTHG, W_OMTHG, NW) = range(24)


@njit(inline="always", **KERNEL)
def _lu3_solve(wk, x0, x1, x2):
    """Solve with the stored LU (forward, then backward); returns the solution."""
    z1 = x1 - wk[W_L10] * x0
    z2 = x2 - wk[W_L20] * x0 - wk[W_L21] * z1
    s2 = z2 * wk[W_IU22]
    s1 = (z1 - wk[W_U12] * s2) * wk[W_IU11]
    s0 = (x0 - wk[W_U01] * s1 - wk[W_U02] * s2) * wk[W_IU00]
    return s0, s1, s2


@njit(inline="always", **KERNEL)
def _w_factor(y, aux, p, hg, ws, wsp, wcage):
    """Build and factorise W = I - hg J for the approximate Jacobian J of the stiff couplings.

    J keeps, per ball, the couplings of (theta, rho, psi, theta', rho', Omega) through contact
    stiffness and damping, traction slopes, pocket spring/damping/friction and drag, and the
    cage (phi_c, omega_c) tied to every ball by the pocket springs (an arrow matrix).  Position
    rows are eliminated (k_pos = r_pos + hg k_vel), which leaves a 3x3 system per ball and one
    scalar for the cage (its Schur complement, wcage[0]).  Structure rows: J = 0."""
    nb = int(p[P_NB])
    mb = p[P_MB]
    jb = p[P_JB]
    rb = p[P_RB]
    rm = p[P_RM]
    kc = p[P_KC]
    ccd = p[P_CCD]
    jc = p[P_JC]
    hg2 = hg * hg
    cage_diag = 1.0 + hg * p[P_CDRAG] / jc
    imb = 1.0 / mb
    ijb = 1.0 / jb
    ijc = 1.0 / jc
    for j in range(nb):
        b = NS0 + NBV * j
        a = aux[j]
        wk = wsp[j]
        r = y[b + B_R]
        w = y[b + B_W]
        imr = imb / r
        qi = a[X_QI]
        qo = a[X_QO]
        cin = a[X_CIN]
        tdi = qi * a[X_DMUI]
        tdo = qo * a[X_DMUO]
        # derivatives of theta'', rho'', Omega' (see _rhs)
        dth_th = -kc * rm * cin * imr
        dth_phic = -dth_th
        # the ball's angle moves its inner contact along the offset shaft (e = dx cos + dy sin):
        # a slow variable forcing the stiff radial mode, so it belongs in W like the time column
        # (and a race defect's depth changes with it: d delta_i = de - dloss_i, d delta_o = -dloss_o)
        tgi = a[X_MUI] * a[X_KTI] * (a[X_DEDTH] - a[X_DLI]) + qi * a[X_DMUI] * ws * a[X_DEDTH]
        tgo = a[X_MUO] * a[X_KTO] * a[X_DLO]                              # d f_o / d theta
        dth_th += (tgo - tgi) * imr
        dr_thg = (a[X_KTI] * (a[X_DEDTH] - a[X_DLI]) + a[X_KTO] * a[X_DLO]) * imb
        dom_thg = rb * (tgo + tgi) * ijb
        dth_r = (a[X_MUI] * a[X_KTI] - a[X_MUO] * a[X_KTO]) * imr
        dth_w = (-(tdi + tdo) * r - ccd * rm * cin - a[X_DRAGD]) * imr
        dth_v = (a[X_MUI] * a[X_CI] - a[X_MUO] * a[X_CO]) * imr
        dth_om = (tdi - tdo) * rb * imr
        dth_wc = ccd * rm * cin * imr
        dr_r = -(a[X_KTI] + a[X_KTO]) * imb + w * w
        dr_v = -(a[X_CI] + a[X_CO]) * imb
        dr_w = 2.0 * r * w
        pf = rb * rb * a[X_FT] * a[X_DMUP]
        # pocket friction: its normal force |F_pocket| follows the pocket spring and damper, and
        # the ball's spin inertia is tiny, so d(Omega')/d(theta) is among the stiffest couplings
        gsp = a[X_MUP] * a[X_SFT] * cin           # d fric / d F_pocket... times the sign of F_pocket
        dfr_th = -gsp * kc * rm                   # d fric / d theta (= - d fric / d phi_c)
        dfr_w = -gsp * ccd * rm                   # d fric / d theta' (= - d fric / d w_c)
        dom_w = (rb * r * (tdi - tdo) + pf - rb * dfr_w) * ijb
        dom_om = (-rb * rb * (tdi + tdo) - pf) * ijb
        dom_r = -rb * (a[X_MUO] * a[X_KTO] + a[X_MUI] * a[X_KTI]) * ijb
        dom_v = -rb * (a[X_MUO] * a[X_CO] + a[X_MUI] * a[X_CI]) * ijb
        dom_th = -rb * dfr_th * ijb
        dom_phic = -dom_th
        dom_wc = rb * dfr_w * ijb
        dr_th = a[X_SARC] * dfr_th * imb
        dr_phic = -dr_th
        dr_wc = -a[X_SARC] * dfr_w * imb
        dr_w += a[X_SARC] * dfr_w * imb
        # reduced matrix on (k_w, k_v, k_om): I - hg A_v - hg^2 A_x (positions paired)
        m00 = 1.0 - hg * dth_w - hg2 * dth_th
        m01 = -hg * dth_v - hg2 * dth_r
        m02 = -hg * dth_om
        m10 = -hg * dr_w - hg2 * (dr_th + dr_thg)
        m11 = 1.0 - hg * dr_v - hg2 * dr_r
        m12 = 0.0
        m20 = -hg * dom_w - hg2 * (dom_th + dom_thg)
        m21 = -hg * dom_v - hg2 * dom_r
        m22 = 1.0 - hg * dom_om
        iu00 = 1.0 / m00
        l10 = m10 * iu00
        l20 = m20 * iu00
        u11 = m11 - l10 * m01
        u12 = m12 - l10 * m02
        iu11 = 1.0 / u11
        l21 = (m21 - l20 * m01) * iu11
        u22 = m22 - l20 * m02 - l21 * u12
        wk[W_L10] = l10
        wk[W_L20] = l20
        wk[W_L21] = l21
        wk[W_IU00] = iu00
        wk[W_U01] = m01
        wk[W_U02] = m02
        wk[W_IU11] = iu11
        wk[W_U12] = u12
        wk[W_IU22] = 1.0 / u22
        wk[W_THTH] = dth_th
        wk[W_THR] = dth_r
        wk[W_THPH] = dth_phic
        wk[W_RR] = dr_r
        wk[W_OMR] = dom_r
        wk[W_RTH] = dr_th
        wk[W_OMTH] = dom_th
        wk[W_RTHG] = dr_thg
        wk[W_OMTHG] = dom_thg
        # the ball's response to the cage unknown k_wc (through phi_c = r_phic + hg k_wc, w_c)
        z0, z1, z2 = _lu3_solve(wk, -(hg * dth_wc + hg2 * dth_phic), -(hg * dr_wc + hg2 * dr_phic),
                                -(hg * dom_wc + hg2 * dom_phic))
        wk[W_ZC0] = z0
        wk[W_ZC1] = z1
        wk[W_ZC2] = z2
        # cage row: d a_c / d theta_j = kc rm^2 cin / jc, d a_c / d w_j = ccd rm^2 cin / jc
        dc_th = kc * rm * rm * cin * ijc
        dc_w = ccd * rm * rm * cin * ijc
        coef = hg * dc_w + hg2 * dc_th
        wk[W_COEF] = coef
        wk[W_DCTH] = dc_th
        cage_diag += coef + coef * z0
    wcage[0] = cage_diag


@njit(inline="always", **KERNEL)
def _w_apply(p, hg, wsp, wcage, rhs_vec, k):
    """k = W^-1 rhs_vec with the factors of :func:`_w_factor`."""
    nb = int(p[P_NB])
    for i in range(NS0 - 2):
        k[i] = rhs_vec[i]
    r_phic = rhs_vec[10]
    cage_rhs = rhs_vec[11]
    for j in range(nb):
        b = NS0 + NBV * j
        wk = wsp[j]
        r_th = rhs_vec[b + B_TH]
        r_r = rhs_vec[b + B_R]
        x0 = rhs_vec[b + B_W] + hg * (wk[W_THTH] * r_th + wk[W_THR] * r_r + wk[W_THPH] * r_phic)
        x1 = rhs_vec[b + B_V] + hg * (wk[W_RR] * r_r + wk[W_RTH] * (r_th - r_phic) + wk[W_RTHG] * r_th)
        x2 = rhs_vec[b + B_OM] + hg * (wk[W_OMR] * r_r + wk[W_OMTH] * (r_th - r_phic) + wk[W_OMTHG] * r_th)
        z0, z1, z2 = _lu3_solve(wk, x0, x1, x2)
        k[b + B_W] = z0
        k[b + B_V] = z1
        k[b + B_OM] = z2
        cage_rhs += hg * wk[W_DCTH] * (r_th - r_phic) + wk[W_COEF] * z0
    kwc = cage_rhs / wcage[0]
    k[11] = kwc
    k[10] = r_phic + hg * kwc
    for j in range(nb):
        b = NS0 + NBV * j
        wk = wsp[j]
        kw = k[b + B_W] - wk[W_ZC0] * kwc
        kv = k[b + B_V] - wk[W_ZC1] * kwc
        kom = k[b + B_OM] - wk[W_ZC2] * kwc
        k[b + B_W] = kw
        k[b + B_V] = kv
        k[b + B_OM] = kom
        k[b + B_TH] = rhs_vec[b + B_TH] + hg * kw
        k[b + B_R] = rhs_vec[b + B_R] + hg * kv
        k[b + B_PSI] = rhs_vec[b + B_PSI] + hg * (kw - kom)


# ---------------------------------------------------------------------------------------------
# the stepping engine
@njit(**STEP_KERNEL)
def _step(kind, ta_, tb_, tc_, tg_, gamma, y, fy, aux0, t, hstep, ramp, p, dtab, wti, wto, film,
          ynew, kst, ytmp, rtmp, auxs, dgs, wsp, wcage, scr, frc):
    """One step of ``hstep`` s from (t, y) with f(t, y) = fy given; result in ynew."""
    ns = tb_.shape[0]
    n = y.shape[0]
    if kind == EXPLICIT:
        for i in range(n):
            kst[0, i] = fy[i]
        for st in range(1, ns):
            for i in range(n):
                acc = y[i]
                for jj in range(st):
                    if ta_[st, jj] != 0.0:
                        acc += hstep * ta_[st, jj] * kst[jj, i]
                ytmp[i] = acc
            ws, ang, fx, fyy = _inputs(ramp, t + tc_[st] * hstep)
            _rhs(ytmp, kst[st], ws, ang, fx, fyy, p, dtab, wti, wto, film, auxs, dgs, scr, frc)
    else:
        hg = hstep * gamma
        ws0, _a0, _x0, _y0 = _inputs(ramp, t)
        _w_factor(y, aux0, p, hg, ws0, wsp, wcage)
        for st in range(ns):
            if st == 0:
                for i in range(n):
                    rtmp[i] = fy[i]
            else:
                for i in range(n):
                    acc = y[i]
                    for jj in range(st):
                        if ta_[st, jj] != 0.0:
                            acc += hstep * ta_[st, jj] * kst[jj, i]
                    ytmp[i] = acc
                ws, ang, fx, fyy = _inputs(ramp, t + tc_[st] * hstep)
                _rhs(ytmp, rtmp, ws, ang, fx, fyy, p, dtab, wti, wto, film, auxs, dgs, scr, frc)
                for jj in range(st):
                    if tg_[st, jj] != 0.0:
                        for i in range(n):
                            rtmp[i] += tg_[st, jj] * kst[jj, i]
            # W k = rtmp  (W = I - gamma h J, J from the step's first evaluation)
            _w_apply(p, hg, wsp, wcage, rtmp, kst[st])
    for i in range(n):
        acc = y[i]
        for st in range(ns):
            acc += hstep * tb_[st] * kst[st, i]
        ynew[i] = acc


@njit(**STEP_KERNEL)
def _record(i, m, y, fy, dg, ws, p, out_acc, out_qi, out_qo, out_cage, out_bs, out_cs,
            out_sli, out_slo, out_fi, out_fo):
    """Sensor-mount acceleration of sample i from the derivative fy; every m-th sample the
    cage, ball and contact values (see :func:`_record_diag`)."""
    out_acc[i, 0] = fy[7]
    out_acc[i, 1] = fy[9] if p[P_HASRES] > 0.0 else fy[8]
    _record_diag(i, m, y, dg, ws, p, out_qi, out_qo, out_cage, out_bs, out_cs, out_sli, out_slo,
                 out_fi, out_fo)


@njit(inline="always", **KERNEL)
def _record_diag(i, m, y, dg, ws, p, out_qi, out_qo, out_cage, out_bs, out_cs, out_sli, out_slo,
                 out_fi, out_fo):
    """Cage speed, skid ratios (eqs 37-38, regularised at standstill), contact loads, slips and
    traction forces, if i is a multiple of m."""
    nb = int(p[P_NB])
    if i % m == 0:
        o = i // m
        out_cage[o] = y[11]
        wct = p[P_CAGER] * ws
        out_cs[o] = 100.0 * (wct - y[11]) * wct / (wct * wct + W_REF * W_REF)
        wbt = p[P_SPINR] * ws
        acc = 0.0
        for j in range(nb):
            b = NS0 + NBV * j
            wb = y[b + B_W] - y[b + B_OM]
            acc += (wbt - wb)
            out_qi[o, j] = dg[j, D_QI]
            out_qo[o, j] = dg[j, D_QO]
            out_sli[o, j] = dg[j, D_SLI]
            out_slo[o, j] = dg[j, D_SLO]
            out_fi[o, j] = dg[j, D_FI]
            out_fo[o, j] = dg[j, D_FO]
        out_bs[o] = 100.0 * (acc / nb) * wbt / (wbt * wbt + W_REF * W_REF)


@njit(inline="always", **KERNEL)
def _copy1(dst, src):
    """dst[:] = src without numpy's overlap check, which may allocate (the engines' loops run
    without numba's runtime: ``STEP_KERNEL``)."""
    for q in range(dst.shape[0]):
        dst[q] = src[q]


@njit(inline="always", **KERNEL)
def _copy2(dst, src):
    """dst[:, :] = src, as :func:`_copy1`."""
    for r in range(dst.shape[0]):
        for q in range(dst.shape[1]):
            dst[r, q] = src[r, q]


def engine_work(nvar: int, nb: int, stages: int) -> tuple:
    """Work arrays of :func:`_engine` for a state of ``nvar`` entries, ``nb`` balls and a method
    of ``stages`` stages, allocated once per model (the engine runs without numba's runtime and
    cannot allocate); ``scr``, the one allocated with zeros (``ENGINE_WORK_ZEROED``), must be
    zero at each call."""
    e = np.empty
    return (e(nvar), e(nvar), e(nvar), e(nvar), e(nvar), e(nvar), e(nvar), e((stages, nvar)),
            e((nb, NAUX)), e((nb, NAUX)), e((nb, NAUX)), e((nb, NDG)), e((nb, NDG)), e((nb, NDG)),
            e((nb, NFILM)), e((nb, NW)), e(1), np.zeros((nb, 5)), e(4))


ENGINE_WORK_ZEROED = (17,)          # scr


@njit(**STEP_KERNEL)
def _engine(y, counters, n, m, hs, hstep, ramp, kind, ta_, tb_, tc_, tg_, gamma, p, dtab,
            wti, wto, film, out_acc, out_qi, out_qo, out_cage, out_bs, out_cs, out_sli,
            out_slo, out_fi, out_fo, fy, ynext, fnext, yint, fint, ytmp, rtmp, kst, aux0,
            auxn, auxs, dg0, dgn, dgs, filmn, wsp, wcage, scr, frc):
    """Advance ``n`` internal samples of spacing ``hs`` with fixed steps of ``hstep``.

    counters[0]: global step count k (the state y is at time k * hstep); counters[1]: global
    index of the first sample of this chunk (at time index * hs).  The step grid is global, so
    chunking does not change the steps; a step that straddles the end of the chunk is taken with
    the inputs held at their final values and recomputed by the next call.  Returns 0, or 1 if
    the state stopped being finite (with counters[2] = the sample where it happened).  Work
    arrays (fy ... frc): :func:`engine_work`.
    """
    nvar = y.shape[0]
    kstep = counters[0]
    i0 = counters[1]
    ty = kstep * hstep
    ws, ang, fx, fyy = _inputs(ramp, ty)
    _rhs(y, fy, ws, ang, fx, fyy, p, dtab, wti, wto, film, aux0, dg0, scr, frc)
    have_next = False
    eps = 1e-9 * hs
    for i in range(n):
        ts = (i0 + i) * hs
        # commit the steps that end at or before this sample
        while (kstep + 1) * hstep <= ts + eps:
            if not have_next:
                _step(kind, ta_, tb_, tc_, tg_, gamma, y, fy, aux0, ty, hstep, ramp, p, dtab, wti,
                      wto, film, ynext, kst, ytmp, rtmp, auxs, dgs, wsp, wcage, scr, frc)
                ws, ang, fx, fyy = _inputs(ramp, ty + hstep)
                _copy2(filmn, film)
                _film_update(ynext, ws, p, filmn, auxs, True)
                _rhs(ynext, fnext, ws, ang, fx, fyy, p, dtab, wti, wto, filmn, auxn, dgn, scr, frc)
            _copy1(y, ynext)
            _copy1(fy, fnext)
            _copy2(film, filmn)
            _copy2(aux0, auxn)
            _copy2(dg0, dgn)
            kstep += 1
            ty = kstep * hstep
            have_next = False
            if not np.isfinite(y[11]) or not np.isfinite(y[3]) or not np.isfinite(fy[8]):
                counters[0] = kstep
                counters[2] = i
                return 1
        ws, ang, fx, fyy = _inputs(ramp, ts)
        if ts - ty <= eps:
            _record(i, m, y, fy, dg0, ws, p, out_acc, out_qi, out_qo, out_cage, out_bs, out_cs,
                    out_sli, out_slo, out_fi, out_fo)
        else:
            if not have_next:
                _step(kind, ta_, tb_, tc_, tg_, gamma, y, fy, aux0, ty, hstep, ramp, p, dtab, wti,
                      wto, film, ynext, kst, ytmp, rtmp, auxs, dgs, wsp, wcage, scr, frc)
                ws1, ang1, fx1, fy1 = _inputs(ramp, ty + hstep)
                _copy2(filmn, film)
                _film_update(ynext, ws1, p, filmn, auxs, True)
                _rhs(ynext, fnext, ws1, ang1, fx1, fy1, p, dtab, wti, wto, filmn, auxn, dgn, scr, frc)
                have_next = True
            th = (ts - ty) / hstep
            h00 = (2.0 * th - 3.0) * th * th + 1.0
            h10 = ((th - 2.0) * th + 1.0) * th * hstep
            h01 = (3.0 - 2.0 * th) * th * th
            h11 = (th - 1.0) * th * th * hstep
            for k in range(nvar):
                yint[k] = h00 * y[k] + h10 * fy[k] + h01 * ynext[k] + h11 * fnext[k]
            _rhs(yint, fint, ws, ang, fx, fyy, p, dtab, wti, wto, film, auxs, dgs, scr, frc)
            _record(i, m, yint, fint, dgs, ws, p, out_acc, out_qi, out_qo, out_cage, out_bs, out_cs,
                    out_sli, out_slo, out_fi, out_fo)
    counters[0] = kstep
    counters[1] = i0 + n
    return 0


@njit(inline="always", **KERNEL)
def _inputs_split(frc, y, kb, fx, fy, wshaft, u):
    """Inputs of the linear structure: ball forces minus the linearised bearing force (which is
    inside the structure's matrix), plus the external load and the shaft weight on the shaft."""
    dx = y[0] - y[2]
    dy = y[1] - y[3]
    lx = kb[0, 0] * dx + kb[0, 1] * dy
    ly = kb[1, 0] * dx + kb[1, 1] * dy
    u[0] = frc[0] + lx + fx
    u[1] = frc[1] + ly + fy - wshaft
    u[2] = frc[2] - lx
    u[3] = frc[3] - ly


@njit(inline="always", **KERNEL)
def _forcing_increment(y, xpred, aux, p, ws, hstep, dlt):
    """h * df/dt of the balls over a step of ``hstep`` in which the structure moves from y[0:10]
    to xpred (and an inner-race defect turns with the shaft):
    the change of each ball's radial, revolution and spin acceleration when the shaft-pedestal
    offset and its rate change, linearised with the contact stiffness, damping and traction
    slope of ``aux``.  The structure is a time-dependent forcing of the (stiff) ball equations;
    a Rosenbrock method needs that term (autonomised: the Jacobian's time column), or it drops
    to first order on them and its lagging quasi-static ball damps the structure."""
    nb = int(p[P_NB])
    mb = p[P_MB]
    jb = p[P_JB]
    rb = p[P_RB]
    ddx = (xpred[0] - xpred[2]) - (y[0] - y[2])
    ddy = (xpred[1] - xpred[3]) - (y[1] - y[3])
    ddvx = (xpred[5] - xpred[7]) - (y[5] - y[7])
    ddvy = (xpred[6] - xpred[8]) - (y[6] - y[8])
    imb = 1.0 / mb
    rb_jb = rb / jb
    for k in range(dlt.shape[0]):
        dlt[k] = 0.0
    for j in range(nb):
        b = NS0 + NBV * j
        a = aux[j]
        c = a[X_C]
        s = a[X_S]
        de = ddx * c + ddy * s
        dedot = ddvx * c + ddvy * s
        # an inner-race defect turns with the shaft: its depth at the ball changes by
        # -ws h dloss_i/dtheta (the slope along theta holds only race defects)
        dq = a[X_KTI] * (de + ws * hstep * a[X_DLI]) + a[X_CI] * dedot
        dfi = -a[X_MUI] * dq - a[X_QI] * a[X_DMUI] * ws * de
        dlt[b + B_V] = dq * imb
        dlt[b + B_W] = dfi * imb / y[b + B_R]
        dlt[b + B_OM] = -rb_jb * dfi


NO_EVENT, CONTACT_EVENT, DEFECT_EVENT, START_EVENT = 0, 1, 2, 3
# steps of the split method done in event sub-steps whatever happens in them after the state is set
# (at set-up, or taken over from another tier; counters[4] counts them down).  Measured: the
# first step from the set-up state, done whole at two samples per step, left the cage for good
# 0.9 mrad behind the reference on the ER-16K inner-race scene (its speed ~0.04 % low over the
# 50-75 ms start-up transient; 3.3 mrad with 24 event sub-steps per sample), which shifted every
# later impact and was most of the bench's line and waveform error there; sub-stepped, 0.001 mrad
START_STEPS = 1
# a ball inside a defect whose contact stays open at both ends of a step by more than this many
# times its gap's change over the step moves freely in the pit, smoothly: not an event.  On seed
# 004's ball+outer scene (2 mm pits, 0.11-0.16 mm deep where the ball meets them, against at most
# ~25 um of Hertz deflection at 2000 N) the ball leaves the race at once and crosses most of each
# pit in free flight: with this rule its defect event steps fell from 24 to 16 % (8.5 % of its
# steps are now tried whole before they are sub-stepped, 3.4 % before) and the scene ran 1.2x
# faster, its line error 0.34 -> 0.42 %; the ER-16K 0.6 mm pits (9-14 um deep) kept their figures
# within 0.04 pp (inner race 0.53 -> 0.55 %, outer 0.15 -> 0.11 %; a margin of 1: 0.62 / 0.09 %,
# 4: 0.53 / 0.13 %, ball+outer 0.43 / 0.45 %; the bench's error metrics, a throwaway script)
OPEN_GAP_MARGIN = 2.0


@njit(inline="always", **KERNEL)
def _inside_defect(a, nb):
    """Whether a ball is inside a defect under a closed contact that the defect changes (see
    ``X_LOSSI`` in :func:`_rhs`), from the contact values ``a`` of one instant: a step that
    starts so is an event whatever happens in it."""
    for j in range(nb):
        if ((a[j, X_LOSSI] > 0.0 and a[j, X_DI] > 0.0)
                or (a[j, X_LOSSO] > 0.0 and a[j, X_DO] > 0.0)):
            return True
    return False


@njit(inline="always", **KERNEL)
def _defect_changes_contact(a0, a1, nb):
    """Whether, between two instants, a ball was inside a defect under a contact it changes (one
    that would be closed without it), unless that contact stayed open at both instants by more
    than ``OPEN_GAP_MARGIN`` times its gap's change between them."""
    for j in range(nb):
        for col_loss, col_d in ((X_LOSSI, X_DI), (X_LOSSO, X_DO)):
            if a0[j, col_loss] > 0.0 or a1[j, col_loss] > 0.0:
                gap0 = -a0[j, col_d]
                gap1 = -a1[j, col_d]
                if not min(gap0, gap1) > OPEN_GAP_MARGIN * abs(gap1 - gap0):
                    return True
    return False


@njit(inline="always", **KERNEL)
def _step_event(a0, a1, nb, has_def):
    """What a step went through, from the contact values at two of its points (its ends, or its
    start and its second stage's point): DEFECT_EVENT if a ball was inside a defect at either
    (:func:`_defect_changes_contact`; only if the scene has defects, ``has_def``); else
    CONTACT_EVENT if a ball-race or ball-pocket contact opened or closed; else NO_EVENT.
    Without pocket clearance the pocket spring stays engaged, but its force is clamped at zero
    where its damping outweighs it (a ball leaving the pocket face), and that kink counts too: a
    plain step of two samples across it, with the spring's stiffness in W, kicked the cage by
    0.1 rad/s for a step and left it 0.014 % slow for tens of milliseconds (ER-16K inner-race
    scene at 676 ms: 0.43 mrad behind the reference by 800 ms, 0.015 by 1 s with it an event;
    no measurable cost)."""
    if has_def and _defect_changes_contact(a0, a1, nb):
        return DEFECT_EVENT
    for j in range(nb):
        if ((a0[j, X_KTI] > 0.0) != (a1[j, X_KTI] > 0.0) or (a0[j, X_KTO] > 0.0) != (a1[j, X_KTO] > 0.0)
                or a0[j, X_CIN] != a1[j, X_CIN]):
            return CONTACT_EVENT
    return NO_EVENT


@njit(inline="always", **KERNEL)
def _tables_between(aux_from, dg_from, film_from, aux_to, dg_to, film_to):
    """Copy the per-ball tables (aux, dg, film) into the split engine's slots or out of them."""
    _copy2(aux_to, aux_from)
    _copy2(dg_to, dg_from)
    _copy2(film_to, film_from)


def split_work(nvar: int, nb: int, kk: int) -> tuple:
    """Work arrays of :func:`_engine_split` for a state of ``nvar`` entries, ``nb`` balls and
    ``kk`` internal samples per step, allocated once per model (the engine runs without numba's
    runtime and cannot allocate); ``scr`` and ``qa``, the ones allocated with zeros
    (``SPLIT_WORK_ZEROED``), must be zero at each call."""
    e = np.empty
    return (e(nvar), e(nvar), e(4), e(nvar), e(nvar), e((2, nvar)), e((2, nb, NAUX)),
            e((nb, NAUX)), e((2, nb, NDG)), e((nb, NDG)), e((2, nb, NFILM)), e((nb, NW)), e(1),
            np.zeros((nb, 5)), e(4), e(10), e(10), e(4), np.zeros(4), e(nvar), e(nvar), e(4),
            e((nb, NAUX)), e((nb, NFILM)), e((kk, 10)), e((kk, 4)), e(nvar), e(nvar), e(10),
            e((nb, NAUX)))


# scr; qa, the input's parabola coefficient in the step just taken (0: a ramp)
SPLIT_WORK_ZEROED = (13, 18)


@njit(**STEP_KERNEL)
def _engine_split(y, fy, un, up, aux0, dg0, film, counters, n, m, hs, kk, ramp, ta_, tg_,
                 tb_, gamma, p, dtab, wti, wto, phi_t, g0_t, g1_t, g2_t, phis, g0s, g1s, g2s,
                 phie_t, g0e_t, g1e_t, nsub, nball, cacc, dacc, kb, out_acc, out_qi, out_qo,
                 out_cage, out_bs, out_cs, out_sli, out_slo, out_fi, out_fo, ynext, fnext, unext,
                 ytmp, rtmp, kst, auxp, auxs, dgp, dgs, filmp, wsp, wcage, scr, frc, xpred, xs, uu,
                 qa, ycur, fcur, ucur, auxc, filmc, xsmp, usmp, ybl, fbl, xbl, auxbl):
    """Advance ``n`` internal samples with :class:`~.integrators.SplitROS2`, one step per ``kk``
    samples.  The state (y, its derivative fy, the structure input un, aux0, dg0, film) persists
    between calls, so chunking does not change the result; counters as in :func:`_engine`
    (counters[3] = 1 once fy/un are valid, 2 when ``up`` also holds the structure input one plain
    step before: see the quadratic hold below; counters[4]: steps still to be sub-stepped whatever
    happens in them, ``START_STEPS`` after the state was set).

    One step (see :class:`~.integrators.SplitROS2`):

        x* = Phi x_n + G0 u_n                      structure predictor (input held)
        ROS2 step of the balls/cage with the structure going linearly from x_n to x*
        u' = ball forces at (z_{n+1}, x*)
        x_{n+1} = x* + G1 (u' - u_n)               structure corrector (input ramped, plus the
                  + G2 (u' - 2 u_n + u_{n-1}) / 2  parabola's term in a plain step after one)

    Event-aware: if a ball is inside a defect under a contact it changes (and that contact did not
    stay well open: ``OPEN_GAP_MARGIN``), or a contact opened or closed, the step is redone as
    ``nsub`` sub-steps (propagators phie, g0e, g1e of one sub-step), and the structure state and
    input at the samples inside the step are kept (xsmp, usmp).  The step's and the sub-step's
    propagators come transposed (``phi_t`` = Phi^T ...).

    The step is written out here rather than in helper functions on purpose: a numba call cost
    about 18 ns per array argument (the array struct and, before the loop ran without numba's
    runtime, its reference count), and a step whose ~40 work arrays went down two call levels
    spent more time in calls than in physics.

    The per-ball tables (aux, dg, film) are double-buffered within a call: ``auxp[cur]`` holds the
    step's start and ``auxp[1 - cur]`` its end, and accepting a step flips ``cur`` instead of
    copying the end over the start (about 400 numbers per step: 1-7 % of a step, measured
    back to back on the bench scenes); the call copies aux0, dg0, film in at its start and the
    current slots out at its end.

    Work arrays (ynext ... auxbl): :func:`split_work`."""
    nvar = y.shape[0]
    nb = int(p[P_NB])
    has_def = dtab.shape[0] > 0          # the scene has defects: defect events are possible
    hstep = kk * hs
    kstep = counters[0]
    i0 = counters[1]
    if counters[3] == 0:
        ws, ang, fx, fyy = _inputs(ramp, kstep * kk * hs)
        _rhs(y, fy, ws, ang, fx, fyy, p, dtab, wti, wto, film, aux0, dg0, scr, frc)
        _inputs_split(frc, y, kb, fx, fyy, p[P_WS], un)
        counters[3] = 1
    # the per-ball tables into slot 0 of their pairs (see the docstring)
    _tables_between(aux0, dg0, film, auxp[0], dgp[0], filmp[0])
    cur = 0
    have_next = False
    substepped = False
    for i in range(n):
        gi = i0 + i
        while True:
            accept = (kstep + 1) * kk <= gi
            if not accept and gi == kstep * kk:
                break                        # a sample on the grid: no step needed
            if not have_next:
                # ---- one grid step from (t, y): first whole (at once in sub-steps if it starts
                # inside a defect under a closed contact), then redone if an event happened (see
                # the docstring); the result in ynext, fnext, unext and the end slots an, dn, fn
                t = kstep * hstep
                a0 = auxp[cur]          # the per-ball tables at the step's start ...
                f0 = filmp[cur]
                an = auxp[1 - cur]      # ... and at its end
                fn = filmp[1 - cur]
                dn = dgp[1 - cur]
                substepped = False
                nsteps = 1
                yc, fc, uc, ac, flc = y, fy, un, a0, f0
                ph, gz, gl = phi_t, g0_t, g1_t
                mball = nball
                # a step that starts with a ball inside a defect under a closed contact is a
                # defect event whatever its end: straight to the sub-steps (the whole step would
                # be thrown away)
                event = NO_EVENT
                if nsub > 1 and has_def and _inside_defect(a0, nb):
                    event = DEFECT_EVENT
                elif nsub > 1 and counters[4] > 0:
                    event = START_EVENT       # the first steps from a set state: see START_STEPS
                for _attempt in range(2):         # the step, and at most one redo
                    if event != NO_EVENT:
                        # redo the step (or do it at once) from the same start
                        for q in range(nvar):
                            ycur[q] = y[q]
                            fcur[q] = fy[q]
                        for q in range(4):
                            ucur[q] = un[q]
                        for jb_ in range(nb):
                            for q in range(NFILM):
                                filmc[jb_, q] = f0[jb_, q]
                        # nsub sub-steps, each with the Jacobian from its own start
                        substepped = True
                        nsteps = nsub
                        ph, gz, gl = phie_t, g0e_t, g1e_t
                        mball = 1
                        for jb_ in range(nb):
                            for q in range(NAUX):
                                auxc[jb_, q] = a0[jb_, q]
                        yc, fc, uc, ac, flc = ycur, fcur, ucur, auxc, filmc
                    hcur = hstep / nsteps
                    for sidx in range(nsteps):
                        tc = t + sidx * hcur
                        # structure predictor with the input held (column by column of the
                        # transposed propagators: the rows vectorise, 2-3 % of the step; each
                        # entry sums in the same order as row by row, so the same bits)
                        for r in range(10):
                            xpred[r] = 0.0
                        for c in range(10):
                            yv = yc[c]
                            for r in range(10):
                                xpred[r] += ph[c, r] * yv
                        for c in range(4):
                            uv = uc[c]
                            for r in range(10):
                                xpred[r] += gz[c, r] * uv
                        # ROS2 on balls and cage, the structure given (going linearly from x_n
                        # to x*), in mball sub-steps (multirate: the balls' stiff forced response
                        # converges at first order in their step where the forcing is rough)
                        hb = hcur / mball
                        hg = hb * gamma
                        if mball == 1:
                            # one ball step (the default) reads the step's start in place
                            # (copying the state and the aux table cost ~2 % of the step)
                            ball_y, ball_f, ball_aux = yc, fc, ac
                        else:
                            for q in range(nvar):
                                ybl[q] = yc[q]
                                fbl[q] = fc[q]
                            for jb_ in range(nb):
                                for q in range(NAUX):
                                    auxbl[jb_, q] = ac[jb_, q]
                            ball_y, ball_f, ball_aux = ybl, fbl, auxbl
                        for sb in range(mball):
                            for q in range(10):
                                xbl[q] = yc[q] + (sb + 1.0) / mball * (xpred[q] - yc[q])
                            ws0, _a0, _x0, _y0 = _inputs(ramp, tc + sb * hb)
                            _w_factor(ball_y, ball_aux, p, hg, ws0, wsp, wcage)
                            _forcing_increment(ball_y, xbl, ball_aux, p, ws0, hb, ytmp)
                            for q in range(nvar):
                                rtmp[q] = ball_f[q] + gamma * ytmp[q]
                                ytmp[q] = -gamma * ytmp[q]
                            _w_apply(p, hg, wsp, wcage, rtmp, kst[0])
                            for q in range(nvar):
                                rtmp[q] = ytmp[q]
                            for q in range(nvar):
                                ytmp[q] = ball_y[q] + hb * ta_[1, 0] * kst[0, q]
                            for q in range(10):
                                ytmp[q] = xbl[q]
                            ws, ang, fx, fyy = _inputs(ramp, tc + (sb + 1) * hb)
                            for q in range(nvar):
                                kst[1, q] = rtmp[q]
                            _rhs(ytmp, rtmp, ws, ang, fx, fyy, p, dtab, wti, wto, flc, auxs, dgs, scr, frc)
                            for q in range(nvar):
                                rtmp[q] += tg_[1, 0] * kst[0, q] + kst[1, q]
                            _w_apply(p, hg, wsp, wcage, rtmp, kst[1])
                            for q in range(nvar):
                                ynext[q] = ball_y[q] + hb * (tb_[0] * kst[0, q]
                                                             + tb_[1] * kst[1, q])
                            for q in range(10):
                                ynext[q] = xbl[q]
                            if sb < mball - 1:
                                _rhs(ynext, fbl, ws, ang, fx, fyy, p, dtab, wti, wto, flc, auxbl, dgs, scr,
                                     frc)
                                for q in range(nvar):
                                    ybl[q] = ynext[q]
                        for jb_ in range(nb):
                            for q in range(NFILM):
                                fn[jb_, q] = flc[jb_, q]
                        _film_update(ynext, ws, p, fn, auxs, True)
                        _rhs(ynext, fnext, ws, ang, fx, fyy, p, dtab, wti, wto, fn, an, dn, scr, frc)
                        _inputs_split(frc, ynext, kb, fx, fyy, p[P_WS], unext)
                        # structure corrector with the input ramped from u_n to u'; in a plain
                        # step after a plain step, on the parabola through u_{n-1}, u_n and u'
                        # (a ramp alone passes a force at frequency f with a relative error of
                        # about (pi f h)^2 / 3 - 6 % at the resonator's 4 kHz at two samples per step)
                        quad = nsteps == 1 and counters[3] == 2
                        for c in range(4):
                            qa[c] = 0.5 * (unext[c] - 2.0 * uc[c] + up[c]) if quad else 0.0
                        for r in range(10):
                            ynext[r] = xpred[r]
                        for c in range(4):
                            du = unext[c] - uc[c]
                            qc = qa[c]
                            for r in range(10):
                                ynext[r] += gl[c, r] * du + g2_t[c, r] * qc
                        if nsteps > 1:
                            for q in range(nvar):
                                ycur[q] = ynext[q]
                                fcur[q] = fnext[q]
                            for q in range(4):
                                ucur[q] = unext[q]
                            for jb_ in range(nb):
                                for q in range(NAUX):
                                    auxc[jb_, q] = an[jb_, q]
                                for q in range(NFILM):
                                    filmc[jb_, q] = fn[jb_, q]
                            done = sidx + 1
                            if done < nsteps and done % (nsteps // kk) == 0:
                                jj = done // (nsteps // kk)
                                for r in range(10):
                                    xsmp[jj, r] = ycur[r]
                                for c in range(4):
                                    usmp[jj, c] = ucur[c]
                    if event != NO_EVENT or nsub <= 1:
                        break
                    event = _step_event(a0, an, nb, has_def)
                    if event == NO_EVENT:
                        # a contact that closes and opens again inside the step shows at neither
                        # end but at the second stage's point (the step's end as the first stage
                        # predicts it): without this, two samples per step let undamped balls
                        # rattle (no EHL film, 600 rpm / 2000 N: RMS 0.06 -> up to 7.5 m/s^2)
                        event = _step_event(a0, auxs, nb, has_def)
                    if event == NO_EVENT:
                        break
                have_next = True
            if not accept:
                break
            for q in range(nvar):
                y[q] = ynext[q]
                fy[q] = fnext[q]
            for q in range(4):
                up[q] = un[q]
                un[q] = unext[q]
            # the next step's parabola needs this step's start and a smooth input over it
            counters[3] = 1 if substepped else 2
            if counters[4] > 0:
                counters[4] -= 1
            cur = 1 - cur                   # the end slots are the next step's start
            kstep += 1
            have_next = False
            if not np.isfinite(y[11]) or not np.isfinite(y[3]) or not np.isfinite(fy[8]):
                _tables_between(auxp[cur], dgp[cur], filmp[cur], aux0, dg0, film)
                counters[0] = kstep
                counters[2] = i
                return 1
        jj = gi - kstep * kk
        ws, ang, fx, fyy = _inputs(ramp, gi * hs)
        if jj == 0:
            for r in range(10):
                xs[r] = y[r]
            for c in range(4):
                uu[c] = un[c]
        else:
            fr = jj / kk
            if substepped:
                for r in range(10):
                    xs[r] = xsmp[jj, r]
                for c in range(4):
                    uu[c] = usmp[jj, c]
            else:
                # the sensor rows of the exact sub-step response (C Phi_j, C G0_j, C G1_j, C G2_j)
                for r in range(2):
                    acc = 0.0
                    for c in range(10):
                        acc += phis[jj, r, c] * y[c]
                    for c in range(4):
                        du = unext[c] - un[c]
                        acc += (g0s[jj, r, c] * un[c] + g1s[jj, r, c] * du + g2s[jj, r, c] * qa[c]
                                + dacc[r, c] * (un[c] + fr * du + (fr - 1.0) * fr * qa[c]))
                    out_acc[i, r] = acc
        if jj == 0 or substepped:
            for r in range(2):
                acc = 0.0
                for c in range(10):
                    acc += cacc[r, c] * xs[c]
                for c in range(4):
                    acc += dacc[r, c] * uu[c]
                out_acc[i, r] = acc
        # the cage, ball and contact values of the grid point at or before the sample (the
        # Simulator's chunks are multiples of 4 samples, so with kk | 4 it is the sample itself)
        _record_diag(i, m, y, dgp[cur], ws, p, out_qi, out_qo, out_cage, out_bs, out_cs, out_sli, out_slo,
                     out_fi, out_fo)
    _tables_between(auxp[cur], dgp[cur], filmp[cur], aux0, dg0, film)
    counters[0] = kstep
    counters[1] = i0 + n
    return 0


def propagators(A: np.ndarray, B: np.ndarray, h: float, tau: float | None = None):
    """(Phi, G0, G1, G2) over ``tau`` (default h) for x' = A x + B u with
    u = u0 + (u1 - u0) r + a (r^2 - r), r = s / h:
    x(tau) = Phi x0 + G0 u0 + G1 (u1 - u0) + G2 a (exact; augmented matrix exponential)."""
    from scipy.linalg import expm

    tau = h if tau is None else tau
    n, k = B.shape
    z = np.zeros((n + 3 * k, n + 3 * k))
    z[:n, :n] = A * tau
    z[:n, n:n + k] = B * tau
    z[n:n + k, n + k:n + 2 * k] = np.eye(k)
    z[n + k:n + 2 * k, n + 2 * k:] = np.eye(k)
    e = expm(z)
    # blocks: responses to the inputs 1, s / tau and (s / tau)^2 / 2
    g1 = e[:n, n + k:n + 2 * k] * (tau / h)
    g2 = 2.0 * e[:n, n + 2 * k:] * (tau / h) ** 2 - g1
    return (np.ascontiguousarray(e[:n, :n]), np.ascontiguousarray(e[:n, n:n + k]),
            np.ascontiguousarray(g1), np.ascontiguousarray(g2))


# ---------------------------------------------------------------------------------------------
def drag_coefficient(scene) -> float:
    """Harris' lubricant drag on one ball in SI, F_v = drag_coefficient * (D_m theta')^1.95 (N,
    D_m theta' in m/s): c_v pi xi d^2 / 32 (seed 000 eq. 30 with d^2 for d and without its
    stray g)."""
    b, lub = scene.bearing, scene.lubrication
    return lub.drag_coefficient * math.pi * lub.fluid_density * b.ball_diameter ** 2 / 32.0


def cage_inertia(scene) -> float:
    """Cage moment of inertia about the bearing axis (kg m^2): ``lubrication.cage_inertia`` if
    given, else a thin ring at the pitch radius of mass ``cage_mass`` (if given, else 0.3 x the
    ball set: pressed-steel cages of deep-groove bearings weigh a quarter to a third of their
    balls, e.g. SKF 6205: 9 balls of 2.05 g, cage about 6 g)."""
    lub = scene.lubrication
    b = scene.bearing
    if lub.cage_inertia > 0.0:
        return lub.cage_inertia
    mass = lub.cage_mass if lub.cage_mass > 0.0 else 0.3 * b.balls * b.ball_mass
    return mass * (0.5 * b.pitch_diameter) ** 2


def parameters(scene) -> np.ndarray:
    """The kernel's parameter vector for a scene (SI)."""
    b = scene.bearing
    st = scene.structure
    lub = scene.lubrication
    p = np.zeros(NPAR)
    ic, oc = b.inner_contact, b.outer_contact
    p[P_NB] = b.balls
    p[P_RB] = 0.5 * b.ball_diameter
    p[P_RM] = 0.5 * b.pitch_diameter
    p[P_DM] = b.pitch_diameter
    p[P_CR] = b.radial_clearance
    p[P_KI] = ic.stiffness
    p[P_KO] = oc.stiffness
    p[P_MB] = b.ball_mass
    p[P_JB] = b.ball_inertia
    p[P_MS], p[P_KS], p[P_CS] = st.shaft_mass, st.shaft_stiffness, st.shaft_damping
    p[P_MP], p[P_KP], p[P_CP] = st.pedestal_mass, st.pedestal_stiffness, st.pedestal_damping
    p[P_HASRES] = 1.0 if st.has_resonator else 0.0
    p[P_MR] = st.resonator_mass if st.has_resonator else 1.0
    p[P_KR], p[P_CRS] = (st.resonator_stiffness, st.resonator_damping) if st.has_resonator else (0.0, 0.0)
    p[P_KC] = lub.cage_stiffness
    p[P_CPK] = lub.cage_pocket_clearance
    p[P_CCD] = 2.0 * lub.pocket_damping_ratio * math.sqrt(lub.cage_stiffness * b.ball_mass)
    p[P_JC] = cage_inertia(scene)
    p[P_CDRAG] = lub.cage_drag
    p[P_CDI] = structural_damping_coefficient(ic, lub, b.ball_mass)
    p[P_CDO] = structural_damping_coefficient(oc, lub, b.ball_mass)
    p[P_TA], p[P_TB], p[P_TC], p[P_TD] = lub.traction_a, lub.traction_b, lub.traction_c, lub.traction_d
    p[P_VC] = lub.creep_velocity
    p[P_DRAG] = drag_coefficient(scene)    # the kernel multiplies by D_m^1.95 w^1.95
    p[P_G] = G if scene.gravity else 0.0
    p[P_WS] = st.shaft_mass * G if scene.gravity else 0.0
    p[P_RI] = 0.5 * b.inner_race_diameter
    p[P_RO] = 0.5 * b.outer_race_diameter
    e_eff = b.effective_modulus
    p[P_FILM] = 1.0 if lub.ehl_film else 0.0
    p[P_HCI] = film_coefficient(ic, lub, e_eff)
    p[P_HCO] = film_coefficient(oc, lub, e_eff)
    p[P_QMIN] = FILM_LOAD_FLOOR
    p[P_SQI] = squeeze_film_coefficient(ic, lub)      # Reynolds' squeeze film: module film
    p[P_SQO] = squeeze_film_coefficient(oc, lub)
    p[P_ROUGH] = lub.surface_roughness
    p[P_CAGER] = b.cage_speed(1.0)          # pure-rolling cage and ball-spin speeds per shaft rad/s
    p[P_SPINR] = b.ball_spin_speed(1.0)
    a = 2.0 * np.pi * np.arange(b.balls) / b.balls
    return np.concatenate([p, np.cos(a), np.sin(a)])       # pocket directions follow


class SolverDiverged(UserError, RuntimeError):
    """The skidding tier's solver met a state that is not finite: a scene, or a solver step,
    beyond what that solver integrates.  One line: the solver, the time of signal (s) where it
    happened, the operating point there (rad/s shown in rpm; N) and what to try.  ``worded``
    says it in a caller's own names for its settings (``errors.SettingNames``: the CLI's options,
    the node's parameters); the Python API raises it worded in its keyword arguments.  A
    UserError, so that a command says it in one line, and still the RuntimeError it was (up to
    2026-11-29: an "internal error" with a traceback in every command)."""

    def __init__(self, solver: str, t: float, shaft_speed: float, radial_load):
        self.solver = solver
        self.t = float(t)                       # s of signal
        self.shaft_speed = float(shaft_speed)   # rad/s
        self.radial_load = (float(radial_load[0]), float(radial_load[1]))   # N
        super().__init__(self.worded(API_SETTINGS))

    def __reduce__(self):
        # made again from its fields (a process pool pickles it; its args are the message)
        return (type(self), (self.solver, self.t, self.shaft_speed, self.radial_load))

    def operating_point(self) -> str:
        """Where it happened: time of signal, shaft speed and radial load."""
        x, y = self.radial_load
        return f"t = {self.t:.4g} s of signal ({self.shaft_speed / RPM:.6g} rpm, radial load [{x:.6g}, {y:.6g}] N)"

    def worded(self, settings: SettingNames) -> str:
        """The message in the names of ``settings``, with the advice it can follow."""
        say = settings.assign
        if self.solver == "reference":
            advice = [f"{say('solver', 'default')} (it takes the structure's motion exactly, however stiff)"]
        else:
            # a smaller step (oversample) did not help on the cases found (2026-11-29): the
            # reference's 0.5 us steps did
            advice = [f"{say('solver', 'reference')} (steps of 1/32 of a sample: slower)"]
        advice = [a for a in advice if "solver" in settings.keys] + [say("fidelity", "kinematic")]
        head = f"{say('solver', self.solver)}: " if "solver" in settings.keys else ""
        return (f"{head}the skidding tier's {self.solver} solver diverged at {self.operating_point()}: the "
                f"scene is beyond what it integrates; try {' or '.join(advice)}")


class RK4Diverged(SolverDiverged):
    """The fixed-step RK4 diverged: a user's choice of step, not an internal error.  ``step`` (s)
    and ``t`` (s) let a caller word the advice in its own names (the CLI's ``--rk4-step``)."""

    def __init__(self, step: float, t: float, shaft_speed: float, radial_load):
        self.step = step
        super().__init__("rk4", t, shaft_speed, radial_load)

    def __reduce__(self):
        return (type(self), (self.step, self.t, self.shaft_speed, self.radial_load))

    def worded(self, settings: SettingNames) -> str:
        step = settings.name("rk4_step")
        return (f"{step} = {self.step:g} s: the fixed-step RK4 diverged at {self.operating_point()} (step beyond "
                f"its stability limit for this load/speed); use a smaller {step} or "
                f"{settings.assign('solver', 'default')}")


def choose_step(rms_at, start: int, cap: int, axes) -> tuple:
    """The step check's rule (``SkiddingModel._check_step``) on its trials' results: ``rms_at(m)``
    the RMS (m/s^2, per axis x, y) of a trial at ``m`` steps per output sample, None where that
    trial diverged; ``axes`` the indices of the axes the sensor reads.  From ``start`` doubling up
    to ``cap``, the first M whose estimate |RMS_M - RMS_2M| x 4/3 (the error is second order in
    the step) is within ``STEP_CHECK_TARGET`` of RMS_2M on every axis read.  An axis below 1 % of
    the other's RMS is left out (a relative change of a signal at rounding level says nothing of
    the step).  A diverged trial gives no estimate: M and M/2 count as off (infinite), since a
    finer step may not diverge.  Returns (M or None where none up to ``cap`` is, {M: estimate},
    the steps per sample whose trials diverged)."""
    diverged = []

    def trial(m: int):
        r = rms_at(m)
        if r is None:
            diverged.append(m)
        return r

    def estimate(r, r2) -> float:
        if r is None or r2 is None:
            return math.inf
        on = [a for a in axes if r2[a] >= 0.01 * r2.max()] or axes
        return float(np.max(np.abs(r - r2)[on] / np.maximum(r2[on], 1e-30))) * 4.0 / 3.0

    estimates = {}
    m, r = start, trial(start)
    while m <= cap:
        r2 = trial(2 * m)
        estimates[m] = estimate(r, r2)
        if estimates[m] <= STEP_CHECK_TARGET:
            return m, estimates, diverged
        m, r = 2 * m, r2
    return None, estimates, diverged


def step_check_warning(estimates: dict, diverged: list, chosen: int, cap: int) -> str:
    """The line the step check leaves where no step up to ``cap`` met its target and the run takes
    ``chosen`` (``choose_step``'s ``estimates`` and ``diverged``): the estimate at the finest step
    tried where it is finite, the steps whose trials diverged (a diverged trial has no estimate:
    it was printed "nan %"), and what a user can do."""
    at = max(estimates)
    est = estimates[at]
    said = [f"estimated {est:.2%} off at oversample {at}"] if math.isfinite(est) else []
    if diverged:
        said.append(f"its trials at oversample {', '.join(map(str, diverged))} diverged within "
                    f"{(STEP_CHECK_SETTLE + STEP_CHECK_WINDOW) * 1e3:g} ms"
                    + (", so the run may" if chosen in diverged else ""))
    return (f"skidding tier: the default solver's step check found no step within {STEP_CHECK_TARGET:.1%} "
            f"up to {cap} steps per sample ({'; '.join(said)}; it runs at {chosen})" + (
                f": fidelity auto takes at most {cap} (a tier switch shares the sensor chain's rate); "
                f"fidelity skidding lets the check go up to {STEP_CHECK_MAX}" if cap < STEP_CHECK_MAX else
                f": oversample {2 * STEP_CHECK_MAX} halves the step again, at {STEP_CHECK_MAX} times the "
                f"default's own cost") + " (docs/solvers.md)")


class SkiddingModel:
    """The skidding tier (see module docstring).  ``internal_rate`` = 4 x the output rate (Hz)."""

    name = "skidding"
    decimation = 4

    def __init__(self, scene, sample_rate: float, seed: int, shaft_speed: float, radial_load,
                 solver: str = "default", rk4_step: float | None = None, method=None,
                 oversample: int | None = None, defect_sizes=None, ellipse_ball_load=None,
                 takes_over_from=None, step_check: int | None = None):
        """``oversample``: steps of the ``"default"`` solver per output sample (default
        ``DEFAULT_OVERSAMPLE``, one step per two internal samples; 1 takes one every 4 internal
        samples, 4 one per internal sample, a multiple of 4 several; the samples between grid
        points come from the structure's exact response).  ``method``: an
        :class:`~.integrators.Method` instance overriding ``solver`` (for studies of step size
        and method; the Simulator does not use it).  ``defect_sizes``: one factor (0-1) per scene
        defect, None = all at full size (``set_defect_sizes``).  ``ellipse_ball_load`` (N): the
        ball load that sizes a wandering ball defect's contact ellipse; None = this tier's most
        loaded ball at the set-up (a tier switch passes the old tier's on).  ``takes_over_from``:
        the model of the tier this one takes over from at a switch (``adopt_state``; its
        ``ellipse_ball_load`` where none is given).  ``step_check``: the most steps per output
        sample the default's step check may choose where ``oversample`` is None (``_check_step``;
        None: no check, the default's own step; the Simulator passes ``STEP_CHECK_MAX``, or its
        ``AUTO_OVERSAMPLE_MAX`` where fidelity auto may switch tiers)."""
        self.scene = scene
        self.seed = int(seed)
        self.sample_rate = float(sample_rate)
        # s of signal at this model's first sample (the Simulator's: a tier switch starts a model
        # mid-run), so that a divergence is told at the signal's time, not the model's own
        self.start_time = 0.0
        self.internal_rate = self.sample_rate * self.decimation
        self.hs = 1.0 / self.internal_rate
        check_rk4_step(rk4_step)
        self.solver = solver
        self.rk4_step = rk4_step
        given = int(oversample or DEFAULT_OVERSAMPLE)
        if not (given in (1, 2) or given % 4 == 0):
            raise UserError(f"oversample = {oversample!r}: allowed values are 1, 2 or a multiple of 4")
        self._set_step(given, method)
        b = scene.bearing
        self.nb = b.balls
        self.p = parameters(scene)
        self.defect_sizes = None if defect_sizes is None else tuple(defect_sizes)
        # a wandering ball defect draws its latitudes from the run's seed, as in the kinematic tier;
        # its contact ellipse is sized below, once the static ball loads are known
        if ellipse_ball_load is None and takes_over_from is not None:
            ellipse_ball_load = takes_over_from.ellipse_ball_load
        self.ellipse_ball_load = None if ellipse_ball_load is None else float(ellipse_ball_load)
        self.dtab = active_defect_table(scene.defects, self.defect_sizes, b, seed=self.seed,
                                        ball_load=self.ellipse_ball_load)
        wt = waviness_table(scene.waviness)
        self.wti = np.ascontiguousarray(wt[wt[:, 0] == 0]) if wt.size else np.zeros((0, 4))
        self.wto = np.ascontiguousarray(wt[wt[:, 0] == 1]) if wt.size else np.zeros((0, 4))
        self.y = np.zeros(NS0 + NBV * self.nb)
        self.film = np.zeros((self.nb, NFILM))
        self._work = None         # the engine's work arrays, allocated at the first advance
        self._aux = np.zeros((self.nb, NAUX))
        self.counters = np.zeros(5, dtype=np.int64)
        self.counters[4] = START_STEPS
        self.shaft_angle = 0.0
        self._held = None        # (t_ref s, shaft angle rad, speed, load x, y): inputs held since t_ref
        self._speed = float(shaft_speed)
        nvar = self.y.size
        # persistent state of the split method (derivative, structure input, contact values)
        self._fy = np.zeros(nvar)
        self._un = np.zeros(4)
        self._up = np.zeros(4)           # the structure input one step before (quadratic hold)
        self._aux0 = np.zeros((self.nb, NAUX))
        self._dg0 = np.zeros((self.nb, NDG))
        load = np.asarray(radial_load, dtype=float)
        if takes_over_from is not None:
            # a tier switch: the state is the old tier's, so no static equilibrium is searched
            # for (two thirds of the set-up: 20-28 ms of a 150-sample switch batch, 7-8 ms
            # without, which the live node spends while batches are due) and the bearing is
            # linearised where the shaft is, as it is when the load moves at run time
            self.adopt_state(takes_over_from)
        else:
            self._equilibrium(load, float(shaft_speed))
        if self.ellipse_ball_load is None:
            # as the kinematic tier does: the most loaded ball's static load, defects left out
            self.ellipse_ball_load = self._most_loaded_ball_load()
            if has_wandering_defect(self.dtab):
                self.dtab = active_defect_table(scene.defects, self.defect_sizes, b, seed=self.seed,
                                                ball_load=self.ellipse_ball_load)
                self._settle(float(shaft_speed))
        self._lin_load = None
        if self.method.kind == SPLIT:
            self._linearise(load)
        # the default at its own step on a bearing where that step may be long: it measures the
        # step it needs (``_check_step``); one line for the Simulator to warn with where the check
        # could not bring it within its target, or did not run (a tier switch: no time for it)
        self.step_warning = ""
        self.step_estimates = {}     # steps per output sample -> the check's error estimate
        self.step_screen = None      # contact frequency x the default's own step at the start
        if oversample is None and method is None and solver == "default":
            fc = self.contact_frequency()
            self.step_screen = fc * self.hstep
            if step_check and self.step_screen > STEP_CHECK_SCREEN:
                self._check_step(int(step_check), load, float(shaft_speed))
            elif self.step_screen > STEP_CONTACT_LIMIT:
                self.step_warning = (
                    f"skidding tier: the default solver's own step ({self.hstep * 1e6:.3g} us) is long for this "
                    f"bearing (its most loaded ball's contact frequency {fc / 1e3:.3g} kHz, above "
                    f"{STEP_CONTACT_LIMIT / self.hstep / 1e3:.3g} kHz) and was not checked (a tier switch): on "
                    f"such bearings it was measured 0.3-50 % off its reference in RMS; fidelity skidding lets "
                    f"the default choose its step up to oversample {STEP_CHECK_MAX} (docs/solvers.md)")

    def _set_step(self, oversample: int, method=None):
        """``oversample`` steps of the default solver per output sample (or ``method``'s step):
        the method, its step (s), the grid, and the structure's propagators for that step."""
        self.oversample = int(oversample)
        self.method = method if method is not None else method_for(
            self.solver, self.rk4_step, default_per_sample=self.oversample / self.decimation)
        self.hstep = self.method.step(self.hs)
        # the split method works on a grid of samples: with several steps per sample it runs on a
        # finer grid (q points per internal sample) and keeps every q-th
        self.q = 1
        if self.method.kind == SPLIT and self.hstep < self.hs * (1.0 - 1e-9):
            self.q = int(round(self.hs / self.hstep))
            self.hstep = self.hs / self.q
        self._tableau = self.method.arrays()
        self._work = None
        if getattr(self, "_lin_load", None) is not None and self.method.kind == SPLIT:
            self._linearise(self._lin_load)

    def _check_step(self, cap: int, load: np.ndarray, speed: float):
        """Choose the default's steps per output sample by measuring, as ODE codes choose their
        first step: throwaway copies of this model (its start state, inputs held; of the bearing
        without its defects where it has any, below) run
        ``STEP_CHECK_SETTLE`` + ``STEP_CHECK_WINDOW`` s at 2, 4, ... steps per sample up to
        ``cap``; the coarsest M whose estimate |RMS_M - RMS_2M| x 4/3 (the error is second order
        in the step) is within ``STEP_CHECK_TARGET`` of RMS_2M is taken (RMS of the pedestal's
        acceleration, m/s^2, on each axis the sensor reads; ``choose_step``).  At the cap without
        that, the cap is taken and ``step_warning`` says so (``step_check_warning``).  The model
        itself has not moved: it then runs as if built with ``oversample`` M (the same samples).
        The trials run on the bearing without its defects, from its own equilibrium: the step is
        the contacts' need, and a defect's impacts are sub-stepped alike at every M (event
        sub-steps per internal sample).  A trial that diverges counts as off (a finer step may
        not), and ``step_warning`` names the steps whose trials diverged."""
        import copy
        from dataclasses import replace

        n = int(round((STEP_CHECK_SETTLE + STEP_CHECK_WINDOW) * self.internal_rate))
        skip = int(round(STEP_CHECK_SETTLE * self.internal_rate))
        base = self
        if self.dtab.shape[0]:
            # with its defects the trials' 30 ms read the start's impacts, not the step: a 2 x 1
            # mm rectangular outer pit on the 6000-size at 13 888 rpm / 4662 N was estimated 48 %
            # off at x2 and 200 % at x4, and went to the cap (8x the cost) with a warning, where x2
            # is within 0.2 % of the reference over 0.2 s (and the bearing alone takes x8)
            base = SkiddingModel(replace(self.scene, defects=()), self.sample_rate, self.seed, speed, load,
                                 solver=self.solver, rk4_step=self.rk4_step)
        memo = {id(base.scene): base.scene}

        def rms(m: int) -> np.ndarray | None:
            trial = copy.deepcopy(base, dict(memo))
            trial._set_step(m)
            try:
                acc = trial.advance(n, speed, speed, load, load).accel[skip:]
            except SolverDiverged:
                return None
            return np.sqrt(np.mean(acc ** 2, axis=0))

        # the axes the sensor reads, each on its own: over both at once the horizontal axis (5-20
        # times the vertical's RMS on the measured points) hid the vertical's error (0.09 %
        # estimated at x2 where it is 12 %)
        axes = [("x", "y").index(a) for a in self.scene.sensor.axes]
        found, self.step_estimates, diverged = choose_step(rms, DEFAULT_OVERSAMPLE, cap, axes)
        chosen = found if found is not None else cap
        if chosen != self.oversample:
            self._set_step(chosen)
        if found is None:
            self.step_warning = step_check_warning(self.step_estimates, diverged, chosen, cap)

    def contact_frequency(self) -> float:
        """The most loaded ball's radial contact frequency (Hz) in the present state: its inner and
        outer Hertz contacts' tangent stiffnesses (1.5 K^(2/3) Q^(1/3), both at the inner contact's
        load Q) in series against the ball's mass (kg).  The stiffer the contacts against the
        balls' mass, the further the default's step was off its reference
        (``STEP_CONTACT_LIMIT``)."""
        b = self.scene.bearing
        q = max(self._most_loaded_ball_load(), 1e-3)
        k = 1.0 / sum(1.0 / (1.5 * c.stiffness ** (2.0 / 3.0) * q ** (1.0 / 3.0))
                      for c in (b.inner_contact, b.outer_contact))
        return math.sqrt(k / b.ball_mass) / (2.0 * math.pi)

    def set_defect_sizes(self, sizes) -> None:
        """Take the scene's defects at ``sizes`` (one factor 0-1 each) from the next step on: a
        defect that appears or grows (``physics.defects.DefectSchedule``)."""
        self.defect_sizes = tuple(sizes)
        self.dtab = active_defect_table(self.scene.defects, self.defect_sizes, self.scene.bearing,
                                        seed=self.seed, ball_load=self.ellipse_ball_load)
        # the split method keeps the contact values and the structure input of the step's start,
        # which the defects change: evaluate them again
        self.counters[3] = 0

    # ---- split method: linear structure ----------------------------------------------------------
    def _mean_pedestal_force(self, d: np.ndarray) -> np.ndarray:
        """Quasi-static force of the balls on the pedestal (N) for a shaft-pedestal offset d (m),
        averaged over one ball spacing of cage angle (no defects): the load-deflection law."""
        y = self.y.copy()
        y[0:2] = d
        y[2:4] = 0.0
        out = np.zeros(4)
        tot = np.zeros(2)
        cages = np.linspace(0.0, 2.0 * np.pi / self.nb, 8, endpoint=False)
        empty = np.zeros((0, self.dtab.shape[1]))
        for c in cages:
            y[10] = c
            y[NS0 + B_TH::NBV][: self.nb] = c + 2.0 * np.pi * np.arange(self.nb) / self.nb
            _quasi_static_forces(self.p, y, 0.0, empty, np.zeros((0, 4)), np.zeros((0, 4)), self.film, out)
            tot += out[2:4]
        return tot / cages.size

    def _linearise(self, load: np.ndarray):
        """Bearing stiffness at the current shaft-pedestal offset (secant over +-0.2 um) and the
        structure's propagators for the step and every sample inside it."""
        with single_threaded_blas():
            self._linearise_on_one_thread(load)

    def _linearise_on_one_thread(self, load: np.ndarray):
        d0 = self.y[0:2] - self.y[2:4]
        self.kb = np.ascontiguousarray(secant_stiffness(self._mean_pedestal_force, d0))
        A, B, self.cacc, self.dacc = structure_system(self.scene, self.kb)
        hs = self.hs / self.q
        kk = int(round(self.hstep / hs))
        self.kk = kk
        self.phi, self.g0, self.g1, self.g2 = propagators(A, B, self.hstep)
        # sensor rows of the sub-step propagators: accel(j hs) = C Phi_j x + C G0_j u0 + C G1_j du + D u
        self.phis = np.zeros((kk, 2, 10))
        self.g0s = np.zeros((kk, 2, 4))
        self.g1s = np.zeros((kk, 2, 4))
        self.g2s = np.zeros((kk, 2, 4))
        self.phis[0] = self.cacc
        for j in range(1, kk):
            ph, gg0, gg1, gg2 = propagators(A, B, self.hstep, j * hs)
            self.phis[j], self.g0s[j], self.g1s[j] = self.cacc @ ph, self.cacc @ gg0, self.cacc @ gg1
            self.g2s[j] = self.cacc @ gg2
        self.nball = max(1, int(getattr(self.method, "ball_substeps", 1)))
        # event sub-steps are per internal sample: a step of kk samples with an event is redone in
        # kk times as many, so that the sub-step, which sets the error of a defect's impacts, is
        # the same at every oversample (at two samples per step, 6 sub-steps per step left the
        # ER-16K inner-race line 1.37 % off, 12 leave 0.13 %)
        self.nsub = int(getattr(self.method, "event_substeps", 1))
        if self.nsub > 1:
            self.nsub = self.nsub * kk
            self.phie, self.g0e, self.g1e, _g2e = propagators(A, B, self.hstep / self.nsub)
        else:
            self.phie, self.g0e, self.g1e = self.phi, self.g0, self.g1
        # the engine takes the step's and the event sub-step's propagators transposed
        self._step_prop_t = tuple(np.ascontiguousarray(a.T)
                                  for a in (self.phi, self.g0, self.g1, self.g2))
        self._event_prop_t = tuple(np.ascontiguousarray(a.T)
                                   for a in (self.phie, self.g0e, self.g1e))
        self._lin_load = load.copy()
        self.counters[3] = 0            # the structure input depends on kb: re-evaluate

    def _needs_relinearising(self, load: np.ndarray) -> bool:
        ref = self._lin_load
        scale = max(float(np.linalg.norm(ref)), 10.0)
        return float(np.linalg.norm(load - ref)) > 0.2 * scale

    # ---- state ---------------------------------------------------------------------------------
    @property
    def x(self) -> np.ndarray:
        """Structure state [xs, ys, xp, yp, yr, vxs, vys, vxp, vyp, vyr] (a view: writable)."""
        return self.y[:10]

    @property
    def angles(self) -> np.ndarray:
        """[shaft, cage, ball spin] angles (rad), the kinematic tier's layout (spin of ball 0), at
        the end of the latest chunk, as ``snapshot`` gives them (carried on from the step grid)."""
        y, lag = self.y, self._state_lag()
        return np.array([self.shaft_angle, y[10] + y[11] * lag,
                         y[NS0 + B_PSI] + (y[NS0 + B_W] - y[NS0 + B_OM]) * lag])

    def _set_rolling(self, speed: float, cage_angle: float, spin_angle: float):
        """Balls in their pockets at the pure-rolling speeds of ``speed`` (rad/s)."""
        p = self.p
        wc = p[P_CAGER] * speed
        self.y[10] = cage_angle
        self.y[11] = wc
        for j in range(self.nb):
            bse = NS0 + NBV * j
            self.y[bse + B_TH] = cage_angle + 2.0 * math.pi * j / self.nb
            self.y[bse + B_R] = p[P_RM]
            self.y[bse + B_PSI] = spin_angle
            self.y[bse + B_W] = wc
            self.y[bse + B_V] = 0.0
            # Omega = theta' - w_b, w_b = spin in the orbital frame (BSF > 0)
            self.y[bse + B_OM] = wc - p[P_SPINR] * speed

    def _most_loaded_ball_load(self) -> float:
        """The most loaded ball's inner-race contact load (N) in the present state, from the
        quasi-static contact law without defects: at the set-up's equilibrium, the load the
        balls carry from shaft to pedestal (the kinematic tier's ``static_ball_load``)."""
        empty = np.zeros((0, self.dtab.shape[1]))
        loads = [_static_loads(self.p, self.y, j, self.shaft_angle, empty, self.wti, self.wto,
                               self.film, self.y[NS0 + NBV * j + B_R])[0] for j in range(self.nb)]
        return float(max(loads))

    def _settle(self, speed: float):
        """Film and quasi-static ball radii for the current structure state (two passes: the film
        depends on the loads)."""
        for _ in range(2):
            _settle_balls(self.p, self.y, self.shaft_angle, self.dtab, self.wti, self.wto, self.film)
            _film_update(self.y, speed, self.p, self.film, self._aux, False)
        _settle_balls(self.p, self.y, self.shaft_angle, self.dtab, self.wti, self.wto, self.film)

    def _equilibrium(self, load: np.ndarray, speed: float):
        """Static equilibrium of shaft and pedestal under ``load`` (+ shaft weight), balls rolling
        at ``speed`` and sitting at their quasi-static radii."""
        from scipy.optimize import fsolve

        p = self.p
        self._set_rolling(speed, 0.0, 0.0)
        ext = load + np.array([0.0, -p[P_WS]])
        ks, kp = p[P_KS], p[P_KP]
        scale = max(float(np.linalg.norm(ext)), 1.0)
        out = np.zeros(4)
        y = self.y

        def residual(z):
            y[:4] = z * 1e-6
            _quasi_static_forces(p, y, 0.0, self.dtab, self.wti, self.wto, self.film, out)
            xs, xp = y[:2], y[2:4]
            return np.concatenate([(out[:2] - ks * xs + ext) / scale, (out[2:] - kp * xp) / scale])

        k_guess = 2.0 * self.scene.bearing.combined_stiffness
        dmag = (scale / k_guess) ** (2.0 / 3.0) + max(p[P_CR], 0.0)
        direction = ext / scale if np.linalg.norm(ext) > 0 else np.array([0.0, -1.0])
        xp0 = ext / kp          # kp > 0: a scene without a pedestal spring is refused (scene._pedestal_error)
        z0 = np.concatenate([xp0 + direction * dmag, xp0]) * 1e6
        # at light loads the law is flat near the clearance and fsolve may stop short of xtol; a
        # start a fraction of a micron off equilibrium only costs a short settling transient
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            for _ in range(2):                               # second pass with the film
                z = fsolve(residual, z0, xtol=1e-12)
                _film_update(y, speed, p, self.film, self._aux, False)
                z0 = z
            z = fsolve(residual, z0, xtol=1e-12)
        y[:4] = z * 1e-6
        y[4] = y[3]                         # the resonator spring carries no static load
        y[5:10] = 0.0
        self._settle(speed)

    def adopt_state(self, other):
        """Start from another tier's state (e.g. the kinematic tier's ``x`` and ``angles``): same
        structure state, cage angle and ball spin angle, balls in their pockets rolling at the
        pure-rolling speeds of the other tier's shaft speed, at their quasi-static radii."""
        snap = other.snapshot()
        self.y[:10] = np.asarray(other.x, dtype=float)[:10]
        ang = np.asarray(other.angles, dtype=float)
        self.shaft_angle = float(ang[0])
        self._held = None
        self._speed = float(snap.shaft_speed)
        self._set_rolling(self._speed, float(ang[1]), float(ang[2]))
        self.counters[3] = 0
        self.counters[4] = START_STEPS
        if isinstance(other, SkiddingModel):
            self.y[:] = other.y
            self.film[:, :] = other.film
            return
        # the kinematic tier's balls have their films from their loads as this tier's do (massless
        # balls, the entrainment speed of pure rolling at both contacts): start from them
        self._settle(self._speed)
        films = other.ball_films(self._speed)
        self.film[:, F_HI] = films[:, 0]
        self.film[:, F_HO] = films[:, 1]
        _settle_balls(self.p, self.y, self.shaft_angle, self.dtab, self.wti, self.wto, self.film)

    # ---- TierModel interface -----------------------------------------------------------------
    def advance(self, n_steps: int, speed0: float, speed1: float, load0, load1) -> TierOutput:
        q = self.q
        n = int(n_steps) * q
        m = self.decimation * q
        hs = self.hs / q
        nb = self.nb
        nd = (n + m - 1) // m
        ramp = np.zeros(NRAMP)
        ramp[R_S0], ramp[R_S1] = float(speed0), float(speed1)
        ramp[R_L0X], ramp[R_L0Y] = float(load0[0]), float(load0[1])
        ramp[R_L1X], ramp[R_L1Y] = float(load1[0]), float(load1[1])
        inputs = (float(speed1), float(load1[0]), float(load1[1]))
        held = (float(speed0), float(load0[0]), float(load0[1])) == inputs
        if held:
            # inputs held since (t_ref, a_ref): the shaft angle a_ref + w (t - t_ref) is then the
            # same number however the run is chunked (taken from each chunk's start it differed
            # in the last bits, and with it an inner-race defect's place)
            if self._held is None or self._held[2:] != inputs:
                self._held = (self.counters[1] * hs, self.shaft_angle) + inputs
            ramp[R_T0], ramp[R_A0] = self._held[:2]
            ramp[R_T] = math.inf
        else:
            self._held = None
            ramp[R_T0] = self.counters[1] * hs
            ramp[R_T] = n * hs
            # shaft angle at the chunk start (the state may sit a little earlier on the step grid)
            ramp[R_A0] = self.shaft_angle
        acc = np.empty((n, 2))
        qi = np.empty((nd, nb))
        qo = np.empty((nd, nb))
        cage = np.empty(nd)
        bs = np.empty(nd)
        cs = np.empty(nd)
        sli = np.empty((nd, nb))
        slo = np.empty((nd, nb))
        fi = np.empty((nd, nb))
        fo = np.empty((nd, nb))
        kind, ta_, tb_, tc_, tg_, gamma = self._tableau
        if kind == SPLIT:
            l1 = np.asarray(load1, dtype=float)
            if self._needs_relinearising(l1):
                self._linearise(l1)
            if self.kk < 1 or m % self.kk != 0:
                raise ValueError("the split method needs a step of 1, 2 or 4 internal samples")
            if self._work is None:
                self._work = split_work(self.y.shape[0], nb, self.kk)
            work = self._work
            for k in SPLIT_WORK_ZEROED:
                work[k][:] = 0.0
            status = _engine_split(self.y, self._fy, self._un, self._up, self._aux0, self._dg0,
                                   self.film, self.counters, n, m, hs, self.kk, ramp, ta_, tg_, tb_,
                                   gamma, self.p, self.dtab, self.wti, self.wto, *self._step_prop_t,
                                   self.phis, self.g0s, self.g1s, self.g2s, *self._event_prop_t,
                                   self.nsub, self.nball, self.cacc, self.dacc, self.kb, acc, qi,
                                   qo, cage, bs, cs, sli, slo, fi, fo, *work)
        else:
            if self._work is None:
                self._work = engine_work(self.y.shape[0], nb, tb_.shape[0])
            work = self._work
            for k in ENGINE_WORK_ZEROED:
                work[k][:] = 0.0
            status = _engine(self.y, self.counters, n, m, hs, self.hstep, ramp, kind, ta_, tb_, tc_, tg_,
                             gamma, self.p, self.dtab, self.wti, self.wto, self.film, acc, qi, qo, cage,
                             bs, cs, sli, slo, fi, fo, *work)
        if status != 0:
            # where it happened: the signal's time and the operating point on this chunk's ramp
            into = self.counters[2] / n
            t_bad = self.start_time + (self.counters[1] + self.counters[2]) * hs
            speed = speed0 + (speed1 - speed0) * into
            load = [a + (b - a) * into for a, b in zip(load0, load1)]
            if self.solver == "rk4":
                raise RK4Diverged(self.hstep, t_bad, speed, load)
            raise SolverDiverged(self.solver, t_bad, speed, load)
        if held:
            self.shaft_angle = ramp[R_A0] + ramp[R_S1] * (self.counters[1] * hs - ramp[R_T0])
        else:
            self.shaft_angle = ramp[R_A0] + 0.5 * (speed0 + speed1) * n * hs
        self._speed = float(speed1)
        if q > 1:
            acc = np.ascontiguousarray(acc[::q])
        extras = {"ball_skid": bs, "cage_skid": cs, "slip_inner": sli, "slip_outer": slo,
                  "friction_inner": fi, "friction_outer": fo}
        return TierOutput(accel=acc, inner_force=qi, outer_force=qo, cage_speed=cage, extras=extras)

    def snapshot(self) -> KinematicSnapshot:
        """Angles and speeds at the end of the latest chunk.  The state sits at the last point of
        the step grid before it (one internal sample up to a whole step earlier: 17-33 us at two
        steps per output sample, 16.7 us per internal sample at 15 kHz); the cage's and the balls'
        speeds are carried on from there with their accelerations where the split engine keeps
        them (its derivative at the grid point, which its next step starts from), and their angles
        on the trapezoid of the two speeds (the shaft's angle and speed are the chunk end's
        already).  Held instead, the speeds were a step old: 0.22 % low on a ramp from 1600 to
        3800 rpm in 10 ms.  The RK4 engines keep no derivative; their grid is at most one of their
        steps (the reference's 0.5 us, RK4's ``rk4_step``, 10 us by default) behind, and the speeds are held."""
        y = self.y
        lag = self._state_lag()
        has_slope = self.method.kind == SPLIT and self.counters[3] > 0
        slope = self._fy if has_slope else np.zeros_like(y)
        th = y[NS0 + B_TH::NBV][: self.nb]
        w0 = y[NS0 + B_W::NBV][: self.nb]
        w = w0 + slope[NS0 + B_W::NBV][: self.nb] * lag
        cage_speed = y[11] + slope[11] * lag
        return KinematicSnapshot(self.shaft_angle, self._speed, float(y[10] + 0.5 * (y[11] + cage_speed) * lag),
                                 float(cage_speed), th + 0.5 * (w0 + w) * lag, w)

    def _state_lag(self) -> float:
        """Time (s) from the step-grid point where the state ``y`` sits to the end of the latest
        chunk (both global: ``counters[0]`` steps, ``counters[1]`` samples)."""
        return self.counters[1] * (self.hs / self.q) - self.counters[0] * self.hstep


# ---------------------------------------------------------------------------------------------
# benchmark hooks
#: settings of this tier that ``bearing-sim bench`` times beside each other: (label, family,
#: Simulator keyword arguments).  RK4 runs only at steps it survives on the benchmark scenes
#: (seed 000's 1e-5 s diverges on this model, README "The skidding tier", "Solvers"); the default
#: at 1, 2 (its own setting, "default"), 4 and 8 steps per output sample.
BENCH_CONFIGS = [
    # RK4 from its stability limit down: 7e-6 s diverges on every bench scene, 6e-6 s survives
    # them all (2026-11-24; the equal-error comparison needs the steps up to that limit, and a
    # grid fine enough that the RK4 row it picks is not much more accurate than the default)
    ("rk4 h=6e-06", "skidding rk4", {"solver": "rk4", "rk4_step": 6.0e-6}),
    ("rk4 h=5e-06", "skidding rk4", {"solver": "rk4", "rk4_step": 5.0e-6}),
    ("rk4 h=4e-06", "skidding rk4", {"solver": "rk4", "rk4_step": 4.0e-6}),
    ("rk4 h=3e-06", "skidding rk4", {"solver": "rk4", "rk4_step": 3.0e-6}),
    ("rk4 h=2e-06", "skidding rk4", {"solver": "rk4", "rk4_step": 2.0e-6}),
    ("rk4 h=1.5e-06", "skidding rk4", {"solver": "rk4", "rk4_step": 1.5e-6}),
    ("rk4 h=1e-06", "skidding rk4", {"solver": "rk4", "rk4_step": 1.0e-6}),
    ("default x1", "skidding default", {"solver": "default", "oversample": 1}),
    ("default", "skidding default", {"solver": "default"}),
    ("default x4", "skidding default", {"solver": "default", "oversample": 4}),
    ("default x8", "skidding default", {"solver": "default", "oversample": 8}),
]


#: scenarios of :func:`speed_study` (label, scene, rpm, radial load N)
STUDY_SCENARIOS = [
    ("ER-16K healthy 2000 rpm 200 N", "er16k_skidding", 2000.0, 200.0),
    ("ER-16K healthy 2000 rpm 2000 N", "er16k_skidding", 2000.0, 2000.0),
    ("ER-16K healthy 10000 rpm 10 N", "er16k_skidding", 10000.0, 10.0),
    ("ER-16K inner race 1600 rpm 50 N", "er16k_inner_race", 1600.0, 50.0),
    ("ER-16K outer race 1600 rpm 50 N", "er16k_outer_race", 1600.0, 50.0),
]


def speed_study(seconds: float = 0.2, settle: float = 0.05, scenarios=None, sample_rate: float = 15000.0,
                squeeze_film: bool = True):
    """Real-time factor (CPU time of the calling thread, tier + accelerometer chain, sensor noise off)
    and error against the reference of each solver setting on each scenario: RMS of both output
    axes and mean cage speed (relative; ``err`` the largest of the three).  Prints a table and
    returns the rows.  ``squeeze_film=False`` removes the squeeze-film damping from every run
    (reference included; the EHL film stays) to show how much of the error it causes.
    ``python -m bearing_sim_ros.physics.skidding [seconds] [--no-squeeze-film]`` runs it."""
    import time
    from dataclasses import replace

    from ..scene import RPM, load_scene
    from .integrators import RK4, SplitROS2
    from .sensor import AccelerometerChain

    # the reference and the default as the model builds them (method_for), the others by hand
    default_per_sample = DEFAULT_OVERSAMPLE / SkiddingModel.decimation
    methods = [("reference", lambda: method_for("reference", None)),
               ("rk4 h=3e-6", lambda: RK4(step=3e-6)), ("rk4 h=2e-6", lambda: RK4(step=2e-6)),
               ("default", lambda: method_for("default", None, default_per_sample=default_per_sample)),
               ("split, 1 sample/step", lambda: SplitROS2(per_sample=1))]
    rows = []
    for label, name, rpm, load in scenarios or STUDY_SCENARIOS:
        sc = load_scene(name)
        sc = replace(sc, shaft_speed=rpm * RPM, radial_load=(0.0, -load),
                     sensor=replace(sc.sensor, noise_density=0.0))
        w, lv = sc.shaft_speed, np.array(sc.radial_load)
        ref = None
        for mlabel, make in methods:
            model = SkiddingModel(sc, sample_rate, 0, w, lv, method=make())
            if not squeeze_film:
                model.p[P_SQI] = model.p[P_SQO] = 0.0
            chain = AccelerometerChain(sc.sensor, sample_rate, 4, 0)
            chain.prime(np.zeros((chain.lookahead_samples * 4, 2)))
            n0, n = int(settle * sample_rate), int(seconds * sample_rate)
            chain.process(model.advance(4 * n0, w, w, lv, lv).accel, 0)
            t0 = time.thread_time()
            out = model.advance(4 * n, w, w, lv, lv)
            acc = chain.process(out.accel, n0)
            cpu = time.thread_time() - t0
            rms = np.sqrt(np.mean(acc ** 2, axis=0))
            row = {"scenario": label, "method": mlabel, "real_time_factor": seconds / cpu,
                   "rms": rms.tolist(), "cage_speed": float(out.cage_speed.mean()),
                   "cage_skid": float(out.extras["cage_skid"].mean()),
                   "ball_skid": float(out.extras["ball_skid"].mean())}
            if ref is None:
                ref = row
            else:
                e = [abs(a / b - 1.0) for a, b in zip(row["rms"], ref["rms"])]
                e.append(abs(row["cage_speed"] / ref["cage_speed"] - 1.0))
                row["err"] = max(e)
            rows.append(row)
            print(f"{label:33s} {mlabel:22s} {row['real_time_factor']:7.2f}x real time  "
                  f"error {row.get('err', 0.0):7.2%}  cage skid {row['cage_skid']:.3f} %", flush=True)
    return rows


# seconds of signal per run of the speed study: 10 ms is the shortest whose RMS means something;
# 60 s already takes the reference solver (0.1x real time) ten minutes per scenario
STUDY_SECONDS_RANGE = (0.01, 60.0)


def study_main(argv=None) -> int:
    """``python -m bearing_sim_ros.physics.skidding [seconds] [--no-squeeze-film]``: the speed
    study.  A mistake is one line on stderr and exit status 2, as for ``bearing-sim`` (a word for
    the seconds ended in float()'s traceback, a negative number in numpy's; another option was
    ignored)."""
    from ..cli import EXIT_USER, _in_range, _Parser
    from ..errors import UserError
    from ..teardown import say_on_stderr

    p = _Parser(prog="python -m bearing_sim_ros.physics.skidding",
                description="speed and error of the skidding tier's solvers (README, \"The skidding tier\")")
    p.add_argument("seconds", nargs="?", type=_in_range(*STUDY_SECONDS_RANGE, "s"), default=0.2,
                   help="seconds of signal per run, after 0.05 s of settling (default: 0.2)")
    p.add_argument("--no-squeeze-film", action="store_true",
                   help="remove the squeeze-film damping from every run, the reference's too")
    try:
        args = p.parse_args(argv)
    except UserError as exc:
        say_on_stderr(f"error: {exc}")
        return EXIT_USER
    speed_study(args.seconds, squeeze_film=not args.no_squeeze_film)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(study_main())
