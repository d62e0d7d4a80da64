"""The README is the user's first hour: what it tells them to type must work as written.

Runs the README's Python blocks as they stand, parses every ``bearing-sim`` command it shows with the
CLI's own parser (and the node's parameters, ``make`` variables, ``python -m`` options, scene names
and launch arguments it names) against the code, so that renaming an option, a parameter or a
scene without the README fails here.  What the commands then do is tested where they are
implemented (test_cli, test_node, test_render, ...).
"""
from __future__ import annotations

import ast
import re
import shlex
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from bearing_sim_ros.waveform import NS

REPO = Path(__file__).resolve().parent.parent
README = (REPO / "README.md").read_text()


def _blocks(lang: str) -> list[tuple[int, str]]:
    """(line number, text) of every fenced block of ``lang`` in the README."""
    found = []
    for m in re.finditer(rf"^```{lang}\n(.*?)^```", README, flags=re.S | re.M):
        found.append((README.count("\n", 0, m.start()) + 1, m.group(1)))
    return found


def _block_containing(lang: str, text: str) -> str:
    hits = [body for _line, body in _blocks(lang) if text in body]
    assert len(hits) == 1, f"expected one {lang} block of the README with {text!r}, found {len(hits)}"
    return hits[0]


def _shell_lines() -> list[str]:
    """Every command line of the README's bash blocks (continuations joined, comments removed)."""
    lines = []
    for _line, body in _blocks("bash"):
        for line in body.replace("\\\n", " ").splitlines():
            line = line.split(" #", 1)[0].strip()
            if line and not line.startswith("#"):
                lines.append(line)
    return lines


# ---- the Python blocks, run as written --------------------------------------------------------
def test_the_waveform_table_recipe_reads_a_published_table():
    """"Consuming a waveform table": the callback's lines, run on a table the node's own
    builder makes from a batch, give that batch's accel_y (float32) and the stamp of sample 0 to
    the ns; also where the fields are listed in another order than their offsets."""
    from bearing_sim_ros import Simulator, load_scene
    from bearing_sim_ros.waveform import to_pointcloud2

    block = _block_containing("python", "def on_accel(msg):")
    head, body = block.split("def on_accel(msg):", 1)
    batch = Simulator(load_scene("er16k_outer_race"), fidelity="kinematic").advance(150)
    stamp_ns = 1_700_000_000_123_456_789
    for reverse in (False, True):
        msg = to_pointcloud2(batch.accel, batch.accel_channels, stamp_ns, "bearing_accel")
        if reverse:
            msg.fields = list(reversed(msg.fields))
        scope = {"msg": msg}
        exec(head, scope)
        exec(textwrap.dedent(body.split("\n", 1)[1]), scope)
        assert scope["column"] == {"accel_x": 0, "accel_y": 1}
        np.testing.assert_array_equal(scope["accel_y"], batch.accel[:, 1].astype("<f4"))
        assert scope["t0_ns"] == stamp_ns


def test_the_python_api_block_runs_as_written():
    """"The Python API (no ROS needed)": every line runs, and the values are what its comments say."""
    scope = {}
    exec(_block_containing("python", "sim.prepare_switches()"), scope)
    b, sim = scope["b"], scope["sim"]
    assert b.accel.shape == (150, 2) and b.accel_channels == ("accel_x", "accel_y")
    assert b.contact_forces.shape[1] == 2 * sim.bearing.balls
    assert sim.tier in ("kinematic", "skidding")
    assert set(sim.bearing.fault_frequencies(scope["scene"].shaft_hz)) == {"ftf", "bpfo", "bpfi", "bsf"}


