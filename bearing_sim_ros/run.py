"""``bearing-sim run`` (what ``make run`` calls): the live node on a scene, recorded, then a summary.

    bearing-sim run --scene er16k_outer_race --duration 10 --out runs/now.mcap

Runs the ``bearing_sim`` node in this process in real time for ``--duration`` seconds (0 = until
Ctrl-C or SIGTERM), publishing on the ROS graph like ``bearing-sim node`` and recording to
``--out`` (split into ``F_000.mcap``, ``F_001.mcap``, ... with ``--max-file-duration`` or
``--max-file-size``).  Then it reads the recording back (so the summary also proves the files are
readable) and prints one screen: the envelope lines found at the fault frequencies against theory
(the shared detector, ``analysis.envelope``, over the last ``ANALYSIS_MAX_S`` seconds, across the
pieces of a split recording), the verdict, the real-time factor and overruns, and where the
recording is.
"""
from __future__ import annotations

import math
import shlex
import sys
from collections import deque
from pathlib import Path

import numpy as np

from .errors import SettingNames, UserError
from .paths import output_file
from .stale_dds_ports import clear_before_start
from .teardown import command_signals, say, say_on_stderr

ANALYSIS_MAX_S = 30.0       # s of signal (the end of the recording) that the summary analyses
# what a divergence's advice offers: run has no --fidelity, the scene's fidelity.tier does it
RUN_SETTINGS = SettingNames(lambda key: key, lambda key, value: f"{key}: {{tier: {value}}} in the scene",
                            ("fidelity",))


def _record_tail(paths, max_s: float) -> dict:
    """The last ``max_s`` seconds of ``accel`` from a recording (its files ``paths``: the pieces
    of a split one, read as one, whose tables continue across the seams), the shaft speed in
    use, the mean cage speed of ``state`` in that stretch (rad/s, None without it: where the
    cage skids, the fault lines are there), how far the shaft and cage speeds moved in it
    (``envelope.spread``; of the speed commands without ``state``), and the skid ratios of the
    whole recording (percent; the skidding tier's ``/diagnostics``).  For order tracking where
    the speeds moved: ``times_s``, the signal time of each sample (s from the stretch's first,
    by its table's stamp), and ``states``, the ``state`` samples that span the stretch (with the
    last before it) as ``monitor_node.order_verdict`` takes them, on the clock of ``t0_ns`` (the
    stretch's first stamp).  ``diagnostics``: (stamp ns, values {key: text}) of each
    ``/diagnostics`` message stamped in the stretch (each the mean of the second before its
    stamp), where the balls' spin is (``bsf_hz``)."""
    from rclpy.serialization import deserialize_message

    from .analysis.envelope import STEADY_LINES, spread
    from .analysis.report import skid_ratios
    from .nodes.monitor_node import window_states
    from .recording.reader import get_message, open_recording
    from .waveform import NS, from_pointcloud2

    parts: deque = deque()
    held = 0
    speeds: deque = deque()
    # (stamp ns, shaft rad/s, cage rad/s, shaft rad, cage rad): the speeds and angles at the end of a batch
    states: deque = deque()
    before = []                     # the last state before the stretch (its angles where it begins)
    starts: deque = deque()         # the stamp of each table in parts
    skids: dict = {}
    diagnostics: deque = deque()    # (stamp ns, {key: text}) of each /diagnostics message in the stretch
    channels, rate = None, None
    prev = None
    with open_recording(paths) as rec:          # a split recording's pieces in order, as one
        topics = rec.topics()
        accel_topic = next((t for t in topics if t.rsplit("/", 1)[-1] == "accel"), None)
        speed_topic = next((t for t in topics if t.rsplit("/", 1)[-1] == "shaft_speed"), None)
        diag_topic = next((t for t in topics if t.rsplit("/", 1)[-1] == "diagnostics"), None)
        state_topic = next((t for t in topics if t.rsplit("/", 1)[-1] == "state"), None)
        if accel_topic is None:
            raise UserError(f"{rec.path}: no accel topic in the recording")
        wanted = [t for t in (accel_topic, speed_topic, diag_topic, state_topic) if t]
        types = {t: get_message(topics[t].msg_type) for t in wanted}
        for topic, _type, _log_ns, data in rec.messages(topics=wanted):
            msg = deserialize_message(data, types[topic])
            if topic == speed_topic:
                speeds.append(float(msg.data))
                continue
            if topic == diag_topic:
                for key, percent in skid_ratios(msg).items():
                    skids.setdefault(key, []).append(percent)
                diagnostics.append((msg.header.stamp.sec * NS + msg.header.stamp.nanosec,
                                    {kv.key: kv.value for status in msg.status for kv in status.values}))
                continue
            if topic == state_topic:
                names = list(msg.name)
                if {"shaft", "cage"} <= set(names) and len(msg.velocity) == len(names):
                    angles = msg.position if len(msg.position) == len(names) else [math.nan] * len(names)
                    states.append((msg.header.stamp.sec * NS + msg.header.stamp.nanosec,
                                   float(msg.velocity[names.index("shaft")]), float(msg.velocity[names.index("cage")]),
                                   float(angles[names.index("shaft")]), float(angles[names.index("cage")])))
                continue
            stamp, channels, arr = from_pointcloud2(msg)
            if prev is not None and rate is None:
                rate = prev[1] * NS / (stamp - prev[0])
            prev = (stamp, arr.shape[0])
            parts.append(arr)
            starts.append(stamp)
            held += arr.shape[0]
            if rate:
                while held - parts[0].shape[0] >= max_s * rate:
                    held -= parts.popleft().shape[0]
                    starts.popleft()
                while len(speeds) > len(parts):       # one speed record per batch
                    speeds.popleft()
                while states and states[0][0] <= starts[0]:     # before the stretch's first sample
                    before = [states.popleft()]
                while diagnostics and diagnostics[0][0] <= starts[0]:
                    diagnostics.popleft()
        meta = dict(rec.metadata)
        counts = {t: c.count for t, c in topics.items()}
    data = np.concatenate(list(parts)) if parts else np.zeros((0, 0), np.float32)
    moved = (max(spread([s[1] for s in states]), spread([s[2] for s in states])) if states else spread(speeds))
    t0 = starts[0] if starts else 0
    # order tracking's signal times (an array as long as the stretch) only where it is wanted
    times = (np.concatenate([(stamp - t0) / NS + np.arange(part.shape[0]) / rate for stamp, part in zip(starts, parts)])
             if rate and moved > STEADY_LINES else None)
    return {"accel": data, "channels": channels, "sample_rate": rate, "times_s": times,
            "states": window_states(before + list(states), t0),
            "shaft_speed": float(np.mean(speeds)) if speeds else None,
            "cage_speed": float(np.mean([s[2] for s in states])) if states else None, "speed_spread": moved,
            "metadata": meta, "diagnostics": list(diagnostics), "t0_ns": t0,
            "counts": counts, "skid_percent": {k: float(np.mean(v)) for k, v in sorted(skids.items())}}


