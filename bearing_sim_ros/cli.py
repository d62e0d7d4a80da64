"""``bearing-sim``: the command line (INTERFACE.md).

Exit status: 0 done; 2 a user mistake (one line naming what is wrong and what is allowed, never a
traceback); 1 an internal error; 3 ``monitor --count N`` whose simulator's run ended before N
verdicts; 4 ``monitor`` with ``--count`` or ``--end-wait`` whose source went away without an end
status (killed, crashed, lost to discovery); 141 (quietly) when the reader of standard output went away;
130 (143, 129) a command stopped by Ctrl-C (SIGTERM, SIGHUP) before it was done, 0 where it runs a node
and stopped as asked (README "Shutdown and recording").  Each subcommand's work lives in its own module; this file only
parses arguments and maps errors to exit codes.
"""
from __future__ import annotations

import argparse
import math
import re
import signal
import sys
from contextlib import contextmanager

# SIGNAL_COMMANDS, the commands that run a node: their Ctrl-C and SIGTERM are handled from the
# first line (teardown.CommandSignals), before the imports of numpy, numba and rclpy, where one was
# lost; the console scripts (entry) note them before this module loads
from . import compile_notice
from .entry import SIGNAL_COMMANDS
from .errors import UserError
from .teardown import EXIT_INTERRUPTED, point_at_devnull, say_on_stderr, signal_handlers

EXIT_OK, EXIT_INTERNAL, EXIT_USER = 0, 1, 2
EXIT_STDOUT_CLOSED = 141        # 128 + SIGPIPE: what the shell reports for `yes | head`
# monitor --count N: the run it watched ended (its end status) and no table came for --end-wait
# seconds before N verdicts; a script must tell that from N verdicts (0) without parsing lines
EXIT_COUNT_NOT_REACHED = 3
# monitor with --count or --end-wait: the publisher of the tables went away without the simulator's
# end status (a node killed or crashed, its machine off) and none came back for --end-wait seconds
EXIT_SOURCE_LOST = 4
# monitor --end-wait (s): long enough for the tables still queued behind the end status and the
# next pass of play --loop; a node restarted in its place takes a second or two to publish
MONITOR_END_WAIT_S, MONITOR_END_WAIT_RANGE_S = 5.0, (0.0, 3600.0)
# play and report: what several files, or a split recording's name, mean
SPLIT_FILES_HELP = ("a split recording (the node's record_max_duration / record_max_size) is read as one: "
                    "give its pieces F_000.mcap F_001.mcap ... (in any order, e.g. F_*.mcap) or the name "
                    "it was recorded to, F.mcap")


# what a value that starts with "-" is taken as, not an option: argparse's own (Python 3.11-3.12)
# takes -5 and -0.5 but not -4.2e8, -1E3 or -inf, which it read as an unknown option ("argument
# --start: expected 7 arguments", "--duration: expected one argument") where the number was meant
NEGATIVE_NUMBER = re.compile(r"^-(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf|infinity|nan)$", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    """argparse that reports a mistake as one line and exit status 2 (its default, too), and
    takes every negative number (``NEGATIVE_NUMBER``) as a value, for its type to accept or name."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message):
        raise UserError(f"{self.prog}: {message}")


def _number(kind, allow_zero: bool, hi: float = math.inf):
    """argparse type: a finite ``kind`` (int or float) > 0, or >= 0 with ``allow_zero``; at most ``hi``."""
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{text!r} is not a {'whole number' if kind is int else 'number'}") from None
        if not (math.isfinite(value) and (value >= 0 if allow_zero else value > 0) and value <= hi):
            upper = f" and <= {hi:g}" if isinstance(hi, float) and hi < math.inf else (
                f" and <= {hi}" if hi < math.inf else "")
            raise argparse.ArgumentTypeError(
                f"{text!r} must be a finite number {'>=' if allow_zero else '>'} 0{upper}")
        return value
    return parse


def _positive(kind):
    return _number(kind, allow_zero=False)


def _nonnegative(kind, hi: float = math.inf):
    return _number(kind, allow_zero=True, hi=hi)


def _in_range(lo: float, hi: float, unit: str):
    """argparse type: a number within [lo, hi] (in ``unit``; "" for a pure number, a ratio)."""
    unit = f" {unit}" if unit else ""

    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"{text}{unit}: allowed range is [{lo:g}, {hi:g}]{unit}")
        return value
    return parse


def _sample_rate(lo: float, hi: float):
    """argparse type of ``render --sample-rate``: within [lo, hi] Hz, and a whole number of samples
    in a render's tables of ``messages.BATCH_DURATION`` (the node's ``batching_error`` rule)."""
    from .messages import BATCH_DURATION, STATE_RATE, batching_error

    in_range = _in_range(lo, hi, "Hz")

    def parse(text):
        value = in_range(text)
        if batching_error(value, BATCH_DURATION, STATE_RATE):
            raise argparse.ArgumentTypeError(
                f"{text} Hz: a render's tables are {BATCH_DURATION * 1e3:g} ms, a whole number of samples each, "
                f"so allowed rates are multiples of {1.0 / BATCH_DURATION:g} Hz in [{lo:g}, {hi:g}] Hz")
        return value
    return parse


def _oversample(text):
    """argparse type: integration steps per output sample, the API's allowed values."""
    from .simulator import OVERSAMPLE_ALLOWED, oversample_allowed

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not oversample_allowed(value):
        raise argparse.ArgumentTypeError(f"{text}: allowed values are {OVERSAMPLE_ALLOWED}")
    return value


