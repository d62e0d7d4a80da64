"""The live ROS 2 node ``bearing_sim``: a virtual bearing accelerometer (INTERFACE.md).

    bearing-sim node --ros-args -p scene:=er16k_outer_race -p record:=run.mcap
    ros2 run bearing_sim_ros bearing_sim_node --ros-args -p real_time:=false -p duration:=60.0

One small :class:`Node` over :class:`~bearing_sim_ros.Simulator`.  A dedicated simulation thread
advances the model in chunks of ``batch_duration``, up to ``compute_ahead`` (50 ms) before they
are due, and publishes each chunk when the moment of its last sample has come on the steady
clock (``time.monotonic``).  The lead absorbs scheduling hiccups of a shared machine.  When a
chunk is not computed in time (an *overrun*) it is published at once and the following chunks
are computed without waiting until the node is ahead again: the node catches up, it never
drifts, and it never drops samples (the waveform tables stay contiguous).  With
``real_time:=false`` it runs as fast as the model allows.  Stamps come from the absolute sample
index (``messages.BatchMessages``), so consecutive tables are contiguous to the nanosecond
whatever the pacing did.

Inputs ``shaft_speed`` (std_msgs/Float64, rad/s) and ``load`` (geometry_msgs/WrenchStamped, N;
x horizontal, y up, z axial) are checked in the subscription callback (see :class:`InputLimits`
and :func:`check_speed`, :func:`check_load`, :func:`check_frame`); a bad message is rejected, logged (throttled) and
counted in ``/diagnostics``, and the last good value stays.  An accepted value becomes the target
of the next chunk computed: ``Simulator.advance`` ramps speed and load linearly from the value in
use to the target over that chunk (10 ms by default), so the signal never jumps.  In the
published stream that chunk starts up to ``compute_ahead`` after the command arrived.

The executor (main thread) serves the subscriptions and parameter services only; publishing,
recording and diagnostics happen in the simulation thread, which owns the simulator.
"""
from __future__ import annotations

import math
import os
import shlex
import sys
import threading
import time
from collections import deque
from pathlib import Path

import rclpy
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node

from ..errors import NODE_SETTINGS, SettingNames, UserError
from ..limits import LOAD_MULTIPLE_C0, NDM_LIMIT, STATIC_F0, InputLimits, bound_text, load_on_balls  # noqa: F401 (names kept here)
from ..teardown import EXIT_INTERRUPTED, SIGNAL_NAMES, command_signals, say_on_stderr, teardown_watchdog
from ..stale_dds_ports import clear_before_start

NODE_NAME = "bearing_sim"
OVERSAMPLE_ZERO = "each tier's own"       # what the parameter oversample's default 0 means
DEFAULT_SCENE = "er16k_outer_race"
DEFAULT_SAMPLE_RATE = 15000.0         # Hz: the parameter sample_rate's default
FIDELITIES = ("auto", "kinematic", "skidding")

# ---- input limits --------------------------------------------------------------------------
# The bearing's limits (n d_m, 2 x C0) live in ..limits, ROS-free: the scene loader applies them too.
CLOCK_SKEW_ALLOWED = 1.0       # s: a load stamp further in the future than this is rejected
REJECT_LOG_PERIOD = 2.0        # s: at most one log line per rejection reason this often
INPUT_DEPTH = 1000             # keep-last depth of shaft_speed and load: a burst a publisher sends
                               # back to back waits for the executor, each message checked and counted
                               # (at 10, 27-31 of 500 NaNs sent at once were counted)
TIME_LINE_JUMP = 1.0           # s: a load stamp further back than this behind the last accepted one
                               # starts a new time line (a recording played again, a publisher
                               # restarted with other stamps); closer, it is out of order
WAIT_FOR_SUBSCRIBERS_MAX = 1000    # the parameter's range: 0 - this many subscribers
PEER_CHECK_S = 2.0             # s between looks at the graph (another publisher on accel, inputs of another type)
# rmw_dds_common's node name for an endpoint whose participant has not (yet) said which node holds
# it: a publisher is discovered before its participant's node list, now and then by a look
UNKNOWN_NODE_NAME = "_NODE_NAME_UNKNOWN_"
SWITCH_COST_GUESS_S = 0.02     # s: a tier switch's batch before the first is measured (8 ms for
                               # kinematic -> skidding on the AMD host; more on a loaded machine)
# A node that cannot keep up with real time falls further behind for ever (each batch an overrun,
# published at once, and the next one later still).  It says so where its real-time factor was
# below 1 in each of the last FALLING_BEHIND_PERIODS one-second periods and it is at least
# FALLING_BEHIND_MIN_S behind, further than at their start: a short stall (a GC pause, a busy
# machine for a moment) is followed by seconds above 1, in which it catches up.
FALLING_BEHIND_PERIODS = 5
FALLING_BEHIND_MIN_S = 0.5     # s behind the schedule: not a stall of a few batches
FALLING_BEHIND_LOG_S = 60.0    # s between the log's warnings while it goes on falling behind


def strangers_to_name(said: dict, publishers) -> tuple[dict, list[tuple[str, str]], bool]:
    """One look at the publishers of another type on an input topic: which to name in the log.

    ``publishers``: ``(endpoint_gid, node, topic_type)`` of each, ``node`` the node's full name or
    None where the graph does not know it yet.  ``said``: what the last look returned, endpoint
    gid -> True where named in the log, False where seen once without a node name.  Each
    publisher is named once, keyed by its endpoint (not by its name, which may arrive a look
    later: a node named both ``_NODE_NAME_UNKNOWN_`` and ``/wrong_types``); one seen without a
    name is held for one look, then named as unknown (a DDS participant that is no ROS node never
    gets a name).

    Returns the new ``said``, the ``(node text, topic type)`` pairs to log now, and whether none
    of the publishers named before is left."""
    now, to_name = {}, []
    for gid, node, kind in sorted(publishers, key=lambda p: (p[1] or "", p[2], p[0])):
        if said.get(gid):
            now[gid] = True
        elif node is not None or gid in said:
            now[gid] = True
            to_name.append((node or "a node the ROS graph has no name for", kind))
        else:
            now[gid] = False
    gone = any(said.values()) and not any(now.values())
    return now, to_name, gone


def check_speed(value: float, limits: InputLimits):
    """None if ``value`` (rad/s) is usable, else ``(reason_key, one-line reason)``."""
    if not math.isfinite(value):
        return "not_finite", f"shaft_speed = {value!r} rad/s: not a finite number"
    if abs(value) > limits.max_speed:
        return "out_of_range", (f"shaft_speed = {value:.6g} rad/s: beyond what the bearing takes "
                                f"(|speed| <= {bound_text(limits.max_speed)} rad/s, n*dm <= {NDM_LIMIT:.0e} rpm mm)")
    return None


def check_load(fx: float, fy: float, fz: float, limits: InputLimits):
    """None if the force (N) is usable, else ``(reason_key, one-line reason)``.  ``fz`` (axial)
    is not modelled but must be sane too; the magnitude of the whole force is limited."""
    if not (math.isfinite(fx) and math.isfinite(fy) and math.isfinite(fz)):
        return "not_finite", f"load = ({fx:.6g}, {fy:.6g}, {fz:.6g}) N: not finite"
    mag = math.sqrt(fx * fx + fy * fy + fz * fz)
    if mag > limits.max_load:
        return "out_of_range", (f"load = ({fx:.6g}, {fy:.6g}, {fz:.6g}) N: |F| = {mag:.6g} N beyond "
                                f"{LOAD_MULTIPLE_C0:g} x C0 = {bound_text(limits.max_load)} N")
    # the balls carry the shaft's weight too: a load within the bound alone may not be with it
    total = load_on_balls(fx, fy, limits.shaft_weight, fz)
    if total > limits.max_load:
        return "out_of_range", (f"load = ({fx:.6g}, {fy:.6g}, {fz:.6g}) N with the shaft's weight "
                                f"{limits.shaft_weight:.6g} N downwards: |F| on the balls = {total:.6g} N beyond "
                                f"{LOAD_MULTIPLE_C0:g} x C0 = {bound_text(limits.max_load)} N")
    return None


def check_frame(frame_id: str, own_frame: str):
    """None if a load's ``frame_id`` is the node's own frame (its tables', which its recordings
    give their loads) or empty (not said), else ``(reason_key, reason)``: the node transforms
    nothing, so a force given in another frame ("base_link", "map") would be applied along the
    bearing's axes as if it were in theirs.  A leading ``/`` is ignored, as tf2 ignores it."""
    if frame_id.lstrip("/") in ("", own_frame.lstrip("/")):
        return None
    return "wrong_frame", (f"load frame_id = {frame_id!r}: expected {own_frame!r} or empty (x horizontal, y "
                           "vertical up, at the bearing; the node transforms nothing)")


def check_stamp(stamp_ns: int, last_ns: int | None, now_ns: int, max_age: float):
    """None if a load stamp (ns) is acceptable, else ``(reason_key, reason)``.  A zero stamp is
    an unstamped message (accepted).  ``max_age`` 0 disables the age checks (for recordings
    played back with their original stamps).  A stamp older than the last accepted one is out of
    order only within ``TIME_LINE_JUMP``: further back it starts a new time line (``play --loop``
    begins its recording again), which the age checks judge; else one stray stamp far ahead, with
    the age checks off, would lock every later load out."""
    if stamp_ns == 0:
        return None
    if last_ns is not None and last_ns - TIME_LINE_JUMP * 1e9 <= stamp_ns < last_ns:
        return "out_of_order", f"load stamp {stamp_ns * 1e-9:.6f} s is older than the last accepted one ({last_ns * 1e-9:.6f} s)"
    if max_age > 0.0:
        age = (now_ns - stamp_ns) * 1e-9
        if age > max_age:
            return "stale", f"load stamp is {age:.3g} s old (input_max_age = {max_age:g} s)"
        if -age > max(CLOCK_SKEW_ALLOWED, max_age):
            return "stale", f"load stamp is {-age:.3g} s in the future (clocks out of step?)"
    return None


