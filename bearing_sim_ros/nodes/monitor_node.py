"""``bearing-sim monitor``: a small condition-monitoring subscriber, the consumer to learn from.

    bearing-sim node &                       # or any recording played with `bearing-sim play`
    bearing-sim monitor --window 4 --count 3
    bearing-sim monitor --window 4 --ros-args -r __ns:=/rig1    # the node in namespace rig1

It subscribes to ``accel`` (waveform tables, reliable like the node offers them) and ``state``
(for the shaft speed in use), decodes each table with :func:`bearing_sim_ros.waveform.from_pointcloud2`
into a float32 array (no per-sample objects), and checks that the tables are contiguous: a gap
(a lost table, a restarted node) starts the window again, because envelope analysis of a signal
with a hole in it would smear the lines.  Every ``window`` seconds of signal it runs the shared
envelope detector (:func:`bearing_sim_ros.analysis.envelope.diagnose`) on each accelerometer axis
at the fault frequencies of the scene's bearing at the measured shaft speed (cage, BPFO and BPFI
from the cage's speed in ``state``, where a skidding cage puts them; 2xBSF from the balls' spin in
the simulator's ``/diagnostics``, ``bsf_hz``, where skidding balls put it), and prints one line:

    t=4.00s shaft=1600rpm verdict=outer truth=outer | bpfo 95.2/95.3Hz x266 | bpfi 144.8/144.7Hz x1.0 | ...

``found/theory Hz`` and ``x`` the height of the line over the median of its neighbourhood
(threshold x4, ``envelope.DETECTION_THRESHOLD``).  The axis where a line stands highest counts.
The line ends with the envelope's band (``band 2-5 kHz``: ``envelope.detector_band`` of the
window's lines and the scene's resonator); where none serves them (lines too close to Nyquist),
``verdict=unknown`` and the one line that says why.
A line that sits on another detected fault's sideband counts for that fault, and the line says
so (``envelope.borrowed_lines``: ``2xBSF sits on BPFI - 1 x shaft rate, ...: counted for inner,
not ball``).
Where those speeds moved by more than 1 % in the window (a speed step or ramp), its lines smear
in Hz: it is judged in orders of the shaft instead (``order_verdict``: ``orders.order_diagnose``
with the shaft and cage angles of the window's ``state`` samples, which go with it into the
analysis queue), and the line says so in its first field after ``truth=``:

    t=2.00s shaft=1749rpm verdict=outer truth=outer | in orders (order tracking over 1499-1989 rpm, ...) | bpfo 3.571/3.572 orders x309.7 | ...

and where it cannot be order tracked (``orders.untrackable``: ``state`` too sparse, a cage skid
that changes, ...) ``verdict=unknown`` and why.
The bearing is ``--scene``'s; where the simulator's ``/diagnostics`` name another scene, one line
says so and whether its bearing differs (:func:`scene_mismatch_line`).

It also scores itself.  The simulator's ``/diagnostics`` (1 Hz) say which faults are in the signal
and since when (``faults_present``: ``none``, ``outer``, ``ball, outer``, ...; ``fault_onsets_s``:
the signal time each appeared), stamped with the end of the signal published so far, the time
line of the tables' stamps; :mod:`bearing_sim_ros.ground_truth` reads them.  Only the status of
the simulator whose waveform it watches counts (``--simulator``; by default ``bearing_sim`` in the
namespace of the resolved ``accel`` topic, ``rig1/bearing_sim: simulator`` for ``/rig1/accel``):
the simulators of several rigs all publish on the one ``/diagnostics``.  ``truth=`` is the
faults in the window's last sample (``none``, ``outer``, ``ball,outer``; ``unknown`` before the
first diagnostics, or with none at all: a real sensor, a recording without them): exact to the
sample once the diagnostics stamped at or after the window's end are in, which leave the node
just after its last table, so a verdict waits for them up to ``TRUTH_GRACE_S``.  On exit, beside
the counts, a score line over the ``truth=`` that each verdict line printed (``healthy`` agrees
with ``none``, a fault verdict when its kind is present) and, for each fault that appeared
during the run, the latency: the end of the first window that names it minus its onset.  (From a
source without ``fault_onsets_s``, a recording made before that key, a fault is known to have
appeared only between two diagnostics, up to 1 s apart: then the line gives both.)

The analysis runs on a thread of its own, and the callbacks only decode and queue: the
subscription keeps a bounded number of tables (``waveform_qos``: ``MONITOR_QUEUE_S`` of 10 ms
tables, 5 s of signal, 1.25 s when a recording plays at 4x), and an analysis on the executor thread (the first one imports scipy,
about 1 s) would let it overflow and lose tables.  On exit the monitor prints how many tables
it took and how many gaps it saw.  ``t=`` in its lines counts from the first table it took, whose
stamp it prints (``monitor: first table stamped 1764392867.120000000 s, t=0 below``): the
source's first table when the monitor was up before it and discovery lost none.  On exit, with
a simulator's diagnostics (whose ``simulated_s`` ties stamps to its signal time), a line says
where on the source's signal that table was, and so how much of it the monitor did not receive.

The simulator's end status (``run: ended`` in its last ``/diagnostics``) is printed, and the
monitor waits on for a node started again or the next pass of ``play --loop``; with ``--count``
(or ``--end-wait``) only until no table has come for ``end_wait`` s after it: a script that ran
a node with a ``duration`` beside ``monitor --count N`` waited forever for verdicts that could
not come.  Short of the count, that is exit status ``cli.EXIT_COUNT_NOT_REACHED`` (3).  A node
killed or crashed (or its machine off) sends no end status: the tables just stop, as they do while a
node with ``use_sim_time`` waits for ``/clock``.  What tells the two apart is the ROS graph: a node
gone leaves no publisher on ``accel`` (DDS drops one that died when its lease runs out: about 20 s
with Fast DDS).  The monitor says so in one line when it sees none left after tables came, waits on
for one to come back (a node restarted in its place), and with ``--count`` (or ``--end-wait``) ends
after ``end_wait`` s without one, exit status ``cli.EXIT_SOURCE_LOST`` (4).

Stamps that go back start a new run (:class:`SourceRun`): another recording played after the
first (``render`` stamps from 0), a node started again with sim time from 0.  The ground truth is
kept by stamp, and the diagnostics of the run before, stamped later than the new run's windows,
answered for them (a healthy recording played after an outer-race one scored ``truth=outer``).
So does a node started again on the wall clock after the end status (or once the publisher was
seen gone): its tables do not continue the last, its diagnostics' signal does not start where the
last run ended (the next pass of ``play --loop`` does both), and the end status of the run before
answered for its windows before its own first diagnostics.  So does a node killed and started
again within DDS's lease, seen neither gone nor ended (the graph keeps the dead publisher): its
tables' and diagnostics' publication sequence numbers (rclpy's message info) start over
(:class:`Publishers`).  One line says so; ``t=`` and the ground truth start afresh, and
the exit lines take each run on its own.
"""
from __future__ import annotations

import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import rclpy
from rclpy.node import Node

from .. import ground_truth
from ..analysis.envelope import (DETECTION_THRESHOLD, FAULT_LINES, STEADY_LINES, NoBand, band_words, borrowed_text, detector_band,
                                 diagnose, pick_verdict, spread, with_cage)
from ..analysis.orders import order_diagnose
from ..messages import RUN_ENDED, RUN_KEY, TOPIC_ACCEL, TOPIC_DIAGNOSTICS, TOPIC_STATE, waveform_qos
from ..stale_dds_ports import clear_before_start
from ..teardown import command_signals, say, say_on_stderr, teardown_watchdog
from .bearing_sim_node import NODE_NAME as SIMULATOR_NODE, PEER_CHECK_S
from ..waveform import NS, from_pointcloud2

DEFAULT_SCENE = "er16k_outer_race"
FAULT_NAMES = {"outer": "outer-race fault", "inner": "inner-race fault", "ball": "ball fault",
               "healthy": "healthy", "unknown": "no verdict"}
