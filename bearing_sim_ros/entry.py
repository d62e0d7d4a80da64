"""The console scripts (setup.py): ``bearing-sim`` and ``bearing_sim_node``.

A module this small is compiled at once even where Python keeps no bytecode (PYTHONDONTWRITEBYTECODE,
as the CI machine sets it; a read-only install): the first thing it does is note Ctrl-C, SIGTERM and
SIGHUP, before ``cli`` (500 lines) is compiled and its imports loaded, tens of milliseconds.  A
Ctrl-C 0.1 s after ``bearing-sim monitor`` started came inside that import, before the command's
handlers (``teardown.CommandSignals``), and ended in a KeyboardInterrupt traceback.  The commands
that run a node take those noted as if they came after their handlers
(``teardown.command_signals``); the others end as on a Ctrl-C during their parser's imports: 130
and one line.
"""
import signal
import sys

SIGNAL_COMMANDS = ("node", "run", "monitor", "play")        # cli.SIGNAL_COMMANDS, without importing cli
EXIT_CTRL_C = 130
# the signals that came before the command's own handlers took over, in order
EARLY_SIGNALS = []


def _note(signum, _frame):
    EARLY_SIGNALS.append(signum)


def _note_signals(signals) -> None:
    """Note ``signals`` from now on (``EARLY_SIGNALS``); a hangup ignored from the start (``nohup``)
    stays ignored, as the command's handlers leave it."""
    for sig in signals:
        if sig != signal.SIGHUP or signal.getsignal(sig) != signal.SIG_IGN:
            signal.signal(sig, _note)


def main() -> int:
    """``bearing-sim``."""
    runs_a_node = sys.argv[1:2] and sys.argv[1] in SIGNAL_COMMANDS
    if runs_a_node:
        _note_signals((signal.SIGINT, signal.SIGTERM, signal.SIGHUP))
        from .cli import main as command

        return command()
    # the others: Ctrl-C while cli is loaded noted, then Python's own handler again (cli holds it
    # over its parser's imports and says an interruption in one line itself)
    interrupt = signal.getsignal(signal.SIGINT)
    if interrupt is signal.default_int_handler:
        _note_signals((signal.SIGINT,))
    from .cli import main as command

    if interrupt is signal.default_int_handler:
        signal.signal(signal.SIGINT, interrupt)
        if EARLY_SIGNALS:
            print("interrupted (Ctrl-C)", file=sys.stderr)
            return EXIT_CTRL_C
    return command()


def node_main() -> int:
    """``bearing_sim_node`` (``ros2 run bearing_sim_ros bearing_sim_node``)."""
    _note_signals((signal.SIGINT, signal.SIGTERM, signal.SIGHUP))
    from .cli import node_main as command

    return command()
