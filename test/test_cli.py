"""``bearing-sim`` as a newcomer meets it: every option's help gives its unit and default, and
error lines show numbers as a user types them."""
from __future__ import annotations

import math

import pytest

from bearing_sim_ros import Simulator, UserError, cli


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
    ("play", "--rate", ["real time", "1"]),
    ("run", "--duration", ["seconds", "10"]),
    ("monitor", "--window", ["seconds", "4"]),
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
    assert "--ros-args -p duration:=10" in out


def test_non_finite_inputs_are_named_with_plain_numbers():
    sim = Simulator("er16k_outer_race", fidelity="kinematic")
    with pytest.raises(UserError) as speed:
        sim.advance(150, shaft_speed=math.nan)
    with pytest.raises(UserError) as load:
        sim.advance(150, radial_load=(math.nan, 0.0))
    assert str(speed.value) == "shaft_speed = nan rad/s: must be a finite number"
    assert str(load.value) == "radial_load = (nan, 0.0) N: must be finite numbers"
    assert "np." not in str(speed.value) + str(load.value)
