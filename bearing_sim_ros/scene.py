"""Scenes: a bearing, its structure, operating point, defects, lubrication and sensor.

A scene is a YAML file (``config/scenes/<name>.yaml`` for the shipped ones).  Keys that carry a
unit say so in their name (``_mm``, ``_um``, ``_rpm``, ``_hz``, ``_deg``); the rest are SI (N, kg,
N/m, N s/m, m/s^2).  :func:`load_scene` validates everything and turns it into frozen
dataclasses in SI units; any mistake is a :class:`~bearing_sim_ros.errors.SceneError` whose one
line names the key, the value and what is allowed.
"""
from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from .catalog import RADIAL_CLEARANCE_RANGE_UM, G, Bearing, bearing_from_mapping, get_bearing
from .errors import SceneError, short_repr
from .limits import (LOAD_MULTIPLE_C0, MAX_LOAD, MAX_SPEED_RPM, NDM_LIMIT, RPM, InputLimits, bound_text,
                     load_on_balls)
from .paths import MCAP_MAGIC, input_file, scenes_dir

DEFECT_KINDS = ("inner", "outer", "ball")
DEPTH_PROFILES = ("geometric", "rectangular", "half_sine", "piecewise", "auto")
TIERS = ("auto", "kinematic", "skidding")
OUTPUTS = ("accel", "contact_forces", "cage_speed", "skid_ratios")


@dataclass(frozen=True)
class Structure:
    """Lumped masses (kg), stiffnesses (N/m) and dampings (N s/m) around the bearing.

    Shaft = spindle + inner race; pedestal = housing + outer race (seed 000 eq. 33).  The
    optional unit resonator (seed 001) is a vertical mass-spring on the pedestal that stands for
    the high-frequency structural/sensor resonance that defect impacts excite; mass 0 = none.
    """

    shaft_mass: float
    shaft_stiffness: float
    shaft_damping: float
    pedestal_mass: float
    pedestal_stiffness: float
    pedestal_damping: float
    resonator_mass: float = 0.0
    resonator_stiffness: float = 0.0
    resonator_damping: float = 0.0

    @property
    def has_resonator(self) -> bool:
        return self.resonator_mass > 0.0

    @property
    def resonator_hz(self) -> float | None:
        """The unit resonator's natural frequency sqrt(k / m) / 2 pi (Hz); None without one."""
        return math.sqrt(self.resonator_stiffness / self.resonator_mass) / (2 * math.pi) if self.has_resonator else None


@dataclass(frozen=True)
class Defect:
    """A local defect (spall, EDM pit).

    kind: "inner" (turns with the shaft), "outer" (fixed), "ball" (on ``ball``, spins with it).
    width: extent along the rolling direction (m); depth (m); length: axial extent (m).
    angle: centre of the defect (rad, counterclockwise from +x, looking along the shaft; the
    bottom of the bearing is -pi/2): fixed for "outer", at t = 0 for "inner"; for "ball" the
    initial spin angle of the defect on the ball.
    profile: depth seen by a ball crossing the defect (seed 001 Sec. 3.3 / seed 000 eqs 5-6).
    wander_turns: ball defects only: the ball's spin axis wanders, so the defect's latitude on the
    ball changes and it meets the races only while it lies within the contact ellipse; a new
    independent latitude every ``wander_turns`` spin revolutions (linear in between, seeded).
    0 = a fixed spin axis: the defect stays on the rolling track (physics/defects.py).
    onset: time of signal (s) at which the defect appears (0: there from the start); growth: time
    (s) over which it then grows, width, length and depth together, from a small pit to its full
    size (0: at full size at once; ``physics.defects.DefectSchedule``).
    """

    kind: str
    width: float
    depth: float
    length: float
    angle: float = -0.5 * math.pi
    profile: str = "geometric"
    ball: int = 0
    wander_turns: float = 0.0
    onset: float = 0.0
    growth: float = 0.0


@dataclass(frozen=True)
class Waviness:
    """One harmonic of race waviness (seed 003 eqs 3.47-3.50): radius change
    ``amplitude * cos(order * phi + phase)`` around the race (m, rad)."""

    race: str
    order: int
    amplitude: float
    phase: float = 0.0


@dataclass(frozen=True)
class Lubrication:
    """Lubricant and traction data for the skidding tier (seed 000 eqs 12-30).

    viscosity: dynamic viscosity at the inlet (Pa s); pressure_viscosity: alpha (1/Pa);
    traction A, B, C, D: the curve mu(dv) = (A + B dv) exp(-C dv) + D of eq. 23 (dv in m/s),
    regularised near zero slip by ``creep_velocity`` (m/s); drag_coefficient c_v and
    fluid_density xi of eq. 30; ehl_film: whether the film thickness/stiffness enters.
    cage_pocket_clearance (m) and cage_stiffness k_c (N/m) of eqs 26-29.
    """

    viscosity: float = 0.04
    pressure_viscosity: float = 2.0e-8
    traction_a: float = -0.1
    traction_b: float = 0.06
    traction_c: float = 0.2
    traction_d: float = 0.1
    creep_velocity: float = 0.01
    drag_coefficient: float = 0.5
    fluid_density: float = 30.0       # a placeholder, not fitted (README, "Model"); ER-16K: 300
    ehl_film: bool = True
    cage_stiffness: float = 1.0e8
    cage_pocket_clearance: float = 0.0
    cage_inertia: float = 0.0         # kg m^2; 0 = from the catalog geometry
    cage_mass: float = 0.0            # kg; 0 = estimated from the geometry
    # skidding tier (issue 3): damping inside a ball-race contact as a ratio of the ball's own
    # contact mode, c = 2 zeta sqrt(m_b k_t) (seed 000 eqs 17-18 give no values; EHL point
    # contacts measure zeta ~ 0.05-0.1, Wijnant 1998); the squeeze-film damping around the contact
    # follows from viscosity and geometry (ehl_film), with surface_roughness (m, composite Ra of
    # ground raceways and balls) as the smallest film it sees.
    contact_damping_ratio: float = 0.05
    surface_roughness: float = 0.05e-6
    pocket_damping_ratio: float = 0.05    # ball-cage pocket contact, same definition with k_c
    cage_drag: float = 0.0            # N m s: viscous torque on the cage (not in seed 000)

    def traction_extreme(self, slip_max: float = 100.0) -> tuple:
        """(largest |mu| of the traction curve over slip velocities 0 - ``slip_max`` m/s, the slip
        velocity (m/s) where it is)."""
        return max((abs(mu), v) for mu, v in self._traction_turns(slip_max))

    def traction_least(self, slip_max: float = 100.0) -> tuple:
        """(smallest mu of the traction curve over slip velocities 0 - ``slip_max`` m/s, the slip
        velocity (m/s) where it is)."""
        return min(self._traction_turns(slip_max))

    def _traction_turns(self, slip_max: float) -> list:
        """(mu, slip velocity m/s) where the traction curve can be largest or smallest over slips
        0 - ``slip_max``: at the ends, and where it turns, v = 1/C - A/B (its one turn)."""
        a, b, c, d = self.traction_a, self.traction_b, self.traction_c, self.traction_d
        slips = [0.0, slip_max]
        if b != 0.0 and c > 0.0 and 0.0 < 1.0 / c - a / b < slip_max:
            slips.append(1.0 / c - a / b)
        return [((a + b * v) * math.exp(-c * v) + d, v) for v in slips]


