"""``bearing-sim render``: every message reads back with two independent readers, the file says
how it was made, the same seed gives the same bytes, profiles drive the operating point, and user
mistakes end with exit status 2 and one line."""
from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from test_node_support import read_recording, rendering_until_stopped, signal_when, stop_render

from bearing_sim_ros import Simulator, UserError, cli, load_scene
from bearing_sim_ros.recording.reader import get_message, open_recording
from bearing_sim_ros.recording.render import profile_at, render
from bearing_sim_ros.scene import RPM
from bearing_sim_ros.waveform import NS, from_pointcloud2

FS = 15000.0


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    out = tmp_path_factory.mktemp("render") / "a.mcap"
    summary = render("er16k_outer_race", 2.0, out, fidelity="kinematic", seed=5, progress=False)
    return out, summary


def test_every_message_reads_back_with_rosbags(rendered):
    from rosbags.highlevel import AnyReader

    path, summary = rendered
    counts = {}
    accel = []
    with AnyReader([path]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        for conn, t, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)      # raises on any unreadable message
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
            if conn.topic == "/accel":
                accel.append(from_pointcloud2(msg))
    assert types == {"/accel": "sensor_msgs/msg/PointCloud2", "/contact_forces": "sensor_msgs/msg/PointCloud2",
                     "/state": "sensor_msgs/msg/JointState", "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
                     "/shaft_speed": "std_msgs/msg/Float64", "/load": "geometry_msgs/msg/WrenchStamped"}
    # 2 s at 100 batches/s; state at 50 Hz; diagnostics once per simulated second
    assert counts == {"/accel": 200, "/contact_forces": 200, "/state": 100, "/diagnostics": 2,
                      "/shaft_speed": 200, "/load": 200}
    assert sum(counts.values()) == summary["messages"]
    # the waveform tables are contiguous: stamp(k+1) = stamp(k) + width / fs, from 0
    stamps = np.array([a[0] for a in accel])
    widths = np.array([a[2].shape[0] for a in accel])
    assert stamps[0] == 0 and widths.sum() == 2 * FS
    assert np.all(np.abs(np.diff(stamps) - widths[:-1] * NS / FS) <= 1)


def test_state_angles_are_those_at_the_stamp(rendered):
    """Read back independently, each ``/state`` gives the shaft and the cage where they are at
    its stamp (steady 1600 rpm from angle 0, the kinematic tier's pure-rolling cage), not 19
    samples later, where the physics is (0.21 rad of the shaft before 2026-11-29)."""
    from rosbags.highlevel import AnyReader

    path, _ = rendered
    scene = load_scene("er16k_outer_race")
    w = scene.shaft_speed
    cage = scene.bearing.cage_speed(w)
    n = 0
    with AnyReader([path]) as reader:
        for conn, _t, raw in reader.messages([c for c in reader.connections if c.topic == "/state"]):
            msg = reader.deserialize(raw, conn.msgtype)
            t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            assert msg.position[0] == pytest.approx(w * t, abs=1e-6)
            assert msg.position[1] == pytest.approx(cage * t, abs=1e-6)
            assert msg.velocity[:2] == pytest.approx([w, cage], rel=1e-12)
            n += 1
    assert n == 100


def test_every_message_reads_back_with_mcap_and_rclpy(rendered):
    from rclpy.serialization import deserialize_message

    path, _ = rendered
    with open_recording(path) as rec:
        assert rec.header.profile == "ros2"
        meta = rec.metadata
        n = 0
        for topic, msg_type, t, data in rec.messages():
            msg = deserialize_message(data, get_message(msg_type))
            if topic == "/state":
                assert list(msg.name[:2]) == ["shaft", "cage"]
                assert msg.header.stamp.sec * NS + msg.header.stamp.nanosec == t
            n += 1
        assert n == rec.message_count
        for info in rec.channels.values():
            assert "reliability: reliable" in info.qos_yaml
    scene = load_scene("er16k_outer_race")
    assert meta["scene"] == "er16k_outer_race" and meta["scene_yaml"] == scene.source_text
    assert meta["seed"] == "5" and meta["tier"] == "kinematic"
    assert meta["package_version"]
    params = rec.parameters()
    assert params["duration"] == 2.0 and params["sample_rate"] == FS and params["fidelity"] == "kinematic"
    assert "bearing-sim render er16k_outer_race" in params["command"]
    assert params["oversample"] == 0 and "--oversample" not in params["command"]   # each tier's own


def test_the_metadata_names_each_topics_role_and_recorded_channel(rendered):
    """``topics`` in the metadata maps each role to the channel it is recorded on: a render
    recorded ``{"accel": "accel", "/diagnostics": "/diagnostics", ...}``, names that are no
    channel of the file (``/accel``) and a role with a slash.  Read with the mcap library and
    rosbags, not the project's reader."""
    import json

    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader

    path, _ = rendered
    with open(path, "rb") as f:
        meta = next(m.metadata for m in make_reader(f).iter_metadata() if m.name == "bearing_sim")
    with AnyReader([path]) as reader:
        channels = {c.topic: c.msgtype for c in reader.connections}
    roles = json.loads(meta["topics"])
    assert roles == {"accel": "/accel", "contact_forces": "/contact_forces", "state": "/state",
                     "diagnostics": "/diagnostics", "shaft_speed": "/shaft_speed", "load": "/load"}
    assert set(roles.values()) == set(channels)


def test_oversample_reaches_the_simulator_and_the_metadata(rendered, tmp_path):
    """``--oversample`` changes the integration (another signal) and says so in the file."""
    path, _ = rendered
    out = tmp_path / "x4.mcap"
    render("er16k_outer_race", 2.0, out, fidelity="kinematic", seed=5, progress=False, oversample=4)
    with open_recording(out) as rec:
        params = rec.parameters()
        assert params["oversample"] == 4 and "--oversample 4" in params["command"]
        mine = [data for topic, _, _, data in rec.messages() if topic == "/accel"]
    with open_recording(path) as rec:
        shipped = [data for topic, _, _, data in rec.messages() if topic == "/accel"]
    assert len(mine) == len(shipped) > 0 and mine != shipped


def test_same_seed_same_bytes_other_seed_other_signal(rendered, tmp_path):
    path, _ = rendered
    again = tmp_path / "b.mcap"
    other = tmp_path / "c.mcap"
    render("er16k_outer_race", 2.0, again, fidelity="kinematic", seed=5, progress=False)
    render("er16k_outer_race", 2.0, other, fidelity="kinematic", seed=6, progress=False)
    assert Path(path).read_bytes() == again.read_bytes()
    assert Path(path).read_bytes() != other.read_bytes()


def test_profile_drives_the_operating_point(tmp_path):
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64

    text = load_scene("er16k_inner_race").source_text + (
        "profile:\n"
        "  - {t: 0.2, shaft_speed_rpm: 1600}\n"
        "  - {t: 0.7, shaft_speed_rpm: 2400, radial_load: [0.0, -150.0]}\n")
    scene_path = tmp_path / "ramp.yaml"
    scene_path.write_text(text)
    scene = load_scene(scene_path)
    assert profile_at(scene, 0.45)[0] == pytest.approx(2000 * RPM)
    assert profile_at(scene, 0.45)[1] == pytest.approx((0.0, -100.0))
    out = tmp_path / "ramp.mcap"
    render(scene_path, 1.0, out, fidelity="kinematic", progress=False)
    with open_recording(out) as rec:
        speeds = [(t, deserialize_message(d, Float64).data) for _, _, t, d in rec.messages(["/shaft_speed"])]
        state = [deserialize_message(d, JointState) for _, _, _, d in rec.messages(["/state"])]
    # the command recorded at the start of each batch is the profile at the batch's end
    for t, w in speeds:
        assert w == pytest.approx(profile_at(scene, t / NS + 0.01)[0], rel=1e-12)
    assert speeds[0][1] == pytest.approx(1600 * RPM) and speeds[-1][1] == pytest.approx(2400 * RPM)
    # the simulated shaft follows: 1600 rpm before the ramp, 2400 rpm after it
    shaft = np.array([s.velocity[0] for s in state]) * 60 / (2 * math.pi)
    assert shaft[5] == pytest.approx(1600, rel=1e-6) and shaft[-1] == pytest.approx(2400, rel=1e-6)
    assert np.all(np.diff(shaft) >= -1e-9)


def _one_line_error(capsys, argv):
    code = cli.main(argv)
    err = capsys.readouterr().err.strip()
    return code, err


