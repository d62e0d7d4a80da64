"""One line on standard error while numba compiles kernels, and one when it is done.

On a cold cache (the first run after an install or a change of the physics) the commands that
simulate sat silent for minutes while numba compiled the tiers' kernels (95 s before the node's
start line and 65 s more on a busy 2-core Intel Xeon): a newcomer took it for a hang.  numba
announces each compilation it actually makes (the ``numba:compile`` event; a kernel loaded from
its cache raises none), so a warm start stays silent, with no timer to guess from.

The commands turn it on (``enable``); the simulator says what is compiled (``Notice.within``) and
when it is ready (``Notice.finish``).  A library user's ``Simulator`` says nothing.
"""
from __future__ import annotations

import threading
import time
from contextlib import contextmanager

_local = threading.local()      # .current: (Notice, label, note) of this thread; .depth: nesting
_lock = threading.Lock()
_enabled = False
_program = "bearing-sim"        # the lines' first word: the command the user typed


class Notice:
    """What one thread compiles for one purpose (a tier's kernels): said once when its first
    compilation starts, and with the compiling time (s) by ``finish``.  Plain data (copied and
    pickled with its simulator)."""

    def __init__(self):
        self.label = None       # what is compiled, as said (None: nothing since the last finish)
        self.spent = 0.0        # s spent compiling since it was said

    @contextmanager
    def within(self, label, note: str = ""):
        """Compilations in this thread within the block are this notice's; ``label``: what they
        compile, or a callable giving it when the first one starts (a tier switch names the tier
        it switches to); ``note``: words after it in the first line."""
        prev = getattr(_local, "current", None)
        _local.current = (self, label, note)
        try:
            yield self
        finally:
            _local.current = prev

    def finish(self) -> None:
        """Say how long the compiling took, if there was any since the last ``finish``."""
        if self.label is not None:
            _say(f"{self.label} compiled in {self.spent:.0f} s")
            self.label, self.spent = None, 0.0


_UNNAMED = Notice()             # compilations outside any notice: said once per process


def enable(program: str = "bearing-sim") -> None:
    """Say the compilations of this process from now on (idempotent), each line beginning with
    ``program``: the name the user started it by (``bearing-sim``, ``bearing_sim_node``)."""
    global _enabled, _program
    with _lock:
        _program = program
        if _enabled:
            return
        import numba.core.event as ev

        class _Listener(ev.Listener):
            # called inside numba's compiler: a notice that failed must not fail the compilation
            def on_start(self, event):
                try:
                    _started()
                except Exception:  # noqa: BLE001 - a line not said is all that is lost
                    pass

            def on_end(self, event):
                try:
                    _ended()
                except Exception:  # noqa: BLE001
                    pass

        ev.register("numba:compile", _Listener())
        _enabled = True


def _started() -> None:
    # nested events: a kernel's callees compile within its compilation; the outermost counts
    depth = getattr(_local, "depth", 0)
    _local.depth = depth + 1
    if depth:
        return
    _local.since = time.monotonic()
    notice, label, note = getattr(_local, "current", None) or (_UNNAMED, "numba kernels", "")
    _local.notice = notice
    if notice.label is not None:        # said already (the unnamed one: for good)
        return
    notice.label = label() if callable(label) else label
    import numba.core.config as nb_config

    _say(f"compiling {notice.label}{note} (the first run after an install or a change of the physics: "
         f"about a minute per tier on 2 cores; kept in {nb_config.CACHE_DIR} for the next runs) ...")


def _ended() -> None:
    _local.depth = getattr(_local, "depth", 1) - 1
    if _local.depth == 0 and getattr(_local, "notice", None) is not None:
        _local.notice.spent += time.monotonic() - _local.since
        _local.notice = None


def _say(text: str) -> None:
    from .teardown import say_on_stderr

    say_on_stderr(f"{_program}: {text}")