def _node_name(text):
    """argparse type of ``monitor --simulator``: a ROS node name, bare (``sim``), with its
    namespace (``rig1/sim``) or from the root (``/bearing_sim``).  Anything else names no node,
    and the monitor waited for a ground truth that could never come."""
    import re

    token = r"[A-Za-z_][A-Za-z0-9_]*"
    if not re.fullmatch(rf"/?{token}(/{token})*", text):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a ROS node name: letters, digits and _, not starting with a digit, namespaces "
            "before it with /, e.g. bearing_sim, rig1/bearing_sim, /bearing_sim")
    return text


def build_parser() -> argparse.ArgumentParser:
    from .physics.integrators import RK4_DEFAULT_STEP, RK4_STEP_RANGE
    from .simulator import AUTO_OVERSAMPLE_MAX, DURATION_MAX_S, OVERSAMPLE_ALLOWED, SAMPLE_RATE_RANGE, SEED_RANGE
    from .messages import BATCH_DURATION
    from .analysis.report import DEFAULT_WINDOW_S, WINDOW_RANGE_S
    from .recording.play import PLAY_RATE_RANGE, PLAY_WAIT_MAX
    from .recording.recorder import SPLIT_MAX_BYTES, SPLIT_MIN_BYTES

    p = _Parser(prog="bearing-sim", description="Virtual bearing accelerometer for ROS 2.")
    sub = p.add_subparsers(dest="command", parser_class=_Parser, metavar="COMMAND")
    sub.required = True
    scene_help = "shipped scene name (see `bearing-sim scenes`) or path of a scene YAML"

    s = sub.add_parser("node", help="run the ROS 2 node (same as ros2 run bearing_sim_ros bearing_sim_node)",
                       usage="%(prog)s [-h] [--scene S] [--ros-args ...]",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       epilog="ROS arguments follow --ros-args, for example\n"
                              "  bearing-sim node --scene er16k_healthy --ros-args -p duration:=10.0 "
                              "-p record:=run.mcap\n"
                              "The node's parameters (sample_rate, duration, record, fidelity, seed, ...):\n"
                              "README.md, \"The live node\", or `ros2 param describe /bearing_sim <name>`.")
    s.add_argument("--scene", default=None, metavar="S",
                   help=f"{scene_help} (default: the scene parameter's, er16k_outer_race)")

    s = sub.add_parser("run", help="what `make run` does: the node on a scene for a while, recorded, then a summary")
    s.add_argument("--scene", default="er16k_outer_race", metavar="S", help=f"{scene_help} (default: %(default)s)")
    s.add_argument("--duration", type=_nonnegative(float, hi=DURATION_MAX_S), default=10.0, metavar="SECONDS",
                   help="seconds of signal in real time; 0 = until Ctrl-C (default: %(default)g)")
    s.add_argument("--out", required=True, metavar="F.mcap", help="MCAP file to record to (required)")
    s.add_argument("--max-file-duration", type=_nonnegative(float, hi=DURATION_MAX_S), default=0.0, metavar="SECONDS",
                   help="split the recording into complete files of this many seconds, F_000.mcap, "
                        "F_001.mcap, ... (the node's record_max_duration); 0 = one file (default: %(default)g)")
    s.add_argument("--max-file-size", type=_nonnegative(int, hi=SPLIT_MAX_BYTES), default=0, metavar="BYTES",
                   help=f"split the recording into complete files of about this many bytes on disk, "
                        f"F_000.mcap, ... (the node's record_max_size), at least {SPLIT_MIN_BYTES}; 0 = one "
                        f"file (default: %(default)s)")

    s = sub.add_parser("render", help="offline, as fast as possible, to MCAP")
    s.add_argument("scene", metavar="S", help=scene_help)
    s.add_argument("--duration", type=_number(float, allow_zero=False, hi=DURATION_MAX_S), required=True,
                   metavar="SECONDS", help=f"seconds of signal, at least one sample, at most {DURATION_MAX_S:g} "
                                       "(required)")
    s.add_argument("--out", required=True, metavar="F.mcap", help="MCAP file to write (required)")
    s.add_argument("--fidelity", default="auto", choices=["auto", "kinematic", "skidding"],
                   help="model tier; auto: the cheapest within the scene's error tolerance "
                        "(default: %(default)s)")
    s.add_argument("--seed", type=_nonnegative(int, hi=SEED_RANGE[1]), default=0, metavar="N",
                   help=f"seed of the random slip and the sensor noise, a whole number {SEED_RANGE[0]} to "
                        f"{SEED_RANGE[1]} (default: %(default)s)")
    s.add_argument("--sample-rate", type=_sample_rate(*SAMPLE_RATE_RANGE), default=15000.0, metavar="HZ",
                   help=f"output sample rate, Hz, {SAMPLE_RATE_RANGE[0]:g} to {SAMPLE_RATE_RANGE[1]:g}, "
                        f"a multiple of {1.0 / BATCH_DURATION:g} (10 ms tables of whole samples) "
                        f"(default: %(default)g)")
    s.add_argument("--solver", default="default", choices=["default", "rk4", "reference"],
                   help="integrator of the skidding tier (the kinematic tier has none): default, rk4 "
                        "(classic RK4 at a fixed step, see --rk4-step) or reference (converged, slow) "
                        "(default: %(default)s)")
    s.add_argument("--rk4-step", type=_in_range(*RK4_STEP_RANGE, "s"), default=None, metavar="SECONDS",
                   help=f"step of --solver rk4, s, {RK4_STEP_RANGE[0]:g} to {RK4_STEP_RANGE[1]:g} "
                        f"(default: {RK4_DEFAULT_STEP:g}, seed 000's, which diverges on this model; "
                        f"6e-06 survives every bench scene)")
    s.add_argument("--oversample", type=_oversample, default=None, metavar="M",
                   help=f"integration steps per output sample (below a 15 kHz output, per physics "
                        f"sample: the physics runs at the smallest whole multiple of the sample rate "
                        f"that reaches 15 kHz): {OVERSAMPLE_ALLOWED} (at most "
                        f"{AUTO_OVERSAMPLE_MAX} where --fidelity auto chooses the tier) (default: each "
                        "tier's own: kinematic 1 while its bearing mode is below a tenth of that "
                        "rate, else 2; skidding 2)")

    s = sub.add_parser("play", help="republish a recording on its topics")
    s.add_argument("file", metavar="F.mcap", nargs="+",
                   help=f"the recording to republish; {SPLIT_FILES_HELP}")
    s.add_argument("--rate", type=_in_range(*PLAY_RATE_RANGE, ""), default=1.0, metavar="X",
                   help=f"playback speed, a multiple of real time, {PLAY_RATE_RANGE[0]:g} to {PLAY_RATE_RANGE[1]:g}; "
                        "where that asks for more than the machine can send, as fast as it can (default: %(default)g)")
    s.add_argument("--loop", action="store_true",
                   help="start again from the beginning at the end, until Ctrl-C (default: play once)")
    s.add_argument("--clock", action="store_true",
                   help="publish /clock from the recording's stamps (default: off)")
    s.add_argument("--wait", type=_in_range(0.0, PLAY_WAIT_MAX, "s"), default=5.0, metavar="SECONDS",
                   help=f"wait up to this long for a first subscriber before publishing, 0 to {PLAY_WAIT_MAX:g} s "
                        "(default %(default)g; DDS discovery can take one 3 s announcement period)")

    s = sub.add_parser("report", help="PNG plots and a summary of a recording")
    s.add_argument("file", metavar="F.mcap", nargs="+", help=f"the recording to analyse; {SPLIT_FILES_HELP}")
    s.add_argument("--out", required=True, metavar="DIR",
                   help="folder for the PNG plots, summary.md and summary.json, created if missing (required)")
    s.add_argument("--window", type=_in_range(*WINDOW_RANGE_S, "s"), default=DEFAULT_WINDOW_S, metavar="SECONDS",
                   help=f"seconds of signal per verdict of the timeline (timeline.png), {WINDOW_RANGE_S[0]:g} to "
                        f"{WINDOW_RANGE_S[1]:g}; the whole recording when shorter than two (default: %(default)g)")

    s = sub.add_parser("bench", help="speed-against-error study")
    s.add_argument("--quick", action="store_true",
                   help="fewer scenes, settings and repeats, shorter runs: about 25 s instead of about "
                        "6 minutes (default: the full study)")
    s.add_argument("--calibrate-fidelity", action="store_true",
                   help="measure the kinematic tier's error against the skidding reference and refit "
                        "config/fidelity.yaml (default: off)")
    s.add_argument("--out", required=True, metavar="DIR",
                   help="folder for bench.md, bench.json and bench.png, created if missing (required)")

    s = sub.add_parser("validate", help="simulated against real CWRU recordings")
    s.add_argument("--cwru", required=True, metavar="DIR",
                   help="folder (or one file) of CWRU bearing data center .mat recordings (required)")
    s.add_argument("--out", required=True, metavar="DIR",
                   help="folder for validation.md, validation.json and the PNG plots (required)")

    sub.add_parser("scenes", help="list the shipped scenes")

    s = sub.add_parser("monitor", help="example condition-monitoring subscriber (envelope analysis)",
                       usage="%(prog)s [-h] [--window SECONDS] [--count N] [--end-wait SECONDS] [--scene S] "
                             "[--simulator NAME] [--ros-args ...]",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       epilog="ROS arguments follow --ros-args, for example the namespace of the rig to watch:\n"
                              "  bearing-sim monitor --window 4 --ros-args -r __ns:=/rig1")
    # the report's range: below 0.5 s the lines' +-20 Hz neighbourhood holds too few bins, and a
    # 1e-4 s window gave "x inf" prominences and a fault verdict on anything
    s.add_argument("--window", type=_in_range(*WINDOW_RANGE_S, "s"), default=4.0, metavar="SECONDS",
                   help=f"seconds of signal per analysis, {WINDOW_RANGE_S[0]:g} to {WINDOW_RANGE_S[1]:g} "
                        "(default: %(default)g)")
    s.add_argument("--count", type=_nonnegative(int), default=0, metavar="N",
                   help="stop after this many verdicts (default: %(default)s = never); where the simulator's "
                        f"run ends before, exit status {EXIT_COUNT_NOT_REACHED} after --end-wait; where its "
                        f"source goes away without an end status, {EXIT_SOURCE_LOST}")
    s.add_argument("--end-wait", type=_in_range(*MONITOR_END_WAIT_RANGE_S, "s"), default=None, metavar="SECONDS",
                   help="once the simulator's run ended (its end status), end when no table has come for this "
                        "long; once no publisher of the tables is left without one (a node killed: DDS notices "
                        f"in about 20 s), when none came back for this long; {MONITOR_END_WAIT_RANGE_S[0]:g} to {MONITOR_END_WAIT_RANGE_S[1]:g} (default: "
                        f"{MONITOR_END_WAIT_S:g} with --count, else wait on until Ctrl-C)")
    s.add_argument("--scene", default=None, metavar="S",
                   help="scene giving the bearing geometry (default: er16k_outer_race); the monitor says once "
                        "when the simulator's /diagnostics name another")
    s.add_argument("--simulator", type=_node_name, default=None, metavar="NAME",
                   help="the simulator node whose /diagnostics give the ground truth: a node name, "
                        "in the namespace of the accel topic (sim), or a full name (rig1/sim, "
                        "/bearing_sim from the root) (default: bearing_sim)")
    return p