def test_scene_error_and_bad_output_exit_2_with_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(load_scene("er16k_healthy").source_text.replace("shaft_speed_rpm: 1600", "shaft_speed_rpm: fast"))
    code, err = _one_line_error(capsys, ["render", str(bad), "--duration", "1", "--out", str(tmp_path / "x.mcap")])
    assert code == 2 and len(err.splitlines()) == 1 and "shaft_speed_rpm" in err and "fast" in err
    code, err = _one_line_error(capsys, ["render", "no_such_scene", "--duration", "1", "--out", str(tmp_path / "x.mcap")])
    assert code == 2 and len(err.splitlines()) == 1 and "er16k_outer_race" in err
    code, err = _one_line_error(capsys, ["render", "er16k_healthy", "--duration", "1",
                                         "--out", str(tmp_path / "nodir" / "x.mcap")])
    assert code == 2 and len(err.splitlines()) == 1 and "cannot write there" in err
    # it named render's temporary file ('.../nodir/x.mcap.<pid>.partial: No such file or
    # directory'), not the folder to create
    assert f"its folder '{tmp_path / 'nodir'}' does not exist; create it first)" in err and ".partial" not in err, err
    assert not (tmp_path / "x.mcap").exists()
    # a folder that takes no files (/proc, even for root): it named the temporary file too
    code, err = _one_line_error(capsys, ["render", "er16k_healthy", "--duration", "1", "--out", "/proc/x.mcap"])
    assert (code, err) == (2, "error: --out = '/proc/x.mcap': cannot write there (No such file or directory)"), err


@pytest.mark.parametrize("extra, message", [
    # said "oversample = 3: ...", the Python API's name, not the option's
    (["--oversample", "3"],
     "bearing-sim render: argument --oversample: 3: allowed values are 1, 2 or a multiple of 4 up to 64"),
    (["--oversample", "x"], "bearing-sim render: argument --oversample: 'x' is not a whole number"),
    (["--oversample", "8"], "--oversample = 8: with --fidelity auto allowed values are 1, 2 or 4 "
                            "(or choose --fidelity kinematic or skidding)"),
    (["--fidelity", "skidding", "--solver", "reference", "--oversample", "8"],
     "--oversample = 8: --solver reference keeps its own step; --oversample applies to the kinematic "
     "tier and --solver default only"),
])
def test_oversample_mistakes_name_the_option(tmp_path, capsys, extra, message):
    out = tmp_path / "x.mcap"
    code, err = _one_line_error(capsys, ["render", "er16k_healthy", "--duration", "0.1", "--out", str(out), *extra])
    assert code == 2 and err == f"error: {message}", err
    assert not out.exists()


