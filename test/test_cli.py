"""``bearing-sim`` as a newcomer meets it: every option's help gives its unit and default, and
error lines show numbers as a user types them."""
from __future__ import annotations

import errno
import math
import re
import signal
import subprocess

import numpy as np
import pytest

from test_node_support import closed_as_it_writes, signal_at_import

from bearing_sim_ros import Simulator, UserError, cli
from bearing_sim_ros.limits import RPM


def _subcommands():
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return sub.choices


def test_every_option_has_help_with_its_default():
    """Each option of each subcommand says what it is and what happens without it (a default or
    "required"); numeric options name their unit or what the number counts."""
    missing = []
    for name, parser in _subcommands().items():
        for action in parser._actions:
            if action.dest == "help":
                continue
            helptext = (action.help or "") % {"default": action.default, "prog": parser.prog}
            if not helptext:
                missing.append(f"{name} {action.option_strings or action.dest}: no help")
            elif action.option_strings and "default" not in helptext and "required" not in helptext:
                missing.append(f"{name} {action.option_strings[0]}: no default in {helptext!r}")
    assert not missing, "\n".join(missing)


@pytest.mark.parametrize("command, option, words", [
    ("render", "--sample-rate", ["Hz", "15000", "1000 to 200000"]),
    ("render", "--duration", ["seconds"]),
    ("render", "--seed", ["0"]),
    ("render", "--rk4-step", ["s,", "1e-05"]),
    ("play", "--rate", ["real time", "1", "0.01 to 100", "as fast as it can"]),
    ("run", "--duration", ["seconds", "10"]),
    ("monitor", "--window", ["seconds", "4"]),
    ("monitor", "--end-wait", ["0 to 3600", "default: 5 with --count"]),
    ("report", "--window", ["seconds", "default: 1)", "0.5 to 120"]),
])
def test_numeric_options_give_unit_and_default(command, option, words):
    parser = _subcommands()[command]
    action = next(a for a in parser._actions if option in a.option_strings)
    helptext = action.help % {"default": action.default}
    for w in words:
        assert w in helptext, helptext


def test_node_help_says_where_ros_arguments_go(capsys):
    assert cli.main(["node", "--help"]) == 0
    out = capsys.readouterr().out
    assert "[--ros-args ...]" in out.splitlines()[0]
    assert "--ros-args -p duration:=10.0" in out


def test_the_node_help_example_runs(ros_env, bearing_sim_exe, tmp_path, capsys):
    """The example of ``bearing-sim node --help`` runs as printed (here as fast as possible).  It
    gave ``-p duration:=10``, which ROS types as an integer, and the node refused it: ``error:
    parameter duration = 10: wrong type, expected a floating-point number such as 1.0``."""
    import shlex

    assert cli.main(["node", "--help"]) == 0
    example = next(ln for ln in capsys.readouterr().out.splitlines() if ln.strip().startswith("bearing-sim node "))
    r = subprocess.run([bearing_sim_exe, *shlex.split(example)[1:], "-p", "real_time:=false"],
                       cwd=tmp_path, env=ros_env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "run.mcap").stat().st_size > 0


def test_monitor_help_says_where_ros_arguments_go(capsys):
    assert cli.main(["monitor", "--help"]) == 0
    out = capsys.readouterr().out
    assert "[--ros-args ...]" in out.splitlines()[0]
    assert "--ros-args -r __ns:=/rig1" in out and "--simulator NAME" in out


@pytest.mark.parametrize("argv", [
    ["monitor", "--bogus"],
    ["play", "a.mcap", "b.mcap", "--bogus"],          # several files are a split recording's pieces
    ["report", "a.mcap", "--out", "r", "--bogus"],
    ["scenes", "extra"],
    ["validate", "--cwru", "c", "--out", "v", "--bogus"],
])
def test_a_stray_argument_is_named_with_its_command(capsys, argv):
    """As `node` does: one line that says which command did not take it, exit status 2, before
    any work (nothing is read or written)."""
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: bearing-sim {argv[0]}: unrecognized arguments: "), err


@pytest.mark.parametrize("command", [["node", "--scene", "", "--ros-args", "-p", "duration:=0.05", "-p",
                                      "real_time:=false"],
                                     ["monitor", "--scene", "", "--count", "1"]])