WARM_UP_RATE, WARM_UP_SAMPLES = 15000.0, 15000    # Hz and samples: the window analysed at start
TRUTH_GRACE_S = 0.25        # wall s a verdict waits for the diagnostics stamped at its window's end
SLACK_NS = 1000             # stamps this close count as the same instant (rounding to the ns)
MONITOR_QUEUE_S = 5.0       # s of 10 ms tables the accel subscription keeps (``waveform_qos``)
# what leaves no publisher on accel and no end status (a play stopped by a signal sends none either)
SOURCE_LOST_CAUSES = "killed, crashed, a play stopped, or lost to discovery"


class Window:
    """Contiguous waveform tables gathered into one (n, channels) array.

    ``add`` returns False when a table does not continue the previous one (then the window
    restarts with it).  The sample rate comes from the stamps: width / (stamp - previous stamp)
    of the first pair of tables after a start or a gap, confirmed by the next table (stamped where
    that rate ends the second): a single table between two gaps, stamped 2 s after the one
    before, gave a rate of 75 Hz that only the following table's stamp showed wrong, and the two
    tables made 4 s of that "signal", a verdict of the default ``--window`` on nothing.  A pair at
    the rate confirmed before the gap (the same source after a lost table, the next pass of play
    --loop, a node started again) needs no third table: with 1 s tables, that would have cost
    every run after the first a verdict."""

    def __init__(self):
        self.clear()
        self.sample_rate = None     # Hz, confirmed by a second pair; None after a start or a gap
        self._proposed_rate = None  # Hz, of the first pair, until the second confirms it
        self._last_rate = None      # Hz, the last confirmed, before the gap
        self.gaps = 0
        self._prev_stamp = None
        self._prev_width = None
        self.channels = None

    def clear(self):
        self.parts = []
        self.samples = 0
        self.first_stamp = None

    def continues(self, stamp_ns: int, channels) -> bool:
        """Would a table stamped ``stamp_ns`` with ``channels`` continue the last one added: the same
        channels, stamped where its samples end (1 us of rounding allowed) at the rate known or
        proposed; any later stamp where neither is (one table since a gap): that pair proposes it."""
        if self._prev_stamp is None:
            return True
        if list(channels) != self.channels:
            return False
        rate = self.sample_rate or self._proposed_rate
        if rate is None:
            return stamp_ns > self._prev_stamp
        return self._ends_last_at(stamp_ns, rate)

    def _ends_last_at(self, stamp_ns: int, rate: float) -> bool:
        """Is ``stamp_ns`` where the last table's samples end at ``rate`` (Hz)?  More than 1 us
        off: a table is missing or time jumped."""
        return abs(stamp_ns - self._prev_stamp - round(self._prev_width * NS / rate)) <= 1000

    def add(self, stamp_ns: int, channels, data: np.ndarray) -> bool:
        contiguous = self.continues(stamp_ns, channels)
        if not contiguous:
            self.gaps += 1
            self.clear()
            self._last_rate = self.sample_rate or self._last_rate
            self.sample_rate = self._proposed_rate = None
        elif self._prev_stamp is not None and self.sample_rate is None:
            if self._proposed_rate is None:         # the first pair of tables proposes the rate
                self._proposed_rate = self._prev_width * NS / (stamp_ns - self._prev_stamp)
                if self._last_rate and self._ends_last_at(stamp_ns, self._last_rate):
                    # that of before the gap: confirmed already
                    self.sample_rate, self._proposed_rate = self._proposed_rate, None
            else:                                   # and the next table, where it fits, confirms it
                self.sample_rate, self._proposed_rate = self._proposed_rate, None
        self._prev_stamp, self._prev_width = stamp_ns, data.shape[0]
        self.channels = list(channels)
        if self.first_stamp is None:
            self.first_stamp = stamp_ns
        self.parts.append(data)
        self.samples += data.shape[0]
        return contiguous

    def seconds(self) -> float:
        return self.samples / self.sample_rate if self.sample_rate else 0.0

    def take(self) -> np.ndarray:
        data = np.concatenate(self.parts, axis=0)
        self.clear()
        return data


def verdict(data: np.ndarray, channels, sample_rate: float, bearing, shaft_hz: float,
            cage_hz: float | None = None, spin_share: float | None = None,
            resonance_hz: float | None = None) -> dict:
    """Envelope verdict over the axes of ``data`` (n, channels): for each fault the highest
    prominence over the axes wins.  Returns {"verdict", "axis", "scores", "lines", "theory"}.
    The lines at pure rolling at ``shaft_hz`` (Hz), or with ``cage_hz`` (the cage's speed in
    ``state``, Hz) the cage, BPFO and BPFI where the cage put them (``envelope.with_cage``): at
    10000 rpm / 10 N the ER-16K's cage skids 7 %, and looking at pure rolling's BPFO the monitor
    called an outer-race pit a ball fault (2xBSF x215).  ``spin_share``: the balls' spin as a
    share of pure rolling's (``spin_share_of``; None: pure rolling), which moves BSF and so the
    ball pit's 2xBSF line: on the skidding tier at 2000 rpm / 200 N the balls spin 2.2 % slow, the
    line falls outside the +-1 % search at pure rolling's, and the monitor called a ball pit
    healthy (x0.9).  The envelope's band (``band``, Hz) is ``envelope.detector_band``'s for
    these lines (``resonance_hz``: the watched scene's resonator, Hz); where none serves them,
    ``verdict`` is "unknown" and ``no_band`` says why."""
    freqs = bearing.fault_frequencies(shaft_hz)
    if cage_hz:
        freqs = with_cage(freqs, bearing.balls, shaft_hz, cage_hz)
    if spin_share:
        freqs = {**freqs, "bsf": freqs["bsf"] * spin_share}
    band, why = detector_band(freqs, sample_rate, resonance_hz)
    if band is None:
        return {"verdict": "unknown", "no_band": why, "band": None, "theory": freqs, "shaft_hz": shaft_hz}
    result = _highest_over_axes(channels, lambda k: diagnose(data[:, k].astype(float), sample_rate, freqs, band))
    return {**result, "theory": freqs, "shaft_hz": shaft_hz, "band": band}


def _highest_over_axes(channels, diagnose_axis) -> dict:
    """{"verdict", "scores", "axis", "lines", "borrowed"} over ``channels`` from
    ``diagnose_axis(k)`` (an ``envelope.diagnose``-like result of axis ``k``): for each fault the
    highest prominence over the axes, and whether that axis found its line on another detected
    fault's sideband (``borrowed``: ``envelope.borrowed_lines``); the verdict as
    ``envelope.pick_verdict`` gives it, with the axis and lines of that fault (or of the highest)."""
    per_fault = {}          # fault -> (score, axis, lines of that axis, that axis's borrowed)
    for k, name in enumerate(channels):
        d = diagnose_axis(k)
        for fault, score in d["scores"].items():
            if fault not in per_fault or score > per_fault[fault][0]:
                per_fault[fault] = (score, name, d["lines"], d.get("borrowed", {}))
    scores = {fault: s for fault, (s, _axis, _lines, _borrowed) in per_fault.items()}
    borrowed = {fault: per_fault[fault][3][fault] for fault in per_fault if fault in per_fault[fault][3]}
    verdict = pick_verdict(scores, borrowed)
    top = verdict if verdict in per_fault else max(scores, key=scores.get)
    return {"verdict": verdict, "scores": scores, "axis": per_fault[top][1], "lines": per_fault[top][2],
            "borrowed": borrowed}