@dataclass(frozen=True)
class Sensor:
    """The accelerometer: where it reads, its resonance, noise and range.

    axes: which pedestal axes are output ("x" horizontal, "y" vertical).  The vertical axis reads
    the unit resonator when the structure has one (seed 001), else the pedestal.
    resonance_hz: mounted resonance of the sensor (0 = ideal), with ``damping_ratio``;
    noise_density: white noise (m/s^2/sqrt(Hz)) over the output band; range: clipping (m/s^2).
    """

    axes: tuple = ("x", "y")
    resonance_hz: float = 0.0
    damping_ratio: float = 0.05
    noise_density: float = 0.0
    range: float = 490.3
    frame_id: str = "bearing_accel"


@dataclass(frozen=True)
class ProfilePoint:
    """A knot of a speed/load profile for offline rendering: time (s), speed (rad/s), load (N)."""

    t: float
    shaft_speed: float
    radial_load: tuple


@dataclass(frozen=True)
class Scene:
    """Everything a simulation needs, in SI units (where the YAML says rpm, mm, um or degrees).
    Built by :func:`load_scene`; ``dataclasses.replace`` makes a changed one, checked as the YAML
    is (a :class:`~bearing_sim_ros.errors.SceneError` of one line).

    shaft_speed: rad/s (not rpm); radial_load: (x, y) N, y up; defects, waviness, profile: tuples
    of :class:`Defect` (m, rad, s), :class:`Waviness` (m, rad) and :class:`ProfilePoint` (s,
    rad/s, N; ``render`` follows it, a ``Simulator`` does not); random_slip: a fraction of the
    ball spacing; fidelity: "auto" | "kinematic" | "skidding" with ``fidelity_tolerance`` (a
    relative error); outputs: from accel, contact_forces, cage_speed, skid_ratios.
    ``source_text`` and ``source_path``: the YAML it was loaded from (not compared).
    """

    name: str
    description: str
    bearing: Bearing
    structure: Structure
    shaft_speed: float            # rad/s, the operating point used when no topic says otherwise
    radial_load: tuple            # (x, y) N on the shaft at the bearing; y up, so (0, -50) pushes down
    defects: tuple = ()
    waviness: tuple = ()
    random_slip: float = 0.0      # fraction of the ball spacing by which ball passes jitter (seed 001: 1-2 %)
    gravity: bool = True          # the shaft's weight acts on the bearing
    lubrication: Lubrication = field(default_factory=Lubrication)
    sensor: Sensor = field(default_factory=Sensor)
    fidelity: str = "auto"
    fidelity_tolerance: float = 0.05
    outputs: tuple = ("accel", "contact_forces", "cage_speed")
    profile: tuple = ()
    source_text: str = field(default="", compare=False, repr=False)
    source_path: str = field(default="", compare=False, repr=False)

    def __post_init__(self):
        # a bearing changed in Python (dataclasses.replace(scene.bearing, ...)) first: every
        # check below rests on it (a ball_mass of -1 was a math domain error inside the physics)
        error = _bearing_error(self.bearing) or _lists_error(self)
        if error:
            raise SceneError(f"scene {self.name}: {error}")
        # the bearing's limits for a scene made in Python too (dataclasses.replace(scene,
        # radial_load=...) ran a scene that load_scene refuses); a YAML scene has met them already,
        # named by its own keys
        knots = [(f"profile[{i}].", p.shaft_speed, p.radial_load) for i, p in enumerate(self.profile)]
        for prefix, speed, load in [("", self.shaft_speed, self.radial_load), *knots]:
            error = _operating_point_type_error(speed, load, f"{prefix}shaft_speed", f"{prefix}radial_load")
            if not error:
                error = _operating_point_error(self.bearing, speed, load, f"{prefix}shaft_speed",
                                               f"{speed:g} rad/s ({speed / RPM:g} rpm)", f"{prefix}radial_load")
            if error:
                raise SceneError(f"scene {self.name}: {error}")
        # and its defects (dataclasses.replace(scene.defects[0], width=...) ran a negative or NaN
        # width as a healthy bearing and a width in mm as a pit of metres) and waviness (a NaN
        # amplitude ran to NaN samples)
        for section, items, error_of in (("defects", self.defects, lambda d, k: _defect_error(self.bearing, d, k)),
                                         ("waviness", self.waviness, _waviness_error)):
            for i, item in enumerate(items):
                error = error_of(item, f"{section}[{i}]")
                if error:
                    raise SceneError(f"scene {self.name}: {error}")
        # and the knobs of a sweep that the YAML bounds (a NaN clearance ran to NaN samples)
        # in m as wide as the um of the YAML and of Python alike (-50 x 1e-6 is above -50e-6, which
        # was refused under a message that gave -5e-05 as the bound)
        lo, hi = _um_range(*RADIAL_CLEARANCE_RANGE_UM)
        tier = ("" if isinstance(self.fidelity, str) and self.fidelity in TIERS
                else f"fidelity = {short_repr(self.fidelity)}: allowed values are {', '.join(TIERS)}")
        for error in (_number_error("bearing.radial_clearance", self.bearing.radial_clearance, lo, hi, "m"),
                      _number_error("random_slip", self.random_slip, 0.0, RANDOM_SLIP_MAX),
                      tier, _number_error("fidelity_tolerance", self.fidelity_tolerance, *TOLERANCE_RANGE),
                      # and its structure, lubrication and sensor (a shaft_mass of 0 was a
                      # ZeroDivisionError inside the physics)
                      _structure_error(self.structure, self.bearing), _lubrication_error(self.lubrication),
                      _sensor_error(self.sensor),
                      # a string "no" was a gravity that acts
                      "" if isinstance(self.gravity, bool) else
                      f"gravity = {short_repr(self.gravity)}: expected True or False"):
            if error:
                raise SceneError(f"scene {self.name}: {error}")
        # held as load_scene makes them, tuples of numbers, so that scenes compare and hash: a
        # numpy load made ``scene == other`` numpy's "truth value ... is ambiguous"
        object.__setattr__(self, "radial_load", tuple(float(v) for v in self.radial_load))
        knots = (ProfilePoint(p.t, p.shaft_speed, tuple(float(v) for v in p.radial_load)) for p in self.profile)
        object.__setattr__(self, "profile", tuple(knots))
        for name in ("defects", "waviness", "outputs"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        # (the pedestal's spring was held to ``_pedestal_error`` with the structure, above)
        error = _shaft_weight_error(self.bearing, self.structure.shaft_mass, self.gravity, "structure.shaft_mass")
        for prefix, load in [("", self.radial_load), *((f"profile[{i}].", p.radial_load)
                                                      for i, p in enumerate(self.profile))]:
            error = error or _load_and_weight_error(self.bearing, load, f"{prefix}radial_load",
                                                    self.structure.shaft_mass, self.gravity, "structure.shaft_mass")
        if error:
            raise SceneError(f"scene {self.name}: {error}")

    @property
    def shaft_weight(self) -> float:
        """The shaft's weight that the balls carry besides the radial load, N (0 without gravity)."""
        return self.structure.shaft_mass * G if self.gravity else 0.0

    @property
    def shaft_hz(self) -> float:
        """The operating point's shaft speed in Hz (revolutions per second; negative: turning
        the other way), what ``Bearing.fault_frequencies`` takes."""
        return self.shaft_speed / (2.0 * math.pi)

    def fault_frequencies(self, shaft_speed: float | None = None) -> dict:
        """Fault frequencies (Hz, ``Bearing.fault_frequencies``) at ``shaft_speed`` (rad/s, unlike
        the bearing's, which takes Hz; default: the scene's)."""
        w = self.shaft_speed if shaft_speed is None else shaft_speed
        return self.bearing.fault_frequencies(w / (2.0 * math.pi))


# --------------------------------------------------------------------------------------------
# validation helpers
class _Section:
    """Reads one mapping of the YAML, checking keys, types and ranges; every error names the
    dotted key path, the value and what is allowed."""

    def __init__(self, data: Any, path: str, allowed: tuple, required: tuple = ()):
        self.path = path
        if data is None:
            data = {}
        if not isinstance(data, dict):
            # the top level has no key to name: the file itself is the wrong shape
            raise SceneError(f"{path or 'top level'} = {short_repr(data)}: expected a mapping with keys "
                             f"{', '.join(allowed)}")
        unknown = sorted(set(map(str, data)) - set(allowed))
        if unknown:
            raise SceneError(f"{self.key(unknown[0])}: unknown key; allowed: {', '.join(allowed)}")
        for key in required:
            if key not in data:
                raise SceneError(f"{self.key(key)}: missing (required)")
        self.data = data

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def has(self, name: str) -> bool:
        return name in self.data

    def number(self, name, default=None, lo=-math.inf, hi=math.inf, integer=False,
               lo_open=False) -> float:
        value = self.data.get(name, default)
        where = self.key(name)
        rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
        if value is None:
            raise SceneError(f"{where}: missing; expected a number in {rng}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(f"{where} = {short_repr(value)}: expected a number in {rng}")
        # the range first: it refuses NaN and infinity, which int() cannot take
        if value != value or not (lo < value if lo_open else lo <= value) or not value <= hi:
            raise SceneError(f"{where} = {short_repr(value)}: allowed range is {rng}")
        if integer and int(value) != value:
            raise SceneError(f"{where} = {short_repr(value)}: expected a whole number in {rng}")
        return float(value)

    def choice(self, name, options, default=None) -> str:
        value = self.data.get(name, default)
        if value not in options:
            raise SceneError(f"{self.key(name)} = {short_repr(value)}: allowed values are {', '.join(options)}")
        return value

    def boolean(self, name, default) -> bool:
        value = self.data.get(name, default)
        if not isinstance(value, bool):
            raise SceneError(f"{self.key(name)} = {short_repr(value)}: expected true or false")
        return value

    def string(self, name, default="") -> str:
        value = self.data.get(name, default)
        if not isinstance(value, str):
            raise SceneError(f"{self.key(name)} = {short_repr(value)}: expected a string")
        return value

    def vector(self, name, length, default=None, lo=-math.inf, hi=math.inf, unit="") -> tuple:
        value = self.data.get(name, default)
        where = self.key(name)
        if (not isinstance(value, (list, tuple)) or len(value) != length
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)):
            raise SceneError(f"{where} = {short_repr(value)}: expected a list of {length} numbers")
        for v in value:
            if v != v or not lo <= v <= hi:
                raise SceneError(f"{where} = {short_repr(value)}: each entry must be in [{lo:g}, {hi:g}]"
                                 + (f" {unit}" if unit else ""))
        return tuple(float(v) for v in value)

    def section(self, name, allowed, required=()) -> "_Section":
        return _Section(self.data.get(name), self.key(name), allowed, required)

    def items(self, name) -> list:
        value = self.data.get(name, [])
        if value is None:
            return []
        if not isinstance(value, list):
            raise SceneError(f"{self.key(name)} = {short_repr(value)}: expected a list")
        return value


def clock_to_angle(clock: float) -> float:
    """Clock position (hours, 12 = top, 3 = +x) to angle (rad, counterclockwise from +x)."""
    return math.pi / 2.0 - clock * math.pi / 6.0


TOLERANCE_RANGE = (1e-4, 1.0)   # relative error allowed to the fidelity choice (fidelity.tolerance)
RANDOM_SLIP_MAX = 0.05          # random_slip: a fraction of the ball spacing (seed 001: 1-2 %)
# MAX_LOAD (N) and MAX_SPEED_RPM (limits.py) bound every scene's speeds and loads whatever the
# bearing; then the bearing's own limits (InputLimits, the live node's) apply: _check_operating_point
MAX_DEFECT_TIME = 1.0e6   # s (11.6 days of signal): a defect's onset_s and growth_s
# The bounds of the structure, lubrication and sensor keys: the YAML's readers (_structure,
# _lubrication, _sensor) and a scene made in Python (_structure_error, _lubrication_error,
# _sensor_error) take them from here, so that the two cannot drift apart.
# structure.shaft and structure.pedestal: key -> (lo, hi, unit); Structure's field is part_key
STRUCTURE_BOUNDS = {"mass": (1e-3, 1e5, "kg"), "stiffness": (0.0, 1e12, "N/m"), "damping": (0.0, 1e8, "N s/m")}
# structure.resonator (mass 0 = none): key -> (lo, hi, unit); Structure holds its mass, stiffness
# m (2 pi f)^2 and damping 2 zeta m (2 pi f)
RESONATOR_BOUNDS = {"mass": (1e-4, 1e3, "kg"), "frequency_hz": (10.0, 50000.0, "Hz"), "damping_ratio": (0.0, 1.0, "")}
# Lubrication's field -> (YAML key, lo, hi) in the key's unit (a key ending _um is in um, the field in m);
# lo excluded where LUBRICATION_LO_OPEN names it
LUBRICATION_BOUNDS = {
    "viscosity": ("viscosity", 1e-4, 10.0),
    "pressure_viscosity": ("pressure_viscosity", 0.0, 1e-7),
    "traction_a": ("traction_a", -1.0, 1.0),
    "traction_b": ("traction_b", -10.0, 10.0),
    "traction_c": ("traction_c", 0.0, 100.0),
    "traction_d": ("traction_d", 0.0, 0.5),
    "creep_velocity": ("creep_velocity", 1e-5, 1.0),
    "drag_coefficient": ("drag_coefficient", 0.0, 10.0),
    "fluid_density": ("fluid_density", 0.0, 2000.0),
    "cage_stiffness": ("cage_stiffness", 1e3, 1e10),
    "cage_pocket_clearance": ("cage_pocket_clearance_um", 0.0, 2000.0),
    "cage_inertia": ("cage_inertia", 0.0, 10.0),
    "cage_mass": ("cage_mass", 0.0, 100.0),
    "contact_damping_ratio": ("contact_damping_ratio", 0.0, 2.0),
    "surface_roughness": ("surface_roughness_um", 0.001, 5.0),
    "pocket_damping_ratio": ("pocket_damping_ratio", 0.0, 2.0),
    "cage_drag": ("cage_drag", 0.0, 1.0),
}
# the film thickness (Hamrock-Dowson) goes as pressure_viscosity^0.49: 0 is no film at all, and the
# kinematic tier's share of it between the races 0 / 0 (a ZeroDivisionError; ehl_film: false
# is the way to have no film)
LUBRICATION_LO_OPEN = ("pressure_viscosity",)
# the traction curve's largest |mu| (over slips up to 100 m/s): dry steel on steel is about 0.6,
# lubricated contacts 0.02-0.1; each key within its bounds, the curve could reach 18 (B = 10), 1.5
# at zero slip (A = 1, D = 0.5) or grow without end (C = 0), and the skidding solver diverged
# (a curve peaking at 1.43 did at 10000 rpm / 10 N; 1.0 ran at 600-20000 rpm, 10-2000 N)
MAX_TRACTION = 1.0
# and never below 0: a traction that drives the slip instead of opposing it feeds the balls
# energy (mu = -1 made the default and the reference solver diverge at every operating point
# tried, -0.5 the default at three of four); TRACTION_ROUNDING lets a curve that starts at
# A + D = 0 in its last bit through
TRACTION_ROUNDING = 1e-12
# Sensor's numeric fields (the YAML keys of the same names) -> (lo, hi, lo_open, unit)
SENSOR_BOUNDS = {"resonance_hz": (0.0, 200000.0, False, "Hz"), "damping_ratio": (0.001, 1.0, False, ""),
                 "noise_density": (0.0, 10.0, False, "m/s^2/sqrt(Hz)"), "range": (0.0, 1e7, True, "m/s^2")}
SENSOR_AXES = ("x", "y")
# waviness: which race, the harmonic's order (whole, 1 - 200) and its amplitude (um in the YAML)
WAVINESS_RACES = ("inner", "outer")
WAVINESS_ORDER_MAX = 200
WAVINESS_AMPLITUDE_MAX_UM = 20.0


def _check_operating_point(where: _Section, rpm: float, load: tuple, bearing: Bearing):
    """The bearing's own limits (``_operating_point_error``) for a YAML operating point or
    profile knot: one line naming its keys."""
    error = _operating_point_error(bearing, rpm * RPM, load, where.key("shaft_speed_rpm"), f"{rpm:g}",
                                   where.key("radial_load"))
    if error:
        raise SceneError(error)


def _operating_point_error(bearing: Bearing, speed: float, load, speed_key: str, speed_text: str,
                           load_key: str) -> str:
    """"" when a shaft speed (rad/s) and load ((x, y) N) are within the bearing's own limits, as
    the live node applies them to its inputs (InputLimits): |speed| up to n d_m = NDM_LIMIT rpm mm
    and |F| up to 2 x C0; else the line naming the key (``speed_key = speed_text``)."""
    limits = InputLimits(bearing)
    if abs(speed) > limits.max_speed:
        return (f"{speed_key} = {speed_text}: beyond what bearing {bearing.name} takes "
                f"(|speed| <= {bound_text(limits.max_speed / RPM)} rpm, n*dm <= {NDM_LIMIT:.0e} rpm mm)")
    force = math.hypot(*load)
    if force > limits.max_load:
        return f"{load_key} = [{load[0]:g}, {load[1]:g}] N: |F| = {force:.6g} N beyond {_load_bound(bearing)}"
    return ""


def _load_bound(bearing: Bearing) -> str:
    """The most load ``bearing`` takes (InputLimits.max_load), said with where it comes from."""
    limit = InputLimits(bearing).max_load
    return (f"{LOAD_MULTIPLE_C0:g} x C0 = {bound_text(limit)} N of bearing {bearing.name}" if limit < MAX_LOAD
            else f"{MAX_LOAD:g} N, the most a scene may ask for")


def _shaft_weight_error(bearing: Bearing, shaft_mass: float, gravity: bool, key: str) -> str:
    """"" when the shaft's weight (``shaft_mass`` kg, with ``gravity``) is a load the bearing takes,
    as a radial load is held to (``_operating_point_error``: 2 x C0), else the line naming ``key``:
    the weight rests on the bearing's balls on top of the radial load, and a 100 t shaft
    (structure.shaft.mass goes to 1e5 kg) put 480 kN on one ball of an ER-16K, 29 x its limit,
    in both tiers."""
    weight = shaft_mass * G if gravity else 0.0
    if weight <= InputLimits(bearing).max_load:
        return ""
    return (f"{key} = {shaft_mass:g} kg: its weight, {weight:.6g} N, is beyond {_load_bound(bearing)} "
            f"(gravity: false leaves the weight out)")


# the most a pedestal spring may give (m) under the most load its bearing takes: a softer one put the
# outer race metres from its place, where the kinematic tier's samples were NaN (1 N/m under an
# ER-16K's 50 N, exit status 0 from render) and both tiers' clipped at the sensor's range from the
# start (100 N/m); at 0.1 m and 0.2 m under 1 % and 99 % of that load both tiers' run finite and agree.
# No spring (0) is refused too: the outer race then floats, held to ground by its damper alone, so
# no static load reaches the balls (the shaft's spring takes all of it, kp xp = F_bearing = 0) and
# the pedestal has no place of its own.  On er16k_outer_race (noise off) the kinematic tier gave
# silence (accel y RMS 4e-10 m/s^2), the skidding tier, whose start was no equilibrium, 2.5 m/s^2
# over the first 0.25 s while the pedestal fell 1.3 mm with the shaft, then silence too (5e-3)
PEDESTAL_SAG_MAX = 0.1


def _pedestal_least(bearing: Bearing) -> float:
    """The least pedestal stiffness (N/m) that ``_pedestal_error`` lets through for ``bearing``."""
    return InputLimits(bearing).max_load / PEDESTAL_SAG_MAX


def _pedestal_error(bearing: Bearing, stiffness, key: str) -> str:
    """"" when a pedestal spring of ``stiffness`` (N/m) holds the pedestal within PEDESTAL_SAG_MAX
    under the most load ``bearing`` takes (InputLimits.max_load, what a radial load and the
    shaft's weight together are held to), else the line naming ``key``: the live node's inputs
    may go that far, a scene's own load too.  0 (no spring), negatives and NaN are refused with
    the same line and its reason: asked ahead of the generic range of STRUCTURE_BOUNDS, whose
    lower bound 0 it refuses anyway (a NaN or -5 N/m was told "allowed range is [0, 1e+12]" and
    0 then "allowed at least 1.668e+05 N/m").  What is not a number, or too stiff, is left to
    that range (with this rule's bound as its lower end)."""
    if (isinstance(stiffness, bool) or not isinstance(stiffness, numbers.Real)
            or stiffness > STRUCTURE_BOUNDS["stiffness"][1]):
        return ""
    least = _pedestal_least(bearing)
    if stiffness >= least:
        return ""
    return (f"{key} = {stiffness:g} N/m: allowed at least {least:.4g} N/m, which holds the pedestal within "
            f"{PEDESTAL_SAG_MAX:g} m under {_load_bound(bearing)} (0, no spring, would leave the balls "
            f"without load)")


def _load_and_weight_error(bearing: Bearing, load, load_key: str, shaft_mass: float, gravity: bool,
                           mass_key: str) -> str:
    """"" when a radial load ((x, y) N) and the shaft's weight (``shaft_mass`` kg, with
    ``gravity``) together are a load the bearing takes (``limits.load_on_balls`` within 2 x C0),
    else the line naming both keys: each is held to that bound alone (``_operating_point_error``,
    ``_shaft_weight_error``), and both near it put twice as much on the balls."""
    weight = shaft_mass * G if gravity else 0.0
    total = load_on_balls(load[0], load[1], weight)
    if total <= InputLimits(bearing).max_load:
        return ""
    return (f"{load_key} = [{load[0]:g}, {load[1]:g}] N with {mass_key} = {shaft_mass:g} kg (its weight "
            f"{weight:.6g} N downwards): |F| on the balls = {total:.6g} N beyond {_load_bound(bearing)} "
            f"(gravity: false leaves the weight out)")


def _defect_bounds(bearing: Bearing) -> tuple:
    """Largest width, depth and length (m) of a defect on ``bearing``: a local defect is at most
    half the ball spacing (and a ball diameter) wide, so one ball meets it at a time; at most half
    a ball diameter deep and a raceway wide."""
    spacing = math.pi * bearing.pitch_diameter / bearing.balls
    return min(0.5 * spacing, bearing.ball_diameter), 0.5 * bearing.ball_diameter, bearing.width


def _number_error(key: str, value, lo: float, hi: float, unit: str = "", lo_open: bool = False) -> str:
    """"" when ``value`` (a field of a scene made in Python) is a finite number in [lo, hi] (or
    (lo, hi]), else the line naming ``key``, the value, the range and ``unit``."""
    unit = f" {unit}" if unit else ""
    rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]{unit}"
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return f"{key} = {short_repr(value)}: expected a number in {rng}"
    if not (math.isfinite(value) and (lo < value if lo_open else lo <= value) and value <= hi):
        return f"{key} = {value:g}{unit}: allowed range is {rng}"
    return ""