def _scenes(_args) -> int:
    from .scene import load_scene, shipped_scenes

    names = shipped_scenes()
    width = max(map(len, names), default=0)
    for name in names:
        print(f"{name:<{width}}  {load_scene(name).description}")
    return EXIT_OK


def _params_file_scenes(ros_args: list) -> list:
    """(file, scene) for each ``--params-file`` among ``ros_args`` that gives the node a ``scene``:
    under a node entry named like the node (``bearing_sim``, ``/rig1/bearing_sim``, nested
    namespaces too) or a wildcard (``/**``).  A file that cannot be read or parsed is left to rcl,
    which names it."""
    from .nodes.bearing_sim_node import NODE_NAME
    from .scene import load_yaml

    def scenes(entry, names):
        if not isinstance(entry, dict):
            return
        params = entry.get("ros__parameters")
        node = "/".join(names).rsplit("/", 1)[-1]
        if isinstance(params, dict) and "scene" in params and (node == NODE_NAME or "*" in "/".join(names)):
            yield params["scene"]
        for key, value in entry.items():
            if key != "ros__parameters":
                yield from scenes(value, [*names, str(key)])

    found = []
    for flag, path in zip(ros_args, ros_args[1:]):
        if flag != "--params-file":
            continue
        try:
            with open(path, encoding="utf-8") as f:
                data = load_yaml(f.read())
        except Exception:  # noqa: BLE001 - rcl says what is wrong with it
            continue
        found += [(path, scene) for scene in scenes(data, [])]
    return found