# ---- parameters --------------------------------------------------------------------------------
def _descriptors():
    """name -> (default, ParameterDescriptor).  Read-only: what the simulator or the recording is
    built from at start-up; the rest may change while the node runs."""
    from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
    from rcl_interfaces.msg import ParameterType as T

    from ..physics.kinematic import DEFAULT_OVERSAMPLE as KINEMATIC_OVERSAMPLE
    from ..physics.kinematic import SOFT_MODE_FRACTION
    from ..physics.skidding import DEFAULT_OVERSAMPLE as SKIDDING_OVERSAMPLE
    from ..messages import BATCH_DURATION, BATCH_DURATION_RANGE, DISCOVERY_GRACE_S, STATE_RATE, STATE_RATE_RANGE
    from ..recording.recorder import SPLIT_MAX_BYTES, SPLIT_MIN_BYTES
    from ..simulator import AUTO_OVERSAMPLE_MAX, DURATION_MAX_S, OVERSAMPLE_ALLOWED, SAMPLE_RATE_RANGE, SEED_RANGE

    def d(kind, text, read_only=False, lo=None, hi=None, constraints=""):
        desc = ParameterDescriptor(type=kind, description=text, read_only=read_only,
                                   additional_constraints=constraints)
        if kind == T.PARAMETER_DOUBLE and lo is not None:
            desc.floating_point_range = [FloatingPointRange(from_value=float(lo), to_value=float(hi), step=0.0)]
        if kind == T.PARAMETER_INTEGER and lo is not None:
            desc.integer_range = [IntegerRange(from_value=int(lo), to_value=int(hi), step=1)]
        return desc

    return {
        "scene": (DEFAULT_SCENE, d(T.PARAMETER_STRING, "shipped scene name or path of a scene YAML", True,
                                   constraints="see `bearing-sim scenes`")),
        "sample_rate": (DEFAULT_SAMPLE_RATE, d(T.PARAMETER_DOUBLE, "output sample rate, Hz", True, *SAMPLE_RATE_RANGE)),
        "batch_duration": (BATCH_DURATION, d(T.PARAMETER_DOUBLE, "samples per waveform table, s", True,
                                             *BATCH_DURATION_RANGE,
                                   "batch_duration x sample_rate must be a whole number of samples")),
        "real_time": (True, d(T.PARAMETER_BOOL, "pace on the steady clock; false = as fast as possible")),
        "duration": (0.0, d(T.PARAMETER_DOUBLE, "seconds of signal, then exit; 0 = forever", False, 0.0, DURATION_MAX_S)),
        "record": ("", d(T.PARAMETER_STRING, "MCAP file to record to; empty = no recording", True)),
        "record_max_duration": (0.0, d(T.PARAMETER_DOUBLE, "split the recording: seconds of it per file "
                                       "(record:=run.mcap writes run_000.mcap, run_001.mcap, ..., each "
                                       "complete); 0 = one file", True, 0.0, DURATION_MAX_S,
                                       "0, or at least batch_duration")),
        "record_max_size": (0, d(T.PARAMETER_INTEGER, "split the recording: bytes on disk per file "
                                 "(run_000.mcap, run_001.mcap, ..., each complete); 0 = one file", True,
                                 0, SPLIT_MAX_BYTES, f"0, or at least {SPLIT_MIN_BYTES}")),
        "fidelity": ("auto", d(T.PARAMETER_STRING, "model tier", True, constraints="auto | kinematic | skidding")),
        "seed": (0, d(T.PARAMETER_INTEGER, "seed of random slip and sensor noise", True, *SEED_RANGE)),
        "oversample": (0, d(T.PARAMETER_INTEGER, "integration steps per output sample, or per physics "
                            "sample below a 15 kHz sample_rate, where the physics runs at the smallest "
                            "whole multiple of sample_rate that reaches 15 kHz (speed against "
                            f"accuracy); 0 = {OVERSAMPLE_ZERO}: kinematic 1 while its bearing mode "
                            f"is below {SOFT_MODE_FRACTION:g} x that rate, else {KINEMATIC_OVERSAMPLE}; "
                            f"skidding {SKIDDING_OVERSAMPLE}", True, 0, 64,
                            f"0, {OVERSAMPLE_ALLOWED}; at most {AUTO_OVERSAMPLE_MAX} where the tier is "
                            f"chosen automatically")),
        "publish_clock": (False, d(T.PARAMETER_BOOL, "publish /clock with the simulation time")),
        "frame_id": ("", d(T.PARAMETER_STRING, "frame of the waveform tables; empty = the scene's sensor frame", True)),
        "state_rate": (STATE_RATE, d(T.PARAMETER_DOUBLE, "JointState rate, Hz; 0 = off; not given, one per "
                                     "batch where batches are longer than 20 ms", False, *STATE_RATE_RANGE,
                                     "at most one per batch: state_rate <= 1 / batch_duration")),
        "compute_ahead": (0.05, d(T.PARAMETER_DOUBLE, "compute batches up to this long before they are "
                                  "due, s: absorbs scheduling hiccups; a command takes effect this much "
                                  "later in the published signal", False, 0.0, 2.0)),
        "input_max_age": (1.0, d(T.PARAMETER_DOUBLE, "reject load messages whose stamp is older than "
                                 "this, s; 0 = accept any age", False, 0.0, 3600.0)),
        "wait_for_subscribers": (0, d(T.PARAMETER_INTEGER, "hold the first batch until this many "
                                      f"subscriptions match accel, then {DISCOVERY_GRACE_S:g} s without a new "
                                      "match (their other topics), so that none misses the start; 0 = "
                                      "start at once", True, 0, WAIT_FOR_SUBSCRIBERS_MAX)),
    }


def check_config(cfg: dict):
    """None if the parameter set ``cfg`` (name -> value) is usable together, else a one-line reason."""
    if cfg["fidelity"] not in FIDELITIES:
        return f"fidelity = {cfg['fidelity']!r}: allowed values are {', '.join(FIDELITIES)}"
    from ..messages import batching_error, duration_error
    from ..recording.recorder import split_error
    from ..simulator import OVERSAMPLE_ALLOWED, oversample_allowed

    if cfg["oversample"] != 0 and not oversample_allowed(cfg["oversample"]):
        # said here, not by the Simulator, which does not take 0
        return f"oversample = {cfg['oversample']!r}: allowed values are 0 ({OVERSAMPLE_ZERO}), {OVERSAMPLE_ALLOWED}"

    return (batching_error(cfg["sample_rate"], cfg["batch_duration"], cfg["state_rate"])
            or duration_error("duration", cfg["duration"], cfg["sample_rate"], no_end=True)
            or split_error(cfg["record_max_duration"], cfg["record_max_size"], cfg["batch_duration"]))


