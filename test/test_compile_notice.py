"""A cold cache's compiling is said on stderr (one line, then its time); a warm start says nothing.

The first run after an install sat silent for minutes while numba compiled the tiers' kernels
(95 s before the node's start line, 65 s more after it, on a busy 2-core machine): a newcomer took
it for a hang.  A tier compiles for 30-70 s here, too long for a test; the mechanism is tested on a
kernel of its own, compiled for real into an empty cache, the node on a copy of the warm cache
less one small kernel (compiled for real in seconds), and the commands' silence on a warm one.
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


def _cache_without(tmp_path, pattern):
    """A copy of this checkout's compiled kernels (warm: ``make test`` compiles them first) less
    the files of ``pattern``: a process that uses it compiles those kernels for real, and only
    those, in seconds instead of a tier's minute."""
    import shutil

    import numba.core.config as nb_config

    import bearing_sim_ros.physics  # noqa: F401 - sets numba's cache folder, as a command does

    cache = tmp_path / "cache"
    # the package keeps them in a folder of its own under NUMBA_CACHE_DIR (per checkout)
    shutil.copytree(nb_config.CACHE_DIR, cache / os.path.basename(nb_config.CACHE_DIR))
    removed = list(cache.rglob(pattern))
    assert removed, f"no {pattern} in {nb_config.CACHE_DIR}: the test would compile nothing"
    for f in removed:
        f.unlink()
    return cache


def test_the_nodes_lines_name_bearing_sim_node_and_its_tier_is_compiled_before_its_start_line(
        tmp_path, ros_env):
    """``bearing_sim_node`` on a cache without the sensor chain's main kernel (a cold cache, for
    that kernel alone): its lines begin with its own name, not ``bearing-sim``, and the running
    tier's "compiled in N s" comes before the start line (until 2026-11-30 it came after the first
    batch, behind the other tier's background lines, and both began ``bearing-sim:``)."""
    cache = _cache_without(tmp_path, "sensor._commit-*")
    node = os.path.join(os.path.dirname(sys.executable), "bearing_sim_node")
    r = subprocess.run([node, "--ros-args", "-p", "scene:=er16k_healthy", "-p", "duration:=0.1"],
                       env={**ros_env, "NUMBA_CACHE_DIR": str(cache)}, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    said = [i for i, ln in enumerate(lines) if "kernels" in ln]
    start = [i for i, ln in enumerate(lines) if "inputs accepted" in ln]
    assert len(said) == 2 and len(start) == 1, r.stderr
    assert lines[said[0]].startswith("bearing_sim_node: compiling the kinematic tier's kernels ("), r.stderr
    assert re.fullmatch(r"bearing_sim_node: the kinematic tier's kernels compiled in \d+ s", lines[said[1]]), r.stderr
    assert said[1] < start[0], r.stderr


def test_loading_the_kernels_ahead_changes_no_sample():
    """``Simulator.load_kernels`` (the node calls it before its start line) advances a copy: the
    simulator's own samples are the same bits with and without it."""
    import numpy as np

    from bearing_sim_ros import Simulator

    plain, loaded = Simulator("er16k_outer_race", seed=3), Simulator("er16k_outer_race", seed=3)
    loaded.load_kernels()
    for _ in range(3):
        a, b = plain.advance(150), loaded.advance(150)
        assert a.index0 == b.index0 == loaded.index - 150
        assert np.array_equal(a.accel, b.accel) and np.array_equal(a.contact_forces, b.contact_forces)
