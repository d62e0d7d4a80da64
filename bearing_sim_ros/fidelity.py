"""Which tier a scene needs: the cheapest whose estimated error stays under the tolerance.

The kinematic tier puts the balls where pure rolling puts them.  What it gets wrong grows with
how much the balls and cage skid, and skidding grows with the lubricant drag the balls must
overcome and shrinks with the traction the load gives them (seed 000 Fig. 17: it falls with
radial load and rises with speed).  The dimensionless *skid index*

    chi = (Nb F_v + T_cage / R_m) / (mu_max W)

compares the two: F_v the lubricant drag of one ball (seed 000 eq. 30 in SI, as the skidding
tier uses it: c_v pi xi d^2 (D_m w_c)^1.95 / 32), T_cage the cage's viscous torque, R_m the pitch
radius, mu_max the peak of the scene's traction curve (eq. 23), W the part of the radial load
and the shaft's weight that the balls carry (``bearing_load``: the shaft's support, in parallel
with the bearing, takes the rest).  It is computed from the scene's own lubrication data, so it carries over to
other bearings and lubricants.

The error skidding causes in the kinematic tier is in its timing: the cage, and with it every
fault frequency, turns slower than pure rolling says.  The estimated error of the kinematic
tier is that relative cage-speed error, a calibrated function of chi,

    error = floor + clearance_gain * max(C_r, 0) / d + scale * chi^power,

(the clearance term: with radial play only a narrow load zone drives the balls, so even a
heavily loaded, slow bearing's cage lags pure rolling; measured 0.36 % for the ER-16K's 45 um,
0.13 % for a 6205 with 10 um, 0.015 % for the preloaded CWRU 6205),

fitted to what ``bearing-sim bench --calibrate-fidelity`` measures (kinematic tier against the
skidding tier's reference solver, cage-speed error) and kept in ``config/fidelity.yaml`` with the
points it was fitted to.  The same calibration records the tiers' RMS and line-height
differences; those come mostly from the EHL squeeze film, which only the skidding tier has
(a difference of model, not of skidding; README "Limitations").  Selection:

* a scene whose ``fidelity.outputs`` ask for skid ratios gets the skidding tier;
* a tier named in the scene or by the caller is used as asked (its estimate is still reported);
* otherwise the kinematic tier if its estimated error is within the tolerance (the scene's
  ``fidelity.tolerance``, default 5 %), else the skidding tier.  At run time a hysteresis keeps
  the tier from chattering: back to kinematic only below 0.7 x the tolerance.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .catalog import G
from .paths import config_dir
from .physics.skidding import drag_coefficient

HYSTERESIS = 0.7
NO_SKID_RATIOS = "kinematic requested: no skid ratios"   # the reason's start where a scene asks for them


@dataclass(frozen=True)
class Selection:
    tier: str                 # "kinematic" | "skidding"
    reason: str
    estimated_error: float    # estimated relative error of the kinematic tier at this operating point
    tolerance: float
    skid_index: float = float("nan")


def traction_peak(lub) -> float:
    """Largest traction coefficient of the curve mu(v) = (A + B v) exp(-C v) + D over slips of
    0 - 20 m/s (``Lubrication.traction_extreme``, exact: it was a 4001-point grid, within 3e-8
    of it on the shipped curves), at least 1e-3."""
    return max(lub.traction_extreme(20.0)[0], 1e-3)


def skid_index(scene, shaft_speed: float, radial_load) -> float:
    """The dimensionless skid index chi of the module docstring at an operating point
    (shaft speed rad/s, load (x, y) N)."""
    b = scene.bearing
    lub = scene.lubrication
    w_cage = b.cage_speed(abs(shaft_speed))
    r_m = 0.5 * b.pitch_diameter
    drag_ball = drag_coefficient(scene) * (b.pitch_diameter * w_cage) ** 1.95
    cage_drag = getattr(lub, "cage_drag", 0.0) * w_cage / r_m
    w_eff = max(bearing_load(scene, radial_load), 1e-3)
    return (b.balls * drag_ball + cage_drag) / (traction_peak(lub) * w_eff)


def _load_with_weight(scene, radial_load) -> float:
    """|radial load + the shaft's weight| (N): what the bearing and the shaft's support carry."""
    weight = scene.structure.shaft_mass * G if scene.gravity else 0.0
    load = np.asarray(radial_load, dtype=float) + np.array([0.0, -weight])
    return float(np.hypot(*load))


# cage positions over one ball spacing that the static load-deflection law averages over
_CAGE_POSITIONS = 8


def bearing_static_force(bearing, displacement) -> np.ndarray:
    """The bearing's static radial force (N) at radial displacements of the inner race (m, along
    the load; an array): Hertz contacts of every ball through both races in series
    (``Bearing.combined_stiffness``), less the radial play (a negative play, a preload, loads every
    ball at no displacement), no film, averaged over the cage's position in one ball spacing.  The
    kinematic tier's ``_mean_force`` is the same law with the films."""
    z = bearing.balls
    phase = (np.arange(_CAGE_POSITIONS)[:, None] / _CAGE_POSITIONS + np.arange(z)[None, :]) * (2.0 * np.pi / z)
    cos_psi = np.cos(phase).ravel()
    e = np.asarray(displacement, dtype=float)[..., None]
    compression = np.maximum(e * cos_psi - bearing.radial_clearance, 0.0)
    return bearing.combined_stiffness * np.sum(compression ** 1.5 * cos_psi, axis=-1) / _CAGE_POSITIONS