def _defect_error(bearing: Bearing, defect, key: str) -> str:
    """"" when ``defect`` (a :class:`Defect` made in Python) keeps to the bounds its YAML keys
    have (``_defects``), else the line naming the field (``key.field``), its value and unit."""
    if not isinstance(defect, Defect):
        return f"{key} = {short_repr(defect)}: expected a bearing_sim_ros.scene.Defect"
    for name, options in (("kind", DEFECT_KINDS), ("profile", DEPTH_PROFILES)):
        value = getattr(defect, name)
        if not (isinstance(value, str) and value in options):
            return f"{key}.{name} = {short_repr(value)}: allowed values are {', '.join(options)}"
    width, depth, length = _defect_bounds(bearing)
    for name, lo, hi, unit in (("width", 0.0, width, "m"), ("depth", 0.0, depth, "m"),
                               ("length", 0.0, length, "m"), ("angle", -2 * math.pi, 2 * math.pi, "rad"),
                               ("wander_turns", 0.0, 1e4, ""), ("onset", 0.0, MAX_DEFECT_TIME, "s"),
                               ("growth", 0.0, MAX_DEFECT_TIME, "s")):
        error = _number_error(f"{key}.{name}", getattr(defect, name), lo, hi, unit,
                              lo_open=name in ("width", "depth", "length"))
        if error:
            return error
    if defect.wander_turns and defect.kind != "ball":
        return (f"{key}.wander_turns = {short_repr(defect.wander_turns)}: only a ball defect has a spin axis "
                f"to wander (this one is kind {defect.kind})")
    ball = defect.ball
    if isinstance(ball, bool) or not isinstance(ball, numbers.Integral) or not 0 <= ball < bearing.balls:
        return f"{key}.ball = {short_repr(ball)}: expected a whole number in [0, {bearing.balls - 1}]"
    return ""


