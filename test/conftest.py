"""Shared test fixtures.

ROS tests run real rclpy publishers and subscribers across processes.  Each test gets its own
ROS_DOMAIN_ID (so parallel or leftover participants never cross-talk) and discovery limited to
localhost, both in this process's environment and in the environment handed to subprocesses.
"""
from __future__ import annotations

import faulthandler
import fcntl
import itertools
import os
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest

from bearing_sim_ros.stale_dds_ports import clear_half_made_ports

REPO = Path(__file__).resolve().parent.parent

# The suite sends SIGINT and SIGHUP to the commands it starts, and they inherit what this
# process ignores: run from a script's background job (SIGINT ignored) or under nohup (SIGHUP
# ignored), the signal tests hung or failed.  The commands honour an ignored signal on purpose
# (nohup keeps a node running), so the suite starts them with both at their defaults.
for _sig, _default in ((signal.SIGINT, signal.default_int_handler), (signal.SIGHUP, signal.SIG_DFL)):
    if signal.getsignal(_sig) == signal.SIG_IGN:
        signal.signal(_sig, _default)
SHARED = REPO.parent / "shared"


def pytest_configure(config):
    # `make test` runs the suite in workers (pytest-xdist, TEST_WORKERS) and then these tests alone: with
    # another test's processes on the other core, a play paced to 10 % over 0.2 s arrived 10 %
    # late and a process sent SIGTERM 0.1 s after launch had not reached its first line yet
    config.addinivalue_line("markers", "wall_clock: measures against the steady clock (pacing, a signal "
                                       "in a process's first moments); `make test` runs these alone")


# A test that hangs (a participant waiting for ever on a broken shared-memory port: one did, for
# 20 minutes, until its worker was killed by hand) prints every thread's stack and ends its
# process after this long, so the run ends with a failure that says where, not at CI's time limit.
# The slowest test takes under 20 s on a quiet 2-core machine, a minute or two loaded or compiling.
# (Code under test that sets a faulthandler timer of its own, teardown_watchdog, replaces the
# faulthandler backstop below for the rest of that test; the timer thread stays.)
HUNG_TEST_S = 300.0
# A hung test's processes are ended with it: a node it started runs until it is stopped, and a
# test process that just ended left it running for ever (an orphan of init, on a domain whose lock
# went with the test, so the next test to claim that domain met it).  Where the hang holds the GIL
# the timer thread that does this cannot run; faulthandler ends the process this much later.
HUNG_EXIT_GRACE_S = 30.0
_uncaptured_stderr = None      # the stacks go where pytest's own lines go, not into a test's capture


def _children() -> list:
    """The pids of this process's children (from /proc: ``pid (name) state ppid ...``)."""
    me = str(os.getpid())
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()    # the name may hold spaces and brackets
        except (OSError, IndexError):
            continue
        if fields[1] == me:
            found.append(int(entry))
    return found


def _signal_children(sig) -> None:
    """``sig`` to each child, and to its process group where it leads one (``start_new_session``)."""
    for pid in _children():
        try:
            if os.getpgid(pid) == pid:
                os.killpg(pid, sig)
            else:
                os.kill(pid, sig)
        except OSError:
            pass                    # gone meanwhile


def _end_hung_test(out) -> None:
    """The test has run ``HUNG_TEST_S``: every thread's stack to ``out``, the processes it started
    stopped (SIGTERM: a node finalises its recording; SIGKILL for what is left after 3 s), and this
    process ended, status 1."""
    out.write(f"\ntest still running after {HUNG_TEST_S:g} s: its stacks, then its processes ended\n")
    faulthandler.dump_traceback(file=out, all_threads=True)
    _signal_children(signal.SIGTERM)
    deadline = time.monotonic() + 3.0
    while _children() and time.monotonic() < deadline:
        time.sleep(0.1)
    _signal_children(signal.SIGKILL)
    out.flush()
    os._exit(1)


def pytest_sessionstart(session):
    global _uncaptured_stderr
    capman = session.config.pluginmanager.getplugin("capturemanager")
    if capman is not None:
        with capman.global_and_fixture_disabled():
            _uncaptured_stderr = os.fdopen(os.dup(2), "w")


