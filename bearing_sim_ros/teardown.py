"""A bound on the middleware's teardown (``destroy_node``, ``rclpy`` shutdown) in every command
that runs a node: ``play``, ``node``, ``run`` and ``monitor``.

Once (CI, clean clone, 2026-11-24) ``play`` logged its last line and then did not exit within
60 s; where it hung is not known (it did not come back in 50 runs since).  A command must not
hang forever there: its work is done by then (the recording closed, the messages sent), so past
``TEARDOWN_TIMEOUT`` the Python stacks of all threads go to stderr, which says where it hung, and
the process exits with status 1.  faulthandler's watchdog is a C thread: it fires even if the hang
holds the GIL.

And ``signal_handlers``: handlers for a block of a command's shutdown (``render`` finishing at a
batch's end, ``render`` and ``run`` holding Ctrl-C while a recording is finalised or read);
``CommandSignals``: Ctrl-C and SIGTERM of a command that runs a node (``node``, ``run``,
``monitor``, ``play``) from its first line to its exit.
"""
from __future__ import annotations

# every module the signal handlers below may use is imported here, none where they run: a handler
# runs between two bytecodes of whatever the main thread does, an import too, and an import it
# started there (``select``, on the first Ctrl-C while numpy was imported) broke Python 3.11's
# record of the import it interrupted (``importlib._bootstrap._blocking_on``, one entry per
# thread): a KeyError out of that import, exit 1 with a traceback
import ctypes
import errno
import faulthandler
import os
import select
import signal
import stat
import sys
import threading
from contextlib import contextmanager

TEARDOWN_TIMEOUT = 30.0      # s: the longest the teardown may take
# 128 + the signal, as the shell says.  SIGHUP: the terminal closed or the SSH session dropped under
# a node that records; Python's default killed it there (129) and the file had no footer
EXIT_INTERRUPTED = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}
SIGNAL_NAMES = {signal.SIGINT: "Ctrl-C", signal.SIGTERM: "SIGTERM", signal.SIGHUP: "SIGHUP"}