def test_the_own_bearing_block_loads_as_written():
    """"A bearing of your own": the block is a scene's bearing as written, with the defaults the
    text gives, and its fault frequencies are the textbook ones of its geometry."""
    import math

    from bearing_sim_ros.scene import load_yaml, scene_from_dict

    doc = load_yaml(_block_containing("yaml", "name: my_6000"))
    doc.update(operating_point={"shaft_speed_rpm": 6000},
               structure={"shaft": {"mass": 0.3, "stiffness": 2e6, "damping": 300},
                          "pedestal": {"mass": 0.8, "stiffness": 5e7, "damping": 1500}})
    b = scene_from_dict(doc).bearing
    assert (b.name, b.balls, b.radial_clearance, b.width) == ("my_6000", 7, 4e-6, 8e-3)
    assert (b.inner_race_diameter, b.outer_race_diameter) == pytest.approx((18e-3 - 4.762e-3, 18e-3 + 4.762e-3))
    assert (b.contact_angle, b.inner_groove_conformity, b.elastic_modulus, b.density) == (0.0, 0.52, 208e9, 7850.0)
    assert b.ball_mass == pytest.approx(7850.0 * math.pi * 4.762e-3 ** 3 / 6.0)
    g = 4.762 / 18.0
    assert b.fault_frequencies(100.0) == pytest.approx(
        {"ftf": 50 * (1 - g), "bpfo": 350 * (1 - g), "bpfi": 350 * (1 + g), "bsf": 50 / g * (1 - g * g)})


def test_the_envelope_analysis_block_runs_as_written():
    """"Envelope analysis in Python": the lines run, and the values are what the comments say."""
    scope = {}
    exec(_block_containing("python", "fault_lines(y, sim.sample_rate, ff)"), scope)
    assert scope["y"].shape == (45000,) and scope["verdict"] == "outer"
    assert abs(scope["bpfo_hz"] - 95.25) < 0.1 and 100 < scope["bpfo_score"] < 1000
    assert scope["freqs"].shape == scope["amp"].shape


def test_the_skidding_outputs_block_runs_as_written():
    """"The skidding tier": the extras it names exist with the shapes it gives."""
    scope = {}
    exec(_block_containing("python", 'b.extras["cage_skid"]'), scope)
    b, nb = scope["b"], scope["sim"].bearing.balls
    assert b.cage_speed.shape == (1500,)
    for key in ("cage_skid", "ball_skid"):
        assert b.extras[key].shape[0] == 1500
    for key in ("slip_inner", "slip_outer", "friction_inner", "friction_outer"):
        assert b.extras[key].shape == (1500, nb)


def test_the_ground_truth_block_scores_with_a_rendered_recordings_diagnostics(tmp_path):
    """"`bearing-sim monitor`": the callback, run as written on the /diagnostics of a render whose
    outer-race pit appears at 1.5 s, keeps their ground truth; the two calls give what the
    comments say: the fault at a window's end after the onset, and when it appeared (to the ns)."""
    from rclpy.serialization import deserialize_message

    from bearing_sim_ros import load_scene
    from bearing_sim_ros.recording.reader import get_message, open_recording
    from bearing_sim_ros.recording.render import render

    scene = tmp_path / "late.yaml"
    scene.write_text(load_scene("cwru_6205_or007_6").source_text.replace(
        "profile: geometric}", "profile: geometric, onset_s: 1.5}"))
    render(str(scene), 3.0, tmp_path / "late.mcap", fidelity="kinematic", progress=False)
    rec = open_recording(tmp_path / "late.mcap")
    try:
        diag = [deserialize_message(data, get_message("diagnostic_msgs/msg/DiagnosticArray"))
                for _t, _ty, _log, data in rec.messages(topics=["/diagnostics"])]
    finally:
        rec.close()
    # the first sample's stamp: the first message's (1 s of signal) minus 1 s
    first_ns = diag[0].header.stamp.sec * NS + diag[0].header.stamp.nanosec - NS
    scope = {"first_ns": first_ns, "end_ns": first_ns + 2 * NS}
    exec(_block_containing("python", "ground_truth.faults_at(truths, end_ns"), scope)
    for msg in diag:
        scope["on_diagnostics"](msg)
    truths, gt = scope["truths"], scope["ground_truth"]
    assert len(truths) == 3
    assert gt.faults_at(truths, first_ns + 2 * NS, slack=1_000) == ("outer",)
    assert gt.faults_at(truths, first_ns + NS, slack=1_000) == ()
    assert gt.appearances(truths, first_ns, slack=1_000) == [("outer", first_ns + 1_500_000_000, first_ns + 1_500_000_000)]


