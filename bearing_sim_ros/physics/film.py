"""The lubricated contact's coefficients (SI units), from the scene's bearing and lubrication.

A ball's contact (seed 000 eqs 12-18, with the choices of PHYSICS_NOTES) is damped by a
structural part c_h = 2 zeta sqrt(m_b k_t), k_t = 1.5 K delta^0.5 the tangent Hertz stiffness,
so c_h = [2 zeta sqrt(1.5 K m_b)] delta^0.25; and, with the EHL film, by Reynolds' squeeze film
of an ellipsoid of radii R_x, R_y on a plane, c_oil = 6 pi eta R_x R_y / (|delta| + h +
roughness) (|delta| the gap, or the interference in contact); h is the Hamrock-Dowson minimum
film thickness h = 3.63 U^0.68 G^0.49 W^-0.073 (1 - exp(-0.68 k)) R_x.  The skidding tier
evaluates them per contact at every step; they are kept here, apart from its kernels, so that
a model of the same contacts can take them from one place.

A massless ball (the kinematic tier's) carries the same load Q at both contacts, and its films
fill part of the clearance: its Hertz deflection is delta = b + h(Q), b the geometric
interference, with Q = K delta^1.5 and h = C Q^-0.073 (C from the speed).  That is a fixed
point, and a film that follows its load one evaluation late is a loop of gain -0.11 h / delta,
unstable where a ball barely touches.  In units of lambda, the deflection at which the film
equals it (lambda^(1 + a) = C K^-0.073, a = 0.1095), it is one law for every bearing and speed:
t - t^-a = u with t = delta / lambda, u = b / lambda, the film h = lambda t^-a; monotonic in u,
so each ball's film is a function of its geometry alone.  ``film_law_table`` tabulates it.
"""
from __future__ import annotations

import math

import numpy as np

FILM_EXP_U, FILM_EXP_Q = 0.68, -0.073     # Hamrock-Dowson exponents (speed, load)
FILM_LOAD_FLOOR = 0.01   # N: the film formula's W^-0.073 has no limit at zero load; a contact's
                         # film is taken at this load at least


def film_coefficient(contact, lub, e_eff: float) -> float:
    """C in h = C u^0.68 Q^-0.073 (m, with u in m/s and Q in N): Hamrock-Dowson (1977) minimum
    film thickness h = 3.63 U^0.68 G^0.49 W^-0.073 (1 - exp(-0.68 k)) R_x, U = eta0 u / (E' R_x),
    G = alpha E', W = Q / (E' R_x^2)."""
    rx = contact.rx
    return (3.63 * rx * (lub.viscosity / (e_eff * rx)) ** FILM_EXP_U
            * (lub.pressure_viscosity * e_eff) ** 0.49 * (1.0 / (e_eff * rx * rx)) ** FILM_EXP_Q
            * (1.0 - math.exp(-0.68 * contact.ellipticity)))


def structural_damping_coefficient(contact, lub, ball_mass: float) -> float:
    """c_h / delta^0.25 (N s/m^1.25): c_h = 2 zeta sqrt(m_b k_t), k_t = 1.5 K delta^0.5."""
    return 2.0 * lub.contact_damping_ratio * math.sqrt(1.5 * contact.stiffness * ball_mass)


def squeeze_film_coefficient(contact, lub) -> float:
    """6 pi eta R_x R_y (N s): the squeeze-film damping times its gap (eq. 14: c_oil = dW/du;
    eq. 17's inlet term c_r); 0 without the EHL film."""
    return 6.0 * math.pi * lub.viscosity * contact.rx * contact.ry if lub.ehl_film else 0.0


FILM_LAW_A = -1.5 * FILM_EXP_Q     # 0.1095: along Hertz (Q ~ delta^1.5) the film goes as delta^-a
# the table of the film law: phi(u) = t^-a, t - t^-a = u, on a grid of FILM_TABLE_PER_U points per
# unit of u: per cell the four coefficients of its cubic Hermite interpolant (value and slope at
# both ends) in the cell's own coordinate, so a look-up is three multiply-adds (half the time of
# forming them from values and slopes); relative error below 1e-6 (test_film_law_table; the law
# bends most near u = -1.2, t = 0.2); outside [FILM_TABLE_U_MIN, FILM_TABLE_U_MAX] two
# fixed-point iterations are exact to 1e-7.  A grid uniform in u costs no
# root per look-up; FILM_TABLE_U_MAX = 256 covers a 1500 N ball on the ER-16K down to 300 rpm.
FILM_TABLE_U_MIN = -2.9       # t = 6e-5: below it only with a load floor's film 1e4 x its deflection
FILM_TABLE_U_MAX = 256.0
FILM_TABLE_PER_U = 16


def film_law_root(u):
    """t > 0 with t - t^-a = u (array or float), to machine precision: bisection on log t."""
    u = np.asarray(u, dtype=float)
    lo = np.full(u.shape, -80.0)
    hi = np.full(u.shape, 12.0)
    for _ in range(120):
        mid = 0.5 * (lo + hi)
        above = np.exp(mid) - np.exp(-FILM_LAW_A * mid) > u
        hi = np.where(above, mid, hi)
        lo = np.where(above, lo, mid)
    return np.exp(0.5 * (lo + hi))


def film_law_table() -> np.ndarray:
    """(n, 4): per cell [u_k, u_k+1), u_k = FILM_TABLE_U_MIN + k / FILM_TABLE_PER_U, the
    coefficients c of phi = c0 + s (c1 + s (c2 + s c3)), s = (u - u_k) FILM_TABLE_PER_U: the
    cubic Hermite interpolant of the film factor phi = t^-a and its slope at the cell's ends."""
    n = int(round((FILM_TABLE_U_MAX - FILM_TABLE_U_MIN) * FILM_TABLE_PER_U)) + 2
    t = film_law_root(FILM_TABLE_U_MIN + np.arange(n) / FILM_TABLE_PER_U)
    g = FILM_LAW_A * t ** (-FILM_LAW_A - 1.0)
    phi = t ** -FILM_LAW_A
    slope = -g / (1.0 + g) / FILM_TABLE_PER_U          # d phi / ds
    p0, m0, dp, m1 = phi[:-1], slope[:-1], np.diff(phi), slope[1:]
    return np.ascontiguousarray(np.column_stack([p0, m0, 3.0 * dp - 2.0 * m0 - m1, m0 + m1 - 2.0 * dp]))