# ---- the node ----------------------------------------------------------------------------------
class BearingSimNode(Node):
    """The ``bearing_sim`` node; see the module docstring.  Raises UserError for a bad
    parameter or scene (rclpy must be initialised).  ``record_argument``: how an error names the
    ``record`` path (``bearing-sim run`` passes ``--out``, the option its user gave);
    ``settings``: how the advice of a solver's divergence names the settings to try
    (``errors.SettingNames``: the node's parameters, or ``bearing-sim run``'s scene keys)."""

    def __init__(self, record_argument: str = "record", settings: SettingNames = NODE_SETTINGS, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self._record_argument = record_argument
        self._settings = settings
        self.recorder = None
        self.end_logged = False                  # log_the_end said its last lines (close_node then does not)
        try:
            self._declare_all()
            # a misspelt `-p name:=value` is otherwise ignored without a word (not an error: a
            # parameters file for several nodes may hold other nodes' parameters)
            for name in sorted(set(getattr(self, "_parameter_overrides", {})) - set(self._cfg)):
                if not self.has_parameter(name):
                    self.get_logger().warning(f"parameter {name}: not a {NODE_NAME} parameter, ignored; "
                                              f"its parameters are {', '.join(self._cfg)}")
            cfg = self._cfg
            for key in ("scene", "record"):
                # `-p record:=~/run.mcap`: no shell expands a ~ after :=, and the node said it
                # could not write '~/run.mcap'
                if cfg[key].startswith("~"):
                    cfg[key] = os.path.expanduser(cfg[key])
            self._state_rate_within_batches()
            reason = check_config(cfg)
            if reason:
                raise UserError(reason)
            self._build(cfg)
            self.add_pre_set_parameters_callback(self._before_set_parameters)
            self.add_on_set_parameters_callback(self._on_set_parameters)
            self.add_post_set_parameters_callback(self._after_set_parameters)
        except BaseException:
            # a bad parameter (or in `bearing-sim run` a Ctrl-C while the kernels load): no caller
            # gets the node to close and destroy, and main ends the process without Python's
            # finalisation, which did it before (the middleware's participant and its shared memory)
            if self.recorder is not None:
                self.recorder.close()
            self.destroy_node()
            raise

    # ---- parameters ----------------------------------------------------------------------
    def _declare_all(self):
        from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException

        self._cfg = {}
        for name, (default, desc) in _descriptors().items():
            try:
                value = self.declare_parameter(name, default, desc).value
            except InvalidParameterTypeException:
                given = _override_value(self, name)
                raise UserError(f"parameter {name} = {given!r}: wrong type, expected {_KINDS[type(default)]} "
                                f"(default {_param_text(default)})") from None
            except InvalidParameterValueException:
                given = _override_value(self, name)
                allowed = _allowed(desc)
                raise UserError(f"parameter {name} = {given!r}: allowed range is {allowed}") from None
            self._cfg[name] = value

    def _state_rate_within_batches(self):
        """``state_rate`` not given: its default (50 Hz) is more than one state per batch for
        batches longer than 20 ms, and ``-p batch_duration:=0.1`` alone ended the node with an
        error about a parameter its user never set.  Then one state per batch.  Given, it is
        checked as it is."""
        from rclpy.parameter import Parameter

        cfg = self._cfg
        given = getattr(self, "_parameter_overrides", {})
        if "state_rate" in given or cfg["state_rate"] * cfg["batch_duration"] <= 1.0:
            return
        rate = 1.0 / cfg["batch_duration"]
        self.set_parameters([Parameter("state_rate", value=rate)])
        cfg["state_rate"] = rate

    def _before_set_parameters(self, params):
        """A parameter the node does not have, set at run time (``ros2 param set /bearing_sim
        sampel_rate 1000.0``): rclpy refuses it before the on-set callback, with "Invalid access
        to undeclared parameter(s): []" (its list comes out empty).  Its own exception, raised
        here, which its parameter services answer with, says which and what the node has."""
        from rclpy.exceptions import ParameterNotDeclaredException

        unknown = [p.name for p in params if not self.has_parameter(p.name)]
        if unknown:
            changeable = [name for name, (_default, desc) in _descriptors().items() if not desc.read_only]
            error = ParameterNotDeclaredException(unknown)
            error.args = (f"parameter {unknown[0]}: not a {NODE_NAME} parameter; its parameters are "
                          f"{', '.join(self._cfg)}, of which these change while it runs: {', '.join(changeable)}",)
            raise error
        return params

    def _on_set_parameters(self, params):
        """Validate a run-time change against the whole configuration (read-only parameters
        and descriptor ranges are refused by rclpy before this is called)."""
        cfg = dict(self._cfg)
        for p in params:
            if p.name in cfg:
                cfg[p.name] = p.value
        reason = check_config(cfg)
        return SetParametersResult(successful=reason is None, reason=reason or "")

    def _after_set_parameters(self, params):
        cfg = dict(self._cfg)
        for p in params:
            if p.name in cfg:
                cfg[p.name] = p.value
        if cfg["real_time"] and not self._cfg["real_time"]:
            self._repace = True          # the sim thread re-anchors its schedule
        self._cfg = cfg                  # one reference swap: the sim thread sees all or none

    # ---- construction ------------------------------------------------------------------------
    def _build(self, cfg):
        from rclpy.qos import QoSProfile

        from .. import Simulator
        from ..physics.skidding import SolverDiverged
        from ..simulator import OversampleForAuto
        from ..messages import (TOPIC_ACCEL, TOPIC_CONTACT, TOPIC_DIAGNOSTICS, TOPIC_LOAD,
                                TOPIC_SHAFT_SPEED, TOPIC_STATE, BatchMessages, waveform_qos)
        from ..scene import load_scene
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import WrenchStamped
        from sensor_msgs.msg import JointState, PointCloud2
        from std_msgs.msg import Float64

        self.scene = load_scene(cfg["scene"])
        try:
            self.sim = Simulator(self.scene, sample_rate=float(cfg["sample_rate"]),
                                 fidelity=cfg["fidelity"], seed=int(cfg["seed"]),
                                 oversample=int(cfg["oversample"]) or None)
        except OversampleForAuto as exc:
            raise UserError(exc.worded("oversample", "fidelity", zero=OVERSAMPLE_ZERO)) from None
        except SolverDiverged as exc:          # its first steps, run ahead as it is made
            raise UserError(exc.worded(self._settings)) from None
        # the rest of the running tier's kernels before the start line: on a cold cache its
        # "compiled in N s" came after the first batch, behind the other tier's background lines
        self.sim.load_kernels()
        self.limits = InputLimits(self.scene.bearing, self.scene.shaft_weight)
        self.n_batch = int(round(cfg["sample_rate"] * cfg["batch_duration"]))
        self.batch_duration = self.n_batch / self.sim.sample_rate
        self.wave_qos = waveform_qos(self.batch_duration)
        self.small_qos = QoSProfile(depth=10)     # reliable, volatile, keep-last 10
        self.input_qos = QoSProfile(depth=INPUT_DEPTH)      # reliable, volatile, keep-last INPUT_DEPTH
        self.pub_accel = self.create_publisher(PointCloud2, TOPIC_ACCEL, self.wave_qos)
        self.pub_contact = self.create_publisher(PointCloud2, TOPIC_CONTACT, self.wave_qos)
        self.pub_state = self.create_publisher(JointState, TOPIC_STATE, self.small_qos)
        self.pub_diag = self.create_publisher(DiagnosticArray, TOPIC_DIAGNOSTICS, self.small_qos)
        self.pub_clock = None                     # created when publish_clock is first true
        self._tier_cache = None                   # (key, tier keys) of the last batch: _tier_keys
        self.sub_speed = self.create_subscription(Float64, TOPIC_SHAFT_SPEED, self._on_speed, self.input_qos)
        self.sub_load = self.create_subscription(WrenchStamped, TOPIC_LOAD, self._on_load, self.input_qos)

        # commands (written by the executor thread, read by the sim thread: plain rebinding)
        self._cmd_speed = float(self.sim.shaft_speed)
        self._cmd_load = tuple(float(v) for v in self.sim.radial_load)
        self._last_load_stamp = None
        self.rejected = {"not_finite": 0, "out_of_range": 0, "wrong_frame": 0, "stale": 0, "out_of_order": 0}
        self._reject_log = {}                     # reason -> (monotonic s of its last line, since, the
                                                  # latest held back's reason text)

        self.start_ns = self.get_clock().now().nanoseconds
        self.msgs = BatchMessages(self.sim, self.start_ns, cfg["frame_id"] or None)
        self.recorder = None
        self._dropped_reported = 0               # recording drops up to the last /diagnostics
        if cfg["record"]:
            self._open_recorder(cfg)
        self._stop = threading.Event()
        self._stop_reason = None                 # stop(reason): why the run ended, for its end status
        self._last_status = None                 # (item, values, level, message) of the last /diagnostics
        self.end_status = None                   # (end_reason, level, message) of the run's end status, to log
                                                 # (without a recording failure, which has its own line)
        self._status_apart_from_recording = (0, "ok")   # (level, message) of the last status but
                                                        # for the recording's failure
        self._repace = False
        self.finished = threading.Event()
        self.error = None
        # the skidding solver's divergence (SolverDiverged): the batches computed before it are
        # published, an ERROR /diagnostics says it, the recording is finalised and main exits 2
        self.failure = None
        self.accel_peers = 0                     # other publishers on accel: _check_peers
        self.clock_peers = 0                     # other publishers on this node's /clock: _check_peers
        self.input_strangers = {}                # input topic -> its strangers_to_name state
        self.stats = _Stats(self.sim.sample_rate, self.sim.bearing, self.scene.sensor.range)
        self._behind = _FallingBehind()
        self._thread = threading.Thread(target=self._run, name="bearing-sim", daemon=True)

    def _open_recorder(self, cfg):
        from ..messages import (TOPIC_ACCEL, TOPIC_CONTACT, TOPIC_DIAGNOSTICS, TOPIC_LOAD,
                                TOPIC_SHAFT_SPEED, TOPIC_STATE, TYPES)
        from ..recording.recorder import Recorder, recording_metadata
        from ..scene import scene_argument

        # each topic under its resolved name (namespace and remaps applied), its type from its
        # role: a remapped name (-r accel:=vibration) says nothing about the type
        # the operating point is recorded once per batch, as render records it (keep-last 10, not
        # the inputs' depth: what is recorded there is not what came in)
        topics = ((TOPIC_SHAFT_SPEED, self.sub_speed, self.small_qos), (TOPIC_LOAD, self.sub_load, self.small_qos),
                  (TOPIC_ACCEL, self.pub_accel, self.wave_qos), (TOPIC_CONTACT, self.pub_contact, self.wave_qos),
                  (TOPIC_STATE, self.pub_state, self.small_qos), (TOPIC_DIAGNOSTICS, self.pub_diag, self.small_qos))
        params = dict(cfg)
        # the scene as a shipped name or an absolute path: a relative path or the name inside a
        # scene file would not load from another directory
        command_cfg = dict(cfg, scene=scene_argument(self.scene))
        params.update({"mode": "live",
                       "command": "bearing-sim node --ros-args " + " ".join(self._ros_arguments(topics) + [
                           f"-p {k}:={_command_text(v)}" for k, v in sorted(command_cfg.items())])})
        meta = recording_metadata(self.scene, params, int(cfg["seed"]), self.sim.selection,
                                  topics={role: ent.topic_name for role, ent, _qos in topics})
        text = self.scene.source_text
        attachments = {f"{self.scene.name}.yaml": text.encode("utf-8")} if text else {}
        # a disk that falls behind costs messages (dropped, counted, reported), never a late batch
        self.recorder = Recorder(cfg["record"], meta, attachments, argument=self._record_argument,
                                 keep=[self.scene.source_path], when_full="drop",
                                 rotate_seconds=float(cfg["record_max_duration"]),
                                 rotate_bytes=int(cfg["record_max_size"]))
        try:
            for role, ent, qos in topics:
                self.recorder.add_topic(ent.topic_name, TYPES[role], qos)
        except BaseException:
            self.recorder.close()        # not a file that looks like a recording and holds none
            raise

    def _ros_arguments(self, topics) -> list:
        """The ROS arguments besides the node's parameters that the recorded command needs to give
        the same topics: namespace, node name (the diagnostics' status is named after both), each
        remapped topic of ``topics`` ((role, entity, qos)), and ``use_sim_time``.  Without them a
        node of rig1 (``-r __ns:=/rig1``) recorded a command that published on /accel."""
        ns = self.get_namespace()
        out = [] if ns == "/" else [f"-r __ns:={ns}"]
        if self.get_name() != NODE_NAME:
            out.append(f"-r __node:={self.get_name()}")
        for role, ent, _qos in topics:
            if ent.topic_name != (role if role.startswith("/") else f"{ns.rstrip('/')}/{role}"):
                out.append(f"-r {role}:={ent.topic_name}")
        if self.get_parameter("use_sim_time").value:
            out.append("-p use_sim_time:=true")
        return out

    # ---- inputs (executor thread) ------------------------------------------------------------
    def _reject(self, key, reason):
        """Count a rejected input and log it: one line per reason every REJECT_LOG_PERIOD at most
        (one throttle for all would let a flood of NaNs hide the stale stamps after them), with
        how many more of that reason came since its last line."""
        self.rejected[key] += 1
        now = time.monotonic()
        last, since, _held = self._reject_log.get(key, (-math.inf, 0, ""))
        if now - last < REJECT_LOG_PERIOD:
            self._reject_log[key] = (last, since + 1, reason)
            return
        self._reject_log[key] = (now, 0, "")
        more = f" ({since} more {key} since the last such line)" if since else ""
        self.get_logger().warning(f"input rejected ({key}), keeping {self._cmd_speed:.6g} rad/s, "
                                  f"load {self._cmd_load}: {reason}{more}")

    def _log_held_rejections(self, logger=None, at_end: bool = False):
        """Log the rejections each reason's throttle held back once its period is over (a timer
        in the executor thread, as ``_reject``): else they waited for that reason's next line,
        and a burst that had none (300 NaNs sent at once) was one line in the log.  ``at_end``:
        the run is over and the executor stopped (``log_end``), so those of a period not over
        yet too, with ``logger``: rejected in the last 2 s, they were counted in /diagnostics
        and never logged."""
        now = time.monotonic()
        for key, (last, since, held) in list(self._reject_log.items()):
            if since and (at_end or now - last >= REJECT_LOG_PERIOD):
                self._reject_log[key] = (now, 0, "")
                (logger or self.get_logger()).warning(
                    f"{since} more input{'s' if since > 1 else ''} rejected ({key}) since the last such line, keeping "
                    f"{self._cmd_speed:.6g} rad/s, load {self._cmd_load}; the latest: {held}")

    def _on_speed(self, msg):
        value = float(msg.data)
        bad = check_speed(value, self.limits)
        if bad:
            self._reject(*bad)
            return
        self._cmd_speed = value

    def _on_load(self, msg):
        f = msg.wrench.force
        fx, fy, fz = float(f.x), float(f.y), float(f.z)
        bad = check_load(fx, fy, fz, self.limits) or check_frame(msg.header.frame_id, self.msgs.frame_id)
        if bad:
            self._reject(*bad)
            return
        stamp_ns = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
        bad = check_stamp(stamp_ns, self._last_load_stamp, self.get_clock().now().nanoseconds,
                          float(self._cfg["input_max_age"]))
        if bad:
            self._reject(*bad)
            return
        if stamp_ns:
            self._last_load_stamp = stamp_ns
        self._cmd_load = (fx, fy)

    # ---- simulation thread -------------------------------------------------------------------
    def start(self):
        self.get_logger().info(
            f"scene {self.scene.name}: {self.sim.tier} tier ({self.sim.selection.reason}), "
            f"{self.sim.sample_rate:g} Hz in batches of {self.n_batch}, "
            f"real_time {self._cfg['real_time']}, duration {self._cfg['duration']:g} s, "
            f"recording {_recording_text(self._cfg)}; inputs accepted: {self.limits}")
        if self.scene.profile:
            # a scene written for `render` ran at its operating point without a word (a ramp
            # expected, a steady run recorded)
            self.get_logger().warning(
                f"scene {self.scene.name}: its speed/load profile ({len(self.scene.profile)} knots) is for "
                f"offline renders; the node runs at the operating point and follows {self.sub_speed.topic_name} "
                f"and {self.sub_load.topic_name} (`bearing-sim play` of a render of the scene publishes "
                f"its profile to them)")
        self._peer_timer = self.create_timer(PEER_CHECK_S, self._check_peers)
        self._reject_timer = self.create_timer(REJECT_LOG_PERIOD / 4, self._log_held_rejections)
        self._thread.start()

    def _check_peers(self):
        """Another publisher on this node's ``accel`` (a second simulator started in the same
        namespace, a ``play`` of a recording): every subscriber then gets both streams' tables
        interleaved, and nothing said so.  Said in the log when it changes and in
        ``/diagnostics`` (``other_accel_publishers``, WARN).

        Another publisher on the ``/clock`` this node publishes (``publish_clock``): two rigs in
        two namespaces both publish the one ``/clock``, each from 0 at its own start under sim
        time, and every node on sim time, these too, then follows two time lines that jump back
        and forth (1.3 s apart 196 times in 4 s, two rigs started 1.5 s apart).  Said in the log
        when it changes."""
        self.accel_peers = self._other_publishers(
            self.pub_accel.topic_name, self.accel_peers,
            "subscribers get their tables interleaved with this node's; give each simulator its own "
            "namespace (-r __ns:=/rig1) or ROS_DOMAIN_ID")
        self._check_input_types()
        if self.pub_clock is not None:
            self.clock_peers = self._other_publishers(
                self.pub_clock.topic_name, self.clock_peers,
                "nodes on sim time follow both clocks interleaved; give each rig's clock its own name "
                "(-r /clock:=/rig1/clock, and the same remap for the rig's consumers) or ROS_DOMAIN_ID")

    def _check_input_types(self) -> None:
        """A publisher on ``shaft_speed`` or ``load`` of another type (``std_msgs/Float32``, a
        ``geometry_msgs/Wrench`` without a stamp) never matches, and neither side said a word: the
        commands were lost and the signal ran on at the old operating point.  Said in the log, once
        per such publisher, and when none is left."""
        from ..messages import TOPIC_LOAD, TOPIC_SHAFT_SPEED, TYPES

        for role, sub in ((TOPIC_SHAFT_SPEED, self.sub_speed), (TOPIC_LOAD, self.sub_load)):
            topic, want = sub.topic_name, TYPES[role]
            publishers = [(bytes(info.endpoint_gid),
                           None if info.node_name == UNKNOWN_NODE_NAME
                           else f"{info.node_namespace.rstrip('/')}/{info.node_name}", info.topic_type)
                          for info in self.get_publishers_info_by_topic(topic) if info.topic_type != want]
            self.input_strangers[topic], to_name, gone = strangers_to_name(
                self.input_strangers.get(topic, {}), publishers)
            for node, kind in to_name:
                self.get_logger().warning(
                    f"{node} publishes {kind} on {topic}, which takes {want}: its messages never reach "
                    f"this node")
            if gone:
                self.get_logger().info(f"no publisher of another type on {topic} any more")

    def _other_publishers(self, topic: str, known: int, advice: str) -> int:
        """The number of publishers on ``topic`` besides this node's, logged (with ``advice``)
        when it differs from ``known``, the number at the last look."""
        others = max(0, self.count_publishers(topic) - 1)
        if others != known:
            if others:
                self.get_logger().warning(
                    f"{others} other publisher{'s' if others > 1 else ''} on {topic}: {advice}")
            else:
                self.get_logger().info(f"no other publisher on {topic} any more")
        return others

    def stop(self, timeout: float = 10.0, reason: str = "stopped"):
        """Finish the batch in progress, publish the end status (``reason``: why the run ended,
        one of ``messages.END_REASONS``, for a run that had not ended by itself), close the
        recording.  Idempotent: the first reason holds."""
        if self._stop_reason is None:
            self._stop_reason = reason
        self._stop.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout)
        if self.recorder is not None:
            self.recorder.close()

    def _run(self):
        try:
            # before the first batch, which starts the clock: a tier switch at run time must not
            # stall the stream while the other tier's kernels load (or compile, on a cold cache)
            self.sim.prepare_switches()
            if self._wait_for_clock() and self._wait_for_subscribers():
                self._loop()
        except BaseException as exc:  # noqa: BLE001 - reported by main() as an internal error
            self.error = exc
        finally:
            self.finished.set()

    def _wait_for_clock(self) -> bool:
        """With ``use_sim_time`` the node's clock is the last ``/clock`` received, and 0 before the
        first.  Where another node publishes it, the first batch waits for it: its time becomes
        sample 0's stamp (one batch before it), as without sim time the wall clock's does.  Where
        this node is the clock (``publish_clock``), there is nothing to wait for: the signal starts
        at 0.  False if the node stops while it waits."""
        clock = self.get_clock()
        said = False
        while clock.ros_time_is_active and not self._cfg["publish_clock"] and clock.now().nanoseconds == 0:
            if self._stop.is_set() or not self.context.ok():
                return False
            if not said:
                said = True
                self.get_logger().info("use_sim_time: waiting for /clock before the first batch "
                                       "(publish_clock:=true makes this node the clock)")
            self._stop.wait(0.02)
        return True

    def _wait_for_subscribers(self) -> bool:
        """With ``wait_for_subscribers`` N > 0, the first batch waits until N subscriptions match
        ``accel`` and then until no new match came for ``DISCOVERY_GRACE_S`` (their other topics):
        a consumer started with the node lost the first tables to discovery (the whole of a 1 s
        run in 2 of 5 runs, 1.0 - 1.7 s of a rig in 2 of 4), since the tables are volatile.  The
        signal starts when the wait ends.  False if the node stops while it waits."""
        from ..messages import DISCOVERY_GRACE_S

        want = self._cfg["wait_for_subscribers"]
        if not want:
            return True
        topic = self.pub_accel.topic_name
        self.get_logger().info(f"waiting for {want} subscriber{'s' if want > 1 else ''} on {topic} "
                               "before the first batch (wait_for_subscribers)")
        counts, stable_since = None, None
        while True:
            if self._stop.is_set() or not self.context.ok():
                return False
            now = time.monotonic()
            new = (self.pub_accel.get_subscription_count(), self.pub_contact.get_subscription_count(),
                   self.pub_state.get_subscription_count())
            if new != counts:
                counts, stable_since = new, now
            elif new[0] >= want and now - stable_since >= DISCOVERY_GRACE_S:
                break
            self._stop.wait(0.02)
        self.get_logger().info(f"{counts[0]} subscriber{'s' if counts[0] > 1 else ''} on {topic}: starting")
        return True

    def _log_switch(self, switches: int) -> None:
        """Say a tier switch in the log, if the simulator made one since it had ``switches``."""
        sim = self.sim
        if sim.tier_switches != switches:
            t, old, new = sim.last_tier_switch
            self.get_logger().info(f"tier switch at {t:.3f} s of signal: {old} -> {new} "
                                   f"({sim.selection.reason})")

    def _compute(self, n, cfg, Clock):
        """Advance one batch and build its messages (no waiting, no publishing)."""
        sim, msgs = self.sim, self.msgs
        speed, load = self._cmd_speed, self._cmd_load       # commands take effect here
        switches = sim.tier_switches
        batch = sim.advance(n, shaft_speed=speed, radial_load=load)
        self._log_switch(switches)
        if batch.index0 == 0:
            # ROS time of sample 0: one batch before now, when the first batch is ready (its
            # computation may include loading compiled kernels: that must not be an overrun); never
            # before 0, where a sim time starts (publish_clock with use_sim_time: this node's own
            # clock, 0 until its first /clock; a negative stamp is no ROS time)
            before = self.get_clock().now().nanoseconds - int(round(n / sim.sample_rate * 1e9))
            self.start_ns = msgs.start_ns = max(0, before)
        end_index = sim.index
        start_stamp, end_stamp = msgs.stamp_ns(batch.index0), msgs.stamp_ns(end_index)
        out = []
        if cfg["publish_clock"]:
            # the clock first, as a simulator advances its time before it publishes data stamped
            # up to it: in real time a table goes out once the moment of its last sample has
            # come, and with sim time a subscriber's clock must have reached it too (published
            # after the tables, it was a batch behind on arrival for most tables)
            if self.pub_clock is None:
                self.pub_clock = self.create_publisher(Clock, "/clock", self.small_qos)
            clk = Clock()
            clk.clock.sec, clk.clock.nanosec = divmod(end_stamp, 1_000_000_000)
            out.append((self.pub_clock, clk))
        out += [(self.pub_accel, msgs.accel(batch)), (self.pub_contact, msgs.contact_forces(batch))]
        rate, sr = cfg["state_rate"], sim.sample_rate
        if rate > 0 and math.floor(end_index * rate / sr) > math.floor(batch.index0 * rate / sr):
            out.append((self.pub_state, msgs.state(end_stamp)))
        return _Pending(batch, end_index, start_stamp, end_stamp, speed, load, self._tier_keys(), out)

    def _tier_keys(self) -> dict:
        """The tier keys of ``/diagnostics`` (``render.tier_values``) as the batch just computed
        ran, for the diagnostics published with it; one dict shared by every batch until the tier,
        its selection, its steps or its balls' law (``Simulator.centrifugal``, re-decided as the
        speed moves) change, so a batch allocates nothing for it."""
        from ..recording.render import tier_values

        sim = self.sim
        key = (sim.selection, sim.tier_switches, sim.oversample, sim.centrifugal)
        cached = self._tier_cache
        if cached is None or cached[0][0] is not key[0] or cached[0][1:] != key[1:]:
            self._tier_cache = cached = (key, tier_values(sim))
        return cached[1]

    def _loop(self):
        """Compute batches up to ``compute_ahead`` before their due time, publish each at its due
        time (the moment of its last sample), record it after publishing.

        Publishing on time comes first: a batch is computed only when the queue is empty or
        there is time for it (``est``, a decaying maximum of recent compute times) before the
        next publication.  An overrun is a batch whose computation ended after its due time;
        the node then publishes it at once and computes on without waiting until it is ahead
        again (catch up; the schedule is fixed by the sample index, so it never drifts)."""
        from rosgraph_msgs.msg import Clock

        from ..physics.skidding import SolverDiverged
        from ..recording.render import load_message, speed_message

        sim, msgs, stats = self.sim, self.msgs, self.stats
        sr = sim.sample_rate
        context = self.context
        queue = deque()
        anchor_t = anchor_i = None            # sample anchor_i is due at steady time anchor_t
        next_diag = None                      # steady-clock time of the next /diagnostics
        next_diag_index = sr                  # real_time:=false: once per second of signal, like render
        est = {}                              # tier -> decaying maximum of its batches' computation (s)
        # the computation of a batch that switches the tier (the new tier's set-up: about 8 ms
        # for kinematic -> skidding), a decaying maximum like est, measured at each switch
        switch_est = SWITCH_COST_GUESS_S
        last_published = None                 # (item, its log time) of the latest batch published
        ended = False                         # the end status went out with the last batch
        rec_failed = False
        stats.period_start(time.monotonic(), 0)
        while True:
            stop = self._stop.is_set() or not context.ok()
            cfg = self._cfg
            real_time = cfg["real_time"]
            total = int(round(cfg["duration"] * sr)) if cfg["duration"] > 0 else 0
            now = time.monotonic()
            if queue and (stop or not real_time or queue[0].due <= now):
                item = queue.popleft()
                if stop and real_time and item.due > now:
                    # computed ahead and not due yet: never published, so not recorded either (the
                    # file ended up to compute_ahead past the stream that subscribers got)
                    continue
                lag = max(0.0, now - item.due) if real_time else 0.0
                stats.batch(lag, item.batch, now)
                out = item.out
                # the run's last batch carries its end status: nothing due after it on a stop (the
                # batches computed ahead are dropped), or the duration's last sample
                if stop:
                    last = not queue or (real_time and queue[0].due > now)
                    ending = (self._stop_reason or "stopped") if last else None
                else:
                    ending = "duration" if total and sim.index >= total and not queue else None
                if ending is not None:
                    out = out + [(self.pub_diag, self._end_status(item, now, ending))]
                elif (now >= next_diag) if real_time else (item.end_index >= next_diag_index):
                    # without pacing, a second of signal passes in far less than a second: the
                    # steady-clock schedule restarts from now, or it would lie as far in the future
                    # as the signal ran ahead, and real_time:=true again would publish none till then
                    next_diag = max(next_diag + 1.0, now - 0.5) if real_time else now + 1.0
                    next_diag_index = (math.floor(item.end_index / sr) + 1) * sr
                    out = out + [(self.pub_diag, self._diagnostics(item, now))]
                self._publish(out)
                # real time: when it was published = end stamp + lateness; otherwise the end
                # stamp, like `render`, so the file replays at the signal's pace
                log_ns = item.end_stamp + int(lag * 1e9)
                last_published = (item, log_ns)
                rec = self.recorder
                if rec is not None:          # after publishing: serialising is off the critical path
                    rec.write(self.sub_speed.topic_name, speed_message(item.speed), log_ns)
                    rec.write(self.sub_load.topic_name,
                              load_message(item.load, item.start_stamp, msgs.frame_id), log_ns)
                    for pub, msg in out:
                        if pub is not self.pub_clock:
                            rec.write(pub.topic_name, msg, log_ns)
                    if rec.error and not rec_failed:
                        rec_failed = True        # said once, when it happens; again at exit
                        self.get_logger().error(f"recording failed, publishing goes on: {rec.error}")
                stats.work(time.monotonic() - now)
                if ending is not None:
                    ended = True
                    break                      # the run is over: a longer duration set now comes too late
                continue
            if stop:
                break                          # every batch that was due is published and recorded
            if self.failure is not None:
                if not queue:
                    break
                # the batches computed before the divergence, published at their times
                self._stop.wait(max(0.0, queue[0].due - now))
                continue
            if total and sim.index >= total:
                if not queue:
                    break
                self._stop.wait(max(0.0, queue[0].due - now))
                continue
            n = min(self.n_batch, total - sim.index) if total else self.n_batch
            if real_time and self._repace:
                self._repace = False
                anchor_t, anchor_i = now, sim.index
            # earliest start of the next computation: when the batch before it is due (just in
            # time), minus compute_ahead
            start_at = (anchor_t + (sim.index - anchor_i) / sr - cfg["compute_ahead"]
                        if real_time and anchor_t is not None else now)
            may = start_at <= now
            cost = est.get(sim.tier, 0.0)
            switching = sim.can_switch_tiers and sim.switch_ahead(self._cmd_speed, self._cmd_load)
            if switching:
                # a switch (the new tier's set-up, several batches' work) is a step of its own,
                # before the batch: started right after a publication, where the next one is a
                # whole batch away (waiting longer cannot help: no gap is wider)
                cost = max(cost, min(switch_est, 0.9 * n / sr))
            if switching and may and (not queue or now + cost <= queue[0].due):
                switches = sim.tier_switches
                sim.maybe_switch_tier(self._cmd_speed, self._cmd_load)      # what advance does first
                self._log_switch(switches)
                done = time.monotonic()
                stats.work(done - now)
                switch_est = max(0.9 * switch_est, done - now)
                # the new tier's first batches (its first steps sub-stepped), whose cost is not
                # known yet: as long as a switch, at most (decaying as its batches are measured)
                est[sim.tier] = max(est.get(sim.tier, 0.0), cost)
                continue
            if may and (not queue or now + cost <= queue[0].due):
                try:
                    item = self._compute(n, cfg, Clock)
                except SolverDiverged as exc:
                    self._fail(exc)
                    continue
                done = time.monotonic()
                stats.compute(done - now)
                est[sim.tier] = max(0.9 * est.get(sim.tier, 0.0), done - now)
                if anchor_t is None:
                    # the schedule starts with the first batch: it is due now
                    anchor_t, anchor_i = done - n / sr, 0
                    next_diag = anchor_t + 1.0
                    stats.period_start(anchor_t, 0)
                    stats.started = anchor_t
                if real_time:
                    item.due = anchor_t + (item.end_index - anchor_i) / sr
                    if done > item.due:
                        stats.overruns += 1    # late: publish at once, the next batches catch up
                else:
                    item.due = done
                queue.append(item)
                continue
            wake = queue[0].due if queue else start_at
            if not may:
                wake = min(wake, start_at)
            self._stop.wait(max(0.0, wake - now))
        # the end status with the last batch published where the loop ended after it (a stop that
        # came just after it, a duration set below the signal published; a divergence).  It is the
        # ground truth of the last sample too, as `render` ends: a run that ended between two
        # /diagnostics (duration 5.5 s, Ctrl-C) had none for its last part-second, and a pit that
        # appeared there was "after this recording ends" to `report`
        if self.failure is not None:
            self._publish_failure(last_published)
        elif last_published is not None and not ended:
            item, log_ns = last_published
            msg = self._end_status(item, time.monotonic(), (self._stop_reason or "stopped") if stop else "duration")
            self._publish([(self.pub_diag, msg)])
            if self.recorder is not None:
                self.recorder.write(self.pub_diag.topic_name, msg, log_ns)
        if last_published is not None:
            self._deliver_the_end()

    def _fail(self, exc) -> None:
        """The skidding solver diverged (``exc``, SolverDiverged): no more batches; said once in
        the log in the node's words."""
        self.failure = exc
        self.get_logger().error(exc.worded(self._settings))

    def _publish_failure(self, last_published) -> None:
        """The end status of a divergence (level ERROR, ``end_reason`` ``diverged``, the line),
        published and recorded: with the keys of the last batch published (``last_published``:
        (item, its log time)), or, where none was, the status alone, stamped now."""
        from ..messages import end_of_run
        from ..recording.render import diagnostics_message

        if last_published is not None:
            item, log_ns = last_published
            msg = self._end_status(item, time.monotonic(), "diverged")
        else:
            log_ns = self.get_clock().now().nanoseconds
            values, level, message = end_of_run({"simulated_s": "0.000000"}, 2, self.failure.worded(self._settings),
                                                "diverged", 0, self.sim.sample_rate, self._cfg["duration"])
            msg = diagnostics_message(log_ns, values, level, message, self.get_fully_qualified_name().lstrip("/"))
        self._publish([(self.pub_diag, msg)])
        if self.recorder is not None:
            self.recorder.write(self.pub_diag.topic_name, msg, log_ns)

    def _publish(self, out):
        """Publish each (publisher, message) of ``out`` while the context lives (a signal may end
        it at any moment: then nothing more goes out)."""
        if self.context.ok():
            try:
                for pub, msg in out:
                    pub.publish(msg)
            except Exception:  # noqa: BLE001 - the context went away between ok() and publish
                if self.context.ok():
                    raise

    def _diagnostics(self, item, now):
        """The ``/diagnostics`` message published with ``item``, the batch whose end it is
        stamped with: what the signal held there, not at the end of what is computed ahead."""
        from ..recording.render import diagnostics_message

        values, level, message = self._status(item, now)
        self._last_status = (item, values, level, message)
        return diagnostics_message(item.end_stamp, values, level, message,
                                   self.get_fully_qualified_name().lstrip("/"))

    def _end_status(self, item, now, reason: str):
        """The run's last ``/diagnostics``, published with ``item``, its last batch: the status
        with ``run: ended``, ``end_reason`` (``reason``) and ``published_samples``
        (``messages.end_of_run``).  Where a /diagnostics went out with that batch already, the
        same status ended: its second's figures, not those of the moment since."""
        from ..messages import end_of_run
        from ..recording.render import diagnostics_message

        last = self._last_status
        if last is not None and last[0] is item and self.failure is None:
            values, level, message = last[1:]
        else:
            values, level, message = self._status(item, now)
        ended = (reason, item.end_index, self.sim.sample_rate, self._cfg["duration"])
        # the log says a recording's failure in its own line after the end's (log_recording): the
        # end's line gives the rest of the status, at its level (it said the failure twice)
        logged = self._status_apart_from_recording if values.get("recording") == "error" else (level, message)
        self.end_status = (reason, *end_of_run(values, *logged, *ended)[1:])
        values, level, message = end_of_run(values, level, message, *ended)
        return diagnostics_message(item.end_stamp, values, level, message,
                                   self.get_fully_qualified_name().lstrip("/"))

    def _deliver_the_end(self) -> None:
        """Give reliable subscribers up to ``END_DELIVERY_GRACE_S`` to acknowledge what the node
        published last (its end status, its last tables) before it is destroyed
        (``messages.deliver_the_end``).  Best effort and silent: an unacknowledged topic is no
        sign of a lost message (a warning of them, after a 2 s wait, was a false alarm in 7 of 10
        live runs whose subscriber had everything)."""
        from ..messages import END_DELIVERY_GRACE_S, deliver_the_end

        late = deliver_the_end((self.pub_accel, self.pub_contact, self.pub_state, self.pub_diag),
                               END_DELIVERY_GRACE_S, self.context.ok)
        if late and self.context.ok():
            self.get_logger().debug(f"not acknowledged within {END_DELIVERY_GRACE_S:g} s at the end of the run: "
                                    f"{', '.join(late)}")

    def _status(self, item, now) -> tuple:
        """``(values, level, message)`` of the ``/diagnostics`` published with ``item``."""
        from ..messages import RUN_KEY, RUN_RUNNING
        from ..recording.render import defect_values, scene_values

        st = self.stats
        published_index = item.end_index
        period = st.period_end(now, published_index)
        rtf = period["signal_s"] / period["wall_s"] if period["wall_s"] > 0 else float("nan")
        values = {
            RUN_KEY: RUN_RUNNING,
            **scene_values(self.scene),
            "real_time_factor": f"{rtf:.4f}",
            "real_time": str(bool(self._cfg["real_time"])).lower(),
            "overruns": st.overruns,
            "overruns_last_period": period["overruns"],
            "lag_s": f"{period['worst_lag']:.6f}",
            "worst_lag_s": f"{st.worst_lag:.6f}",
            "batch_compute_s": f"{period['busy_mean']:.6f}",
            "batch_compute_worst_s": f"{period['busy_worst']:.6f}",
            "sim_thread_load": f"{period['busy_fraction']:.4f}",
            **item.tier,
            # the truth of the signal published so far, not of the batches computed ahead
            **defect_values(self.sim, published_index - 1),
            "shaft_speed_rad_s": f"{item.speed:.6g}",
            "radial_load_n": " ".join(f"{v:.6g}" for v in item.load),
            "simulated_s": f"{published_index / self.sim.sample_rate:.6f}",
            "computed_ahead_s": f"{(self.sim.index - published_index) / self.sim.sample_rate:.3f}",
            "rejected_inputs": sum(self.rejected.values()),
        }
        for key, count in self.rejected.items():
            values[f"rejected_{key}"] = count
        values.update(period["means"])
        level, message = 0, "ok"
        if period["overruns"]:
            level, message = 1, f"{period['overruns']} overruns in the last second"
        behind = self._falling_behind(period)
        values["falling_behind"] = str(bool(behind)).lower()
        if behind:
            message = behind if level == 0 else f"{behind}; {message}"
            level = 1
        if period["clipped"]:
            message = period["clipped"] if level == 0 else f"{message}; {period['clipped']}"
            level = 1
        values["other_accel_publishers"] = self.accel_peers
        if self.accel_peers:
            text = (f"{self.accel_peers} other publisher{'s' if self.accel_peers > 1 else ''} "
                    f"on {self.pub_accel.topic_name}")
            message = text if level == 0 else f"{message}; {text}"
            level = 1
        rec = self.recorder
        if rec is None:
            values["recording"] = "off"
        else:
            rs = rec.status
            values["recording"] = "ok" if rs["ok"] else "error"
            values["recording_path"] = rs["path"]          # of a split recording: the piece being written
            values["recording_files"] = len(rs["files"])
            values["recording_messages"] = rs["messages"]
            values["recording_bytes"] = rs["bytes"]
            values["recording_dropped"] = rs["dropped"]
            dropped, self._dropped_reported = rs["dropped"] - self._dropped_reported, rs["dropped"]
            if not rs["ok"]:
                values["recording_error"] = rs["error"]
                # for the end of the run's log line, which the recording's own line follows
                self._status_apart_from_recording = (level, message)
                # the failure first, and after it the rest of the second's words (overruns, falling
                # behind, saturation, other publishers): replaced by it, they were lost for as long
                # as the node ran on
                failed = "recording failed: " + rs["error"]
                level, message = 2, failed if message == "ok" else f"{failed}; {message}"
            elif dropped:
                # the file has gaps: a warning, as overruns are (the stream itself is whole)
                text = f"recording dropped {dropped} messages in the last second (the disk is not keeping up)"
                message = text if level == 0 else f"{message}; {text}"
                level = 1
        if self.failure is not None:
            level, message = 2, self.failure.worded(self._settings)
        return values, level, message

    def _falling_behind(self, period) -> str:
        """"" where the node keeps up with real time, else the words of a node that falls behind
        for good (``_FallingBehind``) with what to change, for /diagnostics (WARN); said in the log
        too, once every ``FALLING_BEHIND_LOG_S`` while it lasts, and once when it has caught up.
        Such a node said nothing in its log, and its /diagnostics only 'N overruns in the last
        second', each second alike, whether it was a moment's stall or for ever."""
        behind = self._behind
        if not self._cfg["real_time"] or self._repace:
            behind.reset()
            return ""
        behind.add(period["signal_s"], period["wall_s"], self.stats.last_lag)
        log = self.get_logger()
        if not behind.falling:
            if behind.said_at is not None and behind.behind_s < 2 * self.batch_duration:
                log.info(f"caught up with real time again (it had fallen {behind.worst_s:.3g} s behind)")
                behind.said_at = None
            return ""
        text = (f"falling behind real time: x{behind.factor:.2f} over the last {FALLING_BEHIND_PERIODS} s, "
                f"{behind.behind_s:.3g} s behind and further each second; it cannot catch up: "
                f"{self._cheaper_settings()}")
        now = time.monotonic()
        if behind.said_at is None or now - behind.said_at >= FALLING_BEHIND_LOG_S:
            if behind.said_at is None:
                behind.worst_s = behind.behind_s
            behind.said_at = now
            log.warning(text)
        return text

    def _cheaper_settings(self) -> str:
        """What the user can change for a cheaper model, in the caller's words (``SettingNames``):
        the kinematic tier instead of the skidding one, fewer integration steps per sample."""
        sim, names = self.sim, self._settings
        offers = []
        if sim.tier == "skidding" and "fidelity" in names.keys:
            offers.append(f"{names.assign('fidelity', 'kinematic')} (the cheaper tier)")
        if (sim.oversample or 0) > 1 and "oversample" in names.keys:
            offers.append(f"{names.assign('oversample', 1)} (now {sim.oversample} steps per sample; less accurate)")
        if not offers:
            return "no cheaper setting is left; the machine is too slow or too busy for this scene in real time"
        return "try " + " or ".join(offers) + ", or a less busy machine"