def _params_files_in_memory(ros_args: list) -> tuple:
    """(``ros_args`` with each ``--params-file`` that is not a regular file replaced by a copy in
    memory, {copy's path: path given}).  A pipe gives its text once: read here for its scene,
    it left rcl an empty file, whose parameters were lost without a word (``<(...)``), or a FIFO
    that rcl waited on for good.  The copy is a memfd, named ``/proc/self/fd/N``: rcl opens it
    by that path in this process, and it goes with the process, whichever way that ends (the
    node's teardown ends it with ``os._exit``, which no cleanup would outlive).  A path that
    cannot be read is left to rcl, which names it."""
    import os
    import stat

    args, given_as = list(ros_args), {}
    for i, (flag, path) in enumerate(zip(ros_args, ros_args[1:])):
        if flag != "--params-file":
            continue
        try:
            if stat.S_ISREG(os.stat(path).st_mode):
                continue
            with open(path, "rb") as f:
                text = f.read()
        except OSError:
            continue
        fd = os.memfd_create("params_file")         # closed on exec: rcl reads it in this process
        os.write(fd, text)
        args[i + 1] = f"/proc/self/fd/{fd}"
        given_as[args[i + 1]] = path
    return args, given_as


# the commands that load rcl (the ROS client library), which rclpy's serialisation needs too:
# render and report write and read the messages with it
RCL_COMMANDS = ("node", "run", "monitor", "play", "render", "report")


