"""Topic names, types, QoS, and the messages of one batch: shared by the live node and the
offline renderer so that a recording from either is the same, message for message.

No per-sample Python objects: waveform tables are built from arrays (see ``waveform.py``).
"""
from __future__ import annotations

import math
import time

import numpy as np

from .waveform import make_fields, sample_time_ns, to_pointcloud2

# topic -> ROS type (names relative to the node's namespace, INTERFACE.md)
TOPIC_ACCEL = "accel"
TOPIC_CONTACT = "contact_forces"
TOPIC_STATE = "state"
TOPIC_DIAGNOSTICS = "/diagnostics"
TOPIC_CLOCK = "/clock"
TOPIC_SHAFT_SPEED = "shaft_speed"
TOPIC_LOAD = "load"

TYPES = {
    TOPIC_ACCEL: "sensor_msgs/msg/PointCloud2",
    TOPIC_CONTACT: "sensor_msgs/msg/PointCloud2",
    TOPIC_STATE: "sensor_msgs/msg/JointState",
    TOPIC_DIAGNOSTICS: "diagnostic_msgs/msg/DiagnosticArray",
    TOPIC_CLOCK: "rosgraph_msgs/msg/Clock",
    TOPIC_SHAFT_SPEED: "std_msgs/msg/Float64",
    TOPIC_LOAD: "geometry_msgs/msg/WrenchStamped",
}


# the node's ``batch_duration`` (s) and ``state_rate`` (Hz; 0 = no state) parameters and render()'s
# arguments of the same names: defaults, ranges and how they go together (``batching_error``), in
# one place, so that a render's batching also runs live
BATCH_DURATION, BATCH_DURATION_RANGE = 0.01, (0.001, 1.0)
STATE_RATE, STATE_RATE_RANGE = 50.0, (0.0, 1000.0)
# s without a new match once a subscriber matched: its topics match one by one, and what goes out
# before they all have is lost to it (volatile).  `play` and the node's wait_for_subscribers wait so
DISCOVERY_GRACE_S = 0.5


# /diagnostics: the run's state in every message of the simulator's status, ``running``, and in the
# last one ``ended``, with why (``END_REASONS``) and the samples of signal published, so that a
# consumer can tell a run that is complete from a simulator that crashed or stalled and from a
# discovery loss (the publishers just went away before).  The node and ``render`` alike
RUN_KEY, RUN_RUNNING, RUN_ENDED = "run", "running", "ended"
END_REASON_KEY, PUBLISHED_SAMPLES_KEY = "end_reason", "published_samples"
# why a run ended: its duration reached, or a signal (Ctrl-C, SIGTERM, SIGHUP of the node or a
# render), or the node's stop() called by a program that runs it in its own process, or
# the skidding solver's divergence (level ERROR, its line in the message)
END_REASONS = ("duration", "SIGINT", "SIGTERM", "SIGHUP", "stopped", "diverged")
# s the node and `play` give reliable subscribers at their end to acknowledge their last messages
# (the end status, the last tables), in all (``deliver_the_end``); short because Fast DDS often
# acknowledges only with its periodic heartbeat, 3 s after the last write, though the subscriber
# has them within ms, and every exit with subscribers waits it out.  `play` waited up to 2 s per
# topic: about 3 s at the end of every play of a 1 s recording whose subscriber in another
# process had every message 2 ms after the last was published, 12 s with a stalled subscriber
# (6 topics); a subscriber stopped (SIGSTOP) for 1 s across the end of a play that did not wait
# at all still got every message
END_DELIVERY_GRACE_S = 0.5


def deliver_the_end(publishers, grace_s: float, going_on) -> list:
    """Give reliable subscribers up to ``grace_s`` (s) in all to acknowledge what ``publishers``
    published last, before they are destroyed, which takes away what is still on its way; the
    topics not acknowledged in time (no sign of a lost message: Fast DDS learns of a receipt from
    a reader's answer to a heartbeat, often the periodic one).  ``publishers`` the frequent topics
    first: their heartbeats come with their messages, so they take little of the grace.  Stops
    once ``going_on()`` is false (the context shut down, a stop asked for)."""
    from rclpy.duration import Duration

    deadline = time.monotonic() + grace_s
    late = []
    for pub in publishers:
        if not going_on():
            break
        try:
            if not pub.wait_for_all_acked(Duration(seconds=max(0.0, deadline - time.monotonic()))):
                late.append(pub.topic_name)
        except Exception:  # noqa: BLE001 - the context went away while it waited
            if going_on():
                raise
            break
    return late


def end_of_run(values: dict, level: int, message: str, reason: str, samples: int, sample_rate: float,
               duration: float) -> tuple:
    """The last ``/diagnostics`` of a run from the status (``values``, ``level``, ``message``) its
    last batch would have had: ``(values, level, message)`` with ``run: ended``, ``end_reason``
    (one of ``END_REASONS``) and ``published_samples`` (``samples`` at ``sample_rate``, Hz), and a
    message that says so before what the status said otherwise (a warning, an error: its level
    stays).  ``duration``: the run's duration (s, 0 = no end), named where it was reached."""
    seconds = f"{samples / sample_rate:.6f} s of signal ({samples} samples) published"
    if reason == "duration":
        text = f"run ended: duration {duration:g} s reached, {seconds}"
    elif reason == "stopped":
        text = f"run ended: stopped by the program that runs the node, {seconds}"
    elif reason == "diverged":
        text = f"run ended: the solver diverged, {seconds}"
    else:
        text = f"run ended by {reason}: {seconds}"
    values = dict(values, **{RUN_KEY: RUN_ENDED, END_REASON_KEY: reason, PUBLISHED_SAMPLES_KEY: samples})
    return values, level, text if message == "ok" else f"{text}; {message}"


