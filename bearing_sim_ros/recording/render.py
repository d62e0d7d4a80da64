"""``bearing-sim render``: a scene to an MCAP recording, offline, as fast as the model allows.

The messages are the live node's (``messages.BatchMessages``: the ``accel`` and
``contact_forces`` waveform tables, ``state`` at ``state_rate``, ``/diagnostics`` once per
simulated second) without DDS.  Simulation time starts at 0 (the ROS epoch), log time = the time
the live node would publish (the end of each batch), and nothing in the file comes from the wall
clock, so the same scene, duration, fidelity, sample rate and seed give a byte-identical file.

Speed/load profile: when the scene has ``profile`` knots, the operating point follows the
piecewise-linear profile (before the first knot: from the scene's operating point at t = 0 to the
first knot; after the last: held).  Each batch ramps to the profile's value at its end (see
``Simulator.advance``).  The operating point in use is recorded on ``shaft_speed``
(std_msgs/Float64, rad/s) and ``load`` (geometry_msgs/WrenchStamped, N) at the start of every
batch, the topics the live node subscribes to: ``bearing-sim play`` of a profile recording
therefore also drives a live node listening on the same graph through the same profile (within
one batch).
"""
from __future__ import annotations

import contextlib
import math
import numbers
import os
import shlex
import signal
import sys
import time

import numpy as np

from ..errors import API_SETTINGS, CLI_SETTINGS, SettingNames, UserError
from ..paths import output_file
from ..teardown import EXIT_INTERRUPTED, SIGNAL_NAMES, drop_a_closed_terminal, say_on_stderr, signal_handlers
from ..messages import BATCH_DURATION, RUN_KEY, RUN_RUNNING, STATE_RATE, TOPIC_ACCEL, TOPIC_CONTACT, \
    TOPIC_DIAGNOSTICS, TOPIC_LOAD, TOPIC_SHAFT_SPEED, TOPIC_STATE, TYPES, batching_error, duration_error, \
    end_of_run, waveform_qos
from ..ground_truth import BEARING_KEY, SCENE_KEY, diagnostics_values, status_name
from ..waveform import NS

NODE_NAME = "bearing_sim"


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP (``signum``) during a render: handled as Ctrl-C is (``render_command``
    raises it)."""

    def __init__(self, signum: int = signal.SIGTERM):
        super().__init__()
        self.signum = signum


def _interruption(signum: int) -> KeyboardInterrupt:
    """What a render stopped by ``signum`` raises at the end of its batch."""
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


@contextlib.contextmanager
def _stop_at_batch_end():
    """Ctrl-C, SIGTERM and SIGHUP during the render loop: noted (``.signum``), and the loop stops
    at the end of the batch in progress, so that the file holds whole batches and the seconds said are
    exact (raised at once, the exception could fall between a batch's messages).  Only where
    they would otherwise interrupt or kill (Python's default handlers, or ``render_command``'s),
    and in the main thread: a caller's own handlers are left alone."""
    class Stop:
        signum = None

    stop = Stop()

    def note(signum, _frame):
        drop_a_closed_terminal()        # a hangup: the progress bar and the last line go nowhere
        stop.signum = signum

    # a hangup ignored (``nohup``) is neither of these and stays ignored: the render runs on
    ours = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL, signal.SIGHUP: signal.SIG_DFL}
    noted = {sig: note for sig, default in ours.items() if signal.getsignal(sig) in (default, _raise_terminated)}
    with signal_handlers(noted):
        yield stop


def _raise_terminated(signum, _frame):
    drop_a_closed_terminal()
    raise Terminated(signum)


def _signals_held():
    """Ctrl-C and SIGTERM ignored while a recording is finalised (a second Ctrl-C must not
    leave it half done)."""
    return signal_handlers({sig: signal.SIG_IGN for sig in EXIT_INTERRUPTED})


def profile_at(scene, t: float) -> tuple:
    """(shaft speed rad/s, (x, y) load N) of the scene's profile at time ``t`` (s)."""
    pts = list(scene.profile)
    if not pts:
        return float(scene.shaft_speed), tuple(float(v) for v in scene.radial_load)
    knots_t = [p.t for p in pts]
    speeds = [p.shaft_speed for p in pts]
    loads = [tuple(p.radial_load) for p in pts]
    if knots_t[0] > 0.0:           # from the scene's operating point at t = 0
        knots_t.insert(0, 0.0)
        speeds.insert(0, scene.shaft_speed)
        loads.insert(0, tuple(scene.radial_load))
    speed = float(np.interp(t, knots_t, speeds))
    load = tuple(float(np.interp(t, knots_t, [ld[k] for ld in loads])) for k in range(2))
    return speed, load