def rmw_error(environ=None) -> str:
    """'' unless ``RMW_IMPLEMENTATION`` names a middleware that the environment's ament index
    (each AMENT_PREFIX_PATH entry's, and the Python environment's, where ROS 2's wheels put it)
    does not list, else the one line that says so.  rcl ends the process as it loads such a
    setting, render's and report's too, with exit status 102 and "Expected RMW implementation
    identifier of 'rmw_cyclonedds_cpp' but instead found 'rmw_fastrtps_cpp'", which names no
    variable: a shell of an apt ROS 2 that exports another middleware is a usual way to meet it.
    Where no index lists any middleware, nothing is said (rcl's line then stands)."""
    import os
    from pathlib import Path

    environ = os.environ if environ is None else environ
    wanted = environ.get("RMW_IMPLEMENTATION", "").strip()
    if not wanted:
        return ""
    prefixes = [p for p in environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p] + [sys.prefix]
    installed = set()
    for prefix in prefixes:
        index = Path(prefix) / "share" / "ament_index" / "resource_index" / "rmw_typesupport"
        if index.is_dir():
            # rmw_implementation, the loader, is listed there too, and is none of them
            installed.update(entry.name for entry in index.iterdir() if entry.name != "rmw_implementation")
    if not installed or wanted in installed:
        return ""
    return (f"RMW_IMPLEMENTATION = {environ['RMW_IMPLEMENTATION']!r}: not installed here (this environment "
            f"has {', '.join(sorted(installed))}); unset it or give one of those")