def test_an_empty_scene_is_refused_not_the_default(bearing_sim_exe, ros_env, command):
    """``bearing-sim node --scene "$SCENE"`` with SCENE unset ran the default scene without a word
    (``monitor`` alike), where ``run`` and ``render`` refuse an empty scene: now the same line,
    exit 2."""
    done = subprocess.run([bearing_sim_exe, *command], env=ros_env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("error: scene = '': an empty path; give a YAML path or one of b6205_ball_inner")
    assert len(done.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("param", ["scene:=er16k_outer_race", "bearing_sim:scene:=er16k_outer_race"])
def test_node_refuses_two_scenes(capsys, param):
    """``bearing-sim node --scene A --ros-args -p scene:=B`` ran B without a word (rcl takes the
    last override): one line naming both, exit 2, before the node starts."""
    assert cli.main(["node", "--scene", "er16k_healthy", "--ros-args", "-p", param]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: bearing-sim node: --scene er16k_healthy and -p {param} name two scenes; give one"]


@pytest.mark.parametrize("name", ["", "bad!name", "/", "a//b", "1abc", "rig1/"])
def test_monitor_refuses_a_simulator_that_is_no_node_name(name):
    """``monitor --simulator bad!name`` (or '', '/') named no node that could ever publish its
    ground truth, and the monitor ran on without one, saying only which status it watched."""
    with pytest.raises(UserError) as exc:
        cli.build_parser().parse_args(["monitor", "--simulator", name])
    assert str(exc.value) == (f"bearing-sim monitor: argument --simulator: {name!r} is not a ROS node name: letters, "
                              "digits and _, not starting with a digit, namespaces before it with /, e.g. "
                              "bearing_sim, rig1/bearing_sim, /bearing_sim")
    for good in ("sim", "rig1/bearing_sim", "/bearing_sim"):
        assert cli.build_parser().parse_args(["monitor", "--simulator", good]).simulator == good


@pytest.mark.parametrize("text", [
    "bearing_sim:\n  ros__parameters:\n    scene: er16k_outer_race\n",
    "/**:\n  ros__parameters:\n    scene: er16k_outer_race\n",
    "rig1:\n  bearing_sim:\n    ros__parameters:\n      scene: er16k_outer_race\n",
])
def test_node_refuses_a_scene_and_a_params_files_scene(capsys, tmp_path, text):
    """``bearing-sim node --scene A --ros-args --params-file f.yaml`` with ``scene: B`` in the file
    ran B without a word (the file comes after --scene's -p, and rcl takes the last): one line
    naming both, exit 2, before the node starts."""
    path = tmp_path / "params.yaml"
    path.write_text(text)
    # (a duration: the old code ran the node)
    assert cli.main(["node", "--scene", "er16k_healthy", "--ros-args", "--params-file", str(path),
                     "-p", "duration:=0.05", "-p", "real_time:=false"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: bearing-sim node: --scene er16k_healthy and --params-file {path} (scene: er16k_outer_race) "
                   "name two scenes; give one"]


@pytest.mark.parametrize("text, status, said", [
    ("bearing_sim:\n  ros__parameters:\n    duration: 0.05\n", 0, "duration 0.05 s"),
    ("bearing_sim:\n  ros__parameters:\n    scene: er16k_outer_race\n", 2, "(scene: er16k_outer_race) name two scenes"),
])
def test_node_with_a_scene_takes_a_params_file_from_a_pipe(ros_env, bearing_sim_exe, tmp_path, text, status, said):
    """``bearing-sim node --scene A --ros-args --params-file FIFO`` (or ``<(...)``): the check for a
    second scene read the pipe, and rcl then waited on the FIFO for good (or found ``<(...)`` empty
    and ran without the file's parameters).  The pipe is read once, its parameters reach the node,
    and a second scene in it is named with the path given."""
    import os
    import threading

    fifo = tmp_path / "params.yaml"
    os.mkfifo(fifo)

    def write_once():
        with open(fifo, "w") as f:      # blocks until the command opens the FIFO
            f.write(text)

    writer = threading.Thread(target=write_once, daemon=True)
    writer.start()
    try:
        r = subprocess.run([bearing_sim_exe, "node", "--scene", "er16k_healthy", "--ros-args", "--params-file",
                            str(fifo), "-p", "real_time:=false"], env=ros_env, capture_output=True, text=True,
                           timeout=60)
    finally:
        if writer.is_alive():           # the command never opened it: let the thread go
            os.close(os.open(fifo, os.O_RDONLY | os.O_NONBLOCK))
    assert r.returncode == status, r.stdout + r.stderr
    assert said in r.stdout + r.stderr, r.stdout + r.stderr
    if status:
        assert r.stderr.strip().splitlines() == [
            f"error: bearing-sim node: --scene er16k_healthy and --params-file {fifo} (scene: er16k_outer_race) "
            "name two scenes; give one"]


def test_a_bad_params_file_from_a_pipe_is_named_as_given(ros_env, bearing_sim_exe, tmp_path):
    """rcl's line for a pipe that is no parameters file names the path the user gave, not the
    in-memory copy rcl read (``/proc/self/fd/N``)."""
    import os
    import threading

    fifo = tmp_path / "params.yaml"
    os.mkfifo(fifo)
    threading.Thread(target=lambda: fifo.write_text("bearing_sim: [\n"), daemon=True).start()
    r = subprocess.run([bearing_sim_exe, "node", "--scene", "er16k_healthy", "--ros-args", "--params-file",
                        str(fifo)], env=ros_env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stdout + r.stderr
    line = r.stderr.strip().splitlines()[-1]
    assert line.startswith(f"error: ROS arguments: Couldn't parse params file: '--params-file {fifo}'"), line
    assert "/proc/self" not in r.stderr, r.stderr


def test_a_params_file_without_the_nodes_scene_goes_with_scene(tmp_path):
    """Another node's scene, or a file rcl will refuse, is no second scene."""
    from bearing_sim_ros.cli import _params_file_scenes

    path = tmp_path / "params.yaml"
    path.write_text("bearing_monitor:\n  ros__parameters:\n    scene: er16k_outer_race\n"
                    "bearing_sim:\n  ros__parameters:\n    duration: 3.0\n")
    assert _params_file_scenes(["--params-file", str(path), "--params-file", "/nonexistent.yaml"]) == []


@pytest.mark.parametrize("argv, line", [
    # Path("") is the current folder: an empty argument (an unset $VAR) was "'': is a folder, not a
    # file" for a scene, ": is a folder, not a file" for a recording, and validate read the
    # current folder
    (["render", "", "--duration", "1", "--out", "x.mcap"], "error: scene = '': an empty path; give a YAML path or one of "),
    (["report", "", "--out", "r"], "error: '': an empty path; expected an .mcap recording"),
    (["play", ""], "error: '': an empty path; expected an .mcap recording"),
    (["validate", "--cwru", "", "--out", "v"], "error: --cwru '': an empty path; give a folder of CWRU .mat files"),
])
def test_an_empty_path_is_named_empty_not_a_folder(tmp_path, monkeypatch, capsys, argv, line):
    monkeypatch.chdir(tmp_path)
    code, err = _user_mistake(capsys, argv)
    assert code == 2 and err.startswith(line), err
    assert not any(tmp_path.iterdir())


def test_non_finite_inputs_are_named_with_plain_numbers():
    sim = Simulator("er16k_outer_race", fidelity="kinematic")
    with pytest.raises(UserError) as speed:
        sim.advance(150, shaft_speed=math.nan)
    with pytest.raises(UserError) as load:
        sim.advance(150, radial_load=(math.nan, 0.0))
    assert str(speed.value) == "shaft_speed = nan rad/s: must be a finite number"
    assert str(load.value) == "radial_load = (nan, 0.0) N: must be finite numbers"
    with pytest.raises(UserError) as load_y:         # each of the two, not only x
        sim.advance(150, radial_load=(0.0, -math.inf))
    assert str(load_y.value) == "radial_load = (0.0, -inf) N: must be finite numbers"
    assert "np." not in str(speed.value) + str(load.value)


def _user_mistake(capsys, argv):
    """``bearing-sim argv`` in this process: (exit status, its one stderr line)."""
    code = cli.main(argv)
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    return code, lines[0]


@pytest.mark.parametrize("argv, words", [
    # inf passed the > 0 checks: render said "--duration = inf: expected seconds > 0", play waited
    # or played forever
    (["render", "er16k_healthy", "--duration", "inf"], ["--duration", "'inf'", "finite number > 0"]),
    (["render", "er16k_healthy", "--duration", "1e400"], ["--duration", "'1e400'", "finite number > 0"]),
    (["play", "x.mcap", "--rate", "inf"], ["--rate", "inf", "allowed range is [0.01, 100]"]),
    (["play", "x.mcap", "--wait", "inf"], ["--wait", "inf s", "allowed range is [0, 3600] s"]),
    # finite, but a wait for a subscriber that never ends in practice
    (["play", "x.mcap", "--wait", "1e300"], ["--wait", "1e300 s", "allowed range is [0, 3600] s"]),
    (["monitor", "--window", "inf"], ["--window", "inf s", "allowed range is [0.5, 120] s"]),
    # a window of 0.1 ms gave "x inf" prominences and a fault verdict on anything
    (["monitor", "--window", "0.0001"], ["--window", "0.0001 s", "allowed range is [0.5, 120] s"]),
    # a negative number in scientific notation (or -inf) was read by argparse as an unknown
    # option: "argument --duration: expected one argument", the value never named
    (["render", "er16k_healthy", "--duration", "-1e3"], ["--duration", "'-1e3'", "finite number > 0"]),
    (["render", "er16k_healthy", "--duration", "-inf"], ["--duration", "'-inf'", "finite number > 0"]),
    (["render", "er16k_healthy", "--duration", "0.1", "--seed", "-1E3"], ["--seed", "'-1E3'", "not a whole number"]),
    (["play", "x.mcap", "--rate", "-2e0"], ["--rate", "-2e0", "allowed range is [0.01, 100]"]),
    (["report", "x.mcap", "--out", "r", "--window", "-1.5e+1"], ["--window", "-1.5e+1 s", "allowed range is [0.5, 120] s"]),
    # a seed beyond 64 bits ended in an OverflowError traceback (exit 1)
    (["render", "er16k_healthy", "--duration", "0.1", "--seed", "99999999999999999999999"],
     ["--seed", "'99999999999999999999999'", "<= 2147483647"]),
])
def test_non_finite_and_huge_numbers_are_one_line_naming_the_option(tmp_path, capsys, argv, words):
    code, line = _user_mistake(capsys, [*argv, *(["--out", str(tmp_path / "x.mcap")] if argv[0] == "render" else [])])
    assert code == 2
    for w in words:
        assert w in line, line
    assert not (tmp_path / "x.mcap").exists()


def test_seed_range_is_the_nodes():
    """One range of seeds for the API, ``render --seed`` and the node's ``seed``: a seed that
    renders also runs live."""
    from bearing_sim_ros.nodes.bearing_sim_node import _descriptors
    from bearing_sim_ros.simulator import SEED_RANGE

    span = _descriptors()["seed"][1].integer_range[0]
    assert (span.from_value, span.to_value) == SEED_RANGE
    assert Simulator("er16k_healthy", seed=np.int64(SEED_RANGE[1])).seed == SEED_RANGE[1]
    for bad in (SEED_RANGE[1] + 1, 2 ** 63, -1, True, 1.5):
        with pytest.raises(UserError) as exc:
            Simulator("er16k_healthy", seed=bad)
        assert str(exc.value) == f"seed = {bad!r}: expected a whole number in [0, 2147483647]"


@pytest.mark.parametrize("step", [-1.0, 0.0, math.nan, 1.0, "1e-6", True])
def test_a_bad_rk4_step_is_refused_when_the_simulator_is_made(step):
    """Where fidelity auto starts on the kinematic tier (er16k_healthy), ``rk4_step`` of -1, NaN
    or "1e-6" was taken without a word, and refused at the first switch to the skidding tier, in
    the middle of a run; now at once, in the line the skidding tier gives it."""
    from bearing_sim_ros.physics.integrators import RK4_STEP_RANGE

    with pytest.raises(UserError) as exc:
        Simulator("er16k_healthy", solver="rk4", rk4_step=step)
    assert str(exc.value) == f"rk4_step = {step!r}: allowed range is [1e-09, 0.001] s"
    assert Simulator("er16k_healthy", solver="rk4", rk4_step=RK4_STEP_RANGE[1]).rk4_step == RK4_STEP_RANGE[1]


def test_a_scene_path_with_a_nul_is_one_line():
    """A NUL in a scene path given in Python was os.stat's ValueError ("embedded null byte")."""
    from bearing_sim_ros import load_scene

    with pytest.raises(UserError) as exc:
        load_scene("scenes/a\0b.yaml")
    assert str(exc.value).startswith("scene = 'scenes/a\\x00b.yaml': not a path: it holds a NUL character; "
                                     "give a YAML path or one of "), str(exc.value)


@pytest.mark.parametrize("call, message", [
    # a string or a list ended in ValueError/TypeError from float(), a wrong length in
    # "cannot reshape array"
    (lambda s: s.advance(10, shaft_speed="fast"), "shaft_speed = 'fast': expected a number, rad/s"),
    (lambda s: s.advance(10, radial_load=(1.0, 2.0, 3.0)), "radial_load = (1.0, 2.0, 3.0): expected two numbers (x, y), N"),
    (lambda s: s.advance(10, radial_load=5.0), "radial_load = 5.0: expected two numbers (x, y), N"),
    # float() took a string or a bool for a number: '167' ran at 167 rad/s, True at 1 rad/s
    (lambda s: s.advance(10, shaft_speed="167"), "shaft_speed = '167': expected a number, rad/s"),
    (lambda s: s.advance(10, shaft_speed=True), "shaft_speed = True: expected a number, rad/s"),
    (lambda s: s.advance(10, radial_load=("0", "-50")), "radial_load = ('0', '-50'): expected two numbers (x, y), N"),
    (lambda s: s.advance(10, radial_load="05"), "radial_load = '05': expected two numbers (x, y), N"),
    # beyond a scene's bounds the kinematic tier returned NaN without a word; beyond the bearing's
    # own (a scene's, the node's) advance ran on: 900 kN put 444 kN on one ball of an ER-16K
    (lambda s: s.advance(10, shaft_speed=1e9),
     "shaft_speed = 1e+09 rad/s (9.5493e+09 rpm): beyond what bearing ER-16K takes (|speed| <= 25974 rpm, "
     "n*dm <= 1e+06 rpm mm)"),
    (lambda s: s.advance(10, shaft_speed=-30000 * RPM),
     "shaft_speed = -3141.59 rad/s (-30000 rpm): beyond what bearing ER-16K takes (|speed| <= 25974 rpm, "
     "n*dm <= 1e+06 rpm mm)"),
    (lambda s: s.advance(10, radial_load=(0.0, -1e12)),
     "radial_load = [0, -1e+12] N: |F| = 1e+12 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
    (lambda s: s.advance(10, radial_load=(0.0, -900000.0)),
     "radial_load = [0, -900000] N: |F| = 900000 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
    (lambda s: s.advance(10, radial_load=(12000.0, -12000.0)),
     "radial_load = [12000, -12000] N: |F| = 16970.6 N beyond 2 x C0 = 16681 N of bearing ER-16K"),
])
def test_advance_names_a_bad_speed_or_load_and_what_is_allowed(call, message):
    """``advance`` holds a speed and load to the bearing's limits, as a scene and the node do."""
    sim = Simulator("er16k_healthy", fidelity="kinematic")
    with pytest.raises(UserError) as exc:
        call(sim)
    assert str(exc.value) == message
    assert sim.index == 0                     # nothing advanced
    inside = sim.advance(10, shaft_speed=25970 * RPM, radial_load=np.array([11790.0, -11790.0]))
    assert np.isfinite(inside.accel).all() and sim.index == 10


@pytest.mark.parametrize("load, shown", [
    ([[0, -50]], "[[0, -50]]"),                                  # nested: was taken as (0, -50)
    (np.array([[0.0], [-50.0]]), "array([[  0.], [-50.]])"),     # a (2, 1) array: taken as well
    (np.zeros((1, 1, 2)), "array([[[0., 0.]]])"),
    ([[0], -50], "[[0], -50]"),                                  # ragged: numpy's ValueError
    ([0, -50, 1], "[0, -50, 1]"),
    ("0,-50", "'0,-50'"),
    ({"x": 0, "y": -50}, "{'x': 0, 'y': -50}"),
])
@pytest.mark.parametrize("method", ["advance", "switch_ahead", "maybe_switch_tier"])
def test_a_load_that_is_not_two_numbers_is_one_line_in_every_method_that_takes_one(method, load, shown):
    """``radial_load`` is a pair of numbers: ``advance`` took anything numpy could reshape to two
    ([[0, -50]], a column), ``switch_ahead`` and ``maybe_switch_tier`` (which the node calls) did
    not check at all (numpy's "truth value of an array" or "could not convert")."""
    sim = Simulator("er16k_healthy", fidelity="auto")
    before = sim.radial_load
    call = {"advance": lambda: sim.advance(10, radial_load=load),
            "switch_ahead": lambda: sim.switch_ahead(167.0, load),
            "maybe_switch_tier": lambda: sim.maybe_switch_tier(167.0, load)}[method]
    with pytest.raises(UserError) as exc:
        call()
    assert str(exc.value) == f"radial_load = {shown}: expected two numbers (x, y), N"
    assert sim.index == 0 and sim.radial_load == before


@pytest.mark.parametrize("method", ["advance", "switch_ahead", "maybe_switch_tier"])
def test_a_speed_or_load_beyond_floats_is_one_line_with_its_digits_cut(method):
    """An int too large for a float (10**400) was float()'s OverflowError from ``advance``; the
    other two took a string for a speed or ended in a TypeError on a list."""
    sim = Simulator("er16k_healthy", fidelity="auto")
    call = {"advance": lambda s, l: sim.advance(10, shaft_speed=s, radial_load=l),
            "switch_ahead": sim.switch_ahead, "maybe_switch_tier": sim.maybe_switch_tier}[method]
    cut = "100000000000000000...0000000000000000000"
    for speed, load, message in [(10 ** 400, (0.0, -50.0), f"shaft_speed = {cut} rad/s: must be a finite number"),
                                 (167.0, [10 ** 400, 0], f"radial_load = ({cut}, 0) N: must be finite numbers"),
                                 ("167", (0.0, -50.0), "shaft_speed = '167': expected a number, rad/s"),
                                 ([167.0], (0.0, -50.0), "shaft_speed = [167.0]: expected a number, rad/s"),
                                 (math.nan, (0.0, -50.0), "shaft_speed = nan rad/s: must be a finite number"),
                                 (1e9, (0.0, -50.0), "shaft_speed = 1e+09 rad/s (9.5493e+09 rpm): beyond what "
                                  "bearing ER-16K takes (|speed| <= 25974 rpm, n*dm <= 1e+06 rpm mm)")]:
        with pytest.raises(UserError) as exc:
            call(speed, load)
        assert str(exc.value) == message
    assert sim.index == 0
    # a pair in any of the usual forms, numpy's numbers too, is taken
    for load in ((0.0, -50.0), [0, -50], np.array([0.0, -50.0]), (np.float32(0), np.int64(-50))):
        call(np.float64(167.0), load)


@pytest.mark.parametrize("key", ["sample_rate", "seed", "oversample", "tolerance", "fidelity", "solver", "rk4_step"])
@pytest.mark.parametrize("value", [np.array([[15000.0], [1.0]]), 10 ** 400, "x" * 5000],
                         ids=["2-D array", "400 digits", "5000 characters"])
def test_a_bad_setting_of_any_size_is_named_on_one_short_line(key, value):
    """The constructor's refusals printed the value's full repr: numpy's for a 2-D array spans
    lines, and 10**400 or a 5000-character string made a "one line" of thousands of characters."""
    settings = {key: value}
    if key == "rk4_step":
        settings["solver"] = "rk4"
    with pytest.raises(UserError) as exc:
        Simulator("er16k_healthy", **settings)
    text = str(exc.value)
    assert text.startswith(f"{key} = ") and "\n" not in text and len(text) < 250, text
    if not isinstance(value, int):         # a sample index may be any whole number
        with pytest.raises(UserError) as exc:
            Simulator("er16k_healthy", fidelity="kinematic").defect_sizes_at(value)
        assert "\n" not in str(exc.value) and len(str(exc.value)) < 250


@pytest.mark.parametrize("sample_rate, n", [(15000.0, 10 ** 12), (15000.0, 2 ** 20 + 1), (1000.0, 10 ** 9)])
def test_an_advance_too_large_to_hold_in_memory_is_refused_in_one_line(sample_rate, n):
    """``advance(10**12)`` died with a MemoryError (a smaller huge one could meet the OOM killer
    first): every series of a call is held at once.  Now one line names ``n``, the most one call
    takes (``sim.max_advance``, MAX_ADVANCE_INTERNAL internal samples) and the way on: chunks,
    which give the same samples."""
    from bearing_sim_ros.simulator import MAX_ADVANCE_INTERNAL

    sim = Simulator("er16k_healthy", fidelity="kinematic", sample_rate=sample_rate)
    assert sim.max_advance == MAX_ADVANCE_INTERNAL // sim.chain_oversample
    with pytest.raises(UserError) as exc:
        sim.advance(n)
    assert str(exc.value) == (
        f"n = {n}: at most {sim.max_advance} samples ({sim.max_advance / sample_rate:g} s) per advance at "
        f"{sample_rate:g} Hz ({MAX_ADVANCE_INTERNAL} internal samples, about 2 GB of arrays); advance in chunks "
        "of up to sim.max_advance, which give the same samples")
    assert sim.index == 0


@pytest.mark.parametrize("n", [0, -1])
def test_an_advance_of_no_samples_or_fewer_is_refused_in_one_line(n):
    """``advance`` takes 1 - ``max_advance`` samples: 0 is a mistake (a loop's count that came
    out empty), said as one, not an empty batch."""
    sim = Simulator("er16k_healthy", fidelity="kinematic")
    with pytest.raises(UserError) as exc:
        sim.advance(n)
    assert str(exc.value) == f"n = {n}: expected a whole number of samples > 0"
    assert sim.index == 0


def test_an_advance_of_exactly_max_advance_samples_is_taken(monkeypatch):
    """``advance`` takes 1 - ``max_advance`` samples (its docstring, the error's "at most"): the
    bound itself runs and one more is refused.  The memory bound is made small here (the real one
    is 70 s of signal) by the module's ``MAX_ADVANCE_INTERNAL``, which ``max_advance`` reads."""
    from bearing_sim_ros import simulator

    sim = Simulator("er16k_healthy", fidelity="kinematic")
    monkeypatch.setattr(simulator, "MAX_ADVANCE_INTERNAL", 300 * sim.chain_oversample)
    assert sim.max_advance == 300
    assert sim.advance(300).n == 300
    with pytest.raises(UserError, match=r"^n = 301: at most 300 samples \(0.02 s\)"):
        sim.advance(301)
    assert sim.index == 300


@pytest.mark.parametrize("call, message", [
    # True is an int to Python: advance(True) advanced one sample, oversample=np.int64(4) was refused
    (lambda: Simulator("er16k_healthy", fidelity="kinematic").advance(True),
     "n = True: expected a whole number of samples > 0"),
    (lambda: Simulator("er16k_healthy", fidelity="kinematic").advance(False),
     "n = False: expected a whole number of samples > 0"),
    (lambda: Simulator("er16k_healthy", seed=False), "seed = False: expected a whole number in [0, 2147483647]"),
    (lambda: Simulator("er16k_healthy", fidelity="kinematic", oversample=True),
     "oversample = True: allowed values are 1, 2 or a multiple of 4 up to 64"),
])
def test_bools_are_not_whole_numbers(call, message):
    with pytest.raises(UserError) as exc:
        call()
    assert str(exc.value) == message


@pytest.mark.parametrize("call, message", [
    # settings that did nothing, silently: the CLI refuses them the same way
    (lambda: Simulator("er16k_healthy", fidelity="kinematic", solver="rk4"),
     "solver = 'rk4': applies to the skidding tier only, and fidelity='kinematic' runs the kinematic tier"),
    (lambda: Simulator("er16k_healthy", fidelity="skidding", rk4_step=2e-6),
     "rk4_step = 2e-06: applies to solver='rk4' only (given solver='default')"),
    # these two solvers keep their own steps: oversample=8 ran them as without it
    (lambda: Simulator("er16k_healthy", fidelity="skidding", solver="reference", oversample=8),
     "oversample = 8: solver reference keeps its own step; oversample applies to the kinematic tier "
     "and solver default only"),
    (lambda: Simulator("er16k_skidding", solver="rk4", rk4_step=2e-6, oversample=4),
     "oversample = 4: solver rk4 keeps its own step; oversample applies to the kinematic tier "
     "and solver default only"),
])
def test_solver_settings_that_would_do_nothing_are_named(call, message):
    with pytest.raises(UserError) as exc:
        call()
    assert str(exc.value) == message


def test_oversample_takes_1_2_and_the_multiples_of_4_up_to_64_and_auto_up_to_4():
    """The allowed values as the README and the error say them, bounds included: 64 is the
    largest, 4 the largest where fidelity auto may switch tiers (both tiers then share the chain's
    rate); 8 with auto is refused in one line naming the way on."""
    from bearing_sim_ros.simulator import OversampleForAuto, oversample_allowed

    assert [v for v in range(0, 70) if oversample_allowed(v)] == [1, 2] + list(range(4, 65, 4))
    assert Simulator("er16k_healthy", oversample=4).oversample == 4           # auto: kinematic here
    with pytest.raises(OversampleForAuto, match=r"^oversample = 8: with fidelity auto allowed values are 1, 2 or 4 "):
        Simulator("er16k_healthy", oversample=8)


def test_numpy_integers_are_whole_numbers():
    sim = Simulator("er16k_healthy", fidelity="kinematic", seed=np.int32(3), oversample=np.int64(4))
    assert sim.oversample == 4 and type(sim.oversample) is int
    assert sim.advance(np.int64(2)).n == 2


@pytest.mark.parametrize("tolerance", [-1.0, 0.0, math.nan, "x"])
def test_tolerance_outside_the_scenes_range_is_named(tolerance):
    """``tolerance`` (the fidelity choice's allowed error) was taken as given: a string ended in
    a TypeError, a negative or NaN one silently picked a tier."""
    with pytest.raises(UserError) as exc:
        Simulator("er16k_healthy", tolerance=tolerance)
    assert str(exc.value).startswith(f"tolerance = {tolerance!r}: allowed range is [0.0001, 1]")


@pytest.mark.parametrize("out, words", [
    ("", ["--out = ''", "expected the path of a folder"]),              # wrote into the current folder
    ("a_file", ["--out = ", "a_file", "exists and is not a folder"]),
    ("/proc/no_folder_here", ["--out = '/proc/no_folder_here'", "cannot create the folder"]),
    # a folder that exists and cannot be written: report ended in a FileNotFoundError traceback
    # after all its work, bench after minutes of it
    ("/proc/self", ["--out = '/proc/self'", "cannot write in the folder"]),
])
@pytest.mark.parametrize("command", ["report", "bench", "validate"])
def test_output_folders_are_checked_before_the_work(tmp_path, capsys, monkeypatch, command, out, words):
    """report, bench and validate write into a folder: an empty --out, a file or a folder that
    cannot be created is one line naming --out before anything is computed (validate used to
    compute for seconds, then end in a FileNotFoundError traceback; an empty --out wrote into
    the current folder)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a_file").write_text("x")
    argv = {"report": ["report", "rec.mcap", "--out", out],
            "bench": ["bench", "--quick", "--out", out],
            "validate": ["validate", "--cwru", "normal_0_97.mat", "--out", out]}[command]
    if command == "report":
        from bearing_sim_ros.recording.render import render

        render("er16k_healthy", 0.05, tmp_path / "rec.mcap", fidelity="kinematic")
    if command == "validate":            # a usable input: --cwru is checked first
        from scipy.io import savemat

        savemat(str(tmp_path / "normal_0_97.mat"), {"X097_DE_time": np.zeros((48000, 1))})
    code, line = _user_mistake(capsys, argv)
    assert code == 2
    for w in words:
        assert w in line, line
    assert {p.name for p in tmp_path.iterdir()} <= {"a_file", "rec.mcap", "normal_0_97.mat"}    # nothing written


@pytest.mark.parametrize("command", ["report", "bench"])
def test_a_failed_final_write_is_one_line(tmp_path, capsys, monkeypatch, command):
    """A full disk (or the folder made read-only) during the final writes ended in a traceback,
    exit 1: it is one line naming --out and why, exit 2."""
    import errno

    def full(*_a, **_kw):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.chdir(tmp_path)
    if command == "report":
        from bearing_sim_ros.analysis import report
        from bearing_sim_ros.recording.render import render

        render("er16k_healthy", 0.05, tmp_path / "rec.mcap", fidelity="kinematic")
        monkeypatch.setattr(report, "plot_spectrum", full)
        argv = ["report", "rec.mcap", "--out", "rep"]
    else:
        from bearing_sim_ros import bench

        monkeypatch.setattr(bench, "study", lambda **_kw: {"rows": []})
        monkeypatch.setattr(bench, "default_against_rk4", lambda rows: {})
        monkeypatch.setattr(bench, "plot", full)
        monkeypatch.setattr(bench, "markdown", lambda result: "")
        argv = ["bench", "--quick", "--out", "rep"]
    code, line = _user_mistake(capsys, argv)
    assert code == 2 and line == "error: --out = 'rep': cannot write (No space left on device)", line


@pytest.mark.parametrize("out, words", [
    # render said "--out = '': cannot write there (IsADirectoryError: ... '.')"; run took the
    # empty path for the node's "no recording" and ended in an AttributeError traceback
    ("", ["--out = ''", "expected the path of an .mcap file"]),
    ("  ", ["--out = '  '", "expected the path of an .mcap file"]),
    ("a_folder", ["--out = 'a_folder'", "is a folder; expected the path of an .mcap file"]),
])
@pytest.mark.parametrize("command", ["render", "run"])
def test_output_files_are_named_when_empty_or_a_folder(tmp_path, capsys, monkeypatch, command, out, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a_folder").mkdir()
    argv = {"render": ["render", "er16k_healthy", "--duration", "0.1", "--out", out],
            "run": ["run", "--duration", "0.2", "--out", out]}[command]
    code, line = _user_mistake(capsys, argv)
    assert code == 2
    for w in words:
        assert w in line, line
    assert {p.name for p in tmp_path.iterdir()} == {"a_folder"} and not any((tmp_path / "a_folder").iterdir())


def test_the_recorder_names_a_folder_by_the_callers_argument(tmp_path):
    from bearing_sim_ros.recording.recorder import Recorder

    with pytest.raises(UserError) as exc:
        Recorder(tmp_path, {}, argument="record")
    assert str(exc.value) == f"record = {str(tmp_path)!r}: is a folder; expected the path of an .mcap file"


def test_numpy_real_numbers_are_numbers():
    """``sample_rate``, ``tolerance`` and ``rk4_step`` took only Python ints and floats: a rate
    read from a numpy array (``np.float32(15000)``, ``np.int64(12000)``) was refused as "allowed
    range is [1000, 200000] Hz", a value inside that range, while ``seed``, ``n`` and
    ``shaft_speed`` took numpy numbers.  Now they take any real number (a bool still is none)."""
    plain = Simulator("er16k_healthy", fidelity="kinematic", sample_rate=12000.0, tolerance=0.05).advance(40)
    for rate, tol in ((np.float32(12000), np.float32(0.05)), (np.int64(12000), np.float64(0.05))):
        sim = Simulator("er16k_healthy", fidelity="kinematic", sample_rate=rate, tolerance=tol)
        assert sim.sample_rate == 12000.0 and type(sim.sample_rate) is float
        assert np.array_equal(sim.advance(40).accel, plain.accel)
    step = np.float32(5e-6)
    rk4 = [Simulator("er16k_healthy", fidelity="skidding", solver="rk4", rk4_step=h).advance(3).accel
           for h in (step, float(step))]
    assert np.array_equal(*rk4)
    for call, message in (
            (lambda: Simulator("er16k_healthy", sample_rate=np.True_),
             "sample_rate = np.True_: allowed range is [1000, 200000] Hz"),
            (lambda: Simulator("er16k_healthy", sample_rate=np.float32("nan")),
             "sample_rate = np.float32(nan): allowed range is [1000, 200000] Hz"),
            (lambda: Simulator("er16k_healthy", fidelity="skidding", solver="rk4", rk4_step=np.int64(1)),
             "rk4_step = np.int64(1): allowed range is [1e-09, 0.001] s")):
        with pytest.raises(UserError) as exc:
            call()
        assert str(exc.value) == message


def test_a_reader_that_goes_away_ends_the_command_quietly(bearing_sim_exe):
    """``bearing-sim scenes | head -2``: the reader closed the pipe, and the command printed a
    BrokenPipeError traceback and "internal error" (exit 1).  Now nothing is said and the status
    is 141, as the shell reports for ``yes | head``."""
    proc = subprocess.Popen([bearing_sim_exe, "scenes"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()                 # gone before the first line
    err = proc.stderr.read().decode()
    assert proc.wait(60) == 141 and err == "", err


def test_ctrl_c_of_a_command_that_runs_no_node_exits_130(monkeypatch, capsys, tmp_path):
    """Ctrl-C of ``report`` (of ``render`` while it started, ``bench``, ...) exited 0 without a
    word, as if the command had done its work (``report x --out d && upload d`` uploaded a
    folder without its report).  Now 130, as the shell reports an interrupted command, and one
    line."""
    import bearing_sim_ros.analysis.report as report

    def interrupted(_args):
        raise KeyboardInterrupt

    monkeypatch.setattr(report, "report_command", interrupted)
    assert cli.main(["report", str(tmp_path / "x.mcap"), "--out", str(tmp_path / "d")]) == 130
    assert capsys.readouterr().err == "interrupted (Ctrl-C)\n"


def test_ctrl_c_while_the_parser_imports_numpy_is_an_interruption(monkeypatch, capsys):
    """Ctrl-C in a command's first tenths of a second, while building the parser imported numpy:
    raised there it came out of numpy as an ImportError ("Importing the numpy C-extensions
    failed ... bad install"), "internal error", exit 1; a little later, exit 0 without a word.
    Now it is held until the imports are done: 130 and one line, and the command does not run."""
    import os
    import time

    build = cli.build_parser

    def ctrl_c_while_building():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)                # where a handler runs: in the middle of the imports
        return build()

    monkeypatch.setattr(cli, "build_parser", ctrl_c_while_building)
    assert cli.main(["scenes"]) == 130
    out = capsys.readouterr()
    assert (out.out, out.err) == ("", "interrupted (Ctrl-C)\n")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.parametrize("command", ["render", "node"])
def test_a_mistake_said_to_a_reader_that_went_away_keeps_its_exit_status(bearing_sim_exe, ros_env, tmp_path, command):
    """``bearing-sim node ... 2>&1 | head -1`` whose recording then failed (or any mistake, said
    after the reader of standard error went away): printing the ``error:`` line raised a
    BrokenPipeError, and the status was 1, an internal error (``render``, ``run``), or 141, a
    closed output (``node``), not 2.  Now the line goes nowhere and the status is the mistake's."""
    out = str(tmp_path / "no_such_folder" / "x.mcap")
    args = {"render": ["render", "er16k_outer_race", "--duration", "1", "--out", out],
            "node": ["node", "--ros-args", "-p", f"record:={out}"]}[command]
    proc = subprocess.Popen([bearing_sim_exe, *args], env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()
    proc.stderr.close()                 # gone before the line
    assert proc.wait(120) == 2


@pytest.mark.parametrize("command", ["render", "node"])
def test_a_mistake_said_to_a_full_disk_keeps_its_exit_status(bearing_sim_exe, ros_env, tmp_path, command):
    """``bearing-sim node ... 2> node.log`` on a full disk (here /dev/full: every write ENOSPC):
    the ``error:`` line could not be written, and the OSError made the mistake's 2 an internal
    error, 1.  Now the line goes nowhere and the status is the mistake's."""
    out = str(tmp_path / "no_such_folder" / "x.mcap")
    args = {"render": ["render", "er16k_outer_race", "--duration", "1", "--out", out],
            "node": ["node", "--ros-args", "-p", f"record:={out}"]}[command]
    with open("/dev/full", "w") as full:
        assert subprocess.run([bearing_sim_exe, *args], env=ros_env, stdout=subprocess.DEVNULL, stderr=full,
                              timeout=120).returncode == 2


@pytest.mark.parametrize("command", ["node", "monitor"])
def test_a_mistake_said_as_the_terminal_closes_keeps_its_exit_status(bearing_sim_exe, ros_env, tmp_path, command):
    """A mistake said on a terminal that closes as the ``error:`` line is written, by a command
    that takes the hangup's SIGHUP as its end (those that run a node; the others end as any
    program, killed by it): the write failed (EIO) before the SIGHUP was handled, and the
    OSError ended the command as an internal error, exit 1.  Now the line goes nowhere and the
    status is the mistake's, 2.  The moment made exact: ``closed_as_it_writes``."""
    out = str(tmp_path / "no_such_folder" / "x.mcap")
    args = {"node": ["node", "--ros-args", "-p", f"record:={out}"],
            "monitor": ["monitor", "--window", "0"]}[command]
    assert closed_as_it_writes([bearing_sim_exe, *args], ros_env, "error: ", tmp_path, stream="stderr") == 2


@pytest.mark.parametrize("command, status, said", [(("monitor", "--window", "1"), 0, ""),
                                                   (("node",), 0, ""),
                                                   (("scenes",), 130, "interrupted (Ctrl-C)\n")])
def test_ctrl_c_while_the_command_module_loads_is_not_a_traceback(bearing_sim_exe, ros_env, tmp_path, command,
                                                                   status, said):
    """A Ctrl-C in a command's first 0.1 s came while the console script imported ``cli``: 30 ms
    of compiling where Python keeps no bytecode (PYTHONDONTWRITEBYTECODE, as on the CI machine),
    before any handler of the command's, and ended in a KeyboardInterrupt traceback from inside
    the import (``monitor``, in the CI run at 6d3ac47).  Now the console script is a module of a
    few lines that notes the signal first: a command that runs a node takes it as its Ctrl-C (0),
    the others end in one line (130).  The Ctrl-C is sent by the process itself as ``cli``
    imports argparse (a sitecustomize on PYTHONPATH wraps the import), the moment that failed."""
    env = signal_at_import(ros_env, tmp_path, "argparse", signal.SIGINT)
    run = subprocess.run([bearing_sim_exe, *command], env=env, capture_output=True, text=True, timeout=120)
    assert "Traceback" not in run.stderr and run.returncode == status, (run.returncode, run.stderr)
    assert run.stderr.endswith(said), run.stderr
    assert (tmp_path / "signal_sent").exists()


class _WriteFailsWithEIO:
    """A stream on the descriptor ``fd`` whose writes fail as a dying disk's or a hung-up terminal's."""

    def __init__(self, fd: int):
        self.fd = fd

    def fileno(self) -> int:
        return self.fd

    def write(self, text):
        raise OSError(errno.EIO, "Input/output error")

    def flush(self):
        pass


def test_a_line_lost_to_an_eio_of_a_file_is_an_error_and_one_of_a_terminal_is_not(tmp_path):
    """teardown.say drops a line whose write fails with EIO only where it goes to a terminal (one
    that hung up as it was written; the SIGHUP ends the command): on a file (``monitor >
    verdicts.txt`` on a failing disk or network mount) the line is lost, and the error is raised.
    Until 2026-11-30 every EIO was dropped and the monitor went on, exit 0, its lines gone."""
    import os

    from bearing_sim_ros.teardown import say

    with open(tmp_path / "verdicts.txt", "w") as file:
        with pytest.raises(OSError, match="Input/output error"):
            say("t=4.0 s verdict=outer", _WriteFailsWithEIO(file.fileno()))
    leader, terminal = os.openpty()
    try:
        say("t=4.0 s verdict=outer", _WriteFailsWithEIO(terminal))
    finally:
        os.close(leader)
        os.close(terminal)


def test_lines_said_by_two_threads_on_a_write_through_stream_stay_whole(tmp_path):
    """teardown.say writes a line and its newline as one: ``monitor``'s envelope worker says the
    verdicts and its executor the run's news, and print() wrote each line's newline apart, so under
    PYTHONUNBUFFERED (the tests' NodeProcess) a line came between them: ``... monitor ends)t=2.00s
    shaft=1797rpm verdict=unknown`` (CI on 61c1515 read one verdict of two there)."""
    import io
    import sys
    import threading

    from bearing_sim_ros.teardown import say

    lines = 3000
    with open(tmp_path / "out.txt", "wb", buffering=0) as raw:
        stream = io.TextIOWrapper(raw, encoding="utf-8", write_through=True)    # as under -u
        interval = sys.getswitchinterval()
        sys.setswitchinterval(1e-6)     # threads swap between any two writes
        try:
            threads = [threading.Thread(target=lambda name=name: [say(f"{name} {i}", stream) for i in range(lines)])
                       for name in ("verdict", "news")]
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join()
        finally:
            sys.setswitchinterval(interval)
        stream.detach()
    said = (tmp_path / "out.txt").read_text().splitlines()
    assert len(said) == 2 * lines
    broken = [line for line in said if not re.fullmatch(r"(verdict|news) \d+", line)]
    assert not broken, broken[:5]


RMW_CASES = [("bearing-sim", "render", "er16k_healthy", "--duration", "0.05", "--out", "x.mcap"),
             ("bearing-sim", "report", "x.mcap", "--out", "r"),
             ("bearing-sim", "run", "--duration", "0.2", "--out", "x.mcap"),
             ("bearing-sim", "node", "--ros-args", "-p", "duration:=0.2"),
             ("bearing_sim_node", "--ros-args", "-p", "duration:=0.2")]


@pytest.mark.parametrize("command", RMW_CASES, ids=[" ".join(c[:2]) for c in RMW_CASES])
def test_a_middleware_not_installed_is_one_line(ros_env, bearing_sim_exe, tmp_path, command):
    """``RMW_IMPLEMENTATION`` naming a middleware this environment does not have (a shell of an
    apt ROS 2 that exports rmw_cyclonedds_cpp) is one line and exit status 2 in every command that
    loads rcl, render and report too: rcl ended them with status 102 and a line that names no
    variable.  A command without rcl (scenes) runs on."""
    from pathlib import Path

    exe = str(Path(bearing_sim_exe).parent / command[0])
    env = dict(ros_env, RMW_IMPLEMENTATION="rmw_cyclonedds_cpp")
    r = subprocess.run([exe, *command[1:]], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stdout + r.stderr
    assert r.stderr.splitlines() == ["error: RMW_IMPLEMENTATION = 'rmw_cyclonedds_cpp': not installed here (this "
                                     "environment has rmw_fastrtps_cpp); unset it or give one of those"], r.stderr
    assert not (tmp_path / "x.mcap").exists()
    scenes = subprocess.run([bearing_sim_exe, "scenes"], env=env, capture_output=True, text=True, timeout=60)
    assert scenes.returncode == 0 and "er16k_outer_race" in scenes.stdout, scenes.stderr
