"""The suite's guard against a hung test (``conftest.HUNG_TEST_S``): the test ends with its stacks
and with the processes it started."""
import os
import subprocess
import sys
import time
from pathlib import Path

TEST_DIR = Path(__file__).resolve().parent


def test_a_hung_test_ends_with_its_stacks_and_takes_its_processes_with_it(tmp_path):
    """A test that hung was ended after ``HUNG_TEST_S`` by faulthandler, which ends the process
    at once: a node the test had started (its own session, running until stopped) ran on for ever,
    an orphan of init.  Here a throwaway test (limit 3 s) starts a long ``sleep`` in a session of
    its own and hangs: its stack is printed, the run fails, and the sleep is gone too."""
    pid_file = tmp_path / "child.pid"
    hanging = tmp_path / "test_hangs.py"
    hanging.write_text(f"""
import subprocess
import time

import conftest

conftest.HUNG_TEST_S = 3.0


def test_hangs_with_a_child():
    child = subprocess.Popen(["sleep", "600"], start_new_session=True)
    with open({str(pid_file)!r}, "w") as f:
        f.write(str(child.pid))
    time.sleep(600)
""")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(TEST_DIR), os.environ.get("PYTHONPATH")])))
    run = subprocess.run([sys.executable, "-m", "pytest", "-p", "conftest", "-p", "no:cacheprovider", "-q",
                          str(hanging)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    child = int(pid_file.read_text())
    try:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and _runs(child):
            time.sleep(0.1)
        assert not _runs(child), "the hung test's child process was left running"
    finally:
        if _runs(child):
            os.kill(child, 9)
    assert run.returncode != 0, run.stdout
    assert "test still running after 3 s" in run.stderr and "test_hangs_with_a_child" in run.stderr, run.stderr


def _runs(pid: int) -> bool:
    """Whether ``pid`` is a process that has not ended (a zombie has)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