def say_model_warnings(program: str) -> None:
    """The simulator's warnings to the user (``DefaultStepWarning``) as one line on standard error,
    ``<program>: warning: ...``, instead of Python's two (the library's file and line, and its
    source line); any other warning as Python shows it."""
    import warnings

    from .simulator import DefaultStepWarning

    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, DefaultStepWarning):
            say_on_stderr(f"{program}: warning: {message}")
        else:
            shown(message, category, filename, lineno, file, line)

    warnings.showwarning = show


def _dispatch(args, rest) -> int:
    cmd = args.command
    # numba is loaded already (the parser's physics import): a cold cache's compiling is said
    compile_notice.enable()
    say_model_warnings("bearing-sim")
    missing_rmw = rmw_error() if cmd in RCL_COMMANDS else ""
    if missing_rmw:
        raise UserError(missing_rmw)
    if cmd == "scenes":
        return _scenes(args)
    if cmd == "node":
        from .nodes.bearing_sim_node import main as node_main, stray_arguments_error

        # checked here too: the scene's parameter goes first, after a --ros-args of its own
        stray = rest[:rest.index("--ros-args")] if "--ros-args" in rest else rest
        if stray:
            raise stray_arguments_error("bearing-sim node", stray)
        argv, given_as = [], {}
        if args.scene is not None and not args.scene.strip():
            # --scene "$SCENE" with SCENE unset ran the default scene without a word: the scene
            # loader's own line for an empty path
            from .scene import resolve_scene_path

            resolve_scene_path(args.scene)
        if args.scene:
            # rcl takes the last of two: --scene A -p scene:=B ran B without a word
            given = [b for a, b in zip(rest, rest[1:]) if a in ("-p", "--param")
                     and b.split(":=", 1)[0].rsplit(":", 1)[-1] == "scene" and ":=" in b]
            if given:
                raise UserError(f"bearing-sim node: --scene {args.scene} and -p {given[0]} name two scenes; give one")
            # ... and so does a parameters file's (it came after our -p and ran its scene).  A pipe
            # (`<(...)`, a FIFO) is read once, here, into a copy that rcl reads after us
            rest, given_as = _params_files_in_memory(rest)
            in_files = _params_file_scenes(rest)
            if in_files:
                path, scene = in_files[0]
                path = given_as.get(path, path)
                raise UserError(f"bearing-sim node: --scene {args.scene} and --params-file {path} (scene: {scene}) "
                                "name two scenes; give one")
            argv += ["--ros-args", "-p", f"scene:={args.scene}"]
        return node_main(argv + rest, given_as) or EXIT_OK
    if cmd == "monitor":
        from .nodes.monitor_node import main as monitor_main

        return monitor_main(args, rest) or EXIT_OK
    if rest:
        raise UserError(f"bearing-sim {cmd}: unrecognized arguments: {' '.join(rest)}")
    if cmd == "run":
        from .run import run_command

        return run_command(args)
    if cmd == "render":
        from .recording.render import render_command

        return render_command(args)
    if cmd == "play":
        from .recording.play import play_command

        return play_command(args)
    if cmd == "report":
        from .analysis.report import report_command

        return report_command(args)
    if cmd == "bench":
        from .bench import bench_command

        return bench_command(args)
    if cmd == "validate":
        from .analysis.validate import validate_command

        return validate_command(args)
    raise UserError(f"bearing-sim: unknown command {cmd!r}")


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] and argv[0] in SIGNAL_COMMANDS:
        return _signal_command(lambda: _main(argv))
    return _main(argv)