# ---- messages the node also publishes --------------------------------------------------------
def _stamp(header, stamp_ns: int) -> None:
    header.stamp.sec = int(stamp_ns // NS)
    header.stamp.nanosec = int(stamp_ns % NS)


def speed_message(speed: float):
    from std_msgs.msg import Float64

    return Float64(data=float(speed))


def load_message(load, stamp_ns: int, frame_id: str):
    from geometry_msgs.msg import WrenchStamped

    msg = WrenchStamped()
    _stamp(msg.header, stamp_ns)
    msg.header.frame_id = frame_id
    msg.wrench.force.x, msg.wrench.force.y = float(load[0]), float(load[1])
    return msg


def diagnostics_message(stamp_ns: int, values: dict, level: int = 0, message: str = "ok",
                        node: str = NODE_NAME):
    """A DiagnosticArray with one status ``<node>: simulator`` (``ground_truth.status_name``)
    carrying ``values``; ``node`` is the node's name with its namespace (``rig1/bearing_sim``), so
    that nodes in several namespaces, which all publish on the one ``/diagnostics``, can be told
    apart."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    arr = DiagnosticArray()
    _stamp(arr.header, stamp_ns)
    st = DiagnosticStatus(level=bytes([level]), name=status_name(node), message=message, hardware_id=node)
    st.values = [KeyValue(key=str(k), value=str(v)) for k, v in values.items()]
    arr.status = [st]
    return arr


# extras of a batch (``Simulator.advance``) -> its ``/diagnostics`` key, and whether the key is
# the mean of the absolute value (signed slips and frictions of loaded and unloaded balls cancel)
PERIOD_EXTRAS = {"ball_skid": ("ball_skid_ratio", False), "cage_skid": ("cage_skid_ratio", False),
                 "slip_inner": ("slip_inner_m_s", True), "slip_outer": ("slip_outer_m_s", True),
                 "friction_inner": ("friction_inner_n", True), "friction_outer": ("friction_outer_n", True)}


class PeriodMeans:
    """Sample-weighted means over one ``/diagnostics`` period of what the batches carry, as the
    live node and ``render`` both publish them (``values``):

    - the skidding tier's skid ratios, % (``ball_skid_ratio``, ``cage_skid_ratio``), and its
      balls' slip speeds (m/s) and traction forces (N) at each race as the mean absolute value
      over balls and samples (``slip_inner_m_s``, ``slip_outer_m_s``, ``friction_inner_n``,
      ``friction_outer_n``); only while that tier runs;
    - the fault frequencies as they are in the signal, Hz: ``cage_hz`` from the cage's mean speed,
      ``bpfo_hz`` = Z x cage_hz, ``bpfi_hz`` = Z x the shaft's mean speed relative to the cage.
      Where the cage skids they differ from the catalog's pure-rolling ones
      (``Bearing.fault_frequencies``), and they are where the signal's envelope lines are;
    - with ``spin_per_shaft`` (the bearing's pure-rolling ball spin per unit shaft speed,
      ``Bearing.ball_spin_speed(1.0)``): ``bsf_hz``, the balls' mean spin frequency, from the
      shaft's mean speed and, on the skidding tier, the balls' mean skid (which slows their spin
      by that share: the 2xBSF line of a ball defect moves with it);
    - with ``clip_limit`` (the sensor's range, m/s^2): ``accel_clipped_samples``, the samples of
      the period at which an axis sat at the range (a saturated sensor: under a 16 kN load the
      vertical axis clipped at 50 g without a word)."""

    def __init__(self, balls: int, clip_limit: float | None = None, spin_per_shaft: float | None = None):
        self.balls = int(balls)
        self.clip_limit = clip_limit
        self.spin_per_shaft = spin_per_shaft
        self.reset()

    def reset(self) -> None:
        self._sums, self._counts = {}, {}
        self.clipped = 0

    def _add(self, key: str, total: float, n: int) -> None:
        self._sums[key] = self._sums.get(key, 0.0) + total
        self._counts[key] = self._counts.get(key, 0) + n

    def add(self, batch) -> None:
        n = batch.n
        for name, val in batch.extras.items():
            if name in PERIOD_EXTRAS:
                key, absolute = PERIOD_EXTRAS[name]
                # the rows that have values: where fidelity auto switched to the skidding tier,
                # the batch's first rows came from the kinematic tier and are NaN
                rows = ~np.isnan(val).reshape(val.shape[0], -1).any(axis=1)
                had = int(np.count_nonzero(rows))
                if had:
                    self._add(key, float(np.mean(np.abs(val[rows]) if absolute else val[rows])) * had, had)
        self._add("cage", float(np.sum(batch.cage_speed)), n)
        self._add("shaft", float(np.sum(batch.shaft_speed)), n)
        if self.clip_limit is not None:
            self.clipped += int(np.count_nonzero((np.abs(batch.accel) >= self.clip_limit).any(axis=1)))

    def values(self) -> dict:
        """{key: text} of the period so far ({} before a batch)."""
        mean = {k: v / self._counts[k] for k, v in self._sums.items() if self._counts[k]}
        if "cage" not in mean:
            return {}
        cage, shaft = mean.pop("cage"), mean.pop("shaft")
        out = {k: f"{v:.4g}" for k, v in mean.items()}
        out["cage_hz"] = f"{abs(cage) / (2 * math.pi):.6g}"
        out["bpfo_hz"] = f"{self.balls * abs(cage) / (2 * math.pi):.6g}"
        out["bpfi_hz"] = f"{self.balls * abs(shaft - cage) / (2 * math.pi):.6g}"
        if self.spin_per_shaft is not None:
            # ball_skid = 100 (w_rolling - w_ball) / w_rolling per ball: linear, so its mean gives theirs
            slowed = 1.0 - mean.get("ball_skid_ratio", 0.0) / 100.0
            out["bsf_hz"] = f"{self.spin_per_shaft * abs(shaft) * slowed / (2 * math.pi):.6g}"
        if self.clip_limit is not None:
            out["accel_clipped_samples"] = str(self.clipped)
        return out

    def clipped_text(self) -> str:
        """The warning for a period in which the sensor saturated, else ''."""
        if not self.clipped:
            return ""
        return (f"accelerometer saturated: {self.clipped} samples at its range "
                f"(+-{self.clip_limit:g} m/s^2) in the last second")


# the keys ``tier_values`` writes, for readers of recorded diagnostics (``analysis.report``)
TIER_KEYS = ("tier", "tier_reason", "tier_estimated_error", "tier_switches", "last_tier_switch", "oversample",
             "centrifugal")


def tier_values(sim) -> dict:
    """The ``/diagnostics`` keys on the model tier, the live node's and a render's alike: the
    tier in use, why, its estimated error, how many times ``fidelity: auto`` switched, and the
    latest switch (``kinematic -> skidding at 1.230 s``: the simulated time of the first batch
    the new tier computed; ``none``), and its integration steps per output sample
    (``Simulator.oversample``, which the kinematic tier's default changes with the load; ``none``
    for the fixed steps of "rk4" and "reference"); ``centrifugal`` (``Simulator.centrifugal``:
    ``true`` where the kinematic tier's balls carry their centrifugal force, ``false`` where they
    are massless, ``none`` on the skidding tier, whose balls always have their mass); and
    ``step_warning``, only while the running
    tier has one (``Simulator.step_warning``: the default's step is known to be long for the
    bearing), the line the command or node printed on standard error when it was built."""
    last = sim.last_tier_switch
    steps = sim.oversample
    values = {"tier": sim.tier, "tier_reason": sim.selection.reason,
              "tier_estimated_error": f"{sim.selection.estimated_error:.3g}",
              "tier_switches": sim.tier_switches,
              "last_tier_switch": "none" if last is None else f"{last[1]} -> {last[2]} at {last[0]:.3f} s",
              "oversample": "none" if steps is None else steps,
              "centrifugal": "none" if sim.centrifugal is None else str(sim.centrifugal).lower()}
    if sim.step_warning:
        values["step_warning"] = sim.step_warning
    return values


def defect_values(sim, sample: int | None = None) -> dict:
    """The ``/diagnostics`` ground-truth keys (``bearing_sim_ros.ground_truth``) on the scene's
    defects as they are in the signal at output sample ``sample`` (default: the latest computed),
    the live node's and a render's alike: ``faults_present`` (``outer``, ``inner, ball``;
    ``none``), ``defect_sizes`` (each scene defect's size in scene order, 0 before its
    ``onset_s``, 1 at full size; ``none`` for a scene without defects) and ``fault_onsets_s``
    (``outer=5.000000``: when each kind present appeared, s of signal)."""
    sizes = sim.defect_sizes if sample is None else sim.defect_sizes_at(sample)
    return diagnostics_values([d.kind for d in sim.scene.defects], sizes, sim.defect_onsets_s)


def scene_values(scene) -> dict:
    """The ``/diagnostics`` keys that say what the signal is of, the live node's and a render's
    alike: ``scene`` (its name) and ``bearing`` (its bearing's), so that a consumer told another
    scene (``bearing-sim monitor --scene``) can tell."""
    return {SCENE_KEY: scene.name, BEARING_KEY: scene.bearing.name}


def tier_summary(values: dict) -> str:
    """``kinematic tier``, or after switches of ``fidelity: auto`` (``tier_values``) ``skidding
    tier at the end: 1 switch, the last kinematic -> skidding at 0.430 s``."""
    text = f"{values['tier']} tier"
    switches = values["tier_switches"]
    if switches:
        text += (f" at the end: {switches} switch{'es' if switches > 1 else ''}, the last "
                 f"{values['last_tier_switch']}")
    return text


def _qos_for(topic: str, batch_duration: float):
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    if topic in (TOPIC_ACCEL, TOPIC_CONTACT):
        return waveform_qos(batch_duration)
    # small status/command topics: reliable, volatile, keep-last 10 (rclpy's default profile)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                      reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)


class _Progress:
    """A one-line progress bar on stderr, only when stderr is a terminal."""

    def __init__(self, total: float, enabled: bool):
        self.total, self.enabled = total, enabled
        self.t_wall0 = time.perf_counter()
        self.last = 0.0

    def update(self, done: float, force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self.last < 0.1:
            return
        self.last = now
        frac = min(1.0, done / self.total)
        width = 30
        fill = int(round(frac * width))
        wall = max(now - self.t_wall0, 1e-9)
        self._write(f"\rrender [{'#' * fill}{'.' * (width - fill)}] {100 * frac:5.1f}% "
                    f"{done:7.2f}/{self.total:.2f} s  {times_real_time(done / wall):>6}x real time")

    def done(self) -> None:
        if self.enabled and self.last:         # the line after a bar drawn, none without one
            self._write("\n")

    def _write(self, text: str) -> None:
        # a terminal that hung up fails every write (EIO) until the SIGHUP that comes with it is
        # handled (teardown.drop_a_closed_terminal); the bar goes, the render must not
        try:
            sys.stderr.write(text)
            sys.stderr.flush()
        except OSError:
            self.enabled = False


def _runs_skidding(scene, sim, duration: float, sample_rate: float, n_batch: int) -> bool:
    """Whether the skidding tier runs at any batch of this render: the tier chosen at the start,
    then the choice at the operating point that each batch ramps to (as the render loop below
    and ``Simulator.maybe_switch_tier`` make it)."""
    from ..simulator import reselect_tier

    selection = sim.selection
    if not scene.profile:
        return selection.tier == "skidding"      # one operating point: the tier chosen at the start
    point = (sim.shaft_speed, sim.radial_load)
    total = int(round(duration * sample_rate))
    done = 0
    while selection.tier != "skidding" and done < total:
        done += min(n_batch, total - done)
        new_point = profile_at(scene, done / sample_rate)
        selection = reselect_tier(scene, sim.requested_fidelity, selection, point, new_point) or selection
        point = new_point
    return selection.tier == "skidding"


def render(scene, duration: float, out, fidelity: str = "auto", seed: int = 0,
           sample_rate: float = 15000.0, solver: str = "default",
           batch_duration: float = BATCH_DURATION, state_rate: float = STATE_RATE,
           progress: bool | None = None, oversample: int | None = None,
           rk4_step: float | None = None, *, settings: SettingNames = API_SETTINGS) -> dict:
    """Render ``duration`` seconds of ``scene`` (Scene, shipped name or YAML path) to ``out``.

    ``oversample``: integration steps per output sample (None: each tier's own; see
    :class:`~bearing_sim_ros.Simulator`).  ``solver`` and ``rk4_step`` (s, ``solver="rk4"``
    only) are the skidding tier's: when the kinematic tier was asked for, they are an error;
    when ``fidelity="auto"`` keeps to the kinematic tier for the whole render, they are not used,
    not recorded, and the summary's ``solver_unused`` says so.  The metadata's parameters name
    the solver only where the skidding tier runs (``"solver": null`` for a render that keeps to
    the kinematic tier, which has none).  ``batch_duration`` (s) and
    ``state_rate`` (Hz) are the node's parameters of the same names, with the same ranges and
    rule (``messages.batching_error``).  Returns a summary: messages,
    bytes, wall time (s), real-time factor, tier (at the end), tier_values (``tier_values``: the
    tier switches of ``fidelity="auto"``), path, solver_unused.  Where the skidding solver
    diverges, the signal up to the batch that diverged is kept at ``out``, finalised, and
    ``SolverDiverged`` raised with ``recording``: where the file stands, in words.

    ``settings``: how the one-line errors name the arguments, the keyword arguments
    (``duration = 0: ...``, ``rk4_step = 1e-05 s: applies to solver='rk4' only``) or the
    CLI's options (``render_command``: ``--duration = 0: ...``).  What the file records (its
    command, a divergence's words) is in the CLI's words either way, so that both make the same
    bytes."""
    from .. import Simulator
    from ..physics.skidding import SolverDiverged
    from ..scene import changes_since_loaded, load_scene, scene_argument
    from .recorder import Recorder, recording_metadata

    name, assign = settings.name, settings.assign
    if not hasattr(scene, "bearing"):
        scene = load_scene(scene)
    # the file records the scene's YAML and a command that loads it: of a scene changed since,
    # both would say another scene (an inner-race pit at 200 N recorded as er16k_outer_race)
    changed = changes_since_loaded(scene)
    if changed:
        raise UserError(f"scene {scene.name}: changed in Python since it was loaded from "
                        f"{os.path.basename(scene.source_path) or 'its YAML'} ({', '.join(changed)}); a recording "
                        "holds its scene's YAML and the command that makes it again, which would be the unchanged "
                        "scene's: write the changed scene to a YAML file and render that")
    # bool is an int to Python, but render(..., True) is a slip, not one second
    if isinstance(duration, bool) or not (isinstance(duration, numbers.Real) and math.isfinite(duration)
                                          and duration > 0):
        raise UserError(f"{name('duration')} = {duration!r}: expected a finite number of seconds > 0")
    output_file(out, name("out"), keep=[scene.source_path])      # before the work, not after it
    step_is_number = isinstance(rk4_step, numbers.Real)      # a text ('1e-5') has no :g and no float()
    if rk4_step is not None and solver != "rk4":
        shown = f"{rk4_step:g}" if step_is_number else repr(rk4_step)
        raise UserError(f"{name('rk4_step')} = {shown} s: applies to {assign('solver', 'rk4')} only "
                        f"(given {assign('solver', solver)})")
    if solver != "default" and (scene.fidelity if fidelity == "auto" else fidelity) == "kinematic":
        # said in the caller's words before the Simulator says it in the API's
        step = float(rk4_step) if step_is_number else rk4_step
        given = assign("solver", solver) + (f" {assign('rk4_step', step)}" if rk4_step is not None else "")
        asked_by = (assign("fidelity", "kinematic") if fidelity == "kinematic"
                    else f"scene {scene.name}'s fidelity.tier: kinematic")
        raise UserError(f"{given}: the solver applies to the skidding tier only, and {asked_by} runs the "
                        f"kinematic tier; drop {name('solver')} or use {assign('fidelity', 'skidding')}")
    sim = Simulator(scene, sample_rate=sample_rate, fidelity=fidelity, seed=seed, solver=solver,
                    oversample=oversample, rk4_step=rk4_step)
    # the node's rule for its parameters of the same names (a render's batching also runs live);
    # after the Simulator, which checks sample_rate
    reason = batching_error(sim.sample_rate, batch_duration, state_rate)
    if reason:
        raise UserError(reason)
    # a file without a single table, which report and play then refuse
    reason = duration_error(name("duration"), duration, sample_rate)
    if reason:
        raise UserError(reason)
    total = int(round(duration * sample_rate))
    n_batch = int(round(sample_rate * batch_duration))
    runs_skidding = _runs_skidding(scene, sim, duration, sample_rate, n_batch)
    solver_unused = solver != "default" and not runs_skidding
    if solver_unused:
        # auto keeps to the kinematic tier: the file is that of a render without --solver
        solver, rk4_step = "default", None
        sim = Simulator(scene, sample_rate=sample_rate, fidelity=fidelity, seed=seed, oversample=oversample)
    from ..messages import BatchMessages

    msgs = BatchMessages(sim, start_ns=0)
    params = {"mode": "render", "duration": float(duration), "fidelity": fidelity, "seed": int(seed),
              "sample_rate": float(sample_rate),
              # what ran: the skidding tier's solver, none where only the kinematic tier runs
              "solver": solver if runs_skidding else None, "batch_duration": float(batch_duration),
              "state_rate": float(state_rate), "start_time_ns": 0, "oversample": int(oversample or 0),
              "rk4_step": rk4_step,
              # solver, step and oversample only when not the default: a kinematic render must
              # not name a solver it did not use; repr: duration, sample rate and step exactly as
              # given (:g kept 6 digits: --duration 12.345678 came back as 12.3457, one sample more)
              "command": (f"bearing-sim render {shlex.quote(scene_argument(scene))} "
                          f"--duration {float(duration)!r} --fidelity {fidelity} --seed {seed} "
                          f"--sample-rate {float(sample_rate)!r}"
                          + (f" --solver {solver}" if solver != "default" else "")
                          + (f" --rk4-step {float(rk4_step)!r}" if rk4_step is not None else "")
                          + (f" --oversample {oversample}" if oversample else ""))}
    topics = [TOPIC_SHAFT_SPEED, TOPIC_LOAD, TOPIC_ACCEL, TOPIC_CONTACT, TOPIC_STATE, TOPIC_DIAGNOSTICS]
    # each role recorded under its own name (in the root namespace: /accel, /diagnostics, ...)
    meta = recording_metadata(scene, params, seed, sim.selection, topics={t: t for t in topics})
    attachments = {f"{scene.name}.yaml": scene.source_text.encode("utf-8")} if scene.source_text else {}
    # written as <out>.<pid>.partial and moved onto out when finalised: out only ever holds a
    # complete file, and an earlier recording there stays until then; a disk slower than the
    # simulator holds the render up (nothing waits for it), never costs messages
    rec = None                  # opened where a signal is only noted (below)
    bar = _Progress(total / sample_rate, sys.stderr.isatty() if progress is None else progress)
    t_wall0 = time.perf_counter()
    frame = msgs.frame_id
    means = PeriodMeans(scene.bearing.balls, scene.sensor.range, scene.bearing.ball_spin_speed(1.0))
    next_diag_s = 1
    done = 0
    diagnosed = 0               # samples up to the last /diagnostics written

    def write_diagnostics(pub_ns: int, ending: str | None = None, error: str = "") -> None:
        """The ``/diagnostics`` of the signal up to ``pub_ns`` (the end of the last batch); with
        ``ending`` (``messages.END_REASONS``) the render's last, its end status, as the node's;
        ``error``: the line of a failure that ends the render there (level ERROR)."""
        nonlocal diagnosed
        # the live node's keys (nodes/bearing_sim_node.py); what depends on the wall clock
        # or the output path is left out so that the file stays byte-identical
        values = {RUN_KEY: RUN_RUNNING, **scene_values(scene), "real_time_factor": "nan", "real_time": "false",
                  "mode": "render",
                  "overruns": 0, "overruns_last_period": 0, "lag_s": "0.000000",
                  "worst_lag_s": "0.000000", "falling_behind": "false", **tier_values(sim), **defect_values(sim),
                  "shaft_speed_rad_s": f"{sim.shaft_speed:.6g}",
                  "radial_load_n": " ".join(f"{v:.6g}" for v in sim.radial_load),
                  "simulated_s": f"{sim.time:.6f}", "rejected_inputs": 0,
                  "recording": "ok"}
        values.update(means.values())
        clipped = means.clipped_text()         # a warning, as the live node gives it
        means.reset()
        level, message = (2, error) if error else (1 if clipped else 0, clipped or "ok")
        if ending is not None:
            values, level, message = end_of_run(values, level, message, ending, done, sample_rate, duration)
        rec.write(TOPIC_DIAGNOSTICS, diagnostics_message(pub_ns, values, level, message), pub_ns)
        diagnosed = done

    def keep_what_was_rendered(ending: str, error: str = "") -> str:
        """End a render cut short (a signal; a divergence, whose line is ``error``): what was
        rendered, finalised, ending in the /diagnostics of its last sample, its end status
        (``ending``: ``messages.END_REASONS``; level ERROR with ``error``), as a render that ran to
        its end and the live node stopped by a signal end
        (without it the ground truth of the last part-second was missing: a pit that appeared
        there was "after this recording ends"); nothing rendered: nothing replaces what out
        held.  Returns where the file stands, for the line that says so."""
        with _signals_held():
            if done:
                if (diagnosed < done or error) and not rec.error:
                    write_diagnostics(msgs.stamp_ns(done), ending, error)
                rec.close()
            elif rec is not None:       # None: a caller's own handler raised before it was open
                rec.discard()
        bar.done()
        if not done:        # rec may be None: stopped before its file was open
            return f"nothing rendered, {str(out)!r} left as it was"
        st = rec.status
        if st["ok"]:
            return f"{str(out)!r} holds the first {done / sample_rate:g} s, finalised"
        return st["error"]

    try:
        with _stop_at_batch_end() as stop:
            # the partial file opened, and its topics added, where a signal is only noted: raised
            # between its opening and the loop (SIGTERM, SIGHUP; Ctrl-C where a caller's handler
            # raised), it left the file behind, never finalised nor removed
            try:
                rec = Recorder(out, meta, attachments, start_time_ns=0, argument=name("out"),
                               keep=[scene.source_path], replace_when_done=True, when_full="wait",
                               stopped=lambda: stop.signum is not None)
            except KeyboardInterrupt:
                if stop.signum is None:
                    raise
                raise _interruption(stop.signum) from None      # while a pipe at out waited for a reader
            for topic in topics:
                rec.add_topic(topic, TYPES[topic], _qos_for(topic, batch_duration))
            while done < total:
                if stop.signum is not None and not done:     # before the first batch: nothing rendered
                    raise _interruption(stop.signum)
                if rec.error:
                    break       # the recording stopped (disk full, its file deleted): said below
                n = min(n_batch, total - done)
                t0_ns = msgs.stamp_ns(done)
                end_t = (done + n) / sample_rate
                speed, load = profile_at(scene, end_t)
                rec.write(TOPIC_SHAFT_SPEED, speed_message(speed), t0_ns)
                rec.write(TOPIC_LOAD, load_message(load, t0_ns, frame), t0_ns)
                batch = sim.advance(n, shaft_speed=speed, radial_load=load)
                done += n
                pub_ns = msgs.stamp_ns(done)         # the live node publishes when the batch is complete
                rec.write(TOPIC_ACCEL, msgs.accel(batch), pub_ns)
                rec.write(TOPIC_CONTACT, msgs.contact_forces(batch), pub_ns)
                if math.floor(done * state_rate / sample_rate) > math.floor((done - n) * state_rate / sample_rate):
                    rec.write(TOPIC_STATE, msgs.state(pub_ns), pub_ns)
                means.add(batch)
                # a signal stops the render after a whole batch (so done is exact), this one: its
                # /diagnostics is the end status, as the node's on a signal
                ending = ("duration" if done == total else
                          None if stop.signum is None else signal.Signals(stop.signum).name)
                # once per second of signal, and at its end (the end status) when that is within a
                # second: a pit that appears in the last part-second has ground truth too (the report
                # said it came "after this recording ends")
                while done >= next_diag_s * sample_rate and not ending:
                    write_diagnostics(pub_ns)
                    next_diag_s += 1
                if ending:
                    write_diagnostics(pub_ns, ending)
                bar.update(done / sample_rate)
                if stop.signum is not None and done < total:     # in the last batch: complete
                    raise _interruption(stop.signum)
    except KeyboardInterrupt as exc:
        # Ctrl-C, SIGTERM or SIGHUP: keep what was rendered, finalised, and say so.  A
        # KeyboardInterrupt from a caller's own handler comes in the middle of the loop: the end of
        # the signal has its end status all the same
        signum = getattr(exc, "signum", signal.SIGINT)
        say_on_stderr(f"interrupted ({SIGNAL_NAMES[signum]}): {keep_what_was_rendered(signal.Signals(signum).name)}")
        exc.reported = True
        raise
    except SolverDiverged as exc:
        # the signal up to the batch that diverged is good: kept, finalised, ending in an ERROR
        # /diagnostics with the line, as the node's recording does (until 2026-11-29 a traceback
        # and no file); said in one line by the caller, with where the file stands
        exc.recording = keep_what_was_rendered("diverged", exc.worded(CLI_SETTINGS))
        raise
    except BaseException:
        # a failed render (disk full, ...) must not leave a short file that looks complete:
        # its partial file goes, and out keeps what it held (None: it could not be opened)
        if rec is not None:
            with _signals_held():
                rec.discard()
        bar.done()
        raise
    with _signals_held():
        # a file with messages missing is not the render asked for: out keeps what it held
        dropped = rec.status["dropped"]
        if dropped:
            rec.discard()
        else:
            rec.close()
    bar.update(done / sample_rate, force=True)
    bar.done()
    wall = time.perf_counter() - t_wall0
    status = rec.status
    if not status["ok"]:
        raise UserError(f"{name('out')} = {str(out)!r}: {status['error']}")
    if dropped:
        raise UserError(f"{name('out')} = {str(out)!r}: {dropped} messages were not recorded; "
                        f"nothing written, {str(out)!r} left as it was")
    return {"messages": status["messages"], "bytes": status["bytes"], "wall_s": wall,
            "signal_s": total / sample_rate, "real_time_factor": (total / sample_rate) / max(wall, 1e-9),
            "tier": sim.tier, "tier_values": tier_values(sim), "path": status["path"],
            "solver_unused": solver_unused}


def _terminated_on_sigterm_or_sighup():
    """SIGTERM and SIGHUP (the terminal closed, an SSH session dropped) raise ``Terminated`` (a
    KeyboardInterrupt), so that a render ends as on Ctrl-C: what was rendered, finalised (they
    killed the process and left its ``.partial`` file without a footer, and nothing at --out).
    A hangup ignored from the start (``nohup``) stays ignored."""
    handlers = {signal.SIGTERM: _raise_terminated}
    if signal.getsignal(signal.SIGHUP) != signal.SIG_IGN:
        handlers[signal.SIGHUP] = _raise_terminated
    return signal_handlers(handlers)


def render_command(args) -> int:
    """CLI entry: ``bearing-sim render S --duration SEC --out F.mcap [...]``."""
    from ..physics.skidding import SolverDiverged
    from ..scene import load_scene
    from ..simulator import OversampleForAuto, OversampleWithOwnStep

    out = str(args.out)
    try:
        with _terminated_on_sigterm_or_sighup():
            scene = load_scene(args.scene)
            summary = render(scene, float(args.duration), out, fidelity=args.fidelity, seed=int(args.seed),
                             sample_rate=float(args.sample_rate), solver=args.solver,
                             oversample=args.oversample, rk4_step=args.rk4_step, settings=CLI_SETTINGS)
    except KeyboardInterrupt as exc:
        # 130 / 143: the file holds less than asked, and a script should know
        if not getattr(exc, "reported", False):
            say_on_stderr(f"interrupted: nothing rendered, {out!r} left as it was")
        return EXIT_INTERRUPTED[getattr(exc, "signum", signal.SIGINT)]
    except SolverDiverged as exc:
        # the model words its advice for the Python API; here the knobs are options.  Diverged
        # as the Simulator was made (its first steps run ahead): nothing rendered
        text = getattr(exc, "recording", f"nothing rendered, {out!r} left as it was")
        raise UserError(f"{exc.worded(CLI_SETTINGS)}; {text}") from None
    except OversampleForAuto as exc:
        raise UserError(exc.worded("--oversample", "--fidelity")) from None
    except OversampleWithOwnStep as exc:
        raise UserError(exc.worded("--oversample", "--solver")) from None
    tier = tier_summary(summary["tier_values"])
    if summary["solver_unused"]:
        tier += "; --solver applies to the skidding tier only, not used"
    from ..fidelity import NO_SKID_RATIOS
    from .recorder import megabytes

    if summary["tier_values"]["tier_reason"].startswith(NO_SKID_RATIOS):
        tier += "; no skid ratios: the scene asks for them, the skidding tier computes them"
    print(f"{summary['path']}: {summary['signal_s']:g} s of {scene.name} ({tier}), "
          f"{summary['messages']} messages, {megabytes(summary['bytes'])} of messages, "
          f"rendered in {summary['wall_s']:.2f} s = {times_real_time(summary['real_time_factor'])}x real time")
    return 0


def times_real_time(factor: float) -> str:
    """A real-time factor in words: one decimal from 1 up (``27.2``), two significant digits
    below (``0.014``), where one decimal said "0.0x real time" of a render 70 times slower than
    real time."""
    return f"{factor:.1f}" if factor >= 1.0 else f"{factor:.2g}"