@lru_cache(maxsize=64)
def _load_sharing(bearing, support_stiffness: float) -> tuple:
    """(W, the balls' share of W) (N, increasing) for the shaft's support (N/m) in parallel with
    ``bearing``: the law ``bearing_static_force`` on a grid of displacements, from none through
    the radial play to 1 cm (far beyond any Hertz deflection), which ``bearing_load``
    interpolates (a root-find per call took 0.3 - 0.9 ms; the tier is chosen again at every new
    operating point, every batch of a ramp)."""
    play = max(bearing.radial_clearance, 0.0)
    # the play itself a point: below k_s C_r the balls carry exactly nothing
    e = np.unique(np.concatenate([[0.0, play], play + np.geomspace(1e-12, 1e-2, 600)]))
    share = bearing_static_force(bearing, e)
    return support_stiffness * e + share, share


def bearing_load(scene, radial_load) -> float:
    """The radial load the balls carry (N): of W = |radial load + the shaft's weight|, the
    shaft's support (``structure.shaft.stiffness`` k_s, in parallel with the bearing) takes
    k_s e, e the inner race's displacement where k_s e + F_b(e) = W (F_b:
    ``bearing_static_force``).  With radial play the support takes at least k_s C_r (100 N on
    the 6205 scenes: 1e7 N/m over 10 um) and the balls nothing below that
    (``support_carries_all``); under load the balls' deflection adds to it (about 300 N of the
    6205's 2000 N).  Until 2026-11-29 the skid index took W itself, and so underestimated
    skidding where the support's share is large: 2.7x at 200 N on the 6205."""
    total = _load_with_weight(scene, radial_load)
    k_support = scene.structure.shaft_stiffness
    if total <= 0.0 or k_support <= 0.0:
        return total
    loads, shares = _load_sharing(scene.bearing, float(k_support))
    if total >= loads[-1]:
        return total * shares[-1] / loads[-1]
    return float(np.interp(total, loads, shares))


@lru_cache(maxsize=None)
def calibration() -> dict:
    """The fit in config/fidelity.yaml (floor, scale, power and the points behind them)."""
    from .scene import load_yaml

    path = config_dir() / "fidelity.yaml"
    if not path.is_file():
        return {"floor": 0.0, "scale": 0.0, "power": 1.0, "points": [], "source": "none"}
    return load_yaml(path.read_text(encoding="utf-8"))


def clearance_ratio(scene) -> float:
    """Radial play over ball diameter (0 for a preloaded bearing)."""
    return max(scene.bearing.radial_clearance, 0.0) / scene.bearing.ball_diameter


def kinematic_error_estimate(scene, shaft_speed: float, radial_load) -> tuple:
    """(estimated relative error of the kinematic tier, skid index) at an operating point."""
    chi = skid_index(scene, shaft_speed, radial_load)
    cal = calibration()
    est = (cal["floor"] + cal.get("clearance_gain", 0.0) * clearance_ratio(scene)
           + cal["scale"] * chi ** cal["power"])
    return float(est), chi