def _bearing_error(bearing) -> str:
    """"" when ``bearing`` (a :class:`Bearing`, perhaps made or changed in Python) is one that the
    catalog's keys allow (``catalog.bearing_from_mapping``, which the YAML goes through), else its
    line: the geometry given back in the catalog's units (mm, deg, GPa; to 12 digits, so that a
    value read from them comes back within its bounds) and checked there.  Its clearance is left
    to the scene's own check, which names it in m."""
    from .catalog import bearing_from_mapping

    if not isinstance(bearing, Bearing):
        return f"bearing = {short_repr(bearing)}: expected a bearing_sim_ros.catalog.Bearing"
    balls = bearing.balls
    if isinstance(balls, bool) or not isinstance(balls, numbers.Integral):
        return f"bearing.balls = {short_repr(balls)}: expected a whole number (int) in [3, 40]"
    given = {"balls": int(balls), "ball_diameter_mm": (bearing.ball_diameter, 1e3),
             "pitch_diameter_mm": (bearing.pitch_diameter, 1e3),
             "inner_race_diameter_mm": (bearing.inner_race_diameter, 1e3),
             "outer_race_diameter_mm": (bearing.outer_race_diameter, 1e3),
             "contact_angle_deg": (bearing.contact_angle, 180.0 / math.pi), "ball_mass_kg": (bearing.ball_mass, 1.0),
             "width_mm": (bearing.width, 1e3), "inner_groove_conformity": (bearing.inner_groove_conformity, 1.0),
             "outer_groove_conformity": (bearing.outer_groove_conformity, 1.0),
             "elastic_modulus_gpa": (bearing.elastic_modulus, 1e-9), "poisson_ratio": (bearing.poisson_ratio, 1.0),
             "density": (bearing.density, 1.0)}
    mapping = {}
    for key, value in given.items():
        if isinstance(value, tuple):
            value, scale = value
            if isinstance(value, numbers.Real) and not isinstance(value, bool):
                value = float(f"{float(value) * scale:.12g}")
        mapping[key] = value
    try:
        bearing_from_mapping(str(bearing.name), mapping, where="bearing")
    except SceneError as exc:
        return f"{exc} (a Bearing checked in the catalog's units: mm, deg, GPa)"
    return ""


