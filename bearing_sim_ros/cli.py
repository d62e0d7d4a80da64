"""``bearing-sim``: the command line (INTERFACE.md).

Exit status: 0 done; 2 a user mistake (one line naming what is wrong and what is allowed, never a
traceback); 1 an internal error.  Each subcommand's work lives in its own module; this file only
parses arguments and maps errors to exit codes.
"""
from __future__ import annotations

import argparse
import sys

from .errors import UserError

EXIT_OK, EXIT_INTERNAL, EXIT_USER = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    """argparse that reports a mistake as one line and exit status 2 (its default, too)."""

    def error(self, message):
        raise UserError(f"{self.prog}: {message}")


def _number(kind, allow_zero: bool):
    """argparse type: a ``kind`` (int or float) > 0, or >= 0 with ``allow_zero``."""
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{text!r} is not a {'whole number' if kind is int else 'number'}") from None
        if not (value >= 0 if allow_zero else value > 0):
            raise argparse.ArgumentTypeError(f"{text!r} must be {'>=' if allow_zero else '>'} 0")
        return value
    return parse


def _positive(kind):
    return _number(kind, allow_zero=False)


def _nonnegative(kind):
    return _number(kind, allow_zero=True)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="bearing-sim", description="Virtual bearing accelerometer for ROS 2.")
    sub = p.add_subparsers(dest="command", parser_class=_Parser, metavar="COMMAND")
    sub.required = True

    s = sub.add_parser("node", help="run the ROS 2 node (same as ros2 run bearing_sim_ros bearing_sim_node)")
    s.add_argument("--scene", default=None, help="shipped scene name or YAML path")

    s = sub.add_parser("run", help="what `make run` does: the node on a scene for a while, recorded, then a summary")
    s.add_argument("--scene", default="er16k_outer_race")
    s.add_argument("--duration", type=float, default=10.0, help="seconds; 0 = until Ctrl-C")
    s.add_argument("--out", required=True, help="MCAP file to record")

    s = sub.add_parser("render", help="offline, as fast as possible, to MCAP")
    s.add_argument("scene")
    s.add_argument("--duration", type=_positive(float), required=True, help="seconds of signal")
    s.add_argument("--out", required=True, help="output .mcap")
    s.add_argument("--fidelity", default="auto", choices=["auto", "kinematic", "skidding"])
    s.add_argument("--seed", type=_nonnegative(int), default=0)
    s.add_argument("--sample-rate", type=_positive(float), default=15000.0)
    s.add_argument("--solver", default="default", choices=["default", "rk4", "reference"])
    s.add_argument("--oversample", type=int, default=None,
                   help="integration steps per output sample: 1, 2 or a multiple of 4 (default: each tier's own)")

    s = sub.add_parser("play", help="republish a recording on its topics")
    s.add_argument("file")
    s.add_argument("--rate", type=_positive(float), default=1.0)
    s.add_argument("--loop", action="store_true")
    s.add_argument("--clock", action="store_true", help="publish /clock from the recording's stamps")
    s.add_argument("--wait", type=_nonnegative(float), default=5.0, metavar="SECONDS",
                   help="wait up to this long for a first subscriber before publishing (default 5; "
                        "DDS discovery can take one 3 s announcement period)")

    s = sub.add_parser("report", help="PNG plots and a summary of a recording")
    s.add_argument("file")
    s.add_argument("--out", required=True)

    s = sub.add_parser("bench", help="speed-against-error study")
    s.add_argument("--quick", action="store_true")
    s.add_argument("--calibrate-fidelity", action="store_true",
                   help="measure the kinematic tier's error against the skidding reference and refit config/fidelity.yaml")
    s.add_argument("--out", required=True)

    s = sub.add_parser("validate", help="simulated against real CWRU recordings")
    s.add_argument("--cwru", required=True)
    s.add_argument("--out", required=True)

    sub.add_parser("scenes", help="list the shipped scenes")

    s = sub.add_parser("monitor", help="example condition-monitoring subscriber (envelope analysis)")
    s.add_argument("--window", type=_positive(float), default=4.0, help="seconds of signal per analysis")
    s.add_argument("--count", type=_nonnegative(int), default=0, help="stop after this many verdicts (0 = never)")
    s.add_argument("--scene", default=None, help="scene giving the bearing geometry (default: er16k_outer_race)")
    return p


def _scenes(_args) -> int:
    from .scene import load_scene, shipped_scenes

    for name in shipped_scenes():
        scene = load_scene(name)
        print(f"{name:<20} {scene.description}")
    return EXIT_OK


def _dispatch(args, rest) -> int:
    cmd = args.command
    if cmd == "scenes":
        return _scenes(args)
    if cmd == "node":
        from .nodes.bearing_sim_node import main as node_main

        argv = []
        if args.scene:
            argv += ["--ros-args", "-p", f"scene:={args.scene}"]
        return node_main(argv + rest) or EXIT_OK
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
    if cmd == "monitor":
        from .nodes.monitor_node import main as monitor_main

        return monitor_main(args) or EXIT_OK
    raise UserError(f"bearing-sim: unknown command {cmd!r}")


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        parser = build_parser()
        # `node` passes everything after it to ROS (--ros-args ...)
        if argv[:1] == ["node"]:
            args, rest = parser.parse_known_args(argv)
        else:
            args, rest = parser.parse_args(argv), []
        return int(_dispatch(args, rest) or EXIT_OK)
    except UserError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USER
    except KeyboardInterrupt:
        return EXIT_OK
    except SystemExit as exc:           # argparse --help
        return int(exc.code or 0)
    except Exception as exc:  # noqa: BLE001 - the last line of defence: say it, exit 1
        import traceback

        traceback.print_exc()
        print(f"internal error: {exc.__class__.__name__}: {exc}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