class _Pending:
    """A computed batch waiting for its due time (steady clock, s)."""

    __slots__ = ("batch", "end_index", "start_stamp", "end_stamp", "speed", "load", "tier", "out", "due")

    def __init__(self, batch, end_index, start_stamp, end_stamp, speed, load, tier, out):
        self.batch, self.end_index = batch, end_index
        self.start_stamp, self.end_stamp = start_stamp, end_stamp
        self.speed, self.load, self.tier, self.out = speed, load, tier, out
        self.due = 0.0


class _Stats:
    """Pacing and batch statistics.  Written by the sim thread only."""

    def __init__(self, sample_rate: float, bearing, clip_limit: float):
        from ..recording.render import PeriodMeans

        self.sample_rate = sample_rate
        self._means = PeriodMeans(bearing.balls, clip_limit, bearing.ball_spin_speed(1.0))
        self.overruns = 0
        self.worst_lag = 0.0
        self.batches = 0
        self.samples = 0
        self.busy_worst = 0.0
        self.last_lag = 0.0
        self.started = self.last = time.monotonic()   # steady-clock start and last batch (s)

    @property
    def real_time_factor(self) -> float:
        """Signal seconds produced per steady-clock second since the start."""
        wall = self.last - self.started
        return self.samples / self.sample_rate / wall if wall > 0 else float("nan")

    def compute(self, seconds: float) -> None:
        """Time spent computing one batch: model and messages."""
        self.busy_worst = max(self.busy_worst, seconds)
        self._p_compute += seconds
        self._p_busy += seconds
        self._p_busy_worst = max(self._p_busy_worst, seconds)
        self._p_batches += 1

    def work(self, seconds: float) -> None:
        """Time spent publishing and recording one batch."""
        self._p_busy += seconds

    def period_start(self, now, index):
        self._p_t, self._p_i, self._p_over, self._p_lag = now, index, self.overruns, 0.0
        self._p_busy, self._p_compute, self._p_busy_worst, self._p_batches = 0.0, 0.0, 0.0, 0
        self._means.reset()

    def batch(self, lag, batch, now):
        self.last_lag = lag                 # s: how late the latest batch went out
        self.batches += 1
        self.samples += batch.n
        self.last = now
        self.worst_lag = max(self.worst_lag, lag)
        self._p_lag = max(self._p_lag, lag)
        self._means.add(batch)

    def period_end(self, now, index) -> dict:
        """Figures of the period since the last call, and start a new one."""
        sr_index = index - self._p_i
        out = {"wall_s": now - self._p_t, "signal_s": sr_index / self.sample_rate,
               "overruns": self.overruns - self._p_over, "worst_lag": self._p_lag,
               "busy_mean": self._p_compute / max(self._p_batches, 1), "busy_worst": self._p_busy_worst,
               "busy_fraction": self._p_busy / (now - self._p_t) if now > self._p_t else 0.0,
               "means": self._means.values(), "clipped": self._means.clipped_text()}
        self.period_start(now, index)
        return out