def test_the_end_of_a_run_block_sees_a_rendered_recordings_end_status(tmp_path):
    """"The end of a run": the callback, run as written on the /diagnostics of a 1.5 s render,
    calls ``run_ended`` once, with the reason and the samples the recording holds."""
    from rclpy.serialization import deserialize_message

    from bearing_sim_ros.recording.reader import get_message, open_recording
    from bearing_sim_ros.recording.render import render

    render("er16k_outer_race", 1.5, tmp_path / "r.mcap", fidelity="kinematic", progress=False)
    with open_recording(tmp_path / "r.mcap") as rec:
        diag = [deserialize_message(data, get_message("diagnostic_msgs/msg/DiagnosticArray"))
                for _t, _ty, _log, data in rec.messages(topics=["/diagnostics"])]
    ended = []
    scope = {"run_ended": lambda reason, samples: ended.append((reason, samples))}
    exec(_block_containing("python", 'values.get("run") == "ended"'), scope)
    for msg in diag:
        scope["on_diagnostics"](msg)
    assert len(diag) == 2 and ended == [("duration", 22500)]


def test_the_rosbags_block_reads_a_rendered_recording(tmp_path, monkeypatch, bearing_sim_exe):
    """"Open a recording ...": the rosbags loop, run as written on ``outer.mcap`` from the
    README's own render command (shortened), reads waveform tables."""
    subprocess.run([bearing_sim_exe, "render", "er16k_outer_race", "--duration", "0.05", "--out", "outer.mcap"],
                   cwd=tmp_path, check=True, capture_output=True)
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(_block_containing("python", "AnyReader"), scope)
    assert scope["channels"] == ["accel_x", "accel_y"]
    assert scope["samples"].shape == (150, 2) and scope["stamp_ns"] > 0


def test_the_sweep_blocks_make_labelled_recordings_the_api_repeats(tmp_path, monkeypatch, bearing_sim_exe):
    """"Render offline": the sweep, run as written, writes a scene YAML per speed and a file per
    seed; the metadata block reads that file's scene and seed; the command the text gives makes
    the same bytes; the Python API's samples, rounded to float32, are the file's tables; and the
    CWRU pit's depth changes no sample from 0.002 mm up (kinematic tier here; the text's other
    claims on it were checked by hand in both tiers and every profile)."""
    import dataclasses

    from rclpy.serialization import deserialize_message

    from bearing_sim_ros import Simulator, load_scene
    from bearing_sim_ros.recording.reader import get_message, open_recording
    from bearing_sim_ros.waveform import from_pointcloud2

    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(_block_containing("python", "yaml.safe_dump(doc, f"), scope)
    assert sorted(p.name for p in tmp_path.glob("*.mcap")) == [
        "ir007_1200rpm_1000N_s0.mcap", "ir007_1200rpm_1000N_s1.mcap",
        "ir007_2400rpm_1000N_s2.mcap", "ir007_2400rpm_1000N_s3.mcap"]
    exec(_block_containing("python", "make_reader(f).iter_metadata()"), scope)
    assert (scope["meta"]["scene"], scope["meta"]["seed"]) == ("ir007_1200rpm_1000N", "1")

    (command,) = re.findall(r"`(bearing-sim render ir007_1200rpm_1000N\.yaml [^`]*)`", README.replace("\n", " "))
    argv = shlex.split(command)[1:]
    argv[argv.index("--out") + 1] = "cli.mcap"
    subprocess.run([bearing_sim_exe, *argv], cwd=tmp_path, check=True, capture_output=True)
    assert (tmp_path / "cli.mcap").read_bytes() == (tmp_path / "ir007_1200rpm_1000N_s1.mcap").read_bytes()

    pc2 = get_message("sensor_msgs/msg/PointCloud2")
    with open_recording(tmp_path / "ir007_1200rpm_1000N_s1.mcap") as rec:
        tables = [from_pointcloud2(deserialize_message(data, pc2))[2]
                  for _t, _ty, _log, data in rec.messages(topics=["/accel"])]
    recorded = np.concatenate(tables)
    scene = load_scene("ir007_1200rpm_1000N.yaml")
    assert scene.shaft_speed == pytest.approx(1200 * 2 * np.pi / 60) and scene.radial_load == (0.0, -1000.0)
    api = Simulator(scene, seed=1).advance(30000).accel
    assert np.array_equal(api.astype(np.float32), recorded)

    pit = scene.defects[0]
    accel = [Simulator(dataclasses.replace(scene, defects=(dataclasses.replace(pit, depth=depth),)), seed=0,
                       fidelity="kinematic").advance(3000).accel for depth in (0.002e-3, pit.depth, 1e-3)]
    assert np.array_equal(accel[0], accel[1]) and np.array_equal(accel[2], accel[1])