def _defect_texts(scene, end_s: float, analysed_s: float) -> str:
    """The scene's defects, each that appears later (``onset_s``) with when, against the run's
    signal (``end_s`` s long, of which the last ``analysed_s`` analysed): "outer (from 5 s, after
    this run)", where the verdict cannot have seen it."""
    texts = []
    for d in scene.defects:
        if d.onset <= 0:
            texts.append(d.kind)
        elif d.onset >= end_s:
            texts.append(f"{d.kind} (from {d.onset:g} s, after this run)")
        elif d.onset > end_s - analysed_s:
            texts.append(f"{d.kind} (from {d.onset:g} s, inside the analysed stretch)")
        else:
            texts.append(f"{d.kind} (from {d.onset:g} s)")
    return ", ".join(texts)


def _verdict_lines(scene, res: dict, end_s: float = math.inf, analysed_s: float = 0.0) -> list:
    """The verdict, honest about what a line means on a scene without a defect: a healthy
    bearing with clearance shows a line at BPFO, the ball-pass (varying compliance) line, which
    the detector cannot tell from an outer-race fault (README "Limitations"); and about a defect
    that appears later than the stretch analysed (``end_s``, ``analysed_s``: s of signal)."""
    from .analysis.envelope import DETECTION_THRESHOLD, no_defect_note
    from .nodes.monitor_node import FAULT_NAMES

    threshold = f"threshold x{DETECTION_THRESHOLD:g} the local floor"
    if scene.defects:
        defects = _defect_texts(scene, end_s, analysed_s)
        return [f"verdict: {FAULT_NAMES[res['verdict']]} ({threshold}; the scene's defects: {defects})"]
    if res["verdict"] == "healthy":
        return [f"verdict: healthy ({threshold}; this scene has no defect)"]
    what, advice = no_defect_note(res["verdict"], res["lines"]["bpfo"].prominence if "lines" in res else math.nan)
    # the outer-race note names the line itself; another fault's says only what it is not
    said = "" if res["verdict"] == "outer" else f"the detector says {FAULT_NAMES[res['verdict']]} ({threshold}); "
    return [f"verdict: {said}{what},", f"  {advice}"]


