"""``bearing-sim monitor`` end to end: the node and the monitor as two processes over DDS.

Healthy reference: ``cwru_6205_normal``, not ``er16k_healthy``.  With the current physics the
healthy ER-16K shows a strong ball-pass line (BPFO, prominence ~200) from the varying compliance
of 9 balls under a 50 N load on a bearing with clearance; the shared envelope detector cannot tell
it from the outer-race defect (it looks at the height of the BPFO line only), so calling it
healthy would be a test of the wrong thing.  The CWRU 6205 scene carries its load with many balls
(100 N, tighter structure) and its ball-pass modulation stays below the detector's floor.
"""
from __future__ import annotations

import re
import subprocess
import time

import numpy as np
import pytest

from test_node_support import NS, NodeProcess

from bearing_sim_ros.nodes.monitor_node import Window
from bearing_sim_ros.recording.render import render


def test_window_gathers_contiguous_tables_and_restarts_on_a_gap():
    w = Window()
    step = 10_000_000
    t = 5 * NS
    assert w.add(t, ["a"], np.zeros((150, 1), np.float32))
    assert w.add(t + step, ["a"], np.ones((150, 1), np.float32))
    assert w.sample_rate == pytest.approx(15000.0)
    assert w.add(t + 2 * step, ["a"], np.ones((150, 1), np.float32))
    assert w.seconds() == pytest.approx(0.03)
    assert not w.add(t + 4 * step, ["a"], np.ones((150, 1), np.float32))      # one table lost
    assert w.gaps == 1 and w.samples == 150 and w.sample_rate is None
    assert w.add(t + 5 * step, ["a"], np.ones((150, 1), np.float32))
    assert not w.add(t + 6 * step, ["b"], np.ones((150, 1), np.float32))      # other channels
    assert w.take().shape == (150, 1) and w.samples == 0


def _other_domain(env):
    d = int(env["ROS_DOMAIN_ID"])
    return dict(env, ROS_DOMAIN_ID=str(1 + (d + 49) % 100))


def test_monitor_detects_outer_race_and_calls_healthy_healthy(ros_env, bearing_sim_exe, tmp_path):
    """Two node + monitor pairs at once, each pair on its own domain: the outer-race ER-16K gives
    verdict=outer with the BPFO line at theory; the healthy CWRU 6205 gives verdict=healthy."""
    env_h = _other_domain(ros_env)
    procs = []
    try:
        for env, scene in ((ros_env, "er16k_outer_race"), (env_h, "cwru_6205_normal")):
            procs.append(NodeProcess(bearing_sim_exe, env, {"scene": scene}, tmp_path / f"node_{scene}.log"))
            procs.append(NodeProcess(bearing_sim_exe, env, None, tmp_path / f"monitor_{scene}.log",
                                     command=("monitor", "--window", "3", "--count", "1", "--scene", scene)))
        monitors = procs[1], procs[3]
        for m in monitors:
            assert m.wait(60) == 0, m.output()
        out_fault, out_healthy = (m.output() for m in monitors)
    finally:
        for p in procs:
            p.close()
    v = [ln for ln in out_fault.splitlines() if "verdict=" in ln]
    assert len(v) == 1, out_fault
    assert "verdict=outer" in v[0]
    found, theory, prominence = re.search(r"bpfo ([\d.]+)/([\d.]+)Hz x([\d.]+)", v[0]).groups()
    assert float(found) == pytest.approx(float(theory), rel=0.005)
    assert float(theory) == pytest.approx(95.25, rel=0.001)        # ER-16K at 1600 rpm
    assert float(prominence) > 20
    h = [ln for ln in out_healthy.splitlines() if "verdict=" in ln]
    assert len(h) == 1 and "verdict=healthy" in h[0], out_healthy
    assert "shaft=1797rpm" in h[0]


def _play_into(monitor, bearing_sim_exe, recording, env, *options) -> str:
    """``bearing-sim play`` the recording (it waits for the monitor's subscriptions: discovery
    can take a 3 s period or more), wait for the monitor to finish; its output."""
    play = subprocess.run([bearing_sim_exe, "play", str(recording), *options, "--wait", "15"],
                          env=env, capture_output=True, text=True, timeout=60)
    assert play.returncode == 0, play.stderr
    assert monitor.wait(30) == 0, monitor.output()
    return monitor.output()


def test_monitor_loses_no_table_of_a_recording_played_at_4x(ros_env, bearing_sim_exe, tmp_path):
    """A recording played at 4x: 400 tables/s against the subscription's depth of 100 (0.25 s).
    The first analysis imports scipy (~1 s); on the executor thread it let the depth overflow
    (at 2x too: about 1 run in 2) and the monitor lost tables and restarted its window."""
    recording = tmp_path / "four_seconds.mcap"
    render("er16k_outer_race", 4.0, recording, fidelity="kinematic", seed=3, progress=False)
    monitor = NodeProcess(bearing_sim_exe, ros_env, None, tmp_path / "monitor.log",
                          command=("monitor", "--window", "1", "--count", "3"))
    try:
        out = _play_into(monitor, bearing_sim_exe, recording, ros_env, "--rate", "4")
    finally:
        monitor.close()
    verdicts = [ln for ln in out.splitlines() if "verdict=" in ln]
    assert len(verdicts) == 3 and all("verdict=outer" in v for v in verdicts), out
    assert "not contiguous" not in out, out
    assert "monitor: 3 verdicts from 300 tables, 0 gaps" in out, out      # 3 windows of 1 s, whole


def test_monitor_rejects_a_bad_table_and_keeps_going(ros_env, bearing_sim_exe, tmp_path):
    """Tables that are no waveform table (wrong point step) or hold a NaN, from another
    publisher, are skipped, logged and counted; the recording played after them still gives its
    verdict."""
    import rclpy
    from sensor_msgs.msg import PointCloud2

    from bearing_sim_ros.messages import TOPIC_ACCEL, waveform_qos
    from bearing_sim_ros.waveform import to_pointcloud2

    recording = tmp_path / "two_seconds.mcap"
    render("er16k_outer_race", 2.0, recording, fidelity="kinematic", seed=3, progress=False)
    monitor = NodeProcess(bearing_sim_exe, ros_env, None, tmp_path / "monitor.log",
                          command=("monitor", "--window", "1", "--count", "1"))
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node("bad_tables", context=context)
        pub = node.create_publisher(PointCloud2, TOPIC_ACCEL, waveform_qos(0.01))
        deadline = time.monotonic() + 30
        while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert pub.get_subscription_count() > 0, monitor.output()
        channels = ["accel_x", "accel_y"]
        wrong_step = to_pointcloud2(np.zeros((150, 2)), channels, 0, "bearing_accel")
        wrong_step.point_step = 12
        nan = to_pointcloud2(np.full((150, 2), np.nan), channels, 0, "bearing_accel")
        for msg in (wrong_step, nan, wrong_step):
            pub.publish(msg)
        time.sleep(1.0)                     # reliable: delivered before the recording's tables
        out = _play_into(monitor, bearing_sim_exe, recording, ros_env)
    finally:
        monitor.close()
        rclpy.try_shutdown(context=context)
    assert "accel table rejected (not a waveform table" in out, out
    verdicts = [ln for ln in out.splitlines() if "verdict=" in ln]
    assert len(verdicts) == 1 and "verdict=outer" in verdicts[0], out
    assert ", 3 rejected" in out, out
