"""Bearing catalog: derived quantities pinned to the seed papers' numbers (PHYSICS_NOTES.md)."""
import math

import numpy as np
import pytest

from bearing_sim_ros.catalog import bearing_from_mapping, catalog_names, get_bearing, hertz_point_contact
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


def test_fault_frequencies_are_the_same_whichever_way_the_shaft_turns():
    """A reversed shaft (a negative speed, which the node and the API accept) strikes a defect as
    often: the frequencies are rates, >= 0.  They came out negative, and the envelope detector,
    looking for lines at negative frequencies, called an inner-race fault "healthy" (the monitor
    too, from the state's signed shaft speed)."""
    from dataclasses import replace

    from bearing_sim_ros import Simulator, load_scene
    from bearing_sim_ros.analysis.envelope import diagnose

    bearing = get_bearing("ER-16K")
    assert bearing.fault_frequencies(-1600 / 60) == bearing.fault_frequencies(1600 / 60)
    scene = load_scene("er16k_inner_race")
    reversed_shaft = replace(scene, shaft_speed=-scene.shaft_speed)
    assert reversed_shaft.fault_frequencies() == scene.fault_frequencies()
    sim = Simulator(reversed_shaft, fidelity="kinematic")
    y = sim.advance(45000).accel[:, 1]
    assert sim.advance(1).cage_speed[0] < 0                 # it does turn the other way
    assert diagnose(y, sim.sample_rate, reversed_shaft.fault_frequencies())["verdict"] == "inner"


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


CUSTOM = {"balls": 9, "ball_diameter_mm": 7.94, "pitch_diameter_mm": 38.5}


def test_custom_bearing_contact_angle_mass_and_inertia():
    """A bearing typed into a scene: the contact angle (degrees) enters the textbook fault
    frequencies n/2 f (1 -+ d cos(a) / D_m); without ball_mass_kg a 7.94 mm steel ball weighs
    2.05 g; a solid ball's moment of inertia about a diameter is 2/5 m r^2."""
    b = bearing_from_mapping("custom", dict(CUSTOM, contact_angle_deg=15.0))
    g = 7.94 / 38.5 * math.cos(math.radians(15.0))
    f = b.fault_frequencies(10.0)
    assert f["bpfo"] == pytest.approx(4.5 * 10.0 * (1 - g), rel=1e-12)
    assert f["bpfi"] == pytest.approx(4.5 * 10.0 * (1 + g), rel=1e-12)
    assert b.ball_mass == pytest.approx(2.05e-3, rel=0.01)
    assert b.ball_inertia == pytest.approx(0.4 * b.ball_mass * (0.5 * b.ball_diameter) ** 2, rel=1e-12)


@pytest.mark.parametrize("mass", [1e-6, 100.0, 0.006, float("nan")])
def test_a_ball_mass_its_volume_cannot_hold_is_refused_in_one_line(mass):
    """``ball_mass_kg`` was held to [1e-6, 100] kg whatever the ball: a 7.94 mm ball of 1 mg ran
    (the skidding solver diverged at 25 700 rpm, 10 N) and one of 100 kg (centrifugal ball loads of
    3e5 x the radial load).  Now its volume at 1000 - 20000 kg/m^3 bounds it, the density key's
    range: 0.26 - 5.2 g for that ball."""
    with pytest.raises(SceneError) as exc:
        bearing_from_mapping("custom", dict(CUSTOM, ball_mass_kg=mass))
    assert str(exc.value) == (f"bearing.ball_mass_kg = {mass!r}: allowed range is [0.0002621, 0.005242] for a ball "
                              f"of 7.94 mm (its volume at 1000 - 20000 kg/m^3)")


def test_the_smallest_ball_the_catalog_allows_takes_its_own_mass():
    """A 0.5 mm ball (the smallest ``ball_diameter_mm``) was refused for the mass it gets by default,
    0.51 mg of steel, below the fixed 1e-6 kg: no such bearing could be given without a mass that
    makes it 15 000 kg/m^3.  Now its default mass, and a silicon nitride one, are taken."""
    small = {"balls": 8, "ball_diameter_mm": 0.5, "pitch_diameter_mm": 2.0}
    assert bearing_from_mapping("small", small).ball_mass == pytest.approx(7850 * math.pi * 0.5e-3 ** 3 / 6)
    assert bearing_from_mapping("small", dict(small, ball_mass_kg=2.1e-7)).ball_mass == 2.1e-7


