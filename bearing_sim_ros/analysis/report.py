"""``bearing-sim report F.mcap --out DIR``: plots and a short summary of a recording.

Writes to DIR:

- ``waveform.png``: the accelerometer channels, whole recording and a zoom on a few fault periods;
- ``spectrum.png``: power spectral density of each channel (Welch);
- ``envelope.png``: envelope spectrum (``analysis.envelope``) with the fault frequencies of the
  recorded bearing marked, and the verdict;
- ``operating_point.png``: shaft speed and radial load over time;
- ``cage.png`` (when ``state`` was recorded): cage speed against pure rolling and the cage slip
  ratio, plus the skid ratios the skidding tier reports in ``/diagnostics`` when present;
- ``summary.md`` and ``summary.json``: how the recording was made, waveform statistics, fault
  lines against theory, the verdict, and whether the waveform tables are contiguous.

The bearing comes from the scene text in the ``bearing_sim`` metadata record, so a report needs
nothing but the file.  Spectra use at most ``MAX_ANALYSIS_S`` seconds of signal (the start).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..paths import output_folder
from ..recording.reader import open_recording
from ..waveform import NS, from_pointcloud2
from .envelope import DEFAULT_BAND, FAULT_LINES, diagnose, envelope_spectrum, statistics

MAX_ANALYSIS_S = 120.0
LINE_LABELS = {"bpfo": "BPFO", "bpfi": "BPFI", "2bsf": "2xBSF", "ftf": "FTF"}
LINE_COLOURS = {"bpfo": "tab:red", "bpfi": "tab:green", "2bsf": "tab:purple", "ftf": "tab:orange"}
RPM = 60.0 / (2.0 * math.pi)


# ---- reading ---------------------------------------------------------------------------------
class _Data:
    """What the report needs from a recording, as arrays."""

    def __init__(self, rec):
        from rclpy.serialization import deserialize_message

        from ..recording.reader import get_message

        topics = rec.topics()
        self.topics = {t: {"type": c.msg_type, "messages": c.count} for t, c in topics.items()}
        self.metadata = rec.metadata
        self.accel_topic = self._find(topics, "accel", "sensor_msgs/msg/PointCloud2")
        wanted = [t for t in (self.accel_topic, self._find(topics, "state", "sensor_msgs/msg/JointState"),
                              self._find(topics, "shaft_speed", "std_msgs/msg/Float64"),
                              self._find(topics, "load", "geometry_msgs/msg/WrenchStamped"),
                              self._find(topics, "diagnostics", "diagnostic_msgs/msg/DiagnosticArray"))
                  if t]
        classes = {t: get_message(topics[t].msg_type) for t in wanted}
        chunks, stamps, widths = [], [], []
        self.channels = ()
        self.truncated_analysis = False
        state_t, shaft_w, cage_w = [], [], []
        cmd_t, cmd_speed, load_t, load_xy = [], [], [], []
        diag = {}
        tiers = []
        in_signal = []
        samples = 0
        fs_meta = None
        try:
            fs_meta = float(rec.parameters().get("sample_rate") or 0) or None
        except (TypeError, ValueError):
            fs_meta = None
        for topic, _type, log_ns, data in rec.messages(topics=wanted):
            msg = deserialize_message(data, classes[topic])
            if topic == self.accel_topic:
                stamp, names, arr = from_pointcloud2(msg)
                stamps.append(stamp)
                widths.append(arr.shape[0])
                self.channels = tuple(names)
                if fs_meta and samples / fs_meta >= MAX_ANALYSIS_S:
                    self.truncated_analysis = True
                    continue
                chunks.append(arr)
                samples += arr.shape[0]
            elif topic.endswith("state"):
                if len(msg.velocity) >= 2:
                    state_t.append(_stamp(msg.header.stamp))
                    shaft_w.append(msg.velocity[0])
                    cage_w.append(msg.velocity[1])
            elif topic.endswith("shaft_speed"):
                cmd_t.append(log_ns)
                cmd_speed.append(msg.data)
            elif topic.endswith("load"):
                load_t.append(_stamp(msg.header.stamp))
                load_xy.append((msg.wrench.force.x, msg.wrench.force.y))
            else:
                for key, percent in skid_ratios(msg).items():
                    diag.setdefault(key, []).append((_stamp(msg.header.stamp), percent))
                tier = tier_keys(msg)
                if tier.get("tier"):
                    tiers.append(tier)
                found = signal_frequencies(msg)
                if found:
                    in_signal.append(found)
        if not chunks:
            raise UserError(f"{rec.path}: no accelerometer waveform tables (sensor_msgs/msg/PointCloud2 "
                            f"on .../accel) in this recording; topics: {', '.join(sorted(topics)) or 'none'}")
        self.accel = np.concatenate(chunks, axis=0).astype(float)
        self.stamps = np.array(stamps, dtype=np.int64)
        self.widths = np.array(widths, dtype=np.int64)
        self.sample_rate = fs_meta or self._rate_from_stamps()
        self.t0_ns = int(self.stamps[0])
        self.gaps = self._gaps()
        self.state_t = np.array(state_t, dtype=float) / NS
        self.shaft_w = np.array(shaft_w, dtype=float)
        self.cage_w = np.array(cage_w, dtype=float)
        self.cmd_t = np.array(cmd_t, dtype=float) / NS
        self.cmd_speed = np.array(cmd_speed, dtype=float)
        self.load_t = np.array(load_t, dtype=float) / NS
        self.load_xy = np.array(load_xy, dtype=float).reshape(-1, 2)
        self.skid = {k: np.array(v, dtype=float) for k, v in diag.items()}
        # the fault frequencies the recording's /diagnostics gave, mean over the recording
        self.signal_frequencies = ({k: float(np.mean([f[k] for f in in_signal])) for k in in_signal[0]}
                                   if in_signal else {})
        self.tiers = tiers

    @staticmethod
    def _find(topics, name, msg_type):
        for t, c in sorted(topics.items()):
            if t.rstrip("/").split("/")[-1] == name and c.msg_type == msg_type:
                return t
        return None

    def _rate_from_stamps(self) -> float:
        if self.stamps.size < 2 or self.stamps[-1] == self.stamps[0]:
            raise UserError("cannot tell the sample rate: one waveform table and no sample_rate "
                            "parameter in the metadata")
        return float((self.widths[:-1].sum()) * NS / (self.stamps[-1] - self.stamps[0]))

    def _gaps(self) -> int:
        """Waveform tables whose stamp is not the previous stamp + width / sample_rate (1 us)."""
        if self.stamps.size < 2:
            return 0
        expected = self.stamps[:-1] + np.round(self.widths[:-1] * NS / self.sample_rate).astype(np.int64)
        return int(np.sum(np.abs(self.stamps[1:] - expected) > 1000))


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
    """{"ftf", "bpfo", "bpfi": Hz} as the signal has them in one ``/diagnostics`` message
    (``cage_hz``, ``bpfo_hz``, ``bpfi_hz``: ``recording.render.PeriodMeans``); {} in a recording
    made before these keys."""
    keys = {"cage_hz": "ftf", "bpfo_hz": "bpfo", "bpfi_hz": "bpfi"}
    found = {keys[kv.key]: kv.value for status in diagnostics.status for kv in status.values if kv.key in keys}
    try:
        return {k: float(v) for k, v in found.items()} if len(found) == len(keys) else {}
    except ValueError:
        return {}


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
    from ..scene import load_yaml, scene_from_dict

    text = meta.get("scene_yaml", "")
    if not text:
        return None
    try:
        return scene_from_dict(load_yaml(text), name=meta.get("scene", "scene"), source_text=text)
    except Exception:  # noqa: BLE001 - a scene this version cannot read: report without it
        return None


# ---- plots -------------------------------------------------------------------------------------
def _figure(rows: int, height: float = 3.0):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, 1, figsize=(11, height * rows), squeeze=False)
    return plt, fig, axes[:, 0]


def _save(plt, fig, path: Path) -> str:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path.name


def _title(meta: dict) -> str:
    return f"{meta.get('scene', '?')} - {meta.get('tier', '?')} tier, seed {meta.get('seed', '?')}"


def plot_waveform(d: _Data, freqs: dict, out: Path, meta: dict) -> str:
    plt, fig, (ax_all, ax_zoom) = _figure(2, 3.2)
    fs = d.sample_rate
    t = np.arange(d.accel.shape[0]) / fs + d.t0_ns / NS
    for k, name in enumerate(d.channels):
        ax_all.plot(t, d.accel[:, k], lw=0.4, label=name, alpha=0.85)
    ax_all.set(xlabel="time (s)", ylabel="acceleration (m/s²)", title=f"Accelerometer - {_title(meta)}")
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


def plot_spectrum(d: _Data, out: Path, meta: dict) -> str:
    from scipy.signal import welch

    plt, fig, (ax,) = _figure(1, 4.0)
    fs = d.sample_rate
    nper = int(min(d.accel.shape[0], 2 ** int(math.log2(max(256, fs / 2)))))
    for k, name in enumerate(d.channels):
        f, p = welch(d.accel[:, k] - d.accel[:, k].mean(), fs=fs, nperseg=nper)
        ax.semilogy(f / 1e3, np.maximum(p, 1e-30), lw=0.8, label=name)
    lo, hi = DEFAULT_BAND
    ax.axvspan(lo / 1e3, min(hi, 0.45 * fs) / 1e3, color="0.85", alpha=0.5, label="envelope band")
    ax.set(xlabel="frequency (kHz)", ylabel="PSD ((m/s²)²/Hz)", xlim=(0, fs / 2e3),
           title=f"Spectrum (Welch, {nper} points) - {_title(meta)}")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(plt, fig, out / "spectrum.png")


def plot_envelope(x: np.ndarray, fs: float, freqs: dict, verdict: dict, channel: str,
                  out: Path, meta: dict) -> str:
    plt, fig, (ax,) = _figure(1, 4.2)
    targets = {"bpfo": freqs["bpfo"], "bpfi": freqs["bpfi"], "2bsf": 2 * freqs["bsf"], "ftf": freqs["ftf"]}
    fmax = min(0.45 * fs, 3.3 * max(targets.values()))
    f, s = envelope_spectrum(x, fs, max_freq=fmax)
    ax.plot(f, s, color="0.2", lw=0.7)
    top = float(s[f > 2.0].max()) if np.any(f > 2.0) else float(s.max())
    for key, f0 in targets.items():
        for h in (1, 2, 3):
            if h * f0 > fmax:
                continue
            ax.axvline(h * f0, color=LINE_COLOURS[key], lw=1.2 if h == 1 else 0.7,
                       ls="--" if h == 1 else ":", alpha=0.9 if h == 1 else 0.5,
                       label=f"{LINE_LABELS[key]} {f0:.1f} Hz" if h == 1 else None)
    for key, line in verdict["lines"].items():
        if math.isfinite(line.found_hz) and line.prominence >= 2.0:
            ax.annotate(f"{LINE_LABELS[key]} ×{line.prominence:.0f}", (line.found_hz, line.height),
                        xytext=(5, -2), textcoords="offset points", ha="left", va="top", fontsize=9,
                        color=LINE_COLOURS[key], fontweight="bold")
    ax.set(xlabel="frequency (Hz)", ylabel="envelope amplitude (m/s²)", xlim=(0, fmax),
           ylim=(0, 1.25 * top if top > 0 else 1),
           title=(f"Envelope spectrum of {channel} ({DEFAULT_BAND[0] / 1e3:g}-{DEFAULT_BAND[1] / 1e3:g} kHz band) "
                  f"- verdict: {verdict['verdict'].upper()}   (×N: line height over local median)"))
    ax.legend(loc="upper right", fontsize=8, ncol=2)
    ax.grid(alpha=0.3)
    return _save(plt, fig, out / "envelope.png")


def plot_operating_point(d: _Data, scene, out: Path, meta: dict) -> str:
    plt, fig, (ax_s, ax_l) = _figure(2, 2.8)
    if d.cmd_t.size:
        ax_s.step(d.cmd_t, d.cmd_speed * RPM, where="post", lw=1.2, label="shaft_speed topic (command in use)")
    if d.state_t.size:
        ax_s.plot(d.state_t, d.shaft_w * RPM, lw=0.9, ls="--", label="state: shaft")
    if not d.cmd_t.size and not d.state_t.size and scene is not None:
        ax_s.axhline(scene.shaft_speed * RPM, label="scene operating point (nothing recorded)")
    ax_s.set(ylabel="shaft speed (rpm)", title=f"Operating point - {_title(meta)}")
    ax_s.legend(loc="best", fontsize=8)
    ax_s.grid(alpha=0.3)
    if d.load_t.size:
        ax_l.step(d.load_t, d.load_xy[:, 0], where="post", label="Fx (horizontal)")
        ax_l.step(d.load_t, d.load_xy[:, 1], where="post", label="Fy (vertical, up)")
    elif scene is not None:
        ax_l.axhline(scene.radial_load[0], color="tab:blue", label="Fx scene (load not recorded)")
        ax_l.axhline(scene.radial_load[1], color="tab:orange", label="Fy scene (load not recorded)")
    ax_l.set(xlabel="time (s)", ylabel="radial load (N)")
    ax_l.legend(loc="best", fontsize=8)
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


# ---- summary -----------------------------------------------------------------------------------
def build_report(path, out) -> dict:
    """Read ``path``, write the plots and summaries to ``out``; return the summary dict."""
    rec = open_recording(path)
    try:
        d = _Data(rec)
        meta = dict(rec.metadata)
        duration = (rec.end_ns - rec.start_ns) / NS
        message_count = rec.message_count
    finally:
        rec.close()
    out = output_folder(out)
    scene = _scene_from_metadata(meta)
    fs = d.sample_rate
    ch = "accel_y" if "accel_y" in d.channels else d.channels[0]
    x = d.accel[:, d.channels.index(ch)]
    speed = float(np.mean(d.cmd_speed)) if d.cmd_speed.size else (
        float(np.mean(d.shaft_w)) if d.shaft_w.size else (scene.shaft_speed if scene else float("nan")))
    rolling = scene.bearing.fault_frequencies(speed / (2 * math.pi)) if scene is not None else {}
    # where the cage skids, the lines are where the recorded cage puts them, not at pure rolling
    freqs = {**rolling, **d.signal_frequencies} if rolling else {}
    verdict = diagnose(x, fs, freqs) if freqs and x.size > fs * 0.2 else None

    plots = [plot_waveform(d, freqs, out, meta), plot_spectrum(d, out, meta)]
    if verdict is not None:
        plots.append(plot_envelope(x, fs, freqs, verdict, ch, out, meta))
    plots.append(plot_operating_point(d, scene, out, meta))
    cage = plot_cage(d, scene, out, meta)
    if cage:
        plots.append(cage)

    expected = sorted({df.kind for df in scene.defects}) if scene is not None else []
    speed_var = (float(np.ptp(d.cmd_speed) / abs(speed)) if d.cmd_speed.size and speed else 0.0)
    summary = {
        "file": str(path),
        "scene": meta.get("scene", ""),
        "description": meta.get("scene_description", ""),
        "package_version": meta.get("package_version", ""),
        "seed": meta.get("seed", ""),
        "tier": meta.get("tier", ""),
        "tier_reason": meta.get("tier_reason", ""),
        **tier_history(meta, d.tiers),
        "parameters": _json_or_text(meta.get("parameters", "")),
        "duration_s": duration,
        "messages": message_count,
        "topics": d.topics,
        "sample_rate_hz": fs,
        "channels": list(d.channels),
        "analysed_s": d.accel.shape[0] / fs,
        "waveform_gaps": d.gaps,
        "statistics": {name: statistics(d.accel[:, k]) for k, name in enumerate(d.channels)},
        "shaft_speed_rpm": speed * RPM,
        "shaft_speed_variation": speed_var,
        "fault_frequencies_hz": freqs,
        "fault_frequencies_pure_rolling_hz": rolling,
        "fault_frequencies_from": ("the recording's /diagnostics (cage_hz, bpfo_hz, bpfi_hz; bsf: pure rolling)"
                                   if d.signal_frequencies and rolling else "pure rolling at the mean shaft speed"),
        "envelope_channel": ch,
        "fault_lines": ({k: {"expected_hz": v.expected_hz, "found_hz": v.found_hz, "height": v.height,
                             "prominence": v.prominence} for k, v in verdict["lines"].items()}
                        if verdict else {}),
        "verdict": verdict["verdict"] if verdict else "unknown",
        "expected_defects": expected,
        "skid_ratios_percent": {k: float(np.mean(v[:, 1])) for k, v in sorted(d.skid.items())},
        "plots": plots,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=_json_default) + "\n")
    (out / "summary.md").write_text(_markdown(summary))
    return summary


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
    verdict = s["verdict"].upper()
    exp = ", ".join(s["expected_defects"]) or "none (healthy)"
    found = set() if s["verdict"] in ("healthy", "unknown") else {s["verdict"]}
    agree = ("agrees with the scene" if found <= set(s["expected_defects"]) and (found or not s["expected_defects"])
             else "differs from the scene")
    lines += [f"**Verdict (envelope analysis of {s['envelope_channel']}): {verdict}**; the scene's defects: "
              f"{exp} (the verdict {agree}).", ""]
    lines += ["| | |", "| --- | --- |",
              f"| file | `{s['file']}` |",
              f"| made by | bearing_sim_ros {s['package_version']}, {_tiers_text(s)}, seed {s['seed']} |",
              f"| length | {s['duration_s']:.2f} s, {s['messages']} messages; analysed {s['analysed_s']:.2f} s |",
              f"| waveform | {s['sample_rate_hz']:g} Hz, {', '.join(s['channels'])}; "
              f"{'contiguous' if s['waveform_gaps'] == 0 else str(s['waveform_gaps']) + ' gaps'} |",
              f"| shaft speed | {s['shaft_speed_rpm']:.1f} rpm (mean"
              + (f"; varies by {100 * s['shaft_speed_variation']:.0f} %: envelope lines smear and the "
                 "verdict is not reliable" if s["shaft_speed_variation"] > 0.01 else "")
              + ") |", ""]
    if s["fault_lines"]:
        lines += ["## Fault lines in the envelope spectrum", "",
                  f"Expected at the fault frequencies of {s['fault_frequencies_from']}.", "",
                  "| line | expected (Hz) | found (Hz) | prominence (x local median) |", "| --- | --- | --- | --- |"]
        for key, line in s["fault_lines"].items():
            lines.append(f"| {LINE_LABELS[key]} | {line['expected_hz']:.2f} | {_num(line['found_hz'])} | "
                         f"{_num(line['prominence'])} |")
        lines += ["", f"A line counts as a fault above a prominence of 4 (`analysis.envelope.DETECTION_THRESHOLD`); "
                  f"which line marks which fault: {', '.join(f'{k} -> {LINE_LABELS[v]}' for k, v in FAULT_LINES.items())}.", ""]
    if s["skid_ratios_percent"]:
        lines += ["## Skidding", "", "Mean over the recording (`/diagnostics`): "
                  + ", ".join(f"{k.replace('_ratio', '')} {v:.3g} %" for k, v in s["skid_ratios_percent"].items()), ""]
    lines += ["## Waveform statistics", "", "| channel | RMS (m/s²) | kurtosis | crest factor | peak-to-peak (m/s²) |",
              "| --- | --- | --- | --- | --- |"]
    for name, st in s["statistics"].items():
        lines.append(f"| {name} | {_num(st['rms'])} | {_num(st['kurtosis'])} | {_num(st['crest_factor'])} | "
                     f"{_num(st['peak_to_peak'])} |")
    lines += ["", "## Plots", ""] + [f"![{p}]({p})" for p in s["plots"]] + [""]
    return "\n".join(lines)


def report_command(args) -> int:
    """CLI entry: ``bearing-sim report F.mcap --out DIR``."""
    s = build_report(args.file, args.out)
    print(f"{args.out}: {', '.join(s['plots'])}, summary.md, summary.json; verdict {s['verdict']} "
          f"(scene defects: {', '.join(s['expected_defects']) or 'none'})")
    return 0