def _axes_error(axes, kinds: tuple) -> str:
    """"" when ``axes`` (a ``kinds`` sequence) names distinct sensor axes from SENSOR_AXES, at least
    one, else the line naming ``sensor.axes``."""
    # the names first: set() cannot take a list or a mapping among them
    if (not isinstance(axes, kinds) or not axes or any(not isinstance(a, str) or a not in SENSOR_AXES for a in axes)
            or len(set(axes)) != len(axes)):
        return f"sensor.axes = {short_repr(axes)}: expected a list of distinct axes from {', '.join(SENSOR_AXES)}"
    return ""


def _um_range(lo: float, hi: float) -> tuple:
    """[lo, hi] um as m, wide enough for both a YAML value read in um and turned into m (x 1e-6)
    and the same value written in m in Python (20e-6 is one bit above 20 x 1e-6)."""
    return min(lo * 1e-6, lo / 1e6), max(hi * 1e-6, hi / 1e6)


def _waviness_error(waviness, key: str) -> str:
    """"" when ``waviness`` (a :class:`Waviness` made in Python, m and rad) keeps to the bounds of
    the YAML's ``waviness`` keys, else the line naming the field: a NaN amplitude ran to NaN
    samples (the skidding tier: diverged), a race "middle" or an order 2.5 ran as something else."""
    if not isinstance(waviness, Waviness):
        return f"{key} = {short_repr(waviness)}: expected a bearing_sim_ros.scene.Waviness"
    if not (isinstance(waviness.race, str) and waviness.race in WAVINESS_RACES):
        return f"{key}.race = {short_repr(waviness.race)}: allowed values are {', '.join(WAVINESS_RACES)}"
    order = waviness.order
    if isinstance(order, bool) or not isinstance(order, numbers.Integral) or not 1 <= order <= WAVINESS_ORDER_MAX:
        return f"{key}.order = {short_repr(order)}: expected a whole number in [1, {WAVINESS_ORDER_MAX}]"
    return (_number_error(f"{key}.amplitude", waviness.amplitude, *_um_range(0.0, WAVINESS_AMPLITUDE_MAX_UM), "m")
            or _number_error(f"{key}.phase", waviness.phase, -2 * math.pi, 2 * math.pi, "rad"))


