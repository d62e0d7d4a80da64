"""A Fast DDS shared-memory port that a killed process left half made does not hang the next start.

A process killed between sizing its port file (``/dev/shm/fastrtps_port<N>``) and marking it made
leaves the file's state word at 0; every later participant that takes that port waits on it for
ever.  The suite met it: a test on domain 69 hung in ``Node()`` on a file an earlier run's killed
process had left (``bearing_sim_ros/stale_dds_ports.py``).
"""
import os
import struct
import subprocess
import threading
import time
from pathlib import Path

import pytest

from bearing_sim_ros.stale_dds_ports import (DOMAIN_GAIN, PORT_BASE, SHM_DIR, clear_half_made_ports,
                                             domain_from_env, removed_text)
from bearing_sim_ros.recording.reader import open_recording

STATE_MADE = struct.pack("<I", 2)


def _port_file(folder: Path, port: int, head: bytes, age_s: float = 60.0, size: int = 52400) -> Path:
    """A port file as Fast DDS leaves it: ``head`` at its start (the state word), zeros after,
    last written ``age_s`` ago."""
    path = folder / f"fastrtps_port{port}"
    path.write_bytes(head + bytes(max(0, size - len(head))) if size else b"")
    then = time.time() - age_s
    os.utime(path, (then, then))
    return path


def test_only_the_domains_unmade_ports_are_removed(tmp_path):
    base = PORT_BASE + DOMAIN_GAIN * 7
    unmade = _port_file(tmp_path, base + 11, bytes(4))                 # sized, never marked
    making = _port_file(tmp_path, base + 13, struct.pack("<I", 1))     # killed while being made
    empty = _port_file(tmp_path, base + 10, b"", size=0)               # killed before it was sized
    made = _port_file(tmp_path, base + 15, STATE_MADE)
    other_domain = _port_file(tmp_path, base + DOMAIN_GAIN + 11, bytes(4))
    below = _port_file(tmp_path, base - 1, bytes(4))                  # the domain before's last port
    lock = tmp_path / f"fastrtps_port{base + 11}_el"
    lock.write_bytes(b"")
    data = tmp_path / "fastrtps_0045901a953f82f9"                    # a participant's data segment
    data.write_bytes(bytes(8))
    assert clear_half_made_ports(7, shm_dir=tmp_path) == sorted([unmade, making, empty])
    assert {p.name for p in tmp_path.iterdir()} == {made.name, other_domain.name, below.name, lock.name, data.name}
    assert clear_half_made_ports(None, shm_dir=tmp_path) == []
    assert clear_half_made_ports(8, shm_dir=tmp_path) == [other_domain]
    assert removed_text([other_domain], 8) == (f"removed {other_domain}: a Fast DDS shared-memory port that a killed "
                                               "process left half made (every participant on ROS domain 8 that "
                                               "took it hung at start)")
    assert removed_text([unmade, making], 7).startswith(f"removed {unmade}, {making}: Fast DDS shared-memory ports "
                                                        "that killed processes left half made")


def test_a_port_being_made_now_is_waited_for_and_kept(tmp_path):
    base = PORT_BASE + DOMAIN_GAIN * 3
    young = _port_file(tmp_path, base + 11, bytes(4), age_s=0.0)
    stuck = _port_file(tmp_path, base + 13, bytes(4), age_s=0.0)

    def make_it():
        time.sleep(0.2)
        with open(young, "r+b") as f:
            f.write(STATE_MADE)

    maker = threading.Thread(target=make_it)
    maker.start()
    t0 = time.monotonic()
    removed = clear_half_made_ports(3, shm_dir=tmp_path, made_within_s=0.6)
    maker.join()
    assert removed == [stuck]                   # its maker never came back
    assert young.exists() and time.monotonic() - t0 >= 0.5


@pytest.mark.parametrize("env, domain", [({}, 0), ({"ROS_DOMAIN_ID": "42"}, 42), ({"ROS_DOMAIN_ID": " "}, 0),
                                         ({"ROS_DOMAIN_ID": "x"}, None),
                                         ({"ROS_DOMAIN_ID": "5", "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"}, 5),
                                         ({"ROS_DOMAIN_ID": "5", "RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}, None)])
def test_the_domain_comes_from_the_environment_and_only_for_fast_dds(env, domain):
    assert domain_from_env(env) == domain


@pytest.mark.skipif(not SHM_DIR.is_dir(), reason="no /dev/shm")
def test_a_node_after_a_killed_one_starts_and_says_what_it_removed(ros_env, bearing_sim_exe, tmp_path):
    """Half-made ports on every port of the first five participants of the test's domain: the
    node hung at start for ever (in ``rmw_create_node``, boost.interprocess spinning); now it
    removes them, says so in one line, and records its second of signal."""
    domain = int(ros_env["ROS_DOMAIN_ID"])
    base = PORT_BASE + DOMAIN_GAIN * domain
    planted = [_port_file(SHM_DIR, base + 10 + k, bytes(4)) for k in range(10)]
    node = subprocess.Popen([bearing_sim_exe, "node", "--ros-args", "-p", "real_time:=false", "-p", "duration:=1.0",
                             "-p", "record:=live.mcap"], cwd=tmp_path, env=ros_env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        out, err = node.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        node.kill()
        out, err = node.communicate()
        pytest.fail(f"the node hung at start on the half-made ports: {err[-2000:]}")
    finally:
        for path in planted:
            if path.exists() and path.read_bytes()[:4] == bytes(4):
                path.unlink()
    assert node.returncode == 0, err
    said = [ln for ln in err.splitlines() if "half made" in ln]
    assert len(said) == 1 and f"ROS domain {domain}" in said[0], err
    assert all(str(path) in said[0] for path in planted), said
    with open_recording([tmp_path / "live.mcap"]) as rec:
        counts = {t: c.count for t, c in rec.topics().items()}
    assert counts["/accel"] == 100


DOMAIN_CASES = [("node", "300", ("--ros-args", "-p", "duration:=0.2")), ("run", "300", ("--out", "x.mcap")),
                ("monitor", "300", ("--count", "1")), ("play", "300", ("rec.mcap", "--wait", "0")),
                ("node", "abc", ("--ros-args", "-p", "duration:=0.2")),
                ("node", "-1", ("--ros-args", "-p", "duration:=0.2"))]


@pytest.mark.parametrize("command,value,args", DOMAIN_CASES, ids=[f"{c} {v}" for c, v, _ in DOMAIN_CASES])
def test_a_ros_domain_id_no_participant_can_take_is_one_line(ros_env, bearing_sim_exe, tmp_path, command, value, args):
    """Every command that starts a participant refuses a ``ROS_DOMAIN_ID`` that is not a whole
    number 0 - 232 in one line, exit status 2, before it starts: 300 failed in Fast DDS with exit
    status 1 (an internal error), 'abc' was called a ROS argument rcl could not parse, -1 ran on
    domain 0."""
    if command == "play":
        from bearing_sim_ros.recording.render import render

        render("er16k_outer_race", 0.05, tmp_path / "rec.mcap", progress=False)
    env = dict(ros_env, ROS_DOMAIN_ID=value)
    r = subprocess.run([bearing_sim_exe, command, *args], env=env, cwd=tmp_path, capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2, r.stdout + r.stderr
    assert r.stderr.splitlines() == [f"error: ROS_DOMAIN_ID = '{value}': expected a whole number 0 - 232 (0 - 101 "
                                     "keeps clear of Linux's ephemeral ports), the same in every terminal of one setup"], r.stderr
    assert not (tmp_path / "x.mcap").exists()
