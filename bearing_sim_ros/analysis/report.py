"""``bearing-sim report F.mcap --out DIR``: plots and a short summary of a recording.

Writes to DIR:

- ``waveform.png``: the accelerometer channels, whole recording and a zoom on a few fault periods;
- ``spectrum.png``: power spectral density of each channel (Welch);
- ``envelope.png``: envelope spectrum (``analysis.envelope``) with the fault frequencies of the
  recorded bearing marked, and the verdict;
- ``orders.png`` (where the fault lines move and ``state`` tracks the shaft): the envelope
  spectrum in orders of the shaft (``analysis.orders``), the verdict's spectrum then;
- ``operating_point.png``: shaft speed and radial load over time (not drawn when neither is
  recorded and there is no scene: ``plots_not_drawn`` in the summary says why);
- ``cage.png`` (when ``state`` was recorded): cage speed against pure rolling and the cage slip
  ratio, plus the skid ratios the skidding tier reports in ``/diagnostics`` when present;
- ``timeline.png``: the verdict over time: the same detector in consecutive windows
  (``--window``), each window's prominences against the threshold, the faults present by the
  recorded ``/diagnostics`` (the ground truth) and the defect sizes;
- ``summary.md`` and ``summary.json``: how the recording was made, its length (the recorded
  signal's: ``duration_s``), waveform statistics, fault lines against theory, the verdict
  against the faults expected (``expected_defects``: those the recorded ground truth has in the
  analysed stretch, else the scene's), whether the waveform tables are contiguous, and the
  timeline scored against the ground truth (fault onset, first detection, latency).

The bearing comes from the scene text in the ``bearing_sim`` metadata record, so a report needs
nothing but the file.  A split recording (the node's ``record_max_duration`` /
``record_max_size``) is reported as one: its pieces, or the name it was recorded to
(``recording.reader.open_recording``); ``files`` in the summary lists them.  A truncated file
(killed hard: no footer), alone or a split recording's last piece, is reported up to its last
complete chunk, said in ``recovered`` (what is lost) and on the command line.  The waveform,
spectra and the whole-recording verdict use at most ``MAX_ANALYSIS_S`` seconds of signal (the
start); the verdict timeline covers the whole recording (the envelope channel past that start is
kept in a temporary file in DIR as the recording is read, ``_Spool``: the file is read once).

Time bases: signal time is seconds after the first waveform sample (``header.stamp`` of the
first table).  A ``/diagnostics`` message is stamped with the end of the last batch published,
and its ``faults_present`` / ``defect_sizes`` are those of that batch's last sample, in the live
node (whose simulator computes ahead of what it publishes) as in ``render``.  Those messages
come at 1 Hz; their ``fault_onsets_s`` give when each fault appeared to the sample
(``bearing_sim_ros.ground_truth``), and in a recording made before that key 1 s is the resolution
of the ground truth.
"""
from __future__ import annotations

import itertools
import json
import math
import numbers
import tempfile
from array import array
from pathlib import Path

import numpy as np

from .. import ground_truth
from ..errors import UserError
from ..paths import output_folder, replace_file, save_figure, writing_into
from ..recording.reader import open_recording
from ..waveform import NS, from_pointcloud2
from .envelope import (DETECTION_THRESHOLD, FAULT_LINES, LINE_LABELS, STEADY_LINES, band_words, borrowed_text,
                       diagnose, envelope_band, envelope_spectrum, no_defect_note, spread, statistics,
                       with_cage)
from .orders import order_diagnose

MAX_ANALYSIS_S = 120.0
DEFAULT_WINDOW_S = 1.0        # s: the verdict timeline's windows (the detector's own segment length)
WINDOW_RANGE_S = (0.5, MAX_ANALYSIS_S)   # s: below 0.5 s the lines' +-20 Hz neighbourhood holds too few bins
LINE_COLOURS = {"bpfo": "tab:red", "bpfi": "tab:green", "2bsf": "tab:purple", "ftf": "tab:orange"}
RPM = 60.0 / (2.0 * math.pi)


# ---- reading ---------------------------------------------------------------------------------
class _Data:
    """What the report needs from a recording, as arrays; ``spool`` (a ``_Spool``, or None to
    leave them out) takes the envelope channel's samples past those held (``MAX_ANALYSIS_S``)."""

    def __init__(self, rec, spool=None):
        from ..recording.reader import deserialize, get_message, recorded_sample_rate

        topics = rec.topics()
        self.topics = {t: {"type": c.msg_type, "messages": c.count} for t, c in topics.items()}
        self.metadata = rec.metadata
        roles = self._roles(self.metadata)
        self.accel_topic = self._find(topics, "accel", "sensor_msgs/msg/PointCloud2", roles)
        state_topic = self._find(topics, "state", "sensor_msgs/msg/JointState", roles)
        speed_topic = self._find(topics, "shaft_speed", "std_msgs/msg/Float64", roles)
        load_topic = self._find(topics, "load", "geometry_msgs/msg/WrenchStamped", roles)
        wanted = [t for t in (self.accel_topic, state_topic, speed_topic, load_topic,
                              self._find(topics, "diagnostics", "diagnostic_msgs/msg/DiagnosticArray", roles))
                  if t]
        classes = {t: get_message(topics[t].msg_type) for t in wanted}
        # what is kept of every message, as machine numbers: as lists of Python floats, ints and
        # (x, y) tuples an hour's (a state at 50 Hz, a command and a load at 100 Hz, a table's
        # stamp) took 90 MB while the file was read; arrays of them take a sixth of that
        chunks, stamps, widths = [], array("q"), array("q")
        self.channels = ()
        self.truncated_analysis = False
        state_t, shaft_w, cage_w, shaft_angle, cage_angle = array("q"), array("d"), array("d"), array("d"), array("d")
        cmd_t, cmd_speed, load_t, load_xy = array("q"), array("d"), array("q"), array("d")   # load_xy: x, y, x, ...
        diag = {}
        tiers = []
        in_signal, truth_raw = [], []
        # how many /diagnostics carry fault frequencies, and each key's count: the keys that not
        # all of them carry are named where the report cannot place the lines without a scene
        frequency_messages, frequency_key_counts = 0, dict.fromkeys(RECORDED_KEYS, 0)
        self.named_scenes = []          # (scene, bearing) the /diagnostics name, in order of appearance
        samples = 0
        fs_meta = recorded_sample_rate(rec)
        held_rate = fs_meta             # Hz: the rate that tells when MAX_ANALYSIS_S are held
        for topic, _type, log_ns, data in rec.messages(topics=wanted):
            # another writer's bytes or tables were a traceback and "internal error"
            msg = deserialize(rec.path, topic, topics[topic].msg_type, log_ns, data, classes[topic])
            if topic == self.accel_topic:
                try:
                    stamp, names, arr = from_pointcloud2(msg)
                except ValueError as exc:     # another tool's point cloud (a lidar's) on .../accel
                    raise UserError(f"{rec.path}: the table on {topic} logged at {log_ns / NS:.9f} s: {exc}; "
                                    "expected the node's waveform tables (README, \"Consuming a waveform table\")") from None
                bad = int(arr.size - np.count_nonzero(np.isfinite(arr)))
                if bad:
                    # NaN samples went through the envelope analysis to a verdict of "healthy"
                    # (infinite ones too, with numpy's "invalid value" warning), exit status 0
                    raise UserError(f"{rec.path}: the table on {topic} logged at {log_ns / NS:.9f} s holds {bad} "
                                    f"non-finite sample{'s' if bad > 1 else ''} (NaN or infinity) of {arr.size}; "
                                    "a waveform is finite numbers, m/s^2: a damaged recording or another writer's")
                if self.channels and tuple(names) != self.channels:
                    # the columns are concatenated: numpy's error was a traceback
                    raise UserError(f"{rec.path}: {topic}: a table's channels ({', '.join(names)}) are not "
                                    f"the first table's ({', '.join(self.channels)})")
                stamps.append(stamp)
                widths.append(arr.shape[0])
                self.channels = tuple(names)
                if fs_meta is None and len(stamps) == 2 and stamps[1] > stamps[0] and widths[0] > 0:
                    # no sample_rate in the metadata (another tool's file, rosbags-convert's): the
                    # first two tables' stamps give it for holding MAX_ANALYSIS_S, where every sample
                    # was held, 1.3 GB of an hour's recording (the rate reported is all tables')
                    held_rate = widths[0] * NS / (stamps[1] - stamps[0])
                if held_rate and samples / held_rate >= MAX_ANALYSIS_S:
                    self.truncated_analysis = True
                    if spool is not None:
                        spool.append(arr[:, self.channels.index(envelope_channel(self.channels))])
                    continue
                chunks.append(arr)
                samples += arr.shape[0]
            elif topic == state_topic:
                if len(msg.velocity) >= 2:
                    state_t.append(_stamp(msg.header.stamp))
                    shaft_w.append(msg.velocity[0])
                    cage_w.append(msg.velocity[1])
                    # the angles for order tracking (NaN where another tool left them out)
                    angles = msg.position[:2] if len(msg.position) >= 2 else (math.nan, math.nan)
                    shaft_angle.append(angles[0])
                    cage_angle.append(angles[1])
            elif topic == speed_topic:
                cmd_t.append(log_ns)
                cmd_speed.append(msg.data)
            elif topic == load_topic:
                load_t.append(_stamp(msg.header.stamp))
                load_xy.extend((msg.wrench.force.x, msg.wrench.force.y))
            else:
                for key, percent in skid_ratios(msg).items():
                    diag.setdefault(key, []).append((_stamp(msg.header.stamp), percent))
                tier = tier_keys(msg)
                if tier.get("tier"):
                    tiers.append(tier)
                found = signal_frequencies(msg)
                if found:
                    in_signal.append((_stamp(msg.header.stamp), found))
                values = {kv.key: kv.value for status in msg.status for kv in status.values}
                keys_here = [key for key in RECORDED_KEYS if key in values]
                frequency_messages += bool(keys_here)
                for key in keys_here:
                    frequency_key_counts[key] += 1
                named = (values.get(ground_truth.SCENE_KEY), values.get(ground_truth.BEARING_KEY))
                if named[0] is not None and named not in self.named_scenes:
                    self.named_scenes.append(named)
                if ground_truth.FAULTS_KEY in values:
                    truth_raw.append((_stamp(msg.header.stamp), values))
        if not chunks:
            raise UserError(f"{rec.path}: no accelerometer waveform tables (sensor_msgs/msg/PointCloud2 "
                            f"on .../accel) in this recording; topics: {', '.join(sorted(topics)) or 'none'}")
        self.accel = np.concatenate(chunks, axis=0).astype(float)
        self.stamps = np.array(stamps, dtype=np.int64)
        self.widths = np.array(widths, dtype=np.int64)
        self.samples = int(self.widths.sum())     # in every table; self.accel holds the first ones
        if self.samples == 0:
            raise UserError(f"{rec.path}: the waveform tables on {self.accel_topic} hold no samples "
                            f"({len(widths)} tables of width 0)")
        self.sample_rate = fs_meta or self._rate_from_stamps(rec.path)
        self.t0_ns = int(self.stamps[0])
        # the recorded signal's length (s): first stamp to the end of the last table, not the log
        # times' span (the live node logs a table when its batch is complete, a batch after its stamp)
        self.signal_s = (int(self.stamps[-1]) - self.t0_ns) / NS + int(self.widths[-1]) / self.sample_rate
        # signal time (s) of the end of the first samples, those held in self.accel (the analysed stretch)
        self.analysed_end_s = float(sample_times_s([self.accel.shape[0] - 1], self.stamps, self.widths,
                                                   self.sample_rate, self.t0_ns)[0]) + 1.0 / self.sample_rate
        self.gaps = self._gaps()
        self.state_t = np.array(state_t, dtype=float) / NS
        self.shaft_w = np.array(shaft_w, dtype=float)
        self.cage_w = np.array(cage_w, dtype=float)
        self.shaft_angle = np.array(shaft_angle, dtype=float)
        self.cage_angle = np.array(cage_angle, dtype=float)
        self.cmd_t = np.array(cmd_t, dtype=float) / NS
        self.cmd_speed = np.array(cmd_speed, dtype=float)
        self.load_t = np.array(load_t, dtype=float) / NS
        self.load_xy = np.array(load_xy, dtype=float).reshape(-1, 2)
        self.skid = {k: np.array(v, dtype=float) for k, v in diag.items()}
        # the fault frequencies the recording's /diagnostics gave, mean over the recording
        common = set.intersection(*(set(f) for _, f in in_signal)) if in_signal else set()
        self.signal_frequencies = {k: float(np.mean([f[k] for _, f in in_signal])) for k in sorted(common)}
        # ... and each /diagnostics period's, in signal time: (from s, to s, {ftf, bpfo, bpfi: Hz})
        ends = [(ns - self.t0_ns) / NS for ns, _ in in_signal]
        self.signal_frequency_periods = [(0.0 if k == 0 else ends[k - 1], ends[k], f)
                                         for k, (_, f) in enumerate(in_signal)]
        # the ground truth of each /diagnostics, in signal time (s), in stamp order
        parsed = (ground_truth.parse(values, (ns - self.t0_ns) / NS) for ns, values in truth_raw)
        self.truth = sorted((t for t in parsed if t is not None), key=lambda t: t.t)
        self.tiers = tiers
        self.frequency_keys_missing = [key for key, count in frequency_key_counts.items()
                                       if not frequency_messages or count < frequency_messages]

    @staticmethod
    def _roles(metadata: dict) -> dict:
        """Role (``accel``, ``/diagnostics``, ...) -> recorded topic, from the metadata's
        ``topics`` (recordings since 2026-11-25); {} where it is missing or unreadable."""
        try:
            roles = json.loads(metadata.get("topics") or "{}")
        except ValueError:
            return {}
        return {str(k).strip("/"): str(v) for k, v in roles.items()} if isinstance(roles, dict) else {}

    @staticmethod
    def _find(topics, name, msg_type, roles=None):
        """The topic of role ``name`` and type ``msg_type``: the one the metadata names (a
        remapped topic keeps its role there), else the one whose last name segment is ``name``."""
        named = (roles or {}).get(name)
        if named in topics and topics[named].msg_type == msg_type:
            return named
        for t, c in sorted(topics.items()):
            if t.rstrip("/").split("/")[-1] == name and c.msg_type == msg_type:
                return t
        return None

    def _rate_from_stamps(self, path) -> float:
        """The sample rate (Hz) of a recording without a ``sample_rate`` parameter in its metadata
        (another tool's), from its tables' samples over their stamps' span."""
        rate = (float(self.widths[:-1].sum() * NS / (self.stamps[-1] - self.stamps[0]))
                if self.stamps[-1] != self.stamps[0] else 0.0)
        if not (math.isfinite(rate) and rate > 0):
            # zero or negative, the division and scipy's "fs must be positive" were tracebacks
            why = ("one waveform table" if self.stamps.size < 2 else
                   f"{self.stamps.size} tables whose stamps do not increase ({self.stamps[0]} ns .. "
                   f"{self.stamps[-1]} ns)")
            raise UserError(f"{path}: cannot tell the sample rate from the waveform tables on {self.accel_topic} "
                            f"({why}) and the metadata has no usable sample_rate parameter")
        return rate

    def _gaps(self) -> int:
        """Waveform tables whose stamp is not the previous stamp + width / sample_rate (1 us)."""
        if self.stamps.size < 2:
            return 0
        expected = self.stamps[:-1] + np.round(self.widths[:-1] * NS / self.sample_rate).astype(np.int64)
        return int(np.sum(np.abs(self.stamps[1:] - expected) > 1000))