def _structure_error(structure, bearing: Bearing) -> str:
    """"" when ``structure`` (a :class:`Structure` made in Python) keeps to the bounds of the YAML's
    ``structure`` keys (STRUCTURE_BOUNDS, RESONATOR_BOUNDS; the pedestal's stiffness to the rule of
    ``_pedestal_error`` for ``bearing``), else the line naming the field: a shaft_mass of 0 was a
    ZeroDivisionError deep in the physics, a NaN stiffness a LinAlgError."""
    if not isinstance(structure, Structure):
        return f"structure = {short_repr(structure)}: expected a bearing_sim_ros.scene.Structure"
    error = _pedestal_error(bearing, structure.pedestal_stiffness, "structure.pedestal_stiffness")
    if error:
        return error
    for part in ("shaft", "pedestal"):
        for key, (lo, hi, unit) in STRUCTURE_BOUNDS.items():
            if (part, key) == ("pedestal", "stiffness"):
                lo = _pedestal_least(bearing)
            error = _number_error(f"structure.{part}_{key}", getattr(structure, f"{part}_{key}"), lo, hi, unit)
            if error:
                return error
    mass = structure.resonator_mass
    error = _number_error("structure.resonator_mass", mass, 0.0, RESONATOR_BOUNDS["mass"][1], "kg")
    if error or mass == 0.0:
        return error            # no resonator: its stiffness and damping are not used
    if mass < RESONATOR_BOUNDS["mass"][0]:
        lo, hi, unit = RESONATOR_BOUNDS["mass"]
        return f"structure.resonator_mass = {mass:g} {unit}: allowed 0 (no resonator) or [{lo:g}, {hi:g}] {unit}"
    # the YAML gives the resonator's frequency and damping ratio (``_structure``): the stiffness
    # and damping they bound, computed as it computes them; the damping's bound takes a hair of
    # slack, for sqrt(k / m) need not give back the YAML's 2 pi f to the last bit
    lo, hi, _unit = RESONATOR_BOUNDS["frequency_hz"]
    w_lo, w_hi = 2 * math.pi * lo, 2 * math.pi * hi
    error = _number_error("structure.resonator_stiffness", structure.resonator_stiffness,
                          mass * w_lo * w_lo, mass * w_hi * w_hi, "N/m")
    if error:
        return f"{error} ({lo:g} - {hi:g} Hz with resonator_mass {mass:g} kg)"
    w = math.sqrt(structure.resonator_stiffness / mass)
    lo, hi, _unit = RESONATOR_BOUNDS["damping_ratio"]
    error = _number_error("structure.resonator_damping", structure.resonator_damping, 2 * lo * mass * w,
                          2 * hi * mass * w * (1 + 1e-9), "N s/m")
    return f"{error} (damping ratio {lo:g} - {hi:g} at this mass and stiffness)" if error else ""


def _lubrication_error(lubrication) -> str:
    """"" when ``lubrication`` (a :class:`Lubrication` made in Python, SI units) keeps to the
    bounds of the YAML's ``lubrication`` keys (LUBRICATION_BOUNDS), else the line naming the field."""
    if not isinstance(lubrication, Lubrication):
        return f"lubrication = {short_repr(lubrication)}: expected a bearing_sim_ros.scene.Lubrication"
    for name, (key, lo, hi) in LUBRICATION_BOUNDS.items():
        (lo, hi), unit = (_um_range(lo, hi), "m") if key.endswith("_um") else ((lo, hi), "")
        error = _number_error(f"lubrication.{name}", getattr(lubrication, name), lo, hi, unit,
                              lo_open=name in LUBRICATION_LO_OPEN)
        if error:
            return error
    if not isinstance(lubrication.ehl_film, bool):
        return f"lubrication.ehl_film = {short_repr(lubrication.ehl_film)}: expected True or False"
    return _traction_error(lubrication)


def _traction_error(lubrication) -> str:
    """"" when the traction curve of ``lubrication`` stays within 0 - MAX_TRACTION, else the line
    naming its four keys."""
    curve = ", ".join(f"{k} = {getattr(lubrication, 'traction_' + k.lower()):g}" for k in "ABCD")
    said = f"lubrication.traction_a .. traction_d ({curve}): the traction curve (A + B v) exp(-C v) + D"
    mu, slip = lubrication.traction_extreme()
    if mu > MAX_TRACTION:
        return (f"{said} reaches |mu| = {mu:.3g} at a slip of {slip:.3g} m/s; allowed at most {MAX_TRACTION:g} "
                "(dry steel on steel is about 0.6, lubricated contacts 0.02 - 0.1)")
    mu, slip = lubrication.traction_least()
    if mu < -TRACTION_ROUNDING:
        return (f"{said} falls to mu = {mu:.3g} at a slip of {slip:.3g} m/s; allowed at least 0 (traction opposes "
                "the slip; a negative mu drives it)")
    return ""


def _sensor_error(sensor) -> str:
    """"" when ``sensor`` (a :class:`Sensor` made in Python) keeps to the bounds of the YAML's
    ``sensor`` keys (SENSOR_BOUNDS, SENSOR_AXES), else the line naming the field: an axis "z" ran
    as the vertical one labelled accel_z, a range of 0 clipped every sample to 0."""
    if not isinstance(sensor, Sensor):
        return f"sensor = {short_repr(sensor)}: expected a bearing_sim_ros.scene.Sensor"
    error = _axes_error(sensor.axes, (list, tuple))
    for name, (lo, hi, lo_open, unit) in SENSOR_BOUNDS.items():
        error = error or _number_error(f"sensor.{name}", getattr(sensor, name), lo, hi, unit, lo_open)
    if not error and not (isinstance(sensor.frame_id, str) and sensor.frame_id):
        error = f"sensor.frame_id = {short_repr(sensor.frame_id)}: expected a non-empty string"
    return error


# the lists of a Scene and what they hold (their items are checked by _defect_error and so on)
_LISTS = {"defects": "bearing_sim_ros.scene.Defect", "waviness": "bearing_sim_ros.scene.Waviness",
          "profile": "bearing_sim_ros.scene.ProfilePoint"}


def _lists_error(scene) -> str:
    """"" when the defects, waviness and profile of a scene made in Python are lists, the
    profile's knots ProfilePoints whose times increase from 0 on and the outputs known, as the
    YAML's readers make them; else the line naming the field (a lone Defect was "'Defect' object
    is not iterable", a knot as a plain tuple an AttributeError, a misspelt output ran without it)."""
    for key, what in _LISTS.items():
        items = getattr(scene, key)
        if not isinstance(items, (tuple, list)):
            return f"{key} = {short_repr(items)}: expected a tuple of {what}"
    last_t = -math.inf
    for i, knot in enumerate(scene.profile):
        if not isinstance(knot, ProfilePoint):
            return (f"profile[{i}] = {short_repr(knot)}: expected a {_LISTS['profile']} (t s, shaft_speed rad/s, "
                    "radial_load (x, y) N)")
        error = _number_error(f"profile[{i}].t", knot.t, 0.0, 1e6, "s")
        if error:
            return error
        if knot.t <= last_t:
            return f"profile[{i}].t = {knot.t:g} s: times must increase (previous {last_t:g})"
        last_t = knot.t
    outputs = scene.outputs
    if isinstance(outputs, str) or not isinstance(outputs, (tuple, list)) or any(o not in OUTPUTS for o in outputs):
        return f"outputs = {short_repr(outputs)}: expected a list from {', '.join(OUTPUTS)}"
    return ""


def _operating_point_type_error(speed, load, speed_key: str, load_key: str) -> str:
    """"" when ``speed`` is a finite number and ``load`` two (a bool is neither), else the line
    naming the key: a scene made in Python has not been through the YAML's readers."""
    def finite(v):
        return isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)

    if not finite(speed):
        return f"{speed_key} = {short_repr(speed)}: expected a finite number, rad/s"
    if isinstance(load, (str, bytes)) or not (hasattr(load, "__len__") and len(load) == 2
                                              and all(finite(v) for v in load)):
        return f"{load_key} = {short_repr(load)}: expected two finite numbers (x, y), N"
    return ""


def _bearing(top: _Section) -> Bearing:
    value = top.data.get("bearing")
    if isinstance(value, int) and not isinstance(value, bool):
        value = str(value)      # `bearing: 6205` unquoted: YAML reads a number, the catalog names it
    if isinstance(value, str):
        bearing = get_bearing(value, where="bearing")
    elif isinstance(value, dict):
        bearing = bearing_from_mapping(str(value.get("name", "custom")),
                                       {k: v for k, v in value.items() if k != "name"},
                                       where="bearing", also_allowed=("name",))
    else:
        raise SceneError(f"bearing = {short_repr(value)}: expected a catalog name or a mapping of geometry")
    if top.has("radial_clearance_um"):
        lo, hi = RADIAL_CLEARANCE_RANGE_UM
        bearing = bearing.with_clearance(top.number("radial_clearance_um", lo=lo, hi=hi) * 1e-6)
    return bearing


