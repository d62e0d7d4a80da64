"""The lubricated contact's coefficients (SI units), from the scene's bearing and lubrication.

A ball's contact (seed 000 eqs 12-18, with the choices of PHYSICS_NOTES) is damped by a
structural part c_h = 2 zeta sqrt(m_b k_t), k_t = 1.5 K delta^0.5 the tangent Hertz stiffness,
so c_h = [2 zeta sqrt(1.5 K m_b)] delta^0.25; and, with the EHL film, by Reynolds' squeeze film
of an ellipsoid of radii R_x, R_y on a plane, c_oil = 6 pi eta R_x R_y / (|delta| + h +
roughness) (|delta| the gap, or the interference in contact); h is the Hamrock-Dowson minimum
film thickness h = 3.63 U^0.68 G^0.49 W^-0.073 (1 - exp(-0.68 k)) R_x.  The skidding tier
evaluates them per contact at every step; they are kept here, apart from its kernels, so that
a model of the same contacts can take them from one place.
"""
from __future__ import annotations

import math

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
