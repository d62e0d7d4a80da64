"""The linear structure around the bearing, shared by both tiers.

Shaft/inner race and pedestal/outer race in x and y, and seed 001's unit resonator on the
pedestal's y (state layout [xs, ys, xp, yp, yr, vxs, vys, vxp, vyp, vyr]); springs to ground,
viscous damping, and a linearised bearing stiffness between shaft and pedestal.  SI units.
"""
from __future__ import annotations

import numpy as np


def structure_system(scene, kb: np.ndarray):
    """State matrices of the linear structure (x' = A x + B u, x the 10-state layout, u = forces
    on the shaft x, y and on the pedestal x, y) with the linearised bearing stiffness ``kb``
    (2x2, force on the pedestal per shaft-pedestal offset) between shaft and pedestal; and the
    sensor-mount acceleration rows (C, D)."""
    st = scene.structure
    ms, mp = st.shaft_mass, st.pedestal_mass
    has_res = st.has_resonator
    mr = st.resonator_mass if has_res else 1.0
    kr, cr = (st.resonator_stiffness, st.resonator_damping) if has_res else (0.0, 0.0)
    mass = np.array([ms, ms, mp, mp, mr])
    kmat = np.zeros((5, 5))
    cmat = np.zeros((5, 5))
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
    for a_ in range(2):
        for b_ in range(2):
            kmat[a_, b_] += kb[a_, b_]
            kmat[2 + a_, 2 + b_] += kb[a_, b_]
            kmat[a_, 2 + b_] -= kb[a_, b_]
            kmat[2 + a_, b_] -= kb[a_, b_]
    minv = 1.0 / mass
    A = np.zeros((10, 10))
    A[:5, 5:] = np.eye(5)
    A[5:, :5] = -minv[:, None] * kmat
    A[5:, 5:] = -minv[:, None] * cmat
    B = np.zeros((10, 4))
    B[5, 0] = B[6, 1] = 1.0 / ms
    B[7, 2] = B[8, 3] = 1.0 / mp
    rows = [7, 9 if has_res else 8]
    return A, B, np.ascontiguousarray(A[rows]), np.ascontiguousarray(B[rows])


def secant_stiffness(mean_force, d0: np.ndarray, step: float = 2e-7) -> np.ndarray:
    """Linearised bearing stiffness (2x2, N/m, symmetrised) at a shaft-pedestal offset ``d0``
    (m): central secant of ``mean_force(d) -> (2,)`` N over +-``step``.  A secant, not the
    tangent, because the Hertz law's tangent is zero at the edge of contact and steep just
    inside it."""
    kb = np.zeros((2, 2))
    for k in range(2):
        dp = np.array(d0, dtype=float)
        dm = np.array(d0, dtype=float)
        dp[k] += step
        dm[k] -= step
        kb[:, k] = (mean_force(dp) - mean_force(dm)) / (2.0 * step)
    return 0.5 * (kb + kb.T)
