"""The tiers' accel_y RMS apart on bearings other than the shipped ones, and why: the numbers of
docs/fidelity_rms_gap.md.  Run from the repository:
``python docs/probes/fidelity_rms/probe.py [part ...]``, parts ``solvers``, ``grid``, ``light``,
``quasistatic`` (all by default; about 5 minutes on 2 cores once compiled, ``grid`` most of it).

Every run is healthy, sensor noise off, 0.2 s after 0.1 s of settling (the README's custom-bearing
figures: the same window); the bearings and their structures are docs/probes/custom_bearings'.
"""
import importlib.util
import math
import sys
from dataclasses import replace

import numpy as np

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.fidelity import bearing_load
from bearing_sim_ros.limits import RPM, InputLimits
from bearing_sim_ros.physics.film import FILM_EXP_Q, FILM_EXP_U, FILM_LOAD_FLOOR, film_coefficient
from bearing_sim_ros.physics.kinematic import centrifugal_force
from bearing_sim_ros.physics.kinematic import centrifugal_ratio as kinematic_centrifugal_ratio

_spec = importlib.util.spec_from_file_location("custom_bearings", "docs/probes/custom_bearings/probe.py")
custom = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(custom)
BEARINGS, FS, scene, quiet = custom.BEARINGS, custom.FS, custom.scene, custom.quiet

SETTLE, SECONDS = 0.1, 0.2


def rms(s, tier, **kwargs):
    """accel_y RMS (m/s^2) of ``tier`` over SECONDS after SETTLE."""
    y = Simulator(quiet(s), fidelity=tier, seed=0, **kwargs).advance(int((SETTLE + SECONDS) * FS)).accel[int(SETTLE * FS):, -1]
    return float(np.sqrt(np.mean(y ** 2)))


def gap(s, solver=None):
    """accel_y RMS (m/s^2) of the kinematic tier and of the skidding tier (its default solver, or
    ``solver``), and the kinematic tier's relative difference."""
    k, r = rms(s, "kinematic"), rms(s, "skidding", **({"solver": solver} if solver else {}))
    return k, r, k / r - 1.0


def limits(which):
    s = scene(which, 1000, 0)
    return InputLimits(s.bearing, s.shaft_weight)


def variant(s, density=None, film=None):
    """``s`` with its balls' density (kg/m^3, the mass scaled with it) or the EHL film on or off."""
    if density is not None:
        b = s.bearing
        s = replace(s, bearing=replace(b, ball_mass=b.ball_mass * density / b.density, density=density))
    if film is not None:
        s = replace(s, lubrication=replace(s.lubrication, ehl_film=film))
    return s


def solvers():
    """The skidding tier's solvers against each other where the README's custom-bearing figures
    put the tiers 20-70 % apart: the default solver is what is off, not the kinematic tier."""
    for which, rpm, load in [("6000-size", 55555, 4662), ("6000-size", 55555, 2331), ("6-ball", 45454, 7106),
                             ("6000-size", 13888, 4662)]:
        s = scene(which, rpm, load)
        out = [f"kinematic {rms(s, 'kinematic'):.4g}"]
        for label, kw in [("default", {}), ("default x4", {"oversample": 4}), ("default x8", {"oversample": 8}),
                          ("rk4 1e-6 s", {"solver": "rk4", "rk4_step": 1e-6}),
                          ("rk4 4e-7 s", {"solver": "rk4", "rk4_step": 4e-7}), ("reference", {"solver": "reference"})]:
            out.append(f"{label} {rms(s, 'skidding', **kw):.4g}")
        print(f"{which} {rpm} rpm {load} N, accel_y RMS m/s^2: " + ", ".join(out), flush=True)


def grid():
    """Each bearing at 0.1, 0.25, 0.5, 1 x its speed limit and 0.02, 0.1, 0.5, 1 x its load limit:
    the kinematic tier against the skidding tier's default solver and its reference, and the
    balls' centrifugal force over the heaviest ball's load (5 W / Z, W the balls' share)."""
    for which in BEARINGS:
        lim = limits(which)
        for fs in (0.1, 0.25, 0.5, 1.0):
            for fl in (0.02, 0.1, 0.5, 1.0):
                rpm = math.floor(fs * lim.max_speed / RPM)
                load = math.floor(fl * (lim.max_load - lim.shaft_weight - 1))
                s = scene(which, rpm, load)
                k, r, g = gap(s)
                _k, ref, g_ref = gap(s, "reference")
                print(f"{which} {rpm} rpm {load} N: kinematic {k:.4g}, skidding default {r:.4g} ({g:+.1%}), "
                      f"reference {ref:.4g} ({g_ref:+.1%}); F_c / Q_max {centrifugal_ratio(s):.3g}", flush=True)


def centrifugal_ratio(s):
    """F_c / Q_max at the scene's operating point (``physics.kinematic.centrifugal_ratio``, what
    the kinematic tier's gate compares)."""
    return kinematic_centrifugal_ratio(s, s.radial_load, s.shaft_speed)