def support_carries_all(scene, radial_load, margin: float = 1.0) -> bool:
    """Whether the shaft's own support (``structure.shaft.stiffness``, in parallel with the
    bearing) carries the whole radial load and the shaft's weight, so that no ball is loaded:
    until the shaft has moved by the radial play C_r the bearing takes nothing, and the support
    takes k_s x C_r (100 N on the 6205 scenes: 1e7 N/m over 10 um).  There the kinematic tier's
    massless balls carry nothing (its signal is the sensor's noise) while the skidding tier's,
    held out by their centrifugal force, skid; its estimate, from the applied load, said 0.1 %.
    ``margin`` > 1 raises the line (the hysteresis of a run already on the skidding tier).
    False for a preloaded bearing (C_r <= 0)."""
    play = scene.bearing.radial_clearance
    if play <= 0.0:
        return False
    # the line bearing_load's table holds too (its share is exactly 0 up to k_s C_r; the two agree
    # on every shipped scene: test_fidelity), in closed form: the hysteresis raises the line, and
    # through bearing_load it would be a load divided by the margin, no load of the scene, and an
    # interpolation where one product is exact
    return _load_with_weight(scene, radial_load) <= margin * scene.structure.shaft_stiffness * play


def needs_skidding(scene) -> bool:
    """Whether the scene's outputs need the skidding tier whatever the operating point (skid
    ratios: the kinematic tier has no slip)."""
    return "skid_ratios" in scene.outputs


def select_tier(scene, request: str, shaft_speed: float, radial_load, tolerance: float,
                current: str | None = None) -> Selection:
    """Choose the tier for ``scene`` at an operating point; ``current`` (the tier in use at run
    time) enables the hysteresis."""
    est, chi = kinematic_error_estimate(scene, shaft_speed, radial_load)
    if request == "kinematic" and needs_skidding(scene):
        # said where the tier is (the node's log, diagnostics, the render's line, the metadata):
        # the skid ratios the scene asks for were dropped without a word
        return Selection(request, f"{NO_SKID_RATIOS} (the scene asks for them; the skidding tier "
                                  "computes them)", est, tolerance, chi)
    if request in ("kinematic", "skidding"):
        return Selection(request, f"{request} requested", est, tolerance, chi)
    if needs_skidding(scene):
        return Selection("skidding", "the scene asks for skid ratios", est, tolerance, chi)
    if support_carries_all(scene, radial_load, 1.0 / HYSTERESIS if current == "skidding" else 1.0):
        return Selection("skidding", "no ball loaded: the shaft's support carries the whole load",
                         est, tolerance, chi)
    limit = tolerance * (HYSTERESIS if current == "skidding" else 1.0)
    if est <= limit:
        return Selection("kinematic", "kinematic error estimate within tolerance", est, tolerance, chi)
    return Selection("skidding", "kinematic error estimate above tolerance", est, tolerance, chi)


def fit(points: list) -> dict:
    """Fit error = floor + clearance_gain * r + scale * chi^power to [(chi, r, error)]:
    for each power on a grid, non-negative least squares on the relative residuals; the power
    with the smallest worst-case factor wins."""
    from scipy.optimize import nnls

    chi = np.array([p[0] for p in points], dtype=float)
    ratio = np.array([p[1] for p in points], dtype=float)
    err = np.array([p[2] for p in points], dtype=float)
    best = None
    for power in np.linspace(0.2, 2.0, 37):
        basis = np.stack([np.ones_like(chi), ratio, chi ** power], axis=1) / err[:, None]
        coef, _ = nnls(basis, np.ones_like(err))
        model = np.stack([np.ones_like(chi), ratio, chi ** power], axis=1) @ coef
        worst = float(np.max(np.abs(np.log(np.maximum(model, 1e-12) / err))))
        if best is None or worst < best[0]:
            best = (worst, coef, float(power))
    worst, coef, power = best
    return {"floor": float(coef[0]), "clearance_gain": float(coef[1]), "scale": float(coef[2]),
            "power": power, "worst_factor": float(np.exp(worst))}