@pytest.mark.parametrize("change, words", [
    ({"balls": 20}, ["balls = 20", "do not fit", "at most 15"]),
    ({"balls": 2}, ["balls = 2", "[3, 40]"]),
    # a ball as large as the pitch circle: no count fits (was a traceback: asin of d / dm > 1)
    ({"ball_diameter_mm": 40.0}, ["ball_diameter_mm = 40", "not even 3 balls", "33.34 mm"]),
    ({"ball_diameter_mm": 34.0, "balls": 3}, ["ball_diameter_mm = 34", "not even 3 balls"]),
    ({"ball_diameter_mm": -1.0}, ["ball_diameter_mm = -1.0", "allowed range"]),
    ({"poisson_ratio": 0.6}, ["poisson_ratio = 0.6", "[0.0, 0.49]"]),
    # races 20 mm apart radially hold no 7.94 mm ball: D_o - D_i must be close to 2 d
    ({"inner_race_diameter_mm": 30.56, "outer_race_diameter_mm": 70.56},
     ["outer_race_diameter_mm = 70.56", "twice the ball diameter", "15.88"]),
])
def test_impossible_custom_bearing_is_a_one_line_error(change, words):
    with pytest.raises(SceneError) as exc:
        bearing_from_mapping("custom", dict(CUSTOM, **change))
    msg = str(exc.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


def test_contact_ellipse_and_hertz_stiffness_against_the_classical_sphere():
    """The groove's contact ellipse is wider across the groove: a / b = the ellipticity k > 1.
    A circular contact (R_x = R_y = rho, a ball on a flat) has classical Hertz radius
    a^3 = 3 Q rho / (2 E') and Q = (2/3) E' rho^0.5 delta^1.5.  Hamrock-Brewe's curve fits are made
    for elongated contacts: at this end of their range they give a 2.8 % wider contact and an 8.7 %
    stiffer one (k = 1.0339, eps = 1.5971, F = 1.5277 against 1, pi/2, pi/2)."""
    b = get_bearing("ER-16K")
    for contact in (b.inner_contact, b.outer_contact):
        assert contact.ellipticity > 3
        assert contact.a_coeff / contact.b_coeff == pytest.approx(contact.ellipticity, rel=1e-9)
    rho, e_eff = 4e-3, 2.2e11
    c = hertz_point_contact(rho, rho, e_eff)
    radius_coeff = (3 * rho / (2 * e_eff)) ** (1 / 3)
    assert c.a_coeff == pytest.approx(1.028 * radius_coeff, rel=2e-3)
    assert c.b_coeff == pytest.approx(c.a_coeff / 1.0339, rel=1e-9)
    assert c.stiffness == pytest.approx(1.087 * 2 / 3 * e_eff * math.sqrt(rho), rel=1e-3)


def test_contact_radii_are_harris_textbook_values():
    """Effective radii of the two ball-race contacts (Harris, Rolling Bearing Analysis, eqs for a
    deep-groove ball bearing, zero contact angle): rolling direction R_x = d (D_m -+ d) / (2 D_m),
    inner race convex ("-"), outer race concave ("+"); across the groove R_y = f d / (2 f - 1)
    with each race's own conformity f.  A custom bearing with different inner (0.51) and outer
    (0.54) conformities tells the two apart (the catalog bearings have 0.52 on both)."""
    b = bearing_from_mapping("custom", dict(CUSTOM, inner_groove_conformity=0.51, outer_groove_conformity=0.54))
    d, dm = 7.94e-3, 38.5e-3
    assert b.inner_contact.rx == pytest.approx(d * (dm - d) / (2 * dm), rel=1e-12)
    assert b.outer_contact.rx == pytest.approx(d * (dm + d) / (2 * dm), rel=1e-12)
    assert b.inner_contact.ry == pytest.approx(0.51 * d / (2 * 0.51 - 1), rel=1e-12)
    assert b.outer_contact.ry == pytest.approx(0.54 * d / (2 * 0.54 - 1), rel=1e-12)


@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan, 1e300, 9.5])
def test_a_ball_count_that_is_not_a_whole_number_is_a_one_line_error(value):
    """int() of infinity or NaN raised OverflowError / ValueError: the range is checked first."""
    with pytest.raises(SceneError) as exc:
        bearing_from_mapping("custom", dict(CUSTOM, balls=value))
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"bearing.balls = {value!r}: "), msg