def node_main() -> int:
    """``bearing_sim_node`` (``ros2 run bearing_sim_ros bearing_sim_node``): the node, as
    ``bearing-sim node`` runs it."""
    def run():
        missing_rmw = rmw_error()    # before the node's module loads rcl, which ends the process there
        if missing_rmw:
            say_on_stderr(f"error: {missing_rmw}")
            return EXIT_USER
        from .nodes.bearing_sim_node import main as run_node

        compile_notice.enable("bearing_sim_node")     # its lines named as the user started it
        say_model_warnings("bearing_sim_node")
        return run_node()

    return _signal_command(run)


def _signal_command(run) -> int:
    """``run()``, a command that runs a node, with Ctrl-C and SIGTERM handled from here on,
    before the imports of the parser and the node (teardown.CommandSignals; README "Shutdown and
    recording").  The node's main ends the process; where a command returns (``run``, ``monitor``,
    a signal before the node's main took it as an exit 0), this ends it: with a signal held
    during the shutdown, 130 (143), as the shell reports an interrupted command."""
    from .teardown import node_signals

    with node_signals() as signals:
        code = run()
        if signals.first is not None or signals.held:
            signals.exit(code)
    return code


def _stdout_closed() -> bool:
    """Whether standard output is a pipe whose reader has gone (``bearing-sim scenes | head -2``:
    a BrokenPipeError traceback and "internal error", exit 1).  Then it points at /dev/null, so
    that Python's own flush at exit says nothing either."""
    import select

    try:
        fd = sys.stdout.fileno()
        poll = select.poll()
        poll.register(fd, select.POLLOUT)
        # the write end of a pipe without a reader polls as an error
        if not any(events & select.POLLERR for _fd, events in poll.poll(0)):
            return False
    except (OSError, ValueError):       # no descriptor (a test's capture): not this case
        return False
    point_at_devnull(fd)
    return True


@contextmanager
def _ctrl_c_held():
    """Ctrl-C during the block (the parser's imports: numpy) noted and raised after it, as a
    KeyboardInterrupt: raised inside numpy's import, it came out as an ImportError that said
    numpy's install was broken ("Importing the numpy C-extensions failed"), and "internal error",
    exit 1.  Only where Ctrl-C would raise (the commands that run a node hold it from their
    first line, teardown.CommandSignals)."""
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    noted = []
    with signal_handlers({signal.SIGINT: lambda signum, _frame: noted.append(signum)}):
        yield
    if noted:
        raise KeyboardInterrupt


def _main(argv: list) -> int:
    try:
        with _ctrl_c_held():
            parser = build_parser()
        # `node` passes everything after it to ROS (--ros-args ...)
        if argv[:1] == ["node"]:
            args, rest = parser.parse_known_args(argv)
        elif argv[:1] == ["monitor"] and "--ros-args" in argv:
            # the monitor's own options, then ROS's (a namespace, remaps) as the node takes them
            cut = argv.index("--ros-args")
            args, rest = parser.parse_args(argv[:cut]), argv[cut:]
        else:
            # known args first, so that a stray one is named with its command, as `node` does
            args, rest = parser.parse_known_args(argv)
            if rest:
                # the monitor takes ROS arguments too, as the node does, and says where they go
                hint = " (ROS arguments follow --ros-args)" if args.command == "monitor" else ""
                raise UserError(f"bearing-sim {args.command}: unrecognized arguments: {' '.join(rest)}{hint}")
        return int(_dispatch(args, rest) or EXIT_OK)
    except UserError as exc:
        say_on_stderr(f"error: {exc}")
        return EXIT_USER
    except KeyboardInterrupt:
        if argv[:1] and argv[0] in SIGNAL_COMMANDS:
            return EXIT_OK          # stopped while it started: README "Shutdown and recording"
        # render, report, bench, ...: stopped before they were done (it said 0, as if they were),
        # 130 as the shell reports an interrupted command (render says what it kept itself)
        say_on_stderr("interrupted (Ctrl-C)")
        return EXIT_INTERRUPTED[signal.SIGINT]
    except SystemExit as exc:           # argparse --help
        return int(exc.code or 0)
    except BrokenPipeError:
        if not _stdout_closed():
            raise                       # another pipe (a recording's): an error of its own
        return EXIT_STDOUT_CLOSED
    except Exception as exc:  # noqa: BLE001 - the last line of defence: say it, exit 1
        import traceback

        traceback.print_exc()
        print(f"internal error: {exc.__class__.__name__}: {exc}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