def test_console_script_renders_and_reports_exit_2_for_a_bad_scene(bearing_sim_exe, tmp_path, ros_env):
    out = tmp_path / "cli.mcap"
    ok = subprocess.run([bearing_sim_exe, "render", "er16k_healthy", "--duration", "0.5", "--out", str(out),
                         "--fidelity", "kinematic"], env=ros_env, capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0, ok.stderr
    assert "x real time" in ok.stdout and ok.stderr == ""     # no progress bar without a terminal
    assert open_recording(out).message_count > 0
    bad = subprocess.run([bearing_sim_exe, "render", str(tmp_path / "missing.yaml"), "--duration", "1",
                          "--out", str(out)], env=ros_env, capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "Traceback" not in bad.stderr


def _recorded_command(path) -> list:
    """The reproducing command of a recording, as argv for ``cli.main`` (without ``bearing-sim``)."""
    import shlex

    with open_recording(path) as rec:
        argv = shlex.split(rec.parameters()["command"])
    assert argv[:2] == ["bearing-sim", "render"]
    return argv[1:]


def test_the_recorded_command_of_a_scene_file_reproduces_it_from_another_folder(tmp_path, monkeypatch, capsys):
    """A scene given as a (relative) YAML path is recorded as its absolute path, not as the
    ``name:`` inside it, which no command can load; run from elsewhere, the command gives the
    same bytes."""
    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    work.mkdir()
    elsewhere.mkdir()
    text = load_scene("er16k_healthy").source_text.replace("name: er16k_healthy", "name: my_rig")
    (work / "rig.yaml").write_text(text)
    monkeypatch.chdir(work)
    assert cli.main(["render", "rig.yaml", "--duration", "0.2", "--fidelity", "kinematic", "--seed", "3",
                     "--out", "first.mcap"]) == 0
    argv = _recorded_command(work / "first.mcap")
    assert str(work / "rig.yaml") in argv and "my_rig" not in argv
    monkeypatch.chdir(elsewhere)
    assert cli.main(argv + ["--out", "again.mcap"]) == 0, capsys.readouterr().err
    assert (elsewhere / "again.mcap").read_bytes() == (work / "first.mcap").read_bytes()


def test_solver_with_the_kinematic_tier_asked_for_is_one_line(tmp_path, capsys):
    out = tmp_path / "k.mcap"
    code, err = _one_line_error(capsys, ["render", "er16k_outer_race", "--duration", "0.1", "--fidelity",
                                         "kinematic", "--solver", "rk4", "--out", str(out)])
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "--solver rk4" in err and "skidding tier only" in err and "--fidelity kinematic" in err
    assert not out.exists()


def test_the_kinematic_tier_on_a_scene_that_asks_for_skid_ratios_says_they_are_missing(tmp_path, capsys):
    """``er16k_skidding`` asks for skid ratios; ``--fidelity kinematic`` dropped them without a
    word.  The printed line and the recorded tier reason now say so; a scene that does not ask
    for them reads as before."""
    from bearing_sim_ros.recording.reader import open_recording as read

    for scene, said in (("er16k_skidding", True), ("er16k_healthy", False)):
        out = tmp_path / f"{scene}.mcap"
        assert cli.main(["render", scene, "--duration", "0.1", "--fidelity", "kinematic", "--out", str(out)]) == 0
        line = capsys.readouterr().out
        assert ("(kinematic tier; no skid ratios: the scene asks for them, the skidding tier computes them)"
                in line) == said, line
        with read(out) as rec:
            reason = rec.metadata["tier_reason"]
        assert reason.startswith("kinematic requested: no skid ratios") == said, reason


def test_solver_unused_by_auto_is_said_and_not_recorded(tmp_path, capsys):
    """Auto keeps er16k_outer_race on the kinematic tier: ``--solver reference`` changes nothing,
    the printed line says so, and the file is the default's to the byte (its command names no
    solver).  Its parameters name no solver either (they said ``"solver": "default"``, which did
    not run: the kinematic tier has none).  Read with the mcap library."""
    import json

    from mcap.reader import make_reader

    plain, asked = tmp_path / "plain.mcap", tmp_path / "asked.mcap"
    assert cli.main(["render", "er16k_outer_race", "--duration", "0.2", "--out", str(plain)]) == 0
    capsys.readouterr()
    assert cli.main(["render", "er16k_outer_race", "--duration", "0.2", "--solver", "reference",
                     "--out", str(asked)]) == 0
    line = capsys.readouterr().out
    assert "kinematic tier; --solver applies to the skidding tier only" in line
    assert "--solver" not in " ".join(_recorded_command(asked))
    assert asked.read_bytes() == plain.read_bytes()
    with open(asked, "rb") as f:
        meta = next(m.metadata for m in make_reader(f).iter_metadata() if m.name == "bearing_sim")
    params = json.loads(meta["parameters"])
    assert params["solver"] is None and params["rk4_step"] is None and meta["tier"] == "kinematic"


def test_solver_kept_when_a_profile_takes_auto_to_the_skidding_tier(tmp_path, capsys):
    """At 10000 rpm without load auto picks the skidding tier, so there the solver runs: it is
    recorded with its step, and the recorded command reproduces the file."""
    text = load_scene("er16k_outer_race").source_text + (
        "profile:\n  - {t: 0.01, shaft_speed_rpm: 10000, radial_load: [0.0, 0.0]}\n")
    scene_path = tmp_path / "fast.yaml"
    scene_path.write_text(text)
    out = tmp_path / "fast.mcap"
    assert cli.main(["render", str(scene_path), "--duration", "0.02", "--solver", "rk4", "--rk4-step", "2e-6",
                     "--out", str(out)]) == 0
    assert "skidding tier at the end: 1 switch, the last kinematic -> skidding at 0.000 s)" in capsys.readouterr().out
    argv = _recorded_command(out)
    assert " ".join(argv).endswith("--solver rk4 --rk4-step 2e-06")
    with open_recording(out) as rec:
        assert rec.parameters()["rk4_step"] == 2e-6 and rec.parameters()["solver"] == "rk4"
    assert cli.main(argv + ["--out", str(tmp_path / "again.mcap")]) == 0
    assert (tmp_path / "again.mcap").read_bytes() == out.read_bytes()


@pytest.mark.parametrize("extra, words", [
    (["--rk4-step", "5e-6"], ["--rk4-step = 5e-06 s", "--solver rk4 only"]),
    (["--solver", "rk4", "--rk4-step", "0"], ["--rk4-step", "0 s", "[1e-09, 0.001] s"]),
    (["--solver", "rk4", "--rk4-step=-1e-6"], ["--rk4-step", "-1e-6 s", "[1e-09, 0.001] s"]),
    (["--sample-rate", "500"], ["--sample-rate", "500 Hz", "[1000, 200000] Hz"]),
    (["--sample-rate", "250000"], ["--sample-rate", "250000 Hz", "[1000, 200000] Hz"]),
    # 11025 Hz (CD audio's quarter) is in range, but a 10 ms table would be 110.25 samples: the
    # error named batch_duration, which render has no option for, and not what --sample-rate takes
    (["--sample-rate", "11025"], ["--sample-rate", "11025 Hz", "multiples of 100 Hz", "10 ms"]),
    # a typo that would render until the disk is full: the node's bound on duration
    (["--duration", "1e12"], ["--duration", "'1e12'", "<= 1e+09"]),
])
def test_rk4_step_and_sample_rate_mistakes_are_one_line(tmp_path, capsys, extra, words):
    out = tmp_path / "x.mcap"
    code, err = _one_line_error(capsys, ["render", "er16k_skidding", "--duration", "0.1", "--fidelity", "skidding",
                                         "--out", str(out), *extra])
    assert code == 2 and len(err.splitlines()) == 1, err
    for w in words:
        assert w in err, err
    assert not out.exists()


def test_sample_rate_range_is_the_nodes():
    """One range for the API, ``render --sample-rate`` and the node's ``sample_rate``."""
    from bearing_sim_ros.nodes.bearing_sim_node import _descriptors
    from bearing_sim_ros.simulator import SAMPLE_RATE_RANGE

    span = _descriptors()["sample_rate"][1].floating_point_range[0]
    assert (span.from_value, span.to_value) == SAMPLE_RATE_RANGE
    for outside in (SAMPLE_RATE_RANGE[0] - 1, SAMPLE_RATE_RANGE[1] + 1):
        with pytest.raises(UserError, match=r"sample_rate = .*\[1000, 200000\] Hz"):
            Simulator("er16k_healthy", sample_rate=outside)


@pytest.mark.parametrize("duration", [True, 0, -1.0, math.inf, "1"])
def test_a_duration_that_is_not_seconds_is_refused_in_one_line(tmp_path, duration):
    """render(scene, True, out) was one second of signal (bool is an int); the rest were refused,
    in the API's words (they named the CLI's --duration, an option a Python caller never gave)."""
    out = tmp_path / "x.mcap"
    with pytest.raises(UserError) as exc:
        render("er16k_healthy", duration, out, fidelity="kinematic", progress=False)
    assert str(exc.value) == f"duration = {duration!r}: expected a finite number of seconds > 0"
    assert not out.exists()


@pytest.mark.parametrize("kwargs, api, cli_args, cli", [
    ({"duration": 1e-5}, "duration = 1e-05 s: shorter than one sample", ["--duration", "1e-5"],
     "--duration = 1e-05 s: shorter than one sample"),
    ({"rk4_step": 5e-6}, "rk4_step = 5e-06 s: applies to solver='rk4' only (given solver='default')",
     ["--rk4-step", "5e-6"], "--rk4-step = 5e-06 s: applies to --solver rk4 only (given --solver default)"),
    ({"solver": "rk4", "rk4_step": 2e-6, "fidelity": "kinematic"},
     "solver='rk4' rk4_step=2e-06: the solver applies to the skidding tier only, and fidelity='kinematic' runs "
     "the kinematic tier; drop solver or use fidelity='skidding'",
     ["--solver", "rk4", "--rk4-step", "2e-6", "--fidelity", "kinematic"],
     "--solver rk4 --rk4-step 2e-06: the solver applies to the skidding tier only, and --fidelity kinematic runs "
     "the kinematic tier; drop --solver or use --fidelity skidding"),
    ({"out": ""}, "out = '': expected the path of an .mcap file", ["--out", ""],
     "--out = '': expected the path of an .mcap file"),
    ({"rk4_step": "1e-5"}, "rk4_step = '1e-5' s: applies to solver='rk4' only", ["--rk4-step", "1e-5"],
     "--rk4-step = 1e-05 s: applies to --solver rk4 only"),         # a ValueError from the format before
    ({"solver": "rk4", "rk4_step": "2e-6", "fidelity": "kinematic"},
     "solver='rk4' rk4_step='2e-6': the solver applies to the skidding tier only", [], ""),     # float(): ValueError
], ids=["duration", "rk4_step", "solver", "out", "rk4_step_text", "solver_step_text"])
def test_render_names_its_arguments_in_the_callers_words(tmp_path, capsys, kwargs, api, cli_args, cli):
    """``render()`` from Python names its keyword arguments (``duration = ...``,
    ``solver='rk4'``), ``bearing-sim render`` its options (``--duration = ...``, ``--solver rk4``):
    the function said the CLI's words to a Python caller, who had given no option."""
    out = tmp_path / "x.mcap"
    call = {"duration": 0.05, "out": out, **kwargs}
    with pytest.raises(UserError) as exc:
        render("er16k_healthy", call.pop("duration"), call.pop("out"), progress=False, **call)
    assert str(exc.value).startswith(api), str(exc.value)
    if cli_args:                                      # (argparse gives the CLI numbers only)
        args = ["render", "er16k_healthy", "--duration", "0.05", "--out", str(out)] + cli_args
        code, err = _one_line_error(capsys, args)
        assert code == 2 and err.startswith(f"error: {cli}"), err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kwargs, message", [
    # batch_duration 0 ended in a ZeroDivisionError, a negative state_rate was taken
    ({"batch_duration": 0}, "batch_duration = 0: allowed range is [0.001, 1] s"),
    ({"batch_duration": "10ms"}, "batch_duration = '10ms': allowed range is [0.001, 1] s"),
    ({"state_rate": -1}, "state_rate = -1: allowed range is [0, 1000] Hz"),
    ({"state_rate": math.nan}, "state_rate = nan: allowed range is [0, 1000] Hz"),
    ({"batch_duration": 0.0105},
     "batch_duration = 0.0105 s with sample_rate = 15000.0 Hz gives 157.5 samples: must be a whole number >= 1"),
    ({"state_rate": 500.0},
     "state_rate = 500.0 Hz: at most one state per batch, <= 1 / batch_duration = 100 Hz"),
])
def test_batch_duration_and_state_rate_follow_the_nodes_rule(tmp_path, kwargs, message):
    """render() takes the node's batch_duration and state_rate with the node's ranges and rule."""
    out = tmp_path / "x.mcap"
    with pytest.raises(UserError) as exc:
        render("er16k_healthy", 0.05, out, fidelity="kinematic", progress=False, **kwargs)
    assert str(exc.value) == message
    assert not out.exists()


@pytest.mark.parametrize("batch_duration, state_rate, every", [
    (0.001, 0.0, None),       # the smallest batch (15 samples); state_rate 0: no state at all
    (0.001, 1000.0, 1),       # the largest state_rate: a state with each 1 ms batch
    (0.02, 50.0, 1),          # one state per batch, the most the rule allows
    (0.01, 25.0, 4),          # one state every 4 batches
])
def test_batching_at_the_edges_of_the_nodes_rule_renders(tmp_path, batch_duration, state_rate, every):
    """The ends of the allowed ranges are allowed: state_rate 0 (README: no state) and 1000 Hz,
    the smallest batch_duration, and state_rate = 1 / batch_duration.  0.2 s of signal in tables of
    batch_duration, contiguous, and a state every ``every`` batches, stamped at the batch's end."""
    from rosbags.highlevel import AnyReader

    out = tmp_path / "edge.mcap"
    render("er16k_healthy", 0.2, out, fidelity="kinematic", progress=False,
           batch_duration=batch_duration, state_rate=state_rate)
    tables, state_stamps = [], []
    with AnyReader([out]) as reader:
        for conn, t, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == "/accel":
                tables.append(from_pointcloud2(msg))
            elif conn.topic == "/state":
                state_stamps.append(msg.header.stamp.sec * NS + msg.header.stamp.nanosec)
    widths = [arr.shape[0] for _, _, arr in tables]
    assert widths == [round(batch_duration * FS)] * round(0.2 / batch_duration)
    assert np.all(np.abs(np.diff([t[0] for t in tables]) - np.array(widths[:-1]) * NS / FS) <= 1)
    ends = [stamp + round(width * NS / FS) for (stamp, _, _), width in zip(tables, widths)]
    assert state_stamps == ([] if every is None else ends[every - 1::every])


