"""Which tier a scene needs: the cheapest whose estimated error stays under the tolerance.

The kinematic tier puts the balls where pure rolling puts them.  What it gets wrong grows with
how much the balls and cage skid, and skidding grows with the lubricant drag the balls must
overcome and shrinks with the traction the load gives them (seed 000 Fig. 17: it falls with
radial load and rises with speed).  The dimensionless *skid index*

    chi = (Nb F_v + T_cage / R_m) / (mu_max W)

compares the two: F_v the lubricant drag of one ball (seed 000 eq. 30 in SI, as the skidding
tier uses it: c_v pi xi d^2 (D_m w_c)^1.95 / 32), T_cage the cage's viscous torque, R_m the pitch
radius, mu_max the peak of the scene's traction curve (eq. 23), W the radial load plus the
shaft's weight.  It is computed from the scene's own lubrication data, so it carries over to
other bearings and lubricants.

The estimated error of the kinematic tier is a calibrated function of chi,

    error(chi) = floor + scale * chi^power,

fitted to the errors that ``bearing-sim bench --calibrate-fidelity`` measures (kinematic tier
against the skidding tier's reference solver, the study's error metric: max of RMS, envelope
line-height and cage-speed error) and kept in ``config/fidelity.yaml`` with the points it was
fitted to.  Selection:

* a scene whose ``fidelity.outputs`` ask for skid ratios gets the skidding tier;
* a tier named in the scene or by the caller is used as asked (its estimate is still reported);
* otherwise the kinematic tier if its estimated error is within the tolerance (the scene's
  ``fidelity.tolerance``, default 5 %), else the skidding tier.  At run time a hysteresis keeps
  the tier from chattering: back to kinematic only below 0.7 x the tolerance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .paths import config_dir

G = 9.80665
HYSTERESIS = 0.7


@dataclass(frozen=True)
class Selection:
    tier: str                 # "kinematic" | "skidding"
    reason: str
    estimated_error: float    # estimated relative error of the kinematic tier at this operating point
    tolerance: float
    skid_index: float = float("nan")

    def describe(self) -> str:
        return (f"{self.tier} tier ({self.reason}; kinematic error estimate "
                f"{self.estimated_error:.1%} against tolerance {self.tolerance:.1%})")


def traction_peak(lub) -> float:
    """Largest traction coefficient of the curve mu(v) = (A + B v) exp(-C v) + D, v >= 0."""
    v = np.linspace(0.0, 20.0, 4001)
    mu = (lub.traction_a + lub.traction_b * v) * np.exp(-lub.traction_c * v) + lub.traction_d
    return float(max(np.max(np.abs(mu)), 1e-3))


def skid_index(scene, shaft_speed: float, radial_load) -> float:
    """The dimensionless skid index chi of the module docstring at an operating point
    (shaft speed rad/s, load (x, y) N)."""
    b = scene.bearing
    lub = scene.lubrication
    w_cage = abs(shaft_speed) * 0.5 * (1.0 - b.diameter_ratio)
    r_m = 0.5 * b.pitch_diameter
    drag_ball = (lub.drag_coefficient * math.pi * lub.fluid_density * b.ball_diameter ** 2
                 * (b.pitch_diameter * w_cage) ** 1.95 / 32.0)
    cage_drag = getattr(lub, "cage_drag", 0.0) * w_cage / r_m
    weight = scene.structure.shaft_mass * G if scene.gravity else 0.0
    load = np.asarray(radial_load, dtype=float) + np.array([0.0, -weight])
    w_eff = max(float(np.hypot(*load)), 1e-3)
    return (b.balls * drag_ball + cage_drag) / (traction_peak(lub) * w_eff)


@lru_cache(maxsize=None)
def calibration() -> dict:
    """The fit in config/fidelity.yaml (floor, scale, power and the points behind them)."""
    from .scene import load_yaml

    path = config_dir() / "fidelity.yaml"
    if not path.is_file():
        return {"floor": 0.0, "scale": 0.0, "power": 1.0, "points": [], "source": "none"}
    return load_yaml(path.read_text(encoding="utf-8"))


def kinematic_error_estimate(scene, shaft_speed: float, radial_load) -> tuple:
    """(estimated relative error of the kinematic tier, skid index) at an operating point."""
    chi = skid_index(scene, shaft_speed, radial_load)
    cal = calibration()
    return float(cal["floor"] + cal["scale"] * chi ** cal["power"]), chi


def select_tier(scene, request: str, shaft_speed: float, radial_load, tolerance: float,
                current: str | None = None) -> Selection:
    """Choose the tier for ``scene`` at an operating point; ``current`` (the tier in use at run
    time) enables the hysteresis."""
    est, chi = kinematic_error_estimate(scene, shaft_speed, radial_load)
    if request in ("kinematic", "skidding"):
        return Selection(request, f"{request} requested", est, tolerance, chi)
    if "skid_ratios" in scene.outputs:
        return Selection("skidding", "the scene asks for skid ratios", est, tolerance, chi)
    limit = tolerance * (HYSTERESIS if current == "skidding" else 1.0)
    if est <= limit:
        return Selection("kinematic", "kinematic error estimate within tolerance", est, tolerance, chi)
    return Selection("skidding", "kinematic error estimate above tolerance", est, tolerance, chi)


def fit(points: list) -> dict:
    """Least-squares fit of log(error) = log(floor + scale chi^power) to [(chi, error)], by a
    small grid over power and floor (robust for a handful of points)."""
    chi = np.array([p[0] for p in points], dtype=float)
    err = np.array([p[1] for p in points], dtype=float)
    best = None
    for power in np.linspace(0.2, 2.0, 37):
        for floor in np.concatenate([[0.0], np.geomspace(1e-4, max(err.min(), 2e-4), 40)]):
            rest = np.clip(err - floor, 1e-9, None)
            # scale from the log-mean of what the floor leaves
            scale = float(np.exp(np.mean(np.log(rest) - power * np.log(chi))))
            model = floor + scale * chi ** power
            cost = float(np.sum(np.log(model / err) ** 2))
            if best is None or cost < best[0]:
                best = (cost, float(floor), scale, float(power))
    _cost, floor, scale, power = best
    worst = float(np.max(np.abs(np.log((floor + scale * chi ** power) / err))))
    return {"floor": floor, "scale": scale, "power": power, "worst_factor": float(np.exp(worst))}