def _line_table(res: dict, unit: str, digits: int) -> list:
    """The fault lines of ``res`` (a verdict, lines in Hz or orders: ``unit``) as the summary's
    table, each found line's height over its floor, then each line counted for another fault."""
    from .analysis.envelope import DETECTION_THRESHOLD, LINE_LABELS, borrowed_text

    theory, found = f"theory {unit}", f"found {unit}"
    wide = (max(10, len(theory)), max(9, len(found)))
    lines = [f"  {'line':<6} {theory:>{wide[0]}} {found:>{wide[1]}} {'x floor':>8}"]
    for key, label in LINE_LABELS.items():
        ln = res["lines"][key]
        mark = "  <- detected" if key != "ftf" and ln.prominence >= DETECTION_THRESHOLD else ""
        lines.append(f"  {label:<6} {ln.expected_hz:>{wide[0]}.{digits}f} {ln.found_hz:>{wide[1]}.{digits}f} "
                     f"{ln.prominence:>8.1f}{mark}")
    # a line on another detected fault's sideband counts for that fault (envelope.borrowed_lines)
    return lines + [f"  {borrowed_text(fault, res['borrowed'])}" for fault in res.get("borrowed", {})]


def recording_argument(out: str, split: bool) -> str:
    """How ``report`` and ``play`` are given the recording made to ``out``: the file itself, or
    for a split recording (``split``: ``out``'s stem + ``_000.mcap``, ...) the name it was made
    to, which reads every piece; a shell pattern of the pieces where a file of that name exists
    (an earlier recording's: the name would read it instead)."""
    if not split or not Path(out).exists():
        return out
    return str(Path(out).with_name(f"{Path(out).stem}_*{Path(out).suffix or '.mcap'}"))