def test_offered_qos_is_the_readmes(rendered):
    """README "QoS": accel and contact_forces reliable, volatile (a late subscriber gets no old
    tables), keep-last about one second of batches (100 at 10 ms); state, diagnostics and the
    operating point reliable, volatile, keep-last 10.  As a player of the file (rosbags) reads
    them."""
    from rosbags.highlevel import AnyReader

    path, _ = rendered
    with AnyReader([path]) as reader:
        offered = {c.topic: c.ext.offered_qos_profiles[0] for c in reader.connections}
    for topic, qos in offered.items():
        depth = 100 if topic in ("/accel", "/contact_forces") else 10
        assert (qos.history.name, qos.depth, qos.reliability.name, qos.durability.name) == \
            ("KEEP_LAST", depth, "RELIABLE", "VOLATILE"), topic
    assert len(offered) == 6


def test_batch_duration_and_state_rate_ranges_are_the_nodes():
    from bearing_sim_ros.messages import BATCH_DURATION, BATCH_DURATION_RANGE, STATE_RATE, STATE_RATE_RANGE
    from bearing_sim_ros.nodes.bearing_sim_node import _descriptors

    for name, default, span in (("batch_duration", BATCH_DURATION, BATCH_DURATION_RANGE),
                                ("state_rate", STATE_RATE, STATE_RATE_RANGE)):
        value, desc = _descriptors()[name]
        fp = desc.floating_point_range[0]
        assert (value, (fp.from_value, fp.to_value)) == (default, span)


def test_rk4_divergence_names_the_option_that_sets_the_step(tmp_path, capsys):
    out = tmp_path / "d.mcap"
    code, err = _one_line_error(capsys, ["render", "er16k_skidding", "--duration", "0.02", "--fidelity", "skidding",
                                         "--solver", "rk4", "--rk4-step", "2e-5", "--out", str(out)])
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith("error: --rk4-step = 2e-05 s: the fixed-step RK4 diverged")
    assert "smaller --rk4-step or --solver default" in err and "rk4_step" not in err
    assert not out.exists()


def test_tier_keys_name_what_tier_values_writes():
    """report reads recorded diagnostics by render.TIER_KEYS: the keys tier_values writes."""
    from bearing_sim_ros.recording.render import TIER_KEYS, tier_values

    assert tuple(tier_values(Simulator("er16k_healthy", fidelity="kinematic"))) == TIER_KEYS


def test_recorded_diagnostics_say_whether_the_kinematic_balls_carry_their_centrifugal_force(tmp_path):
    """``centrifugal`` in a recording's /diagnostics (read with rosbags): ``true`` on
    b6307_seed001, whose kinematic balls carry F_c (F_c / Q_max 0.025, above
    ``CENTRIFUGAL_GATE``), ``false`` on er16k_healthy (0.0053: massless balls), ``none`` on the
    skidding tier; as ``Simulator.centrifugal`` says."""
    from rosbags.highlevel import AnyReader

    from bearing_sim_ros.recording.render import render

    def recorded(name, fidelity):
        out = tmp_path / f"{name}_{fidelity}.mcap"
        render(name, 0.02, out, fidelity=fidelity, progress=False)
        with AnyReader([out]) as reader:
            conns = [c for c in reader.connections if c.topic == "/diagnostics"]
            return {({kv.key: kv.value for kv in reader.deserialize(raw, conn.msgtype).status[0].values}
                     .get("centrifugal")) for conn, _t, raw in reader.messages(connections=conns)}

    assert recorded("b6307_seed001", "kinematic") == {"true"}
    assert recorded("er16k_healthy", "kinematic") == {"false"}
    assert recorded("er16k_healthy", "skidding") == {"none"}


def _accel_y_and_diagnostics(out):
    """The recording ``out``'s accel_y tables ([array]) and /diagnostics ([{key: value}])."""
    from rclpy.serialization import deserialize_message

    accel, diag = [], []
    with open_recording(out) as rec:
        for topic, msg_type, _t, data in rec.messages():
            msg = deserialize_message(data, get_message(msg_type))
            if topic == "/accel":
                accel.append(from_pointcloud2(msg)[2][:, 1])
            elif topic == "/diagnostics":
                diag.append({kv.key: kv.value for kv in msg.status[0].values})
    return accel, diag


