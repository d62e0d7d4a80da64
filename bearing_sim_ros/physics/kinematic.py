"""Kinematic tier: seed 001's 5-DOF model (inner race/shaft x, y; outer race/pedestal x, y; unit
resonator on the pedestal, vertical) with Hertz contacts of the balls at kinematic positions.

Balls sit where pure rolling puts them (cage speed from geometry), optionally with seeded
random slip (seed 001 Sec. 2.2); a ball is massless and carries
Q = K (delta)^1.5 with delta = (x_s - x_p) cos(theta) + (y_s - y_p) sin(theta) - C_r - loss + gain
(seed 000 eqs 4 and 10; K of both contacts in series, Hamrock-Brewe).  Gravity on the shaft
and the radial load act on the shaft; the pedestal's own weight is static and an (AC-coupled,
piezoelectric) accelerometer does not see it.

Integrator: second-order exponential time differencing (ETD2, Cox & Matthews 2002).  The
structure plus the bearing stiffness linearised at the static equilibrium form a linear system
integrated exactly by precomputed propagators (matrix exponentials); only the residual
(Hertz minus its linearisation: ball passes, defects, clearance) is explicit.  The stiff but
linear parts (resonator, pedestal, average bearing stiffness) therefore cost nothing in
stability, and the step is limited only by how fast the residual changes.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import KinematicSnapshot, TierOutput
from .defects import (D_ANGLE, D_BALL, D_DEPTH, D_HALF, D_HMAX_I, D_HMAX_O, D_KIND, D_PROFILE,
                      D_RAMP_I, D_RAMP_O, D_RHO_I, D_RHO_O, KIND_BALL, KIND_INNER, _profile_drop,
                      add_defect_losses, defect_table, waviness_gain, wrap)
from .rng import uniform

G = 9.80665
NSTATE = 10   # xs, ys, xp, yp, yr, vxs, vys, vxp, vyp, vyr
ANCHOR_STEPS = 4096   # re-anchor the rotated cage direction to cos/sin this often
NINPUT = 4    # residual bearing force on the pedestal (x, y); external force on the shaft (x, y)

# geometry vector layout
(P_NB, P_K, P_CR, P_RB, P_RI, P_RO, P_CAGE, P_SPIN, P_SLIP, P_GRAV) = range(10)


@njit(cache=True, inline="always")
def ball_geometry(geo, cj, sj, dtab, wtab, seed, shaft_angle, cage_angle, c0, s0, spin_angle,
                  slip_cache, eps, loss_i, loss_o, gc, gs, goff):
    """Where each ball is and how much interference it has lost, at one instant.

    ``c0, s0`` = cos, sin of ``cage_angle`` (the caller advances them by rotation).  Fills gc,
    gs (cos, sin of each ball's angle) and goff (clearance + defect loss - waviness gain, m) so
    that the ball's deflection is ``dx * gc + dy * gs - goff``.  It depends only on the angles,
    so one call serves every force evaluation at that instant.

    Random slip (seed 001): each ball is offset by a linear interpolation of uniform(-1, 1)
    knots one ball spacing apart in cage angle, times ``slip * spacing``.  The knots are hashed
    from (seed, ball, knot index), so the offset depends only on where the cage is
    (chunk-invariant); ``slip_cache`` (nb, 3: knot index, value there, value at the next)
    avoids re-hashing until the cage passes a knot.
    """
    nb = int(geo[P_NB])
    cr = geo[P_CR]
    spacing = 2.0 * math.pi / nb
    slip_amp = geo[P_SLIP] * spacing
    if slip_amp > 0.0:
        q = cage_angle / spacing
        kq = math.floor(q)
        f = q - kq
        for j in range(nb):
            if slip_cache[j, 0] != kq:
                ki = np.int64(kq)
                slip_cache[j, 0] = kq
                slip_cache[j, 1] = 2.0 * uniform(seed, 1000 + j, np.uint64(ki)) - 1.0
                slip_cache[j, 2] = 2.0 * uniform(seed, 1000 + j, np.uint64(ki + 1)) - 1.0
            a = slip_cache[j, 1]
            eps[j] = slip_amp * (a + (slip_cache[j, 2] - a) * f)
    for j in range(nb):
        c = c0 * cj[j] - s0 * sj[j]
        s = s0 * cj[j] + c0 * sj[j]
        e = eps[j]
        if e != 0.0:
            ce = 1.0 - 0.5 * e * e          # cos/sin of a small angle, error < e^3/6
            c, s = c * ce - s * e, s * ce + c * e
        gc[j] = c
        gs[j] = s
        goff[j] = cr
    if dtab.shape[0] > 0:
        for j in range(nb):
            loss_i[j] = 0.0
            loss_o[j] = 0.0
        add_defect_losses(dtab, cage_angle, spacing, nb, eps, shaft_angle, spin_angle,
                          geo[P_RI], geo[P_RO], geo[P_RB], loss_i, loss_o)
        for j in range(nb):
            goff[j] += loss_i[j] + loss_o[j]
    if wtab.shape[0] > 0:
        for j in range(nb):
            goff[j] -= waviness_gain(wtab, cage_angle + j * spacing + eps[j], shaft_angle)


@njit(cache=True, inline="always")
def _rotate(c, s, dth):
    """(cos, sin) of angle + dth from those of angle; dth small (< 0.1 rad): Taylor to 5th
    order, relative error below 1e-9 per call and renormalised at every chunk start."""
    d2 = dth * dth
    cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0))
    sd = dth * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0)))
    return c * cd - s * sd, s * cd + c * sd


@njit(cache=True, inline="always")
def hertz_force(kc, gc, gs, goff, dx, dy, q_out):
    """Force of the balls on the pedestal (N, x and y) for a shaft-pedestal offset (dx, dy) m;
    each ball's load (N) goes to q_out."""
    fx = 0.0
    fy = 0.0
    for j in range(gc.shape[0]):
        delta = dx * gc[j] + dy * gs[j] - goff[j]
        if delta > 0.0:
            qj = kc * delta * math.sqrt(delta)
            q_out[j] = qj
            fx += qj * gc[j]
            fy += qj * gs[j]
        else:
            q_out[j] = 0.0
    return fx, fy


@njit(cache=True)
def bearing_force(geo, cj, sj, dtab, wtab, seed, dx, dy, shaft_angle, cage_angle, spin_angle, q_out):
    """Force of the balls on the pedestal at one instant (convenience for set-up code)."""
    nb = int(geo[P_NB])
    gc = np.empty(nb)
    gs = np.empty(nb)
    goff = np.empty(nb)
    eps = np.zeros(nb)
    li = np.zeros(nb)
    lo = np.zeros(nb)
    cache = np.full((nb, 3), np.nan)
    ball_geometry(geo, cj, sj, dtab, wtab, seed, shaft_angle, cage_angle, math.cos(cage_angle),
                  math.sin(cage_angle), spin_angle, cache, eps, li, lo, gc, gs, goff)
    return hertz_force(geo[P_K], gc, gs, goff, dx, dy, q_out)


@njit(cache=True)
def advance_kernel(x, ang, trig, step, n, m, s0, s1, l0x, l0y, l1x, l1y, h, geo, cj, sj, dtab, wtab,
                   seed, slip_cache, kb, phi_t, g0_t, g1_t, cacc_t, dacc_t, out_acc, out_q, out_cage):
    """ETD2 over ``n`` steps of ``h`` s.  x: state (10,), ang: (shaft, cage, ball spin) angles,
    trig: (cos, sin) of the cage angle, step: (1,) int64 steps taken since t = 0;
    the propagators come transposed (``phi_t = Phi.T`` etc.).  Speed and load ramp linearly
    from (s0, l0) to (s1, l1).  Writes the sensor-mount acceleration of every step to out_acc
    (n, 2) and ball loads / cage speed of every m-th step to out_q (n // m, Nb) and out_cage.

    Why the loop body spells out the Hertz sums instead of calling ``hertz_force``: every call
    of a compiled function that takes arrays pays reference counting on each array, which cost
    more than the physics here (measured: 250 -> under 100 ns per step).
    """
    nb = int(geo[P_NB])
    kc = geo[P_K]
    q = np.zeros(nb)
    gc = np.empty(nb)
    gs = np.empty(nb)
    goff = np.empty(nb)
    eps = np.zeros(nb)
    loss_i = np.zeros(nb)
    loss_o = np.zeros(nb)
    u = np.zeros(NINPUT)
    us = np.zeros(NINPUT)
    xs = np.zeros(NSTATE)
    grav = geo[P_GRAV]
    r_cage = geo[P_CAGE]
    r_spin = geo[P_SPIN]
    k00, k01, k10, k11 = kb[0, 0], kb[0, 1], kb[1, 0], kb[1, 1]
    cr = geo[P_CR]
    spacing = 2.0 * math.pi / nb
    slip_amp = geo[P_SLIP] * spacing
    n_def = dtab.shape[0]
    has_defects = n_def > 0
    has_wav = wtab.shape[0] > 0
    r_in, r_out, r_ball = geo[P_RI], geo[P_RO], geo[P_RB]
    qk = 0.0
    kq = 0.0
    fq = 0.0
    inv_n = 1.0 / n
    # cos/sin of the cage angle advance by rotation (no trig per step) and are re-anchored to
    # the angle every ANCHOR_STEPS steps counted from t = 0, so chunking cannot change them
    cage_cos = trig[0]
    cage_sin = trig[1]
    ball_geometry(geo, cj, sj, dtab, wtab, seed, ang[0], ang[1], cage_cos, cage_sin, ang[2],
                  slip_cache, eps, loss_i, loss_o, gc, gs, goff)
    for i in range(n):
        f0 = i * inv_n
        f1 = (i + 1) * inv_n
        w0 = s0 + (s1 - s0) * f0
        w1 = s0 + (s1 - s0) * f1
        # residual bearing force at the start of the step
        dx = x[0] - x[2]
        dy = x[1] - x[3]
        fx = 0.0
        fy = 0.0
        for j in range(nb):
            delta = dx * gc[j] + dy * gs[j] - goff[j]
            if delta > 0.0:
                qj = kc * delta * math.sqrt(delta)
                q[j] = qj
                fx += qj * gc[j]
                fy += qj * gs[j]
            else:
                q[j] = 0.0
        u[0] = fx - (k00 * dx + k01 * dy)
        u[1] = fy - (k10 * dx + k11 * dy)
        u[2] = l0x + (l1x - l0x) * f0
        u[3] = l0y + (l1y - l0y) * f0 - grav
        # sensor-mount acceleration at the start of the step
        a0 = 0.0
        a1 = 0.0
        for k in range(NSTATE):
            a0 += cacc_t[k, 0] * x[k]
            a1 += cacc_t[k, 1] * x[k]
        for k in range(NINPUT):
            a0 += dacc_t[k, 0] * u[k]
            a1 += dacc_t[k, 1] * u[k]
        out_acc[i, 0] = a0
        out_acc[i, 1] = a1
        if i % m == 0:
            o = i // m
            for j in range(nb):
                out_q[o, j] = q[j]
            out_cage[o] = r_cage * w0
        # predictor: x* = Phi x + G0 u
        for r in range(NSTATE):
            xs[r] = 0.0
        for k in range(NSTATE):
            xk = x[k]
            for r in range(NSTATE):
                xs[r] += phi_t[k, r] * xk
        for k in range(NINPUT):
            uk = u[k]
            for r in range(NSTATE):
                xs[r] += g0_t[k, r] * uk
        # angles and ball geometry at the end of the step (trapezoid on the linear speed ramp)
        dth = 0.5 * (w0 + w1) * h
        ang[0] += dth
        ang[1] += r_cage * dth
        ang[2] += r_spin * dth
        step[0] += 1
        if step[0] % ANCHOR_STEPS == 0:
            cage_cos = math.cos(ang[1])
            cage_sin = math.sin(ang[1])
        else:
            cage_cos, cage_sin = _rotate(cage_cos, cage_sin, r_cage * dth)
        # (same as ball_geometry, spelled out for the reason in the docstring)
        if slip_amp > 0.0:
            qk = ang[1] / spacing
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
        if has_defects:
            # add_defect_losses, spelled out (see the docstring): each defect is tested against
            # the ball nearest to it and that ball's neighbours only
            for k in range(n_def):
                kind = int(dtab[k, D_KIND])
                half = dtab[k, D_HALF]
                prof = int(dtab[k, D_PROFILE])
                depth = dtab[k, D_DEPTH]
                if kind == KIND_BALL:
                    j = int(dtab[k, D_BALL])
                    psi = ang[2] + dtab[k, D_ANGLE]
                    uu = wrap(psi)
                    if abs(uu) < half:
                        goff[j] += _profile_drop(prof, uu, half, r_ball, dtab[k, D_RHO_O],
                                                 dtab[k, D_HMAX_O], dtab[k, D_RAMP_O], depth)
                    uu = wrap(psi - math.pi)
                    if abs(uu) < half:
                        goff[j] += _profile_drop(prof, uu, half, r_ball, dtab[k, D_RHO_I],
                                                 dtab[k, D_HMAX_I], dtab[k, D_RAMP_I], depth)
                    continue
                inner = kind == KIND_INNER
                centre = dtab[k, D_ANGLE] + (ang[0] if inner else 0.0)
                rel = wrap(centre - ang[1])
                nearest = int(math.floor(rel / spacing + 0.5))
                for dj in range(-1, 2):
                    j = (nearest + dj) % nb
                    uu = rel - (nearest + dj) * spacing - eps[j]
                    if abs(uu) < half:
                        if inner:
                            goff[j] += _profile_drop(prof, -uu, half, r_in, dtab[k, D_RHO_I],
                                                     dtab[k, D_HMAX_I], dtab[k, D_RAMP_I], depth)
                        else:
                            goff[j] += _profile_drop(prof, -uu, half, r_out, dtab[k, D_RHO_O],
                                                     dtab[k, D_HMAX_O], dtab[k, D_RAMP_O], depth)
        if has_wav:
            for j in range(nb):
                goff[j] -= waviness_gain(wtab, ang[1] + j * spacing + eps[j], ang[0])
        # residual at the predicted state
        dx = xs[0] - xs[2]
        dy = xs[1] - xs[3]
        fx = 0.0
        fy = 0.0
        for j in range(nb):
            delta = dx * gc[j] + dy * gs[j] - goff[j]
            if delta > 0.0:
                qj = kc * delta * math.sqrt(delta)
                fx += qj * gc[j]
                fy += qj * gs[j]
        us[0] = fx - (k00 * dx + k01 * dy)
        us[1] = fy - (k10 * dx + k11 * dy)
        us[2] = l0x + (l1x - l0x) * f1
        us[3] = l0y + (l1y - l0y) * f1 - grav
        # corrector: x_{n+1} = x* + G1 (u* - u)
        for r in range(NSTATE):
            x[r] = xs[r]
        for k in range(NINPUT):
            du = us[k] - u[k]
            for r in range(NSTATE):
                x[r] += g1_t[k, r] * du
    trig[0] = cage_cos
    trig[1] = cage_sin


class KinematicModel:
    """The kinematic tier (see module docstring).  ``internal_rate`` in Hz."""

    name = "kinematic"

    def __init__(self, scene, output_rate: float, oversample: int, seed: int, shaft_speed: float,
                 radial_load):
        self.scene = scene
        self.decimation = int(oversample)
        self.internal_rate = float(output_rate) * self.decimation
        self.h = 1.0 / self.internal_rate
        self.seed = int(seed)
        b = scene.bearing
        st = scene.structure
        nb = b.balls
        gam = b.diameter_ratio
        self.geo = np.zeros(10)
        self.geo[P_NB] = nb
        self.geo[P_K] = b.combined_stiffness
        self.geo[P_CR] = b.radial_clearance
        self.geo[P_RB] = 0.5 * b.ball_diameter
        self.geo[P_RI] = 0.5 * b.inner_race_diameter
        self.geo[P_RO] = 0.5 * b.outer_race_diameter
        self.geo[P_CAGE] = 0.5 * (1.0 - gam)
        self.geo[P_SPIN] = 0.5 * b.pitch_diameter / b.ball_diameter * (1.0 - gam * gam)
        self.geo[P_SLIP] = scene.random_slip
        self.geo[P_GRAV] = st.shaft_mass * G if scene.gravity else 0.0
        a = 2.0 * np.pi * np.arange(nb) / nb
        self.cj, self.sj = np.cos(a), np.sin(a)
        self.dtab = defect_table(scene.defects, b)
        from .defects import waviness_table

        self.wtab = waviness_table(scene.waviness)
        self.angles = np.zeros(3)   # shaft, cage, ball spin (rad)
        self.slip_cache = np.full((nb, 3), np.nan)
        self.trig = np.array([1.0, 0.0])              # cos, sin of the cage angle
        self.step = np.zeros(1, dtype=np.int64)
        self.x = np.zeros(NSTATE)
        self._lin_load = None
        self._linearise(np.asarray(radial_load, dtype=float), initial=True)

    # ---- linearisation and propagators ---------------------------------------------------------
    def _mean_force(self, d: np.ndarray) -> np.ndarray:
        """Bearing force on the pedestal averaged over one ball spacing of cage angle (no
        defects, no slip): the quasi-static load-deflection law."""
        nb = int(self.geo[P_NB])
        cage = np.linspace(0.0, 2 * np.pi / nb, 12, endpoint=False)
        geo = self.geo.copy()
        geo[P_SLIP] = 0.0
        q = np.zeros(nb)
        empty = np.zeros((0, 12))
        f = np.zeros(2)
        for c in cage:
            fx, fy = bearing_force(geo, self.cj, self.sj, empty, np.zeros((0, 4)), 0, d[0], d[1], 0.0, c, 0.0, q)
            f += (fx, fy)
        return f / cage.size

    def _equilibrium(self, load: np.ndarray) -> np.ndarray:
        """Static positions (xs, ys, xp, yp) under the load (+ shaft weight)."""
        from scipy.optimize import fsolve

        st = self.scene.structure
        ext = load + np.array([0.0, -self.geo[P_GRAV]])
        ks, kp = st.shaft_stiffness, st.pedestal_stiffness
        scale = max(np.linalg.norm(ext), 1.0)

        def residual(z):
            xs, xp = z[:2] * 1e-6, z[2:] * 1e-6
            fb = self._mean_force(xs - xp)
            return np.concatenate([(ks * xs + fb - ext) / scale, (kp * xp - fb) / scale])

        # guess: the bearing takes the load through its stiffest ball, pedestal spring in series
        k_guess = self.geo[P_K] * 2.0
        dmag = (scale / k_guess) ** (2.0 / 3.0) + max(self.geo[P_CR], 0.0)
        direction = ext / scale if np.linalg.norm(ext) > 0 else np.array([0.0, -1.0])
        xp0 = ext / kp if kp > 0 else np.zeros(2)
        z0 = np.concatenate([xp0 + direction * dmag, xp0]) * 1e6
        z, _info, ier, _msg = fsolve(residual, z0, full_output=True, xtol=1e-12)
        return z * 1e-6

    def _linearise(self, load: np.ndarray, initial: bool = False):
        from scipy.linalg import expm

        st = self.scene.structure
        eq = self._equilibrium(load)
        d0 = eq[:2] - eq[2:]
        # secant stiffness of the averaged law (robust where the tangent is zero or steep)
        kb = np.zeros((2, 2))
        eps = 2e-7
        for k in range(2):
            dp = d0.copy()
            dm = d0.copy()
            dp[k] += eps
            dm[k] -= eps
            kb[:, k] = (self._mean_force(dp) - self._mean_force(dm)) / (2 * eps)
        kb = 0.5 * (kb + kb.T)
        self.kb = kb
        ms, mp = st.shaft_mass, st.pedestal_mass
        has_res = st.has_resonator
        mr = st.resonator_mass if has_res else 1.0
        kr, cr = (st.resonator_stiffness, st.resonator_damping) if has_res else (0.0, 0.0)
        mass = np.array([ms, ms, mp, mp, mr])
        kmat = np.zeros((5, 5))
        cmat = np.zeros((5, 5))
        # shaft (0, 1) and pedestal (2, 3) springs to ground, resonator (4) on the pedestal's y
        kmat[0, 0] = kmat[1, 1] = st.shaft_stiffness
        kmat[2, 2] = kmat[3, 3] = st.pedestal_stiffness
        cmat[0, 0] = cmat[1, 1] = st.shaft_damping
        cmat[2, 2] = cmat[3, 3] = st.pedestal_damping
        kmat[3, 3] += kr
        kmat[4, 4] += kr
        kmat[3, 4] = kmat[4, 3] = -kr
        cmat[3, 3] += cr
        cmat[4, 4] += cr
        cmat[3, 4] = cmat[4, 3] = -cr
        # linearised bearing between shaft (0,1) and pedestal (2,3): force on pedestal kb (s - p)
        for a_ in range(2):
            for b_ in range(2):
                kmat[a_, b_] += kb[a_, b_]
                kmat[2 + a_, 2 + b_] += kb[a_, b_]
                kmat[a_, 2 + b_] -= kb[a_, b_]
                kmat[2 + a_, b_] -= kb[a_, b_]
        minv = 1.0 / mass
        A = np.zeros((NSTATE, NSTATE))
        A[:5, 5:] = np.eye(5)
        A[5:, :5] = -minv[:, None] * kmat
        A[5:, 5:] = -minv[:, None] * cmat
        B = np.zeros((NSTATE, NINPUT))
        B[5, 0] = -1.0 / ms     # residual bearing force acts -on the shaft, +on the pedestal
        B[6, 1] = -1.0 / ms
        B[7, 0] = 1.0 / mp
        B[8, 1] = 1.0 / mp
        B[5, 2] = 1.0 / ms      # external force on the shaft
        B[6, 3] = 1.0 / ms
        h = self.h
        nz = NSTATE + 2 * NINPUT
        Z = np.zeros((nz, nz))
        Z[:NSTATE, :NSTATE] = A * h
        Z[:NSTATE, NSTATE:NSTATE + NINPUT] = B * h
        Z[NSTATE:NSTATE + NINPUT, NSTATE + NINPUT:] = np.eye(NINPUT)
        E = expm(Z)
        # stored transposed for the kernel's column-outer products
        self.phi_t = np.ascontiguousarray(E[:NSTATE, :NSTATE].T)
        self.g0_t = np.ascontiguousarray(E[:NSTATE, NSTATE:NSTATE + NINPUT].T)
        self.g1_t = np.ascontiguousarray(E[:NSTATE, NSTATE + NINPUT:].T)
        rows = [7, 9 if has_res else 8]
        self.cacc_t = np.ascontiguousarray(A[rows].T)
        self.dacc_t = np.ascontiguousarray(B[rows].T)
        self._lin_load = load.copy()
        if initial:
            self.x[:4] = eq
            self.x[4] = eq[3]          # the resonator spring carries no static load

    def _needs_relinearising(self, load: np.ndarray) -> bool:
        ref = self._lin_load
        scale = max(np.linalg.norm(ref), 10.0)
        return np.linalg.norm(load - ref) > 0.2 * scale

    # ---- TierModel interface --------------------------------------------------------------------
    def advance(self, n_steps, speed0, speed1, load0, load1) -> TierOutput:
        load1 = np.asarray(load1, dtype=float)
        if self._needs_relinearising(load1):
            self._linearise(load1)
        nb = int(self.geo[P_NB])
        m = self.decimation
        acc = np.empty((n_steps, 2))
        q = np.empty((n_steps // m, nb))
        cage = np.empty(n_steps // m)
        advance_kernel(self.x, self.angles, self.trig, self.step, n_steps, m, float(speed0), float(speed1),
                       float(load0[0]), float(load0[1]), float(load1[0]), float(load1[1]),
                       self.h, self.geo, self.cj, self.sj, self.dtab, self.wtab, self.seed,
                       self.slip_cache, self.kb, self.phi_t, self.g0_t, self.g1_t, self.cacc_t,
                       self.dacc_t, acc, q, cage)
        self._last_speed = float(speed1)
        return TierOutput(accel=acc, inner_force=q, outer_force=q.copy(), cage_speed=cage)

    def adopt_state(self, other) -> None:
        """Continue from another tier's state (same ``x`` layout and ``angles``): the switch
        of fidelity tiers keeps positions, velocities and angles, so the signal has no seam."""
        self.x[:] = other.x
        self.angles[:] = other.angles
        self.step[:] = getattr(other, "step", self.step)
        self.trig[:] = (math.cos(self.angles[1]), math.sin(self.angles[1]))
        self._last_speed = getattr(other, "_last_speed", self.scene.shaft_speed)

    def snapshot(self) -> KinematicSnapshot:
        nb = int(self.geo[P_NB])
        w = getattr(self, "_last_speed", self.scene.shaft_speed)
        cage = self.angles[1]
        balls = cage + 2 * np.pi * np.arange(nb) / nb
        return KinematicSnapshot(self.angles[0], w, cage, self.geo[P_CAGE] * w,
                                 balls, np.full(nb, self.geo[P_CAGE] * w))