def order_verdict(data: np.ndarray, channels, sample_rate: float, times_s, bearing, states,
                  spin_share: float | None = None, spin_shares=None, resonance_hz: float | None = None) -> tuple:
    """The envelope verdict over the axes of ``data`` (n, channels; sample ``k`` at signal time
    ``times_s[k]``, s) in orders of the shaft (``orders.order_diagnose``), for a stretch whose
    speeds moved, where one spectrum in Hz smears every line: ``(result, "")`` with ``verdict``'s
    keys (``lines`` in orders) and ``shaft_rpm`` (slowest, fastest) and ``revolutions`` of the
    stretch tracked, or ``(None, why not)`` (``orders.untrackable``).  ``states``: the ``state``
    samples that span the stretch, (stamp s on ``times_s``' clock, shaft angle rad, shaft speed
    rad/s, cage angle rad, cage speed rad/s) arrays, NaN for an angle not given; a cage speed of
    NaN (a ``state`` without the cage) is pure rolling's, as ``verdict`` takes then;
    ``spin_share`` moves BSF as there; ``spin_shares`` (the balls' spin share at each state
    sample, ``spin_shares_at``), where given, instead: a skid that moves in the window
    (a speed step on the skidding tier) has the 2xBSF line judged on the balls' spin angle
    (``orders.order_diagnose``); ``resonance_hz``: the scene's resonator (Hz), for the envelope's
    band (``band``, Hz, at the fastest shaft speed: ``orders.order_diagnose``)."""
    state_t, shaft_angle, shaft_w, cage_angle, cage_w = (np.asarray(a, dtype=float) for a in states)
    per_shaft_hz = bearing.fault_frequencies(1.0)
    if spin_shares is not None:
        spin_share = None
    if spin_share:
        per_shaft_hz = {**per_shaft_hz, "bsf": per_shaft_hz["bsf"] * spin_share}
    if not np.all(np.isfinite(cage_w)):
        cage_w, cage_angle = shaft_w * per_shaft_hz["ftf"], np.full_like(shaft_w, np.nan)
    tracked = []            # order_diagnose's result of each axis
    for k in range(len(channels)):
        # why not is the same on every axis: it depends on the states and times alone
        result, why = order_diagnose(data[:, k].astype(float), sample_rate, times_s, state_t, shaft_angle, shaft_w,
                                     cage_angle, cage_w, per_shaft_hz, bearing.balls, spin_shares=spin_shares,
                                     resonance_hz=resonance_hz)
        if result is None:
            return None, why
        tracked.append(result)
    first = tracked[0]          # the stretch, speeds and orders are the same on every axis
    return {**_highest_over_axes(channels, tracked.__getitem__), "theory": first["orders"],
            "shaft_rpm": first["shaft_rpm"], "revolutions": first["revolutions"], "band": first["band"]}, ""


