"""What a bearing can take: its speed and load limits, from its catalog geometry (no ROS).

The scene loader checks a scene's operating point and every knot of its profile against them
(``scene.py``); the live node checks every ``shaft_speed`` and ``load`` message
(``nodes/bearing_sim_node.py``, README "Inputs: what is accepted").
"""
from __future__ import annotations

import math

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm

# Bounds against absurd values whatever the bearing (a scene's keys, ``Simulator.advance``); a
# bearing's own limits (InputLimits) are tighter but for a very small or very large custom one.
MAX_LOAD = 1.0e6        # N
MAX_SPEED_RPM = 60000.0

# Speed: a speed factor n * d_m (rpm x mm) of 1.0e6 is above the reference speeds that catalogs
# give for oil-lubricated deep-groove ball bearings (0.5-0.8e6); beyond it the pure-rolling
# kinematics this model rests on no longer hold, so such a command is a mistake, not an input.
NDM_LIMIT = 1.0e6              # rpm * mm
# Load: ISO 76 basic static radial load rating C0 = f0 * Z * Dw^2 * cos(alpha) (N, mm) with
# f0 = 14.7, the lowest value of the ISO 76 deep-groove table (gives 8.3 kN for a 6205; the
# catalog says 7.8 kN).  C0 is the load of 4.2 GPa peak contact stress, where permanent
# denting starts; twice C0 is far beyond any working load, so more is rejected.
STATIC_F0 = 14.7
LOAD_MULTIPLE_C0 = 2.0


def bound_text(value: float) -> str:
    """A bound (rpm, rad/s, N) as a message shows it: a whole number rounded down, so that the
    number a user reads and types back is within it (rounded to the nearest, a custom 61820's
    8888.9 rpm showed as 8889, which the same message refused; the shipped 6307's 39748.8 N and
    6205-2RS-SKF's 25614.8 rpm did so too)."""
    return f"{math.floor(value):.0f}"


def load_on_balls(load_x: float, load_y: float, shaft_weight: float, load_z: float = 0.0) -> float:
    """|F| (N) that the balls carry: the radial load (``load_x``, ``load_y`` N, y up; ``load_z``
    axial, which the node's inputs count too) and the shaft's weight (``shaft_weight`` N, acting
    downwards), added as vectors as both tiers add them on the shaft.  Each alone within 2 x C0,
    the two together reached twice that: 16.6 kN down on a 1.7 t shaft put 33 kN on an ER-16K."""
    return math.sqrt(load_x * load_x + (load_y - shaft_weight) ** 2 + load_z * load_z)


class InputLimits:
    """What the bearing of a scene can take: ``max_speed`` (rad/s), ``static_capacity`` C0 and
    ``max_load`` (N).  Derived from the catalog geometry (see the constants above).
    ``shaft_weight`` (N, 0 without gravity): the weight the balls carry besides a load, held with
    it to ``max_load`` (``load_on_balls``)."""

    def __init__(self, bearing, shaft_weight: float = 0.0):
        self.shaft_weight = shaft_weight
        dm_mm = bearing.pitch_diameter * 1e3
        dw_mm = bearing.ball_diameter * 1e3
        self.static_capacity = STATIC_F0 * bearing.balls * dw_mm ** 2 * math.cos(bearing.contact_angle)
        # never beyond what ``Simulator.advance`` takes (a scene's bounds), which only a very
        # small (speed) or very large (load) custom bearing reaches
        self.max_speed = min(NDM_LIMIT / dm_mm, MAX_SPEED_RPM) * RPM
        self.max_load = min(LOAD_MULTIPLE_C0 * self.static_capacity, MAX_LOAD)

    def __str__(self):
        """As the node's start line says it."""
        weight = f", the shaft's weight ({self.shaft_weight:.3g} N) included" if self.shaft_weight else ""
        return (f"shaft speed up to {bound_text(self.max_speed)} rad/s ({bound_text(self.max_speed / RPM)} rpm), "
                f"radial load up to {bound_text(self.max_load)} N{weight} (static capacity C0 "
                f"{self.static_capacity:.0f} N)")

    def __repr__(self):
        return (f"InputLimits(max_speed={self.max_speed:.1f} rad/s, "
                f"static_capacity={self.static_capacity:.0f} N, max_load={self.max_load:.0f} N)")