def _structure(top: _Section, bearing: Bearing) -> Structure:
    s = top.section("structure", ("shaft", "pedestal", "resonator"), required=("shaft", "pedestal"))
    parts = {}
    for part in ("shaft", "pedestal"):
        p = s.section(part, tuple(STRUCTURE_BOUNDS), required=tuple(STRUCTURE_BOUNDS))
        bounds = dict(STRUCTURE_BOUNDS)
        if part == "pedestal":
            # the pedestal rule's bound and its reason for a spring too soft; its bound in the range
            # that the other messages (not a number, too stiff) give
            error = _pedestal_error(bearing, p.data["stiffness"], p.key("stiffness"))
            if error:
                raise SceneError(error)
            bounds["stiffness"] = (_pedestal_least(bearing), *STRUCTURE_BOUNDS["stiffness"][1:])
        parts[part] = tuple(p.number(key, lo=lo, hi=hi) for key, (lo, hi, _unit) in bounds.items())
    res = (0.0, 0.0, 0.0)
    if s.has("resonator") and s.data["resonator"] is not None:
        r = s.section("resonator", tuple(RESONATOR_BOUNDS), required=tuple(RESONATOR_BOUNDS))
        m, f, z = (r.number(key, lo=lo, hi=hi) for key, (lo, hi, _unit) in RESONATOR_BOUNDS.items())
        w = 2 * math.pi * f
        res = (m, m * w * w, 2 * z * m * w)
    return Structure(*parts["shaft"], *parts["pedestal"], *res)


def _defects(top: _Section, bearing: Bearing) -> tuple:
    out = []
    for i, raw in enumerate(top.items("defects")):
        d = _Section(raw, f"defects[{i}]",
                     ("kind", "width_mm", "depth_mm", "length_mm", "clock", "angle_deg", "profile", "ball",
                      "wander_turns", "onset_s", "growth_s"),
                     required=("kind", "width_mm", "depth_mm"))
        kind = d.choice("kind", DEFECT_KINDS)
        max_width, max_depth, max_length = (v / 1e-3 for v in _defect_bounds(bearing))
        width = d.number("width_mm", lo=0.0, hi=max_width, lo_open=True) * 1e-3
        depth = d.number("depth_mm", lo=0.0, hi=max_depth, lo_open=True) * 1e-3
        length = d.number("length_mm", width / 1e-3, lo=0.0, hi=max_length, lo_open=True) * 1e-3
        if d.has("clock") and d.has("angle_deg"):
            raise SceneError(f"defects[{i}]: give either clock or angle_deg, not both")
        if d.has("clock"):
            angle = clock_to_angle(d.number("clock", lo=0.0, hi=12.0))
        else:
            angle = math.radians(d.number("angle_deg", -90.0, lo=-360.0, hi=360.0))
        if d.has("ball") and kind != "ball":
            raise SceneError(f"{d.key('ball')} = {short_repr(d.data['ball'])}: only a ball defect is on a ball "
                             f"(this one is kind {kind})")
        # the key at all, 0 included (0 = no wander, which means nothing on a race either)
        if d.has("wander_turns") and kind != "ball":
            raise SceneError(f"{d.key('wander_turns')} = {short_repr(d.data['wander_turns'])}: only a ball "
                             f"defect has a spin axis to wander (this one is kind {kind})")
        ball = int(d.number("ball", 0, lo=0, hi=bearing.balls - 1, integer=True))
        wander = d.number("wander_turns", 0.0, lo=0.0, hi=1e4)
        onset = d.number("onset_s", 0.0, lo=0.0, hi=MAX_DEFECT_TIME)
        growth = d.number("growth_s", 0.0, lo=0.0, hi=MAX_DEFECT_TIME)
        out.append(Defect(kind, width, depth, length, angle, d.choice("profile", DEPTH_PROFILES, "geometric"), ball,
                          wander, onset, growth))
    return tuple(out)


def _waviness(top: _Section) -> tuple:
    out = []
    for i, raw in enumerate(top.items("waviness")):
        w = _Section(raw, f"waviness[{i}]", ("race", "order", "amplitude_um", "phase_deg"),
                     required=("race", "order", "amplitude_um"))
        out.append(Waviness(w.choice("race", WAVINESS_RACES),
                            int(w.number("order", lo=1, hi=WAVINESS_ORDER_MAX, integer=True)),
                            w.number("amplitude_um", lo=0.0, hi=WAVINESS_AMPLITUDE_MAX_UM) * 1e-6,
                            math.radians(w.number("phase_deg", 0.0, lo=-360, hi=360))))
    return tuple(out)


def _lubrication(top: _Section) -> Lubrication:
    s = top.section("lubrication", (*(key for key, _lo, _hi in LUBRICATION_BOUNDS.values()), "ehl_film"))
    d = Lubrication()
    values = {}
    for name, (key, lo, hi) in LUBRICATION_BOUNDS.items():
        # a key in um is read in um and held in m (the default converted as it always was)
        um = key.endswith("_um")
        default = getattr(d, name) * 1e6 if um else getattr(d, name)
        values[name] = s.number(key, default, lo=lo, hi=hi, lo_open=name in LUBRICATION_LO_OPEN) * (1e-6 if um else 1.0)
    lubrication = Lubrication(ehl_film=s.boolean("ehl_film", d.ehl_film), **values)
    error = _traction_error(lubrication)        # the four keys together (Scene checks it again)
    if error:
        raise SceneError(error)
    return lubrication


def _sensor(top: _Section) -> Sensor:
    s = top.section("sensor", ("axes", "resonance_hz", "damping_ratio", "noise_density", "range", "frame_id"))
    axes = s.data.get("axes", list(SENSOR_AXES))
    error = _axes_error(axes, (list,))
    if error:
        raise SceneError(error)
    return Sensor(axes=tuple(a for a in SENSOR_AXES if a in axes),
                  **{name: s.number(name, getattr(Sensor, name), lo=lo, hi=hi, lo_open=lo_open)
                     for name, (lo, hi, lo_open, _unit) in SENSOR_BOUNDS.items()},
                  frame_id=s.string("frame_id", "bearing_accel") or "bearing_accel")


def _profile(top: _Section, speed: float, load: tuple, bearing: Bearing) -> tuple:
    points = []
    last_t = -math.inf
    for i, raw in enumerate(top.items("profile")):
        p = _Section(raw, f"profile[{i}]", ("t", "shaft_speed_rpm", "radial_load"), required=("t",))
        t = p.number("t", lo=0.0, hi=1e6)
        if t <= last_t:
            raise SceneError(f"profile[{i}].t = {t:g}: times must increase (previous {last_t:g})")
        last_t = t
        rpm = p.number("shaft_speed_rpm", speed / RPM, lo=-MAX_SPEED_RPM, hi=MAX_SPEED_RPM)
        load = p.vector("radial_load", 2, list(load), lo=-MAX_LOAD, hi=MAX_LOAD, unit="N")
        _check_operating_point(p, rpm, load, bearing)
        speed = rpm * RPM
        points.append(ProfilePoint(t, speed, load))
    return tuple(points)


TOP_KEYS = ("name", "description", "bearing", "radial_clearance_um", "structure", "operating_point",
            "defects", "waviness", "random_slip", "gravity", "lubrication", "sensor", "fidelity",
            "profile")