# ---- the commands, against the code ------------------------------------------------------------
def _subparsers():
    from bearing_sim_ros.cli import build_parser

    parser = build_parser()
    (action,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    return parser, action.choices


def test_every_bearing_sim_command_line_parses():
    """Each ``bearing-sim`` line of a bash block parses with the CLI's parser; a synopsis with
    ``[--option a|b]`` names existing options with exactly the choices the parser has; the
    node's ``-p name:=value`` names are node parameters."""
    from bearing_sim_ros.nodes.bearing_sim_node import _descriptors

    parser, subs = _subparsers()
    params = set(_descriptors())
    checked = 0
    for line in _shell_lines():
        for command in re.findall(r"bearing-sim\s(?:[^;&|]|\|(?! ))*", line):
            argv = shlex.split(command)[1:]
            if "[" in command:                     # a synopsis: options and their choices
                sub = subs[argv[0]]
                for option, choices in re.findall(r"\[(--[\w-]+)(?: ([\w|.-]+))?\]", command):
                    assert option in sub._option_string_actions, f"README: {command}: no option {option}"
                    known = sub._option_string_actions[option].choices
                    if known is not None:
                        assert choices.split("|") == list(known), f"README: {option} {choices} vs {known}"
            elif argv[0] == "node":
                args, rest = parser.parse_known_args(argv)
                if rest:
                    assert rest[0] == "--ros-args", f"README: {command}"
                for name in re.findall(r"-p (\w+):=", " ".join(rest)):
                    assert name in params, f"README: {command}: {name} is not a node parameter"
            else:
                parser.parse_args(argv)
            checked += 1
    assert checked >= 12


def test_every_inline_bearing_sim_option_exists():
    """`bearing-sim SUB --option ...` in the text: the subcommand and every option it shows
    exist (``--bogus`` is the README's example of a wrong argument; ROS's follow --ros-args)."""
    _parser, subs = _subparsers()
    mentions = re.findall(r"`bearing-sim ([a-z]+)((?: [^`]*)?)`", README)
    assert len(mentions) > 20
    for sub, rest in mentions:
        assert sub in subs, f"README: bearing-sim {sub}: no such command"
        for option in re.findall(r"(?<!\S)(--[\w-]+)", rest.split("--ros-args")[0]):
            if option != "--bogus":
                assert option in subs[sub]._option_string_actions, f"README: bearing-sim {sub}: no option {option}"


def test_node_parameters_named_in_the_readme_exist():
    """`-p name:=` and the parameter table name the node's parameters, and the table lists
    every one of them."""
    from bearing_sim_ros.nodes.bearing_sim_node import _descriptors

    params = set(_descriptors())
    for name in set(re.findall(r"-p (\w+):=", README)) - {"sampel_rate"}:   # the README's misspelt example
        assert name in params, f"README: -p {name}: not a node parameter"
    section = README.split("### Parameters", 1)[1].split("\n### ", 1)[0]
    tabled = set(re.findall(r"^\| `(\w+)` \|", section, flags=re.M))
    assert tabled == params, f"README parameter table: missing {params - tabled}, unknown {tabled - params}"


def test_python_m_commands_name_existing_options():
    """``python -m bearing_sim_ros.X --opt``: the module exists and its help names each option."""
    modules = {}
    for module, rest in re.findall(r"python -m (bearing_sim_ros[\w.]+)([^\n`#]*)", README):
        modules.setdefault(module, set()).update(re.findall(r"(?<!\S)(--[\w-]+)", rest))
    assert "bearing_sim_ros.nodes.node_bench" in modules
    for module, options in modules.items():
        path = REPO / (module.replace(".", "/") + ".py")
        assert path.is_file(), f"README: python -m {module}: no such module"
        if "argparse" in path.read_text():
            text = subprocess.run([sys.executable, "-m", module, "--help"], cwd=REPO, capture_output=True,
                                  text=True, check=True).stdout
        else:
            text = path.read_text()
        for option in options:
            assert re.search(rf"(?<![\w-]){option}(?![\w-])", text), f"README: python -m {module}: no option {option}"


def test_make_variables_and_targets_exist():
    """``make run SCENE=... DURATION=...``: the targets and variables are the Makefile's."""
    makefile = (REPO / "Makefile").read_text()
    uses = re.findall(r"`?make ((?:[a-z]+)(?: [A-Z]+=\S+)*)", README)
    assert uses
    for use in uses:
        target, *assignments = use.split()
        assert re.search(rf"^{target}:", makefile, flags=re.M), f"README: make {target}: no such target"
        for assignment in assignments:
            name = assignment.split("=")[0]
            assert re.search(rf"^{name}\s*\?=", makefile, flags=re.M), f"README: make {name}=: not a variable"


def test_scene_names_in_the_readme_are_shipped():
    from bearing_sim_ros.scene import shipped_scenes

    shipped = set(shipped_scenes())
    named = set(re.findall(r"\b((?:er16k|cwru_6205|b6205|b6307)_[a-z0-9_]+)\b", README))
    assert named and named <= shipped, f"README names scenes that are not shipped: {sorted(named - shipped)}"
    table = README.split("## Scenes", 1)[1].split("\n## ", 1)[0]
    assert shipped <= set(re.findall(r"`(\w+)`", table)), "the README's scene table misses a shipped scene"


def test_the_launch_file_offers_every_node_parameter_with_its_default():
    """``ros2 launch bearing_sim_ros bearing_sim.launch.py NAME:=...`` (README, "The live node"):
    ``launch`` has no wheel here, so its ARGUMENTS table is read from the source and checked
    against the node's parameters: every one, with the node's default."""
    from bearing_sim_ros.nodes.bearing_sim_node import _descriptors

    tree = ast.parse((REPO / "launch" / "bearing_sim.launch.py").read_text())
    (table,) = [n.value for n in tree.body if isinstance(n, ast.Assign) and n.targets[0].id == "ARGUMENTS"]
    arguments = {row.elts[0].value: (row.elts[1].value, row.elts[2].id) for row in table.elts}
    descriptors = _descriptors()
    assert set(arguments) == set(descriptors)
    casts = {"str": str, "float": float, "int": int, "bool": lambda text: text == "true"}
    for name, (default_text, kind) in arguments.items():
        assert casts[kind](default_text) == descriptors[name][0], f"launch {name}:={default_text}"
    for name in re.findall(r"bearing_sim\.launch\.py((?: \w+:=\S+)+)", README):
        for arg in re.findall(r"(\w+):=", name):
            assert arg in arguments or arg == "namespace", f"README: launch argument {arg}"


def test_test_counts_quoted_in_the_readme_are_the_suites():
    """"`python -m pytest -q test/test_X.py` (N tests, ...)": N is what pytest collects there."""
    quoted = re.findall(r"`python -m pytest -q (test/\w+\.py)` \((\d+) tests", README)
    assert quoted
    for path, count in quoted:
        out = subprocess.run([sys.executable, "-m", "pytest", "-q", "--collect-only", "-p", "no:cacheprovider",
                              path], cwd=REPO, capture_output=True, text=True).stdout
        assert f"{count} tests collected" in out, f"README: {path} has {count} tests; pytest: {out.splitlines()[-1:]}"
