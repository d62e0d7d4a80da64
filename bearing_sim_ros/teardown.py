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
``signals_noted``: Ctrl-C and SIGTERM noted, not raised, while the node shuts down.
"""
from __future__ import annotations

import faulthandler
import signal
import threading
from contextlib import contextmanager

TEARDOWN_TIMEOUT = 30.0      # s: the longest the teardown may take
EXIT_INTERRUPTED = {signal.SIGINT: 130, signal.SIGTERM: 143}    # 128 + the signal, as the shell says


@contextmanager
def teardown_watchdog():
    """Run the block (the teardown) under the watchdog: if it lasts more than
    ``TEARDOWN_TIMEOUT`` s, dump every thread's stack to stderr and exit with status 1."""
    faulthandler.dump_traceback_later(TEARDOWN_TIMEOUT, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


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


@contextmanager
def signals_noted(on_signal=None):
    """Ctrl-C and SIGTERM noted, not raised, for the block: a shutdown that must run to its end (a
    KeyboardInterrupt in the middle of finalising a recording lost the file).  Yields the list of
    the signals that came (numbers, in order); ``on_signal(signum)`` is called at each, in the main
    thread between two steps of the block.  In the main thread only, like ``signal_handlers``."""
    noted = []

    def note(signum, _frame):
        noted.append(signum)
        if on_signal is not None:
            on_signal(signum)

    with signal_handlers({signal.SIGINT: note, signal.SIGTERM: note}):
        yield noted