def test_cage_and_ball_spin_speeds_are_the_fault_frequencies_in_rad_s():
    """Pure rolling with the outer race fixed (Harris): the cage turns at w / 2 (1 - g) and a ball
    spins relative to the cage at w D_m / (2 d) (1 - g^2), g = d cos(a) / D_m, the FTF and BSF (Hz)
    times 2 pi; a bearing with a 15 deg contact angle tells (1 - g^2) from (1 - g) and cos from none."""
    b = bearing_from_mapping("custom", dict(CUSTOM, contact_angle_deg=15.0))
    g = 7.94 / 38.5 * math.cos(math.radians(15.0))
    w = 2 * math.pi * 25.0
    assert b.cage_speed(w) == pytest.approx(0.5 * w * (1 - g), rel=1e-12)
    assert b.ball_spin_speed(w) == pytest.approx(w * 38.5 / (2 * 7.94) * (1 - g * g), rel=1e-12)
    f = b.fault_frequencies(25.0)
    assert b.cage_speed(w) == pytest.approx(2 * math.pi * f["ftf"], rel=1e-12)
    assert b.ball_spin_speed(w) == pytest.approx(2 * math.pi * f["bsf"], rel=1e-12)


def test_a_custom_bearings_defaults_and_limits_of_fit():
    """What a bearing typed into a scene gets without the optional keys: grooves of conformity
    0.52 (PHYSICS_NOTES), balls of ``density`` (silicon nitride, 3200 kg/m^3: 0.84 g for 7.94 mm);
    as many balls as fit on the pitch circle (15 of 7.94 mm on 38.5 mm: sin(pi / 15) x 38.5 =
    7.99 mm) are taken; races whose radial gap misses twice the ball diameter by more than 5 % of
    a ball (0.5 mm here, 0.4 mm allowed) are refused, 0.3 mm is taken."""
    b = bearing_from_mapping("custom", CUSTOM)
    assert (b.inner_groove_conformity, b.outer_groove_conformity) == (0.52, 0.52)
    ceramic = bearing_from_mapping("custom", dict(CUSTOM, density=3200.0))
    assert ceramic.ball_mass == pytest.approx(3200.0 * math.pi * 7.94e-3 ** 3 / 6, rel=1e-12)
    assert bearing_from_mapping("custom", dict(CUSTOM, balls=15)).balls == 15
    d, dm = 7.94, 38.5
    near = dict(CUSTOM, inner_race_diameter_mm=dm - d, outer_race_diameter_mm=dm + d + 0.3)
    assert bearing_from_mapping("custom", near).outer_race_diameter == pytest.approx((dm + d + 0.3) * 1e-3)
    with pytest.raises(SceneError, match="outer minus inner race diameter must be close to twice the ball diameter"):
        bearing_from_mapping("custom", dict(near, outer_race_diameter_mm=dm + d + 0.5))


def test_a_race_diameter_that_does_not_fit_is_named_by_the_key_given():
    """An inner race diameter typed alone, which leaves no room for the balls, is named: the
    error named outer_race_diameter_mm with its default (pitch plus ball diameter, 46.44 mm),
    a key and a value the user never wrote.  An unknown key in a scene's bearing lists ``name``
    among the allowed ones, which a scene's bearing takes."""
    with pytest.raises(SceneError, match=r"^bearing\.inner_race_diameter_mm = 20: outer minus inner race "
                                         r"diameter must be close to twice the ball diameter \(15\.88 mm"):
        bearing_from_mapping("custom", dict(CUSTOM, inner_race_diameter_mm=20.0))
    from bearing_sim_ros.scene import scene_from_dict

    with pytest.raises(SceneError, match=r"bearing\.bore_mm: unknown key; allowed: .*, name, "):
        scene_from_dict({"bearing": dict(CUSTOM, bore_mm=25.0), "operating_point": {"shaft_speed_rpm": 1000},
                         "structure": {"shaft": {"mass": 1.0, "stiffness": 1e7, "damping": 100},
                                       "pedestal": {"mass": 1.0, "stiffness": 1e8, "damping": 100}}})