def spin_shares_at(spins, stamps_ns) -> np.ndarray | None:
    """The balls' spin share at each of ``stamps_ns`` (a window's state samples, ns) from
    ``spins`` ((stamp ns, share) of the diagnostics, ``SourceRun.spins``): each share (the mean of
    the second before its stamp) put half a second before its stamp, linear between them and held
    beyond; None without any (pure rolling).  (Held over each period instead, a ball pit over a
    step from 1000 to 2000 rpm scored x4.4, not x5.5.)"""
    spins = list(spins)         # the executor thread appends to it
    if not spins:
        return None
    at = np.array([stamp - NS // 2 for stamp, _share in spins], dtype=float)
    shares = np.array([share for _stamp, share in spins], dtype=float)
    return np.interp(np.asarray(stamps_ns, dtype=float), at, shares)


def spin_share_of(values: dict, bearing) -> float | None:
    """The balls' mean spin as a share of pure rolling's by a simulator's ``/diagnostics``
    ``values``: ``bsf_hz`` over the pure-rolling spin of ``bearing`` at the period's shaft speed
    (``cage_hz`` + ``bpfi_hz`` / Z, Hz).  1 on the kinematic tier, 1 - ``ball_skid_ratio`` / 100
    on the skidding tier (0.978 at 2000 rpm / 200 N on the ER-16K).  None where they do not give
    it (a real sensor, a recording made before ``bsf_hz``, a stopped shaft): then pure rolling."""
    try:
        bsf, cage, bpfi = (float(values[key]) for key in ("bsf_hz", "cage_hz", "bpfi_hz"))
    except (KeyError, ValueError):
        return None
    shaft = cage + bpfi / bearing.balls
    rolling = bearing.fault_frequencies(shaft)["bsf"] if np.isfinite(shaft) and shaft > 0 else 0.0
    share = bsf / rolling if rolling > 0 else float("nan")
    return share if np.isfinite(share) and share > 0 else None


def window_states(states, start_ns: int) -> tuple:
    """``order_verdict``'s ``states`` from the monitor's ``state`` records ``states`` ((stamp ns,
    shaft rad/s, cage rad/s or None, shaft angle rad, cage angle rad), in order) of a window whose
    first sample is stamped ``start_ns``: stamps in s from it, the cage speed NaN where not given."""
    return (np.array([(s[0] - start_ns) / NS for s in states]), np.array([s[3] for s in states]),
            np.array([s[1] for s in states]), np.array([s[4] for s in states]),
            np.array([np.nan if s[2] is None else s[2] for s in states]))


def format_verdict(t: float, result: dict) -> str:
    """One line per verdict (see the module docstring)."""
    parts = [f"t={t:.2f}s shaft={result['shaft_hz'] * 60:.0f}rpm verdict={result['verdict']} "
             f"truth={truth_text(result.get('truth'))}"]
    if result["verdict"] == "unknown" and result.get("no_band"):
        return " | ".join(parts + [result["no_band"]])
    if result["verdict"] == "unknown":
        untracked = result.get("untracked")
        return " | ".join(parts + [f"the shaft and cage speeds in state moved by {100 * result['moved']:.0f} % in "
                                   "the window (a speed step or ramp, a load step that changed the cage's skid): "
                                   "its envelope lines smear, no verdict"
                                   + (f"; no order tracking: {untracked}" if untracked else "")])
    in_orders = "shaft_rpm" in result           # order_verdict's: the lines in orders of the shaft
    if in_orders:
        slowest, fastest = result["shaft_rpm"]
        parts.append(f"in orders (order tracking over {slowest:.0f}-{fastest:.0f} rpm, {result['revolutions']:.0f} "
                     f"revolutions: the speeds in state moved by {100 * result['moved']:.0f} % in the window, which "
                     "smears the lines in Hz)")
    for fault, key in FAULT_LINES.items():
        if fault == "cage":
            continue
        line = result["lines"][key]
        where = f"{line.found_hz:.3f}/{line.expected_hz:.3f} orders" if in_orders else \
            f"{line.found_hz:.1f}/{line.expected_hz:.1f}Hz"
        parts.append(f"{key} {where} x{line.prominence:.1f}")
    parts += [borrowed_text(fault, result.get("borrowed", {})) for fault in result.get("borrowed", {})]
    band = f", band {band_words(result['band'])}" if result.get("band") else ""
    parts.append(f"({FAULT_NAMES[result['verdict']]}, threshold x{DETECTION_THRESHOLD:g}, axis {result['axis']}{band})")
    return " | ".join(parts)


# ---- ground truth and score (plain functions: test/test_monitor.py checks them without ROS) ----
def truth_at(reports, t_ns: int):
    """The faults (a sorted tuple of kinds) in the signal just before ``t_ns`` (a window's end) by
    the diagnostics ``reports`` (``ground_truth.Truth`` each, in arrival order), None when
    unknown: exact where a report stamped at or after ``t_ns`` has ``fault_onsets_s``, else the
    latest report's at or before it (``ground_truth.faults_at``)."""
    return ground_truth.faults_at(reports, t_ns, SLACK_NS)


def truth_text(truth) -> str:
    """``unknown``, ``none``, ``outer``, ``ball,outer`` (no space: one ``truth=`` word)."""
    return "unknown" if truth is None else ",".join(sorted(truth)) or "none"


def simulator_name(accel_topic: str, name: str | None = None) -> str:
    """The full name of the simulator whose ground truth goes with the waveform on ``accel_topic``
    (resolved: ``/rig1/accel``), as ROS resolves a node's name: ``name`` (default ``bearing_sim``)
    in that topic's namespace where it is a bare node name (``sim`` -> ``rig1/sim``; the node
    publishes ``accel`` relative to its own namespace), as given where it holds a namespace
    (``rig1/sim``), and from the root where it starts with ``/`` (``/bearing_sim``).  A bare name
    was taken from the root: ``--simulator sim`` beside ``-r __ns:=/left`` matched nothing."""
    name = name or SIMULATOR_NODE
    if "/" in name:
        return name.strip("/")
    namespace = accel_topic.rsplit("/", 1)[0].strip("/")
    return f"{namespace}/{name}" if namespace else name


def agrees(verdict: str, truth):
    """Does a verdict agree with the truth?  ``healthy`` with no fault, a fault verdict when
    that kind is present; None when the truth is unknown or there is no verdict (``unknown``)."""
    if truth is None or verdict == "unknown":
        return None
    return not truth if verdict == "healthy" else verdict in truth


def score_lines(scored, appeared, t0_ns: int) -> list:
    """The exit lines on ``scored`` ((window end ns, verdict, truth, whether the verdict is
    "unknown" for want of a detector band) per verdict, in order) and
    ``appeared``, the faults that appeared during the run (after ``t0_ns``, the first table's
    stamp) by all the diagnostics (``ground_truth.appearances``): agreement of each verdict with
    the truth its line printed (the diagnostics that came later may tell a window's truth
    better, after a grace that ran out, but the score must count what the lines say), and one
    latency line per appearance.  Times as in the verdict lines: s from ``t0_ns``."""
    marks = [agrees(verdict, truth) for _end, verdict, truth, _no_band in scored]
    known = [m for m in marks if m is not None]
    none = sum(verdict == "unknown" for _end, verdict, _truth, _no_band in scored)
    # no band for the lines is the sample rate's doing, not a speed that moved: said apart
    no_band = sum(bool(no_band) for _end, _verdict, _truth, no_band in scored)
    lines = [f"monitor: score {sum(known)} of {len(known)} verdicts agree with the truth, "
             f"{len(marks) - len(known) - none} truth=unknown"
             + (f", {none - no_band} verdict=unknown (the lines moved in the window)" if none > no_band else "")
             + (f", {no_band} verdict=unknown (no detector band for the fault lines at this sample rate)"
                if no_band else "")]
    if not scored:
        return lines
    calls = [(end, verdict) for end, verdict, _truth, _no_band in scored]
    for fault in appeared:
        before, after = ((t - t0_ns) / NS for t in (fault.earliest, fault.latest))
        found, since = ground_truth.first_detection(calls, fault, SLACK_NS)
        where = (f"{fault.kind} appeared at t={after:.2f}s" if fault.exact else
                 f"{fault.kind} appeared between t={before:.2f}s and t={after:.2f}s by the diagnostics")
        if found is None:
            lines.append(f"monitor: latency none: {where}, not called in {since} verdicts since")
            continue
        t = (found - t0_ns) / NS
        # from the later bound; without onsets to the sample, it may have been there up to
        # after - before longer
        more = "" if fault.exact else f" (to {after - before:.2f}s more)"
        lines.append(f"monitor: latency {max(0.0, t - after):.2f}s{more}: {where}, first called at t={t:.2f}s")
    return lines


def scene_mismatch_line(scene, values: dict, simulator: str):
    """The line that says the simulator ``simulator`` runs another scene than the monitor's
    ``scene`` (``--scene``), by the ``scene`` and ``bearing`` of its ``/diagnostics`` ``values``;
    None where it runs the same or does not say (a recording made before those keys).  The
    monitor keeps to ``--scene``, as a condition monitoring system keeps to the bearing its
    engineer configured; the line says whether that bearing is the signal's, and if not where the
    signal's BPFO is against the one the verdicts look at (at the simulator's shaft speed)."""
    theirs = values.get(ground_truth.SCENE_KEY)
    bearing = values.get(ground_truth.BEARING_KEY)
    # a scene copied from a shipped one keeps its ``name:`` whatever bearing it was given: the
    # name alone does not say that the fault lines are where the verdicts look
    if theirs is None or (theirs == scene.name and bearing in (None, scene.bearing.name)):
        return None
    bearing = bearing or "bearing not given"
    said = (f"monitor: {simulator!r} runs scene {theirs} ({bearing}), not --scene {scene.name} "
            f"({scene.bearing.name})")
    if bearing == scene.bearing.name:
        return (f"{said}: the same bearing, so the verdicts look for the fault lines where they are; "
                "only the operating point used without `state` is --scene's")
    try:
        shaft_hz = abs(float(values["shaft_speed_rad_s"])) / (2 * np.pi)
        where = (f" (BPFO {scene.bearing.fault_frequencies(shaft_hz)['bpfo']:.1f} Hz, the signal's "
                 f"{float(values['bpfo_hz']):.1f} Hz at {shaft_hz * 60:.0f} rpm)")
    except (KeyError, ValueError):
        where = ""
    # of the same name, the node's scene is a YAML that only its path tells from --scene's
    node_scene = "the path of the node's scene YAML" if theirs == scene.name else theirs
    return (f"{said}: the verdicts look for the fault lines of another bearing{where}; give the monitor "
            f"the node's scene (--scene {node_scene})")


def source_start_line(t0_ns: int, source_start_ns: int):
    """The exit line that places the first table taken (stamp ``t0_ns``) on the source's signal
    time line (its signal time 0 stamped ``source_start_ns``, by ``simulated_s`` of its
    diagnostics, to the us): at 0 the monitor took the whole signal; later, the seconds before it
    were not received (the monitor started after the source, or discovery lost the first
    tables).  None when the two do not fit (a diagnostics message from a later pass of a looped
    recording, its signal time started over)."""
    into = (t0_ns - source_start_ns) / NS
    if into < -1e-5:
        return None
    if into < 1e-5:
        return "monitor: first table at 0.000 s of the source's signal (by its diagnostics): none lost"
    return (f"monitor: first table at {into:.3f} s of the source's signal (by its diagnostics): the "
            f"{into:.3f} s before it not received (the monitor started after the source, or "
            f"discovery lost them)")


class SourceRun:
    """What the monitor knows of one run of its source, along which stamps only go on: a node from
    its start (a node started again on the wall clock, the passes of ``play --loop``: their stamps
    go on too), one recording played.  Its own ``t=`` clock, ground truth and verdicts."""

    def __init__(self, number: int):
        self.number = number        # 1, 2, ... in the order the monitor saw them
        self.t0 = None              # stamp (ns) of its first table taken: its t= counts from there
        self.source_start = None    # stamp (ns) of the source's signal time 0, by its diagnostics
        # ground_truth.Truth of the /diagnostics that the windows still to come may ask about
        # (stamps in ns; ground_truth.forget_before after each verdict), and what the latency lines
        # need of them all: a monitor kept every 1 Hz message for those, about 1 kB an hour
        self.reports = []
        self.appeared = ground_truth.AppearanceLog(SLACK_NS)
        self.verdicts = []          # (window end ns, verdict, truth, no band) of its own verdicts
        self.windows = 0            # its windows queued for analysis
        self.last_table = None      # stamp (ns) of its latest table
        self.last_report = None     # stamp (ns) of its simulator's latest /diagnostics
        # (stamp ns, the balls' spin share: ``spin_share_of``) of its simulator's /diagnostics that
        # windows still to come may ask about: where the balls skid, a ball pit's 2xBSF line is
        # off pure rolling's
        self.spins = []

    def spin_share(self, start_ns: int, end_ns: int) -> float | None:
        """The balls' spin share over the window ``start_ns`` - ``end_ns``: the mean of the
        diagnostics stamped in it (each the mean of the second before its stamp), else the latest
        before it; None without any (pure rolling)."""
        spins = list(self.spins)        # the executor thread appends to it
        inside = [share for stamp, share in spins if start_ns + SLACK_NS < stamp <= end_ns + SLACK_NS]
        before = [share for stamp, share in spins if stamp <= start_ns + SLACK_NS][-1:]
        chosen = inside or before
        return float(np.mean(chosen)) if chosen else None

    def forget_spins_before(self, t_ns: int) -> None:
        """Drop the spins that no window ending after ``t_ns`` reads: all before the latest stamped
        at or before it (as ``ground_truth.forget_before`` does with the truth)."""
        k = sum(1 for stamp, _share in list(self.spins) if stamp <= t_ns + SLACK_NS)
        del self.spins[:max(0, k - 1)]

    def exit_lines(self) -> list:
        """Where its first table was on the source's signal (where the diagnostics say), then the
        score and latency lines of its verdicts (``score_lines``)."""
        t0 = self.t0 or 0
        lines = []
        if self.t0 is not None and self.source_start is not None:
            line = source_start_line(self.t0, self.source_start)
            if line:
                lines.append(line)
        return lines + score_lines(self.verdicts, self.appeared.appearances(t0), t0)


def stamp_text(stamp_ns: int) -> str:
    """A stamp (ns) in s to the ns: ``1764392867.120000000`` (a float of it is 0.2 us off)."""
    return f"{stamp_ns // NS}.{stamp_ns % NS:09d}"


def went_back(what: str, stamp_ns: int, last_ns: int) -> str:
    """Why a run starts where a ``what`` (``table``, ``/diagnostics``) stamped ``stamp_ns`` came
    after one of ``last_ns`` on the same topic (``new_run_line``)."""
    return (f"a {what} stamped {stamp_text(stamp_ns)} s after one stamped {stamp_text(last_ns)} s: the stamps went back "
            "(another recording played, a node started again with sim time from 0)")


def started_again(what: str, stamp_ns: int, after: str) -> str:
    """Why a run starts where a ``what`` stamped ``stamp_ns`` does not continue the run that ended
    or was lost (``after``: ``its end status``, ``its publisher was gone``; ``new_run_line``)."""
    return f"a {what} stamped {stamp_text(stamp_ns)} s not continuing the run before, after {after}: a node started again"


def publication_number(info) -> int | None:
    """The publication sequence number of a message, from the message info that rclpy gives a
    subscription callback that takes two arguments: its publisher numbers its messages 1, 2, ...
    (a node started again numbers from 1 anew).  None where the middleware does not give it, or
    without the info (a callback called directly)."""
    return info.get("publication_sequence_number") if info else None


class Publishers:
    """The publishers of one topic, told apart by the publication sequence numbers of their
    messages (``publication_number``): each numbers its own 1, 2, ..., so a message goes on from
    the publisher whose last number is the highest below its own, and one numbered at most the
    last of every publisher known is from a new one (a node started again numbers from 1 anew).
    The stamps cannot tell a node killed and started again at once on the wall clock (they jump
    on, as after lost tables), nor can the graph (DDS keeps the dead publisher for its lease,
    about 20 s), and rclpy gives no publisher GID with a message.  Two publishers whose messages
    interleave (two simulators in one namespace) stay two, not a new one at every switch; the
    switches are counted (``switches``), for telling them from a dead publisher the graph keeps."""

    KEPT = 256      # publishers remembered, the latest to go on: a dead one stays at its last number

    def __init__(self):
        self.last = []              # the last number of each publisher known, the latest last
        self.previous = None        # the number of the message before on the topic
        self.numbered = False       # a message came with its number
        # messages from another publisher than the message before's (the first message is none)
        self.switches = 0

    def is_new(self, number: int | None) -> bool:
        """Is the message numbered ``number`` from a publisher not known before (the first message
        too)?  False where ``number`` is None (the middleware does not give it).  Counts it."""
        if number is None:
            return False
        self.numbered = True
        self.previous = self.last[-1] if self.last else None
        below = [k for k, last in enumerate(self.last) if last < number]
        # the publisher it goes on from (None: a new one)
        going_on = max(below, key=self.last.__getitem__) if below else None
        if self.last and going_on != len(self.last) - 1:
            self.switches += 1
        if going_on is not None:
            del self.last[going_on]
        self.last = (self.last + [number])[-self.KEPT:]
        return going_on is None


def new_publisher(what: str, stamp_ns: int, number: int, previous: int) -> str:
    """Why a run starts where a ``what`` stamped ``stamp_ns``, numbered ``number`` by a new
    publisher (``Publishers``), came after one numbered ``previous`` (``new_run_line``)."""
    return (f"a {what} stamped {stamp_text(stamp_ns)} s from a new publisher (its publication sequence number "
            f"{number} after {previous}: a node started again within DDS's lease)")


def new_run_line(number: int, why: str) -> str:
    """The line that says run ``number`` starts, and ``why``."""
    return f"monitor: run {number}: {why}; t= and the ground truth start afresh"


class MonitorNode(Node):
    """Subscribes to ``accel``, ``state`` and ``/diagnostics``; prints a verdict every ``window``
    s of signal, with the ground truth the diagnostics of ``simulator`` give (its full name,
    ``rig1/bearing_sim``, or a node name in the namespace of ``accel``: :func:`simulator_name`)."""

    def __init__(self, scene, window: float, count: int = 0, out=None, simulator: str | None = None,
                 end_wait: float | None = None, **kwargs):
        from diagnostic_msgs.msg import DiagnosticArray
        from sensor_msgs.msg import JointState, PointCloud2

        super().__init__("bearing_monitor", **kwargs)
        self.scene = scene
        self.window_s = float(window)
        self.count = int(count)
        # s without a table after the simulator's end status before the monitor ends (None: never)
        self.end_wait = end_wait
        self.out = out or sys.stdout
        self.window = Window()
        self.tables = 0
        self.rejected = 0           # tables that were no waveform table or held non-finite samples
        self.windows_queued = 0
        self.windows_done = 0       # analysed (printed, or failed and logged)
        # the watched simulator's end status while no table of a later run or pass came: (its stamp,
        # ns: the end of the run's last table; monotonic s it came); and when the last table came
        self._ended = None
        self._last_table_at = None
        # monotonic s since when every look at the graph found no publisher on accel, after tables
        # came and without an end status (None: one is there, or none is expected)
        self._gone_since = None
        # the source was seen gone (no publisher, no end status) and nothing of it came since: what
        # comes next that does not continue its run is a new run
        self._lost = False
        # (window end ns, verdict, truth) of each verdict printed, for the score at the end: the
        # whole analysis (lines, scores, frequencies) kept per verdict was about 3 kB, and a
        # monitor left running grew by megabytes an hour
        self.verdicts = []
        # the run of the source the tables now come from, and the runs before it that have windows
        # (their verdicts, some maybe still in the analysis queue, and the lines they give at exit)
        self.run = SourceRun(1)
        self.runs_before = []
        self._went_back_said_at = None  # monotonic s of the last run-started line (throttled)
        self._run_said = True           # the current run's start was said (its first table is, then)
        # the publishers of the tables and of the watched simulator's /diagnostics: a new one is a
        # node started again, maybe within DDS's lease
        self._table_publishers = Publishers()
        self._report_publishers = Publishers()
        self.simulator = simulator_name(self.resolve_topic_name(TOPIC_ACCEL), simulator)
        self.simulator_given = simulator    # --simulator as given (None: the default, resolved)
        self._several_said = False
        self.truth_status = ground_truth.status_name(self.simulator)
        self.ignored = set()        # names of other simulators' statuses, said once each
        self._trouble = ""          # the simulator's trouble said last (``_say_trouble``): "", "error", "behind"
        self.scenes_said = set()    # the simulator's (scene, bearing) that are not --scene's, said once each
        self._speeds = []
        self._warned = False
        # the OSError of a verdict line that could not be written (no reader: BrokenPipeError; a full disk)
        self.output_failed = None
        # one worker: verdicts come out in signal order; the windows wait in its queue, so an
        # analysis slower than the signal would grow it (8 ms per 3 s window here, no danger)
        self._analysis = ThreadPoolExecutor(max_workers=1, thread_name_prefix="envelope")
        # one analysis of a made-up window before the tables come: the first one imported
        # scipy.signal and built its filters, a second or two on a busy machine while the tables
        # arrived, and the subscription's one-second queue overflowed (a monitor started before
        # the node missed its first 0.12 and 1.53 s in two of eight runs under load)
        warm = np.random.default_rng(0).standard_normal((WARM_UP_SAMPLES, 1))
        verdict(warm, ("warm_up",), WARM_UP_RATE, scene.bearing, scene.shaft_hz)
        # reliable like the node offers; depth = MONITOR_QUEUE_S of 10 ms batches: the executor
        # thread only decodes tables, but on a busy machine it can stall for a fraction of a second,
        # and 1 s of them (0.25 s of a recording played at 4x) then overflowed: a table lost and a
        # window restarted, in about 1 run in 8 of test_monitor's 4x play beside other work
        # (the callbacks of accel and /diagnostics take the message info too, for the publication
        # sequence number that tells a new publisher: rclpy gives it to a callback of two arguments)
        self.create_subscription(PointCloud2, TOPIC_ACCEL,
                                 lambda msg, info: self._on_accel(msg, publication_number(info)),
                                 waveform_qos(0.01, MONITOR_QUEUE_S))
        self.create_subscription(JointState, TOPIC_STATE, self._on_state, 10)
        self.create_subscription(DiagnosticArray, TOPIC_DIAGNOSTICS,
                                 lambda msg, info: self._on_diagnostics(msg, publication_number(info)), 10)

    @property
    def done(self) -> bool:
        return bool(self.count) and len(self.verdicts) >= self.count

    def run_over(self, now: float) -> bool:
        """Has the simulator's run ended for good, by ``end_wait``: its end status came, no table
        for ``end_wait`` s since it or the last table (those still queued behind it, DDS orders
        no topic against another), and every window taken is analysed.  A table stamped at or
        after the end status (the next pass of ``play --loop``, a node started again) cancels it."""
        if self.end_wait is None or self._ended is None or self.windows_done < self.windows_queued:
            return False
        return now - max(self._ended[1], self._last_table_at or 0.0) >= self.end_wait

    def source_lost(self, now: float) -> bool:
        """Has the source gone away without an end status, by ``end_wait``: tables came, then every
        look at the graph for ``end_wait`` s found no publisher on ``accel`` (``check_sources``)
        and no table came, and every window taken is analysed.  Tables that merely stop (a node
        waiting for ``/clock``, a stalled one) leave its publisher: that is no loss."""
        if self.end_wait is None or self._gone_since is None or self.windows_done < self.windows_queued:
            return False
        return now - max(self._gone_since, self._last_table_at) >= self.end_wait

    def _until(self, awaited: str) -> str:
        """What ends the wait for ``awaited`` (a table) that a waiting line names: ``end_wait``
        or, without it, Ctrl-C."""
        if self.end_wait is None:
            return "Ctrl-C ends the monitor"
        return f"without {awaited} for {self.end_wait:g} s the monitor ends"

    def _whose_truth(self) -> str:
        """Why the truth is that simulator's, for the line on another one's: the default is the
        simulator of the watched accel topic, which a user who gave no --simulator did not choose
        (the line said "--simulator names another" to them)."""
        if self.simulator_given is None:
            return (f"the simulator of {self.resolve_topic_name(TOPIC_ACCEL)} "
                    "(--simulator NAME takes another's)")
        return f"the simulator --simulator {self.simulator_given} names"

    def _on_state(self, msg):
        names = list(msg.name)
        if "shaft" in names and len(msg.velocity) == len(names):
            cage = float(msg.velocity[names.index("cage")]) if "cage" in names else None
            stamp = msg.header.stamp.sec * NS + msg.header.stamp.nanosec
            # the angles for order tracking (NaN where another tool leaves them out: then the
            # speeds alone give them)
            angles = msg.position if len(msg.position) == len(names) else [np.nan] * len(names)
            self._speeds.append((stamp, float(msg.velocity[names.index("shaft")]), cage,
                                 float(angles[names.index("shaft")]),
                                 float(angles[names.index("cage")]) if cage is not None else np.nan))

    def _on_diagnostics(self, msg, number: int | None = None):
        """A /diagnostics message, ``number`` by its publisher (``publication_number``; None:
        not known)."""
        stamp = msg.header.stamp.sec * NS + msg.header.stamp.nanosec
        for status in msg.status:           # a simulator's: a status with faults_present
            values = {kv.key: kv.value for kv in status.values}
            truth = ground_truth.parse(values, stamp, NS)
            if truth is None:
                continue
            if status.name != self.truth_status:
                # another rig's simulator (all publish on the one /diagnostics): its faults are
                # not in this waveform
                if status.name not in self.ignored:
                    self.ignored.add(status.name)
                    say(f"monitor: ground truth of {status.name!r} ignored: truth= is that of "
                        f"{self.truth_status!r}, {self._whose_truth()}", self.out)
                continue
            new = self._report_publishers.is_new(number)
            if self.run.last_report is not None and stamp < self.run.last_report - SLACK_NS:
                self._start_run(went_back("/diagnostics", stamp, self.run.last_report))
            else:
                after = self._started_again_after(values, stamp)
                if after:
                    self._start_run(started_again("/diagnostics", stamp, after))
                elif new and self.run.last_report is not None:
                    self._start_run(new_publisher("/diagnostics", stamp, number, self._report_publishers.previous))
            self._lost = False
            self.run.last_report = stamp
            self.run.reports.append(truth)
            self.run.appeared.add(truth)
            self._check_scene(values)
            self._say_trouble(status, values)
            share = spin_share_of(values, self.scene.bearing)
            if share is not None:
                self.run.spins.append((stamp, share))
            if values.get(RUN_KEY) == RUN_ENDED:
                # the simulator's end status (its last /diagnostics): the tables stopped because the
                # run is complete (or was stopped), not because it crashed or discovery lost it
                self._ended = (stamp, time.monotonic())
                say(f"monitor: {self.simulator}: {status.message}; waiting for more (a node started "
                    f"again, the next pass of play --loop; {self._until('a table')})", self.out)
            if self.run.source_start is None and ground_truth.TIME_KEY in values:
                try:
                    self.run.source_start = stamp - round(float(values[ground_truth.TIME_KEY]) * NS)
                except ValueError:
                    pass

    def _say_trouble(self, status, values: dict) -> None:
        """The watched simulator's own trouble, said once as it begins and once as it ends: an
        ERROR (its recording failed, its solver diverged) or falling behind real time
        (``falling_behind``), which delays every verdict.  The monitor printed a simulator's
        status only at its end, and a recording that failed an hour into a run went unsaid.
        The end status is said on its own (``_on_diagnostics``)."""
        level = status.level[0] if isinstance(status.level, (bytes, bytearray)) else int(status.level)
        trouble = ("error" if level >= 2 else "behind" if values.get("falling_behind") == "true" else "")
        if values.get(RUN_KEY) == RUN_ENDED or trouble == self._trouble:
            return
        if trouble:
            say(f"monitor: {self.simulator} says ({'ERROR' if trouble == 'error' else 'WARN'}): {status.message}",
                self.out)
        else:
            say(f"monitor: {self.simulator}: {'no error' if self._trouble == 'error' else 'keeping up'} "
                f"again ({status.message})", self.out)
        self._trouble = trouble

    def _started_again_after(self, values: dict, stamp: int):
        """After what (``its end status``, ``its publisher was gone``) a diagnostics of the watched
        simulator stamped ``stamp`` with ``values`` begins a run of its own, or None where it goes
        on with the run, or cannot tell (no ``simulated_s``).  Its signal's start (``stamp -
        simulated_s``) tells: the next pass of ``play --loop`` starts where the end status said the
        last ended; the same node back after it was seen gone (a pause longer than DDS's lease)
        keeps its start."""
        if self._ended is None and not self._lost:
            return None
        try:
            start = stamp - round(float(values[ground_truth.TIME_KEY]) * NS)
        except (KeyError, ValueError):
            return None
        if self._ended is not None:
            if stamp < self._ended[0] - SLACK_NS or abs(start - self._ended[0]) <= 2 * SLACK_NS:
                return None
            return "its end status"
        if self.run.source_start is not None and abs(start - self.run.source_start) <= 2 * SLACK_NS:
            return None
        return "its publisher was gone"

    def _check_scene(self, values: dict) -> None:
        """Say once (for each scene it runs) that the simulator runs another scene than
        ``--scene``: the verdicts may look for the fault lines of another bearing."""
        theirs = (values.get(ground_truth.SCENE_KEY), values.get(ground_truth.BEARING_KEY))
        if theirs in self.scenes_said:
            return
        line = scene_mismatch_line(self.scene, values, self.simulator)
        if line:
            self.scenes_said.add(theirs)
            say(line, self.out)

    def _on_accel(self, msg, number: int | None = None):
        """A table on accel, ``number`` by its publisher (``publication_number``; None: not known)."""
        self._last_table_at = time.monotonic()
        if self.count and self.windows_queued >= self.count:
            return
        try:
            stamp, channels, data = from_pointcloud2(msg)
            if not np.all(np.isfinite(data)):
                raise ValueError("non-finite samples")
        except ValueError as exc:
            # a bad table from some other publisher: skip it, say so now and then, keep going
            self.rejected += 1
            self.get_logger().warning(f"accel table rejected ({exc}); {self.rejected} so far",
                                      throttle_duration_sec=5.0)
            return
        self.tables += 1
        ended = self._ended is not None and stamp >= self._ended[0] - SLACK_NS
        new = self._table_publishers.is_new(number)
        if self.run.last_table is not None and stamp < self.run.last_table - SLACK_NS:
            self._start_run(went_back("table", stamp, self.run.last_table))
        elif (ended or self._lost) and not self.window.continues(stamp, channels):
            self._start_run(started_again("table", stamp, "its end status" if ended else "its publisher was gone"))
        elif new and self.run.last_table is not None:
            self._start_run(new_publisher("table", stamp, number, self._table_publishers.previous))
        self._lost = False
        first_of_run = self.run.last_table is None      # of a new run (said), or the monitor's first
        self.run.last_table = stamp
        if self._ended is not None and stamp >= self._ended[0] - SLACK_NS:
            self._ended = None      # a table after the end: the next pass, a node started again
        if self.run.t0 is None:
            self.run.t0 = stamp
            # t= counts from here: the source's first table unless discovery or a late start
            # lost some, which this stamp (against a recording's first) tells; unsaid for a run
            # whose start went unsaid (two sources interleaving start one at every switch)
            if self._run_said:
                say(f"monitor: first table stamped {stamp_text(stamp)} s, t=0 below", self.out)
        if not self.window.add(stamp, channels, data) and not first_of_run:
            self.get_logger().warning("accel tables not contiguous (a table was lost or the source "
                                      "restarted): starting the window again", throttle_duration_sec=5.0)
            self._speeds = []
        if self.window.sample_rate and self.window.seconds() >= self.window_s:
            fs = self.window.sample_rate
            end = stamp + round(data.shape[0] * NS / fs)
            # the states of this window's signal, by their stamps (the end of their batch): the
            # state of its last batch may come after its table, and then goes uncounted
            start = self.window.first_stamp
            speeds = [s for s in self._speeds if start + SLACK_NS < s[0] <= end + SLACK_NS]
            # for order tracking, the states that span the window: those in it and the last at or
            # before its start (its shaft angle where the window begins)
            before = [s for s in self._speeds if s[0] <= start + SLACK_NS][-1:]
            # the last at or before the end stays: it begins the next window (it comes after this
            # window's last table, or with it)
            self._speeds = ([s for s in self._speeds if s[0] <= end + SLACK_NS][-1:]
                            + [s for s in self._speeds if s[0] > end + SLACK_NS])
            # the speed in use comes from `state`; without it, the scene's operating point
            shaft = float(np.mean([s[1] for s in speeds])) if speeds else float(self.scene.shaft_speed)
            cages = [s[2] for s in speeds if s[2] is not None]
            cage = float(np.mean(cages)) if cages else None
            moved = max(spread([s[1] for s in speeds]), spread(cages))
            # only a window whose lines move is order tracked, and only its states go with it
            states = window_states(before + speeds, start) if moved > STEADY_LINES else None
            self.windows_queued += 1
            self.run.windows += 1
            self._analysis.submit(self._analyse, end, self.window.take(), channels, fs, shaft,
                                  time.monotonic() + TRUTH_GRACE_S, self.run, cage, moved, states, start)

    def _analyse(self, end: int, x: np.ndarray, channels, fs: float, shaft: float, grace: float,
                 run: SourceRun | None = None, cage: float | None = None, moved: float = 0.0,
                 states=None, start: int | None = None) -> None:
        """On the analysis thread: one verdict with the truth at the window's ``end`` (ns),
        printed.  ``grace``: until when (monotonic s) to wait for the diagnostics stamped there;
        ``run``: the run of the source the window is of (default the current one), whose clock
        and ground truth it takes: a new run may start while the window waits in the queue.
        ``shaft``, ``cage``: their mean speeds in the window (rad/s; ``cage`` None without it in
        ``state``); ``moved``: how far they moved in it (``envelope.spread``), beyond
        ``STEADY_LINES`` the verdict in orders of the shaft (``order_verdict`` with ``states``,
        ``window_states``), or where that cannot be, none (``unknown``); ``start``: the stamp (ns)
        of the window's first sample, for the balls' spin of the diagnostics stamped in it."""
        try:
            self._verdict_line(end, x, channels, fs, shaft, grace, run or self.run, cage, moved, states, start)
        except OSError as exc:
            # the reader of the lines went away (``monitor | head -3``: BrokenPipeError) or their
            # file could not take them (ENOSPC of a full disk, EIO of a failing one): raised on
            # this thread, it went unseen into the future, and the monitor ran on printing to
            # nobody, or a --count ended it with 0; the main thread raises it
            # (``raise_output_failure``) as it does its own lines' (cli: 141, or exit 1)
            self.output_failed = exc
        finally:
            self.windows_done += 1

    def raise_output_failure(self) -> None:
        """Raise the OSError of a verdict line that could not be written, if there was one."""
        if self.output_failed is not None:
            raise self.output_failed

    def _verdict_line(self, end: int, x: np.ndarray, channels, fs: float, shaft: float, grace: float,
                      run: SourceRun, cage: float | None = None, moved: float = 0.0, states=None,
                      start: int | None = None) -> None:
        """``_analyse``'s work: the verdict on the window of ``run`` that ends at ``end``, printed."""
        t = (end - run.t0) / NS
        shaft_hz = abs(shaft) / (2 * np.pi)
        reports = run.reports
        while time.monotonic() < grace and not (reports and reports[-1].t >= end - SLACK_NS):
            time.sleep(0.01)        # the diagnostics stamped at ``end`` (if any) are not in yet
        spin = run.spin_share(end if start is None else start, end)
        try:
            if moved > STEADY_LINES:
                # a step or ramp in the window smeared its lines in Hz ("healthy" of an outer-race
                # pit): in orders of the shaft they hold still
                # the balls' spin at each state sample (``window_states``' stamps: s from ``start``):
                # a skid that moves in the window moves 2xBSF
                shares = (spin_shares_at(run.spins, (end if start is None else start) + np.asarray(states[0]) * NS)
                          if states is not None else None)
                tracked, why = (order_verdict(x, channels, fs, np.arange(x.shape[0]) / fs, self.scene.bearing, states,
                                              spin, shares, self.scene.structure.resonator_hz)
                                if states is not None else (None, "no state samples in the window"))
                result = ({**tracked, "shaft_hz": shaft_hz, "moved": moved} if tracked is not None else
                          {"verdict": "unknown", "shaft_hz": shaft_hz, "moved": moved, "untracked": why})
            else:
                result = verdict(x, channels, fs, self.scene.bearing, shaft_hz,
                                 None if cage is None else abs(cage) / (2 * np.pi), spin,
                                 self.scene.structure.resonator_hz)
        except Exception as exc:  # noqa: BLE001 - a failed analysis must not end the monitor silently
            self.get_logger().error(f"envelope analysis at t={t:.2f}s failed: {exc}")
            return
        result.update(end_ns=end, truth=truth_at(reports, end))
        # no detector band for the lines, in Hz or (the speeds moved) in orders
        no_band = "no_band" in result or isinstance(result.get("untracked"), NoBand)
        scored = (end, result["verdict"], result["truth"], no_band)
        self.verdicts.append(scored)
        run.verdicts.append(scored)
        say(format_verdict(t, result), self.out)
        ground_truth.forget_before(reports, end, SLACK_NS)      # the next windows end later
        run.forget_spins_before(end)

    def _start_run(self, why: str) -> None:
        """A new run of the source, for ``why`` (``went_back``, ``started_again``).  The run before
        keeps its clock and truth for its windows still queued; said in one line, at most every
        5 s, with its first table's stamp (two sources whose tables interleave would start one at
        every switch)."""
        if self.run.windows:
            self.runs_before.append(self.run)
        self.run = SourceRun(self.run.number + 1)
        self._ended = None          # the end status was the run before's
        self._lost = False
        self._speeds = []
        now = time.monotonic()
        self._run_said = self._went_back_said_at is None or now - self._went_back_said_at >= 5.0
        if self._run_said:
            self._went_back_said_at = now
            say(new_run_line(self.run.number, why), self.out)

    def exit_lines(self) -> list:
        """The lines after the verdict count at exit: those of the run (``SourceRun.exit_lines``);
        after stamps went back, the score over all verdicts, then each run's with its number (its
        latency lines' t= are on its own clock, as its verdict lines were)."""
        runs = [run for run in self.runs_before if run.windows]
        if self.run.windows or not runs:
            runs.append(self.run)
        if len(runs) == 1:
            return runs[0].exit_lines()
        lines = score_lines(self.verdicts, [], 0)[:1]
        for run in runs:
            lines += [line.replace("monitor: ", f"monitor: run {run.number}: ", 1) for line in run.exit_lines()]
        return lines

    def check_sources(self) -> None:
        """Several publishers on ``accel`` (two simulators in one namespace, a ``play`` beside a
        node): their tables interleave, each switch reads as a gap or a restarted source, and the
        verdicts (and their t=) are of no one signal.  Said once, once the tables are seen to switch
        publishers back and forth (``Publishers.switches``).  And none left after tables came,
        without an end status (a node killed or crashed): said once each time, for ``source_lost``."""
        topic = self.resolve_topic_name(TOPIC_ACCEL)
        n = self.count_publishers(topic)
        switches, self._table_publishers.switches = self._table_publishers.switches, 0
        if n or self._ended is not None or self._last_table_at is None:
            self._gone_since = None
        elif self._gone_since is None:
            self._gone_since = time.monotonic()
            self._lost = True
            say(f"monitor: no publisher on {topic} any more and no end status from {self.simulator} "
                f"({SOURCE_LOST_CAUSES}); waiting for one (a node started again; {self._until('one')})", self.out)
        # a publisher that sends no tables interleaves none: a node killed and started again
        # within DDS's lease leaves its dead publisher in the graph (the tables switched once, to
        # the new one); said where they switched back and forth since the last look, or without
        # their publication sequence numbers (as where no table came yet)
        if n > 1 and not self._several_said and (switches > 1 or not self._table_publishers.numbered):
            self._several_said = True
            say(f"monitor: {n} publishers on {topic}: their tables interleave and the verdicts are not of "
                f"one signal; give each simulator its own namespace and watch one (--ros-args -r __ns:=/rig1)",
                self.out)

    def finish(self) -> None:
        """The window being analysed finishes, its verdict said; queued ones are dropped (Ctrl-C
        means stop).  Before the exit lines, which count its verdict, and before the middleware's
        teardown, which may hang (``teardown_watchdog``)."""
        self._analysis.shutdown(wait=True, cancel_futures=True)

    def destroy_node(self):
        self.finish()
        return super().destroy_node()


def main(args, ros_args=()) -> int:
    """``bearing-sim monitor --window S --count N --end-wait S --scene S --simulator NAME
    [--ros-args ...]``; exit 0 after ``count`` verdicts, on Ctrl-C or SIGTERM, or (without
    ``count``, with ``end_wait``) after the simulator's run ended; ``cli.EXIT_COUNT_NOT_REACHED``
    with one line where its run ended before ``count`` verdicts (``end_wait`` s without a table
    after its end status: default ``cli.MONITOR_END_WAIT_S`` with ``count``, else never);
    ``cli.EXIT_SOURCE_LOST`` with one line where, with ``end_wait``, the tables' publisher went
    away without an end status and none came back for ``end_wait`` s; 2 with
    one line for a bad scene or ROS argument.  ``ros_args``: from ``--ros-args`` on (a namespace,
    remaps)."""
    from rclpy._rclpy_pybind11 import RCLError, UnknownROSArgsError
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    from ..cli import EXIT_COUNT_NOT_REACHED, EXIT_OK, EXIT_SOURCE_LOST, MONITOR_END_WAIT_S
    from ..scene import load_scene
    from .bearing_sim_node import ros_arguments_error

    # UserError: exit 2; an empty --scene ("$SCENE" unset) too, which ran the default scene
    scene = getattr(args, "scene", None)
    scene = load_scene(DEFAULT_SCENE if scene is None else scene)
    # the command's handlers from its first line (cli.SIGNAL_COMMANDS): a Ctrl-C while numpy and
    # rclpy were imported went missing, and the monitor waited on for tables
    signals = command_signals()
    node = executor = None
    status = EXIT_OK
    try:
        try:
            signals.check()
            clear_before_start(say_on_stderr)
            rclpy.init(args=["bearing-sim monitor", *ros_args], signal_handler_options=SignalHandlerOptions.NO)
            end_wait = getattr(args, "end_wait", None)
            if end_wait is None and args.count:
                end_wait = MONITOR_END_WAIT_S       # a script's --count N must not wait forever
            node = MonitorNode(scene, args.window, args.count, simulator=getattr(args, "simulator", None),
                               end_wait=end_wait)
        except (RCLError, UnknownROSArgsError) as exc:
            if isinstance(exc, RCLError) and rclpy.ok():
                raise                   # not the arguments: rclpy.init went through
            raise ros_arguments_error(exc) from None
        signals.check()
        say(f"monitor: {scene.bearing.name} ({scene.name}), envelope analysis every {args.window:g} s "
            f"of {node.resolve_topic_name(TOPIC_ACCEL)}, ground truth from /diagnostics "
            f"{node.truth_status!r}")
        # one executor for the run: rclpy.spin_once(node) adds and removes the node at every
        # call, a wait set rebuilt per callback at 100 tables/s
        try:
            executor = SingleThreadedExecutor()
        except RCLError:
            if rclpy.ok():
                raise
            raise ExternalShutdownException() from None     # Ctrl-C before the first spin
        executor.add_node(node)
        t_start = next_look = time.monotonic()
        while rclpy.ok() and not node.done and signals.first is None:
            node.raise_output_failure()
            if node.source_lost(time.monotonic()):
                status = EXIT_SOURCE_LOST
                of = f" of --count {node.count}" if node.count else ""
                say(f"monitor: {len(node.verdicts)}{of} verdicts: no publisher on "
                    f"{node.resolve_topic_name(TOPIC_ACCEL)} for {node.end_wait:g} s and no end status from "
                    f"{node.simulator} ({SOURCE_LOST_CAUSES}; exit status {status})")
                break
            if node.run_over(time.monotonic()):
                if node.count:
                    status = EXIT_COUNT_NOT_REACHED
                    say(f"monitor: {len(node.verdicts)} of --count {node.count} verdicts: the run of "
                        f"{node.simulator} ended and no table came in the {node.end_wait:g} s since "
                        f"(exit status {status})")
                break
            executor.spin_once(timeout_sec=0.2)
            if time.monotonic() >= next_look:
                next_look += PEER_CHECK_S
                node.check_sources()
            # no table at all, not an empty window: the window is empty too from the moment it is
            # taken for its analysis, and a first window that ended after 5 s said "no waveform
            # tables yet" with hundreds taken
            if not node.tables and not node.rejected and time.monotonic() - t_start > 5.0 and not node._warned:
                node._warned = True
                say(f"monitor: no waveform tables on {node.resolve_topic_name(TOPIC_ACCEL)} yet "
                    "(is `bearing-sim node` running on this ROS_DOMAIN_ID?)")
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        signals.shutting_down()         # a signal from here on is held: exit 130 / 143 after the lines
        try:
            # the lines first: a hang in the middleware's teardown below once lost them (and
            # turned the verdicts' exit status into 1)
            if node is not None:
                node.finish()
                say(f"monitor: {len(node.verdicts)} verdicts from {node.tables} tables, "
                    f"{node.window.gaps} gaps (lost tables or a restarted source), "
                    f"{node.rejected} rejected")
                for line in node.exit_lines():
                    say(line)
                node.raise_output_failure()     # the last window's, analysed as the loop ended (--count)
        finally:
            with teardown_watchdog("monitor", status):
                if executor is not None:
                    executor.shutdown(timeout_sec=0)
                if node is not None:
                    node.destroy_node()
                rclpy.try_shutdown()
    return status