def scene_from_dict(data: Any, name: str = "scene", source_text: str = "", source_path: str = "") -> Scene:
    """Validate a parsed scene mapping and build the :class:`Scene`."""
    top = _Section(data, "", TOP_KEYS, required=("bearing", "structure", "operating_point"))
    bearing = _bearing(top)
    op = top.section("operating_point", ("shaft_speed_rpm", "radial_load"), required=("shaft_speed_rpm",))
    rpm = op.number("shaft_speed_rpm", lo=-MAX_SPEED_RPM, hi=MAX_SPEED_RPM)
    load = op.vector("radial_load", 2, [0.0, 0.0], lo=-MAX_LOAD, hi=MAX_LOAD, unit="N")
    _check_operating_point(op, rpm, load, bearing)
    speed = rpm * RPM
    fid = top.section("fidelity", ("tier", "tolerance", "outputs"))
    outputs = fid.data.get("outputs", ["accel", "contact_forces", "cage_speed"])
    if not isinstance(outputs, list) or any(o not in OUTPUTS for o in outputs):
        raise SceneError(f"fidelity.outputs = {short_repr(outputs)}: expected a list from {', '.join(OUTPUTS)}")
    structure = _structure(top, bearing)
    gravity = top.boolean("gravity", True)
    error = _shaft_weight_error(bearing, structure.shaft_mass, gravity, "structure.shaft.mass")
    profile = _profile(top, speed, load, bearing)
    for key, knot_load in [(op.key("radial_load"), load),
                           *((f"profile[{i}].radial_load", p.radial_load) for i, p in enumerate(profile))]:
        error = error or _load_and_weight_error(bearing, knot_load, key, structure.shaft_mass, gravity,
                                                "structure.shaft.mass")
    if error:
        raise SceneError(error)
    return Scene(
        name=top.string("name", name) or name,
        description=top.string("description", ""),
        bearing=bearing,
        structure=structure,
        shaft_speed=speed,
        radial_load=load,
        defects=_defects(top, bearing),
        waviness=_waviness(top),
        random_slip=top.number("random_slip", 0.0, lo=0.0, hi=RANDOM_SLIP_MAX),
        gravity=gravity,
        lubrication=_lubrication(top),
        sensor=_sensor(top),
        fidelity=fid.choice("tier", TIERS, "auto"),
        fidelity_tolerance=fid.number("tolerance", 0.05, *TOLERANCE_RANGE),
        outputs=tuple(outputs),
        profile=profile,
        source_text=source_text,
        source_path=source_path,
    )


def shipped_scenes() -> list:
    """Names of the scenes in ``config/scenes``."""
    return sorted(p.stem for p in scenes_dir().glob("*.yaml"))


def scene_argument(scene: Scene) -> str:
    """How a command line names ``scene`` so that it loads the same file from any directory: a
    shipped scene by its name, any other scene file by its absolute path (the ``name:`` inside a
    file is a label that ``load_scene`` cannot find the file by).  A scene built in Python from a
    mapping has no file; its name is all there is."""
    if not scene.source_path:
        return scene.name
    path = Path(scene.source_path).resolve()
    if path.suffix == ".yaml" and path == (scenes_dir() / f"{path.stem}.yaml").resolve():
        return path.stem
    return str(path)


def changes_since_loaded(scene: Scene) -> tuple:
    """The fields of ``scene`` that differ from the YAML it was loaded from (``source_text``):
    a scene changed in Python (``dataclasses.replace``) keeps its file's text and path, which a
    recording takes for how to make it again.  () for a scene as loaded, or without a text."""
    if not scene.source_text:
        return ()
    name = Path(scene.source_path).stem if scene.source_path else scene.name
    loaded = scene_from_dict(load_yaml(scene.source_text), name=name)
    return tuple(f.name for f in fields(Scene) if f.compare and getattr(scene, f.name) != getattr(loaded, f.name))


def resolve_scene_path(name_or_path: str | Path) -> Path:
    """A shipped scene name or a path to a YAML file -> the file's path."""
    if not isinstance(name_or_path, (str, os.PathLike)):
        # str() would make any value a name: load_scene(None) said "unknown scene 'None'"
        raise SceneError(f"scene = {short_repr(name_or_path)}: expected a shipped scene name or the path of a scene "
                         f"YAML (str or pathlib.Path), not {type(name_or_path).__name__}")
    text = str(name_or_path)
    path = Path(text)
    if path.suffix in (".yaml", ".yml") or path.exists() or "/" in text:
        return input_file(text, f"scene = {text!r}", f"give a YAML path or one of {', '.join(shipped_scenes())}",
                          error=SceneError)
    shipped = scenes_dir() / f"{text}.yaml"
    if not shipped.is_file():
        raise SceneError(f"scene = {text!r}: unknown scene; shipped scenes are {', '.join(shipped_scenes())}")
    return shipped


def _yaml_loader():
    """A safe YAML loader that also reads ``1e7`` and ``4.24e4`` as floats (YAML 1.2 style;
    PyYAML's 1.1 rule wants ``1.0e+7``, which surprises everyone) and refuses a key given twice
    in one mapping (PyYAML keeps the last: a second ``defects:`` block dropped the first)."""
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        def construct_mapping(self, node, deep=False):
            if isinstance(node, yaml.MappingNode):
                seen = {}
                for key_node, _ in node.value:
                    if key_node.tag == "tag:yaml.org,2002:merge":
                        continue        # "<<: *base" then a key of base: an override, not a repeat
                    key = self.construct_object(key_node, deep=deep)
                    try:
                        first = seen.setdefault(key, key_node.start_mark)
                    except TypeError:
                        continue        # a list as a key: the base class says so
                    if first is not key_node.start_mark:
                        lines = (f"on line {first.line + 1}" if first.line == key_node.start_mark.line
                                 else f"(lines {first.line + 1} and {key_node.start_mark.line + 1})")
                        raise yaml.constructor.ConstructorError(
                            "while constructing a mapping", node.start_mark,
                            f"key {short_repr(key)} appears twice {lines}; give it once", key_node.start_mark)
            return super().construct_mapping(node, deep=deep)

    Loader.add_implicit_resolver(
        "tag:yaml.org,2002:float",
        re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                    |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                    |[-+]?\.(?:inf|Inf|INF)
                    |\.(?:nan|NaN|NAN))$""", re.X),
        list("-+0123456789."))
    return Loader


def load_yaml(text: str):
    """Parse YAML text safely (see :func:`_yaml_loader`)."""
    import yaml

    return yaml.load(text, Loader=_yaml_loader())  # noqa: S506 - a SafeLoader subclass


def load_scene(name_or_path: str | Path) -> Scene:
    """Load and validate a scene: a shipped name (``"er16k_outer_race"``) or a YAML path."""
    import yaml

    path = resolve_scene_path(name_or_path)
    where = f"scene = {str(path)!r}"
    try:
        with open(path, "rb") as f:
            # a recording where the scene goes (both end up as arguments of render and report)
            # is told by its first bytes, before a possibly large file is read
            if f.read(len(MCAP_MAGIC)) == MCAP_MAGIC:
                raise SceneError(f"{where}: not a YAML scene but an MCAP recording; "
                                 "`bearing-sim play` and `bearing-sim report` take recordings")
            f.seek(0)
            data = f.read()
    except OSError as exc:
        raise SceneError(f"{where}: cannot read it ({exc.strerror or exc.__class__.__name__})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError(f"{where}: not a YAML scene: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset "
                         f"{exc.start}); expected a scene YAML file") from None
    try:
        data = load_yaml(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise SceneError(f"scene {path.name}: not valid YAML{where}: {problem}") from None
    try:
        return scene_from_dict(data, name=path.stem, source_text=text, source_path=str(path))
    except SceneError as exc:
        raise SceneError(f"scene {path.name}: {exc}") from None