def light():
    """Light load, high speed, where the kinematic tier is off the reference itself: the balls'
    mass (their centrifugal force) and the film, against the reference."""
    cases = [(f"{w} {n} rpm {q} N", scene(w, n, q)) for w, n, q in
             [("6000-size", 55555, 93), ("6220-size", 7142, 3781), ("61820-size", 4444, 739),
              ("6220-size", 3571, 3781), ("6-ball", 45454, 142)]]
    cases.append(("b6307_seed001 (shipped) 1500 rpm", replace(load_scene("b6307_seed001"), defects=())))
    for label, s in cases:
        out = []
        for name, kw in [("as it is", {}), ("balls at 1001 kg/m^3", {"density": 1001.0}),
                         ("at 19990 kg/m^3", {"density": 19990.0}), ("no film", {"film": False})]:
            k, r, g = gap(variant(s, **kw), "reference")
            out.append(f"{name} {g:+.0%}")
        print(f"{label} (F_c / Q_max {centrifugal_ratio(s):.3g}), kinematic against the reference: "
              + ", ".join(out), flush=True)


# the quasi-static ball-pass force: each ball's inner-contact load at the races' offset e, the
# massless ball (the kinematic tier's: one load through both contacts) against one held out by
# its centrifugal force F_c (the outer contact carries the inner's load plus F_c), each contact
# with its own Hamrock-Dowson film; the fluctuation of the balls' total force over one ball
# spacing at the static offset that carries W
_POSITIONS = 32


def _bisect(g, lo, hi, n=60):
    for _ in range(n):
        mid = 0.5 * (lo + hi)
        up = g(mid) > 0
        hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
    return 0.5 * (lo + hi)


def _inner_loads(s, interference, massive):
    b, lub, w = s.bearing, s.lubrication, abs(s.shaft_speed)
    speed = (0.5 * b.outer_race_diameter * b.cage_speed(1.0) * w) ** FILM_EXP_U
    ci, co = ((film_coefficient(c, lub, b.effective_modulus) * speed if lub.ehl_film else 0.0)
              for c in (b.inner_contact, b.outer_contact))
    fc = centrifugal_force(b, w) if massive else 0.0
    ki, ko = b.inner_contact.stiffness, b.outer_contact.stiffness

    def excess(log_q):      # Hertz approaches less films less the interference: increasing in Q
        qi = np.exp(log_q)
        qo = qi + fc
        films = ci * np.maximum(qi, FILM_LOAD_FLOOR) ** FILM_EXP_Q + co * np.maximum(qo, FILM_LOAD_FLOOR) ** FILM_EXP_Q
        return (qi / ki) ** (2 / 3) + (qo / ko) ** (2 / 3) - films - interference

    lo = np.full(interference.shape, math.log(1e-9))
    q = np.exp(_bisect(excess, lo, np.full(interference.shape, math.log(1e8))))
    return np.where(excess(lo) >= 0, 0.0, q)


def _forces(s, offset, massive):
    b = s.bearing
    phase = (np.arange(_POSITIONS)[:, None] / _POSITIONS + np.arange(b.balls)[None, :]) * (2 * np.pi / b.balls)
    q = _inner_loads(s, np.asarray(offset)[..., None, None] * np.cos(phase) - b.radial_clearance, massive)
    return (q * np.cos(phase)).sum(-1), (q * np.sin(phase)).sum(-1)


def ball_pass_fluctuation(s, massive):
    """RMS over one ball spacing of the balls' total force (N) at the static offset carrying W."""
    load = max(bearing_load(s, s.radial_load), 1e-3)
    offset = _bisect(lambda e: _forces(s, e, massive)[0].mean(-1) - load, np.array(-5e-5), np.array(1e-3), 50)
    along, across = _forces(s, offset, massive)
    return float(np.sqrt(along.var() + across.var()))


def quasistatic():
    """The quasi-static ball-pass force of massless balls over that of balls with their
    centrifugal force, against the RMS measured (reference): where F_c / Q_max is large."""
    for which, rpm, load in [("6000-size", 55555, 93), ("6000-size", 27777, 93), ("6000-size", 55555, 4662),
                             ("6220-size", 7142, 3781), ("6220-size", 3571, 3781), ("61820-size", 4444, 739),
                             ("6-ball", 45454, 710), ("6-ball", 45454, 7106)]:
        s = scene(which, rpm, load)
        predicted = ball_pass_fluctuation(s, False) / ball_pass_fluctuation(s, True) - 1.0
        _k, _r, measured = gap(s, "reference")
        print(f"{which} {rpm} rpm {load} N: F_c / Q_max {centrifugal_ratio(s):.3g}, quasi-static {predicted:+.1%}, "
              f"measured {measured:+.1%}", flush=True)


if __name__ == "__main__":
    parts = {"solvers": solvers, "grid": grid, "light": light, "quasistatic": quasistatic}
    for name in sys.argv[1:] or parts:
        parts[name]()