def test_diagnostics_give_the_fault_frequencies_where_the_signal_has_them(skidding_outer_race):
    """At 10000 rpm / 10 N the cage skids 7 %: the outer-race line of the recorded signal is
    7 % below the catalog's pure-rolling BPFO, and ``bpfo_hz`` in the recorded ``/diagnostics``
    is where the line is (envelope spectrum of accel_y, within 0.2 Hz of 552 Hz); cage_hz and the
    cage skid ratio tell the same story.  The slips and frictions are mean absolute values in
    their units (they were means of signed values named ``*_ratio``)."""
    from bearing_sim_ros.analysis.envelope import envelope_spectrum, line_at

    scene_path, out = skidding_outer_race
    scene = load_scene(scene_path)
    accel, diag = _accel_y_and_diagnostics(out)
    last = diag[-1]
    assert last["falling_behind"] == "false"            # the live node's key: a render has no pace to fall behind
    bpfo, cage = float(last["bpfo_hz"]), float(last["cage_hz"])
    theory = scene.bearing.fault_frequencies(scene.shaft_hz)
    assert bpfo == pytest.approx(scene.bearing.balls * cage, rel=1e-5)
    assert bpfo < 0.95 * theory["bpfo"]                       # the cage skids
    assert bpfo == pytest.approx(theory["bpfo"] * (1 - float(last["cage_skid_ratio"]) / 100), rel=2e-3)
    x = np.concatenate(accel)[int(FS) // 5:].astype(float)   # after the start-up transient
    freqs, spec = envelope_spectrum(x, FS, max_freq=2000.0)
    assert abs(line_at(freqs, spec, theory["bpfo"], search_rel=0.1).found_hz - bpfo) < 0.2
    inner = float(last["bpfi_hz"])
    assert inner == pytest.approx(scene.bearing.balls * (scene.shaft_hz - cage), rel=1e-5)
    for key in ("slip_inner_m_s", "slip_outer_m_s", "friction_inner_n", "friction_outer_n"):
        assert float(last[key]) > 0
    assert not [k for k in last if k.endswith("_ratio") and "skid" not in k]


def test_the_recorded_command_gives_duration_and_sample_rate_exactly(tmp_path):
    """``{duration:g}`` kept six digits: ``--duration 12.345678`` was recorded as 12.3457, which
    renders 185186 samples instead of 185185.  Both are recorded as given (repr)."""
    out = tmp_path / "exact.mcap"
    render("er16k_healthy", 0.0123456789, out, fidelity="kinematic", sample_rate=15000.0, progress=False)
    argv = _recorded_command(out)
    assert float(argv[argv.index("--duration") + 1]) == 0.0123456789
    assert float(argv[argv.index("--sample-rate") + 1]) == 15000.0


def test_a_duration_shorter_than_one_sample_is_refused_in_one_line(tmp_path, capsys):
    """``--duration 0.00001`` at 15 kHz (0.15 of a sample) wrote a file without a table, exit 0,
    which report then refused: it is an argument error, and no file is made."""
    out = tmp_path / "tiny.mcap"
    assert cli.main(["render", "er16k_healthy", "--duration", "0.00001", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == ("error: --duration = 1e-05 s: shorter than one sample at 15000 Hz; "
                   "expected at least 6.66667e-05 s\n")
    assert not out.exists()
    render("er16k_healthy", 1 / FS, out, fidelity="kinematic", progress=False)     # one sample renders
    with open_recording(out) as rec:
        assert rec.topics()["/accel"].count == 1


def test_the_scene_file_and_other_files_that_are_not_recordings_are_not_replaced(tmp_path, monkeypatch, capsys):
    """``render my.yaml --out my.yaml`` made the scene file an MCAP (exit 0), and any existing
    file at --out was replaced: the scene's own file (by any name) and a file that is not an MCAP
    recording are refused in one line, exit 2, untouched; an MCAP file and an empty file are
    replaced (rendering again to the same path is normal use)."""
    monkeypatch.chdir(tmp_path)
    text = load_scene("er16k_healthy").source_text
    Path("my.yaml").write_text(text)
    Path("notes.txt").write_text("my notes\n")
    for out, words in (("my.yaml", "--out = 'my.yaml': is the scene's own file; give another path"),
                       (str(tmp_path / "sub" / ".." / "my.yaml"), "is the scene's own file"),
                       ("notes.txt", "--out = 'notes.txt': exists and is not an MCAP recording, so it is not "
                                     "replaced; give another path or remove the file first")):
        (tmp_path / "sub").mkdir(exist_ok=True)
        code, err = _one_line_error(capsys, ["render", "my.yaml", "--duration", "0.05", "--out", out])
        assert code == 2 and len(err.splitlines()) == 1 and err.startswith("error: ") and words in err, err
        assert "Traceback" not in err
    assert Path("my.yaml").read_text() == text and Path("notes.txt").read_text() == "my notes\n"
    assert cli.main(["render", "my.yaml", "--duration", "0.05", "--out", "a.mcap"]) == 0
    assert cli.main(["render", "my.yaml", "--duration", "0.1", "--out", "a.mcap"]) == 0     # an MCAP: replaced
    Path("empty.mcap").touch()
    assert cli.main(["render", "my.yaml", "--duration", "0.05", "--out", "empty.mcap"]) == 0
    for name, samples in (("a.mcap", 1500), ("empty.mcap", 750)):
        with open_recording(name) as rec:
            assert rec.topics()["/accel"].count == samples // 150


def test_a_symbolic_link_at_out_is_written_through_and_a_loop_is_one_line(tmp_path, monkeypatch, capsys):
    """``--out link.mcap``: the partial file was moved onto the link itself, which became a regular
    file while its target (an earlier recording, or nothing where it dangled) stayed as it was.
    Now the target is written (created where the link dangles) and the link stays, as a shell's
    ``>`` does; a link that loops was pathlib's "RuntimeError: Symlink loop" as an internal error."""
    monkeypatch.chdir(tmp_path)
    Path("runs").mkdir()
    os.symlink("runs/new.mcap", "dangling.mcap")
    assert cli.main(["render", "er16k_healthy", "--duration", "0.05", "--out", "dangling.mcap"]) == 0
    assert cli.main(["render", "er16k_healthy", "--duration", "0.05", "--out", "runs/old.mcap"]) == 0
    os.symlink("runs/old.mcap", "live.mcap")
    assert cli.main(["render", "er16k_healthy", "--duration", "0.1", "--out", "live.mcap"]) == 0   # replaces old
    for link, target, samples in (("dangling.mcap", "runs/new.mcap", 750), ("live.mcap", "runs/old.mcap", 1500)):
        assert Path(link).is_symlink() and os.readlink(link) == target
        with open_recording(target) as rec:
            assert rec.topics()["/accel"].count == samples // 150
    assert sorted(p.name for p in Path("runs").iterdir()) == ["new.mcap", "old.mcap"]   # no partial file left
    os.symlink("loop.mcap", "loop.mcap")
    code, err = _one_line_error(capsys, ["render", "er16k_healthy", "--duration", "0.05", "--out", "loop.mcap"])
    assert (code, err.strip()) == (2, "error: --out = 'loop.mcap': a symbolic link that loops (it leads back to "
                                      "itself); give another path or remove the link")
    assert os.readlink("loop.mcap") == "loop.mcap"


@pytest.mark.parametrize("sig, status", [(2, 130), (15, 143), (1, 129)], ids=["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_render_stopped_by_a_signal_leaves_a_finalised_file_at_out_and_says_so(tmp_path, ros_env, sig, status):
    """SIGTERM killed a render (status 143, no word) and left a file without a footer at --out,
    which report and play refuse; SIGHUP (the terminal closed) still did (129), leaving its
    ``.partial`` file and nothing at --out.  Ctrl-C, SIGTERM and SIGHUP all finalise what was
    rendered, move it onto --out (it was written beside it, ``<out>.<pid>.partial``), say so in
    one line and exit 130 / 143 / 129: the file is shorter than asked."""
    import sys

    out = tmp_path / "long.mcap"
    # far longer than the second it runs (the file's size says little: the writer lags the loop)
    proc = subprocess.Popen([sys.executable, "-m", "bearing_sim_ros.cli", "render", "er16k_outer_race",
                             "--duration", "3000", "--fidelity", "kinematic", "--out", str(out)],
                            env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    def rendering_for_a_second():
        # nothing at --out until it is complete
        return any(tmp_path.glob("long.mcap*")) and not out.exists()

    stdout, stderr = signal_when(proc, rendering_for_a_second, sig, 1.0, "no partial file")
    assert proc.returncode == status, stderr
    how = {2: "Ctrl-C", 15: "SIGTERM", 1: "SIGHUP"}[sig]
    line = re.fullmatch(rf"interrupted \({how}\): '{re.escape(str(out))}' holds the first ([\d.]+) s, finalised\n",
                        stderr)
    assert line, stderr
    assert stdout == ""
    assert [p.name for p in tmp_path.iterdir()] == ["long.mcap"]           # no partial file left
    with open_recording(out) as rec:
        assert rec.topics()["/accel"].count == round(float(line.group(1)) * FS / 150)


def test_a_render_whose_terminal_closes_keeps_a_finalised_file_at_out(tmp_path, ros_env):
    """A render on a terminal whose window is closed (or whose SSH session drops): killed by the
    SIGHUP, it left its ``.partial`` file without a footer and nothing at --out.  Now it ends as
    on SIGHUP: what was rendered, finalised, at --out, exit 129, though its progress bar and its
    last line go to a terminal that fails every write."""
    import sys

    from test_node_support import on_a_terminal_that_closes

    out = tmp_path / "long.mcap"
    status = on_a_terminal_that_closes([sys.executable, "-m", "bearing_sim_ros.cli", "render", "er16k_outer_race",
                                        "--duration", "3000", "--fidelity", "kinematic", "--out", str(out)],
                                       ros_env, lambda: any(tmp_path.glob("long.mcap.*.partial")), 1.0,
                                       "no partial file")
    assert status == 129
    assert [p.name for p in tmp_path.iterdir()] == ["long.mcap"]           # no partial file left
    with open_recording(out) as rec:
        assert rec.recovered is None and rec.topics()["/accel"].count > 0         # finalised


def test_a_pipe_or_a_device_at_out_gets_a_complete_recording(tmp_path):
    """A pipe or a device at --out is written directly (README), but finalising fsynced it, which
    they refuse (EINVAL): ``--out /dev/null`` and a named pipe ended in exit 2, "could not be
    finalised".  Both render now, and what comes out of the pipe is a whole recording."""
    import os
    import threading

    from mcap.reader import make_reader

    assert cli.main(["render", "er16k_healthy", "--duration", "0.05", "--out", os.devnull]) == 0
    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    rendered = False
    try:
        assert cli.main(["render", "er16k_healthy", "--duration", "0.05", "--out", str(fifo)]) == 0
        rendered = True
    finally:
        if not rendered:
            # the reader ends (EOF) if the render never opened the pipe.  Not when it did: the
            # reader may have read to the end and not yet kept it, and a blocking open would wait
            # for a reader that never comes (the suite hung there once)
            try:
                os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
            except OSError:
                pass                            # no reader left: nothing to end
        reader.join(30)
    (tmp_path / "copy.mcap").write_bytes(got[0])
    with open(tmp_path / "copy.mcap", "rb") as f:
        summary = make_reader(f).get_summary()    # footer, summary: the file was finalised
    assert summary is not None and summary.statistics.channel_message_counts
    with open_recording(tmp_path / "copy.mcap") as rec:
        assert rec.topics()["/accel"].count == 5


def test_a_render_into_a_pipe_nobody_reads_says_it_waits_and_ends_on_a_signal_or_writes_once_read(tmp_path,
                                                                                                    ros_env):
    """A render to a named pipe that no program read waited in the kernel's open, without a word
    and for ever: the SIGTERM of ``timeout 90`` was only noted (Python opened again), and the
    process sat there ten minutes until it was killed.  Now it says after a second that it waits
    for a reader; SIGTERM then ends it (143, nothing rendered), and a reader that comes gets the
    whole recording."""
    import select
    import sys

    from mcap.reader import make_reader

    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    args = [sys.executable, "-m", "bearing_sim_ros.cli", "render", "er16k_healthy", "--duration", "0.05",
            "--out", str(fifo)]
    waiting = f"--out = '{fifo}': a named pipe that no program reads yet; the recording waits for one to open it"

    def waits(proc):
        deadline = time.monotonic() + 120               # imports, and kernels compiled on a cold cache
        said = ""
        while time.monotonic() < deadline and proc.poll() is None and waiting not in said:
            if select.select([proc.stderr], [], [], 1.0)[0]:     # a silent wait must not hold the test
                said += os.read(proc.stderr.fileno(), 4096).decode()
        return said

    proc = subprocess.Popen(args, env=ros_env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        said = waits(proc)
        assert waiting in said, said
        proc.send_signal(signal.SIGTERM)
        rest = proc.communicate(timeout=30)[1].decode()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == 143, said + rest
    assert f"interrupted (SIGTERM): nothing rendered, '{fifo}' left as it was" in rest, rest
    assert "Traceback" not in said + rest

    proc = subprocess.Popen(args, env=ros_env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        assert waiting in waits(proc)
        with open(fifo, "rb") as pipe:
            data = pipe.read()
        assert proc.wait(30) == 0, proc.communicate()[1]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    (tmp_path / "copy.mcap").write_bytes(data)
    with open(tmp_path / "copy.mcap", "rb") as f:
        assert make_reader(f).get_summary() is not None          # finalised
    with open_recording(tmp_path / "copy.mcap") as rec:
        assert rec.topics()["/accel"].count == 5


def test_a_second_render_to_the_same_out_is_refused_in_one_line_and_the_first_kept_whole(tmp_path, ros_env,
                                                                                        capsys):
    """Two renders of a batch script given one --out both exited 0, and the one that finished
    last was kept: the other's recording was lost without a word.  The second now ends before it
    renders, in one line and exit 2 (and ``render()`` raises the same UserError); the first
    renders on, and its file at --out is whole."""
    out = tmp_path / "same.mcap"
    with rendering_until_stopped(out, 1, ros_env) as first:
        busy = (f"--out = '{out}': another recording is being written to this file (two renders, nodes or runs "
                "given the same path?); give each its own, or wait until the other ends")
        code, err = _one_line_error(capsys, ["render", "er16k_healthy", "--duration", "0.5", "--seed", "2",
                                             "--out", str(out)])
        assert (code, err) == (2, f"error: {busy}")
        with pytest.raises(UserError) as refused:
            render("er16k_healthy", 0.5, out, seed=3, progress=False)
        assert str(refused.value) == busy[2:]          # the API's words: out = '...'; the rest alike
        assert not out.exists() and len(list(tmp_path.iterdir())) == 1      # the first's partial file alone
        stop_render(first)
    assert [p.name for p in tmp_path.iterdir()] == ["same.mcap"]
    assert read_recording(out)[1]["bearing_sim"]["seed"] == "1"
    with open_recording(out) as rec:
        assert rec.recovered is None and rec.topics()["/accel"].count > 0


def test_a_partial_file_left_by_a_killed_render_neither_blocks_a_render_nor_stays(tmp_path, ros_env, capsys):
    """A render killed with ``kill -9`` leaves its ``<out>.<pid>.partial`` behind, held by nobody:
    the next render to that --out renders and removes it.  A partial file nobody holds whose
    process still runs (it may have just created it) is left alone, and blocks nothing either."""
    import signal

    out = tmp_path / "same.mcap"
    with rendering_until_stopped(out, 1, ros_env) as killed:
        killed.send_signal(signal.SIGKILL)
        killed.communicate(timeout=30)
    (stale,) = tmp_path.glob("same.mcap.*.partial")
    starting = tmp_path / f"same.mcap.{os.getppid()}.partial"       # a live process's, not yet held
    starting.write_bytes(b"")
    assert cli.main(["render", "er16k_healthy", "--duration", "0.5", "--seed", "2", "--out", str(out)]) == 0, \
        capsys.readouterr().err
    assert not stale.exists() and sorted(p.name for p in tmp_path.iterdir()) == sorted(["same.mcap", starting.name])
    assert read_recording(out)[1]["bearing_sim"]["seed"] == "2"


def test_a_render_that_fails_keeps_the_earlier_recording_at_out(tmp_path, monkeypatch):
    """A render that failed after it started writing unlinked --out, which (opened "wb") may have
    held an earlier good recording: the earlier file stays, byte for byte, and the partial file
    goes."""
    out = tmp_path / "a.mcap"
    render("er16k_healthy", 0.2, out, fidelity="kinematic", progress=False)
    before = out.read_bytes()
    calls = []
    advance = Simulator.advance

    def failing(self, *a, **kw):
        calls.append(1)
        if len(calls) > 30:
            raise RuntimeError("the model failed")
        return advance(self, *a, **kw)

    monkeypatch.setattr(Simulator, "advance", failing)
    with pytest.raises(RuntimeError, match="the model failed"):
        render("er16k_healthy", 1.0, out, fidelity="kinematic", progress=False)
    assert out.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["a.mcap"]


@pytest.mark.parametrize("how", ["deleted", "replaced"])
def test_a_render_whose_partial_file_goes_away_fails_in_one_line_and_stops(tmp_path, capsys, monkeypatch, how):
    """The ``.partial`` file a render writes, deleted (or replaced by another file) on the way:
    deleted, the render ran to its end and failed on the rename with a FileNotFoundError;
    replaced, it moved the other file onto ``--out`` and said it had rendered.  Now the recorder
    notices (within ``CHECK_PATH_S``) and the render stops there, exit status 2 and one line
    naming ``--out`` and what happened; ``--out`` keeps the earlier recording, and the other
    file is left alone."""
    from bearing_sim_ros.recording import recorder

    out = tmp_path / "a.mcap"
    render("er16k_healthy", 0.2, out, fidelity="kinematic", progress=False)
    before = out.read_bytes()
    monkeypatch.setattr(recorder, "CHECK_PATH_S", 0.01)
    calls, taken = [], []
    advance = Simulator.advance
    # the writer thread notices within CHECK_PATH_S of its own time; a busy machine may not run
    # it for a while, and the render races on meanwhile: the test waits for it to notice
    noticed = threading.Event()
    fail = recorder.Recorder._fail

    def fail_and_tell(self, *a, **kw):
        fail(self, *a, **kw)
        noticed.set()

    monkeypatch.setattr(recorder.Recorder, "_fail", fail_and_tell)

    def advance_and_take_the_partial_away(self, *a, **kw):
        calls.append(1)
        if len(calls) == 30:
            (partial,) = tmp_path.glob("a.mcap.*.partial")
            taken.append(partial.name)
            if how == "replaced":         # at once, as mv does: unlinked first, it may be seen deleted
                other = tmp_path / "other"
                other.write_text("someone else's file\n")
                os.replace(other, partial)
            else:
                partial.unlink()
            assert noticed.wait(30.0)
        return advance(self, *a, **kw)

    monkeypatch.setattr(Simulator, "advance", advance_and_take_the_partial_away)
    code, err = _one_line_error(capsys, ["render", "er16k_healthy", "--duration", "40", "--fidelity", "kinematic",
                                         "--out", str(out)])
    (name,) = taken
    why = "deleted" if how == "deleted" else "replaced by another file"
    assert code == 2 and err == (f"error: --out = '{out}': recording to {out} stopped: its temporary file {name} "
                                 f"was {why} while it was written"), err
    assert len(calls) == 30             # stopped at the next batch, not after all 4000
    assert out.read_bytes() == before
    others = sorted(p.name for p in tmp_path.iterdir())
    assert others == (["a.mcap"] if how == "deleted" else sorted(["a.mcap", name]))


def test_a_writer_that_falls_behind_holds_the_render_up_and_loses_nothing(tmp_path, monkeypatch):
    """render has no deadline, so a disk slower than the simulator must cost time, not messages.
    With a queue limit of 0 bytes every write finds the writer thread behind (it sleeps 20 ms
    whenever it finds the queue empty), where the node's recorder would drop: every message of
    the 0.2 s render reads back with rosbags all the same (20 batches: speed, load, accel and
    contact forces each; state at 50 Hz; the diagnostics at the end of the signal)."""
    from rosbags.highlevel import AnyReader

    from bearing_sim_ros.recording import recorder

    monkeypatch.setattr(recorder, "MAX_QUEUE_BYTES", 0)
    out = tmp_path / "slow.mcap"
    summary = render("er16k_outer_race", 0.2, out, fidelity="kinematic", progress=False)
    with AnyReader([out]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        samples = sum(reader.deserialize(raw, c.msgtype).width
                      for c, _t, raw in reader.messages([c for c in reader.connections if c.topic == "/accel"]))
    assert counts == {"/shaft_speed": 20, "/load": 20, "/accel": 20, "/contact_forces": 20, "/state": 10,
                      "/diagnostics": 1}, counts
    assert samples == 0.2 * FS and summary["messages"] == 91


def test_a_saturated_sensor_is_counted_and_warned_in_the_diagnostics(tmp_path):
    """The outer-race scene with the sensor's range lowered to +-20 m/s^2 (its impacts reach
    beyond it): every second's ``/diagnostics`` counts the samples at the range
    (``accel_clipped_samples``, as many as the recorded accel has at +-20 m/s^2) and warns
    (level 1, ``accelerometer saturated: ...``); at the shipped +-50 g the count is 0 and the
    level ok.  Before, a clipped signal was said nowhere."""
    from rclpy.serialization import deserialize_message

    source = load_scene("er16k_outer_race").source_text
    assert "range: 490.3" in source
    scene = tmp_path / "clipped.yaml"
    scene.write_text(source.replace("range: 490.3", "range: 20.0"))
    for path, limit in ((scene, 20.0), ("er16k_outer_race", None)):
        out = tmp_path / "r.mcap"
        render(path, 2.0, out, fidelity="kinematic", progress=False)
        at_range, diag = 0, []
        with open_recording(out) as rec:
            for topic, msg_type, _t, data in rec.messages():
                msg = deserialize_message(data, get_message(msg_type))
                if topic == "/accel":
                    x = from_pointcloud2(msg)[2]
                    at_range += int(np.count_nonzero((np.abs(x) >= np.float32(limit or 1e9)).any(axis=1)))
                elif topic == "/diagnostics":
                    st = msg.status[0]
                    diag.append((int(st.level[0]) if isinstance(st.level, bytes) else int(st.level), st.message,
                                 int({kv.key: kv.value for kv in st.values}["accel_clipped_samples"])))
        assert len(diag) == 2
        # the last is the end status, whose message says so before the warning (at its level)
        end = "run ended: duration 2 s reached, 2.000000 s of signal (30000 samples) published"
        if limit is None:
            assert diag == [(0, "ok", 0), (0, end, 0)]
        else:
            assert diag[1][1].startswith(end + "; ")
            diag[1] = (diag[1][0], diag[1][1].removeprefix(end + "; "), diag[1][2])
            assert all(level == 1 and message.startswith("accelerometer saturated: ") for level, message, _n in diag)
            assert all(n > 0 for _l, _m, n in diag) and sum(n for _l, _m, n in diag) == at_range


def test_bsf_hz_is_where_a_skidding_balls_defect_line_is(tmp_path):
    """A ball defect on the ER-16K at 10000 rpm / 10 N, skidding tier: the balls spin about 7 %
    slower than pure rolling, and the 2xBSF envelope line of the ball's pit sits there (720 Hz
    against the catalog's 774).  ``bsf_hz`` in the recorded ``/diagnostics`` is that spin (the
    pure-rolling value slowed by ``ball_skid_ratio``) and is where the line is, within 0.5 Hz
    (the report placed it at pure rolling); on the kinematic tier it is the catalog's."""
    from bearing_sim_ros.analysis.envelope import envelope_spectrum, line_at

    text = load_scene("er16k_outer_race").source_text
    ball = (text.replace("{shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}",
                         "{shaft_speed_rpm: 10000, radial_load: [0.0, -10.0]}")
            .replace("{kind: outer, width_mm: 0.6, depth_mm: 0.25, length_mm: 0.6, clock: 6, profile: geometric}",
                     "{kind: ball, width_mm: 0.6, depth_mm: 0.25, length_mm: 0.6, angle_deg: 0, ball: 0}"))
    assert "kind: ball" in ball and "10000" in ball, "er16k_outer_race.yaml moved: update this test"
    path = tmp_path / "fast_ball.yaml"
    path.write_text(ball)
    scene = load_scene(path)
    rolling = scene.bearing.fault_frequencies(scene.shaft_hz)["bsf"]
    for tier in ("skidding", "kinematic"):
        out = tmp_path / f"{tier}.mcap"
        render(path, 2.0, out, fidelity=tier, progress=False)
        accel, diag = _accel_y_and_diagnostics(out)
        last = diag[-1]
        bsf = float(last["bsf_hz"])
        if tier == "kinematic":
            assert bsf == pytest.approx(rolling, rel=1e-5)
            continue
        assert bsf == pytest.approx(rolling * (1 - float(last["ball_skid_ratio"]) / 100), rel=1e-4)
        assert bsf < 0.95 * rolling
        x = np.concatenate(accel)[int(FS) // 5:].astype(float)
        freqs, spec = envelope_spectrum(x, FS, max_freq=2000.0)
        assert abs(line_at(freqs, spec, 2 * rolling, search_rel=0.1).found_hz - 2 * bsf) < 0.5


@pytest.mark.parametrize("batches, sig", [(None, None), (200, "SIGINT"), (130, "SIGTERM")],
                         ids=["duration", "SIGINT-at-a-whole-second", "SIGTERM"])
def test_a_renders_last_diagnostics_is_its_end_status(tmp_path, monkeypatch, batches, sig):
    """A recording's last ``/diagnostics`` says the run ended (``run: ended``; ``running`` in the
    others), why and how much signal it holds, as the live node's end status says it to its
    consumers (``play`` republishes it): a render that ran its duration, one stopped by Ctrl-C just
    at a whole second (its last /diagnostics was the ordinary one of that second) and one stopped
    by SIGTERM."""
    import signal

    calls = []
    advance = Simulator.advance

    def interrupted(self, *a, **kw):
        calls.append(1)
        if len(calls) == batches:                 # the batch completes, and is the last
            os.kill(os.getpid(), getattr(signal, sig))
        return advance(self, *a, **kw)

    monkeypatch.setattr(Simulator, "advance", interrupted)
    out = tmp_path / "r.mcap"
    if batches is None:
        render("er16k_outer_race", 2.5, out, fidelity="kinematic", progress=False)
    else:
        with pytest.raises(KeyboardInterrupt):
            from bearing_sim_ros.recording.render import _terminated_on_sigterm_or_sighup

            with _terminated_on_sigterm_or_sighup():
                render("er16k_outer_race", 10.0, out, fidelity="kinematic", progress=False)
    from rclpy.serialization import deserialize_message

    statuses = []
    with open_recording(out) as rec:
        cls = get_message("diagnostic_msgs/msg/DiagnosticArray")
        for _, _, log_ns, data in rec.messages(["/diagnostics"]):
            st = deserialize_message(data, cls).status[0]
            statuses.append((log_ns, st.message, {kv.key: kv.value for kv in st.values}))
    samples = 37500 if batches is None else batches * 150
    assert statuses[-1][0] == samples * NS // 15000 and len(statuses) == math.ceil(samples / 15000)
    assert [v["run"] for _t, _m, v in statuses] == ["running"] * (len(statuses) - 1) + ["ended"]
    _t, message, values = statuses[-1]
    assert values["end_reason"] == (sig or "duration") and values["published_samples"] == str(samples)
    seconds = f"{samples / 15000:.6f} s of signal ({samples} samples) published"
    assert message == (f"run ended by {sig}: {seconds}" if sig else f"run ended: duration 2.5 s reached, {seconds}")


def test_a_render_stopped_by_a_signal_ends_with_the_diagnostics_of_its_last_sample(tmp_path, monkeypatch):
    """A render stopped by Ctrl-C keeps a finalised file of what it rendered, but its last
    ``/diagnostics`` was that of the last whole second: the ground truth of the rest was missing
    (here a pit that appears at 2.2 s, in a file that holds 2.5 s, was in no message, and the
    report called it "after the analysed stretch").  Now the file ends with the ``/diagnostics``
    of its last sample, as a render that runs to its end and the live node stopped by a signal
    do."""
    import signal

    from bearing_sim_ros.analysis.report import build_report

    scene = tmp_path / "late.yaml"
    text = load_scene("er16k_outer_race").source_text
    scene.write_text(text.replace("profile: geometric}", "profile: geometric, onset_s: 2.2}"))
    calls = []
    advance = Simulator.advance

    def interrupted_after_2_5_s(self, *a, **kw):
        calls.append(1)
        if len(calls) == 250:                     # the batch that ends at 2.5 s; it completes
            os.kill(os.getpid(), signal.SIGINT)
        return advance(self, *a, **kw)

    monkeypatch.setattr(Simulator, "advance", interrupted_after_2_5_s)
    out = tmp_path / "stopped.mcap"
    with pytest.raises(KeyboardInterrupt):
        render(str(scene), 10.0, out, fidelity="kinematic", progress=False)
    diagnostics = []
    with open_recording(out) as rec:
        assert rec.topics()["/accel"].count == 250
        cls = get_message("diagnostic_msgs/msg/DiagnosticArray")
        from rclpy.serialization import deserialize_message

        for _, _, log_ns, data in rec.messages(["/diagnostics"]):
            msg = deserialize_message(data, cls)
            values = {kv.key: kv.value for st in msg.status for kv in st.values}
            diagnostics.append((log_ns, values["simulated_s"], values["faults_present"]))
    assert diagnostics == [(1 * NS, "1.000000", "none"), (2 * NS, "2.000000", "none"),
                           (2_500_000_000, "2.500000", "outer")]
    s = build_report(out, tmp_path / "report")
    assert s["scene_defects"] == [{"kind": "outer", "onset_s": pytest.approx(2.2), "present": "in part of the analysed stretch"}]


def test_period_means_leave_out_the_rows_without_skid_ratios():
    """The batch in which fidelity auto switches to the skidding tier has no skid ratios for its
    first rows (NaN: the kinematic tier computed them); a ``/diagnostics`` period's means are
    those of the rows that have them, not NaN."""
    from types import SimpleNamespace

    from bearing_sim_ros.recording.render import PeriodMeans

    n, balls = 150, 9
    skid = np.full(n, 2.0)
    skid[:19] = np.nan
    slip = np.full((n, balls), -0.5)
    slip[:19] = np.nan
    batch = SimpleNamespace(n=n, extras={"cage_skid": skid, "slip_inner": slip}, cage_speed=np.full(n, 60.0),
                            shaft_speed=np.full(n, 160.0), accel=np.zeros((n, 2)))
    means = PeriodMeans(balls)
    means.add(batch)
    batch.extras = {"cage_skid": np.full(n, 4.0), "slip_inner": np.full((n, balls), 1.0)}
    means.add(batch)
    values = means.values()
    # sample-weighted: 131 rows at 2 %, 150 at 4 %
    assert float(values["cage_skid_ratio"]) == pytest.approx((131 * 2.0 + 150 * 4.0) / 281, rel=1e-3)
    assert float(values["slip_inner_m_s"]) == pytest.approx((131 * 0.5 + 150 * 1.0) / 281, rel=1e-3)


def test_a_scene_changed_in_python_is_not_recorded_as_its_file(tmp_path):
    """A recording holds its scene's YAML and the command that makes it again (INTERFACE:
    "a recording says how to reproduce it").  A scene changed in Python after loading
    (``dataclasses.replace``) was recorded with its file's YAML and command: an inner-race pit at
    200 N went into the file as er16k_outer_race's outer-race pit at 50 N, and ``report`` said
    the scene's outer-race defect was "not in this recording".  Now ``render`` refuses it in one
    line that names the fields that differ, before any work; the scene as loaded renders."""
    import dataclasses

    scene = load_scene("er16k_outer_race")
    changed = dataclasses.replace(scene, defects=(dataclasses.replace(scene.defects[0], kind="inner"),),
                                  radial_load=(0.0, -200.0))
    out = tmp_path / "changed.mcap"
    with pytest.raises(UserError, match=r"^scene er16k_outer_race: changed in Python since it was loaded from "
                                        r"er16k_outer_race.yaml \(radial_load, defects\); .* write the changed "
                                        r"scene to a YAML file and render that$"):
        render(changed, 0.05, out, fidelity="kinematic", progress=False)
    assert not out.exists()
    render(dataclasses.replace(scene), 0.05, out, fidelity="kinematic", progress=False)    # the same scene
    assert out.exists()


def test_a_diverging_solver_ends_a_render_in_one_line_and_keeps_what_was_rendered(diverging_scene, tmp_path,
                                                                                    capsys):
    """The skidding solver's divergence was "internal error: SolverDiverged: skidding solver
    'default' diverged at t = ..." after a traceback, exit 1, and the partial file deleted.  Now
    one line in the command's options (solver, time of signal, operating point, what to try)
    and where the file stands, exit 2: the signal up to the batch that diverged, finalised,
    ending in an ERROR /diagnostics with the same line; nothing rendered (it diverged in the
    first batch): nothing written."""
    from rclpy.serialization import deserialize_message

    out = tmp_path / "d.mcap"
    code, err = _one_line_error(capsys, ["render", str(diverging_scene(0.05)), "--duration", "0.2", "--out", str(out)])
    found = re.fullmatch(r"error: (--solver default: the skidding tier's default solver diverged at t = (0\.\d+) s of "
                         r"signal \(2000 rpm, radial load \[0, -200\] N\): the scene is beyond what it integrates; try "
                         r"--solver reference \(.*\) or --fidelity kinematic); '(.*)' holds the first (0\.\d+) s, "
                         r"finalised", err)
    assert code == 2 and found and found[3] == str(out), err
    line, t, kept = found[1], float(found[2]), float(found[4])
    assert 0.05 < kept < t < 0.2
    accel, _diag = _accel_y_and_diagnostics(out)
    assert len(accel) == round(kept / 0.01) and all(np.isfinite(a).all() for a in accel)
    with open_recording(out) as rec:
        last = [deserialize_message(data, get_message(msg_type)).status[0]
                for topic, msg_type, _t, data in rec.messages() if topic == "/diagnostics"][-1]
    # the end status: the run ended by the divergence, the signal kept, the line
    samples = round(kept * 15000)
    assert (last.level, last.message) == (b"\x02", f"run ended: the solver diverged, {kept:.6f} s of signal "
                                                    f"({samples} samples) published; {line}")
    assert {kv.key: kv.value for kv in last.values}["end_reason"] == "diverged"
    # diverged in the first batch: nothing rendered, nothing written
    code, err = _one_line_error(capsys, ["render", str(diverging_scene(0.0)), "--duration", "0.2",
                                         "--out", str(tmp_path / "none.mcap")])
    assert code == 2 and err.endswith(f"; nothing rendered, '{tmp_path / 'none.mcap'}' left as it was"), err
    assert len(err.splitlines()) == 1 and not (tmp_path / "none.mcap").exists()


@pytest.mark.parametrize("sig, status", [("SIGTERM", 143), ("SIGHUP", 129)])
def test_a_signal_as_the_render_opens_its_file_leaves_no_partial_file(tmp_path, monkeypatch, capsys, sig, status):
    """SIGTERM or SIGHUP between the render opening its ``<out>.<pid>.partial`` and entering its
    loop raised there, and left that file behind, neither finalised nor removed (hH's report; a
    window of milliseconds).  Now the file is opened where a signal is only noted: the render
    ends before its first batch, says nothing was rendered, and leaves nothing."""
    import signal

    import bearing_sim_ros.recording.recorder as recorder_module

    opened = recorder_module.Recorder

    class SignalledAsItOpens(opened):
        def __init__(self, *a, **kw):
            super().__init__(*a, **kw)
            os.kill(os.getpid(), getattr(signal, sig))      # the partial file is there now

    monkeypatch.setattr(recorder_module, "Recorder", SignalledAsItOpens)      # render imports it as it runs
    out = tmp_path / "x.mcap"
    assert cli.main(["render", "er16k_healthy", "--duration", "1", "--out", str(out)]) == status
    assert list(tmp_path.iterdir()) == []
    err = capsys.readouterr().err
    assert err == f"interrupted ({sig}): nothing rendered, {str(out)!r} left as it was\n", err


def test_a_render_slower_than_real_time_says_how_much_slower(tmp_path, capsys):
    """The line's real-time factor had one decimal: a render 70 times slower than real time (the
    reference solver at 200 kHz) said "= 0.0x real time".  Below 1 it has two significant digits,
    the signal's seconds over the line's own wall seconds."""
    out = tmp_path / "slow.mcap"
    assert cli.main(["render", "er16k_skidding", "--duration", "0.02", "--fidelity", "skidding", "--solver",
                     "reference", "--sample-rate", "200000", "--out", str(out)]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    found = re.search(r"rendered in ([0-9.]+) s = ([0-9.e-]+)x real time$", line)
    assert found, line
    wall, factor = float(found.group(1)), float(found.group(2))
    assert wall > 0.02 and factor == pytest.approx(0.02 / wall, rel=0.06), line      # 2 digits, and the wall's rounding


def test_a_short_render_says_what_its_messages_weigh(tmp_path, capsys):
    """The line gave the messages' size with one decimal in MB: 20 ms of signal said "0.0 MB of
    messages".  Below 1 MB it has two significant digits, still in MB, and agrees with the bytes
    of the messages an independent reader finds in the file."""
    from mcap.reader import make_reader

    out = tmp_path / "short.mcap"
    assert cli.main(["render", "er16k_healthy", "--duration", "0.02", "--out", str(out)]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    found = re.search(r"messages, ([0-9.]+) MB of messages, ", line)
    assert found, line
    with open(out, "rb") as f:
        message_bytes = sum(len(m.data) for _s, _c, m in make_reader(f).iter_messages())
    assert 1_000 < message_bytes < 1_000_000
    shown = found.group(1)
    assert float(shown) == pytest.approx(message_bytes / 1e6, rel=0.05), (line, message_bytes)
    assert len(shown.lstrip("0.")) == 2, line                        # two significant digits
