"""Bearing catalog: geometry and material of deep-groove ball bearings, and what follows from them.

The typed-in numbers live in ``config/bearings.yaml``; everything derived (fault frequencies,
Hertz load-deflection constants, ball inertia) is computed here.  SI units throughout: m, kg,
N, Pa, rad, s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

from .errors import SceneError, short_repr
from .paths import config_dir

G = 9.80665  # standard gravity, m/s^2


@dataclass(frozen=True)
class HertzContact:
    """Hamrock-Brewe point contact between a ball and one race.

    ``stiffness`` K gives the load Q = K * delta**1.5 (N, m).  ``rx``, ``ry`` are the effective
    radii in rolling and transverse direction (m), ``a``/``b`` factors give the contact
    semi-axes for a load Q as ``a = a_coeff * Q**(1/3)`` (m).
    """

    rx: float
    ry: float
    ellipticity: float
    stiffness: float
    a_coeff: float
    b_coeff: float


def hertz_point_contact(rx: float, ry: float, e_eff: float) -> HertzContact:
    """Hamrock and Brewe (1983) approximations for an elliptical point contact.

    rx, ry: effective radii of curvature (m), rolling and transverse; e_eff: E' = E/(1-nu^2) (Pa).
    """
    r = 1.0 / (1.0 / rx + 1.0 / ry)
    alpha_r = ry / rx
    k = 1.0339 * alpha_r ** 0.636              # ellipticity a/b (a transverse)
    eps = 1.0003 + 0.5968 / alpha_r            # complete elliptic integral of the 2nd kind
    f = 1.5277 + 0.6023 * math.log(alpha_r)    # complete elliptic integral of the 1st kind
    # delta = F * [ (9 / (2 eps R)) (Q / (pi k E'))^2 ]^(1/3)  =>  Q = K delta^1.5
    stiffness = math.pi * k * e_eff * math.sqrt(2.0 * eps * r / (9.0 * f ** 3))
    # semi-axes: a = (6 k^2 eps Q R / (pi E'))^(1/3), b = (6 eps Q R / (pi k E'))^(1/3)
    a_coeff = (6.0 * k * k * eps * r / (math.pi * e_eff)) ** (1.0 / 3.0)
    b_coeff = (6.0 * eps * r / (math.pi * k * e_eff)) ** (1.0 / 3.0)
    return HertzContact(rx, ry, k, stiffness, a_coeff, b_coeff)


@dataclass(frozen=True)
class Bearing:
    """A deep-groove ball bearing.  All lengths in m.

    ``radial_clearance`` is seed 000's C_r: with both races centred, the gap between a ball and
    its races summed over the inner and the outer contact (seed 000 eq. 3 gives each contact half
    of it; eq. 4 follows), so a ball touches when the races are offset by C_r towards it.  That is
    half of what bearing makers and ISO 5753-1 call the radial internal clearance (the play of one
    ring from one extreme to the other, Harris' diametral clearance P_d: C_r = P_d / 2): a 6205
    of the normal group (CN, 5-20 um for a 24-30 mm bore) has C_r 2.5-10 um.  A negative value
    is a preload.
    """

    name: str
    balls: int
    ball_diameter: float
    pitch_diameter: float
    inner_race_diameter: float
    outer_race_diameter: float
    radial_clearance: float
    contact_angle: float
    ball_mass: float
    width: float
    inner_groove_conformity: float
    outer_groove_conformity: float
    elastic_modulus: float
    poisson_ratio: float
    density: float
    source: str = ""
    extra: dict = field(default_factory=dict, compare=False, repr=False)

    # ---- kinematics -------------------------------------------------------------------------
    @property
    def diameter_ratio(self) -> float:
        """gamma = d cos(alpha) / D_m."""
        return self.ball_diameter * math.cos(self.contact_angle) / self.pitch_diameter

    def fault_frequencies(self, shaft_hz: float) -> dict:
        """Kinematic (pure rolling) fault frequencies in Hz at a shaft speed in Hz (not rad/s).

        Returns ``{"ftf", "bpfo", "bpfi", "bsf"}``: cage (fundamental train), ball pass outer
        and inner race, ball spin.  The ball-defect line in an envelope spectrum sits at 2 x BSF
        (the defect meets both races once per spin turn).  Rates of events, >= 0 whichever way
        the shaft turns (a negative speed gave negative ones, where no detector finds a line).
        """
        g = self.diameter_ratio
        n = self.balls
        shaft_hz = abs(shaft_hz)
        ftf = 0.5 * shaft_hz * (1.0 - g)
        return {
            "ftf": ftf,
            "bpfo": n * ftf,
            "bpfi": 0.5 * n * shaft_hz * (1.0 + g),
            "bsf": 0.5 * shaft_hz * self.pitch_diameter / self.ball_diameter * (1.0 - g * g),
        }

    def cage_speed(self, shaft_speed: float) -> float:
        """Pure-rolling cage speed (rad/s) for a shaft speed (rad/s), outer race fixed."""
        return 0.5 * shaft_speed * (1.0 - self.diameter_ratio)

    def ball_spin_speed(self, shaft_speed: float) -> float:
        """Pure-rolling ball spin speed about its own axis relative to the cage (rad/s)."""
        g = self.diameter_ratio
        return 0.5 * shaft_speed * self.pitch_diameter / self.ball_diameter * (1.0 - g * g)

    # ---- contact mechanics ------------------------------------------------------------------
    @property
    def effective_modulus(self) -> float:
        """E' = E / (1 - nu^2) for two bodies of the same steel (Pa)."""
        return self.elastic_modulus / (1.0 - self.poisson_ratio ** 2)

    @property
    def inner_contact(self) -> HertzContact:
        rb = 0.5 * self.ball_diameter
        rr = 0.5 * self.inner_race_diameter
        rx = rb * rr / (rb + rr)                                   # convex race
        ry = 1.0 / (1.0 / rb - 1.0 / (self.inner_groove_conformity * self.ball_diameter))
        return hertz_point_contact(rx, ry, self.effective_modulus)

    @property
    def outer_contact(self) -> HertzContact:
        rb = 0.5 * self.ball_diameter
        rr = 0.5 * self.outer_race_diameter
        rx = rb * rr / (rr - rb)                                   # concave race
        ry = 1.0 / (1.0 / rb - 1.0 / (self.outer_groove_conformity * self.ball_diameter))
        return hertz_point_contact(rx, ry, self.effective_modulus)

    @property
    def combined_stiffness(self) -> float:
        """K of one ball between both races in series: Q = K (delta_i + delta_o)^1.5 (N/m^1.5)."""
        ki = self.inner_contact.stiffness
        ko = self.outer_contact.stiffness
        return (ki ** (-2.0 / 3.0) + ko ** (-2.0 / 3.0)) ** (-1.5)

    @property
    def ball_inertia(self) -> float:
        """Moment of inertia of a solid ball about a diameter (kg m^2)."""
        return 0.1 * self.ball_mass * self.ball_diameter ** 2

    def with_clearance(self, radial_clearance: float) -> "Bearing":
        return replace(self, radial_clearance=radial_clearance)


_MM = 1e-3
_CATALOG_KEYS = {
    "source", "balls", "ball_diameter_mm", "pitch_diameter_mm", "inner_race_diameter_mm",
    "outer_race_diameter_mm", "radial_clearance_um", "contact_angle_deg", "ball_mass_kg",
    "width_mm", "inner_groove_conformity", "outer_groove_conformity", "elastic_modulus_gpa",
    "poisson_ratio", "density",
}
_REQUIRED = ("balls", "ball_diameter_mm", "pitch_diameter_mm")
RADIAL_CLEARANCE_RANGE_UM = (-50.0, 500.0)   # a catalog's or a scene's radial_clearance_um (negative: preload)
# kg/m^3: the density key, and what a ball's mass may make of its volume (ball_mass_kg): from
# polymers to tungsten carbide (steel 7850, silicon nitride 3200, WC 15 000)
DENSITY_RANGE = (1000.0, 20000.0)


def bearing_from_mapping(name: str, data: dict, where: str = "bearing", also_allowed: tuple = ()) -> Bearing:
    """Build a :class:`Bearing` from a catalog-style mapping (mm, um, deg, GPa), validating it.
    ``also_allowed``: keys the caller took out of ``data`` before (a scene's ``name``), named
    among the allowed ones where a key is unknown."""
    if not isinstance(data, dict):
        raise SceneError(f"{where}: expected a catalog name or a mapping of geometry, got {short_repr(data)}")
    unknown = sorted(set(map(str, data)) - _CATALOG_KEYS)     # str: a YAML key may be a number
    if unknown:
        raise SceneError(
            f"{where}.{unknown[0]}: unknown key; allowed: {', '.join(sorted(_CATALOG_KEYS | set(also_allowed)))}")
    for key in _REQUIRED:
        if key not in data:
            raise SceneError(f"{where}.{key}: missing; a bearing needs {', '.join(_REQUIRED)}")

    def num(key, default, lo, hi, integer=False):
        value = data.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(f"{where}.{key} = {short_repr(value)}: expected a number in [{lo}, {hi}]")
        # the range first: it refuses NaN and infinity, which int() cannot take
        if not (lo <= value <= hi) or value != value:
            raise SceneError(f"{where}.{key} = {short_repr(value)}: allowed range is [{lo}, {hi}]")
        if integer and int(value) != value:
            raise SceneError(f"{where}.{key} = {short_repr(value)}: expected a whole number in [{lo}, {hi}]")
        return float(value)

    balls = int(num("balls", None, 3, 40, integer=True))
    d = num("ball_diameter_mm", None, 0.5, 200.0) * _MM
    dm = num("pitch_diameter_mm", None, 1.0, 2000.0) * _MM
    if d >= dm * math.sin(math.pi / 3):
        # not even the fewest balls (3) fit: the ball, not the count, is what is wrong
        raise SceneError(
            f"{where}.ball_diameter_mm = {d / _MM:g}: not even 3 balls of {d / _MM:g} mm fit on a "
            f"pitch circle of {dm / _MM:g} mm (a ball must be under sin(60 deg) x the pitch "
            f"diameter, {dm * math.sin(math.pi / 3) / _MM:.4g} mm)")
    if d >= dm * math.sin(math.pi / balls):
        raise SceneError(
            f"{where}.balls = {balls}: {balls} balls of {d / _MM:g} mm do not fit on a pitch "
            f"circle of {dm / _MM:g} mm (at most {int(math.pi / math.asin(d / dm))})")
    di = num("inner_race_diameter_mm", (dm - d) / _MM, 0.1, 2000.0) * _MM
    do = num("outer_race_diameter_mm", (dm + d) / _MM, 0.1, 2000.0) * _MM
    if abs((do - di) - 2 * d) > 0.05 * d:
        # the key the mapping gave: an inner diameter alone was refused under the outer one's
        # key, with a value (the pitch plus the ball diameter) that the user never typed
        key, value, other = (("outer_race_diameter_mm", do, f"inner {di / _MM:g} mm")
                             if "outer_race_diameter_mm" in data or "inner_race_diameter_mm" not in data
                             else ("inner_race_diameter_mm", di, f"outer {do / _MM:g} mm, by default the pitch "
                                   "plus the ball diameter"))
        raise SceneError(
            f"{where}.{key} = {value / _MM:g}: outer minus inner race diameter must be close to twice "
            f"the ball diameter ({2 * d / _MM:g} mm, within 5 % of a ball; the {other})")
    density = num("density", 7850.0, *DENSITY_RANGE)
    mass_default = density * math.pi * d ** 3 / 6.0
    # the ball's mass as its volume holds it at DENSITY_RANGE: a fixed [1e-6, 100] kg let a 7.94 mm
    # ball weigh 1 mg (the skidding solver diverged at 25 700 rpm) or 100 kg (centrifugal loads of
    # 3e5 x the radial load), and refused the default mass of every steel ball under 0.9 mm
    lo, hi = (rho * math.pi * d ** 3 / 6.0 for rho in DENSITY_RANGE)
    ball_mass = data.get("ball_mass_kg", mass_default)
    if isinstance(ball_mass, bool) or not isinstance(ball_mass, (int, float)) or not lo <= ball_mass <= hi:
        raise SceneError(f"{where}.ball_mass_kg = {short_repr(ball_mass)}: allowed range is [{lo:.4g}, {hi:.4g}] for "
                         f"a ball of {d / _MM:g} mm (its volume at {DENSITY_RANGE[0]:g} - {DENSITY_RANGE[1]:g} kg/m^3)")
    return Bearing(
        name=name,
        balls=balls,
        ball_diameter=d,
        pitch_diameter=dm,
        inner_race_diameter=di,
        outer_race_diameter=do,
        radial_clearance=num("radial_clearance_um", 10.0, *RADIAL_CLEARANCE_RANGE_UM) * 1e-6,
        contact_angle=math.radians(num("contact_angle_deg", 0.0, 0.0, 45.0)),
        ball_mass=float(ball_mass),
        width=num("width_mm", 2 * d / _MM, 0.1, 1000.0) * _MM,
        inner_groove_conformity=num("inner_groove_conformity", 0.52, 0.505, 0.6),
        outer_groove_conformity=num("outer_groove_conformity", 0.52, 0.505, 0.6),
        elastic_modulus=num("elastic_modulus_gpa", 208.0, 1.0, 1000.0) * 1e9,
        poisson_ratio=num("poisson_ratio", 0.3, 0.0, 0.49),
        density=density,
        source=str(data.get("source", "")),
    )


@lru_cache(maxsize=None)
def _catalog_data() -> dict:
    from .scene import load_yaml

    with open(config_dir() / "bearings.yaml", encoding="utf-8") as fh:
        return load_yaml(fh.read())


def catalog_names() -> list:
    return sorted(_catalog_data())


def get_bearing(name: str, where: str = "bearing") -> Bearing:
    """The catalog bearing called ``name`` (e.g. ``"ER-16K"``, ``"6205"``, ``"6307"``)."""
    data = _catalog_data()
    if name not in data:
        raise SceneError(f"{where} = {short_repr(name)}: unknown bearing; catalog has {', '.join(sorted(data))}")
    return bearing_from_mapping(name, data[name], where=f"catalog[{name}]")
