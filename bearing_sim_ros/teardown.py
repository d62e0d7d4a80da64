"""A bound on the middleware's teardown (``executor.shutdown``, ``destroy_node``, ``rclpy``
shutdown) in every command that runs a node: ``play``, ``node``, ``run`` and ``monitor``.

Twice it hung: once (CI, clean clone, 2026-11-24) ``play`` logged its last line and did not exit
within 60 s; once (a full suite, 2026-11-30) a ``monitor`` gave its verdicts and then stayed 30 s
in rclpy's ``Node.destroy_node`` (``destroy_when_not_in_use``: rcl's and Fast DDS's node
teardown); neither came back since (the monitor's test: 8 runs alone, 20 more, 10 of them beside a
CPU hog, and twice with test_monitor.py and test_play.py in 2 workers, 2026-12-01).  A command's work is done by then: its lines said,
its recording closed, its exit status decided.  So the teardown comes last (``teardown_watchdog``)
and a hang there costs time, never the outcome: past ``TEARDOWN_TIMEOUT`` one line on stderr says
what hung and that the work is complete, the Python stacks of all threads follow (where it hung),
and the process exits with the status the command had decided (0, 3, 4, 130, ...), not 1.  All of
that runs in C threads (POSIX timers, faulthandler): the hang in ``destroy_when_not_in_use`` holds
the GIL (rclpy does not release it there), and no Python thread runs until it returns.

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
import shlex
import signal
import stat
import sys
import threading
import time
from contextlib import contextmanager

TEARDOWN_TIMEOUT = 30.0      # s: the longest the teardown may take
# after TEARDOWN_TIMEOUT's line, s: the stacks, then the exit (apart, so that each has ended before
# the next begins: each runs on a C thread of its own); the backstop (SIGKILL, 137) only where the
# exit's thread could not be started
_STACKS_AFTER_S, _EXIT_AFTER_S, _BACKSTOP_AFTER_S = 0.5, 1.0, 10.0
# 128 + the signal, as the shell says.  SIGHUP: the terminal closed or the SSH session dropped under
# a node that records; Python's default killed it there (129) and the file had no footer
EXIT_INTERRUPTED = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}
SIGNAL_NAMES = {signal.SIGINT: "Ctrl-C", signal.SIGTERM: "SIGTERM", signal.SIGHUP: "SIGHUP"}


class _SigEvent(ctypes.Structure):
    """glibc's ``struct sigevent`` (64 bytes): the value, the signal, how to notify, then a union
    whose SIGEV_THREAD member is the function to call and its thread's attributes."""
    _fields_ = [("value", ctypes.c_void_p), ("signo", ctypes.c_int), ("notify", ctypes.c_int),
                ("function", ctypes.c_void_p), ("attributes", ctypes.c_void_p), ("pad", ctypes.c_int * 8)]


class _TimeSpec(ctypes.Structure):
    _fields_ = [("sec", ctypes.c_long), ("nsec", ctypes.c_long)]


class _ITimerSpec(ctypes.Structure):
    _fields_ = [("interval", _TimeSpec), ("value", _TimeSpec)]


_SIGEV_SIGNAL, _SIGEV_THREAD, _CLOCK_MONOTONIC = 0, 2, 1
_LIBC = None


def _libc():
    global _LIBC
    if _LIBC is None:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.timer_create.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]
        libc.timer_settime.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]
        libc.timer_delete.argtypes = [ctypes.c_void_p]
        _LIBC = libc
    return _LIBC


def _c_timer(seconds: float, function=None, argument: int = 0, signo: int = 0):
    """A one-shot POSIX timer: ``seconds`` (s) from now, the C ``function(argument)`` runs on a
    thread of its own (``argument``: an int or a pointer, as C's ``union sigval`` passes it), or
    without a function, ``signo`` is sent to the process.  Neither needs the GIL.  Its id, for
    ``timer_delete``; OSError where it cannot be made."""
    libc = _libc()
    event = _SigEvent(value=argument, signo=signo, notify=_SIGEV_THREAD if function else _SIGEV_SIGNAL,
                      function=ctypes.cast(function, ctypes.c_void_p).value if function else None)
    timer = ctypes.c_void_p()
    if libc.timer_create(_CLOCK_MONOTONIC, ctypes.byref(event), ctypes.byref(timer)) != 0:
        raise OSError(ctypes.get_errno(), "timer_create failed")
    whole = int(seconds)
    spec = _ITimerSpec(value=_TimeSpec(whole, max(1, int((seconds - whole) * 1e9))))
    if libc.timer_settime(timer, 0, ctypes.byref(spec), None) != 0:
        libc.timer_delete(timer)
        raise OSError(ctypes.get_errno(), "timer_settime failed")
    return timer


