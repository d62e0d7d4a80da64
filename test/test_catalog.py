"""Bearing catalog: derived quantities pinned to the seed papers' numbers (PHYSICS_NOTES.md)."""
import math

import numpy as np
import pytest

from bearing_sim_ros.catalog import get_bearing, catalog_names
from bearing_sim_ros.errors import SceneError


def test_er16k_fault_frequencies_seed000():
    f = get_bearing("ER-16K").fault_frequencies(1600 / 60)
    assert f["bpfi"] == pytest.approx(144.8, rel=1e-3)      # seed 000 Table 2
    assert f["bpfo"] == pytest.approx(95.25, rel=1e-3)


def test_6205_fault_frequencies_seed004():
    f = get_bearing("6205").fault_frequencies(1750 / 60)
    assert f["bpfo"] == pytest.approx(104.2, rel=1e-3)
    assert f["bpfi"] == pytest.approx(158.3, rel=1e-3)      # not the misprinted 153.8
    assert f["bsf"] == pytest.approx(67.7, rel=1e-3)        # without the stray factor N


def test_cwru_multiples_of_shaft_speed():
    f = get_bearing("6205-2RS-SKF").fault_frequencies(1.0)
    assert f["bpfi"] == pytest.approx(5.4152, rel=2e-4)
    assert f["bpfo"] == pytest.approx(3.5848, rel=2e-4)
    assert f["ftf"] == pytest.approx(0.39828, rel=2e-4)
    assert 2 * f["bsf"] == pytest.approx(4.7135, rel=2e-4)


def test_6307_bpfi_seed001():
    f = get_bearing("6307").fault_frequencies(1500 / 60)
    assert f["bpfi"] == pytest.approx(122.6, rel=1e-3)
    assert 1 / f["bpfo"] == pytest.approx(0.013, rel=0.01)   # outer-race period


def test_fault_frequencies_scale_with_speed():
    b = get_bearing("ER-16K")
    f1, f2 = b.fault_frequencies(10.0), b.fault_frequencies(25.0)
    for key in f1:
        assert f2[key] == pytest.approx(2.5 * f1[key])


def test_hertz_constant_er16k_matches_hamrock_brewe_estimate():
    # PHYSICS_NOTES: total K about 1e10 N/m^1.5 for ER-16K, conformity 0.52
    b = get_bearing("ER-16K")
    assert 0.8e10 < b.combined_stiffness < 1.2e10
    # the outer (conforming) contact is stiffer than the inner one
    assert b.outer_contact.stiffness > b.inner_contact.stiffness
    # series law: K = (Ki^-2/3 + Ko^-2/3)^-3/2 is below both
    assert b.combined_stiffness < b.inner_contact.stiffness


def test_ball_radial_mode_in_the_stated_band():
    # a 2 g ball between two Hertz contacts: 27.5 kHz at 10 N, 45.3 kHz at 200 N
    b = get_bearing("ER-16K")
    # seed 000 Table 1's 2 g is the steel sphere of 7.94 mm (2.05 g)
    steel_sphere = b.density * math.pi * b.ball_diameter ** 3 / 6
    assert b.ball_mass == pytest.approx(steel_sphere, rel=0.03)
    for load in (10.0, 200.0):
        f_hz = []
        for k in (b.inner_contact.stiffness, b.outer_contact.stiffness):
            delta = (load / k) ** (2 / 3)
            f_hz.append(1.5 * k * math.sqrt(delta))     # tangent stiffness of each contact
        k_tan = sum(f_hz)                                 # the ball sits between both: in parallel
        freq = math.sqrt(k_tan / b.ball_mass) / (2 * math.pi)
        assert 25e3 < freq < 50e3


def test_clearance_convention_eq3_eq4():
    """A ball touches when the race offset equals the radial clearance C_r (seed 000 eq. 4);
    beyond that it carries K * delta^1.5."""
    from bearing_sim_ros.physics.kinematic import bearing_force, P_CR, P_K
    from bearing_sim_ros.scene import load_scene
    from bearing_sim_ros.physics.kinematic import KinematicModel

    scene = load_scene("er16k_healthy")
    model = KinematicModel(scene, 15000.0, 1, 0, scene.shaft_speed, scene.radial_load)
    geo = model.geo.copy()
    geo[8] = 0.0                                           # no slip
    q = np.zeros(scene.bearing.balls)
    cr = geo[P_CR]
    # cage angle that puts ball 0 at the bottom (-pi/2)
    at_clearance = bearing_force(geo, model.cj, model.sj, model.dtab[:0], model.wtab, 0,
                                 0.0, -cr, 0.0, -math.pi / 2, 0.0, q)
    assert at_clearance == (0.0, 0.0)
    delta = 5e-6
    fx, fy = bearing_force(geo, model.cj, model.sj, model.dtab[:0], model.wtab, 0,
                           0.0, -(cr + delta), 0.0, -math.pi / 2, 0.0, q)
    assert q[0] == pytest.approx(geo[P_K] * delta ** 1.5, rel=1e-9)
    assert fy == pytest.approx(-q[0]) and abs(fx) < 1e-9 * q[0]


def test_catalog_lists_the_three_families():
    names = catalog_names()
    for name in ("ER-16K", "6205", "6205-2RS-SKF", "6307"):
        assert name in names


def test_unknown_bearing_is_a_one_line_error():
    with pytest.raises(SceneError) as exc:
        get_bearing("6999")
    msg = str(exc.value)
    assert "6999" in msg and "ER-16K" in msg and "\n" not in msg