class _FallingBehind:
    """Whether the node falls behind real time for good, from its one-second periods (the sim
    thread's, at each /diagnostics in real time): its real-time factor below 1 in each of the last
    ``FALLING_BEHIND_PERIODS`` and at least ``FALLING_BEHIND_MIN_S`` behind its schedule, further
    than at their start.  ``said_at``: when the log last warned of it (monotonic s), None once it
    caught up again; ``worst_s``: how far behind it fell since then."""

    def __init__(self):
        self._periods = deque(maxlen=FALLING_BEHIND_PERIODS)     # (signal s, steady-clock s, s behind at its end)
        self.said_at = None
        self.worst_s = 0.0

    def add(self, signal_s: float, wall_s: float, behind_s: float) -> None:
        self._periods.append((signal_s, wall_s, behind_s))
        if self.said_at is not None:
            self.worst_s = max(self.worst_s, behind_s)

    def reset(self) -> None:
        """Not paced (``real_time:=false``), or paced anew from now: nothing to fall behind."""
        self._periods.clear()

    @property
    def falling(self) -> bool:
        periods = self._periods
        return (len(periods) == periods.maxlen and all(sig < wall for sig, wall, _ in periods)
                and periods[-1][2] >= FALLING_BEHIND_MIN_S and periods[-1][2] > periods[0][2])

    @property
    def factor(self) -> float:
        """The real-time factor over the periods held (signal s per steady-clock s)."""
        wall = sum(p[1] for p in self._periods)
        return sum(p[0] for p in self._periods) / wall if wall > 0 else float("nan")

    @property
    def behind_s(self) -> float:
        return self._periods[-1][2] if self._periods else 0.0