def pytest_sessionfinish(session, exitstatus):
    """Close the hung-test guard's copy of stderr: left open, every run ended with "sys:1:
    ResourceWarning: unclosed file" (each test's guard is cancelled before this)."""
    global _uncaptured_stderr
    if _uncaptured_stderr is not None:
        _uncaptured_stderr.close()
        _uncaptured_stderr = None


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    out = _uncaptured_stderr or sys.stderr
    hung = threading.Timer(HUNG_TEST_S, _end_hung_test, args=(out,))
    hung.daemon = True
    hung.start()
    faulthandler.dump_traceback_later(HUNG_TEST_S + HUNG_EXIT_GRACE_S, exit=True, file=out)
    try:
        yield
    finally:
        hung.cancel()
        faulthandler.cancel_dump_traceback_later()


VENV_BIN = Path(sys.executable).parent

# domain ids 1..101 are valid for Fast DDS on localhost; start from the pid to keep parallel
# pytest runs on one machine apart
_domains = itertools.count(1 + (os.getpid() % 50))
# a test holds a lock on its domain id for as long as it runs, so that two suites on one machine
# (two checkouts, a helper's run beside make test) never share one: walking from the pid alone,
# two suites started close together met on the same ids and saw each other's nodes
_DOMAIN_LOCKS = Path(tempfile.gettempdir()) / "bearing_sim_ros_test_domains"


def _next_domain() -> int:
    return 1 + (next(_domains) - 1) % 100


def _claim_domain():
    """(domain id, open lock file): the next id no other running test holds (flock, released
    when the file is closed, also if the process dies)."""
    _DOMAIN_LOCKS.mkdir(exist_ok=True)
    for _ in range(100):
        domain = _next_domain()
        lock = open(_DOMAIN_LOCKS / f"{domain}.lock", "w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return domain, lock
        except OSError:
            lock.close()
    raise RuntimeError(f"every ROS domain id 1-100 is held by a running test ({_DOMAIN_LOCKS})")


@pytest.fixture
def ros_env(monkeypatch):
    """An environment dict for subprocesses with a fresh ROS_DOMAIN_ID that no other test on
    this machine holds while this one runs; also applied to this process (call ``rclpy.init``
    after requesting the fixture)."""
    domain, lock = _claim_domain()
    # a port file of this domain that a killed process left half made (an earlier test's, or an
    # earlier run's) hung every participant that took it, and with it the suite
    clear_half_made_ports(domain)
    domain = str(domain)
    env = dict(os.environ)
    env.update({
        "ROS_DOMAIN_ID": domain,
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "AMENT_PREFIX_PATH": env.get("AMENT_PREFIX_PATH") or str(VENV_BIN.parent),
        "RMW_IMPLEMENTATION": env.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp"),
        "PYTHONUNBUFFERED": "1",
        # a subprocess that a test aborts (SIGABRT) because it hung prints every thread's stack
        "PYTHONFAULTHANDLER": "1",
    })
    for key in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "AMENT_PREFIX_PATH", "RMW_IMPLEMENTATION"):
        monkeypatch.setenv(key, env[key])
    try:
        yield env
    finally:
        lock.close()


@pytest.fixture
def bearing_sim_exe():
    """Path of the installed ``bearing-sim`` console script."""
    exe = VENV_BIN / "bearing-sim"
    assert exe.exists(), f"{exe} missing: run `make test` (it installs the package)"
    return str(exe)


@pytest.fixture
def cwru_dir():
    """The shared CWRU recordings, or skip with the reason."""
    folder = SHARED / "validation" / "cwru"
    if not folder.is_dir():
        pytest.skip(f"CWRU recordings not found at {folder} (a user checkout has no ../shared)")
    return folder


@pytest.fixture(scope="session")
def outer_run_up(tmp_path_factory):
    """er16k_outer_race run up from 1000 to 3000 rpm over 4 s, kinematic (``render_run_up``):
    rendered once for test_report, test_monitor and test_run."""
    from test_node_support import render_run_up

    return render_run_up(tmp_path_factory.mktemp("run_up"), "er16k_outer_race")


