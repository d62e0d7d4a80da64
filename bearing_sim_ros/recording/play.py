"""``bearing-sim play``: republish a recording on its topics, with its types and QoS.

The node is named ``bearing_sim`` like the live node and publishes every recorded topic under its
recorded (fully qualified) name with the recorded type and the QoS read from the channel's
``offered_qos_profiles`` (above 1x a keep-last depth times ``--rate``, so that it holds as much
wall-clock time as recorded), paced by the log times (= the live node's publish times) divided by
``--rate``.  Messages keep their recorded stamps, so a subscriber sees what it would have seen
from the live node: contiguous waveform tables, state, diagnostics.

``--loop`` repeats the recording with every header stamp (and log time) moved on by the
recording's length, measured on the waveform tables (last stamp + last width / sample rate -
first stamp), so the tables stay contiguous across the seam and time never goes back.  A
recording that spans no time (every message at one log time, no table with a sample rate) has
no length to move on by: ``--loop`` refuses it rather than repeat it without a pause.  Play
refuses, looped or not, a recording with nothing on the topics it plays (all on ``/clock``, with
``--clock``).
A split recording (the node's ``record_max_duration`` / ``record_max_size``) plays as one: its
pieces one after the other (their tables continue each other to the nanosecond), given as files
or by the name it was recorded to (``reader.open_recording``); ``--loop`` repeats them all.
A truncated file (killed hard: no footer) plays up to its last complete chunk, said in one line.
``--clock`` publishes ``/clock`` with the recording's time (log time, shifted like the stamps)
before each new instant, for nodes running with ``use_sim_time``.  A recorded ``/clock`` topic
is replaced by the generated one then.

Recordings made by ``bearing-sim render`` also hold ``shaft_speed`` and ``load``: the operating
point in use.  Played into a graph with a live node, they drive it through the same profile.

Before the first message, play waits up to ``--wait`` seconds (``WAIT_FOR_SUBSCRIBERS`` by
default) for a subscriber to appear: messages sent before a subscriber is matched are lost for it.
After ``WAIT_NOTICE`` s without one it says that it is waiting, and at the end that it plays anyway.
Discovery on one machine usually takes well under a second, but when a participant's first
announcements are missed it waits for the next periodic one (Fast DDS: every 3 s).  In this
project's test runs that happened to about 1 play in 3.  With the former 3 s default about 1 play
in 10 then started just before the match and its subscriber missed the first ~50 ms; hence 5 s.
A test or pipeline that needs every message even after two missed periods passes a longer
``--wait``.
"""
from __future__ import annotations

import json
import math
import sys
import threading
import time

from ..errors import UserError
from ..messages import DISCOVERY_GRACE_S, END_DELIVERY_GRACE_S, deliver_the_end
from ..stale_dds_ports import clear_before_start
from ..teardown import say, say_on_stderr, teardown_watchdog
from ..waveform import NS
from .reader import deserialize, get_message, open_recording, recorded_sample_rate
from .schemas import qos_from_yaml

WAIT_FOR_SUBSCRIBERS = 5.0    # s, the default of --wait: one missed 3 s announcement period and margin
WAIT_NOTICE = 1.0             # s without a subscriber before saying that play is waiting for one
WAVEFORM_TYPE = "sensor_msgs/msg/PointCloud2"
# --rate, a multiple of real time: 0.01 plays a 10 ms table interval in 1 s (below it a recording's
# seconds become hours: 1e-9 was accepted, and one second took 31 years); 100 plays a second in 10
# ms.  Where a rate asks for more messages a second than play can send, it sends them as fast as
# it can (``_sleep_until`` does not pause once it is behind), so a higher bound would promise
# nothing more
PLAY_RATE_RANGE = (0.01, 100.0)
# --wait, s: an hour is far beyond any discovery (seconds) and covers a subscriber started by hand;
# 1e300 was taken, a wait that never ends in practice, where a mistyped value should be said
PLAY_WAIT_MAX = 3600.0


