"""Scene loading: every shipped scene loads; every mistake is one line naming key, value and
what is allowed; the CLI turns it into exit status 2 without a traceback."""
import dataclasses
import math
import subprocess
import textwrap

import numpy as np
import pytest
import yaml

from bearing_sim_ros import Simulator
from bearing_sim_ros.errors import SceneError, UserError
from bearing_sim_ros.scene import RPM, ProfilePoint, Waviness, load_scene, load_yaml, scene_from_dict, shipped_scenes

CONTRACT_SCENES = {
    "er16k_healthy", "er16k_inner_race", "er16k_outer_race", "er16k_skidding",
    "cwru_6205_normal", "cwru_6205_ir007", "cwru_6205_or007_6", "cwru_6205_b007",
    "b6307_seed001", "b6205_ball_inner", "b6205_ball_outer", "b6205_inner_outer",
}

GOOD = textwrap.dedent("""\
    bearing: ER-16K
    structure:
      shaft: {mass: 1.0, stiffness: 4.24e4, damping: 1376}
      pedestal: {mass: 2.5, stiffness: 1.51e7, damping: 2210}
    operating_point: {shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}
    defects:
      - {kind: outer, width_mm: 0.6, depth_mm: 0.25, clock: 6}
    """)


def test_contract_scenes_are_shipped_and_load():
    assert CONTRACT_SCENES <= set(shipped_scenes())
    for name in shipped_scenes():
        scene = load_scene(name)
        assert scene.shaft_speed > 0 and scene.bearing.balls >= 3


def test_operating_points_match_the_contract():
    rpm = lambda s: s.shaft_speed * 60 / (2 * math.pi)  # noqa: E731
    s = load_scene("er16k_outer_race")
    assert rpm(s) == pytest.approx(1600) and s.radial_load == (0.0, -50.0)
    d = s.defects[0]
    assert (d.kind, d.width, d.depth) == ("outer", pytest.approx(0.6e-3), pytest.approx(0.25e-3))
    assert d.angle == pytest.approx(-math.pi / 2)          # bottom of the load zone
    s = load_scene("er16k_skidding")
    assert rpm(s) == pytest.approx(2000) and s.radial_load == (0.0, -200.0)
    s = load_scene("cwru_6205_or007_6")
    assert rpm(s) == pytest.approx(1797) and s.defects[0].width == pytest.approx(0.1778e-3)
    s = load_scene("b6205_ball_inner")
    assert rpm(s) == pytest.approx(1750) and s.radial_load == (0.0, -2000.0)
    assert {d.kind for d in s.defects} == {"ball", "inner"}