@pytest.fixture(scope="session")
def skidding_outer_race(tmp_path_factory):
    """(scene path, recording path): er16k_outer_race moved to 10000 rpm / 10 N, where its cage
    skids about 7 % (the outer-race line sits 7 % below the catalog's pure-rolling BPFO, 552
    against 595 Hz), rendered once for 2 s on the skidding tier (test_render, test_report)."""
    return _skidding_variant(tmp_path_factory, "er16k_outer_race", [(
        "{shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}", "{shaft_speed_rpm: 10000, radial_load: [0.0, -10.0]}")])


def _skidding_variant(tmp_path_factory, shipped: str, changes: list, seconds: float = 2.0, fidelity: str = "skidding"):
    """(scene path, recording path): the shipped scene ``shipped`` with each (old, new) text of
    ``changes`` replaced, rendered for ``seconds`` on the skidding tier (or ``fidelity``'s)."""
    from bearing_sim_ros.recording.render import render

    text = (REPO / "config" / "scenes" / f"{shipped}.yaml").read_text()
    for old, new in changes:
        assert old in text, f"{shipped}.yaml no longer has {old!r}: update this fixture"
        text = text.replace(old, new)
    folder = tmp_path_factory.mktemp(shipped)
    path = folder / f"{shipped}_variant.yaml"
    path.write_text(text)
    recording = folder / "variant.mcap"
    render(str(path), seconds, recording, fidelity=fidelity, progress=False)
    return path, recording


@pytest.fixture(scope="session")
def skidding_ball_pit(tmp_path_factory):
    """(scene path, recording path): er16k_skidding (2000 rpm / 200 N) with a 0.6 mm ball pit,
    rendered once for 2 s on the skidding tier, whose balls spin 2.2 % slower than pure rolling:
    the pit's 2xBSF line sits at 151.3 Hz, not pure rolling's 154.75 (test_monitor, test_run)."""
    return _skidding_variant(tmp_path_factory, "er16k_skidding", [BALL_PIT])


BALL_PIT = ("defects: []", "defects: [{kind: ball, width_mm: 0.6, depth_mm: 0.25, angle_deg: 0}]")


@pytest.fixture(scope="session")
def skidding_inner_pit_1000rpm(tmp_path_factory):
    """(scene path, recording path): er16k_inner_race at 1000 rpm / 200 N, rendered once for 2 s on
    the skidding tier, whose balls spin about 5 % slow: 2xBSF (74.1 Hz) falls on the inner pit's
    BPFI - 1 x shaft line (74.0 Hz), which stands higher than BPFI (test_report, test_monitor)."""
    return _skidding_variant(tmp_path_factory, "er16k_inner_race", [(
        "{shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}", "{shaft_speed_rpm: 1000, radial_load: [0.0, -200.0]}")])


@pytest.fixture(scope="session")
def skidding_ball_pit_300rpm(tmp_path_factory):
    """(scene path, recording path): er16k_healthy with a 0.6 mm ball pit at 300 rpm / 50 N,
    rendered once for 4 s (8 cage turns) on the skidding tier: the pit's 2xBSF - 1 x FTF line falls
    on BPFO and its 2xBSF + 4 x FTF on BPFI, which stands highest of the three (test_monitor)."""
    return _skidding_variant(tmp_path_factory, "er16k_healthy", [BALL_PIT, (
        "{shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}", "{shaft_speed_rpm: 300, radial_load: [0.0, -50.0]}")],
        seconds=4.0)


@pytest.fixture(scope="session")
def ball_pit_3000rpm(tmp_path_factory):
    """(scene path, recording path): er16k_healthy with a 0.6 mm ball pit at 3000 rpm / 50 N,
    rendered once for 2 s on the kinematic tier: the pit's 2xBSF + 2 x FTF line (271.8 Hz) falls
    on BPFI (271.4 Hz) and stands higher than 2xBSF (test_report, test_monitor)."""
    return _skidding_variant(tmp_path_factory, "er16k_healthy", [BALL_PIT, (
        "{shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}", "{shaft_speed_rpm: 3000, radial_load: [0.0, -50.0]}")],
        fidelity="kinematic")


