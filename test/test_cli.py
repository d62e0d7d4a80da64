"""``bearing-sim`` as a newcomer meets it: error lines show numbers as a user types them."""
from __future__ import annotations

import math

import pytest

from bearing_sim_ros import Simulator, UserError


def test_non_finite_inputs_are_named_with_plain_numbers():
    sim = Simulator("er16k_outer_race", fidelity="kinematic")
    with pytest.raises(UserError) as speed:
        sim.advance(150, shaft_speed=math.nan)
    with pytest.raises(UserError) as load:
        sim.advance(150, radial_load=(math.nan, 0.0))
    assert str(speed.value) == "shaft_speed = nan rad/s: must be a finite number"
    assert str(load.value) == "radial_load = (nan, 0.0) N: must be finite numbers"
    assert "np." not in str(speed.value) + str(load.value)