def batching_error(sample_rate: float, batch_duration, state_rate) -> str | None:
    """None if ``batch_duration`` (s) and ``state_rate`` (Hz) are usable at ``sample_rate`` (Hz, a
    valid one), else a one-line reason naming the argument, its value and what is allowed: each
    within its range, a batch a whole number (>= 1) of samples, at most one state per batch."""
    import numbers

    for name, value, (lo, hi), unit in (("batch_duration", batch_duration, BATCH_DURATION_RANGE, "s"),
                                        ("state_rate", state_rate, STATE_RATE_RANGE, "Hz")):
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not lo <= value <= hi:
            return f"{name} = {value!r}: allowed range is [{lo:g}, {hi:g}] {unit}"
    samples = sample_rate * batch_duration
    if abs(samples - round(samples)) > 1e-6 * max(samples, 1.0) or round(samples) < 1:
        return (f"batch_duration = {batch_duration!r} s with sample_rate = {sample_rate!r} Hz "
                f"gives {samples:.6g} samples: must be a whole number >= 1")
    if state_rate > 1.0 / batch_duration * (1 + 1e-9):
        return (f"state_rate = {state_rate!r} Hz: at most one state per batch, "
                f"<= 1 / batch_duration = {1.0 / batch_duration:g} Hz")
    return None


def duration_error(name: str, duration: float, sample_rate: float, no_end: bool = False) -> str | None:
    """None if ``duration`` (s) holds at least one sample at ``sample_rate`` (Hz), else a one-line
    reason naming ``name`` (``--duration``, the node's ``duration``).  ``no_end``: 0 means no end
    (the node's), and is allowed; a positive duration under half a sample rounded to 0 samples,
    which the node took for that: ``-p duration:=0.00001`` ran until Ctrl-C."""
    if no_end and duration == 0:
        return None
    if round(duration * sample_rate) >= 1:
        return None
    least = f"at least {1.0 / sample_rate:.6g} s"
    return (f"{name} = {duration!r} s: shorter than one sample at {sample_rate:g} Hz; expected "
            + (f"0 (no end) or {least}" if no_end else least))


def batch_qos_depth(batch_duration: float, seconds: float = 1.0) -> int:
    """Keep-last depth holding about ``seconds`` (s) of batches of ``batch_duration`` (s), and
    at least 10."""
    return max(10, int(math.ceil(seconds / batch_duration)))


def waveform_qos(batch_duration: float, seconds: float = 1.0):
    """Reliable, volatile, keep-last about ``seconds`` (s) of batches of ``batch_duration`` (s)."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=batch_qos_depth(batch_duration, seconds),
                      reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)


class BatchMessages:
    """Builds the ``accel`` and ``contact_forces`` waveform tables and the ``state`` message of
    a batch.  ``start_ns``: the ROS time of simulation sample 0 (wall clock at start for the
    live node, 0 or a chosen epoch for offline renders)."""

    def __init__(self, simulator, start_ns: int, frame_id: str | None = None):
        self.sim = simulator
        self.start_ns = int(start_ns)
        self.frame_id = frame_id or simulator.scene.sensor.frame_id
        self._accel_fields = make_fields(simulator.accel_channels)
        self._contact_fields = make_fields(simulator.contact_channels)
        nb = simulator.bearing.balls
        self.joint_names = ["shaft", "cage"] + [f"ball_{j:02d}" for j in range(nb)]

    def stamp_ns(self, index: int) -> int:
        """ROS time (ns) of output sample ``index``."""
        return sample_time_ns(self.start_ns, index, self.sim.sample_rate)

    def accel(self, batch):
        return to_pointcloud2(batch.accel, batch.accel_channels, self.stamp_ns(batch.index0),
                              self.frame_id, self._accel_fields)

    def contact_forces(self, batch):
        return to_pointcloud2(batch.contact_forces, batch.contact_channels,
                              self.stamp_ns(batch.index0), self.frame_id, self._contact_fields)

    def state(self, stamp_ns: int):
        """JointState of shaft, cage and balls: angle (rad) and speed (rad/s) now."""
        from sensor_msgs.msg import JointState

        snap = self.sim.snapshot()
        msg = JointState()
        msg.header.stamp.sec = int(stamp_ns // 1_000_000_000)
        msg.header.stamp.nanosec = int(stamp_ns % 1_000_000_000)
        msg.header.frame_id = self.frame_id
        msg.name = self.joint_names
        msg.position = np.concatenate([[snap.shaft_angle, snap.cage_angle], snap.ball_angles]).tolist()
        msg.velocity = np.concatenate([[snap.shaft_speed, snap.cage_speed], snap.ball_speeds]).tolist()
        return msg