@pytest.fixture(scope="session")
def skidding_ball_pit_speed_step(tmp_path_factory):
    """(scene path, recording path): as ``skidding_ball_pit``, at 1000 rpm stepping to 2000 rpm at
    1.8-2.2 s, rendered for 4 s: the balls' skid moves from about 4.8 % to 3 %, and the pit's 2xBSF
    line by 2 % in orders of the shaft (test_monitor, test_report)."""
    return _skidding_variant(tmp_path_factory, "er16k_skidding", [BALL_PIT, (
        "{shaft_speed_rpm: 2000, radial_load: [0.0, -200.0]}",
        "{shaft_speed_rpm: 1000, radial_load: [0.0, -200.0]}\nprofile:\n"
        "  - {t: 1.8, shaft_speed_rpm: 1000}\n  - {t: 2.2, shaft_speed_rpm: 2000}")], seconds=4.0)


# A scene within every bound on which the skidding tier's default solver diverges, 10 - 60 ms
# after its pit appears (2026-11-29): er16k_skidding (2000 rpm, 200 N) with the widest and
# deepest outer-race pit the bounds allow on an ER-16K (6.7 of 6.72 mm, 3.9 of 3.97 mm) and seed
# 001's rectangular depth function, whose exit edge is a step of about 1.4 mm that the ball runs
# into.  Should the bounds come to refuse it, the tests of a divergence need another such scene.
DIVERGING_PIT = "{kind: outer, width_mm: 6.7, depth_mm: 3.9, clock: 6, profile: rectangular, onset_s: %r}"


def small_bearing(rpm: float, load_n: float, defects=(), **sensor) -> dict:
    """The 6000-size bearing of README "Limitations" (docs/probes/custom_bearings/probe.py: 7 balls
    of 4.762 mm on 18 mm pitch, 4 um play, with that probe's structure, resonator and lubricant) as
    a user types a scene, at ``rpm`` under ``load_n`` N downwards with ``defects`` (the YAML's
    mappings); ``sensor``: keys over sensor noise off.  A mapping, for ``scene_from_dict`` or a
    YAML file (test_skidding, test_fidelity, test_monitor, test_validate: ``from conftest import
    small_bearing``)."""
    part = lambda m, k, c: {"mass": m, "stiffness": k, "damping": c}  # noqa: E731
    return {"name": "6000-size",
            "bearing": {"name": "6000-size", "balls": 7, "ball_diameter_mm": 4.762, "pitch_diameter_mm": 18.0,
                        "radial_clearance_um": 4.0, "width_mm": 8.0},
            "structure": {"shaft": part(0.3, 2e6, 300), "pedestal": part(0.8, 5e7, 1500),
                          "resonator": {"mass": 0.02, "frequency_hz": 4000, "damping_ratio": 0.04}},
            "operating_point": {"shaft_speed_rpm": rpm, "radial_load": [0.0, -float(load_n)]},
            "lubrication": {"viscosity": 0.04, "pressure_viscosity": 2.0e-8},
            "sensor": {"noise_density": 0.0, **sensor}, "defects": [dict(d) for d in defects]}


@pytest.fixture
def diverging_scene(tmp_path):
    """``diverging_scene(onset_s)``: the path of that scene with its pit appearing at ``onset_s``
    s, in the test's folder (it asks for skid ratios: the skidding tier runs)."""
    text = (REPO / "config" / "scenes" / "er16k_skidding.yaml").read_text()

    def write(onset_s: float = 0.0):
        pitted = text.replace("defects: []", f"defects: [{DIVERGING_PIT % float(onset_s)}]")
        assert pitted != text, "er16k_skidding.yaml's defects line moved: update this fixture"
        path = tmp_path / "diverging.yaml"
        path.write_text(pitted)
        return path

    return write
