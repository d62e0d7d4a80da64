"""Rosenbrock-W tableaus (Hairer-Wanner alpha/Gamma/b form) and their conversion to the engine's
form  W k_i = f(t + c_i h, y + h sum_j a_ij k_j) + sum_j g_ij k_j + tt_i h f_t,  W = I - gamma h J,
y_new = y + h sum_i b_i k_i.

With U_i = h gamma k_i and K = Gamma^-1 U (HW's stage increments K_i):
    G  = I - gamma Gamma^-1  (strictly lower: g_ij = -gamma (Gamma^-1)_ij)
    a  = gamma alpha Gamma^-1,   b = gamma b_HW Gamma^-1
    c  = alpha 1,                tt = gamma (I - G)^-1 1 = Gamma 1  (HW's gamma_i = sum_j Gamma_ij)
(tt is the time component of k for the autonomised system: t' = 1, k_t = (I - G)^-1 1.)"""
import math
import numpy as np

def hw_ros2():
    g = 1.0 + 1.0 / math.sqrt(2.0)
    al = np.array([[0.0, 0.0], [1.0, 0.0]])
    Ga = np.array([[g, 0.0], [-2.0 * g, g]])
    b = np.array([0.5, 0.5])
    return al, Ga, b

def hw_ros34pw2():
    # Rang & Angermann, BIT 45 (2005) 761-787, ROS34PW2; coefficients as in PETSc's TSROSWRA34PW2
    # (src/ts/impls/rosw/rosw.c) and identically in several independent codes (find_string)
    g = 4.3586652150845900e-01
    al = np.array([[0, 0, 0, 0],
                   [8.7173304301691801e-01, 0, 0, 0],
                   [8.4457060015369423e-01, -1.1299064236484185e-01, 0, 0],
                   [0, 0, 1.0, 0]])
    Ga = np.array([[g, 0, 0, 0],
                   [-8.7173304301691801e-01, g, 0, 0],
                   [-9.0338057013044082e-01, 5.4180672388095326e-02, g, 0],
                   [2.4212380706095346e-01, -1.2232505839045147e+00, 5.4526025533510214e-01, g]])
    b = np.array([2.4212380706095346e-01, -1.2232505839045147e+00, 1.5452602553351020e+00, 4.3586652150845900e-01])
    return al, Ga, b

def hw_ra3pw():
    # Rang & Angermann ROS3PW (3 stages, W-order 3, R(inf) = 0.73: NOT L-stable); PETSc TSROSWRA3PW
    g = 7.8867513459481287e-01
    al = np.array([[0, 0, 0], [1.5773502691896257e+00, 0, 0], [0.5, 0, 0]])
    Ga = np.array([[g, 0, 0], [-1.5773502691896257e+00, g, 0],
                   [-6.7075317547305480e-01, -1.7075317547305482e-01, g]])
    b = np.array([1.0566243270259355e-01, 4.9038105676657971e-02, 8.4529946162074843e-01])
    return al, Ga, b

HW = {"ros2": hw_ros2, "ros34pw2": hw_ros34pw2, "ra3pw": hw_ra3pw}

def engine_form(name):
    al, Ga, b = HW[name]()
    s = b.size
    gam = Ga[0, 0]
    Gi = np.linalg.inv(Ga)
    G = np.eye(s) - gam * Gi
    G = np.tril(G, -1)
    a = gam * al @ Gi
    bb = gam * b @ Gi
    c = al.sum(axis=1)
    tt = gam * np.linalg.solve(np.eye(s) - G, np.ones(s))
    return dict(a=a, g=G, b=bb, c=c, tt=tt, gamma=gam)

def engine_form_exact_ros2():
    """ROS2 as integrators.ROS2 has it (so the patched engine can be compared bit for bit)."""
    g = 1.0 + 1.0 / math.sqrt(2.0)
    return dict(a=np.array([[0.0, 0.0], [1.0, 0.0]]), g=np.array([[0.0, 0.0], [-2.0, 0.0]]),
                b=np.array([1.5, 0.5]), c=np.array([0.0, 1.0]), tt=np.array([g, -g]), gamma=g)

def r_inf(name):
    al, Ga, b = HW[name]()
    B = al + Ga
    return 1.0 - b @ np.linalg.solve(B, np.ones(b.size))

def stab(name, z):
    al, Ga, b = HW[name]()
    B = al + Ga
    s = b.size
    return 1.0 + z * b @ np.linalg.solve(np.eye(s) - z * B, np.ones(s))