_KINDS = {bool: "true or false", int: "a whole number", float: "a floating-point number such as 1.0",
          str: "a string"}


def _override_value(node, name):
    """The value given with ``-p name:=value`` (rclpy keeps the overrides in a private dict)."""
    p = getattr(node, "_parameter_overrides", {}).get(name)
    return getattr(p, "value", "?")


def _allowed(desc) -> str:
    # the range, and what else is asked (record_max_size: "0, or at least 1000000")
    more = f"; {desc.additional_constraints}" if desc.additional_constraints else ""
    for r in desc.floating_point_range:
        return f"[{r.from_value:g}, {r.to_value:g}]{more}"
    for r in desc.integer_range:
        return f"[{r.from_value}, {r.to_value}]{more}"
    return desc.additional_constraints or "see the parameter description"


def _recording_text(cfg) -> str:
    """'off', 'runs/run.mcap', or where a split recording goes: 'runs/run.mcap in files of at most
    600 s: runs/run_000.mcap, runs/run_001.mcap, ...'."""
    from ..recording.recorder import rotated_path

    if not cfg["record"]:
        return "off"
    limits = ([f"{cfg['record_max_duration']:g} s"] if cfg["record_max_duration"] else []) + \
             ([f"{cfg['record_max_size']} bytes"] if cfg["record_max_size"] else [])
    if not limits:
        return cfg["record"]
    first, second = (rotated_path(Path(cfg["record"]), k) for k in (0, 1))
    return f"{cfg['record']} in files of at most {' or '.join(limits)}: {first}, {second}, ..."


