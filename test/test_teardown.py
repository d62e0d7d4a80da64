"""``teardown.teardown_watchdog`` on its own: a real hang (a sleep, with the GIL held or free) in a
subprocess, past a timeout cut to 1 s; what the process says and the status it exits with.  The
commands under it (``play``, ``node``, ``monitor``) are in their own tests' files."""
from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

from test_node_support import HANG_HOLDING_THE_GIL, assert_hung_teardown_said


def _run_script(tmp_path, lines: list, sig=None) -> tuple:
    """Run ``lines`` (Python, after the watchdog's timeout is cut to 1 s) in a subprocess; with
    ``sig``, send it that signal once it printed ``tearing down``.  (exit status, stdout, stderr,
    seconds it took)."""
    script = tmp_path / "teardown.py"
    script.write_text("\n".join(["import ctypes, sys, time",
                                 "from bearing_sim_ros import teardown",
                                 "teardown.TEARDOWN_TIMEOUT = 1.0", *lines, ""]))
    started = time.monotonic()
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    if sig is not None:
        assert proc.stdout.readline() == "tearing down\n"
        time.sleep(0.2)
        proc.send_signal(sig)
    out, err = proc.communicate(timeout=30)
    return proc.returncode, out, err, time.monotonic() - started


@pytest.mark.parametrize("hang", ["time.sleep(600)", HANG_HOLDING_THE_GIL])
def test_a_hung_teardown_exits_with_the_commands_status_a_line_and_the_stacks(tmp_path, hang):
    """A teardown that never returns, with the GIL free or held (no Python thread can run then):
    at the timeout one line says what hung and that the work is done, the stacks say where, and the
    process exits with the status the command decided (3 here), not faulthandler's 1.  The lines
    said before the teardown are kept (flushed before it: ``_exit`` drops buffers)."""
    status, out, err, took = _run_script(tmp_path, [
        "print('monitor: 3 verdicts')",         # block-buffered: stdout is a pipe
        "with teardown.teardown_watchdog('monitor', 3):",
        f"    {hang}",
    ])
    assert status == 3, err
    assert out == "monitor: 3 verdicts\n", out
    assert_hung_teardown_said(err.replace("<module>", "<lambda>"), "monitor", 3)
    assert "Traceback" not in err and took < 10, (took, err)


def test_a_user_error_on_its_way_through_a_hung_teardown_exits_2_with_its_line(tmp_path):
    """A command that failed (a UserError) before its teardown: where the teardown hangs, the
    error's line (which the command line would say after it) and the watchdog's, exit 2."""
    status, _out, err, _took = _run_script(tmp_path, [
        "from bearing_sim_ros.errors import UserError",
        "try:",
        "    raise UserError('x.mcap: nothing to play')",
        "finally:",
        "    with teardown.teardown_watchdog('play x.mcap', 0):",
        "        time.sleep(600)",
    ])
    assert status == 2, err
    lines = err.splitlines()
    assert lines[0] == "error: x.mcap: nothing to play", err
    assert_hung_teardown_said(err.replace("<module>", "<lambda>"), "play x.mcap", 2)


def test_a_teardown_that_raises_raises_and_leaves_nothing_armed(tmp_path):
    """A teardown that raises is a defect: the exception comes out of the block (the command line
    prints its traceback, exit 1), and nothing of the watchdog fires after it: the process goes on
    past the timeout and exits as it chooses."""
    status, _out, err, took = _run_script(tmp_path, [
        "try:",
        "    with teardown.teardown_watchdog('monitor', 0):",
        "        raise RuntimeError('rcl said no')",
        "except RuntimeError as exc:",
        "    print(f'raised: {exc}', file=sys.stderr)",
        "time.sleep(3)                  # the line at 1 s, the stacks at 1.5 s, the exit at 2 s",
        "sys.exit(5)",
    ])
    assert status == 5 and err == "raised: rcl said no\n", err
    assert took >= 3, took


def test_a_signal_held_during_a_hung_teardown_gives_its_status(tmp_path):
    """SIGTERM during a teardown that hangs (the GIL free: the handler runs), after the command's
    end began: held, as during any shutdown, and the process exits 143, as one whose teardown
    ended does (``CommandSignals.exit``), and the line says so."""
    status, _out, err, _took = _run_script(tmp_path, [
        "signals = teardown.command_signals()",
        "signals.shutting_down()",
        "print('tearing down', flush=True)",
        "with teardown.teardown_watchdog('bearing_sim', 0):",
        "    time.sleep(600)",
    ], sig=signal.SIGTERM)
    assert status == 143, err
    assert_hung_teardown_said(err.replace("<module>", "<lambda>"), "bearing_sim", 143)