def envelope_channel(channels) -> str:
    """The channel of the waveform tables (``channels``: their names) that the envelope verdicts
    are of: ``accel_y`` where they have it, else the first."""
    return "accel_y" if "accel_y" in channels else channels[0]


def skid_ratios(diagnostics) -> dict:
    """{key: percent} of the skid ratios in one ``/diagnostics`` message: the skidding tier's
    ``ball_skid_ratio`` and ``cage_skid_ratio`` (percent already, physics/skidding.py)."""
    found = {}
    for status in diagnostics.status:
        for kv in status.values:
            if "skid" in kv.key:
                try:
                    found[kv.key] = float(kv.value)
                except ValueError:
                    pass            # not a number: not a ratio to average
    return found


def signal_frequencies(diagnostics) -> dict:
    """{"ftf", "bpfo", "bpfi"[, "bsf"]: Hz} as the signal has them in one ``/diagnostics``
    message (``cage_hz``, ``bpfo_hz``, ``bpfi_hz``, ``bsf_hz``: ``recording.render.PeriodMeans``);
    {} in a recording made before the first three, without "bsf" in one made before ``bsf_hz``
    (then the ball's line is placed at pure rolling)."""
    keys = {"cage_hz": "ftf", "bpfo_hz": "bpfo", "bpfi_hz": "bpfi", "bsf_hz": "bsf"}
    found = {keys[kv.key]: kv.value for status in diagnostics.status for kv in status.values if kv.key in keys}
    try:
        found = {k: float(v) for k, v in found.items()}
    except ValueError:
        return {}
    if not all(math.isfinite(v) for v in found.values()):
        # "nan" or "inf" (another writer's) places no line: taken, one such message made the
        # mean over the recording NaN, and the report ended in an IndexError, "internal error"
        return {}
    return found if {"ftf", "bpfo", "bpfi"} <= set(found) else {}


def tier_keys(diagnostics) -> dict:
    """The model-tier keys of one ``/diagnostics`` message (``recording.render.TIER_KEYS``:
    ``tier``, ``tier_switches``, ``last_tier_switch``, ...), as text; {} when it has none."""
    from ..recording.render import TIER_KEYS

    return {kv.key: kv.value for status in diagnostics.status for kv in status.values
            if kv.key in TIER_KEYS}


def tier_history(metadata: dict, tiers: list) -> dict:
    """What ran: the tier the recording started with (its metadata), the tiers that
    ``/diagnostics`` reported in order of appearance, and the switches (count, latest)."""
    seen = [metadata["tier"]] if metadata.get("tier") else []
    for t in tiers:
        if not seen or seen[-1] != t["tier"]:
            seen.append(t["tier"])
    last = tiers[-1] if tiers else {}
    try:
        switches = int(last.get("tier_switches", ""))
    except ValueError:
        switches = None                 # a recording from before the key, or none reported
    return {"tiers": seen, "tier_switches": switches,
            "last_tier_switch": last.get("last_tier_switch", "none") if switches else "none"}


def _stamp(stamp) -> int:
    return int(stamp.sec) * NS + int(stamp.nanosec)


def _scene_from_metadata(meta: dict):
    """(the recording's Scene or None, why None: "" when read)."""
    from ..scene import load_yaml, scene_from_dict

    text = meta.get("scene_yaml", "")
    if not text:
        return None, "the recording has no bearing_sim scene"
    try:
        return scene_from_dict(load_yaml(text), name=meta.get("scene", "scene"), source_text=text), ""
    except Exception as exc:  # noqa: BLE001 - a scene this version cannot read: report without it
        return None, f"this version cannot read its scene: {(str(exc).splitlines() or [type(exc).__name__])[0]}"