def summarise(scene, tail: dict, node_figures: dict, path, out: str | None = None) -> str:
    """The one-screen summary (text); ``path``: how ``report`` and ``play`` are given the
    recording (``recording_argument``); ``out``: the name it was made to (default ``path``),
    whose stem names the report's folder."""
    from .analysis.envelope import STEADY_LINES, band_words
    from .nodes.monitor_node import order_verdict, spin_share_of, spin_shares_at, verdict
    from .recording.render import tier_summary
    from .waveform import NS

    lines = []
    f = node_figures
    n_msgs = sum(tail["counts"].values())
    if f["signal_s"] > 0:
        lines.append(f"bearing-sim run: {scene.name} ({scene.bearing.name}), {f['signal_s']:.2f} s of signal in "
                     f"{f['wall_s']:.2f} s: real-time factor {f['rtf']:.3f}, {f['overruns']} overruns, "
                     f"worst lag {1e3 * f['worst_lag']:.1f} ms, {tier_summary(f['tier_values'])}")
    else:       # a signal while the node started (a real-time factor of nan said nothing)
        lines.append(f"bearing-sim run: {scene.name} ({scene.bearing.name}), stopped before the first batch, "
                     f"{tier_summary(f['tier_values'])}")
    fs = tail["sample_rate"]
    x = tail["accel"]
    if n_msgs and (not fs or x.shape[0] < fs):      # no messages: the recording line below says so
        lines.append("envelope analysis: less than 1 s of signal recorded, nothing to analyse")
    elif n_msgs:
        speed = tail["shaft_speed"] if tail["shaft_speed"] is not None else scene.shaft_speed
        shaft_hz = abs(speed) / (2 * math.pi)
        cage = tail.get("cage_speed")
        moved = tail.get("speed_spread", 0.0)
        # the balls' spin from the simulator's /diagnostics in the stretch: on the skidding tier
        # they spin 1-3 % slower than pure rolling, and a ball pit's 2xBSF line with them,
        # outside the detector's +-1 % search at pure rolling's (a ball pit was called healthy)
        spins = [(stamp, share) for stamp, share in ((stamp, spin_share_of(values, scene.bearing))
                                                      for stamp, values in tail.get("diagnostics", ()))
                 if share is not None]
        spin = float(np.mean([share for _stamp, share in spins])) if spins else None
        tracked, untracked = None, ""
        if moved > STEADY_LINES:
            # a speed step or ramp (commands to the node) smeared the lines in Hz: in orders of
            # the shaft they hold still; where it moves the balls' skid, the 2xBSF line is judged
            # on their spin angle, from their spin at each state sample (as monitor and report do)
            shares = spin_shares_at(spins, tail["t0_ns"] + np.asarray(tail["states"][0]) * NS) if spins else None
            tracked, untracked = order_verdict(x, tail["channels"], fs, tail["times_s"], scene.bearing,
                                               tail["states"], spin, shares, scene.structure.resonator_hz)
        if moved > STEADY_LINES and tracked is None:
            lines.append(f"envelope analysis of the last {x.shape[0] / fs:.1f} s: no verdict: the shaft and cage "
                         f"speeds moved by {100 * moved:.0f} % in it (a speed step or ramp, a load step that "
                         "changed the cage's skid), which smears the envelope lines; bearing-sim report gives "
                         f"the verdict of each second; no order tracking: {untracked}")
        else:
            if tracked is not None:
                res, unit, digits = tracked, "order", 3
                slowest, fastest = tracked["shaft_rpm"]
                # the band the envelope was taken in, as the detector chose it (envelope.detector_band):
                # 2-5 kHz held under 0.9 x Nyquist, or moved up above fast lines
                lines.append(f"envelope analysis of the last {x.shape[0] / fs:.1f} s ({', '.join(tail['channels'])}, "
                             f"band {band_words(res['band'])}) by order tracking, axis {res['axis']}: the shaft and "
                             f"cage speeds moved by {100 * moved:.0f} % in it ({slowest:.0f}-{fastest:.0f} rpm), which "
                             f"smears the lines in Hz; in orders of the shaft ({tracked['revolutions']:.0f} revolutions) "
                             "they hold still:")
            else:
                # the cage's speed from state: where it skids (7 % at 10000 rpm / 10 N on the
                # ER-16K) the lines are there, and at pure rolling's this said "ball fault" of an
                # outer-race pit
                res, unit, digits = verdict(x, tail["channels"], fs, scene.bearing, shaft_hz,
                                            None if cage is None else abs(cage) / (2 * math.pi), spin,
                                            scene.structure.resonator_hz), "Hz", 2
                head = f"envelope analysis of the last {x.shape[0] / fs:.1f} s"
                at = f"at shaft {shaft_hz:.2f} Hz ({shaft_hz * 60:.0f} rpm)"
                lines.append(f"{head} {at}: {res['no_band']}" if res.get("no_band") else
                             f"{head} ({', '.join(tail['channels'])}, band {band_words(res['band'])}) {at}, "
                             f"axis {res['axis']}:")
            if not res.get("no_band"):
                lines += _line_table(res, unit, digits)
                lines += _verdict_lines(scene, res, f["signal_s"], x.shape[0] / fs)
    if tail["skid_percent"]:
        lines.append(f"skid ratios, mean of the recording's /diagnostics ({f['tier_values']['tier']} tier): "
                     + ", ".join(f"{k.replace('_ratio', '')} {v:.3g} %" for k, v in tail["skid_percent"].items()))
    lines.append(f"recording: {f['files']} ({f['sizes']}, {n_msgs} messages on "
                 f"{len(tail['counts'])} topics, {f['dropped']} dropped)")
    if n_msgs:                  # report and play refuse a recording without messages
        # shell-quoted, to paste as they are: a path with a space split into two arguments
        folder = shlex.quote(str(Path(out or path).with_suffix("")) + "_report")
        path = shlex.quote(str(path))
        lines.append(f"  next: bearing-sim report {path} --out {folder}"
                     f"   |   bearing-sim play {path}")
    return "\n".join(lines)


