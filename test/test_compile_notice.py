"""A cold cache's compiling is said on stderr (one line, then its time); a warm start says nothing.

The first run after an install sat silent for minutes while numba compiled the tiers' kernels
(95 s before the node's start line, 65 s more after it, on a busy 2-core machine): a newcomer took
it for a hang.  A tier compiles for 30-70 s here, too long for a test; the mechanism is tested on a
kernel of its own, compiled for real into an empty cache, and the commands' silence on a warm one.
"""
import os
import re
import subprocess
import sys

# a fresh process, as a command is: numba compiles into (or loads from) NUMBA_CACHE_DIR
SCRIPT = """
import sys
sys.path.insert(0, sys.argv[1])
from bearing_sim_ros import compile_notice
if sys.argv[2] == "enabled":
    compile_notice.enable()
import tiny_kernels
notice = compile_notice.Notice()
for x in (2.0, 3.0):            # the second time: nothing compiles, nothing to say
    with notice.within("the tiny kernels"):
        assert tiny_kernels.square(x) == x * x
    notice.finish()
tiny_kernels.cube(2.0)          # outside any notice: said once, without a time
tiny_kernels.cube(2)            # another signature: compiled, not said again
"""

KERNELS = """
from numba import njit


@njit(cache=True)
def square(x):
    return x * x


@njit(cache=True)
def cube(x):
    return x * x * x
"""


def _run(tmp_path, cache, mode):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    r = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path), mode], env=env, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return r.stderr.splitlines()


def test_a_cold_compilation_is_said_once_with_its_time_and_a_cached_load_says_nothing(tmp_path):
    (tmp_path / "tiny_kernels.py").write_text(KERNELS)
    cache = tmp_path / "cache"
    lines = _run(tmp_path, cache, "enabled")
    assert len(lines) == 3, lines
    assert lines[0] == (f"bearing-sim: compiling the tiny kernels (the first run after an install or a change of "
                        f"the physics: about a minute per tier on 2 cores; kept in {cache} for the next runs) ..."), lines
    assert re.fullmatch(r"bearing-sim: the tiny kernels compiled in \d+ s", lines[1]), lines
    assert lines[2].startswith("bearing-sim: compiling numba kernels (the first run"), lines
    # the same kernels again, from the cache: silent, as a warm start of a command is
    assert _run(tmp_path, cache, "enabled") == []


def test_a_library_user_is_not_told(tmp_path):
    """Only the commands turn the lines on: a ``Simulator`` in someone's script compiles silently."""
    (tmp_path / "tiny_kernels.py").write_text(KERNELS)
    cache = tmp_path / "cache"
    assert _run(tmp_path, cache, "disabled") == []
    assert list(cache.rglob("*.nbi")), "nothing compiled: the test tested nothing"


def test_a_warm_render_says_nothing_on_stderr(tmp_path, bearing_sim_exe, ros_env):
    """The real command: the second of two renders (the first compiled, if the cache was cold, and
    then said so in exactly two lines) loads every kernel and says nothing on stderr."""
    argv = [bearing_sim_exe, "render", "er16k_outer_race", "--duration", "0.05", "--fidelity", "kinematic",
            "--out", str(tmp_path / "x.mcap")]
    first = subprocess.run(argv, env=ros_env, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr
    said = first.stderr.splitlines()
    assert said == [] or (len(said) == 2 and said[0].startswith(
        "bearing-sim: compiling the kinematic tier's kernels (") and "compiled in" in said[1]), said
    (tmp_path / "x.mcap").unlink()
    second = subprocess.run(argv, env=ros_env, capture_output=True, text=True, timeout=120)
    assert second.returncode == 0 and second.stderr == "", second.stderr