# ---- verdict over time -------------------------------------------------------------------------
def window_bounds(samples: int, sample_rate_hz: float, window_s: float) -> list:
    """Consecutive, non-overlapping windows of ``window_s`` seconds over ``samples`` samples at
    ``sample_rate_hz``, as (first, end) sample indices.  Fewer samples than two windows: one
    window, the whole signal.  Otherwise a rest shorter than a window is left out (scored on less
    signal, its prominences would not compare with the others')."""
    n = int(round(window_s * sample_rate_hz))
    if samples < 2 * n:
        return [(0, samples)]
    return [(k * n, (k + 1) * n) for k in range(samples // n)]


def sample_times_s(index, stamps_ns, widths, sample_rate_hz: float, t0_ns: int) -> np.ndarray:
    """Signal time (s after sample 0) of the samples ``index`` (counted over the waveform tables
    in order), from the stamp of each sample's table: times stay right across a lost table."""
    index = np.asarray(index, dtype=np.int64)
    first = np.concatenate(([0], np.cumsum(widths)[:-1]))
    table = np.clip(np.searchsorted(first, index, side="right") - 1, 0, len(first) - 1)
    return (stamps_ns[table] - t0_ns) / NS + (index - first[table]) / sample_rate_hz


def mean_in_window(t_s, values, start_s: float, end_s: float):
    """Mean of ``values`` whose time ``t_s`` (s) lies in [start_s, end_s); without any, the last
    value before ``start_s`` (a command holds until the next); None when there is neither."""
    t_s, values = np.asarray(t_s, dtype=float), np.asarray(values, dtype=float)
    inside = (t_s >= start_s) & (t_s < end_s)
    if inside.any():
        return float(values[inside].mean())
    before = np.flatnonzero(t_s < start_s)
    return float(values[before[-1]]) if before.size else None


def commands_in_effect(t_s, values, start_s: float, end_s: float) -> np.ndarray:
    """The commands (``values`` logged at ``t_s``, s) in effect during [start_s, end_s): those
    logged within it, and the last one before it unless one is logged at its start (``render``
    logs the command of a batch at the batch's first sample, and the one before held only until then)."""
    t_s, values = np.asarray(t_s, dtype=float), np.asarray(values, dtype=float)
    inside = (t_s >= start_s - SLACK_S) & (t_s < end_s - SLACK_S)
    before = np.flatnonzero(t_s < start_s - SLACK_S)
    at_start = bool(np.any(np.abs(t_s - start_s) <= SLACK_S))
    held = values[before[-1:]] if before.size and not at_start else values[:0]
    return np.concatenate((held, values[inside]))


def states_in(t_s, values, start_s: float, end_s: float) -> np.ndarray:
    """The ``state`` values (stamped ``t_s``, s) of the signal in [start_s, end_s): a ``state`` gives
    the speeds at its stamp, the end of its batch, so those stamped in (start_s, end_s]."""
    t_s, values = np.asarray(t_s, dtype=float), np.asarray(values, dtype=float)
    return values[(t_s > start_s + SLACK_S) & (t_s <= end_s + SLACK_S)]


STATES_TO_TELL = 5     # state samples that tell how a stretch's speeds moved (0.1 s at the default 50 Hz)


def line_spread(d: "_Data", start_s: float, end_s: float) -> float:
    """How far the fault lines move over [start_s, end_s) of signal (s), relative (``spread``):
    by the shaft and cage speeds ``state`` gives there (50 Hz by default; the cage's skid moves
    BPFO and BPFI at a steady shaft speed: a load step, a tier switch), the larger; where it gives
    fewer than ``STATES_TO_TELL`` (a low ``state_rate``), by those and the ``shaft_speed``
    commands in effect (the live node applies one 50-70 ms after it logs it, so with ``state``
    enough they are not asked), the largest; with neither, by the BPFO of the recorded
    ``/diagnostics`` periods it overlaps (1 Hz)."""
    cmd_t, state_t = d.cmd_t - d.t0_ns / NS, d.state_t - d.t0_ns / NS
    shaft = states_in(state_t, d.shaft_w, start_s, end_s)
    moved = max(spread(shaft), spread(states_in(state_t, d.cage_w, start_s, end_s)))
    if shaft.size >= STATES_TO_TELL:
        return moved
    commands = commands_in_effect(cmd_t, d.cmd_speed, start_s, end_s)
    if shaft.size or commands.size:
        return max(moved, spread(commands))
    return spread([f["bpfo"] for p0, p1, f in d.signal_frequency_periods
                   if p1 > start_s + SLACK_S and p0 < end_s - SLACK_S])


def at_shaft_speed(periods: list, shaft_hz: float) -> list:
    """The recorded ``/diagnostics`` periods (``recorded_frequencies``) with their frequencies
    moved to the shaft speed ``shaft_hz`` (Hz) at their own cage skid and ball skid: every line is
    the shaft speed times a ratio that the skids set (cage_hz, BPFO = Z cage_hz, BPFI = Z (shaft -
    cage), BSF), and a period's mean shaft speed is cage_hz + BPFI / Z, Z = BPFO / cage_hz.  A
    period that holds a speed step gives the lines of neither speed; moved, those at the
    window's (a 0.5 s window at 3000 rpm in a period half at 1600 had its lines 23 % low, and
    its 2xBSF fell on the outer race's BPFO: "ball", x325).  Unchanged where ``shaft_hz`` is not
    a speed or a period has no cage."""
    if not (math.isfinite(shaft_hz) and shaft_hz > 0):
        return periods
    return [(p0, p1, _moved_to(f, shaft_hz)) for p0, p1, f in periods]


def _moved_to(frequencies: dict, shaft_hz: float) -> dict:
    """One period's ``frequencies`` ({"ftf", "bpfo", "bpfi"[, "bsf"]: Hz}) moved to the shaft
    speed ``shaft_hz`` (Hz, a speed) at their own skids (``at_shaft_speed``)."""
    f = frequencies
    period_hz = f["ftf"] + f["bpfi"] * f["ftf"] / f["bpfo"] if f["ftf"] > 0 and f["bpfo"] > 0 else 0.0
    scale = shaft_hz / period_hz if period_hz > 0 else 1.0
    return {k: v * scale for k, v in f.items()}


def recorded_frequencies(periods: list, start_s: float, end_s: float) -> dict:
    """{"ftf", "bpfo", "bpfi"[, "bsf"]: Hz} as the recording's ``/diagnostics`` give them over
    [start_s, end_s): the mean of the periods' values weighted by their overlap with the window
    (each period runs from the previous ``/diagnostics`` to its own, s); a window outside every
    period takes the nearest; {} without periods (a recording made before these keys)."""
    if not periods:
        return {}
    overlap = np.array([max(0.0, min(end_s, p1) - max(start_s, p0)) for p0, p1, _ in periods])
    if overlap.sum() <= 0.0:
        mid = 0.5 * (start_s + end_s)
        overlap = np.zeros(len(periods))
        overlap[int(np.argmin([min(abs(mid - p0), abs(mid - p1)) for p0, p1, _ in periods]))] = 1.0
    w = overlap / overlap.sum()
    common = set.intersection(*(set(f) for _, _, f in periods))
    return {k: float(sum(wi * f[k] for wi, (_, _, f) in zip(w, periods))) for k in sorted(common)}


class RecordedPeriods:
    """The recorded ``/diagnostics`` periods (``_Data.signal_frequency_periods``) for asking
    ``recorded_frequencies(at_shaft_speed(periods, shaft_hz), start_s, end_s)`` of every window
    of a long recording: the periods' bounds are held as arrays, and a window moves and weighs
    only the periods it overlaps, the others weighing 0 (the same numbers).  Moving and weighing
    all of them in Python for each window made the verdict timeline quadratic in the length:
    80 s of a 30-min recording's report (1800 windows by 1800 periods), 4 x that for an hour.
    The periods' values are finite: ``signal_frequencies`` takes none that is not (a NaN would
    make every window's mean NaN in ``recorded_frequencies``, even at weight 0, and only the
    windows it overlaps here)."""

    def __init__(self, periods: list):
        self.periods = periods
        self.starts = np.array([p0 for p0, _, _ in periods], dtype=float)
        self.ends = np.array([p1 for _, p1, _ in periods], dtype=float)
        self.common = sorted(set.intersection(*(set(f) for _, _, f in periods))) if periods else []

    def frequencies(self, start_s: float, end_s: float, shaft_hz: float | None = None) -> dict:
        """``recorded_frequencies`` over [start_s, end_s) (s) of the periods moved to
        ``shaft_hz`` (Hz, ``at_shaft_speed``; None: as recorded)."""
        moving = shaft_hz is not None and math.isfinite(shaft_hz) and shaft_hz > 0
        if not self.periods:
            return {}
        # recorded_frequencies' weights, element for element (the sum over the same array)
        overlap = np.maximum(0.0, np.minimum(end_s, self.ends) - np.maximum(start_s, self.starts))
        if overlap.sum() <= 0.0:
            mid = 0.5 * (start_s + end_s)
            overlap = np.zeros(len(self.periods))
            overlap[int(np.argmin(np.minimum(np.abs(mid - self.starts), np.abs(mid - self.ends))))] = 1.0
        w = overlap / overlap.sum()
        used = np.flatnonzero(w)
        values = [_moved_to(self.periods[i][2], shaft_hz) if moving else self.periods[i][2] for i in used]
        return {k: float(sum(w[i] * f[k] for i, f in zip(used, values))) for k in self.common}


LINE_KEYS = {"ftf", "bpfo", "bpfi", "bsf"}     # what envelope.diagnose places its lines by
RECORDED_KEYS = ("cage_hz", "bpfo_hz", "bpfi_hz", "bsf_hz")     # the /diagnostics keys that give them


def line_frequencies(rolling: dict, recorded: dict) -> dict:
    """{"ftf", "bpfo", "bpfi", "bsf": Hz} to look for the fault lines at: pure rolling of the
    scene's bearing (``rolling``, {} without a scene) overridden by what the recording's
    ``/diagnostics`` give (``recorded``: where the cage skids, the lines are there); without a
    scene, ``recorded`` alone when it has all four (a recording that lost its ``bearing_sim``
    metadata, rewritten by another tool, still carries them); {} when neither places every line."""
    found = {**rolling, **recorded}
    return found if LINE_KEYS <= set(found) else {}


def frequencies_source(rolling: dict, recorded: dict, scene_problem: str, missing=RECORDED_KEYS) -> str:
    """Where ``line_frequencies(rolling, recorded)`` come from, in words (``fault_frequencies_from``);
    ``missing``: the keys of ``RECORDED_KEYS`` that not every recorded /diagnostics gives."""
    if not line_frequencies(rolling, recorded):
        return f"none: {no_frequencies_reason(scene_problem, missing)}"
    if not rolling:
        return (f"the recording's /diagnostics ({', '.join(RECORDED_KEYS)}), mean over the recording, as it has no "
                f"scene to take the bearing from ({scene_problem})")
    if not recorded:
        return "pure rolling at the mean shaft speed"
    return (f"the recording's /diagnostics ({', '.join(RECORDED_KEYS)})" if "bsf" in recorded else
            "the recording's /diagnostics (cage_hz, bpfo_hz, bpfi_hz; bsf: pure rolling)")


def no_frequencies_reason(scene_problem: str, missing=RECORDED_KEYS) -> str:
    """Why there are no fault lines to look at: no scene (``scene_problem``: why) and no
    ``/diagnostics`` that give every fault frequency (``missing``: the keys they lack; a recording
    made before ``bsf_hz`` has the other three, and a line that named all four sent its reader
    looking for keys that are there)."""
    if set(missing) >= set(RECORDED_KEYS):
        return (f"no bearing to place the fault lines on ({scene_problem}) and no fault frequencies in its "
                f"/diagnostics ({', '.join(RECORDED_KEYS)})")
    there = [key for key in RECORDED_KEYS if key not in missing]
    return (f"no bearing to place the fault lines on ({scene_problem}) and no {', '.join(missing)} in its "
            f"/diagnostics (they give {', '.join(there)}; the lines need all four)")


def named_scene_text(named: list) -> str:
    """``scene er16k_outer_race (ER-16K)``: the scenes and bearings a recording's /diagnostics name
    (``named``: (scene, bearing or None) pairs), for a recording whose metadata has no scene."""
    return ", ".join(f"scene {scene} ({bearing or 'bearing not given'})" for scene, bearing in named)


SLACK_S = 1e-6      # s: times this close count as equal (stamps rounded to the ns)


def fault_onset(truth: list):
    """(onset s, resolution s) of the first fault to appear after the first sample, by the
    ground truth ``truth`` (``ground_truth.Truth`` each, in signal s): to the sample (resolution
    0) where the recording's ``/diagnostics`` have ``fault_onsets_s``, else the first message with
    the fault and the time since the one before it (the fault appeared in between).  None when no
    fault appears: a healthy recording, or one with its fault there from the first sample."""
    found = ground_truth.appearances(truth, 0.0, SLACK_S)
    if not found or faults_at_start(truth):
        return None                           # none, or not from none: a fault from the start
    return found[0].latest, found[0].latest - found[0].earliest


def faults_at_start(truth: list) -> tuple:
    """The faults in the first sample (t = 0), or where that is not known (a recording without
    ``fault_onsets_s`` whose first message has a fault), those of the first message."""
    at_start = ground_truth.faults_at(truth, 2 * SLACK_S, SLACK_S)
    return at_start if at_start is not None else (truth[0].faults if truth else ())


THROUGHOUT, IN_PART, AFTER_ANALYSED, NOT_RECORDED = (
    "throughout the analysed stretch", "in part of the analysed stretch", "after the analysed stretch",
    "not in this recording")


def scene_defects(scene, truth: list, analysed_end_s: float, end_s: float) -> list:
    """Each kind of the scene's defects (sorted), with the earliest ``onset_s`` the scene gives
    its defects of that kind and where the recorded ground truth ``truth`` has it
    (``present``): ``THROUGHOUT`` the analysed stretch (the signal up to ``analysed_end_s``, from
    its first sample), ``IN_PART`` of it (it appeared within), ``AFTER_ANALYSED`` (it appeared
    before the recording's end ``end_s``, after the analysed stretch) or ``NOT_RECORDED``; None
    without ground truth.  [] without a scene."""
    if scene is None:
        return []
    onsets: dict = {}
    for df in scene.defects:
        onsets[df.kind] = min(df.onset, onsets.get(df.kind, df.onset))
    at_start = faults_at_start(truth) if truth else None
    analysed = ground_truth.faults_at(truth, analysed_end_s, SLACK_S) if truth else None
    recorded = ground_truth.faults_at(truth, end_s, SLACK_S) if truth else None
    rows = []
    for kind in sorted(onsets):
        if analysed is None:
            present = None
        elif kind in analysed:
            present = THROUGHOUT if kind in at_start else IN_PART
        else:
            present = AFTER_ANALYSED if recorded and kind in recorded else NOT_RECORDED
        rows.append({"kind": kind, "onset_s": onsets[kind], "present": present})
    return rows


def expected_defects(scene, truth: list, analysed_end_s: float):
    """(the faults the one verdict is checked against, sorted, and where they come from): where
    the recording carries ground truth, those its ``/diagnostics`` have in the analysed stretch
    (the signal up to ``analysed_end_s``: defects do not vanish, so those of its last sample),
    "ground truth"; without it, every defect kind of the scene, "scene"; (None, None) without a
    scene (no verdict then)."""
    if scene is None:
        return None, None
    analysed = ground_truth.faults_at(truth, analysed_end_s, SLACK_S) if truth else None
    if analysed is not None:
        return sorted(analysed), "ground truth"
    return sorted({df.kind for df in scene.defects}), "scene"


def fault_detections(timeline: list, truth: list) -> list:
    """Each fault kind that appeared after the first sample, with the first window of
    ``timeline`` that calls it once it is there: {"fault", "onset_s", "onset_resolution_s" (0 to
    the sample), "first_detection_s" and "latency_s" (from the onset; None when never called),
    "windows_since"}."""
    scored = [(w["end_s"], w["verdict"]) for w in timeline]
    rows = []
    for fault in ground_truth.appearances(truth, 0.0, SLACK_S):
        found, since = ground_truth.first_detection(scored, fault, SLACK_S)
        rows.append({"fault": fault.kind, "onset_s": fault.latest,
                     "onset_resolution_s": fault.latest - fault.earliest, "first_detection_s": found,
                     "latency_s": None if found is None else max(0.0, found - fault.latest),
                     "windows_since": since})
    return rows


def truth_changes(truth: list) -> list:
    """Where the faults present change: {"t_s": when (exact, or the first message that shows it),
    "after_s": the earliest it may have been (= t_s where exact), faults_present: from then on,
    defect_sizes: of the first message that shows the new fault (None if none does)}, in order.
    A message stamped at the very onset does not show it: it tells the sample before its stamp."""
    changes = []
    for fault in ground_truth.appearances(truth, 0.0, SLACK_S):
        if changes and abs(changes[-1]["t_s"] - fault.latest) <= SLACK_S:
            continue                          # two kinds at once: one change
        shows = next((r for r in truth if r.t >= fault.latest - SLACK_S and fault.kind in r.faults), None)
        faults = ground_truth.faults_at(truth, fault.latest + 2 * SLACK_S, SLACK_S)
        changes.append({"t_s": fault.latest, "after_s": fault.earliest, "faults_present": list(faults),
                        "defect_sizes": None if shows is None else list(shows.sizes)})
    return changes


def score_windows(windows, sample_rate_hz: float, times_s: list, frequencies: list,
                  truth: list, speeds_rad_s: list, spreads: list | None = None, track=None,
                  resonance_hz: float | None = None) -> list:
    """The envelope detector (``envelope.diagnose``, as for the whole recording) in each window:
    the samples of each of ``windows`` (an iterable of arrays), spanning ``times_s`` (start s,
    end s) of signal, looking at ``frequencies`` ({"ftf", "bpfo", "bpfi", "bsf": Hz} per window, {}
    when unknown) at the window's shaft speed (``speeds_rad_s``); verdict "unknown" without
    frequencies, in less than 0.2 s of signal, or where the lines move within the window by more
    than ``STEADY_LINES`` (``spreads``, ``line_spread`` of each window; None: steady): a speed
    step or ramp in it smeared them, and its verdict was "healthy", or "ball" where 2xBSF of one
    speed fell on BPFO of the other.  Those are scored in orders of the shaft instead where
    ``track`` (``track(samples, times_s)``: ``order_tracked``'s (result, why)) gives a result; their
    rows have ``order_tracked``: True, every other row False.  ``resonance_hz``: the scene's resonator (Hz, None: not
    known), for the detector's band (``envelope.detector_band``), as for the whole recording.
    One dict per window: start_s, end_s, shaft_speed_rpm, line_spread, verdict, prominences
    ({fault: line height over local median}; {} unscored), envelope_band_hz (the band the
    detector used, [low, high] Hz, in orders at the fastest speed; None unscored), and
    the ground truth at its end: faults_present, those in its last sample
    (``ground_truth.faults_at``: to the sample where the recording has ``fault_onsets_s``), and
    defect_sizes with truth_t_s, the sizes of the latest ``/diagnostics`` at or before the end
    with those faults (else the first after it) and that message's time (None each without
    ground truth)."""
    rows = []
    spreads = [0.0] * len(times_s) if spreads is None else spreads
    for xw, (t0, t1), freqs, speed, moved in zip(windows, times_s, frequencies, speeds_rad_s, spreads):
        usable = freqs and freqs["bpfo"] > 0 and xw.size > 0.2 * sample_rate_hz     # as for the whole
        verdict = (diagnose(xw, sample_rate_hz, freqs, resonance_hz=resonance_hz)
                   if usable and moved <= STEADY_LINES else None)
        tracked = (track(xw, t0 + np.arange(xw.size) / sample_rate_hz)[0]
                   if usable and moved > STEADY_LINES and track is not None else None)
        verdict = verdict or tracked
        faults = ground_truth.faults_at(truth, t1, SLACK_S)
        sizes = ground_truth.truth_before(truth, t1, SLACK_S)
        if sizes is not None and faults is not None and sizes.faults != faults:
            # the fault appeared after that message: the sizes of the first one that has it
            sizes = next((r for r in truth if r.t >= t1 - SLACK_S and r.faults == faults), sizes)
        rows.append({"start_s": t0, "end_s": t1, "shaft_speed_rpm": speed * RPM, "line_spread": moved,
                     "verdict": verdict["verdict"] if verdict else "unknown",
                     "prominences": verdict["scores"] if verdict else {},
                     "envelope_band_hz": list(verdict["band"]) if verdict and verdict["band"] is not None else None,
                     "faults_present": list(faults) if faults is not None else None,
                     "defect_sizes": list(sizes.sizes) if sizes else None,
                     "truth_t_s": sizes.t if sizes else None,
                     "order_tracked": bool(tracked)})
    return rows


def one_verdict(whole, timeline: list, moved: float, end_s: float, tracked=None, untracked: str = "") -> tuple:
    """(the recording's one verdict, the fault kinds it names, where it comes from in words).
    ``whole``: ``diagnose`` of the analysed stretch (None: no verdict); ``moved``: its
    ``line_spread``; ``end_s``: its end (s).  Where the lines hold still (``STEADY_LINES``) that
    is ``whole``'s.  Where they move (speed steps or a ramp, a load step or tier switch that moves
    the cage's skid), one envelope spectrum smears every line, and ``whole`` said "inner" of an
    outer-race recording stepped 1600 -> 10000 rpm (its lines at the mean speed's) and "healthy"
    of one ramped: then the verdict is that of ``tracked``, the analysed stretch's envelope
    spectrum in orders of the shaft (``order_tracked``), where the lines hold still in orders.
    Where it could not be tracked (``untracked``: why) it is that of ``timeline``'s windows in the
    analysed stretch, each at its own lines, those whose lines move within them order tracked
    or else unscored ("unknown"): the fault they name, "healthy" where they name none, "mixed"
    where they name several, "unknown" where none is scored."""
    if whole is None:
        return "unknown", [], "no verdict"
    if moved <= STEADY_LINES:
        return whole["verdict"], [] if whole["verdict"] == "healthy" else [whole["verdict"]], "the analysed stretch"
    if tracked is not None:
        slowest, fastest = tracked["shaft_rpm"]
        return tracked["verdict"], [] if tracked["verdict"] == "healthy" else [tracked["verdict"]], (
            f"order tracking over the analysed stretch ({tracked['start_s']:.2f}-{tracked['end_s']:.2f} s, "
            f"{slowest:.0f}-{fastest:.0f} rpm, {tracked['revolutions']:.0f} revolutions): the fault lines move by "
            f"{100 * moved:.0f} % in Hz (shaft speed), which one envelope spectrum smears; in orders of the shaft "
            "they hold still")
    counts = {}
    for w in timeline:
        if w["end_s"] <= end_s + SLACK_S:
            counts[w["verdict"]] = counts.get(w["verdict"], 0) + 1
    faults = sorted(k for k in counts if k not in ("healthy", "unknown"))
    verdict = ("mixed" if len(faults) > 1 else faults[0] if faults else
               "healthy" if counts.get("healthy") else "unknown")
    tally = ", ".join(f"{v} in {n}" for v, n in sorted(counts.items(), key=lambda c: -c[1]))
    why = '; "unknown": the lines move within it' if counts.get("unknown") else ""
    return verdict, faults, (f"the windows of the verdict over time ({tally}{why}): the fault lines move by "
                             f"{100 * moved:.0f} % over the analysed stretch (shaft speed, cage skid), which one "
                             "envelope spectrum of it smears" + (f"; no order tracking: {untracked}" if untracked else ""))


def first_detection(timeline: list):
    """End (s) of the first window whose verdict names a fault present in its ground truth;
    None when there is none (or no ground truth)."""
    return next((w["end_s"] for w in timeline if w["faults_present"] and w["verdict"] in w["faults_present"]),
                None)


def verdict_timeline(d: "_Data", x, scene, window_s: float, mean_speed_rad_s: float, windows_beyond=None) -> list:
    """``score_windows`` over the whole recording's channel ``x`` of ``d`` in windows of
    ``window_s`` s, each at its own speed (the ``shaft_speed`` commands in the window, else
    ``state``, else ``mean_speed_rad_s``) and fault frequencies (pure rolling at that speed, with
    those of the recorded ``/diagnostics`` over the window moved to it, ``at_shaft_speed``, and the
    cage of ``state`` in it, ``with_state_cage``), those whose lines move within it
    (``line_spread``) in orders of the shaft (``order_tracked``) where they can be, else unscored.
    ``x`` holds the first samples (``MAX_ANALYSIS_S``); the windows beyond it come from
    ``windows_beyond(bounds)`` (``_windows_spooled``).  Without a scene, the recorded ``/diagnostics``
    alone (``line_frequencies``); [] where they do not give all four lines either."""
    if scene is None and not line_frequencies({}, d.signal_frequencies):
        return []
    fs = d.sample_rate
    bounds = window_bounds(d.samples, fs, window_s)
    edges = sample_times_s([i for b in bounds for i in b], d.stamps, d.widths, fs, d.t0_ns)
    times = [(float(edges[2 * k]), float(edges[2 * k + 1])) for k in range(len(bounds))]
    cmd_t, state_t = d.cmd_t - d.t0_ns / NS, d.state_t - d.t0_ns / NS
    periods = RecordedPeriods(d.signal_frequency_periods)
    speeds, freqs, spreads = [], [], []
    for t0, t1 in times:
        speed = mean_in_window(cmd_t, d.cmd_speed, t0, t1)
        if speed is None:
            speed = mean_in_window(state_t, d.shaft_w, t0, t1)
        speed = mean_speed_rad_s if speed is None else speed
        speeds.append(speed)
        rolling = scene.bearing.fault_frequencies(speed / (2 * math.pi)) if scene is not None else {}
        recorded = periods.frequencies(t0, t1, abs(speed) / (2 * math.pi))
        freqs.append(line_frequencies(rolling, with_state_cage(recorded, d, scene, t0, t1)))
        spreads.append(line_spread(d, t0, t1))
    held = [b for b in bounds if b[1] <= x.size]          # the windows in memory; the rest from windows_beyond
    rest = bounds[len(held):]
    windows = itertools.chain((x[i0:i1] for i0, i1 in held), windows_beyond(rest) if rest else ())
    return score_windows(windows, fs, times, freqs, d.truth, speeds, spreads,
                         lambda xw, times_s: order_tracked(d, xw, times_s, scene, periods),
                         scene.structure.resonator_hz if scene is not None else None)


def with_state_cage(recorded: dict, d: "_Data", scene, start_s: float, end_s: float) -> dict:
    """``recorded`` ({"ftf", "bpfo", "bpfi"[, "bsf"]: Hz} of the ``/diagnostics`` periods over
    [start_s, end_s)) with the cage, BPFO and BPFI of the mean shaft and cage speeds that
    ``state`` gives in that stretch, where it does (50 Hz, so a period that holds a tier switch
    or a load step, whose cage skid is neither side's, does not place the lines of a window on
    one side); Z the scene's balls, else BPFO / cage_hz of ``recorded``; unchanged without either."""
    state_t = d.state_t - d.t0_ns / NS
    shaft, cage = states_in(state_t, d.shaft_w, start_s, end_s), states_in(state_t, d.cage_w, start_s, end_s)
    balls = scene.bearing.balls if scene is not None else (
        round(recorded["bpfo"] / recorded["ftf"]) if recorded.get("ftf", 0) > 0 else 0)
    if not (cage.size and balls and recorded):
        return recorded
    return with_cage(recorded, balls, shaft.mean() / (2 * math.pi), cage.mean() / (2 * math.pi))


def order_tracked(d: "_Data", x, times_s, scene, periods: RecordedPeriods | None = None):
    """``orders.order_diagnose`` of the samples ``x`` of ``d``'s envelope channel at signal times
    ``times_s`` (s), with the shaft and cage angles of its ``state``: ``(result, "")``, or
    ``(None, why not)`` (no ``state``, too sparse, a cage skid that changes, ...).  The fault
    frequencies per shaft hertz are the scene's bearing's at pure rolling with those of the
    recorded ``/diagnostics`` over the stretch moved to 1 Hz (``at_shaft_speed``: the ball's spin
    where the balls skid); the cage's lines come from ``state``.  ``periods``: ``d``'s
    ``RecordedPeriods``, made once for the windows of a timeline (made here when None)."""
    start_s, end_s = float(times_s[0]), float(times_s[-1])
    if not d.state_t.size:
        return None, "the recording has no state (JointState of shaft and cage) to take the shaft angle from"
    rolling = scene.bearing.fault_frequencies(1.0) if scene is not None else {}
    if periods is None:
        periods = RecordedPeriods(d.signal_frequency_periods)
    per_shaft_hz = line_frequencies(rolling, periods.frequencies(start_s, end_s, 1.0))
    if not per_shaft_hz or per_shaft_hz["ftf"] <= 0:
        return None, "no fault frequencies to take the fault orders from"
    balls = scene.bearing.balls if scene is not None else round(per_shaft_hz["bpfo"] / per_shaft_hz["ftf"])
    state_t = d.state_t - d.t0_ns / NS
    return order_diagnose(x, d.sample_rate, times_s, state_t, d.shaft_angle, d.shaft_w, d.cage_angle, d.cage_w,
                          per_shaft_hz, balls,
                          spin_shares=spin_shares(d.signal_frequency_periods, state_t, per_shaft_hz["bsf"], balls),
                          resonance_hz=scene.structure.resonator_hz if scene is not None else None)


def spin_shares(periods: list, at_s, bsf_per_shaft_hz: float, balls: int):
    """The balls' spin at each of the times ``at_s`` (s of signal) as a share of
    ``bsf_per_shaft_hz`` (BSF per shaft hertz), from the recorded ``/diagnostics`` ``periods``
    ((from s, to s, {"ftf", "bpfi", "bsf": Hz}): ``_Data.signal_frequency_periods``): each
    period's BSF over its shaft speed (FTF + BPFI / Z) at its middle, linear between them and held
    beyond, as the monitor takes them (``monitor_node.spin_shares_at``); ``order_diagnose`` judges
    the 2xBSF line on the balls' spin angle where the share moves.  None where a period lacks
    ``bsf`` (a recording made before ``bsf_hz``) or a shaft that turns: the mean BSF then."""
    middles, shares = [], []
    for p0, p1, f in periods:
        shaft = f.get("ftf", 0.0) + f.get("bpfi", 0.0) / balls
        if "bsf" not in f or not shaft > 0 or not bsf_per_shaft_hz > 0:
            return None
        middles.append(0.5 * (p0 + p1))
        shares.append(f["bsf"] / shaft / bsf_per_shaft_hz)
    return np.interp(np.asarray(at_s, dtype=float), middles, shares) if shares else None


class _Spool:
    """The envelope channel's samples past those the report holds in memory (``MAX_ANALYSIS_S``),
    for the windows of the verdict timeline beyond them: kept as the recording has them (float32,
    4 bytes a sample: 216 MB an hour at 15 kHz) in a nameless temporary file in the report's
    folder ``out`` (``--out``), made at the first sample kept, gone when closed or the process
    ends.  The report read the file again for those windows: every chunk decompressed twice, a
    truncated file's three times with the scan as it opens (README, "What a long recording
    costs"); now once, in the memory of one window."""

    def __init__(self, out):
        self.out = out
        self.file = None

    def append(self, samples) -> None:
        """Keep ``samples`` (float32), the next after those kept; a full disk is one line naming --out."""
        with writing_into(self.out):
            if self.file is None:
                self.file = tempfile.TemporaryFile(dir=output_folder(self.out), prefix=".bearing-sim-report-")
            self.file.write(np.ascontiguousarray(samples, dtype="<f4").tobytes())

    def read(self, first: int, end: int) -> np.ndarray:
        """The samples ``first`` to ``end`` (excluded) of those kept, as float."""
        self.file.seek(4 * first)
        return np.frombuffer(self.file.read(4 * (end - first)), dtype="<f4").astype(float)

    def close(self) -> None:
        if self.file is not None:
            self.file.close()


def _windows_spooled(x, spool: _Spool, bounds: list):
    """The samples of each window (first, end) of ``bounds`` (sample indices over the waveform
    tables in order) where the first ``x.size`` are ``x`` and the rest ``spool``'s, one window at a
    time (a window across the two: both parts joined)."""
    held = x.size
    for i0, i1 in bounds:
        yield np.concatenate((x[i0:held], spool.read(max(i0, held) - held, i1 - held)))


# ---- plots -------------------------------------------------------------------------------------
def _figure(rows: int, height: float = 3.0):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, 1, figsize=(11, height * rows), squeeze=False)
    return plt, fig, axes[:, 0]


def _save(plt, fig, path: Path) -> str:
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path.name


def _title(meta: dict) -> str:
    return f"{meta.get('scene', '?')} - {meta.get('tier', '?')} tier, seed {meta.get('seed', '?')}"


def band_text(band) -> str:
    """The envelope band ``band`` ((low, high) Hz) in words: ``2-5 kHz band``."""
    return f"{band_words(band)} band"


def held_part(d: _Data) -> str:
    """The words that say a plot holds the first ``MAX_ANALYSIS_S`` of a longer recording
    (``", the first 120.00 s of 150.00 s"``); "" where it holds all of it."""
    held = d.accel.shape[0] / d.sample_rate
    return f", the first {held:.2f} s of {d.signal_s:.2f} s" if d.truncated_analysis else ""


def plot_waveform(d: _Data, freqs: dict, out: Path, meta: dict) -> str:
    plt, fig, (ax_all, ax_zoom) = _figure(2, 3.2)
    fs = d.sample_rate
    t = np.arange(d.accel.shape[0]) / fs + d.t0_ns / NS
    for k, name in enumerate(d.channels):
        ax_all.plot(t, d.accel[:, k], lw=0.4, label=name, alpha=0.85)
    ax_all.set(xlabel="time (s)", ylabel="acceleration (m/s²)",
               title=f"Accelerometer{held_part(d)} - {_title(meta)}")
    ax_all.legend(loc="upper right", fontsize=8)
    ax_all.grid(alpha=0.3)
    # zoom: about five periods of the slowest race-defect line, at least 20 ms
    period = 1.0 / freqs["bpfo"] if freqs else 0.02
    span = max(0.02, min(5 * period, t[-1] - t[0]))
    i0 = d.accel.shape[0] // 2
    sel = slice(i0, min(d.accel.shape[0], i0 + int(span * fs)))
    for k, name in enumerate(d.channels):
        ax_zoom.plot(t[sel] * 1e3, d.accel[sel, k], lw=0.7, label=name)
    if freqs:
        t_first = t[sel][0]
        for j in range(int(span * freqs["bpfo"]) + 1):
            ax_zoom.axvline((t_first + j / freqs["bpfo"]) * 1e3, color="tab:red", lw=0.6, ls=":",
                            alpha=0.6, label="BPFO spacing" if j == 0 else None)
    ax_zoom.set(xlabel="time (ms)", ylabel="acceleration (m/s²)",
                title=f"Zoom: {span * 1e3:.0f} ms (dotted: one BPFO period apart, arbitrary phase)")
    ax_zoom.legend(loc="upper right", fontsize=8)
    ax_zoom.grid(alpha=0.3)
    return _save(plt, fig, out / "waveform.png")


def plot_spectrum(d: _Data, out: Path, meta: dict, band=None) -> str:
    """Welch PSD of each channel, ``band`` (the envelope's, (low, high) Hz; None: the default as
    ``envelope.envelope_band`` clips it) shaded."""
    from scipy.signal import welch

    plt, fig, (ax,) = _figure(1, 4.0)
    fs = d.sample_rate
    nper = int(min(d.accel.shape[0], 2 ** int(math.log2(max(256, fs / 2)))))
    for k, name in enumerate(d.channels):
        f, p = welch(d.accel[:, k] - d.accel[:, k].mean(), fs=fs, nperseg=nper)
        ax.semilogy(f / 1e3, np.maximum(p, 1e-30), lw=0.8, label=name)
    # the band the envelope analysis used (envelope.detector_band: clipped below 11.1 kHz of
    # sample rate, at 1 kHz 225-450 Hz, where 2 kHz to 0.45 x the rate shaded the wrong part;
    # moved up above fast lines)
    lo, hi = band if band is not None else envelope_band(fs)
    ax.axvspan(lo / 1e3, hi / 1e3, color="0.85", alpha=0.5, label="envelope band")
    ax.set(xlabel="frequency (kHz)", ylabel="PSD ((m/s²)²/Hz)", xlim=(0, fs / 2e3),
           title=f"Spectrum (Welch, {nper} points{held_part(d)}) - {_title(meta)}")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(plt, fig, out / "spectrum.png")


def plot_envelope(x: np.ndarray, fs: float, freqs: dict, verdict: dict, channel: str,
                  out: Path, meta: dict, instead: str = "", held: str = "") -> str:
    """The envelope spectrum of ``x`` with the lines of ``freqs`` and ``verdict``'s prominences;
    ``instead``: the title's words in place of ``verdict``'s where the recording's verdict is
    not this spectrum's (its lines move: ``one_verdict``); ``held``: ``held_part``."""
    plt, fig, (ax,) = _figure(1, 4.2)
    targets = {"bpfo": freqs["bpfo"], "bpfi": freqs["bpfi"], "2bsf": 2 * freqs["bsf"], "ftf": freqs["ftf"]}
    fmax = min(0.45 * fs, 3.3 * max(targets.values()))
    f, s = envelope_spectrum(x, fs, verdict["band"], max_freq=fmax)
    _draw_lines(ax, f, s, targets, verdict["lines"], fmax, "Hz", 2.0)
    ax.set(xlabel="frequency (Hz)",
           title=(f"Envelope spectrum of {channel} ({band_text(verdict['band'])}{held}) "
                  f"- {instead or 'verdict: ' + verdict['verdict'].upper()}   (×N: line height over local median)"))
    return _save(plt, fig, out / "envelope.png")


def _draw_lines(ax, f, s, targets: dict, lines: dict, fmax: float, unit: str, floor: float) -> None:
    """The spectrum ``s`` at ``f`` (Hz or orders, ``unit``) up to ``fmax`` on ``ax``, the fault
    lines ``targets`` ({key: where}) and their harmonics marked, and each of ``lines`` (``Line``)
    whose prominence is 2 or more labelled with it; the y axis above the tallest peak beyond
    ``floor`` (the envelope's mean leaks into the first bins)."""
    ax.plot(f, s, color="0.2", lw=0.7)
    top = float(s[f > floor].max()) if np.any(f > floor) else float(s.max())
    for key, f0 in targets.items():
        for h in (1, 2, 3):
            if h * f0 > fmax:
                continue
            ax.axvline(h * f0, color=LINE_COLOURS[key], lw=1.2 if h == 1 else 0.7,
                       ls="--" if h == 1 else ":", alpha=0.9 if h == 1 else 0.5,
                       label=f"{LINE_LABELS[key]} {f0:.{1 if unit == 'Hz' else 3}f} {unit}" if h == 1 else None)
    for key, line in lines.items():
        if math.isfinite(line.found_hz) and line.prominence >= 2.0:
            ax.annotate(f"{LINE_LABELS[key]} ×{line.prominence:.0f}", (line.found_hz, line.height),
                        xytext=(5, -2), textcoords="offset points", ha="left", va="top", fontsize=9,
                        color=LINE_COLOURS[key], fontweight="bold")
    ax.set(ylabel="envelope amplitude (m/s²)", xlim=(0, fmax), ylim=(0, 1.25 * top if top > 0 else 1))
    ax.legend(loc="upper right", fontsize=8, ncol=2)
    ax.grid(alpha=0.3)


def plot_orders(tracked: dict, channel: str, out: Path, meta: dict) -> str:
    """``orders.png``: the envelope spectrum of ``channel`` in orders of the shaft
    (``order_tracked``'s result ``tracked``) with its fault orders and their prominences."""
    plt, fig, (ax,) = _figure(1, 4.2)
    orders, spec = tracked["spectrum"]
    fmax = min(float(orders[-1]), 3.3 * max(tracked["orders"].values()))
    keep = orders <= fmax
    slowest, fastest = tracked["shaft_rpm"]
    _draw_lines(ax, orders[keep], spec[keep], tracked["orders"], tracked["lines"], fmax, "orders", 3 * orders[1])
    ax.set(xlabel="order (events per shaft revolution)",
           title=(f"Envelope spectrum of {channel} in orders, {tracked['start_s']:.2f}-{tracked['end_s']:.2f} s, "
                  f"{slowest:.0f}-{fastest:.0f} rpm - verdict: {tracked['verdict'].upper()}   (×N: line height over "
                  "local median)"))
    return _save(plt, fig, out / "orders.png")


def _legend_or_note(ax, note: str) -> None:
    """A legend of what ``ax`` shows, or, with nothing drawn on it, ``note`` (why) in its middle:
    an empty legend is a matplotlib warning on the user's terminal."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    else:
        ax.text(0.5, 0.5, note, transform=ax.transAxes, ha="center", va="center", color="0.4")


def operating_point_missing(d: _Data, scene) -> str | None:
    """Why ``operating_point.png`` has nothing to show, or None: no shaft speed or load recorded
    and no scene to take the operating point from."""
    if d.cmd_t.size or d.state_t.size or d.load_t.size or scene is not None:
        return None
    return "no /shaft_speed, /state or /load in the recording and no scene to take the operating point from"


def plot_operating_point(d: _Data, scene, out: Path, meta: dict) -> str:
    plt, fig, (ax_s, ax_l) = _figure(2, 2.8)
    if d.cmd_t.size:
        ax_s.step(d.cmd_t, d.cmd_speed * RPM, where="post", lw=1.2, label="shaft_speed topic (command in use)")
    if d.state_t.size:
        ax_s.plot(d.state_t, d.shaft_w * RPM, lw=0.9, ls="--", label="state: shaft")
    if not d.cmd_t.size and not d.state_t.size and scene is not None:
        ax_s.axhline(scene.shaft_speed * RPM, label="scene operating point (nothing recorded)")
    ax_s.set(ylabel="shaft speed (rpm)", title=f"Operating point - {_title(meta)}")
    _legend_or_note(ax_s, "shaft speed not recorded (no /shaft_speed or /state) and no scene")
    ax_s.grid(alpha=0.3)
    if d.load_t.size:
        ax_l.step(d.load_t, d.load_xy[:, 0], where="post", label="Fx (horizontal)")
        ax_l.step(d.load_t, d.load_xy[:, 1], where="post", label="Fy (vertical, up)")
    elif scene is not None:
        ax_l.axhline(scene.radial_load[0], color="tab:blue", label="Fx scene (load not recorded)")
        ax_l.axhline(scene.radial_load[1], color="tab:orange", label="Fy scene (load not recorded)")
    ax_l.set(xlabel="time (s)", ylabel="radial load (N)")
    _legend_or_note(ax_l, "radial load not recorded (no /load) and no scene")
    ax_l.grid(alpha=0.3)
    return _save(plt, fig, out / "operating_point.png")


def plot_cage(d: _Data, scene, out: Path, meta: dict) -> str | None:
    if not d.state_t.size or scene is None:
        return None
    ideal = np.array([scene.bearing.cage_speed(w) for w in d.shaft_w])
    with np.errstate(divide="ignore", invalid="ignore"):
        slip = np.where(np.abs(ideal) > 1e-9, 1.0 - d.cage_w / ideal, np.nan)
    if not d.skid and not np.nanmax(np.abs(slip), initial=0.0) > 1e-4:
        return None            # pure rolling (kinematic tier): nothing to look at
    rows = 3 if d.skid else 2
    plt, fig, axes = _figure(rows, 2.6)
    axes[0].plot(d.state_t, d.cage_w, lw=1.0, label="cage (state)")
    axes[0].plot(d.state_t, ideal, lw=1.0, ls="--", label="pure rolling")
    axes[0].set(ylabel="cage speed (rad/s)", title=f"Cage - {_title(meta)}")
    axes[0].legend(loc="best", fontsize=8)
    axes[0].grid(alpha=0.3)
    axes[1].plot(d.state_t, 100 * slip, lw=1.0, color="tab:red")
    axes[1].set(ylabel="cage slip (%)", xlabel="time (s)" if rows == 2 else None)
    axes[1].grid(alpha=0.3)
    if d.skid:
        for key, arr in sorted(d.skid.items()):
            # the node reports skid ratios in percent already (physics/skidding.py, seed 000 eqs 37-38)
            axes[2].plot(arr[:, 0] / NS, arr[:, 1], marker="o", ms=3, lw=1.0, label=key)
        axes[2].set(ylabel="skid ratio (%, /diagnostics)", xlabel="time (s)")
        axes[2].legend(loc="best", fontsize=8)
        axes[2].grid(alpha=0.3)
    return _save(plt, fig, out / "cage.png")


TIMELINE_LINES = (("outer", "bpfo"), ("inner", "bpfi"), ("ball", "2bsf"))   # fault, its envelope line


def plot_timeline(timeline: list, truth: list, kinds: list, onset, detected_s, out: Path, meta: dict) -> str:
    """Per-window prominences of BPFO, BPFI and 2xBSF against signal time (one step per window),
    the detection threshold, the faults present by ``/diagnostics`` shaded from the onset (a
    dashed line where it is known to the sample, hatched where only between two messages), the
    first detection; below, the defect sizes of ``truth`` when the recording has any (``kinds``:
    the scene's defect kinds, for the labels)."""
    sized = any(r.sizes for r in truth)
    plt, fig, axes = _figure(2 if sized else 1, 3.4 if sized else 4.2)
    ax = axes[0]
    edges = np.array([w["start_s"] for w in timeline] + [timeline[-1]["end_s"]])
    for fault, key in TIMELINE_LINES:
        prom = np.array([w["prominences"].get(fault, np.nan) for w in timeline], dtype=float)
        ax.step(edges, np.append(prom, prom[-1]), where="post", color=LINE_COLOURS[key], lw=1.3,
                label=f"{LINE_LABELS[key]} ({fault})")
    ax.axhline(DETECTION_THRESHOLD, color="0.3", ls="--", lw=1.0,
               label=f"detection threshold {DETECTION_THRESHOLD:g}")
    end = edges[-1]
    # defects appear and never vanish: one band from where the first fault is in the signal
    if faults_at_start(truth):
        ax.axvspan(edges[0], end, color="tab:red", alpha=0.12, lw=0, label="fault present (/diagnostics)")
    elif onset is not None:
        ax.axvspan(onset[0], end, color="tab:red", alpha=0.12, lw=0, label="fault present (/diagnostics)")
        if onset[1] > 0:
            ax.axvspan(onset[0] - onset[1], onset[0], facecolor="none", edgecolor="tab:red", alpha=0.4,
                       hatch="//", lw=0, label="onset somewhere here (1 Hz /diagnostics)")
        else:
            ax.axvline(onset[0], color="tab:red", lw=1.2, ls="--", label=f"onset {onset[0]:.2f} s")
    if detected_s is not None:
        ax.axvline(detected_s, color="k", lw=1.2, label=f"first detection {detected_s:.2f} s")
    ax.set_yscale("log")
    ax.set(ylabel="prominence (line / local median)", xlim=(edges[0], end),
           title=f"Envelope verdict per {timeline[0]['end_s'] - timeline[0]['start_s']:.3g} s window - {_title(meta)}")
    ax.legend(loc="upper left", fontsize=8, ncol=2)
    ax.grid(alpha=0.3, which="both")
    if sized:
        t = [r.t for r in truth]
        for k in range(max(len(r.sizes) for r in truth)):
            size = [r.sizes[k] if k < len(r.sizes) else np.nan for r in truth]
            name = kinds[k] if k < len(kinds) else "?"
            # dotted: between two samples the size is not known
            axes[1].plot(t, size, marker="o", ms=4, lw=0.8, ls=":", label=f"defect {k + 1} ({name})")
        axes[1].set(ylabel="defect size (1 = full)", title="Defect sizes in /diagnostics (1 Hz samples)",
                    ylim=(-0.05, 1.05), xlim=(edges[0], end))
        axes[1].legend(loc="upper left", fontsize=8)
        axes[1].grid(alpha=0.3)
    axes[-1].set_xlabel("signal time (s after the first sample)")
    return _save(plt, fig, out / "timeline.png")


# ---- summary -----------------------------------------------------------------------------------
def window_error(window_s) -> str | None:
    """Why ``window_s`` cannot be the timeline's window (one line naming ``--window``), or None."""
    lo, hi = WINDOW_RANGE_S
    if isinstance(window_s, bool) or not isinstance(window_s, numbers.Real) or not lo <= window_s <= hi:
        return f"--window = {window_s!r} s: allowed range is [{lo:g}, {hi:g}] s"
    return None


def build_report(path, out, window_s: float = DEFAULT_WINDOW_S) -> dict:
    """Read ``path``, write the plots and summaries to ``out``; return the summary dict.
    ``window_s``: length (s) of the windows of the verdict timeline."""
    reason = window_error(window_s)
    if reason:
        raise UserError(reason)
    # open once: a truncated file is scanned (every chunk decompressed) as it opens, and a second
    # open scanned it again
    rec = open_recording(path)
    spool = _Spool(out)
    try:
        return _report(rec, out, window_s, spool)
    finally:
        spool.close()
        rec.close()


def _lines_placeable(rec) -> bool:
    """Whether the report of ``rec`` may place the fault lines, and so score a timeline, as far
    as can be told before its messages are read: a scene it reads, or ``/diagnostics``, which may
    give the fault frequencies (``line_frequencies``).  Without either there is no verdict and
    no timeline, and the samples past those held (``_Spool``) are not kept: an hour's recording
    of another tool wrote 216 MB to --out that nothing read."""
    if _scene_from_metadata(rec.metadata)[0] is not None:
        return True
    return any(c.msg_type == "diagnostic_msgs/msg/DiagnosticArray" and c.count for c in rec.topics().values())


def _report(rec, out, window_s: float, spool: _Spool) -> dict:
    """``build_report`` of the open recording ``rec``, the samples past those it holds kept in
    ``spool`` where a timeline may be scored (``_lines_placeable``)."""
    d = _Data(rec, spool if _lines_placeable(rec) else None)
    meta = dict(rec.metadata)
    log_span = (rec.end_ns - rec.start_ns) / NS
    message_count = rec.message_count
    shown, files, notes, recovered = str(rec.path), [str(f) for f in rec.paths], list(rec.notes), rec.recovered
    out = output_folder(out)
    scene, scene_problem = _scene_from_metadata(meta)
    if scene is None and d.named_scenes:
        # a name, not a bearing to place lines on: a scene file's name may be anybody's YAML, so
        # the report names it and where it came from, and takes nothing from it
        scene_problem += f"; its /diagnostics name {named_scene_text(d.named_scenes)}"
    fs = d.sample_rate
    ch = envelope_channel(d.channels)
    x = d.accel[:, d.channels.index(ch)]
    speed = float(np.mean(d.cmd_speed)) if d.cmd_speed.size else (
        float(np.mean(d.shaft_w)) if d.shaft_w.size else (scene.shaft_speed if scene else float("nan")))
    rolling = scene.bearing.fault_frequencies(speed / (2 * math.pi)) if scene is not None else {}
    # where the cage skids, the lines are where the recorded cage puts them, not at pure rolling;
    # without a scene (a recording rewritten by another tool lost the bearing_sim metadata) the
    # recorded /diagnostics alone place them, when they give all four
    freqs = line_frequencies(rolling, d.signal_frequencies)
    # the envelope's band from these lines (envelope.detector_band) and the scene's resonator
    resonance = scene.structure.resonator_hz if scene is not None else None
    verdict = diagnose(x, fs, freqs, resonance_hz=resonance) if freqs and x.size > fs * 0.2 else None
    no_band = verdict["no_band"] if verdict is not None and verdict["band"] is None else ""
    if no_band:                         # fault lines too close to Nyquist: no verdict, said why
        verdict = None

    not_drawn = {}                      # plot -> why it is not drawn
    if verdict is None:
        why = no_band or ("less than 0.2 s of signal" if freqs else
                          no_frequencies_reason(scene_problem, d.frequency_keys_missing))
        not_drawn["envelope.png"] = not_drawn["timeline.png"] = f"no verdict: {why}"
    missing = operating_point_missing(d, scene)
    if missing:
        not_drawn["operating_point.png"] = missing
    with writing_into(out):             # a full disk: one line, not a traceback
        timeline = (verdict_timeline(d, x, scene, window_s, speed, lambda bounds: _windows_spooled(x, spool, bounds))
                    if verdict is not None else [])
        moved = line_spread(d, 0.0, d.analysed_end_s)
        tracked, untracked = None, ""
        if verdict is not None and moved > STEADY_LINES:
            # the lines move in Hz: in orders of the shaft they may hold still
            tracked, untracked = order_tracked(
                d, x, sample_times_s(np.arange(x.size), d.stamps, d.widths, fs, d.t0_ns), scene)
        overall, named, verdict_from = one_verdict(verdict, timeline, moved, d.analysed_end_s, tracked, untracked)
        band = tracked["band"] if tracked else verdict["band"] if verdict is not None else None
        plots = [plot_waveform(d, freqs, out, meta), plot_spectrum(d, out, meta, band)]
        if verdict is not None:
            plots.append(plot_envelope(x, fs, freqs, verdict, ch, out, meta,
                                       "" if moved <= STEADY_LINES else
                                       f"verdict {overall.upper()} "
                                       f"{'by order tracking' if tracked else 'of the windows'}: the lines move by "
                                       f"{100 * moved:.0f} % and smear here", held_part(d)))
        if tracked:
            plots.append(plot_orders(tracked, ch, out, meta))
        if "operating_point.png" not in not_drawn:
            plots.append(plot_operating_point(d, scene, out, meta))
        cage = plot_cage(d, scene, out, meta)
        if cage:
            plots.append(cage)
        onset = fault_onset(d.truth)
        detected = first_detection(timeline)
        if timeline:
            plots.append(plot_timeline(timeline, d.truth, [df.kind for df in scene.defects] if scene else [],
                                       onset, detected, out, meta))
    changes = truth_changes(d.truth)
    # the verdict and its BPFO line's height for the note on a scene without a defect
    if tracked:
        noted = (tracked["verdict"], tracked["lines"]["bpfo"].prominence)
    elif verdict is not None and overall != verdict["verdict"]:
        # the windows' verdict: their highest BPFO line stands for the recording's
        noted = (overall, max((w["prominences"].get("outer", 0.0) for w in timeline), default=0.0))
    elif verdict is not None:
        noted = (verdict["verdict"], verdict["lines"]["bpfo"].prominence)

    expected, expected_from = expected_defects(scene, d.truth, d.analysed_end_s)
    speed_var = (float(np.ptp(d.cmd_speed) / abs(speed)) if d.cmd_speed.size and speed else 0.0)
    summary = {
        "file": shown,
        "files": files,                  # the pieces of a split recording, in order; else [file]
        "files_left_out": notes,         # a split recording's unreadable last piece, and why
        "recovered": recovered,          # a truncated (last) file read up to its last complete chunk: what is lost
        "scene": meta.get("scene", ""),
        "description": meta.get("scene_description", ""),
        "package_version": meta.get("package_version", ""),
        "seed": meta.get("seed", ""),
        "tier": meta.get("tier", ""),
        "tier_reason": meta.get("tier_reason", ""),
        **tier_history(meta, d.tiers),
        "parameters": _json_or_text(meta.get("parameters", "")),
        "duration_s": d.signal_s,        # the recorded signal: first table's stamp to the last one's end
        "log_time_span_s": log_span,     # first to last message's log time
        "messages": message_count,
        "topics": d.topics,
        "sample_rate_hz": fs,
        "channels": list(d.channels),
        "analysed_s": d.accel.shape[0] / fs,
        # the plots and the one verdict hold the first MAX_ANALYSIS_S s only (the timeline all of it)
        "analysed_first_only": d.truncated_analysis,
        "waveform_gaps": d.gaps,
        "statistics": {name: statistics(d.accel[:, k]) for k, name in enumerate(d.channels)},
        "shaft_speed_rpm": speed * RPM,
        "shaft_speed_variation": speed_var,
        "fault_frequencies_hz": freqs,
        "fault_frequencies_pure_rolling_hz": rolling,
        "fault_frequencies_from": frequencies_source(rolling, d.signal_frequencies, scene_problem,
                                                     d.frequency_keys_missing),
        "envelope_channel": ch,
        # the band-pass before the envelope (envelope.detector_band; order tracking: at the fastest
        # shaft speed); null where no band serves the fault lines (no_band says why)
        "envelope_band_hz": None if no_band else list(band if band is not None else envelope_band(fs)),
        "no_band": no_band or None,
        "fault_lines": ({k: {"expected_hz": v.expected_hz, "found_hz": v.found_hz, "height": v.height,
                             "prominence": v.prominence} for k, v in verdict["lines"].items()}
                        if verdict else {}),
        # the analysed stretch's lines that sit on another detected fault's sideband and count for
        # that fault (envelope.borrowed_lines), in words
        "borrowed_lines": ({fault: borrowed_text(fault, verdict["borrowed"]) for fault in verdict["borrowed"]}
                           if verdict else {}),
        "verdict": overall,
        "verdict_faults": named,         # the fault kinds the verdict names (several where "mixed")
        "verdict_from": verdict_from,    # the analysed stretch, or its windows where the lines move
        "fault_line_variation": moved,   # line_spread of the analysed stretch
        # where the lines move: the envelope spectrum in orders of the shaft, or why there is none
        "order_tracking": None if verdict is None or moved <= STEADY_LINES else _order_summary(tracked, untracked),
        "expected_defects": expected,
        "expected_defects_from": expected_from,
        # a fault verdict on a scene without a defect (the healthy ER-16K's ball-pass line at BPFO)
        "verdict_note": (", ".join(no_defect_note(*noted) or ()) or None
                         if verdict and scene is not None and not scene.defects else None),
        "scene_defects": scene_defects(scene, d.truth, d.analysed_end_s, d.signal_s),
        "scene_unknown": scene_problem or None,
        # the scenes (and bearings) the recording's /diagnostics name: [] before those keys
        "diagnostics_scenes": [{"scene": sc, "bearing": b} for sc, b in d.named_scenes],
        "skid_ratios_percent": {k: float(np.mean(v[:, 1])) for k, v in sorted(d.skid.items())},
        "verdict_describes_recording": (not changes) if d.truth else None,
        "ground_truth_to_the_sample": any(r.onsets is not None for r in d.truth) if d.truth else None,
        "timeline_window_s": (timeline[0]["end_s"] - timeline[0]["start_s"]) if timeline else None,
        "timeline_unscored_s": ((d.samples - window_bounds(d.samples, fs, window_s)[-1][1]) / fs) if timeline else None,
        "timeline": timeline,
        "ground_truth_changes": changes,
        "fault_onset_s": onset[0] if onset else None,
        "fault_onset_resolution_s": onset[1] if onset else None,
        "scene_defect_kinds": [df.kind for df in scene.defects] if scene is not None else [],
        "scene_defect_onsets_s": [df.onset for df in scene.defects] if scene is not None else [],
        "first_detection_s": detected,
        "detection_latency_s": detected - onset[0] if onset and detected is not None else None,
        "fault_detections": fault_detections(timeline, d.truth),
        "plots": plots,
        "plots_not_drawn": not_drawn,
    }
    with writing_into(out):
        replace_file(out / "summary.json", json.dumps(summary, indent=2, default=_json_default) + "\n")
        replace_file(out / "summary.md", _markdown(summary))
    return summary


def _order_summary(tracked, untracked: str) -> dict:
    """``summary.json``'s ``order_tracking``: the stretch, speeds, verdict and the lines in orders
    of ``tracked`` (``order_tracked``'s result), or its ``why_not``."""
    if tracked is None:
        return {"verdict": None, "why_not": untracked}
    return {"verdict": tracked["verdict"], "why_not": None, "start_s": tracked["start_s"], "end_s": tracked["end_s"],
            "shaft_rpm": list(tracked["shaft_rpm"]), "revolutions": tracked["revolutions"],
            "lines": {k: {"expected_order": v.expected_hz, "found_order": v.found_hz, "height": v.height,
                          "prominence": v.prominence} for k, v in tracked["lines"].items()}}


def _json_or_text(text: str):
    try:
        return json.loads(text)
    except ValueError:
        return text


def _json_default(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    return str(value)


def _num(v) -> str:
    return "n/a" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.4g}"


def _tiers_text(s: dict) -> str:
    """``kinematic tier (reason)``, or with ``fidelity: auto`` switching: which tiers ran."""
    text = f"{s['tier']} tier ({s['tier_reason']})"
    if s["tier_switches"]:
        text += (f" at the start, then {' -> '.join(s['tiers'][1:]) or s['tier']}: "
                 f"{s['tier_switches']} tier switch{'es' if s['tier_switches'] > 1 else ''}, "
                 f"the last {s['last_tier_switch']}")
    return text


def _markdown(s: dict) -> str:
    lines = [f"# Recording report: {s['scene'] or Path(s['file']).name}", ""]
    if s["description"]:
        lines += [s["description"], ""]
    verdict = s["verdict"].upper() + (f" ({', '.join(s['verdict_faults'])})" if s["verdict"] == "mixed" else "")
    if s["expected_defects"] is None:      # no agreement to claim without the scene
        lines += [f"**Verdict (envelope analysis of {s['envelope_channel']}): {verdict}**; the scene's defects: "
                  f"unknown ({s['scene_unknown']}).", ""]
    else:
        found = set(s["verdict_faults"])
        agree = ("agrees with" if found <= set(s["expected_defects"])
                 and (found or not s["expected_defects"]) else "differs from")
        checked = "no verdict to check against" if s["verdict"] == "unknown" else f"the verdict {agree}"
        scene_part, present = _expected_texts(s)
        against = (f"; present in the analysed {s['analysed_s']:.2f} s (by `/diagnostics`): {present} "
                   f"({checked} the faults present)" if present is not None
                   else f" ({checked} the scene)")
        lines += [f"**Verdict (envelope analysis of {s['envelope_channel']}): {verdict}**; the scene's defects: "
                  f"{scene_part or 'none (healthy)'}{against}.", ""]
    if _from_windows(s):
        lines += [f"The verdict is that of {s['verdict_from']}; see \"Verdict over time\".", ""]
    elif _from_orders(s):
        lines += [f"The verdict is that of {s['verdict_from']}; see \"Order tracking\".", ""]
    if s["verdict_note"]:
        lines += [f"The verdict on a scene without a defect: {s['verdict_note']}.", ""]
    if s["scene_unknown"] and not s["fault_lines"]:     # (with them, the lines' section says where from)
        lines += [f"Fault frequencies: {s['fault_frequencies_from']}.", ""]
    if s["verdict_describes_recording"] is False:
        lines += [f"**The faults present change during this recording ({_changes_text(s)}): one verdict does "
                  "not describe it; see \"Verdict over time\".**", ""]
    lines += ["| | |", "| --- | --- |",
              (f"| file | `{s['file']}` |" if len(s["files"]) == 1 else
               f"| files | `{s['files'][0]}` .. `{s['files'][-1]}`: {len(s['files'])} pieces of a split recording, "
               "read as one |"),
              *(f"| left out | {note} |" for note in s["files_left_out"]),
              *([f"| recovered | {s['recovered']} |"] if s["recovered"] else []),
              (f"| made by | bearing_sim_ros {s['package_version']}, {_tiers_text(s)}, seed {s['seed']} |"
               if s["package_version"] else "| made by | unknown (no bearing_sim metadata) |"),
              f"| length | {s['duration_s']:.2f} s, {s['messages']} messages; analysed {s['analysed_s']:.2f} s |",
              f"| waveform | {s['sample_rate_hz']:g} Hz, {', '.join(s['channels'])}; "
              f"{'contiguous' if s['waveform_gaps'] == 0 else _count(s['waveform_gaps'], 'gap') + ' (lost tables)'} |",
              f"| shaft speed | {s['shaft_speed_rpm']:.1f} rpm (mean"
              + (f"; varies by {100 * s['shaft_speed_variation']:.0f} %" if s["shaft_speed_variation"] > 0.01 else "")
              + ") |"]
    if _from_windows(s):
        lines.append(f"| fault lines | move by {100 * s['fault_line_variation']:.0f} % over the analysed stretch "
                     "(shaft speed, cage skid): one envelope spectrum of it smears them; the verdict is the "
                     "windows' |")
    elif _from_orders(s):
        lines.append(f"| fault lines | move by {100 * s['fault_line_variation']:.0f} % over the analysed stretch "
                     "(shaft speed): one envelope spectrum of it in Hz smears them; the verdict is that of its "
                     "envelope spectrum in orders of the shaft |")
    lines.append("")
    if s["fault_lines"]:
        lo, hi = s["envelope_band_hz"]
        lines += ["## Fault lines in the envelope spectrum", "",
                  f"The envelope of {s['envelope_channel']}, band-passed to {lo:g}-{hi:g} Hz.", "",
                  f"Expected at the fault frequencies of {s['fault_frequencies_from']}."
                  + (" The lines move over the analysed stretch: this spectrum of all of it smears them, and "
                     "these prominences are not the verdict ("
                     + ("\"Order tracking\" has the lines in orders)." if _from_orders(s) else
                        "\"Verdict over time\" has each window's).")
                     if _from_windows(s) or _from_orders(s) else ""), "",
                  "| line | expected (Hz) | found (Hz) | prominence (x local median) |", "| --- | --- | --- | --- |"]
        for key, line in s["fault_lines"].items():
            lines.append(f"| {LINE_LABELS[key]} | {line['expected_hz']:.2f} | {_num(line['found_hz'])} | "
                         f"{_num(line['prominence'])} |")
        lines += ["", f"A line counts as a fault above a prominence of 4 (`analysis.envelope.DETECTION_THRESHOLD`); "
                  f"which line marks which fault: {', '.join(f'{k} -> {LINE_LABELS[v]}' for k, v in FAULT_LINES.items())}"
                  # a line on another detected fault's sideband (envelope.borrowed_lines)
                  + "".join(f"; {said}" for said in s.get("borrowed_lines", {}).values()) + ".", ""]
    lines += _orders_markdown(s)
    lines += _timeline_markdown(s)
    if s["skid_ratios_percent"]:
        lines += ["## Skidding", "", "Mean over the recording (`/diagnostics`): "
                  + ", ".join(f"{k.replace('_ratio', '')} {v:.3g} %" for k, v in s["skid_ratios_percent"].items()), ""]
    lines += ["## Waveform statistics", "", "| channel | RMS (m/s²) | kurtosis | crest factor | peak-to-peak (m/s²) |",
              "| --- | --- | --- | --- | --- |"]
    for name, st in s["statistics"].items():
        lines.append(f"| {name} | {_num(st['rms'])} | {_num(st['kurtosis'])} | {_num(st['crest_factor'])} | "
                     f"{_num(st['peak_to_peak'])} |")
    lines += ["", "## Plots", ""] + [f"![{p}]({p})" for p in s["plots"]] + [""]
    if s["plots_not_drawn"]:
        lines += ["Not drawn:", ""] + [f"- `{p}`: {why}" for p, why in s["plots_not_drawn"].items()] + [""]
    return "\n".join(lines)


def _from_windows(s: dict) -> bool:
    """Whether the summary's verdict is that of the timeline's windows (``one_verdict``)."""
    return s["verdict_from"] not in ("the analysed stretch", "no verdict") and not _from_orders(s)


def _from_orders(s: dict) -> bool:
    """Whether the summary's verdict is that of order tracking (``one_verdict``)."""
    return s["verdict_from"].startswith("order tracking")


def _orders_markdown(s: dict) -> list:
    """The "Order tracking" section where the lines move: the lines in orders, or why there are none."""
    tracked = s["order_tracking"]
    if tracked is None:
        return []
    if tracked["verdict"] is None:
        return ["## Order tracking", "", f"Not done: {tracked['why_not']}.", ""]
    slowest, fastest = tracked["shaft_rpm"]
    lines = ["## Order tracking", "",
             f"The envelope ({s['envelope_channel']}, band-passed in Hz) resampled at equal steps of shaft angle "
             f"(`state`) over {tracked['start_s']:.2f}-{tracked['end_s']:.2f} s, {slowest:.0f}-{fastest:.0f} rpm, "
             f"{tracked['revolutions']:.0f} revolutions; its spectrum in orders (events per shaft revolution), "
             f"where the fault lines hold still: `orders.png`.  Verdict: {tracked['verdict'].upper()}.", "",
             "| line | expected (order) | found (order) | prominence (x local median) |", "| --- | --- | --- | --- |"]
    for key, line in tracked["lines"].items():
        lines.append(f"| {LINE_LABELS[key]} | {line['expected_order']:.4f} | {_num(line['found_order'])} | "
                     f"{_num(line['prominence'])} |")
    return lines + [""]


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"


def _faults_text(faults) -> str:
    return "n/a" if faults is None else (", ".join(faults) or "none")


def _changes_text(s: dict) -> str:
    """``none, then outer from 2.50 s`` (``from between 2.00 and 3.00 s`` from a recording
    without ``fault_onsets_s``) from ``ground_truth_changes``."""
    first = s["timeline"][0]["faults_present"] if s["timeline"] else None
    parts = [_faults_text(first)] if first is not None else []
    parts += [f"{_faults_text(c['faults_present'])} from "
              + (f"{c['t_s']:.2f} s" if c["after_s"] == c["t_s"] else
                 f"between {c['after_s']:.2f} and {c['t_s']:.2f} s")
              for c in s["ground_truth_changes"]]
    return ", then ".join(parts)


MAX_TIMELINE_ROWS = 40


def _run_key(window: dict) -> tuple:
    return window["verdict"], window["faults_present"], window["order_tracked"]


def _timeline_runs(timeline: list) -> list:
    """The timeline as runs of consecutive windows with the same verdict and faults present, each
    the list of its windows."""
    runs = []
    for w in timeline:
        if runs and _run_key(w) == _run_key(runs[-1][0]):
            runs[-1].append(w)
        else:
            runs.append([w])
    return runs


def _sizes_text(run: list, kinds: list) -> str:
    """The defect sizes over a run of timeline windows: their range ("0.2-0.6"), and where the
    scene has several defects, each one's by its kind ("ball 1, inner 0.2-0.6"; ``kinds``: the
    scene's, in its order, that of ``defect_sizes``; two of a kind by their place, "outer #1 1,
    outer #2 0.5"; a recording without its scene numbers them, "#1 1, #2 0.2-0.6"): the range of
    all of them at once said "1" for a ball and an inner-race defect.  "n/a" without sizes."""
    count = max((len(w["defect_sizes"] or []) for w in run), default=0)
    per_defect = [sorted({w["defect_sizes"][k] for w in run if w["defect_sizes"] and k < len(w["defect_sizes"])})
                  for k in range(count)]
    if not any(per_defect):
        return "n/a"
    ranges = [_num(v[0]) + ("-" + _num(v[-1]) if len(v) > 1 else "") if v else "n/a" for v in per_defect]
    if count == 1:
        return ranges[0]
    if len(kinds) == count:             # a kind twice in the scene: each by its place among them
        names = [kind if kinds.count(kind) == 1 else f"{kind} #{kinds[:k + 1].count(kind)}"
                 for k, kind in enumerate(kinds)]
    else:
        names = [f"#{k + 1}" for k in range(count)]
    return ", ".join(f"{name} {text}" for name, text in zip(names, ranges))


def _timeline_markdown(s: dict) -> list:
    """The "Verdict over time" section: onset, first detection, latency and the runs of windows."""
    timeline = s["timeline"]
    if not timeline:
        return []
    lines = ["## Verdict over time", "",
             f"The same detector in {len(timeline)} consecutive windows of {s['timeline_window_s']:.3g} s of "
             f"{s['envelope_channel']}"
             + (f" (the last {s['timeline_unscored_s']:.3g} s, shorter than a window, not scored)"
                if s["timeline_unscored_s"] > 1e-9 else "")
             + ", each at its own shaft speed; `timeline.png`, and every window in `summary.json`.", ""]
    if timeline[0]["faults_present"] is None:
        lines += ["No ground truth in this recording (its `/diagnostics` have no `faults_present`: made "
                  "before that key).", ""]
    else:
        lines += (["Ground truth: the recorded `/diagnostics`: the faults in each window's last sample by "
                   "`fault_onsets_s` (to the sample), the defect sizes of the latest message at or before "
                   "its end (1 Hz).", ""] if s["ground_truth_to_the_sample"] else
                  ["Ground truth: `faults_present` and `defect_sizes` of the recorded `/diagnostics` (1 Hz), "
                   "the latest at or before each window's end, so a change shows up to one `/diagnostics` "
                   "period late (a recording from before `fault_onsets_s`).", ""])
        scene = [t for t in s["scene_defect_onsets_s"] if t > 0]
        set_by = f"; the scene sets {', '.join(f'{t:g}' for t in scene)} s" if scene else ""
        if s["fault_onset_s"] is not None and s["fault_onset_resolution_s"] == 0:
            lines.append(f"- fault onset: {s['fault_onset_s']:.4f} s (the first sample with the fault, by "
                         f"`/diagnostics`{set_by})")
        elif s["fault_onset_s"] is not None:
            lines.append(f"- fault onset: {s['fault_onset_s']:.2f} s (by `/diagnostics`: none at "
                         f"{s['fault_onset_s'] - s['fault_onset_resolution_s']:.2f} s, so the fault appeared "
                         f"within the {s['fault_onset_resolution_s']:.2f} s before{set_by})")
        else:
            lines.append("- fault onset: none seen (the faults present do not go from none to some)")
        if s["first_detection_s"] is not None:
            lines.append(f"- first detection: {s['first_detection_s']:.2f} s (the end of the first window whose "
                         "verdict names a fault present)")
        else:
            lines.append("- first detection: none (no window's verdict names a fault present)")
        if s["detection_latency_s"] is not None and s["fault_onset_resolution_s"] == 0:
            lines.append(f"- detection latency: {s['detection_latency_s']:.2f} s after the onset")
        elif s["detection_latency_s"] is not None:
            lines.append(f"- detection latency: {s['detection_latency_s']:.2f} s after the onset by `/diagnostics` "
                         f"(from the fault's appearance: {s['detection_latency_s']:.2f} to "
                         f"{s['detection_latency_s'] + s['fault_onset_resolution_s']:.2f} s)")
        if len(s["fault_detections"]) > 1:
            lines.append("- each fault that appeared: " + "; ".join(
                f"{d['fault']} at {d['onset_s']:.2f} s"
                + ("" if d["onset_resolution_s"] == 0 else f" (up to {d['onset_resolution_s']:.2f} s earlier)")
                + (f", first called at {d['first_detection_s']:.2f} s (latency {d['latency_s']:.2f} s)"
                   if d["first_detection_s"] is not None else f", not called in {d['windows_since']} windows since")
                for d in s["fault_detections"]))
        lines.append("")
    runs = _timeline_runs(timeline)
    lines += ["| signal time (s) | windows | verdict | faults present | defect sizes | "
              "highest prominence BPFO / BPFI / 2xBSF |", "| --- | --- | --- | --- | --- | --- |"]
    kinds = s["scene_defect_kinds"]
    for run in runs[:MAX_TIMELINE_ROWS]:
        tops = [max((w["prominences"].get(fault, float("nan")) for w in run), default=float("nan"))
                for fault, _ in TIMELINE_LINES]
        lines.append(f"| {run[0]['start_s']:.2f}-{run[-1]['end_s']:.2f} | {len(run)} | {run[0]['verdict']}"
                     f"{' (in orders)' if run[0]['order_tracked'] else ''} | "
                     f"{_faults_text(run[0]['faults_present'])} | {_sizes_text(run, kinds)} | "
                     f"{' / '.join(_num(v) for v in tops)} |")
    if len(runs) > MAX_TIMELINE_ROWS:
        lines.append(f"| ... | {sum(map(len, runs[MAX_TIMELINE_ROWS:]))} more windows in "
                     f"{len(runs) - MAX_TIMELINE_ROWS} more runs: `summary.json` | | | | |")
    lines += ["", "A row is a run of consecutive windows with the same verdict and faults present."
              + (" \"(in orders)\": the window's lines move, and its verdict is that of its envelope spectrum in orders "
                 "of the shaft (order tracking)." if any(w["order_tracked"] for w in timeline) else "")]
    if s["fault_onset_s"] is not None:
        t1, t0 = s["fault_onset_s"], s["fault_onset_s"] - s["fault_onset_resolution_s"]
        pending = [w for w in timeline if t0 + 1e-6 < w["end_s"] < t1 - 1e-6]
        if pending:
            several = len(pending) > 1
            lines.append(f"The window{'s' if several else ''} ending between {t0:.2f} and {t1:.2f} s ("
                         + ", ".join(f"{w['start_s']:.2f}-{w['end_s']:.2f} s: {w['verdict']}" for w in pending)
                         + f") may already hold the fault, which /diagnostics had not reported yet: "
                         f"{'they count' if several else 'it counts'} as before the onset, and a fault verdict "
                         "there may be an earlier detection.")
    return lines + [""]


def _expected_texts(s: dict) -> tuple:
    """(the scene's defects, each with its onset and where the recording has it where that is not
    throughout the analysed stretch; the faults present in the analysed stretch, or None where
    they are the scene's, from its first sample, or there is no ground truth to tell)."""
    analysed = f"{s['analysed_s']:.2f} s"
    where = {IN_PART: "", AFTER_ANALYSED: f", after the analysed {analysed}",
             NOT_RECORDED: ", after this recording ends"}
    parts = []
    for d in s["scene_defects"]:
        if d["present"] in (None, THROUGHOUT):
            parts.append(d["kind"])
        elif d["onset_s"] > 0:
            parts.append(f"{d['kind']} (from {d['onset_s']:g} s{where[d['present']]})")
        else:
            parts.append(f"{d['kind']} ({d['present']})")
    same = all(d["present"] in (None, THROUGHOUT) for d in s["scene_defects"])
    present = None if s["expected_defects_from"] != "ground truth" or same else (
        ", ".join(s["expected_defects"]) or "none")
    return ", ".join(parts), present


def _defects_text(s: dict) -> str:
    if s["expected_defects"] is None:
        return f"unknown, {s['scene_unknown']}"
    scene_part, present = _expected_texts(s)
    return (scene_part or "none") + ("" if present is None else f"; present: {present}")


def report_command(args) -> int:
    """CLI entry: ``bearing-sim report F.mcap [F_001.mcap ...] --out DIR``."""
    import sys

    s = build_report(args.file, args.out, window_s=args.window)
    for note in [*s["files_left_out"], *([s["recovered"]] if s["recovered"] else [])]:
        print(f"report: {note}", file=sys.stderr)
    timing = "".join(f", {label} {s[key]:.2f} s" for key, label in (
        ("fault_onset_s", "fault onset"), ("first_detection_s", "first detection"),
        ("detection_latency_s", "latency")) if s[key] is not None)
    print(f"{args.out}: {', '.join(s['plots'])}, summary.md, summary.json; verdict {s['verdict']}"
          + (f" ({', '.join(s['verdict_faults'])})" if s["verdict"] == "mixed" else "")
          + f" (scene defects: {_defects_text(s)}{timing})")
    if s["analysed_first_only"]:
        # the plots' time axis ended at 120 s of an hour's recording, said nowhere but summary.md
        print(f"{args.out}: waveform.png, spectrum.png, envelope.png and the one verdict are of the first "
              f"{s['analysed_s']:.2f} s of {s['duration_s']:.2f} s (the most the report holds in memory); "
              "the verdict over time (timeline.png) covers all of it")
    if _from_windows(s) or _from_orders(s):
        print(f"{args.out}: the verdict is that of {s['verdict_from']}")
    if s["verdict_note"]:
        print(f"{args.out}: {s['verdict_note']}")
    if s["scene_unknown"]:              # the fault lines without a scene: where from, or why none
        print(f"{args.out}: " + (f"fault lines looked for at the frequencies of {s['fault_frequencies_from']}"
                                 if s["fault_lines"] else s["plots_not_drawn"]["envelope.png"]))
    return 0