def run_command(args) -> int:
    """CLI entry: ``bearing-sim run --scene S --duration SEC --out F.mcap [--max-file-duration SEC]
    [--max-file-size BYTES]`` (the last two: the node's ``record_max_duration``, ``record_max_size``)."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.parameter import Parameter
    from rclpy.signals import SignalHandlerOptions

    from .nodes.bearing_sim_node import (DEFAULT_SAMPLE_RATE, BearingSimNode, build_node, close_node,
                                         log_the_end, say_held, spin_node, stop_reason)
    from .messages import BATCH_DURATION, duration_error
    from .recording.recorder import files_text, sizes_text, split_error
    from .recording.render import tier_values
    from .scene import load_scene

    duration = float(args.duration)           # finite and >= 0: the parser's type checks it
    scene = load_scene(args.scene)
    out = str(args.out)
    # the node takes an empty record for "no recording"; and nothing starts if --out is the scene
    output_file(out, keep=[scene.source_path])
    split = (float(args.max_file_duration), int(args.max_file_size))
    reason = (duration_error("--duration", duration, DEFAULT_SAMPLE_RATE, no_end=True)
              or split_error(*split, BATCH_DURATION, names=("--max-file-duration", "--max-file-size")))
    if reason:                                # said in run's words, not the node parameters'
        raise UserError(reason)
    overrides = [Parameter("scene", value=str(args.scene)), Parameter("duration", value=duration),
                 Parameter("record", value=out), Parameter("real_time", value=True),
                 Parameter("record_max_duration", value=split[0]), Parameter("record_max_size", value=split[1])]
    node = None
    error = None
    # the command's handlers from its first line (cli.SIGNAL_COMMANDS), as the node's: never a
    # KeyboardInterrupt in the middle of finalising or reading the recording, and a Ctrl-C while
    # numpy, numba and rclpy were imported no longer went missing (a run until Ctrl-C ran on)
    signals = command_signals()
    signals.on_held = say_held(lambda: node)
    try:
        signals.check()
        clear_before_start(say_on_stderr)
        rclpy.init(args=[], signal_handler_options=SignalHandlerOptions.NO)
        node = build_node(lambda: BearingSimNode(record_argument="--out", settings=RUN_SETTINGS,
                                                 parameter_overrides=overrides))
        signals.check()
        say(f"bearing-sim run: {scene.name} in real time "
            f"{'until Ctrl-C' if duration == 0 else f'for {duration:g} s'}, recording to {out}")
        spin_node(node, signals)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        signals.shutting_down()         # a signal from here on is held, said, and exits 130 / 143
        if node is not None:
            node.stop(reason=stop_reason(signals))
            error = node.error
        figures = None
        if node is not None:
            log_the_end(node)
            rs = node.recorder.status
            # the signal published (and recorded), not the simulator's time: after a Ctrl-C
            # that holds the batches computed ahead, which were never published
            figures = {"signal_s": node.stats.samples / node.stats.sample_rate,
                       "wall_s": node.stats.last - node.stats.started,
                       "rtf": node.stats.real_time_factor,
                       "overruns": node.stats.overruns, "worst_lag": node.stats.worst_lag,
                       "tier_values": tier_values(node.sim),
                       "dropped": rs["dropped"], "ok": rs["ok"], "error": rs["error"],
                       "path": rs["path"], "paths": rs["files"], "files": files_text(rs),
                       "sizes": sizes_text(rs)}
        try:
            # the outcome (a UserError, or the summary) before the middleware's teardown, which
            # may hang (close_node: it exits with the status decided here)
            if error is None and sys.exc_info()[1] is None and node is not None:
                _say_the_end(scene, node, figures, out, split)
        finally:
            close_node(node, 1 if error is not None else 0,
                       [f"internal error: {error.__class__.__name__}: {error}"] if error is not None else [])
    if error is not None:
        raise error
    return 0


def _say_the_end(scene, node, figures: dict, out: str, split) -> None:
    """``run``'s last line, its summary (``summarise``) of the recording ``out``, once the node
    stopped and closed it; a UserError where the run failed (the solver diverged) or the recording
    did (``figures``: the node's, taken as it stopped)."""
    from .nodes.bearing_sim_node import failure_recording_text

    if node.failure is not None:
        # the skidding solver diverged: the recording is finalised, the summary is not the run's
        raise UserError(f"{node.failure.worded(RUN_SETTINGS)}{failure_recording_text(node)}")
    if not figures["ok"]:
        raise UserError(f"--out = {out!r}: {figures['error']}")
    # the recording is complete.  A second Ctrl-C while its tail is read for the summary (about a
    # second) surfaced inside rclpy's deserialiser as a TypeError traceback: it is held (130)
    tail = _record_tail(figures["paths"], ANALYSIS_MAX_S)
    say(summarise(scene, tail, figures, recording_argument(out, any(split)), out))
