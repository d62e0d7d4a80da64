"""Which tier a scene needs: the cheapest whose estimated error stays under the tolerance.

This first version chooses the skidding tier whenever the scene asks for skidding outputs or a
tier explicitly; the error model of issue 6 refines ``estimated_error``.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Selection:
    tier: str                 # "kinematic" | "skidding"
    reason: str
    estimated_error: float    # estimated relative error of the kinematic tier on what the scene needs
    tolerance: float


def select_tier(scene, request: str, shaft_speed: float, radial_load, tolerance: float) -> Selection:
    if request in ("kinematic", "skidding"):
        return Selection(request, f"requested {request}", float("nan"), tolerance)
    if "skid_ratios" in scene.outputs:
        return Selection("skidding", "scene asks for skid ratios", float("inf"), tolerance)
    return Selection("kinematic", "no skidding outputs requested", 0.0, tolerance)