class _Watchdog:
    """The C side of ``teardown_watchdog``: at ``TEARDOWN_TIMEOUT`` the line (``/bin/sh``, started
    by C's ``system``), ``_STACKS_AFTER_S`` later the stacks (faulthandler's timer thread),
    ``_EXIT_AFTER_S`` later C's ``_exit`` with the status.  Not a signal for the stacks (to a
    handler of faulthandler's): it interrupts the hung call (EINTR: a hung ``sleep`` returned),
    and a teardown that hangs is left alone, not pushed into half an end.  The backstop,
    ``_BACKSTOP_AFTER_S`` later, is a SIGKILL from the kernel: the timers' calls each need a new
    thread, which a process at its limit of threads may not get; it must end all the same."""

    def __init__(self, who: str, status: int, said):
        self.who, self.status, self.said = who, status, list(said)
        self.deadline = time.monotonic() + TEARDOWN_TIMEOUT
        self._timers = {}           # name: timer id
        self._texts = {}            # the line's shell command (C keeps a pointer to it) and the status

    def code(self) -> int:
        """The status, or where it is 0, the 130 / 143 of a signal held during the shutdown."""
        return _COMMAND_SIGNALS.code(self.status) if _COMMAND_SIGNALS is not None else self.status

    def arm(self) -> None:
        faulthandler.dump_traceback_later(TEARDOWN_TIMEOUT + _STACKS_AFTER_S, exit=False)
        try:
            self._arm_line_and_exit()
            self._timers["backstop"] = _c_timer(TEARDOWN_TIMEOUT + _BACKSTOP_AFTER_S, signo=signal.SIGKILL)
        except (OSError, AttributeError):       # no POSIX timers (not glibc): faulthandler's exit, 1
            self.disarm()
            faulthandler.dump_traceback_later(TEARDOWN_TIMEOUT, exit=True)

    def _arm_line_and_exit(self) -> None:
        code = self.code()
        line = (f"{self.who}: the middleware's teardown (destroy_node, rclpy shutdown) has not ended after "
                f"{TEARDOWN_TIMEOUT:g} s; the command's work is complete (its lines above, a recording "
                f"closed), so it exits with its status {code} without it; where it hung: the stacks below")
        command = ctypes.create_string_buffer(
            ("printf '%s\\n' " + " ".join(shlex.quote(text) for text in [*self.said, line]) + " >&2").encode())
        left = max(0.001, self.deadline - time.monotonic())
        self._timers["line"] = _c_timer(left, _libc().system, ctypes.addressof(command))
        self._timers["exit"] = _c_timer(left + _EXIT_AFTER_S, _libc()._exit, code)
        self._texts = {"command": command, "code": code}

    def rearm(self) -> None:
        """Once a signal was held: the status it gives (``code``), if it changed."""
        if self._texts.get("code") in (None, self.code()):
            return
        for name in ("line", "exit"):
            _libc().timer_delete(self._timers.pop(name))
        self._arm_line_and_exit()

    def disarm(self) -> None:
        faulthandler.cancel_dump_traceback_later()
        for timer in self._timers.values():
            _libc().timer_delete(timer)
        self._timers = {}


_WATCHDOG = None


@contextmanager
def teardown_watchdog(who: str, status: int = 0, said=()):
    """Run the block, the middleware's teardown and nothing else, as the last thing a command
    does: where it lasts more than ``TEARDOWN_TIMEOUT`` s, the lines ``said`` (what the command
    would say after it) and one line (``who`` hung in the teardown, the work is complete) go to
    stderr, then every thread's stack, and the process exits with ``status`` (or, 0 with a
    signal held, 130 / 143) as the command would have.  Where an exception is on its way through
    the block (the command failed before it), the status is the command line's for it: 2 with its
    ``error:`` line for a UserError, 141 for a closed standard output, else 1.  A block that raises
    raises (exit 1 with a traceback: a defect).  Standard output and error are flushed first:
    ``_exit`` drops what is buffered."""
    global _WATCHDOG
    from .cli import EXIT_INTERNAL, EXIT_STDOUT_CLOSED, EXIT_USER      # cli imports this module
    from .errors import UserError

    failing = sys.exc_info()[1]
    if isinstance(failing, UserError):
        status, said = EXIT_USER, [*said, f"error: {failing}"]
    elif isinstance(failing, BrokenPipeError):
        status = EXIT_STDOUT_CLOSED
    elif failing is not None and not isinstance(failing, KeyboardInterrupt):
        status, said = EXIT_INTERNAL, [*said, f"internal error: {failing.__class__.__name__}: {failing}"]
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):   # closed, or its reader gone: nothing to keep
            pass
    _libc().fflush(None)            # C's: rcutils' log lines
    watchdog = _Watchdog(who, status, said)
    watchdog.arm()
    _WATCHDOG = watchdog
    try:
        yield
    finally:
        _WATCHDOG = None
        watchdog.disarm()


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
        if _WATCHDOG is not None:
            _WATCHDOG.rearm()       # a teardown that hangs now exits 130 / 143, as one that ends
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