def _shift_stamp(msg, offset_ns: int) -> None:
    """Move ``header.stamp`` (and ``Clock.clock``) by ``offset_ns``."""
    for attr in ("header", "clock"):
        obj = getattr(msg, attr, None)
        if obj is None:
            continue
        stamp = obj.stamp if attr == "header" else obj
        t = int(stamp.sec) * NS + int(stamp.nanosec) + offset_ns
        stamp.sec, stamp.nanosec = int(t // NS), int(t % NS)


class _Span:
    """Length of a recording for looping, from its first waveform topic's tables."""

    def __init__(self, sample_rate: float | None):
        self.topic = None
        self.first = self.last = None
        self.last_width = 0
        self.samples = 0
        self.sample_rate = sample_rate

    def see(self, topic: str, msg) -> None:
        if self.topic is None:
            self.topic = topic
        if topic != self.topic:
            return
        t = int(msg.header.stamp.sec) * NS + int(msg.header.stamp.nanosec)
        if self.first is None:
            self.first = t
        self.last = t
        self.last_width = int(msg.width)
        self.samples += int(msg.width)

    def length_ns(self, start_ns: int, end_ns: int) -> int:
        """The recording's length (ns) for ``--loop``; 0 when it has none (every message at one
        log time and no table with a sample rate): looping that would never pause."""
        fs = self.sample_rate if self.first is not None else None
        if self.first is not None and not fs and self.last > self.first:
            fs = (self.samples - self.last_width) * NS / (self.last - self.first)
        if not fs:
            return end_ns - start_ns + 1 if end_ns > start_ns else 0
        return self.last - self.first + int(round(self.last_width * NS / fs))


def play(path, rate: float = 1.0, loop: bool = False, clock: bool = False,
         wait_for_subscribers: float = WAIT_FOR_SUBSCRIBERS, log=None, stop=None) -> int:
    """Republish ``path`` (one file, or the pieces of a split recording: ``open_recording``);
    returns the number of messages published.  ``rate``: a multiple of real time, within
    ``PLAY_RATE_RANGE``.  ``wait_for_subscribers``: s, 0 to ``PLAY_WAIT_MAX``.  ``stop``: a
    ``threading.Event`` that ends playback between two messages (set by the signal handlers)."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    lo, hi = PLAY_RATE_RANGE
    if not lo <= rate <= hi:            # NaN too
        raise UserError(f"--rate = {rate!r}: expected a multiple of real time in [{lo:g}, {hi:g}]")
    if not 0 <= wait_for_subscribers <= PLAY_WAIT_MAX:         # NaN too
        raise UserError(f"--wait = {wait_for_subscribers!r}: expected seconds in [0, {PLAY_WAIT_MAX:g}]")
    # teardown.say: a line written as the terminal closes goes nowhere (an EIO was an internal error)
    log = log or (lambda text: say(text, sys.stderr))
    stop = stop or threading.Event()
    running = lambda: rclpy.ok() and not stop.is_set()  # noqa: E731
    rec = open_recording(path)
    path = rec.path                      # what messages call it: one file, or a split recording's pieces
    try:
        for note in rec.notes:
            log(f"play {path}: {note}")
        if rec.recovered:               # it names the file cut: the recording's last
            log(f"play {rec.recovered}")
        topics = rec.topics()
        if not topics or rec.message_count == 0:
            raise UserError(f"{path}: the recording holds no messages")
        classes = {}
        for t, c in topics.items():
            try:
                classes[t] = get_message(c.msg_type)
            except UserError as exc:        # which file and topic: another tool's type
                raise UserError(f"{path}: {t}: {exc}") from None
        sample_rate = recorded_sample_rate(rec)
        played = [c for t, c in topics.items() if not (clock and t == "/clock")]
        if not any(c.count for c in played):
            # --loop went round this empty loop at 100 % CPU forever
            raise UserError(f"{path}: nothing to play: its messages are all on /clock, which --clock "
                            "replaces; play it without --clock")
        if loop and rec.end_ns == rec.start_ns and not (
                sample_rate and any(c.msg_type == WAVEFORM_TYPE for c in played)):
            raise UserError(_no_length(path, rec.message_count))
        for info in played:
            _check_topic_name(path, info.topic)

        from rclpy.signals import SignalHandlerOptions

        # our own handlers (play_command) set ``stop``: the loop ends between two messages and
        # the node is destroyed and the context shut down in order
        clear_before_start(say_on_stderr)
        rclpy.init(args=None, signal_handler_options=SignalHandlerOptions.NO)
        node = rclpy.create_node("bearing_sim")
        try:
            pubs = {}
            for topic, info in sorted(topics.items()):
                if clock and topic == "/clock":
                    continue
                qos = qos_from_yaml(info.qos_yaml) or QoSProfile(depth=10)
                if rate > 1.0 and qos.history == HistoryPolicy.KEEP_LAST:
                    # the recorded depth is the node's 1 s of batches; played faster, the same
                    # depth holds less time for a subscriber that stalls (0.25 s at 4x: a monitor
                    # stopped for 0.8 s lost tables), so it holds the same wall-clock time
                    qos.depth = math.ceil(qos.depth * rate)
                pubs[topic] = node.create_publisher(classes[topic], topic, qos)
            clock_pub = None
            if clock:
                from rosgraph_msgs.msg import Clock

                clock_pub = node.create_publisher(
                    Clock, "/clock", QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                                                reliability=ReliabilityPolicy.RELIABLE,
                                                durability=DurabilityPolicy.VOLATILE))
            pieces = f" in {len(rec.paths)} files" if len(rec.paths) > 1 else ""
            log(f"play {path}: {rec.message_count} messages{pieces} on {len(pubs)} topic{'' if len(pubs) == 1 else 's'}, "
                f"{_length_said(rec, classes, sample_rate)} at {rate:g}x"
                + (", looping" if loop else "") + (", publishing /clock" if clock else ""))
            _wait_for_subscribers(pubs, wait_for_subscribers, running, lambda text: log(f"play {path}: {text}"))

            published = 0
            offset = 0
            span = _Span(sample_rate)
            wall0 = time.perf_counter()
            rec0 = rec.start_ns
            last_clock = None
            while running():
                for topic, msg_type, log_ns, data in rec.messages():
                    if topic not in pubs:
                        continue
                    t_rec = log_ns + offset
                    _sleep_until(wall0 + (t_rec - rec0) / NS / rate, running)
                    if not running():
                        break
                    if clock_pub is not None and (last_clock is None or t_rec > last_clock):
                        from rosgraph_msgs.msg import Clock

                        cmsg = Clock()
                        cmsg.clock.sec, cmsg.clock.nanosec = int(t_rec // NS), int(t_rec % NS)
                        clock_pub.publish(cmsg)
                        last_clock = t_rec
                    if offset == 0:
                        # first pass: the recorded bytes go out as they are
                        if loop and msg_type == WAVEFORM_TYPE and span.topic in (None, topic):
                            span.see(topic, deserialize(rec.path, topic, msg_type, log_ns, data, classes[topic]))
                        pubs[topic].publish(data)
                    else:
                        msg = deserialize(rec.path, topic, msg_type, log_ns, data, classes[topic])
                        _shift_stamp(msg, offset)
                        pubs[topic].publish(msg)
                    published += 1
                if not loop or not running():
                    break
                length = span.length_ns(rec.start_ns, rec.end_ns)    # measured on the first pass
                # what the checks above cannot see (a summary that counts messages the file does
                # not hold; tables of no width): the loop would spin without a pause
                if not published:
                    raise UserError(f"{path}: nothing to play: no message found on its topics")
                if length <= 0:
                    raise UserError(_no_length(path, published))
                offset += length
            # let reliable subscribers receive the tail: the node's grace, the frequent topics
            # first (/clock, then by their recorded messages)
            frequent_first = sorted(pubs, key=lambda topic: -topics[topic].count)
            deliver_the_end(([clock_pub] if clock_pub is not None else []) + [pubs[t] for t in frequent_first],
                            END_DELIVERY_GRACE_S, running)
            log(f"play {path}: {'stopped after' if stop.is_set() else 'published'} {published} messages")
            return published
        finally:
            # the last thing: its lines are said, every message published (teardown_watchdog)
            with teardown_watchdog(f"play {path}"):
                node.destroy_node()
                if rclpy.ok():
                    rclpy.shutdown()
    finally:
        rec.close()


def _length_said(rec, classes: dict, sample_rate: float | None) -> str:
    """The recording's length as its start line says it: the signal's, from the first waveform
    table's stamp to the end of the last (its stamp + its width / ``sample_rate``), as ``report``'s
    ``duration_s`` and ``render`` say it and ``--loop`` moves on by (``5.00 s of signal``); the
    log times' span where it has no table or no sample rate (``0.50 s of log time``).  The log
    times of a 5 s recording span a batch less (a table is logged as its batch ends): "4.99 s"
    was said of it."""
    roles = {}
    try:
        roles = json.loads(rec.metadata.get("topics") or "{}")
    except ValueError:
        pass
    waveforms = sorted(t for t, c in rec.topics().items() if c.msg_type == WAVEFORM_TYPE and c.count)
    named = roles.get("accel") if isinstance(roles, dict) else None
    topic = named if named in waveforms else (waveforms[0] if waveforms else None)
    ends = rec.first_and_last(topic) if topic and sample_rate else None
    if ends:
        (first_ns, first), (last_ns, last) = ends
        first = deserialize(rec.path, topic, WAVEFORM_TYPE, first_ns, first, classes[topic])
        last = deserialize(rec.path, topic, WAVEFORM_TYPE, last_ns, last, classes[topic])
        stamp = lambda msg: int(msg.header.stamp.sec) * NS + int(msg.header.stamp.nanosec)  # noqa: E731
        return f"{(stamp(last) - stamp(first)) / NS + int(last.width) / sample_rate:.2f} s of signal"
    return f"{(rec.end_ns - rec.start_ns) / NS:.2f} s of log time"


def _check_topic_name(path, topic: str) -> None:
    """A recorded topic that ROS 2 cannot publish on (another tool's name: ``/1abc``, a space)
    is a one-line UserError naming ``path`` and the topic, before the node starts: rclpy's
    InvalidTopicNameException was a traceback of several lines."""
    from rclpy.exceptions import InvalidTopicNameException
    from rclpy.validate_topic_name import validate_topic_name

    try:
        validate_topic_name(topic)
    except InvalidTopicNameException as exc:
        # its text: "Invalid topic name: <why>:", then the name and a caret under the fault
        why = str(exc).splitlines()[0].split(": ", 1)[-1].rstrip(":")
        raise UserError(f"{path}: topic {topic!r} cannot be published in ROS 2 ({why}); "
                        "give a recording whose topic names ROS 2 allows") from None


def _no_length(path, messages: int) -> str:
    """Why ``--loop`` cannot repeat ``path``: it has no length to move the stamps on by."""
    return (f"{path}: --loop: the recording spans no time ({messages} message{'' if messages == 1 else 's'} at "
            "one log time, no waveform table with a sample rate), so the loop would repeat without a "
            "pause; play it without --loop")


def _wait_for_subscribers(pubs: dict, timeout: float, running, log) -> None:
    """Wait up to ``timeout`` s for a first subscriber; once one appears, until the number of
    matched subscriptions has not changed for ``DISCOVERY_GRACE_S`` s (a subscriber's topics
    match one by one), at most ``timeout`` s more.  After ``WAIT_NOTICE`` s without one it
    ``log``s once that it is waiting (a silent 5 s looked like a hung command), then whether one
    came or it plays anyway."""
    start = time.perf_counter()
    first_match = stable_since = counts = None
    noticed = False
    while running():
        now = time.perf_counter()
        new = tuple(p.get_subscription_count() for p in pubs.values())
        if any(new):
            if first_match is None:
                first_match = now
                if noticed:
                    log(f"a subscriber matched after {now - start:.1f} s")
            if new != counts:
                counts, stable_since = new, now
            elif now - stable_since >= DISCOVERY_GRACE_S:
                return
            if now - first_match >= timeout:
                return
        elif now - start >= timeout:
            if timeout > 0:
                log(f"no subscriber after {timeout:g} s; playing anyway (to nobody until one matches)")
            return
        elif not noticed and now - start >= WAIT_NOTICE:
            log(f"no subscriber yet; waiting up to {timeout:g} s in all before publishing "
                "(--wait 0 starts at once)")
            noticed = True
        time.sleep(0.02)


def _sleep_until(target: float, running) -> None:
    while True:
        delay = target - time.perf_counter()
        if delay <= 0 or not running():
            return
        time.sleep(min(delay, 0.1))


def play_command(args) -> int:
    """CLI entry: ``bearing-sim play F.mcap [F_001.mcap ...] [--rate X] [--loop] [--clock] [--wait S]``.
    Ctrl-C and SIGTERM stop playback cleanly (exit status 0; 130 / 143 for one more while it
    shuts down); on success the process ends here (``CommandSignals.exit``)."""
    from ..teardown import command_signals

    # the command's handlers from its first line (cli.SIGNAL_COMMANDS): a flag, not an
    # exception (one raised inside rclpy's C calls comes out as a TypeError), which the loop
    # checks between messages
    signals = command_signals()
    play(args.file, rate=float(args.rate), loop=bool(args.loop), clock=bool(args.clock),
         wait_for_subscribers=float(args.wait), stop=signals.stopped)
    # everything is published, the node destroyed and the recording closed: skip the
    # interpreter's finalisation, where the middleware's static objects and threads are torn
    # down, so that it cannot be where `play` hangs (see module ``teardown``)
    signals.shutting_down()
    signals.exit(0)