def _command_text(value) -> str:
    """``value`` as a shell command line gives it to ``-p name:=``: a string shell-quoted (a
    path with a space), an empty one as ``"''"``: the shell makes ``frame_id:=''`` of it, which
    rcl reads as an empty string (``frame_id:=''`` typed in a shell is ``frame_id:=``, which rcl
    refuses: every recorded command, with its default frame_id, failed so)."""
    if isinstance(value, str):
        return shlex.quote(value) if value else "\"''\""
    return _param_text(value)


def _param_text(value) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return value if value else "''"
    return repr(value)


def log_end(node) -> None:
    """Log the message of the run's end status (``run ended: duration 30 s reached, 30.000000 s
    of signal (450000 samples) published``) at its level: a run without a recording that reached
    its ``duration`` left no line at all in the log.  None for a run stopped before its first
    table (no end status) or one whose solver diverged (its error was logged when it happened).
    Under the node's own logger name, like :func:`log_recording`, by :func:`log_the_end`.
    First the input rejections that a reason's throttle still held back (``_log_held_rejections``)."""
    log = rclpy.logging.get_logger(node.get_logger().name)
    node._log_held_rejections(log, at_end=True)
    if node.end_status is None or node.end_status[0] == "diverged":
        return
    _reason, level, message = node.end_status
    (log.info, log.warning, log.error)[min(int(level), 2)](message)


def log_recording(node) -> None:
    """Log where the node's closed recording went, by :func:`log_the_end`.  Under the node's own
    logger name (``rig1.bearing_sim`` in namespace rig1), like its other lines: with nodes in
    several namespaces, ``bearing_sim`` did not say which one's recording it was."""
    from ..recording.recorder import files_text, sizes_text

    recorder = node.recorder
    if recorder is None:
        return
    st = recorder.status
    log = rclpy.logging.get_logger(node.get_logger().name)
    if not st["ok"]:
        log.error(f"recording: {st['error']}")
        return
    text = f"recording {files_text(st)}: {st['messages']} messages, {sizes_text(st)}, {st['dropped']} dropped"
    if st["dropped"]:
        log.warning(f"{text}: the disk did not keep up, the file has gaps")
    else:
        log.info(text)


# s the node pauses after its last log lines where something subscribes to /rosout (log_the_end)
ROSOUT_GRACE_S = 0.3