def test_numbers_in_exponent_form_are_floats(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(GOOD)
    assert load_scene(path).structure.shaft_stiffness == 4.24e4


@pytest.mark.parametrize("old,new,expect", [
    ("bearing: ER-16K", "bearing: ER-99", ["bearing", "ER-99", "ER-16K"]),
    ("mass: 1.0,", "mass: -1.0,", ["structure.shaft.mass", "-1.0", "["]),
    ("mass: 1.0,", "mass: heavy,", ["structure.shaft.mass", "heavy", "number"]),
    ("width_mm: 0.6", "width_mm: 9.0", ["defects[0].width_mm", "9.0", "]"]),
    ("depth_mm: 0.25", "depth_mm: 5.0", ["defects[0].depth_mm", "5.0", "]"]),
    ("kind: outer", "kind: cage", ["defects[0].kind", "cage", "inner, outer, ball"]),
    ("shaft_speed_rpm: 1600", "shaft_speed_rpm: 1e9", ["shaft_speed_rpm", "1000000000", "60000"]),
    ("radial_load: [0.0, -50.0]", "radial_load: [0.0]", ["radial_load", "2 numbers"]),
    ("clock: 6", "clock: 6, colour: red", ["defects[0].colour", "unknown key"]),
    ("width_mm: 0.6", "width_mm: 0", ["defects[0].width_mm", "0", "(0, "]),
    ("operating_point:", "operating_pont:", ["operating_pont", "unknown key"]),
    # a position given twice is refused, not silently taken from one of the two
    ("clock: 6", "clock: 6, angle_deg: 30", ["defects[0]", "clock", "angle_deg", "not both"]),
    # balls are numbered 0 .. 8 on the 9-ball ER-16K: ball 9 would be a defect no ball carries
    ("kind: outer", "kind: ball, ball: 9", ["defects[0].ball", "9", "[0, 8]"]),
    # a ball number on a race defect was ignored (wander_turns there was refused already)
    ("kind: outer", "kind: outer, ball: 3", ["defects[0].ball = 3: only a ball defect is on a ball", "kind outer"]),
    ("kind: outer", "kind: inner, ball: 0", ["defects[0].ball = 0: only a ball defect is on a ball", "kind inner"]),
    # wander_turns: 0 on a race defect was accepted (only a non-zero value was refused)
    ("kind: outer", "kind: outer, wander_turns: 0",
     ["defects[0].wander_turns = 0: only a ball defect has a spin axis to wander", "kind outer"]),
    ("kind: outer", "kind: inner, wander_turns: 2.5",
     ["defects[0].wander_turns = 2.5: only a ball defect has a spin axis to wander", "kind inner"]),
    ("clock: 6}\n", "clock: 6}\nsensor: {axes: [x, z]}\n", ["sensor.axes", "'z'", "x, y"]),
    # a range of 0 m/s^2 would clip every sample to 0
    ("clock: 6}\n", "clock: 6}\nsensor: {range: 0}\n", ["sensor.range", "0", "(0, "]),
    # the film goes as pressure_viscosity^0.49: 0 was a ZeroDivisionError in the kinematic tier
    ("clock: 6}\n", "clock: 6}\nlubrication: {pressure_viscosity: 0}\n",
     ["lubrication.pressure_viscosity = 0: allowed range is (0, 1e-07]"]),
])
def test_bad_scene_is_one_line_naming_key_value_and_allowed(tmp_path, old, new, expect):
    path = tmp_path / "bad.yaml"
    assert old in GOOD
    path.write_text(GOOD.replace(old, new))
    with pytest.raises(SceneError) as exc:
        load_scene(path)
    msg = str(exc.value)
    assert "\n" not in msg
    for piece in expect:
        assert piece in msg, msg


def test_keys_with_a_unit_in_their_name_become_si_and_omitted_ones_take_their_documented_value(tmp_path):
    """A key's suffix is its unit: radial_clearance_um 20 is 20e-6 m (it replaces the catalog's
    45 um), cage_pocket_clearance_um 30 is 30e-6 m, surface_roughness_um 0.1 is 1e-7 m.  A defect
    without length_mm is as long as it is wide (0.6 mm).  A profile knot without a speed or a load
    holds the previous knot's (the operating point's before the first): 1600 rpm is
    1600 * 2 pi / 60 = 167.55 rad/s, not 1600 rad/s and not 167.55 rpm.  Without a fidelity
    section the tier is chosen automatically with a tolerance of 5 % (README)."""
    path = tmp_path / "s.yaml"
    path.write_text("radial_clearance_um: 20\n" + GOOD
                    + "lubrication: {cage_pocket_clearance_um: 30, surface_roughness_um: 0.1}\n"
                    + "profile:\n  - {t: 0.5}\n"
                    + "  - {t: 1.0, shaft_speed_rpm: 2400, radial_load: [10.0, -150.0]}\n  - {t: 1.5}\n")
    scene = load_scene(path)
    assert (scene.fidelity, scene.fidelity_tolerance) == ("auto", 0.05)
    assert scene.bearing.radial_clearance == pytest.approx(20e-6, rel=1e-12)
    assert scene.lubrication.cage_pocket_clearance == pytest.approx(30e-6, rel=1e-12)
    assert scene.lubrication.surface_roughness == pytest.approx(0.1e-6, rel=1e-12)
    assert scene.defects[0].length == pytest.approx(0.6e-3, rel=1e-12)
    knots = [(p.t, p.shaft_speed, p.radial_load) for p in scene.profile]
    assert knots == [(0.5, pytest.approx(1600 * 2 * math.pi / 60), (0.0, -50.0)),
                     (1.0, pytest.approx(2400 * 2 * math.pi / 60), (10.0, -150.0)),
                     (1.5, pytest.approx(2400 * 2 * math.pi / 60), (10.0, -150.0))]


def test_resonator_from_its_frequency_and_damping_ratio(tmp_path):
    """The unit resonator is given as mass, natural frequency and damping ratio; its stiffness
    and damping are the single-degree-of-freedom ones: sqrt(k / m) = 2 pi f (rad/s) and
    c / (2 sqrt(k m)) = zeta (a factor 2 lost in c would halve the damping the scene asks for)."""
    path = tmp_path / "s.yaml"
    path.write_text(GOOD.replace("damping: 2210}", "damping: 2210}\n  resonator: {mass: 0.05, frequency_hz: 4200, "
                                 "damping_ratio: 0.04}"))
    st = load_scene(path).structure
    assert st.has_resonator and st.resonator_mass == 0.05
    assert math.sqrt(st.resonator_stiffness / st.resonator_mass) == pytest.approx(2 * math.pi * 4200, rel=1e-12)
    assert st.resonator_damping / (2 * math.sqrt(st.resonator_stiffness * st.resonator_mass)) == pytest.approx(
        0.04, rel=1e-12)


def test_defect_position_by_clock_or_degrees_and_waviness_phase(tmp_path):
    """Clock positions (12 top, 3 at +x) and degrees become angles counterclockwise from +x (rad,
    up to whole turns); a defect given neither sits at the bottom (-90 deg); a waviness phase in
    degrees is radians."""
    path = tmp_path / "s.yaml"
    for spec, angle in (("clock: 3", 0.0), ("clock: 12", math.pi / 2), ("clock: 4.5", -math.pi / 4),
                        ("angle_deg: 30", math.pi / 6), ("angle_deg: -120", -2 * math.pi / 3)):
        path.write_text(GOOD.replace("clock: 6", spec))
        got = load_scene(path).defects[0].angle
        assert math.remainder(got - angle, 2 * math.pi) == pytest.approx(0.0, abs=1e-12), (spec, got)
    path.write_text(GOOD.replace(", clock: 6", "") + "waviness:\n  - {race: inner, order: 3, amplitude_um: 2, phase_deg: 90}\n")
    scene = load_scene(path)
    assert scene.defects[0].angle == pytest.approx(-math.pi / 2)
    (w,) = scene.waviness
    assert (w.race, w.order, w.amplitude, w.phase) == ("inner", 3, pytest.approx(2e-6), pytest.approx(math.pi / 2))


def test_profile_times_must_increase_strictly(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(GOOD + "profile:\n  - {t: 1.0, shaft_speed_rpm: 1000}\n  - {t: 1.0, shaft_speed_rpm: 2000}\n")
    with pytest.raises(SceneError, match=r"profile\[1\]\.t = 1: times must increase"):
        load_scene(path)


def test_missing_section_and_broken_yaml(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(GOOD.replace("operating_point: {shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}\n", ""))
    with pytest.raises(SceneError, match="operating_point: missing"):
        load_scene(path)
    path.write_text("bearing: [unclosed\n")
    with pytest.raises(SceneError, match="not valid YAML"):
        load_scene(path)
    with pytest.raises(SceneError, match="unknown scene"):
        load_scene("no_such_scene")


@pytest.mark.parametrize("value, kind", [(None, "NoneType"), (3, "int"), (["er16k_healthy"], "list")])
def test_a_scene_that_is_not_a_name_or_path_says_what_was_expected(value, kind):
    """load_scene(None) said "unknown scene 'None'" (str() made any value a name)."""
    message = (f"scene = {value!r}: expected a shipped scene name or the path of a scene YAML "
               f"(str or pathlib.Path), not {kind}")
    with pytest.raises(SceneError) as exc:
        load_scene(value)
    assert str(exc.value) == message
    with pytest.raises(SceneError) as exc:
        Simulator(value)
    assert str(exc.value) == message


def test_cli_bad_scene_exit_2_one_line(tmp_path, bearing_sim_exe):
    path = tmp_path / "bad.yaml"
    path.write_text(GOOD.replace("mass: 1.0,", "mass: -1.0,"))
    out = subprocess.run([bearing_sim_exe, "render", str(path), "--duration", "0.1",
                          "--out", str(tmp_path / "x.mcap")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "structure.shaft.mass" in lines[0] and "Traceback" not in out.stderr


def test_a_folder_given_as_the_scene_is_named_a_folder_not_missing(tmp_path, bearing_sim_exe, ros_env):
    """A folder where a scene file is expected said "no such file" (it exists): the API, render
    and the node say it is a folder, in one line naming the scene and what is allowed."""
    folder = tmp_path / "scenes"
    folder.mkdir()
    start = f"scene = {str(folder)!r}: is a folder, not a file; give a YAML path or one of "
    for load in (load_scene, Simulator):
        with pytest.raises(SceneError) as exc:
            load(folder)
        assert str(exc.value).startswith(start) and "er16k_outer_race" in str(exc.value)
    for argv in (["render", str(folder), "--duration", "0.1", "--out", str(tmp_path / "x.mcap")],
                 ["node", "--ros-args", "-p", f"scene:={folder}"]):
        r = subprocess.run([bearing_sim_exe, *argv], env=ros_env, capture_output=True, text=True, timeout=60)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1 and lines[0].startswith(f"error: {start}"), r.stderr
    assert not (tmp_path / "x.mcap").exists()


def test_a_recording_or_binary_file_as_the_scene_is_not_a_yaml_scene(tmp_path, bearing_sim_exe):
    """A recording where the scene goes (``render run.mcap ...``, both are file arguments) said
    "cannot read it (UnicodeDecodeError: 'utf-8' codec can't decode byte 0x89 ...)": now one line
    that it is not a YAML scene, and for an MCAP file that recordings go to play and report."""
    from std_msgs.msg import Float64

    from bearing_sim_ros.recording.recorder import Recorder

    recording = tmp_path / "run.mcap"
    with Recorder(recording, {"scene": "tiny"}, start_time_ns=0) as rec:
        rec.add_topic("/x", "std_msgs/msg/Float64", 10)
        rec.write("/x", Float64(data=1.0), 0)
    binary = tmp_path / "scene.yaml"
    binary.write_bytes(b"bearing: ER-16K\n\xff\xfe\n")
    expected = {recording: f"scene = {str(recording)!r}: not a YAML scene but an MCAP recording; "
                           "`bearing-sim play` and `bearing-sim report` take recordings",
                binary: f"scene = {str(binary)!r}: not a YAML scene: not UTF-8 text (byte 0xff at offset 16); "
                        "expected a scene YAML file"}
    for path, message in expected.items():
        with pytest.raises(SceneError) as exc:
            load_scene(path)
        assert str(exc.value) == message
    r = subprocess.run([bearing_sim_exe, "render", str(recording), "--duration", "0.1", "--out",
                        str(tmp_path / "x.mcap")], capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stderr) == (2, f"error: {expected[recording]}\n")


def test_cli_scenes_lists_one_line_each(bearing_sim_exe):
    out = subprocess.run([bearing_sim_exe, "scenes"], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0
    names = [ln.split()[0] for ln in out.stdout.splitlines()]
    assert set(names) == set(shipped_scenes())


@pytest.mark.parametrize("text, expect", [
    ("", "scene bad.yaml: bearing: missing (required)"),                        # an empty file
    ("- a\n- b\n", "scene bad.yaml: top level = ['a', 'b']: expected a mapping with keys name, "),
    ("just words\n", "scene bad.yaml: top level = 'just words': expected a mapping"),
    (GOOD + "colour: red\n", "scene bad.yaml: colour: unknown key; allowed: name, "),
    (GOOD.replace("bearing: ER-16K", "bearing: {balls: 9, 8: x}"), "scene bad.yaml: bearing.8: unknown key"),
])
def test_top_level_mistakes_name_the_key_without_a_stray_dot(tmp_path, text, expect):
    """The top level has no path: its keys are named bare ("colour", not ".colour"), a file that
    is not a mapping says so, and a number among a bearing's keys is a key like any other (it
    used to end in a TypeError from sorting str and int keys)."""
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(SceneError) as exc:
        load_scene(path)
    assert str(exc.value).startswith(expect), str(exc.value)


_BALLS = "bearing: {balls: %s, ball_diameter_mm: 7.94, pitch_diameter_mm: 38.5}"
_WHOLE = {   # key -> the scene with %s where its value goes
    "defects[0].ball": GOOD.replace("kind: outer", "kind: ball, ball: %s"),
    "waviness[0].order": GOOD + "waviness:\n  - {race: inner, order: %s, amplitude_um: 1}\n",
    "bearing.balls": GOOD.replace("bearing: ER-16K", _BALLS),
}
_LISTS = {
    "sensor.axes": GOOD + "sensor: {axes: %s}\n",
    "operating_point.radial_load": GOOD.replace("[0.0, -50.0]", "%s"),
    "fidelity.outputs": GOOD + "fidelity: {outputs: %s}\n",
}


@pytest.mark.parametrize("key, value", [(k, v) for k in _WHOLE for v in (
    ".inf", "-.inf", ".nan", "1e300", "[[1]]", "{a: 1}", "x", "true", "null")] + [(k, v) for k in _LISTS for v in (
    "[[1]]", "[{a: 1}]", "[.inf, 1]", "[.nan, 1]", "x", "{a: 1}", "null")])
def test_a_value_of_the_wrong_kind_is_one_line_not_a_traceback(key, value):
    """A whole number given as infinity or NaN, or a list of names holding a list or a mapping,
    is refused in one line naming the key: int(.inf) raised OverflowError, int(.nan) ValueError,
    set() of [[1]] TypeError (the type and range are checked before the value is converted)."""
    text = (_WHOLE.get(key) or _LISTS[key]) % value
    with pytest.raises(SceneError) as exc:
        scene_from_dict(load_yaml(text))
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith((f"{key} = ", f"{key}: missing")), msg


def test_a_catalog_name_that_yaml_reads_as_a_number_is_that_bearing():
    """`bearing: 6205` unquoted is the int 6205 to YAML; it names the catalog's 6205 (it said
    "expected a catalog name").  A number the catalog does not have is an unknown bearing."""
    scene = scene_from_dict(load_yaml(GOOD.replace("bearing: ER-16K", "bearing: 6205")))
    assert scene.bearing.name == "6205" and scene.bearing.balls == 9
    with pytest.raises(SceneError, match=r"^bearing = '6999': unknown bearing; catalog has .*6205"):
        scene_from_dict(load_yaml(GOOD.replace("bearing: ER-16K", "bearing: 6999")))


@pytest.mark.parametrize("text, line", [
    (GOOD + "defects:\n  - {kind: inner, width_mm: 0.6, depth_mm: 0.25}\n",
     "not valid YAML at line 8: key 'defects' appears twice (lines 6 and 8); give it once"),
    (GOOD.replace("damping: 1376}", "damping: 1376, mass: 2.0}"),
     "not valid YAML at line 3: key 'mass' appears twice on line 3; give it once"),
])
def test_a_key_given_twice_is_refused_naming_it_and_its_lines(tmp_path, text, line):
    """PyYAML keeps the last of two equal keys: a second defects: block silently dropped the
    first.  A repeated key is a one-line error; a merge (<<: *base) may still override a key."""
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(SceneError) as exc:
        load_scene(path)
    assert str(exc.value) == f"scene bad.yaml: {line}"
    merged = load_yaml("base: &b {mass: 1.0, stiffness: 2.0}\nshaft: {<<: *b, mass: 3.0}\n")
    assert merged["shaft"] == {"mass": 3.0, "stiffness": 2.0}


def test_a_long_value_is_shortened_in_the_error():
    """A 20 000-entry radial_load was echoed whole: a 100 kB "one line".  Long lists, mappings
    and strings are cut with "..."; the key and the rule stay."""
    load = "[" + ", ".join(["1.0"] * 20000) + "]"
    for text, start, rule in (
            (GOOD.replace("[0.0, -50.0]", load), "operating_point.radial_load = [1.0, 1.0, ", "2 numbers"),
            (GOOD + "fidelity: {tier: " + "k" * 10000 + "}\n", "fidelity.tier = 'kkk", "allowed values are auto"),
            (GOOD.replace("bearing: ER-16K", "bearing: {balls: " + load + ", ball_diameter_mm: 7.94, "
                          "pitch_diameter_mm: 38.5}"), "bearing.balls = [1.0, ", "number")):
        with pytest.raises(SceneError) as exc:
            scene_from_dict(load_yaml(text))
        msg = str(exc.value)
        assert msg.startswith(start) and "..." in msg and rule in msg and len(msg) < 300, msg[:400]


@pytest.mark.parametrize("old, new, line", [
    # 2 x C0 = 2 x 14.7 x 9 x 7.94^2 = 16681 N on the ER-16K: a scene ran with 900 kN
    ("radial_load: [0.0, -50.0]", "radial_load: [0, -900000]",
     "operating_point.radial_load = [0, -900000] N: |F| = 900000 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
    ("radial_load: [0.0, -50.0]", "radial_load: [12000, -12000]",
     "operating_point.radial_load = [12000, -12000] N: |F| = 16970.6 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
    # n d_m <= 1e6 rpm mm: 25974 rpm on its 38.5 mm pitch circle
    ("shaft_speed_rpm: 1600", "shaft_speed_rpm: -30000",
     "operating_point.shaft_speed_rpm = -30000: beyond what bearing ER-16K takes (|speed| <= 25974 rpm, "
     "n*dm <= 1e+06 rpm mm)"),
    # every knot of a profile, named by its own key
    ("clock: 6}\n", "clock: 6}\nprofile:\n  - {t: 1, shaft_speed_rpm: 2000}\n  - {t: 2, radial_load: [0, -20000]}\n",
     "profile[1].radial_load = [0, -20000] N: |F| = 20000 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
    ("clock: 6}\n", "clock: 6}\nprofile:\n  - {t: 1, shaft_speed_rpm: 2000}\n  - {t: 2, shaft_speed_rpm: 26000}\n",
     "profile[1].shaft_speed_rpm = 26000: beyond what bearing ER-16K takes (|speed| <= 25974 rpm, "
     "n*dm <= 1e+06 rpm mm)"),
    # a bearing too big for 2 x C0 to bind: the scene's own bound of 1 MN on |F|
    ("bearing: ER-16K", "bearing: {balls: 12, ball_diameter_mm: 150, pitch_diameter_mm: 1000}\n"
     "radial_clearance_um: 10", None),
])
def test_the_operating_point_and_profile_are_within_the_bearings_limits(old, new, line):
    """The live node refuses a speed above n d_m = 1e6 rpm mm and a load above 2 x C0 on its
    topics (InputLimits); a scene asking for the same was run.  Just inside the limits loads."""
    text = GOOD.replace(old, new)
    if line is None:
        text = text.replace("1600, radial_load: [0.0, -50.0]", "500, radial_load: [-900000, -900000]")
        line = ("operating_point.radial_load = [-900000, -900000] N: |F| = 1.27279e+06 N beyond 1e+06 N, "
                "the most a scene may ask for")
    with pytest.raises(SceneError) as exc:
        scene_from_dict(load_yaml(text))
    assert str(exc.value) == line
    inside = scene_from_dict(load_yaml(GOOD.replace("shaft_speed_rpm: 1600", "shaft_speed_rpm: 25970")
                                       .replace("[0.0, -50.0]", "[11790, -11790]")))
    assert inside.radial_load == (11790.0, -11790.0)


@pytest.mark.parametrize("change, line", [
    ({"radial_load": (0.0, -900000.0)},
     "radial_load = [0, -900000] N: |F| = 900000 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
    ({"shaft_speed": 30000 * RPM},
     "shaft_speed = 3141.59 rad/s (30000 rpm): beyond what bearing ER-16K takes (|speed| <= 25974 rpm, "
     "n*dm <= 1e+06 rpm mm)"),
    ({"profile": (ProfilePoint(1.0, 2000 * RPM, (0.0, -50.0)), ProfilePoint(2.0, 2000 * RPM, (0.0, -20000.0)))},
     "profile[1].radial_load = [0, -20000] N: |F| = 20000 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
    ({"shaft_speed": float("nan")}, "shaft_speed = nan: expected a finite number, rad/s"),
    ({"radial_load": "0 -50"}, "radial_load = '0 -50': expected two finite numbers (x, y), N"),
])
def test_a_scene_changed_in_python_is_held_to_the_bearings_limits(change, line):
    """``dataclasses.replace(scene, radial_load=...)``, the Python API's way to another operating
    point, skipped the limits that load_scene applies: a Simulator ran the ER-16K at 900 kN.  Now
    the scene itself refuses, in the YAML's words with the Python field's name and unit, and a
    Simulator never sees it; within the limits (a numpy load too) it runs."""
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError) as exc:
        Simulator(dataclasses.replace(scene, **change), fidelity="kinematic")
    assert str(exc.value) == f"scene er16k_outer_race: {line}"
    inside = dataclasses.replace(scene, shaft_speed=25970 * RPM, radial_load=np.array([11790.0, -11790.0]))
    assert Simulator(inside, fidelity="kinematic").advance(150).accel.shape == (150, 2)


@pytest.mark.parametrize("change, line", [
    ({"width": -1e-3}, "defects[0].width = -0.001 m: allowed range is (0, 0.00671952] m"),
    ({"width": float("nan")}, "defects[0].width = nan m: allowed range is (0, 0.00671952] m"),
    ({"width": 0.6, "length": 0.6}, "defects[0].width = 0.6 m: allowed range is (0, 0.00671952] m"),
    ({"depth": "0.25e-3"}, "defects[0].depth = '0.25e-3': expected a number in (0, 0.00397] m"),
    ({"length": 0.0}, "defects[0].length = 0 m: allowed range is (0, 0.015] m"),
    ({"kind": "bogus"}, "defects[0].kind = 'bogus': allowed values are inner, outer, ball"),
    ({"profile": "square"},
     "defects[0].profile = 'square': allowed values are geometric, rectangular, half_sine, piecewise, auto"),
    ({"angle": float("inf")}, "defects[0].angle = inf rad: allowed range is [-6.28319, 6.28319] rad"),
    ({"wander_turns": 3.0}, "defects[0].wander_turns = 3.0: only a ball defect has a spin axis to wander "
                            "(this one is kind outer)"),
    ({"kind": "ball", "ball": 9}, "defects[0].ball = 9: expected a whole number in [0, 8]"),
    ({"onset": -1.0}, "defects[0].onset = -1 s: allowed range is [0, 1e+06] s"),
])
def test_a_defect_changed_in_python_is_held_to_the_yamls_limits(change, line):
    """A defect-size sweep by ``dataclasses.replace(scene.defects[0], width=...)`` skipped every
    check that load_scene applies to ``width_mm``: a negative or NaN width ran as a healthy
    bearing, a width given in mm by mistake (0.6 for 0.6 mm) as a 0.6 m pit that clipped the
    sensor, and an unknown kind failed deep in the physics with a KeyError.  Now the scene refuses
    it in one line, in the Python field's name and SI unit, with the YAML's bounds; within them it
    runs."""
    scene = load_scene("er16k_outer_race")
    defect = dataclasses.replace(scene.defects[0], **change)
    with pytest.raises(SceneError) as exc:
        Simulator(dataclasses.replace(scene, defects=(defect,)), fidelity="kinematic")
    assert str(exc.value) == f"scene er16k_outer_race: {line}"


def test_a_defect_changed_in_python_within_the_limits_runs():
    scene = load_scene("er16k_outer_race")
    wider = dataclasses.replace(scene.defects[0], width=1.2e-3, length=1.2e-3, onset=0.001)
    ball = dataclasses.replace(scene.defects[0], kind="ball", ball=8, wander_turns=3.0)
    sim = Simulator(dataclasses.replace(scene, defects=[wider, ball]), fidelity="kinematic")
    assert np.isfinite(sim.advance(150).accel).all()


@pytest.mark.parametrize("change, line", [
    (lambda s: {"bearing": s.bearing.with_clearance(float("nan"))},
     "bearing.radial_clearance = nan m: allowed range is [-5e-05, 0.0005] m"),
    (lambda s: {"bearing": s.bearing.with_clearance(45.0)},
     "bearing.radial_clearance = 45 m: allowed range is [-5e-05, 0.0005] m"),
    (lambda s: {"random_slip": -1.0}, "random_slip = -1: allowed range is [0, 0.05]"),
    (lambda s: {"random_slip": float("nan")}, "random_slip = nan: allowed range is [0, 0.05]"),
    (lambda s: {"fidelity": "skiding"}, "fidelity = 'skiding': allowed values are auto, kinematic, skidding"),
    (lambda s: {"fidelity_tolerance": 0.0}, "fidelity_tolerance = 0: allowed range is [0.0001, 1]"),
    (lambda s: {"gravity": "no"}, "gravity = 'no': expected True or False"),
])
def test_a_scenes_clearance_slip_and_tier_changed_in_python_are_held_to_the_yamls_limits(change, line):
    """A clearance sweep by ``scene.bearing.with_clearance(...)`` ran a NaN clearance to NaN
    samples without a word and a clearance in um by mistake (45) as 45 m; a negative or NaN
    ``random_slip`` and a misspelt ``fidelity`` ran as something else.  Now the scene refuses
    them in one line with the YAML's bounds (``radial_clearance_um``, ``random_slip``,
    ``fidelity.tier``, ``fidelity.tolerance``) in SI units."""
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError) as exc:
        Simulator(dataclasses.replace(scene, **change(scene)), fidelity="kinematic")
    assert str(exc.value) == f"scene er16k_outer_race: {line}"
    inside = dataclasses.replace(scene, bearing=scene.bearing.with_clearance(-5e-6), random_slip=0.02)
    assert np.isfinite(Simulator(inside, fidelity="kinematic").advance(150).accel).all()


def test_a_shaft_heavier_than_the_bearing_takes_is_refused_in_one_line():
    """structure.shaft.mass goes to 1e5 kg for every bearing, and its weight rests on the balls on
    top of the radial load, which is held to 2 x C0: a 100 t shaft on an ER-16K put 480 kN on one
    ball in both tiers (29 x the limit).  Now the weight is held to the same limit, the YAML naming
    its key, a scene changed in Python its field; with gravity off, or a lighter shaft, it runs."""
    data = load_yaml(GOOD)
    data["structure"]["shaft"]["mass"] = 1e5
    with pytest.raises(SceneError) as exc:
        scene_from_dict(data, name="heavy")
    assert str(exc.value) == ("structure.shaft.mass = 100000 kg: its weight, 980665 N, is beyond 2 x C0 = 16681 N of "
                              "bearing ER-16K (gravity: false leaves the weight out)")
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError, match=r"^scene er16k_outer_race: structure.shaft_mass = 2000 kg: its weight, "
                                         r"19613.3 N, is beyond 2 x C0 = 16681 N of bearing ER-16K"):
        dataclasses.replace(scene, structure=dataclasses.replace(scene.structure, shaft_mass=2000.0))
    heavy = dataclasses.replace(scene.structure, shaft_mass=1e5)
    dataclasses.replace(scene, structure=heavy, gravity=False)
    data["gravity"] = False
    scene_from_dict(data, name="weightless")
    light = dataclasses.replace(scene, structure=dataclasses.replace(scene.structure, shaft_mass=1000.0))
    assert np.isfinite(Simulator(light, fidelity="kinematic").advance(150).accel).all()


def test_a_load_and_a_shaft_weight_within_the_bound_each_but_not_together_are_refused_in_one_line():
    """The radial load and the shaft's weight were each held to 2 x C0, not together: a 1 t
    shaft (9.8 kN) under 10 kN downwards put 19.8 kN on the balls of an ER-16K and ran.  Their
    vector sum, as both tiers add them, is held to the bound now: the operating point and every
    profile knot, in the YAML (its keys) and changed in Python (the fields), and the simulator's
    commands; upwards the weight takes load off, and without gravity the load alone counts."""
    data = load_yaml(GOOD)
    data["structure"]["shaft"]["mass"] = 1000.0
    data["operating_point"]["radial_load"] = [0.0, -10000.0]
    with pytest.raises(SceneError) as exc:
        scene_from_dict(data, name="heavy")
    assert str(exc.value) == (
        "operating_point.radial_load = [0, -10000] N with structure.shaft.mass = 1000 kg (its weight 9806.65 N "
        "downwards): |F| on the balls = 19806.7 N beyond 2 x C0 = 16681 N of bearing ER-16K "
        "(gravity: false leaves the weight out)")
    data["operating_point"]["radial_load"] = [0.0, -5000.0]
    data["profile"] = [{"t": 0.0}, {"t": 1.0, "radial_load": [3000.0, -9000.0]}]
    with pytest.raises(SceneError, match=r"^profile\[1\]\.radial_load = \[3000, -9000\] N with structure\.shaft\.mass "
                                         r"= 1000 kg .*: \|F\| on the balls = 19044\.4 N beyond 2 x C0 = 16681 N"):
        scene_from_dict(data, name="heavy")
    data["profile"][1]["radial_load"] = [0.0, 10000.0]          # upwards: 197 N on the balls
    scene_from_dict(data, name="lifted")
    data["gravity"] = False
    data["profile"][1]["radial_load"] = [0.0, -10000.0]
    scene_from_dict(data, name="weightless")

    scene = load_scene("er16k_outer_race")
    heavy = dataclasses.replace(scene.structure, shaft_mass=1000.0)
    with pytest.raises(SceneError, match=r"^scene er16k_outer_race: radial_load = \[0, -10000\] N with "
                                         r"structure\.shaft_mass = 1000 kg \(its weight 9806\.65 N downwards\): "
                                         r"\|F\| on the balls = 19806\.7 N beyond 2 x C0 = 16681 N of bearing ER-16K"):
        dataclasses.replace(scene, structure=heavy, radial_load=(0.0, -10000.0))
    knots = (ProfilePoint(0.0, scene.shaft_speed, (0.0, -50.0)), ProfilePoint(1.0, scene.shaft_speed, (0.0, -9000.0)))
    with pytest.raises(SceneError, match=r"^scene er16k_outer_race: profile\[1\]\.radial_load = \[0, -9000\] N with "):
        dataclasses.replace(scene, structure=heavy, profile=knots)
    sim = Simulator(dataclasses.replace(scene, structure=heavy), fidelity="kinematic")
    with pytest.raises(UserError, match=r"^radial_load = \[0, -10000\] N with the scene's structure\.shaft_mass = "
                                        r"1000 kg .*: \|F\| on the balls = 19806\.7 N beyond 2 x C0"):
        sim.advance(150, radial_load=(0.0, -10000.0))
    assert np.isfinite(sim.advance(150, radial_load=(0.0, -5000.0)).accel).all()


def test_a_clearance_at_the_edges_of_its_bounds_written_in_m_is_taken():
    """``scene.bearing.with_clearance(-50e-6)``, the preload the YAML's ``radial_clearance_um:
    -50`` allows, was refused with "radial_clearance = -5e-05 m: allowed range is [-5e-05, 0.0005]
    m" (the bound was -50 x 1e-6, one bit above -50e-6).  Both ends are taken, in m as in um;
    beyond them, refused."""
    scene = load_scene("er16k_outer_race")
    for clearance in (-50e-6, -50 * 1e-6, 500e-6, 500 * 1e-6):
        dataclasses.replace(scene, bearing=scene.bearing.with_clearance(clearance))
    for clearance in (-50.001e-6, 500.001e-6):
        with pytest.raises(SceneError, match=r"radial_clearance = .* m: allowed range is \[-5e-05, 0\.0005\] m"):
            dataclasses.replace(scene, bearing=scene.bearing.with_clearance(clearance))


@pytest.mark.parametrize("section, change, line", [
    ("structure", {"shaft_mass": 0.0}, "structure.shaft_mass = 0 kg: allowed range is [0.001, 100000] kg"),
    # the generic range's lower end is the pedestal rule's (below it: the next test)
    ("structure", {"pedestal_stiffness": 2e12},
     "structure.pedestal_stiffness = 2e+12 N/m: allowed range is [166813, 1e+12] N/m"),
    ("structure", {"shaft_damping": "1376"}, "structure.shaft_damping = '1376': expected a number in [0, 1e+08] N s/m"),
    ("structure", {"resonator_mass": 1e-6},
     "structure.resonator_mass = 1e-06 kg: allowed 0 (no resonator) or [0.0001, 1000] kg"),
    ("structure", {"resonator_stiffness": 1.0}, "structure.resonator_stiffness = 1 N/m: allowed range is "
                                                "[197.392, 4.9348e+09] N/m (10 - 50000 Hz with resonator_mass 0.05 kg)"),
    ("lubrication", {"viscosity": -1.0}, "lubrication.viscosity = -1: allowed range is [0.0001, 10]"),
    ("lubrication", {"surface_roughness": 0.05},
     "lubrication.surface_roughness = 0.05 m: allowed range is [1e-09, 5e-06] m"),
    ("lubrication", {"ehl_film": "yes"}, "lubrication.ehl_film = 'yes': expected True or False"),
    ("lubrication", {"pressure_viscosity": 0.0}, "lubrication.pressure_viscosity = 0: allowed range is (0, 1e-07]"),
    ("lubrication", {"traction_b": 2.0},
     "lubrication.traction_a .. traction_d (A = -0.1, B = 2, C = 0.2, D = 0.1): the traction curve (A + B v) "
     "exp(-C v) + D reaches |mu| = 3.74 at a slip of 5.05 m/s; allowed at most 1 (dry steel on steel is about "
     "0.6, lubricated contacts 0.02 - 0.1)"),
    ("sensor", {"axes": ("z",)}, "sensor.axes = ('z',): expected a list of distinct axes from x, y"),
    ("sensor", {"range": 0.0}, "sensor.range = 0 m/s^2: allowed range is (0, 1e+07] m/s^2"),
    ("sensor", {"resonance_hz": float("inf")}, "sensor.resonance_hz = inf Hz: allowed range is [0, 200000] Hz"),
])
def test_a_scenes_structure_lubrication_and_sensor_changed_in_python_are_held_to_the_yamls_limits(
        section, change, line):
    """``dataclasses.replace(scene, structure=dataclasses.replace(scene.structure, shaft_mass=0))``
    failed deep in the physics with a ZeroDivisionError, a NaN stiffness with numpy's LinAlgError,
    and a sensor axis "z" or a range of 0 ran (labelled accel_z; every sample clipped to 0).  Now
    the scene refuses them in one line, in the Python field's name and SI unit, with the bounds
    of the YAML's keys; within them it runs."""
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError) as exc:
        Simulator(dataclasses.replace(scene, **{section: dataclasses.replace(getattr(scene, section), **change)}),
                  fidelity="kinematic")
    assert str(exc.value) == f"scene er16k_outer_race: {line}"


def test_a_scenes_structure_lubrication_and_sensor_within_the_limits_run():
    """Every shipped scene meets its own bounds made in Python (the YAML's resonator frequency
    and damping ratio, turned into a stiffness and a damping, stay within them to the last
    bit), and changes within them run."""
    for name in shipped_scenes():
        load_scene(name)
    scene = load_scene("er16k_outer_race")
    changed = dataclasses.replace(scene, structure=dataclasses.replace(scene.structure, shaft_mass=2.0,
                                                                       resonator_mass=0.0),
                                  sensor=dataclasses.replace(scene.sensor, axes=("y",)),
                                  lubrication=dataclasses.replace(scene.lubrication, viscosity=0.1))
    batch = Simulator(changed, fidelity="kinematic").advance(150)
    assert batch.accel_channels == ("accel_y",) and np.isfinite(batch.accel).all()


@pytest.mark.parametrize("curve, said", [
    ({"traction_b": 10.0}, "reaches |mu| = 18.5 at a slip of 5.01 m/s; allowed at most 1"),   # each key in bounds
    ({"traction_a": 1.0, "traction_d": 0.5}, "reaches |mu| = 1.5 at a slip of 0 m/s; allowed at most 1"),
    ({"traction_a": 0.0, "traction_b": 0.1, "traction_c": 0.0}, "reaches |mu| = 10.1 at a slip of 100 m/s; allowed "
                                                                "at most 1"),                       # no end
    ({"traction_a": -1.0, "traction_b": 0.0, "traction_c": 0.0, "traction_d": 0.0},
     "falls to mu = -1 at a slip of 0 m/s; allowed at least 0 (traction opposes the slip"),
    ({"traction_d": 0.0}, "falls to mu = -0.1 at a slip of 0 m/s; allowed at least 0"),   # the ER-16K's less its D
    ({"traction_a": 0.0, "traction_b": -0.05, "traction_c": 1.0, "traction_d": 0.0},
     "falls to mu = -0.0184 at a slip of 1 m/s; allowed at least 0"),                     # below 0 where it turns
])
def test_a_traction_curve_beyond_dry_friction_or_below_0_is_refused_in_one_line(curve, said, tmp_path):
    """Each traction key within its bounds, the curve could peak at mu = 18 (B = 10) or start at
    1.5, and the skidding solver diverged: ``SolverDiverged``, a traceback and "internal error"
    (a helper's finding).  Now the YAML (and a scene changed in Python) is refused where the
    curve's |mu| passes 1 over slips up to 100 m/s, naming the four keys; 1 runs (below).  Nor
    may it fall below 0 (a traction that drives the slip: at mu = -1 the default and the reference
    solver diverged at every operating point tried, 2000 and 25 974 rpm, 10 N to 16.7 kN); the
    shipped curves, 0 at zero slip, load."""
    data = load_yaml(GOOD)
    data.setdefault("lubrication", {}).update(curve)
    path = tmp_path / "curve.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(SceneError) as exc:
        load_scene(str(path))
    assert str(exc.value).startswith("scene curve.yaml: lubrication.traction_a .. traction_d (") and (
        said in str(exc.value)), str(exc.value)
    for name in shipped_scenes():
        assert load_scene(name).lubrication.traction_least() == (0.0, 0.0)


def test_a_traction_curve_at_the_limit_runs_on_the_skidding_tier():
    """The curves at |mu| = 1 that the limit lets through run finite where one at 1.43 diverged
    (10000 rpm, 10 N: the most slip of the ER-16K scenes)."""
    scene = load_scene("er16k_skidding")
    for curve in ({"traction_a": 0.5, "traction_b": 0.0, "traction_d": 0.5},        # 1.0 at zero slip
                  {"traction_b": 0.49}):                                           # 0.97 at 5.2 m/s
        lub = dataclasses.replace(scene.lubrication, **curve)
        assert 0.95 < lub.traction_extreme()[0] <= 1.0
        sim = Simulator(dataclasses.replace(scene, lubrication=lub, shaft_speed=10000 * 2 * np.pi / 60,
                                            radial_load=(0.0, -10.0)), fidelity="skidding")
        batch = sim.advance(1500)                                                  # 0.1 s
        assert np.isfinite(batch.accel).all() and np.isfinite(batch.cage_speed).all()


def test_a_yaml_resonator_at_the_edges_of_its_bounds_loads():
    """A YAML resonator at the edges of frequency_hz and damping_ratio loads: the stiffness and
    damping computed from them are within what the scene's own check allows (sqrt(k / m) need
    not give back 2 pi f to the last bit)."""
    for mass in (1e-4, 0.05, 1e3):
        for frequency, ratio in ((10.0, 0.0), (50000.0, 1.0), (3333.3, 1.0), (10.0, 1.0)):
            data = load_yaml(GOOD)
            data["structure"]["resonator"] = {"mass": mass, "frequency_hz": frequency, "damping_ratio": ratio}
            assert scene_from_dict(data, name="edge").structure.has_resonator


@pytest.mark.parametrize("waviness, line", [
    (Waviness("inner", 3, float("nan")), "waviness[0].amplitude = nan m: allowed range is [0, 2e-05] m"),
    (Waviness("inner", 3, 1.0), "waviness[0].amplitude = 1 m: allowed range is [0, 2e-05] m"),
    (Waviness("middle", 3, 1e-6), "waviness[0].race = 'middle': allowed values are inner, outer"),
    (Waviness("outer", 2.5, 1e-6), "waviness[0].order = 2.5: expected a whole number in [1, 200]"),
    (Waviness("outer", 0, 1e-6), "waviness[0].order = 0: expected a whole number in [1, 200]"),
    (Waviness("outer", 3, 1e-6, float("inf")), "waviness[0].phase = inf rad: allowed range is [-6.28319, 6.28319] rad"),
])
def test_a_scenes_waviness_changed_in_python_is_held_to_the_yamls_limits(waviness, line):
    """``dataclasses.replace(scene, waviness=(Waviness("inner", 3, nan),))`` ran to NaN samples in
    the kinematic tier (the skidding tier: SolverDiverged), an amplitude of 1 m likewise, and a
    race "middle" or an order 2.5 ran as something else.  Now one line, the YAML's bounds in SI
    units; within them it runs."""
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError) as exc:
        dataclasses.replace(scene, waviness=(waviness,))
    assert str(exc.value) == f"scene er16k_outer_race: {line}"
    wavy = dataclasses.replace(scene, waviness=[Waviness("outer", 200, 20e-6, -6.0), Waviness("inner", np.int64(1), 0)])
    assert np.isfinite(Simulator(wavy, fidelity="kinematic").advance(150).accel).all()


def test_a_scene_changed_in_python_holds_tuples_and_compares():
    """A scene given a numpy load or lists (``dataclasses.replace(scene, radial_load=np.array(...),
    defects=[...])``, which the README's Python API takes) holds them as tuples of numbers, as
    load_scene makes them: ``scene == other`` raised numpy's "truth value of an array ... is
    ambiguous" (and so did render's check that a scene is as loaded), and ``hash(scene)``
    "unhashable type: 'numpy.ndarray'"."""
    scene = load_scene("er16k_outer_race")
    same = dataclasses.replace(scene, radial_load=np.array([0.0, -50.0]), defects=list(scene.defects),
                               outputs=list(scene.outputs),
                               profile=[ProfilePoint(1.0, np.float64(100.0), np.array([0.0, -60.0]))])
    assert same.radial_load == (0.0, -50.0) and type(same.radial_load[1]) is float
    assert isinstance(same.defects, tuple) and isinstance(same.outputs, tuple) and isinstance(same.profile, tuple)
    assert same.profile[0].radial_load == (0.0, -60.0)
    assert same == dataclasses.replace(scene, profile=same.profile) and hash(same) == hash(same)


@pytest.mark.parametrize("change, line", [
    (lambda s: {"defects": s.defects[0]},
     r"defects = Defect\(kind='outer', .*: expected a tuple of bearing_sim_ros.scene.Defect"),
    (lambda s: {"waviness": Waviness("inner", 3, 1e-6)},
     r"waviness = Waviness\(race='inner', .*: expected a tuple of bearing_sim_ros.scene.Waviness"),
    (lambda s: {"profile": ((0.5, 100.0, (0.0, -50.0)),)},
     r"profile\[0\] = \(0.5, 100.0, \(0.0, -50.0\)\): expected a bearing_sim_ros.scene.ProfilePoint "
     r"\(t s, shaft_speed rad/s, radial_load \(x, y\) N\)"),
    (lambda s: {"profile": (ProfilePoint(1.0, 100.0, (0.0, -50.0)), ProfilePoint(0.5, 100.0, (0.0, -50.0)))},
     r"profile\[1\].t = 0.5 s: times must increase \(previous 1\)"),
    (lambda s: {"profile": (ProfilePoint(-1.0, 100.0, (0.0, -50.0)),)},
     r"profile\[0\].t = -1 s: allowed range is \[0, 1e\+06\] s"),
    (lambda s: {"outputs": ("accel", "skid_ratio")},
     r"outputs = \('accel', 'skid_ratio'\): expected a list from accel, contact_forces, cage_speed, skid_ratios"),
])
def test_a_scenes_lists_changed_in_python_are_checked(change, line):
    """A scene's defects, waviness, profile and outputs set in Python: a lone Defect for a tuple
    of them was "TypeError: 'Defect' object is not iterable", a knot given as a plain tuple an
    AttributeError, knots out of order or before 0 were taken as given (the YAML refuses them),
    and a misspelt output ("skid_ratio") ran the kinematic tier without the skid ratios the scene
    asked for, without a word.  Now one line each, as the YAML's keys have it."""
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError, match=rf"^scene er16k_outer_race: {line}$"):
        dataclasses.replace(scene, **change(scene))
    fine = dataclasses.replace(scene, defects=list(scene.defects), outputs=["accel", "skid_ratios"],
                               profile=[ProfilePoint(0.0, 100.0, (0.0, -50.0)), ProfilePoint(1.0, 150.0, (0.0, -60.0))])
    assert Simulator(fine).tier == "skidding"


@pytest.mark.parametrize("change, line", [
    ({"ball_mass": -1.0}, "bearing.ball_mass_kg = -1.0: allowed range is [0.0002621, 0.005242] for a ball of "
                          "7.94 mm (its volume at 1000 - 20000 kg/m^3)"),
    ({"elastic_modulus": 0.0}, "bearing.elastic_modulus_gpa = 0.0: allowed range is [1.0, 1000.0]"),
    ({"inner_groove_conformity": 0.4}, "bearing.inner_groove_conformity = 0.4: allowed range is [0.505, 0.6]"),
    ({"ball_diameter": float("nan")}, "bearing.ball_diameter_mm = nan: allowed range is [0.5, 200.0]"),
    ({"balls": 0}, "bearing.balls = 0: allowed range is [3, 40]"),
    ({"balls": 9.0}, "bearing.balls = 9.0: expected a whole number (int) in [3, 40]"),
])
def test_a_bearing_changed_in_python_is_held_to_the_catalogs_limits(change, line):
    """``dataclasses.replace(scene, bearing=dataclasses.replace(scene.bearing, ball_mass=-1.0))``
    was a "math domain error" inside the physics, an elastic modulus of 0 a ZeroDivisionError, a
    NaN ball diameter a message about the defect's depth.  Now the catalog's own check, in its
    units, in one line; a bearing within it (numpy's int for the balls too) runs."""
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError) as exc:
        dataclasses.replace(scene, bearing=dataclasses.replace(scene.bearing, **change))
    assert str(exc.value) in (f"scene er16k_outer_race: {line}",
                              f"scene er16k_outer_race: {line} (a Bearing checked in the catalog's units: mm, deg, GPa)")
    other = dataclasses.replace(scene.bearing, balls=np.int64(8), contact_angle=math.radians(45.0), ball_mass=0.004)
    assert np.isfinite(Simulator(dataclasses.replace(scene, bearing=other), fidelity="kinematic").advance(150).accel).all()


@pytest.mark.parametrize("old, new, line", [
    ("clock: 6}\n", "clock: 6}\nwaviness:\n  - {race: inner, order: 2.5, amplitude_um: 1}\n",
     "waviness[0].order = 2.5: expected a whole number in [1, 200]"),
    ("kind: outer, width_mm: 0.6", "kind: ball, ball: 1.5, width_mm: 0.6",
     "defects[0].ball = 1.5: expected a whole number in [0, 8]"),
])
def test_a_fraction_where_a_whole_number_goes_is_refused_not_truncated(old, new, line):
    """A waviness order of 2.5 or a defect on ball 1.5 is a mistake, refused in one line; int()
    would have made them order 2 and ball 1 without a word."""
    with pytest.raises(SceneError) as exc:
        scene_from_dict(load_yaml(GOOD.replace(old, new)))
    assert str(exc.value) == line


def test_a_scene_exactly_at_the_bearings_limits_runs():
    """The limits are inclusive ("up to", as the node's check_speed and check_load): a speed of
    exactly n d_m = 1e6 rpm mm and a load of exactly 2 x C0 (no gravity, so nothing adds to it)
    are a scene that runs; a hair more is not."""
    from bearing_sim_ros.limits import InputLimits

    scene = dataclasses.replace(load_scene("er16k_outer_race"), gravity=False)
    limits = InputLimits(scene.bearing)
    assert limits.max_speed == pytest.approx(1e6 / 38.5 * RPM, rel=1e-12)
    assert limits.max_load == pytest.approx(2 * 14.7 * 9 * 7.94 ** 2, rel=1e-12)
    edge = dataclasses.replace(scene, shaft_speed=-limits.max_speed, radial_load=(0.0, -limits.max_load))
    assert edge.radial_load == (0.0, -limits.max_load)
    for beyond in ({"shaft_speed": -limits.max_speed * (1 + 1e-12)},
                   {"radial_load": (0.0, -limits.max_load * (1 + 1e-12))}):
        with pytest.raises(SceneError, match="beyond"):
            dataclasses.replace(edge, **beyond)


def test_a_contact_angle_changed_in_python_is_held_to_45_degrees():
    """A Bearing holds its contact angle in rad and is checked in the catalog's degrees (0 - 45):
    50 deg (0.873 rad) is refused as 50 deg, not taken for 0.873 deg; 45 deg runs (the test
    above)."""
    scene = load_scene("er16k_outer_race")
    said = r"bearing\.contact_angle_deg = 50(\.0)?: allowed range is \[0(\.0)?, 45(\.0)?\]"
    with pytest.raises(SceneError, match=said):
        dataclasses.replace(scene, bearing=dataclasses.replace(scene.bearing, contact_angle=math.radians(50.0)))


def test_sensor_axes_in_any_order_are_x_then_y():
    """``sensor.axes: [y, x]`` is the two axes in the contract's channel order (accel_x, accel_y:
    INTERFACE.md), not a table whose first column is the vertical one."""
    scene = scene_from_dict(load_yaml(GOOD + "sensor: {axes: [y, x]}\n"))
    assert scene.sensor.axes == ("x", "y")
    assert Simulator(scene, fidelity="kinematic").accel_channels == ("accel_x", "accel_y")


def test_a_profile_changed_in_python_must_have_increasing_times():
    """Two knots at one time in a profile made in Python are refused as the YAML's are (a jump
    of speed or load in no time)."""
    scene = load_scene("er16k_outer_race")
    knots = (ProfilePoint(1.0, 1000 * RPM, (0.0, -50.0)), ProfilePoint(1.0, 2000 * RPM, (0.0, -50.0)))
    with pytest.raises(SceneError) as exc:
        dataclasses.replace(scene, profile=knots)
    assert str(exc.value) == "scene er16k_outer_race: profile[1].t = 1 s: times must increase (previous 1)"


def test_a_critically_damped_resonator_at_the_yamls_bound_loads():
    """``damping_ratio: 1.0`` is within the YAML's bound; the scene's own check recomputes the
    ratio from the stiffness and damping it became, where sqrt(k / m) can come back one bit
    below 2 pi f (0.05 kg at 3000 Hz): such a scene loads, at a ratio of 1 to 1e-12."""
    text = GOOD.replace("damping: 2210}", "damping: 2210}\n  resonator: {mass: 0.05, frequency_hz: 3000, "
                                          "damping_ratio: 1.0}")
    st = scene_from_dict(load_yaml(text)).structure
    assert st.resonator_damping / (2 * math.sqrt(st.resonator_stiffness * st.resonator_mass)) == pytest.approx(
        1.0, rel=1e-12)


def test_the_shafts_weight_on_the_balls_is_there_only_with_gravity():
    """``Scene.shaft_weight`` (what the node's limits add to a load) is m g with gravity and 0
    without: a 1 kg ER-16K shaft weighs 9.80665 N."""
    scene = load_scene("er16k_outer_race")
    assert scene.gravity and scene.shaft_weight == pytest.approx(scene.structure.shaft_mass * 9.80665, rel=1e-12)
    assert dataclasses.replace(scene, gravity=False).shaft_weight == 0.0


def test_a_scene_without_sensor_slip_or_gravity_keys_takes_the_documented_defaults():
    """README: the sensor saturates at +-50 g (490.3 m/s^2) "unless it says otherwise" and its
    frame is ``bearing_accel``; an omitted sensor is ideal (no resonance, no noise) on both axes
    in x, y order; no ``random_slip`` is no jitter of the ball passes and no ``gravity`` key
    is the shaft's weight acting."""
    scene = scene_from_dict(load_yaml(GOOD))
    s = scene.sensor
    assert (s.axes, s.resonance_hz, s.noise_density, s.frame_id) == (("x", "y"), 0.0, 0.0, "bearing_accel")
    assert s.range == pytest.approx(50 * 9.80665, abs=0.05)
    assert scene.random_slip == 0.0 and scene.gravity is True


def test_an_operating_point_without_a_load_is_the_shafts_weight_alone():
    """README: ``operating_point.radial_load`` is [0, 0] N when omitted (the balls then carry the
    shaft's weight alone, with gravity on), while ``shaft_speed_rpm`` is required."""
    scene = scene_from_dict(load_yaml(GOOD.replace(", radial_load: [0.0, -50.0]", "")))
    assert scene.radial_load == (0.0, 0.0)
    with pytest.raises(SceneError, match="operating_point.shaft_speed_rpm"):
        scene_from_dict(load_yaml(GOOD.replace("shaft_speed_rpm: 1600, ", "")))


# a user's own bearings, typed into a scene: a thin-section 61820-like one (pitch 112.5 mm:
# n*dm = 1e6 rpm mm at 8888.9 rpm) and the shipped catalog's CWRU 6205 and 6307, whose limits,
# 25614.8 rpm and 39748.8 N, are not whole numbers either
_THIN = {"balls": 20, "ball_diameter_mm": 7.938, "pitch_diameter_mm": 112.5, "width_mm": 13.0}


def _scene_doc(bearing, rpm, load):
    return {"bearing": bearing, "operating_point": {"shaft_speed_rpm": rpm, "radial_load": [0.0, -load]},
            "structure": {"shaft": {"mass": 10.0, "stiffness": 1e7, "damping": 4000},
                          "pedestal": {"mass": 20.0, "stiffness": 5e8, "damping": 2e4}},
            "gravity": False}


@pytest.mark.parametrize("bearing", [_THIN, "6205-2RS-SKF", "6307"], ids=["61820-like", "6205-2RS-SKF", "6307"])
def test_the_limit_a_refusal_names_is_a_value_the_bearing_takes(bearing):
    """The speed and load bound that a refusal names, typed back into the scene, is taken: they
    were rounded to the nearest whole number, so that '|speed| <= 8889 rpm' refused 8889 rpm on
    a 61820-like bearing (and 25615 rpm on the CWRU 6205, 39749 N on the 6307)."""
    import re

    with pytest.raises(SceneError) as speed_error:
        scene_from_dict(_scene_doc(bearing, 60000, 100.0))
    rpm = float(re.search(r"\|speed\| <= (\d+) rpm", str(speed_error.value)).group(1))
    with pytest.raises(SceneError) as load_error:
        scene_from_dict(_scene_doc(bearing, 1000, 1e6))
    load = float(re.search(r"2 x C0 = (\d+) N", str(load_error.value)).group(1))
    scene = scene_from_dict(_scene_doc(bearing, rpm, load))
    assert scene.shaft_speed == pytest.approx(rpm * RPM)
    assert scene.radial_load == (0.0, -load)
    # and the live node's input checks, in rad/s and N
    from bearing_sim_ros.limits import InputLimits
    from bearing_sim_ros.nodes.bearing_sim_node import check_load, check_speed

    limits = InputLimits(scene.bearing)
    speed = float(re.search(r"\|speed\| <= (\d+) rad/s", check_speed(1e9, limits)[1]).group(1))
    load = float(re.search(r"C0 = (\d+) N", check_load(0.0, -1e7, 0.0, limits)[1]).group(1))
    assert check_speed(speed, limits) is None and check_load(0.0, -load, 0.0, limits) is None


def _pedestal_least() -> float:
    """The least pedestal stiffness (N/m) that an ER-16K takes: its 2 x C0, 16681 N, within 0.1 m."""
    from bearing_sim_ros.limits import InputLimits

    return InputLimits(load_scene("er16k_healthy").bearing).max_load / 0.1


@pytest.mark.parametrize("stiffness", [0.0, 1e-9, 0.5, 100.0, 0.999 * _pedestal_least(), -5.0, math.nan])
def test_a_pedestal_spring_too_soft_to_hold_the_bearings_load_is_refused_in_one_line(stiffness, tmp_path):
    """A pedestal spring of 1e-9 - 1 N/m under the ER-16K's 50 N put the outer race metres away;
    the kinematic tier's samples were NaN from the first (render wrote them and said exit status
    0), and at 100 N/m both tiers' clipped at the sensor's range from the start.  None (0) left
    the balls without load: the kinematic tier was silent and the skidding tier rang for a
    quarter of a second while the pedestal fell with the shaft.  A pedestal spring holds the
    pedestal within 0.1 m under the most load the bearing takes (2 x C0, which the live node's
    inputs may reach); a YAML scene and one changed in Python are refused in one line naming the
    key, the value and that bound.  A negative or NaN spring gets the same line: it was told the
    generic range, [0, 1e+12], whose 0 this rule refuses."""
    path = tmp_path / "soft.yaml"
    path.write_text(GOOD.replace("stiffness: 1.51e7", f"stiffness: {'.nan' if math.isnan(stiffness) else repr(stiffness)}"))
    allowed = ("N/m: allowed at least 1.668e+05 N/m, which holds the pedestal within 0.1 m under "
               "2 x C0 = 16681 N of bearing ER-16K (0, no spring, would leave the balls without load)")
    with pytest.raises(SceneError) as exc:
        load_scene(path)
    assert str(exc.value) == f"scene soft.yaml: structure.pedestal.stiffness = {stiffness:g} {allowed}"
    scene = load_scene("er16k_outer_race")
    with pytest.raises(SceneError) as exc:
        dataclasses.replace(scene, structure=dataclasses.replace(scene.structure, pedestal_stiffness=stiffness))
    assert str(exc.value) == f"scene er16k_outer_race: structure.pedestal_stiffness = {stiffness:g} {allowed}"


def test_a_pedestal_spring_at_the_bound_runs_finite(tmp_path):
    """The least pedestal stiffness allowed loads, and runs finite in both tiers."""
    stiffness = _pedestal_least()
    path = tmp_path / "ok.yaml"
    path.write_text(GOOD.replace("stiffness: 1.51e7", f"stiffness: {stiffness!r}"))
    scene = load_scene(path)
    for fidelity in ("kinematic", "skidding"):
        assert np.isfinite(Simulator(scene, fidelity=fidelity).advance(300).accel).all()