@contextmanager
def teardown_watchdog():
    """Run the block (the teardown) under the watchdog: if it lasts more than
    ``TEARDOWN_TIMEOUT`` s, dump every thread's stack to stderr and exit with status 1."""
    faulthandler.dump_traceback_later(TEARDOWN_TIMEOUT, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


def drop_a_closed_terminal() -> None:
    """Point standard output and error at /dev/null where they go to a terminal that hung up
    (its window closed, the SSH session dropped: the SIGHUP that comes with it).  Every write to
    such a terminal fails (EIO): the lines a command prints as it ends (``run``'s summary,
    ``monitor``'s last lines, ``render``'s progress bar and its ``interrupted`` line) raised an
    OSError there, after the recording was finalised, and ended the command as an internal error
    (exit 1; a traceback where stderr went to a file), or ended a render before it kept its file.
    Nobody can read them any more.  A terminal still there (a ``kill -HUP`` by hand) is kept."""
    for fd in (1, 2):                   # standard output and error
        try:
            poll = select.poll()
            poll.register(fd, select.POLLOUT)
            # a terminal that hung up polls as hung up (and in error); a live one, a file or a pipe not
            hung_up = any(events & select.POLLHUP for _fd, events in poll.poll(0))
        except OSError:                 # closed
            continue
        if hung_up:
            point_at_devnull(fd)


# re-entrant: a signal handler that says its line runs in the thread it interrupted, maybe inside say
_SAY_LOCK = threading.RLock()


def say(line: str, file=None) -> None:
    """``line`` on ``file`` (default standard output, as it is now), flushed.  Where that fails with
    EIO, a terminal that hung up as the line was written, before the SIGHUP that comes with it was
    handled (``CommandSignals.handle``; a shell passing the hangup on to its jobs takes
    milliseconds): the line goes nowhere, as every line after it does (``drop_a_closed_terminal``),
    and the command goes on to the end its SIGHUP gives it.  ``monitor``'s, ``run``'s and ``play``'s
    lines raised the OSError there and ended them as an internal error, exit 1.  An EIO of a file
    (``monitor > verdicts.txt`` on a failing disk or network mount) is raised: its lines are lost."""
    file = file or sys.stdout
    try:
        with _SAY_LOCK:
            # one write of the line with its newline: print() writes the two apart, and where the
            # stream writes through (PYTHONUNBUFFERED) another thread's line came between them
            # (monitor's envelope worker and its executor: 'waiting for more)t=2.00s ...')
            file.write(line + "\n")
            file.flush()
    except OSError as exc:
        if exc.errno != errno.EIO or not _a_terminal(file):
            raise
        # not re-raised where the terminal is not found hung up: the SIGHUP's handler may have
        # pointed it at /dev/null between the write and here
        drop_a_closed_terminal()


def _a_terminal(file) -> bool:
    """Is ``file`` a character device: a terminal (one that hung up is no longer ``isatty``: its
    ioctls fail), or /dev/null where the SIGHUP's handler pointed it there since?"""
    try:
        return stat.S_ISCHR(os.fstat(file.fileno()).st_mode)
    except (AttributeError, OSError, ValueError):      # no descriptor (io.StringIO) or closed
        return False


def say_on_stderr(line: str) -> None:
    """``line`` on standard error; where its reader went away (``bearing-sim node ... 2>&1 | head
    -1``), its terminal closed as it was written (``say``) or its file cannot take it (``2> log``
    on a full disk), nothing, and the command's exit status stays its own: the BrokenPipeError
    made a mistake's or a failed recording's 2 an "internal error" (1) or a closed output (141),
    and the terminal's EIO or the disk's ENOSPC an internal error (whose own lines went nowhere)."""
    try:
        say(line, sys.stderr)
    except OSError:         # nowhere left to say it; the status says it
        point_at_devnull(sys.stderr.fileno())


def point_at_devnull(fd: int) -> None:
    """Point descriptor ``fd`` (standard output or error whose reader went away) at /dev/null:
    what is still written there, Python's own flush at exit included, goes nowhere quietly."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


@contextmanager
def signal_handlers(handlers: dict):
    """Install ``handlers`` ({signal: handler}) for the block and put the previous ones back
    after it.  In the main thread only, where Python runs signal handlers and may set them;
    elsewhere (a caller's worker thread) the block runs with the handlers as they are."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    saved = {sig: signal.signal(sig, handler) for sig, handler in handlers.items()}
    try:
        yield
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)


class CommandSignals:
    """Ctrl-C, SIGTERM and SIGHUP of a command that runs a node (``bearing-sim node``,
    ``bearing_sim_node``, ``run``, ``monitor``, ``play``), from its first line to the end of the
    process, in the main thread.

    The node's shutdown must run to its end (a KeyboardInterrupt in the middle of finalising a
    recording lost the file), and a signal must not be lost on the way: before, one in the first
    half second (while numpy and numba were imported) killed the process (143) or printed a
    KeyboardInterrupt traceback, and a second Ctrl-C after the shutdown's handlers were put back,
    while the process exited (0.4 s: the middleware's and numba's teardown), was swallowed (exit
    0).  So one handler serves the whole life of the process, and it never raises (a
    KeyboardInterrupt raised into an import came out of numpy as an ImportError):

    * the first signal is noted (``first``, and ``stopped`` set for a loop that waits on an
      event): the start-up ends at its next step (``check()``, between imports, ``rclpy.init`` and
      the node's construction), the command's loop ends on it;
    * after the first signal, or from ``shutting_down()`` on (``duration`` ended): every signal is
      noted in ``held`` and said (``on_held(signum, done)``);
    * ``exit(status)``: the process ends there (``os._exit``, once the command has closed and
      destroyed what it opened), with ``status``, or where it is 0 and a signal was held, that
      signal's 130 or 143, as the shell reports an interrupted command.  A signal that comes while
      it exits ends it at once with that status too: after ``exit`` nothing is left to run."""

    def __init__(self):
        self.first = None           # the signal that ended the run
        self.stopped = threading.Event()    # set with ``first``
        self.held = []              # signals during the shutdown
        self.on_held = None         # on_held(signum, done): say it; done = the process is exiting
        self._stopping = False
        self._status = None         # set by exit()

    def handle(self, signum, _frame):
        drop_a_closed_terminal()
        if self.first is None and not self._stopping:
            self.first = signum
            self._stopping = True
            self.stopped.set()
            return
        self.held.append(signum)
        if self.on_held is not None:
            self.on_held(signum, self._status is not None)
        if self._status is not None:
            self._exit_now()

    def check(self) -> None:
        """KeyboardInterrupt if a signal came: between two steps of the start-up, where it ends
        nothing half done."""
        if self.first is not None:
            raise KeyboardInterrupt

    def shutting_down(self) -> None:
        self._stopping = True

    def code(self, status: int) -> int:
        """``status``, or where it is 0 the 130 / 143 of the first signal held."""
        return EXIT_INTERRUPTED[self.held[0]] if status == 0 and self.held else status

    def exit(self, status: int):
        """End the process with ``code(status)``: Python's streams and C's (rcutils' log lines)
        flushed, its finalisation skipped (nothing of it is the command's any more)."""
        self._status = status
        self._exit_now()

    def _exit_now(self):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # noqa: BLE001 - closed, full, or a flush this signal interrupted
                pass
        ctypes.CDLL(None).fflush(None)
        os._exit(self.code(self._status))


_COMMAND_SIGNALS = None


def command_signals() -> CommandSignals:
    """The process's ``CommandSignals``: the one ``node_signals`` installed, else one installed now
    (in the main thread; elsewhere signals stay as they are)."""
    global _COMMAND_SIGNALS
    if _COMMAND_SIGNALS is None:
        _COMMAND_SIGNALS = CommandSignals()
        if threading.current_thread() is threading.main_thread():
            for sig in EXIT_INTERRUPTED:
                # a hangup ignored from the start (``nohup``) stays ignored: run to survive it
                if sig != signal.SIGHUP or signal.getsignal(sig) != signal.SIG_IGN:
                    signal.signal(sig, _COMMAND_SIGNALS.handle)
            # those the console script noted before (``entry``: while cli was loaded), as if now
            from .entry import EARLY_SIGNALS

            while EARLY_SIGNALS:
                _COMMAND_SIGNALS.handle(EARLY_SIGNALS.pop(0), None)
    return _COMMAND_SIGNALS


def signal_noted() -> bool:
    """Whether this process's ``CommandSignals`` (a command that runs a node) noted a signal: a
    wait that the handler does not interrupt (it never raises) asks it to end."""
    return _COMMAND_SIGNALS is not None and _COMMAND_SIGNALS.first is not None


@contextmanager
def node_signals():
    """``command_signals()`` for the block, the first thing a command that runs a node does; the
    handlers before it are put back after it, which only a command that did not run its node
    reaches (``--help``, a mistake in its arguments)."""
    global _COMMAND_SIGNALS
    saved = {sig: signal.getsignal(sig) for sig in EXIT_INTERRUPTED}
    try:
        yield command_signals()
    finally:
        if threading.current_thread() is threading.main_thread():
            for sig, handler in saved.items():
                if handler is not None:          # None: not one set from Python
                    signal.signal(sig, handler)
        _COMMAND_SIGNALS = None