def log_the_end(node) -> None:
    """The node's last log lines, once it stopped (``node.stop``: its recording closed): its end
    status (``log_end``) and where its recording went (``log_recording``).  Before the
    middleware's teardown (``close_node``), which may hang: a hang there lost them.  The node's
    logger still has its /rosout publisher then, so they go to /rosout too; where the context is
    already shut down, rcl would say "Failed to publish log message to rosout" for each: then
    after ``destroy_node``, by ``close_node``.  Where anything subscribes to /rosout, the node
    then pauses ``ROSOUT_GRACE_S`` (s) before its teardown."""
    if node is not None and node.context.ok():
        log_end(node)
        log_recording(node)
        node.end_logged = True
        # A /rosout subscriber in another process takes a line only while the writer that sent it
        # exists: with the node destroyed at once, the last lines were lost to it under load (2 of
        # 6 runs beside three CPU hogs; none of 14 with this pause).  rcl keeps that writer to itself,
        # so its acknowledgements cannot be waited for as the topics' are (_deliver_the_end).
        try:
            if node.count_subscribers("/rosout"):
                time.sleep(ROSOUT_GRACE_S)
        except Exception:  # noqa: BLE001 - the context went away (a signal): nothing to wait for
            if node.context.ok():
                raise


def close_node(node, status: int = 0, said=()) -> None:
    """The end of a command that ran ``node`` (None: it was not built), once it stopped and said
    its last lines (``log_the_end``, its ``error:`` line): the node destroyed, rclpy shut down,
    under the teardown watchdog, so that a hang in DDS's teardown can neither keep the process
    from its exit nor change its exit ``status`` (``teardown.teardown_watchdog``: ``said``, the
    lines the command says after this)."""
    with teardown_watchdog(node.get_logger().name if node is not None else NODE_NAME, status, said):
        if node is not None:
            node.destroy_node()
            if not node.end_logged:
                log_end(node)
                log_recording(node)
        rclpy.try_shutdown()


def failure_recording_text(node) -> str:
    """``; recorded to PATH, finalised`` after a divergence's line, or "" without a recording."""
    from ..recording.recorder import files_text

    if node.recorder is None:
        return ""
    st = node.recorder.status
    return f"; recorded to {files_text(st)}, finalised" if st["ok"] else f"; recording: {st['error']}"


def say_held(node):
    """``CommandSignals.on_held`` for the node (``node()``, None before it is built): a Ctrl-C
    (or SIGTERM) while it shuts down, said once in its log.  Such a signal once raised
    KeyboardInterrupt into the wait for the recording's writer, and the file was lost (no footer);
    the node finishes instead, then exits 130 (143)."""
    said = []

    def say(signum, done):
        if said:
            return                  # once: a user who presses Ctrl-C again reads it once
        said.append(signum)
        how = SIGNAL_NAMES[signum]
        if done:
            what = "has shut down and exits"
        else:
            what = ("finalises its recording and " if node() is not None and node().recorder is not None
                    else "") + "shuts down first, then exits"
        # a child of the node's logger: the node's own may have lost its /rosout publisher with
        # the node (rcl would add "Failed to publish log message to rosout")
        name = node().get_logger().name if node() is not None else NODE_NAME
        rclpy.logging.get_logger(f"{name}.shutdown").warning(
            f"{how} during shutdown: the node {what} with status {EXIT_INTERRUPTED[signum]}")

    return say


def spin_node(node, signals=None) -> None:
    """Serve ``node`` until its simulation ends, rclpy shuts down (SIGTERM) or Ctrl-C
    (KeyboardInterrupt, raised to the caller); with ``signals`` (teardown.CommandSignals), until
    the first signal.  The caller then calls ``node.stop()``."""
    from rclpy._rclpy_pybind11 import RCLError
    from rclpy.executors import SingleThreadedExecutor

    try:
        executor = SingleThreadedExecutor(context=node.context)
    except RCLError:
        if node.context.ok():
            raise
        return                      # a signal came between building the node and serving it
    executor.add_node(node)
    node.start()
    try:
        # a short timeout: the end of ``duration`` (set by the sim thread), or a signal, is
        # noticed at once
        while node.context.ok() and not node.finished.is_set() and (signals is None or signals.first is None):
            executor.spin_once(timeout_sec=0.1)
    finally:
        executor.remove_node(node)
        executor.shutdown(timeout_sec=0)


def stop_reason(signals) -> str:
    """Why the run ends where it did not end by itself (``messages.END_REASONS``), for the node's
    end status: the signal that ended it (``SIGTERM``), else ``stopped``."""
    import signal

    return signal.Signals(signals.first).name if signals.first is not None else "stopped"


def build_node(factory):
    """``factory()``, the node, with a signal during start-up taken as what it is.  Ctrl-C or
    SIGTERM while the node is being built (loading or, on a cold cache, compiling its kernels:
    up to ~20 s) shuts rclpy's context down, and rcl then refuses the next publisher with an
    RCLError: an interruption (ExternalShutdownException), not a mistake in the arguments."""
    from rclpy._rclpy_pybind11 import RCLError
    from rclpy.executors import ExternalShutdownException

    try:
        return factory()
    except RCLError:
        if rclpy.ok():
            raise
        raise ExternalShutdownException() from None


def ros_arguments_error(exc, given_as=None) -> UserError:
    """The one-line UserError for ROS arguments that rcl cannot parse (RCLError from
    ``rclpy.init``) or does not know (UnknownROSArgsError from the node): rcl's reason without
    its source locations, and what is allowed.  ``given_as``: {copy's path: path given} of the
    ``--params-file`` pipes that ``bearing-sim node`` read into memory
    (``cli._params_files_in_memory``): rcl names the copy, ``/proc/self/fd/N``, the line the
    path the user gave."""
    import re

    from rclpy._rclpy_pybind11 import UnknownROSArgsError

    text = (str(exc).splitlines() or [exc.__class__.__name__])[0]
    text = re.sub(r",? at /\S+:\d+", "", text).removeprefix("failed to initialize rcl: ")
    if isinstance(exc, UnknownROSArgsError):
        text = "unknown " + text.strip("[]").replace("'", "")      # "['--bogus']" -> "unknown --bogus"
    for copy, given in (given_as or {}).items():
        text = re.sub(re.escape(copy) + r"(?!\d)", lambda _m, given=given: given, text)
    return UserError(f"ROS arguments: {text}; after --ros-args come -p name:=value (an empty string: "
                     f"name:=\"''\"), -r from:=to, --params-file FILE, --log-level LEVEL")


def stray_arguments_error(program: str, stray: list) -> UserError:
    """The one-line UserError for arguments that are not ROS arguments (rclpy ignores them
    without a word): the node takes its settings as parameters after --ros-args."""
    return UserError(f"{program}: unrecognized arguments: {' '.join(stray)} (ROS arguments follow --ros-args)")


def main(argv=None, params_files_given_as=None) -> int:
    """``bearing_sim_node`` / ``bearing-sim node``: run the node until ``duration``, Ctrl-C or
    SIGTERM, and end the process (``teardown.CommandSignals.exit``): exit status 0, or 2 with one
    line for a bad parameter, scene or ROS argument or a recording that failed on the way (disk
    full: the node published on), or 130 / 143 for a signal while it shut down.  An internal
    error is raised.  ``params_files_given_as``: see ``ros_arguments_error``."""
    from rclpy._rclpy_pybind11 import RCLError, UnknownROSArgsError
    from rclpy.executors import ExternalShutdownException
    from rclpy.signals import SignalHandlerOptions
    from rclpy.utilities import remove_ros_args

    # those the command installed before its imports, or now
    signals = command_signals()
    args = list(sys.argv) if argv is None else ["bearing_sim_node", *argv]
    node = None
    status = 0
    error = None
    signals.on_held = say_held(lambda: node)
    try:
        try:
            signals.check()             # a signal while Python imported numpy, numba, rclpy
            # the signals are CommandSignals' alone: rclpy's would shut its context down under the
            # running node at the first one, and raise KeyboardInterrupt wherever Python is
            clear_before_start(say_on_stderr)     # else a killed node's half-made port hangs us
            rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
            stray = remove_ros_args(args)[1:]
            if stray:           # `ros2 run ... bearing_sim_node --bogus` ran the node regardless
                raise stray_arguments_error(Path(args[0]).name, stray)
            node = build_node(BearingSimNode)
        except (RCLError, UnknownROSArgsError) as exc:
            if isinstance(exc, RCLError) and rclpy.ok():
                raise                   # not the arguments: rclpy.init went through
            raise ros_arguments_error(exc, params_files_given_as) from None
        signals.check()                 # ... or while the node was built (its kernels loading)
        spin_node(node, signals)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except UserError as exc:
        say_on_stderr(f"error: {exc}")
        status = 2
    finally:
        signals.shutting_down()         # a signal from here on is held, said, and exits 130 / 143
        said = []
        if node is not None:
            node.stop(reason=stop_reason(signals))      # the recording is closed here, before anything can hang
            error = node.error
            log_the_end(node)
        # the command's outcome before the middleware's teardown, which may hang (close_node)
        if error is not None:
            status, said = 1, [f"internal error: {error.__class__.__name__}: {error}"]
        elif sys.exc_info()[1] is not None:
            pass                        # on its way out (an internal error): close_node takes its status
        elif status == 0 and node is not None and node.failure is not None:
            # said in the log as it happened; here the line a script sees, and where the file stands
            say_on_stderr(f"error: {node.failure.worded(node._settings)}{failure_recording_text(node)}")
            status = 2
        elif status == 0 and node is not None and node.recorder is not None and node.recorder.error:
            # published in full, but the file is not: a script that checks the status must know
            say_on_stderr(f"error: {node.recorder.error}")
            status = 2
        close_node(node, status, said)
    if error is not None:
        raise error
    # where the user insisted (a second Ctrl-C), 130 as the shell says; the recording is complete
    # all the same.  Ends the process: a signal until its very end is not lost
    signals.exit(status)


if __name__ == "__main__":
    sys.exit(main())
