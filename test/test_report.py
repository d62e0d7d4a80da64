"""``bearing-sim report`` draws its plots from nothing but the file (the recording's samples, their
spectra and envelope spectrum) and finds the recorded fault, over the whole recording and window
by window against the recorded ground truth; bad inputs end with exit status 2 and one line."""
from __future__ import annotations

import json
import math
import re
import tracemalloc

import numpy as np
import pytest

from bearing_sim_ros import cli, load_scene
from bearing_sim_ros.ground_truth import faults_at
from bearing_sim_ros.analysis import report
from bearing_sim_ros.analysis.envelope import DETECTION_THRESHOLD, envelope_spectrum
from bearing_sim_ros.analysis.report import build_report
from bearing_sim_ros.recording.reader import open_recording
from bearing_sim_ros.recording.render import render
from bearing_sim_ros.waveform import NS, from_pointcloud2

from test_node_support import render_run_up


@pytest.fixture(scope="module")
def outer(tmp_path_factory):
    d = tmp_path_factory.mktemp("report")
    rec = d / "outer.mcap"
    render("er16k_outer_race", 2.0, rec, fidelity="kinematic", seed=1, progress=False)
    return rec, d / "out"


def _recorded_waveform(path):
    """(channel names, (n, c) float array, first stamp in s) of the recording's /accel tables,
    read here independently of the report."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import PointCloud2

    tables = []
    with open_recording(path) as rec:
        for _, _, _, data in rec.messages(["/accel"]):
            tables.append(from_pointcloud2(deserialize_message(data, PointCloud2)))
    return tables[0][1], np.concatenate([t[2] for t in tables]).astype(float), tables[0][0] / NS


def _line_with(ax, ydata):
    """The Line2D of ``ax`` whose y data is ``ydata`` (same length, equal to 1e-12), or None."""
    for line in ax.get_lines():
        y = np.asarray(line.get_ydata(), dtype=float)
        if y.shape == ydata.shape and np.allclose(y, ydata, rtol=1e-12, atol=0):
            return line
    return None


@pytest.fixture
def figures(monkeypatch):
    """{file name: matplotlib figure} of every plot the report saves, kept as it is saved, so that
    a test can check what is drawn on it."""
    kept = {}
    save = report._save

    def keep_and_save(plt, fig, path):
        kept[path.name] = fig
        return save(plt, fig, path)

    monkeypatch.setattr(report, "_save", keep_and_save)
    return kept


def test_report_draws_plots_and_finds_the_outer_race_fault(outer, figures):
    import matplotlib.image as mpimg

    rec, out = outer
    # what is drawn on each figure is checked below, against the recording
    code = cli.main(["report", str(rec), "--out", str(out)])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    for name in ("waveform.png", "spectrum.png", "envelope.png", "operating_point.png", "timeline.png"):
        assert name in summary["plots"]
        img = mpimg.imread(out / name)
        assert img.shape[0] > 300 and img.shape[1] > 1000
        assert img[..., :3].std() > 0.05         # something drawn, not a blank canvas
    assert "cage.png" not in summary["plots"]   # kinematic tier: pure rolling, nothing to show
    # the fault lines come from the bearing in the recording's own scene text
    bpfo = load_scene("er16k_outer_race").fault_frequencies()["bpfo"]
    assert summary["fault_frequencies_hz"]["bpfo"] == pytest.approx(bpfo)
    line = summary["fault_lines"]["bpfo"]
    assert line["found_hz"] == pytest.approx(bpfo, rel=0.01) and line["prominence"] > 10
    assert summary["verdict"] == "outer" and summary["expected_defects"] == ["outer"]
    assert summary["waveform_gaps"] == 0 and summary["sample_rate_hz"] == 15000.0
    assert summary["duration_s"] == pytest.approx(2.0, abs=0.02)
    assert summary["tiers"] == ["kinematic"] and summary["tier_switches"] == 0
    md = (out / "summary.md").read_text()
    assert "OUTER" in md and "![envelope.png](envelope.png)" in md and "| BPFO | 95.25 |" in md

    # the data drawn is the recording's (pixel statistics alone pass with the data lines removed:
    # grid, legend, marker lines and titles are enough for them)
    names, accel, t0 = _recorded_waveform(rec)
    fs = summary["sample_rate_hz"]
    assert accel.shape == (30000, 2) and summary["channels"] == list(names)
    whole, zoom = figures["waveform.png"].axes
    for k, name in enumerate(names):
        line = _line_with(whole, accel[:, k])             # every sample, at its time
        assert line is not None and line.get_label() == name, name
        assert np.allclose(line.get_xdata(), t0 + np.arange(accel.shape[0]) / fs)
        zoomed = [ln for ln in zoom.get_lines() if ln.get_label() == name]
        assert len(zoomed) == 1, name
        i0 = int(round((zoomed[0].get_xdata()[0] / 1e3 - t0) * fs))   # ms -> sample index
        part = accel[i0:i0 + len(zoomed[0].get_ydata()), k]
        assert part.size >= 0.02 * fs and np.array_equal(zoomed[0].get_ydata(), part), name
    # each channel's PSD integrates to its variance (Parseval): the channel's own spectrum
    (spec_ax,) = figures["spectrum.png"].axes
    for k, name in enumerate(names):
        lines = [ln for ln in spec_ax.get_lines() if ln.get_label() == name]
        assert len(lines) == 1, name
        f, psd = (np.asarray(v, dtype=float) for v in lines[0].get_data())
        assert np.sum(psd) * (f[1] - f[0]) * 1e3 == pytest.approx(accel[:, k].var(), rel=0.05), name
    # the envelope spectrum of accel_y, up to past 3 x BPFO (the marked harmonics)
    (env_ax,) = figures["envelope.png"].axes
    f, s = envelope_spectrum(accel[:, names.index(summary["envelope_channel"])], fs, max_freq=fs / 2)
    line = next((ln for ln in env_ax.get_lines() if len(ln.get_ydata()) > 100), None)
    assert line is not None, [len(ln.get_ydata()) for ln in env_ax.get_lines()]
    n = len(line.get_ydata())
    assert f[n - 1] > 3 * bpfo and _line_with(env_ax, s[:n]) is line
    assert np.allclose(line.get_xdata(), f[:n], rtol=1e-12, atol=0)


def test_a_write_cut_short_leaves_no_broken_file_in_out(tmp_path):
    """A full disk while report wrote its plots: one line and exit status 2, but the plot whose
    write failed stayed in --out cut short (118 784 bytes of a PNG, hH's 3 MB tmpfs), beside the
    complete ones, for a script or a viewer to take as the report.  Now every file is written
    beside its place and moved there whole; a write that fails leaves nothing.  A limit on a
    file's size (RLIMIT_FSIZE, as a full disk would) just below the first plot's size fails its
    last write, the buffer's at the file's close, where a write that failed earlier, inside
    Pillow, had the file removed by Pillow."""
    import subprocess
    import sys

    recording = tmp_path / "rec.mcap"
    render("er16k_outer_race", 0.5, recording, fidelity="kinematic", seed=1, progress=False)
    assert cli.main(["report", str(recording), "--out", str(tmp_path / "whole")]) == 0
    sizes = {p.name: p.stat().st_size for p in (tmp_path / "whole").iterdir()}
    limit = sizes["waveform.png"] - 50         # the first file report writes
    code = "\n".join([
        "import resource, signal, sys",
        "from bearing_sim_ros import cli",
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)",
        f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, resource.RLIM_INFINITY))",
        "sys.exit(cli.main(sys.argv[1:]))",
    ])
    out = tmp_path / "cut"
    run = subprocess.run([sys.executable, "-c", code, "report", str(recording), "--out", str(out)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2 and run.stderr.startswith(f"error: --out = {str(out)!r}: cannot write"), run.stderr
    assert run.stderr.count("\n") == 1 and "File too large" in run.stderr, run.stderr
    left = {p.name: p.stat().st_size for p in out.iterdir()}
    assert all(size == sizes[name] for name, size in left.items()), (left, sizes)      # whole files only


def test_report_of_a_healthy_bearing_says_healthy(tmp_path):
    # (not er16k_healthy: at its clearance and load it rings at BPFO by varying compliance, seed
    # 000 Fig. 9, and the envelope detector calls that "outer"; see test_kinematic.py)
    rec = tmp_path / "healthy.mcap"
    render("cwru_6205_normal", 2.0, rec, fidelity="kinematic", progress=False)
    s = build_report(rec, tmp_path / "out")
    assert s["verdict"] == "healthy" and s["expected_defects"] == []
    assert "agrees with the scene" in (tmp_path / "out" / "summary.md").read_text()
    # window by window too, and nothing to detect: no onset, no detection, no latency
    assert [(w["verdict"], w["faults_present"]) for w in s["timeline"]] == [("healthy", [])] * 2
    assert s["fault_onset_s"] is None and s["first_detection_s"] is None and s["detection_latency_s"] is None
    assert s["verdict_describes_recording"] is True
    assert s["verdict_note"] is None                       # nothing to explain


def test_a_fault_verdict_on_a_scene_without_a_defect_is_explained(tmp_path, capsys):
    """The healthy ER-16K rings at BPFO by varying compliance (seed 000 Fig. 9), and the report
    said "verdict OUTER ... the verdict differs from the scene" and nothing more, where
    ``bearing-sim run`` explains the ball-pass line.  Now the report says it too: on the command
    line, in summary.md and as ``verdict_note`` in summary.json."""
    rec = tmp_path / "healthy.mcap"
    render("er16k_healthy", 2.0, rec, fidelity="kinematic", progress=False)
    out = tmp_path / "out"
    assert cli.main(["report", str(rec), "--out", str(out)]) == 0
    said = capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())
    assert s["verdict"] == "outer" and s["expected_defects"] == []
    assert "is the ball-pass (varying compliance) line" in s["verdict_note"], s["verdict_note"]
    assert "compare line heights with a healthy baseline" in s["verdict_note"]
    assert s["verdict_note"] in said and s["verdict_note"] in (out / "summary.md").read_text()


def _with_onset(tmp_path, onset_s: float):
    """A scene YAML: cwru_6205_or007_6 with its outer-race pit appearing at ``onset_s``, at full size."""
    text = load_scene("cwru_6205_or007_6").source_text
    late = text.replace("clock: 6, profile: geometric}", f"clock: 6, profile: geometric, onset_s: {onset_s}}}")
    assert late != text, "cwru_6205_or007_6.yaml's defect line moved: update this test"
    path = tmp_path / "late.yaml"
    path.write_text(late)
    return path


def test_a_defect_the_recording_ends_before_is_not_expected_of_the_verdict(tmp_path, capsys):
    """A 2 s render of a scene whose outer-race pit appears at 3 s: its /diagnostics have no fault
    throughout, and the healthy verdict is right.  The report checked it against every defect of
    the scene ("the scene's defects: outer (the verdict differs from the scene)"); now against the
    faults the ground truth has in the analysed stretch, none, and it says when the scene's
    defect comes.  The same file without its /diagnostics (no ground truth) is checked against
    the scene's defects, as before."""
    from rosbags.highlevel import AnyReader

    rec = tmp_path / "before.mcap"
    render(str(_with_onset(tmp_path, 3.0)), 2.0, rec, fidelity="kinematic", seed=1, progress=False)
    with AnyReader([rec]) as reader:           # the file's own ground truth, read independently
        conns = [c for c in reader.connections if c.topic == "/diagnostics"]
        faults = {kv.value for _, _, raw in reader.messages(conns)
                  for st in reader.deserialize(raw, conns[0].msgtype).status
                  for kv in st.values if kv.key == "faults_present"}
    assert faults == {"none"}
    out = tmp_path / "out"
    assert cli.main(["report", str(rec), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["verdict"] == "healthy" and s["verdict_describes_recording"] is True
    assert s["expected_defects"] == [] and s["expected_defects_from"] == "ground truth"
    assert s["scene_defects"] == [{"kind": "outer", "onset_s": 3.0, "present": "not in this recording"}]
    md = (out / "summary.md").read_text()
    assert ("the scene's defects: outer (from 3 s, after this recording ends); present in the analysed "
            "2.00 s (by `/diagnostics`): none (the verdict agrees with the faults present).") in md
    assert "differs" not in md
    assert "(scene defects: outer (from 3 s, after this recording ends); present: none)" in capsys.readouterr().out
    # without ground truth: the scene's defects, the only expectation there is
    bare = tmp_path / "bare.mcap"
    assert _copy_without(rec, bare, lambda topic, k: topic == "/diagnostics") == 2
    s = build_report(bare, tmp_path / "bare_out")
    assert s["expected_defects"] == ["outer"] and s["expected_defects_from"] == "scene"
    assert s["scene_defects"] == [{"kind": "outer", "onset_s": 3.0, "present": None}]
    assert s["verdict_describes_recording"] is None
    assert "the scene's defects: outer (the verdict differs from the scene)." in (
        tmp_path / "bare_out" / "summary.md").read_text()


def test_a_defect_that_appears_in_the_last_part_second_is_in_the_recording(tmp_path, capsys):
    """A 2.5 s render of a scene whose outer-race pit appears at 2.2 s holds 0.3 s of the pit, but
    its last /diagnostics were those at 2 s: the report said the pit came "after this recording
    ends" and that the one verdict described the recording.  The render now ends with the ground
    truth of its last sample."""
    rec = tmp_path / "tail.mcap"
    render(str(_with_onset(tmp_path, 2.2)), 2.5, rec, fidelity="kinematic", progress=False)
    out = tmp_path / "out"
    assert cli.main(["report", str(rec), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["scene_defects"] == [{"kind": "outer", "onset_s": 2.2, "present": "in part of the analysed stretch"}]
    assert s["expected_defects"] == ["outer"] and s["verdict_describes_recording"] is False
    assert s["fault_onset_s"] == pytest.approx(2.2) and "after this recording ends" not in capsys.readouterr().out


def test_the_length_is_the_recorded_signals_not_the_log_times_span(outer, tmp_path):
    """As in a live node's recording, the first message logged at the end of the first 10 ms
    batch (the render's /shaft_speed and /load, logged at a batch's start, left out): the report
    gave the log times' span, 1.99 s, as the length of a 2 s recording.  The length is the
    signal's, from the tables (read here with rosbags): the first stamp to the last + its width
    / sample rate; the log span stays, under its own name."""
    from rosbags.highlevel import AnyReader

    live_like = tmp_path / "live_like.mcap"
    _copy_without(outer[0], live_like, lambda topic, k: topic in ("/shaft_speed", "/load"))
    with AnyReader([live_like]) as reader:
        conns = [c for c in reader.connections if c.topic == "/accel"]
        tables = [reader.deserialize(raw, conns[0].msgtype) for _, _, raw in reader.messages(conns)]
        log_span = (reader.end_time - 1 - reader.start_time) / NS
    stamps = [t.header.stamp.sec * NS + t.header.stamp.nanosec for t in tables]
    length = (stamps[-1] - stamps[0]) / NS + tables[-1].width / 15000.0
    assert length == pytest.approx(2.0, abs=1e-9) and log_span == pytest.approx(1.99, abs=1e-9)
    s = build_report(live_like, tmp_path / "out")
    assert s["duration_s"] == pytest.approx(length, abs=1e-9)
    assert s["log_time_span_s"] == pytest.approx(log_span, abs=1e-9)
    assert "| length | 2.00 s, " in (tmp_path / "out" / "summary.md").read_text()


def test_report_timeline_scores_detection_against_the_recorded_onset(tmp_path, figures):
    """An outer-race pit that appears 2.5 s into a 5 s recording: in 1 s windows (the default)
    the verdict is healthy, with no fault present by /diagnostics, before the onset and outer
    with the fault present from the window it appears in.  The onset comes to the sample from
    /diagnostics' fault_onsets_s (1 Hz messages): the scene's 2.5 s, resolution 0; the latency is
    the first detection minus it, per fault too.  timeline.png draws each window's prominences
    as summary.json has them, over the windows' times, with the threshold and the onset; the
    whole-recording verdict stays, with the note that one verdict does not describe this
    recording."""
    rec = tmp_path / "late.mcap"
    render(str(_with_onset(tmp_path, 2.5)), 5.0, rec, fidelity="kinematic", seed=1, progress=False)
    out = tmp_path / "out"
    assert cli.main(["report", str(rec), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    timeline = s["timeline"]
    assert s["timeline_window_s"] == pytest.approx(1.0) and len(timeline) == 5
    assert [(w["start_s"], w["end_s"]) for w in timeline] == [pytest.approx((k, k + 1.0)) for k in range(5)]
    before = [w for w in timeline if w["end_s"] <= 2.5]
    after = [w for w in timeline if w["end_s"] > 2.5]
    assert len(before) == 2 and len(after) == 3
    assert all(w["verdict"] == "healthy" and w["faults_present"] == [] and w["defect_sizes"] == [0.0]
               for w in before), before
    assert all(w["verdict"] == "outer" and w["faults_present"] == ["outer"] and w["defect_sizes"] == [1.0]
               and w["prominences"]["outer"] > 10 for w in after), after
    assert all(w["shaft_speed_rpm"] == pytest.approx(1797.0) for w in timeline)
    # the ground truth's time base: the onset in signal time, to the sample
    onset = s["fault_onset_s"]
    assert s["scene_defect_onsets_s"] == [2.5]
    assert onset == pytest.approx(2.5, abs=1e-6) and s["fault_onset_resolution_s"] == 0.0
    assert s["ground_truth_to_the_sample"] is True
    assert s["ground_truth_changes"] == [{"t_s": onset, "after_s": onset, "faults_present": ["outer"],
                                          "defect_sizes": [1.0]}]
    assert s["first_detection_s"] == after[0]["end_s"] == pytest.approx(3.0)    # 0.5 s of the pit
    assert s["detection_latency_s"] == pytest.approx(0.5)
    assert s["fault_detections"] == [{"fault": "outer", "onset_s": onset, "onset_resolution_s": 0.0,
                                      "first_detection_s": s["first_detection_s"],
                                      "latency_s": s["detection_latency_s"], "windows_since": 3}]
    # the whole recording's verdict as before, said not to describe it
    assert s["verdict"] == "outer" and s["verdict_describes_recording"] is False
    # checked against the faults present in the analysed stretch: the pit, for part of it
    assert s["expected_defects"] == ["outer"] and s["expected_defects_from"] == "ground truth"
    assert s["scene_defects"] == [{"kind": "outer", "onset_s": 2.5, "present": "in part of the analysed stretch"}]
    md = (out / "summary.md").read_text()
    assert ("the scene's defects: outer (from 2.5 s); present in the analysed 5.00 s (by `/diagnostics`): "
            "outer (the verdict agrees with the faults present).") in md
    assert "one verdict does not describe it" in md and "## Verdict over time" in md
    assert "| 0.00-2.00 | 2 | healthy | none | 0 |" in md          # a run of windows, not each window
    assert "(none, then outer from 2.50 s)" in md and "- fault onset: 2.5000 s (the first sample" in md
    # the plot: the per-window prominences against the windows' times, and the threshold
    assert "timeline.png" in s["plots"] and (out / "timeline.png").stat().st_size > 10_000
    ax = figures["timeline.png"].axes[0]
    for fault, label in (("outer", "BPFO (outer)"), ("inner", "BPFI (inner)"), ("ball", "2xBSF (ball)")):
        (line,) = [ln for ln in ax.get_lines() if ln.get_label() == label]
        prom = [w["prominences"][fault] for w in timeline]
        np.testing.assert_allclose(line.get_ydata(), prom + prom[-1:], rtol=1e-12)
        np.testing.assert_allclose(line.get_xdata(), [w["start_s"] for w in timeline] + [5.0], rtol=1e-12)
    assert any(ln.get_label().startswith("detection threshold") and ln.get_ydata()[0] == 4.0
               for ln in ax.get_lines())
    (onset_line,) = [ln for ln in ax.get_lines() if ln.get_label() == "onset 2.50 s"]
    assert onset_line.get_xdata()[0] == pytest.approx(2.5)
    sizes_ax = figures["timeline.png"].axes[1]
    assert [tuple(ln.get_ydata()) for ln in sizes_ax.get_lines()] == [(0.0, 0.0, 1.0, 1.0, 1.0)]
    # windows that do not end on a /diagnostics message: 0.7 s.  The one holding the onset (2.1-2.8
    # s) has the fault present, though the message before its end did not, with the sizes of the
    # first message that has it
    s = build_report(rec, tmp_path / "short", window_s=0.7)
    assert [round(w["end_s"], 6) for w in s["timeline"]] == [0.7, 1.4, 2.1, 2.8, 3.5, 4.2, 4.9]
    assert [w["faults_present"] for w in s["timeline"]] == [[]] * 3 + [["outer"]] * 4
    assert [(w["defect_sizes"], w["truth_t_s"]) for w in s["timeline"][2:4]] == [([0.0], 2.0), ([1.0], 3.0)]
    assert s["fault_onset_s"] == onset and s["first_detection_s"] in (pytest.approx(2.8), pytest.approx(3.5))
    assert "may already hold the fault" not in (tmp_path / "short" / "summary.md").read_text()


def test_the_timeline_covers_a_recording_longer_than_the_report_holds(tmp_path, monkeypatch):
    """The waveform, the spectra and the one verdict use the first ``MAX_ANALYSIS_S`` seconds; the
    verdict over time reads the rest of the recording again, one window at a time, and comes out
    window for window as that of the whole recording held in memory.  Here the limit is 1.5 s of
    a 5 s recording whose pit appears at 2.5 s, after it, in windows of 0.7 s (one of them
    across the limit)."""
    rec = tmp_path / "late.mcap"
    render(str(_with_onset(tmp_path, 2.5)), 5.0, rec, fidelity="kinematic", seed=1, progress=False)
    whole = build_report(rec, tmp_path / "whole", window_s=0.7)
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 1.5)
    short = build_report(rec, tmp_path / "short", window_s=0.7)
    assert whole["analysed_s"] == pytest.approx(5.0) and short["analysed_s"] == pytest.approx(1.5)
    assert whole["verdict"] == "outer" and short["verdict"] == "healthy"       # the pit is not in 0-1.5 s
    assert whole["expected_defects"] == ["outer"] and short["expected_defects"] == []    # ... by /diagnostics
    assert short["scene_defects"][0]["present"] == "after the analysed stretch"
    assert "outer (from 2.5 s, after the analysed 1.50 s); present in the analysed 1.50 s (by `/diagnostics`): " \
           "none (the verdict agrees with the faults present)" in (tmp_path / "short" / "summary.md").read_text()
    assert len(short["timeline"]) == 7 and short["timeline"] == whole["timeline"]
    for key in ("fault_onset_s", "first_detection_s", "detection_latency_s", "fault_detections",
                "timeline_unscored_s", "ground_truth_changes"):
        assert short[key] == whole[key], key
    assert short["first_detection_s"] == pytest.approx(3.5) or short["first_detection_s"] == pytest.approx(2.8)


def test_report_timeline_without_a_fault_change_has_no_latency(outer, tmp_path):
    """er16k_outer_race has its defect from the start: every window has the outer fault present,
    so there is no onset and no latency, only a first detection; one verdict describes the
    recording.  ``--window`` longer than half the 2 s recording gives one window, the whole of it."""
    rec, _ = outer
    s = build_report(rec, tmp_path / "out")
    assert [w["faults_present"] for w in s["timeline"]] == [["outer"]] * 2
    assert [w["verdict"] for w in s["timeline"]] == ["outer"] * 2
    assert s["ground_truth_changes"] == [] and s["verdict_describes_recording"] is True
    assert s["fault_onset_s"] is None and s["detection_latency_s"] is None
    assert s["first_detection_s"] == pytest.approx(1.0)
    assert "does not describe" not in (tmp_path / "out" / "summary.md").read_text()
    whole = build_report(rec, tmp_path / "whole", window_s=1.5)["timeline"]
    assert len(whole) == 1 and (whole[0]["start_s"], whole[0]["end_s"]) == pytest.approx((0.0, 2.0))


@pytest.mark.parametrize("window, shown", [("0.1", "0.1 s"), ("200", "200 s"), ("nan", "nan s"), ("x", "'x'")])
def test_report_window_out_of_range_is_one_line(outer, tmp_path, capsys, window, shown):
    rec, _ = outer
    code = cli.main(["report", str(rec), "--out", str(tmp_path / "o"), "--window", window])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "--window" in err[0] and shown in err[0], err[0]
    assert window == "x" or "allowed range is [0.5, 120] s" in err[0]
    assert not (tmp_path / "o").exists()
    with pytest.raises(cli.UserError, match=r"^--window = 0 s: allowed range is \[0.5, 120\] s$"):
        build_report(rec, tmp_path / "o", window_s=0)


@pytest.mark.parametrize("kind", ["not_mcap", "truncated", "folder"])
def test_report_bad_files_exit_2_with_one_line(kind, outer, tmp_path, capsys):
    rec, _ = outer
    bad = tmp_path / "bad.mcap"
    if kind == "not_mcap":
        bad.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(100))
    elif kind == "truncated":       # inside its first record (one cut later is reported: below)
        bad.write_bytes(rec.read_bytes()[:12])
    else:                           # was "no such file": it exists
        bad.mkdir()
    code = cli.main(["report", str(bad), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert {"not_mcap": "not an MCAP file", "truncated": "truncated",
            "folder": f"{bad}: is a folder, not a file; expected an .mcap recording"}[kind] in err[0]


def test_a_truncated_recording_is_reported_as_recovered(outer, tmp_path, capsys):
    """A file a hard kill left without its footer was refused (exit 2, "`mcap recover` can
    salvage its complete chunks").  It is reported up to its last complete chunk: one line on the
    command line says so, ``recovered`` in summary.json and summary.md what is lost; the
    report is that of its messages."""
    rec, _ = outer
    data = rec.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) - 500])         # in its summary: every message there
    code = cli.main(["report", str(cut), "--out", str(tmp_path / "o")])
    captured = capsys.readouterr()
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert code == 0 and captured.err.splitlines() == [f"report: {summary['recovered']}"], captured.err
    assert summary["recovered"].startswith(f"{cut}: read as recovered: no footer and no summary ")
    assert summary["recovered"].endswith("its data section complete, only the summary lost")
    whole = build_report(rec, tmp_path / "whole")
    assert whole["recovered"] is None
    same = ("duration_s", "messages", "analysed_s", "waveform_gaps", "statistics", "verdict", "timeline")
    assert {k: summary[k] for k in same} == {k: whole[k] for k in same}
    assert f"| recovered | {summary['recovered']} |" in (tmp_path / "o" / "summary.md").read_text()


def test_report_of_a_skidding_run_shows_cage_and_skid_ratios(tmp_path):
    pytest.importorskip("bearing_sim_ros.physics.skidding")
    rec = tmp_path / "skid.mcap"
    render("er16k_skidding", 1.0, rec, fidelity="skidding", progress=False)
    s = build_report(rec, tmp_path / "out")
    assert "cage.png" in s["plots"]
    ratios = s["skid_ratios_percent"]
    assert set(ratios) >= {"ball_skid_ratio", "cage_skid_ratio"}
    # percent, and the cage runs slower than pure rolling (seed 000: 1.25 % at this point)
    assert 0.05 < ratios["cage_skid_ratio"] < 20


def test_report_looks_for_the_lines_where_the_recorded_cage_puts_them(tmp_path, skidding_outer_race):
    """Where the cage skids 7 % (10000 rpm / 10 N) the outer-race line is 7 % below pure
    rolling's BPFO; looking there, the report called this outer-race recording a ball fault.  It
    takes the fault frequencies from the recording's /diagnostics: verdict outer, the BPFO line
    found within 0.5 Hz of the recorded bpfo_hz."""
    _scene, rec = skidding_outer_race
    s = build_report(rec, tmp_path / "out")
    rolling, used = s["fault_frequencies_pure_rolling_hz"], s["fault_frequencies_hz"]
    assert used["bpfo"] < 0.95 * rolling["bpfo"] and "/diagnostics" in s["fault_frequencies_from"]
    assert s["verdict"] == "outer"
    assert abs(s["fault_lines"]["bpfo"]["found_hz"] - used["bpfo"]) < 0.5
    assert "Expected at the fault frequencies of the recording's /diagnostics" in (
        tmp_path / "out" / "summary.md").read_text()


def test_order_tracking_looks_for_a_ball_pit_on_the_balls_spin(tmp_path, skidding_ball_pit_speed_step):
    """On the skidding tier a speed step from 1000 to 2000 rpm takes the balls' skid from about
    4.8 % to 3 %: a ball pit's 2xBSF line moves by 2 % in orders of the shaft, out of the +-1 %
    search, and order tracking at the stretch's mean spin called this pit healthy (2xBSF x3.0).
    Now it takes each /diagnostics period's spin (``spin_shares``) and judges the line on the
    balls' spin angle, as the monitor does: ball."""
    _scene, rec = skidding_ball_pit_speed_step
    s = build_report(rec, tmp_path / "out")
    assert s["order_tracking"]["verdict"] == "ball" and s["verdict"] == "ball", s["order_tracking"]
    assert s["order_tracking"]["lines"]["2bsf"]["prominence"] > DETECTION_THRESHOLD, s["order_tracking"]


def test_an_inner_pits_shaft_sideband_on_2xbsf_is_counted_for_the_inner_race(tmp_path, skidding_inner_pit_1000rpm):
    """On the skidding tier at 1000 rpm / 200 N the ER-16K's balls spin about 5 % slow, and 2xBSF
    falls within 0.2 % of BPFI - 1 x shaft rate, a sideband of an inner pit's own line that stands
    higher than BPFI: the report called this inner pit a ball fault (the highest line wins).  Now
    a line on another detected fault's sideband counts for that fault
    (``envelope.borrowed_lines``): inner, and the report says why 2xBSF does not count."""
    _scene, rec = skidding_inner_pit_1000rpm
    s = build_report(rec, tmp_path / "out")
    lines = s["fault_lines"]
    assert s["verdict"] == "inner", (s["verdict"], lines)
    # the coincidence is still there: the sideband found at 2xBSF is the higher of the two
    assert lines["2bsf"]["prominence"] > lines["bpfi"]["prominence"] > DETECTION_THRESHOLD, lines
    shaft_hz = s["shaft_speed_rpm"] / 60.0
    assert abs(lines["2bsf"]["found_hz"] - (lines["bpfi"]["found_hz"] - shaft_hz)) < 0.1, lines
    said = s["borrowed_lines"]["ball"]
    assert said.startswith("2xBSF sits on BPFI - 1 x shaft rate") and "counted for inner" in said, said
    assert said in (tmp_path / "out" / "summary.md").read_text()


def test_a_ball_pits_cage_sideband_on_bpfi_is_counted_for_the_ball(tmp_path, ball_pit_3000rpm):
    """On the ER-16K a ball pit's 2xBSF + 2 x FTF line lies 0.15 % from BPFI, and at 3000 rpm /
    50 N (kinematic) it stands higher than 2xBSF: the report called this ball pit an inner-race
    fault.  Now it is the ball's line (``envelope.borrowed_lines``): ball."""
    _scene, rec = ball_pit_3000rpm
    s = build_report(rec, tmp_path / "out")
    lines = s["fault_lines"]
    assert s["verdict"] == "ball", (s["verdict"], lines)
    assert lines["bpfi"]["prominence"] > lines["2bsf"]["prominence"] > DETECTION_THRESHOLD, lines
    assert s["borrowed_lines"]["inner"].startswith("BPFI sits on 2xBSF + 2 x FTF"), s["borrowed_lines"]


def test_report_says_when_auto_switched_tiers(tmp_path):
    """A profile from 1600 to 10000 rpm with the load taken off moves ``fidelity: auto`` from the
    kinematic to the skidding tier part way: the metadata keeps the tier at the start, and the
    report tells from ``/diagnostics`` that the skidding tier ran after it, and when it took over
    (a batch boundary while the profile ramps)."""
    scene = tmp_path / "up.yaml"
    scene.write_text(load_scene("er16k_outer_race").source_text
                     + "profile:\n  - {t: 0.5, shaft_speed_rpm: 10000, radial_load: [0.0, 0.0]}\n")
    rec = tmp_path / "up.mcap"
    render(str(scene), 1.0, rec, progress=False)
    s = build_report(rec, tmp_path / "out")
    assert s["tier"] == "kinematic" and s["tiers"] == ["kinematic", "skidding"]
    assert s["tier_switches"] == 1
    old_new, t = s["last_tier_switch"].split(" at ")
    assert old_new == "kinematic -> skidding"
    t_s = float(t.removesuffix(" s"))
    assert 0.0 < t_s < 0.5 and t_s * 100 == pytest.approx(round(t_s * 100), abs=1e-9)
    md = (tmp_path / "out" / "summary.md").read_text()
    assert "kinematic tier (" in md and "at the start, then skidding: 1 tier switch, the last kinematic -> skidding at" in md


def _profiled(tmp_path, name, operating_point, profile, duration=3.0):
    """A render of er16k_outer_race at ``operating_point`` (its YAML line) with ``profile`` (YAML
    list items), ``duration`` s, ``fidelity: auto``."""
    text = load_scene("er16k_outer_race").source_text
    old = "operating_point: {shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}"
    assert old in text, "er16k_outer_race.yaml's operating point moved: update this test"
    scene = tmp_path / f"{name}.yaml"
    scene.write_text(text.replace(old, f"operating_point: {operating_point}") + "profile:\n"
                     + "".join(f"  - {item}\n" for item in profile))
    rec = tmp_path / f"{name}.mcap"
    render(str(scene), duration, rec, progress=False)
    return rec


def _verdicts(s):
    return [w["verdict"] for w in s["timeline"]]


def test_a_recording_whose_speed_steps_gets_the_verdict_of_order_tracking(tmp_path, capsys):
    """er16k_outer_race stepped from 1600 to 3000 rpm at 1.5 s (the kinematic tier throughout).
    One envelope spectrum of the whole recording looked for the lines at the mean speed, where
    neither speed has them, and called it a ball fault (2xBSF x11), as did the window that holds
    the step; with --window 0.5 the windows at 1600 and 3000 rpm by the step took the fault
    frequencies of the /diagnostics period that holds it (a mean of both speeds): "healthy", and
    "ball" at x325.  Then the window that holds the step was not scored ("unknown", the lines
    move 61 % in it), and the one verdict was that of the others.  Now that window, and the
    whole recording, are judged in orders of the shaft (order tracking): outer; every other
    window looks at its own lines in Hz (outer)."""
    rec = _profiled(tmp_path, "step", "{shaft_speed_rpm: 1600, radial_load: [0.0, -50.0]}",
                    ["{t: 1.5, shaft_speed_rpm: 1600}", "{t: 1.51, shaft_speed_rpm: 3000}"])
    assert cli.main(["report", str(rec), "--out", str(tmp_path / "out")]) == 0
    said = capsys.readouterr().out
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert _verdicts(s) == ["outer", "outer", "outer"]
    # the key in every window (a consumer's w["order_tracked"] was a KeyError on a steady one)
    assert [w["order_tracked"] for w in s["timeline"]] == [False, True, False]
    assert s["timeline"][1]["line_spread"] > 0.5 and s["timeline"][1]["prominences"]["outer"] > 20      # x55
    assert s["verdict"] == "outer" and s["verdict_faults"] == ["outer"]
    assert s["fault_line_variation"] > 0.5 and s["verdict_from"].startswith("order tracking over the analysed stretch")
    assert "verdict outer (scene defects: outer" in said and "the verdict is that of order tracking" in said
    md = (tmp_path / "out" / "summary.md").read_text()
    assert "**Verdict (envelope analysis of accel_y): OUTER**" in md and "(the verdict agrees with the scene)" in md
    assert "| fault lines | move by 61 % over the analysed stretch" in md
    half = build_report(rec, tmp_path / "half", window_s=0.5)
    assert _verdicts(half) == ["outer"] * 6
    assert [round(w["shaft_speed_rpm"]) for w in half["timeline"]] == [1600] * 3 + [3000] * 3


def test_an_outer_race_run_up_gets_its_verdict_from_order_tracking(outer_run_up, tmp_path, capsys, figures):
    """er16k_outer_race run up from 1000 to 3000 rpm over 4 s: its lines move by 89 % in Hz, so
    the report said "unknown" of the recording and of every window (each ramps 500 rpm), an
    outer-race pit it could not see.  Now the envelope is resampled at equal steps of shaft angle
    (``state``) and its spectrum in orders has BPFO where the bearing puts it: "outer", of the
    recording and of every window, and the summary says how it got there."""
    out = tmp_path / "out"
    assert cli.main(["report", str(outer_run_up), "--out", str(out)]) == 0
    said = capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())
    assert s["verdict"] == "outer" and s["verdict_faults"] == ["outer"] and s["fault_line_variation"] > 0.8
    assert s["verdict_from"].startswith("order tracking over the analysed stretch (0.02-4.00 s, 1009-2999 rpm, "
                                        "133 revolutions)"), s["verdict_from"]
    assert f"the verdict is that of {s['verdict_from']}" in said
    tracked = s["order_tracking"]
    assert tracked["verdict"] == "outer" and tracked["why_not"] is None
    assert tracked["lines"]["bpfo"]["found_order"] == pytest.approx(tracked["lines"]["bpfo"]["expected_order"], rel=1e-3)
    assert tracked["lines"]["bpfo"]["prominence"] > 50
    assert all(line["prominence"] < 4 for key, line in tracked["lines"].items() if key != "bpfo")
    assert [(w["verdict"], w["order_tracked"]) for w in s["timeline"]] == [("outer", True)] * 4
    (orders_ax,) = figures["orders.png"].axes
    assert "orders.png" in s["plots"] and orders_ax.get_xlabel() == "order (events per shaft revolution)"
    bpfo = tracked["lines"]["bpfo"]["expected_order"]
    assert any(list(ln.get_xdata()) == [bpfo, bpfo] for ln in orders_ax.get_lines())      # BPFO marked
    md = (out / "summary.md").read_text()
    assert "**Verdict (envelope analysis of accel_y): OUTER**" in md and "(the verdict agrees with the scene)" in md
    assert "## Order tracking" in md and "| BPFO | 3.5719 | 3.572 |" in md
    assert "| 0.00-4.00 | 4 | outer (in orders) | outer |" in md


@pytest.mark.parametrize("scene_name, verdict", [("er16k_inner_race", "inner"), ("cwru_6205_normal", "healthy")])
def test_an_inner_race_or_healthy_run_up_gets_its_own_verdict(tmp_path, scene_name, verdict):
    """The same run-up of an inner-race pit is "inner" and of a healthy bearing "healthy" (the
    CWRU 6205: the healthy ER-16K rings at BPFO by varying compliance, README "Scenes"); the old
    report said "unknown" of both."""
    s = build_report(render_run_up(tmp_path, scene_name), tmp_path / "out")
    assert s["verdict"] == verdict and s["order_tracking"]["verdict"] == verdict, s.get("order_tracking")
    assert s["verdict_from"].startswith("order tracking")
    assert s["expected_defects"] == ([] if verdict == "healthy" else [verdict])
    assert [w["verdict"] for w in s["timeline"]] == [verdict] * 4
    assert "(the verdict agrees with the scene)" in (tmp_path / "out" / "summary.md").read_text()


@pytest.mark.parametrize("kept, why", [
    (lambda k: False, "the recording has no state (JointState of shaft and cage) to take the shaft angle from"),
    (lambda k: k % 10 == 9, "state samples up to 0.2 s apart: order tracking needs them at most 0.1 s apart"),
])
def test_a_run_up_without_state_enough_to_track_stays_unknown_and_says_why(outer_run_up, tmp_path, kept, why):
    """Without ``state`` (or with 5 Hz of it, too sparse to draw the shaft angle through a
    change) there is no order tracking: the verdict stays "unknown", and the summary says why."""
    rec = tmp_path / "less_state.mcap"
    _copy_without(outer_run_up, rec, lambda topic, k: topic == "/state" and not kept(k))
    s = build_report(rec, tmp_path / "out")
    assert s["verdict"] == "unknown" and s["order_tracking"] == {"verdict": None, "why_not": s["order_tracking"]["why_not"]}
    assert s["order_tracking"]["why_not"].startswith(why) and f"no order tracking: {why}" in s["verdict_from"]
    assert _verdicts(s) == ["unknown"] * 4
    assert f"## Order tracking\n\nNot done: {s['order_tracking']['why_not']}." in (tmp_path / "out" / "summary.md").read_text()


def test_a_load_step_that_moves_the_cages_skid_is_a_moving_line_too(tmp_path):
    """At a steady 10000 rpm the load goes from 50 to 10 N at 1.5 s: fidelity auto switches to the
    skidding tier, whose cage skids, and BPFO moves from 595 to 552 Hz (7 %).  The shaft speed
    did not vary, so the report said nothing, and its one spectrum looked at the mean of both:
    "healthy".  With --window 0.5 the steady window before the switch took the lines of the
    /diagnostics period that holds it: "healthy".  Now the cage speed of ``state`` places each
    window's lines and tells where they move (here in no window more than its first 20 ms, as
    the cage settles after the switch); every verdict is outer."""
    pytest.importorskip("bearing_sim_ros.physics.skidding")
    rec = _profiled(tmp_path, "load", "{shaft_speed_rpm: 10000, radial_load: [0.0, -50.0]}",
                    ["{t: 1.5, radial_load: [0.0, -50.0]}", "{t: 1.51, radial_load: [0.0, -10.0]}"])
    s = build_report(rec, tmp_path / "out", window_s=0.5)
    assert _verdicts(s) == ["outer"] * 6 and s["verdict"] == "outer"
    assert s["tiers"] == ["kinematic", "skidding"] and s["shaft_speed_variation"] == 0.0
    assert s["fault_line_variation"] > 0.05


def test_the_speed_commands_tell_a_step_that_a_low_state_rate_does_not():
    """A node with ``state_rate:=1.0`` gives one ``state`` a second: a window with one sample
    looked steady by it, though the recorded commands stepped from 1600 to 3000 rpm in it (the
    window was scored at lines that neither half has).  With fewer than ``STATES_TO_TELL`` state
    samples the commands count too; with enough, ``state`` alone (the live node applies a
    command 50-70 ms after it logs it)."""
    from types import SimpleNamespace

    rpm = 2 * np.pi / 60
    one_state = SimpleNamespace(t0_ns=0, cmd_t=np.array([0.0, 0.5]), cmd_speed=np.array([1600, 3000]) * rpm,
                                state_t=np.array([0.9]), shaft_w=np.array([3000 * rpm]),
                                cage_w=np.array([1000 * rpm]), signal_frequency_periods=[])
    assert report.line_spread(one_state, 0.0, 1.0) > 0.5
    # 50 Hz, all at 3000 rpm: the command logged at 0.98 s took effect after the window
    many = SimpleNamespace(**{**vars(one_state), "state_t": np.arange(1, 51) / 50.0,
                              "shaft_w": np.full(50, 3000 * rpm), "cage_w": np.full(50, 1000 * rpm),
                              "cmd_t": np.array([0.0, 0.98]), "cmd_speed": np.array([3000, 6000]) * rpm})
    assert report.line_spread(many, 0.0, 1.0) == 0.0


def test_the_verdict_of_windows_names_one_fault_healthy_mixed_or_unknown():
    """``one_verdict`` where the lines move: the fault the scored windows name (healthy ones
    beside it: a fault that appeared, or a speed where its line is weak), "healthy" where they
    name none, "mixed" (both listed) where they name two, "unknown" where none is scored; the
    windows after the analysed stretch do not count; a steady stretch keeps its own verdict."""
    whole = {"verdict": "inner"}

    def of(*verdicts, end_s=10.0, moved=0.5):
        timeline = [{"end_s": k + 1.0, "verdict": v} for k, v in enumerate(verdicts)]
        return report.one_verdict(whole, timeline, moved, end_s)[:2]

    assert of("healthy", "outer", "unknown", "outer") == ("outer", ["outer"])
    assert of("healthy", "unknown") == ("healthy", [])
    assert of("outer", "ball", "outer") == ("mixed", ["ball", "outer"])
    assert of("unknown", "unknown") == ("unknown", [])
    assert of("outer", "ball", end_s=1.0) == ("outer", ["outer"])
    assert of("outer", "ball", moved=0.005) == ("inner", ["inner"])
    assert report.one_verdict(None, [], 0.5, 1.0)[0] == "unknown"


def test_ground_truth_parse_reads_several_faults_sizes_and_onsets():
    """Several faults present are comma-separated (read as a sorted tuple), sizes
    space-separated, onsets ``kind=s`` in signal time, which ``simulated_s`` ties to the stamp:
    on a consumer's time line in s or in ns (the live node's keys are those of the last sample it
    published, whatever it computed ahead: test_defect_onset).  A recording from before
    ``fault_onsets_s`` has no onsets; one from before ``faults_present`` no ground truth."""
    from bearing_sim_ros import ground_truth
    from bearing_sim_ros.recording.render import diagnostics_message

    live = {"faults_present": "inner, ball", "defect_sizes": "1 0.25", "computed_ahead_s": "0.040",
            "fault_onsets_s": "inner=0.000000, ball=3.250000", "simulated_s": "5.000000"}
    assert ground_truth.parse(live, 7.0) == ((7.0, ("ball", "inner"), (1.0, 0.25), {"inner": 2.0, "ball": 5.25}))
    in_ns = ground_truth.parse(live, 7 * NS + 1, NS)
    assert in_ns.onsets == {"inner": 2 * NS + 1, "ball": 5_250_000_001}
    assert all(type(t) is int for t in in_ns.onsets.values())
    old = ground_truth.parse({"faults_present": "none", "defect_sizes": "none"}, 1.0)
    assert old == (1.0, (), (), None)
    assert ground_truth.parse({"tier": "kinematic"}, 1.0) is None
    assert ground_truth.parse({"faults_present": "outer", "defect_sizes": "x"}, 1.0) is None
    # what the simulator writes: a kind once, at its earliest present defect's onset
    written = ground_truth.diagnostics_values(["outer", "ball", "outer"], (0.5, 0.0, 1.0), (4.0, 1.0, 2.5))
    assert written == {"faults_present": "outer", "defect_sizes": "0.5 0 1", "fault_onsets_s": "outer=2.500000"}
    assert ground_truth.diagnostics_values([], (), ()) == {"faults_present": "none", "defect_sizes": "none",
                                                           "fault_onsets_s": "none"}
    message = diagnostics_message(0, {**written, "simulated_s": "3.000000"})
    values = {kv.key: kv.value for kv in message.status[0].values}
    assert ground_truth.parse(values, 3.0).onsets == {"outer": 2.5}


def _truth(t, faults, sizes, onsets=None):
    from bearing_sim_ros.ground_truth import Truth

    return Truth(t, tuple(sorted(faults)), sizes, onsets)


def test_fault_onset_and_truth_with_onsets_to_the_sample():
    """With fault_onsets_s the faults in a window's last sample are exact: those that appeared
    before its end, whichever message tells; the onset has resolution 0; two faults that appear
    between the same two messages are two changes."""
    onsets = {"outer": 1.25, "inner": 1.75}
    truth = [_truth(1.0, (), (0.0, 0.0), {}), _truth(2.0, ("outer", "inner"), (1.0, 1.0), onsets),
             _truth(3.0, ("outer", "inner"), (1.0, 1.0), onsets)]
    assert report.fault_onset(truth) == (1.25, 0.0)
    assert [faults_at(truth, t, report.SLACK_S) for t in (0.5, 1.25, 1.2501, 1.75, 1.76, 9.0)] == \
        [(), (), ("outer",), ("outer",), ("inner", "outer"), ("inner", "outer")]
    changes = report.truth_changes(truth)
    assert [(c["t_s"], c["after_s"], c["faults_present"]) for c in changes] == \
        [(1.25, 1.25, ["outer"]), (1.75, 1.75, ["inner", "outer"])]
    timeline = [{"end_s": e, "verdict": v} for e, v in ((1.0, "healthy"), (1.5, "healthy"), (2.0, "outer"),
                                                        (2.5, "inner"))]
    assert [(d["fault"], d["first_detection_s"], d["latency_s"], d["windows_since"])
            for d in report.fault_detections(timeline, truth)] == [("outer", 2.0, 0.75, 3), ("inner", 2.5, 0.75, 2)]
    # an onset on a message's stamp: that message tells the sample before it (no fault yet, the
    # old sizes); the change's sizes are those of the first message that shows the fault
    on_stamp = [_truth(1.0, (), (0.0,), {}), _truth(2.0, (), (0.0,), {}),
                _truth(3.0, ("outer",), (1.0,), {"outer": 2.0})]
    assert report.truth_changes(on_stamp) == [{"t_s": 2.0, "after_s": 2.0, "faults_present": ["outer"],
                                               "defect_sizes": [1.0]}]
    # a fault there from the first sample: no onset, though another joins it later
    assert report.fault_onset([_truth(1.0, ("ball",), (1.0,), {"ball": 0.0}),
                               _truth(2.0, ("ball", "outer"), (1.0,), {"ball": 0.0, "outer": 1.5})]) is None


def test_fault_onset_without_onsets_is_the_first_change_from_none_and_truth_holds_until_the_next():
    """A recording from before fault_onsets_s: the onset is where the faults present go from none
    to some (not where a second fault joins one already there), known between two messages; a
    window's ground truth is the latest message at or before its end, none before the first when
    that has none."""
    truth = [_truth(1.0, (), (0.0, 0.0)), _truth(2.0, ("outer",), (0.4, 0.0)),
             _truth(3.0, ("outer", "inner"), (1.0, 1.0))]
    assert report.fault_onset(truth) == (2.0, 1.0)
    assert report.fault_onset(truth[1:]) is None          # a fault there at the first sample
    assert report.truth_changes(truth)[1] == {"t_s": 3.0, "after_s": 2.0, "faults_present": ["inner", "outer"],
                                              "defect_sizes": [1.0, 1.0]}
    assert [faults_at(truth, t, report.SLACK_S) for t in (0.5, 1.0, 1.999998, 1.9999999, 2.5, 9.0)] == \
        [(), (), (), ("outer",), ("outer",), ("inner", "outer")]          # 1 us of rounding allowed
    assert faults_at(truth[1:], 0.5, report.SLACK_S) is None       # before a first message with a fault
    assert faults_at([], 1.0) is None
    timeline = [{"end_s": e, "verdict": v} for e, v in ((1.5, "outer"), (2.0, "healthy"), (2.5, "outer"))]
    (outer, inner) = report.fault_detections(timeline, truth)
    assert (outer["onset_s"], outer["onset_resolution_s"], outer["first_detection_s"]) == (2.0, 1.0, 2.5)
    assert (inner["fault"], inner["first_detection_s"], inner["windows_since"]) == ("inner", None, 0)


def _copy_without(src, dst, drop, metadata=lambda m: m, rewrite=lambda topic, data: data) -> int:
    """Copy the MCAP ``src`` to ``dst`` (metadata, schemas, channels, messages) leaving out the
    messages for which ``drop(topic, index on that topic)`` is true, each metadata record's
    values through ``metadata``, each message's bytes through ``rewrite(topic, data)``; how many
    were left out."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    left_out, schemas, channels, counts = 0, {}, {}, {}
    with open(src, "rb") as f, open(dst, "wb") as g:
        reader, writer = make_reader(f), Writer(g)
        header = reader.get_header()
        writer.start(header.profile, header.library)
        for meta in reader.iter_metadata():
            writer.add_metadata(meta.name, metadata(dict(meta.metadata)))
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            k = counts[channel.topic] = counts.get(channel.topic, -1) + 1
            if drop(channel.topic, k):
                left_out += 1
                continue
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(channel.topic, channel.message_encoding,
                                                               schemas[schema.id], dict(channel.metadata))
            writer.add_message(channels[channel.id], message.log_time, rewrite(channel.topic, message.data),
                               message.publish_time, message.sequence)
        writer.finish()
    return left_out


def test_report_timeline_keeps_signal_time_across_a_lost_table(tmp_path):
    """A recording that lost one 10 ms accel table at 1.5 s (a subscriber that fell behind): the
    summary counts the gap, the windows take their times from the tables' stamps (the one across
    the gap is 10 ms longer, the ones after it 10 ms later), and the ground truth follows signal
    time, so the pit that appears at 2.5 s is present from the window that holds 2.5 s on."""
    whole = tmp_path / "late.mcap"
    render(str(_with_onset(tmp_path, 2.5)), 5.0, whole, fidelity="kinematic", seed=1, progress=False)
    lost = tmp_path / "lost.mcap"
    assert _copy_without(whole, lost, lambda topic, k: topic == "/accel" and k == 150) == 1
    s = build_report(lost, tmp_path / "out")
    assert s["waveform_gaps"] == 1 and s["analysed_s"] == pytest.approx(4.99)
    spans = [(w["start_s"], w["end_s"]) for w in s["timeline"]]
    assert spans == [pytest.approx(t, abs=1e-9) for t in ((0.0, 1.0), (1.0, 2.01), (2.01, 3.01), (3.01, 4.01))]
    assert [w["faults_present"] for w in s["timeline"]] == [[], [], ["outer"], ["outer"]]
    assert s["fault_onset_s"] == pytest.approx(2.5, abs=1e-6)
    assert [w["verdict"] for w in s["timeline"]] == ["healthy", "healthy", "outer", "outer"]
    assert s["detection_latency_s"] == pytest.approx(0.51)
    assert "| waveform | 15000 Hz, accel_x, accel_y; 1 gap (lost tables) |" in (tmp_path / "out" / "summary.md").read_text()


def test_report_of_a_recording_whose_scene_this_version_cannot_read_claims_nothing_about_it(
        outer, tmp_path, capsys):
    """A recording whose scene YAML this version does not accept (made by another version, or
    edited): the report said "the scene's defects: none (healthy) (the verdict agrees with the
    scene)" under the scene's own title.  Now the defects are unknown, with why, and no
    agreement is claimed; the verdict itself still comes from the waveform (as it can: the lines
    need the bearing, so without the scene it is unknown)."""
    from bearing_sim_ros import cli

    odd = tmp_path / "odd.mcap"
    _copy_without(outer[0], odd, lambda topic, k: False,
                  metadata=lambda m: dict(m, scene_yaml=m["scene_yaml"].replace("bearing:", "bearing_x:"))
                  if "scene_yaml" in m else m)
    out = tmp_path / "odd_report"
    assert cli.main(["report", str(odd), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["expected_defects"] is None
    assert s["scene_unknown"].startswith("this version cannot read its scene: ") and "bearing_x" in s["scene_unknown"]
    md = (out / "summary.md").read_text()
    assert "the scene's defects: unknown (this version cannot read its scene: " in md
    assert "agrees" not in md and "none (healthy)" not in md
    assert "scene defects: unknown, this version cannot read its scene" in capsys.readouterr().out


@pytest.mark.parametrize("kept", [("/accel",), ("/accel", "/state")])
def test_report_of_a_recording_with_no_operating_point_says_so_without_a_warning(outer, tmp_path, figures, kept):
    """Only /accel (no /shaft_speed, /load, /state, /diagnostics) and no scene in the metadata,
    as from `ros2 bag record /accel`: the report let matplotlib's "No artists with labels found to
    put in legend" through to the terminal (the operating-point plot had nothing to draw and a
    legend of nothing).  Now nothing is warned; with no operating point at all the plot is not
    drawn and the summary says why, with a shaft speed (from /state) but no load the load panel
    says what is missing in the figure."""
    import warnings

    rec = tmp_path / "partial.mcap"
    _copy_without(outer[0], rec, lambda topic, k: topic not in kept,
                  metadata=lambda m: {k: v for k, v in m.items() if k != "scene_yaml"})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = build_report(rec, tmp_path / "out")
    assert [str(w.message) for w in caught] == []
    no_verdict = ("no verdict: no bearing to place the fault lines on (the recording has no bearing_sim scene) "
                  "and no fault frequencies in its /diagnostics (cage_hz, bpfo_hz, bpfi_hz, bsf_hz)")
    md = (tmp_path / "out" / "summary.md").read_text()
    if kept == ("/accel",):
        why = "no /shaft_speed, /state or /load in the recording and no scene to take the operating point from"
        assert s["plots_not_drawn"] == {"envelope.png": no_verdict, "timeline.png": no_verdict,
                                        "operating_point.png": why}
        assert s["plots"] == ["waveform.png", "spectrum.png"] and not (tmp_path / "out" / "operating_point.png").exists()
        assert f"- `operating_point.png`: {why}" in md
    else:
        assert "operating_point.png" in s["plots"] and "operating_point.png" not in s["plots_not_drawn"]
        speed, load = figures["operating_point.png"].axes
        assert speed.get_legend() is not None and load.get_legend() is None
        assert [t.get_text() for t in load.texts] == ["radial load not recorded (no /load) and no scene"]


def _other_tools_recording(path, tables) -> None:
    """An MCAP file written with ``rosbags`` (another tool, no ``bearing_sim`` metadata) whose
    ``/accel`` holds ``tables``: PointCloud2 messages (rosbags' type) or raw CDR bytes each."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    msgtype = "sensor_msgs/msg/PointCloud2"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/accel", msgtype, typestore=store)
        for k, table in enumerate(tables):
            data = table if isinstance(table, bytes) else store.serialize_cdr(table, msgtype)
            writer.write(conn, k * 10_000_000, data)


def _table(stamp_ns: int, fields=(("accel_y", 7),), width: int = 150):
    """A rosbags PointCloud2 of ``width`` points with ``fields`` (name, PointField datatype), 4
    bytes each: a waveform table where every datatype is FLOAT32 (7)."""
    from rosbags.typesys import Stores, get_typestore

    types = get_typestore(Stores.ROS2_JAZZY).types
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=stamp_ns // NS, nanosec=stamp_ns % NS), frame_id="s")
    step = 4 * len(fields)
    return types["sensor_msgs/msg/PointCloud2"](
        header=header, height=1, width=width, is_bigendian=False, point_step=step, row_step=step * width,
        is_dense=True, data=np.zeros(step * width, dtype=np.uint8),
        fields=[types["sensor_msgs/msg/PointField"](name=n, offset=4 * k, datatype=t, count=1)
                for k, (n, t) in enumerate(fields)])


@pytest.mark.parametrize("kind, said", [
    ("not_a_table", "/accel logged at 0.000000000 s: not a waveform table: field(s) intensity not one FLOAT32 each"),
    ("undecodable", "the sensor_msgs/msg/PointCloud2 on /accel logged at 0.000000000 s does not deserialize as that "
                    "type (RMWError: "),
    ("no_samples", "the waveform tables on /accel hold no samples"),
    ("stamps_go_back", "cannot tell the sample rate from the waveform tables on /accel"),
    ("one_table", "cannot tell the sample rate from the waveform tables on /accel"),
    ("channels_change", "/accel: a table's channels (accel_x, accel_y) are not the first table's (accel_y)"),
])
def test_report_of_another_tools_recording_it_cannot_read_is_one_line(kind, said, tmp_path, capsys):
    """Recordings from another tool (written with rosbags) whose ``/accel`` is not what the
    report reads: a point cloud with a UINT8 field (a lidar's), bytes that are not a
    PointCloud2, tables of no samples, stamps going back, one table only, channels that change
    from one table to the next.  Each ended in a traceback and 'internal error' (exit 1:
    ValueError, RMWError, ZeroDivisionError, scipy's "fs must be positive", numpy's concatenate);
    now one line that names the file, exit status 2."""
    tables = {
        "not_a_table": [_table(k * 10_000_000, (("x", 7), ("intensity", 2))) for k in range(3)],
        "undecodable": [b"\x00\x01\x00\x00" + b"\xff" * 40] * 3,
        "no_samples": [_table(k * 10_000_000, width=0) for k in range(3)],
        "stamps_go_back": [_table(10 * NS - k * 10_000_000) for k in range(3)],
        "one_table": [_table(0)],
        "channels_change": [_table(0), _table(10_000_000, (("accel_x", 7), ("accel_y", 7)))],
    }[kind]
    bag = tmp_path / "bag"
    _other_tools_recording(bag, tables)
    path = bag / "bag.mcap"
    code = cli.main(["report", str(path), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"error: {path}: ") and said in err[0], err[0]


def _one_topic_recording(path, data: bytes):
    """A ros2-profile MCAP with five messages of ``data`` on /accel, typed PointCloud2."""
    from mcap.writer import Writer

    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="ros2", library="test")
        schema = writer.register_schema(name="sensor_msgs/msg/PointCloud2", encoding="ros2msg", data=b"")
        channel = writer.register_channel(topic="/accel", message_encoding="cdr", schema_id=schema)
        for k in range(5):
            writer.add_message(channel, log_time=k * NS // 10, publish_time=k * NS // 10, data=data)
        writer.finish()


def test_a_recording_of_other_bytes_or_tables_is_one_line(tmp_path, capsys):
    """Bytes that are not the type the channel names (a damaged file, another writer's), and a
    PointCloud2 that is no waveform table, ended report with rclpy's RMWError or a ValueError
    traceback and "internal error" (exit 1).  Now one line naming the file, topic and message,
    exit 2."""
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import PointCloud2

    garbage, empty = tmp_path / "garbage.mcap", tmp_path / "empty_cloud.mcap"
    _one_topic_recording(garbage, b"\x00\x01\x00\x00garbage")
    _one_topic_recording(empty, serialize_message(PointCloud2()))
    for path, line in ((garbage, rf"error: {re.escape(str(garbage))}: the sensor_msgs/msg/PointCloud2 on /accel logged "
                                 r"at 0\.000000000 s does not deserialize as that type \(RMWError: [^\n]+\); a damaged "
                                 r"recording or another writer's"),
                       (empty, re.escape(f"error: {empty}: the table on /accel logged at 0.000000000 s: not a waveform "
                                         "table: point_step 0, channels 0, height 0, big-endian False; expected the "
                                         "node's waveform tables (README, \"Consuming a waveform table\")"))):
        assert cli.main(["report", str(path), "--out", str(tmp_path / "r")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and re.fullmatch(line, err[0]), err


def _rewritten_by_rosbags(src, folder, exclude_topics=()):
    """``src`` rewritten by the ``rosbags`` library (``rosbags-convert``, the independent reader
    the README names): the messages, schemas and channels as they were, the ``bearing_sim``
    metadata record (scene, parameters) gone.  The path of the MCAP file it writes."""
    from rosbags.convert import convert

    convert([src], folder, dst_storage="mcap", dst_version=9, compress=None, compress_mode="file",
            default_typestore=None, typestore=None, exclude_topics=list(exclude_topics), include_topics=[],
            exclude_msgtypes=[], include_msgtypes=[])
    return folder / f"{folder.name}.mcap"


def test_report_without_the_bearing_sim_metadata_takes_the_fault_lines_from_the_recorded_diagnostics(
        outer, tmp_path, capsys):
    """A recording rewritten by rosbags has no ``bearing_sim`` metadata, so no scene and no
    bearing: the report gave no verdict ("unknown", no envelope, no timeline), although every
    recorded ``/diagnostics`` gives the fault frequencies as the signal has them (``cage_hz``,
    ``bpfo_hz``, ``bpfi_hz``, ``bsf_hz``).  Now it looks for the lines there, says so, and finds
    the outer-race fault as it does in the original; without those /diagnostics either, one line
    says there is no verdict and why."""
    rewritten = _rewritten_by_rosbags(outer[0], tmp_path / "rewritten")
    with open_recording(rewritten) as rec:
        assert "scene_yaml" not in rec.metadata          # what rosbags keeps of the original
    out = tmp_path / "rewritten_report"
    assert cli.main(["report", str(rewritten), "--out", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    s = json.loads((out / "summary.json").read_text())
    original = build_report(outer[0], tmp_path / "original_report")
    assert s["verdict"] == original["verdict"] == "outer"
    assert s["fault_frequencies_hz"] == pytest.approx(original["fault_frequencies_hz"])
    assert [w["verdict"] for w in s["timeline"]] == [w["verdict"] for w in original["timeline"]]
    assert {"envelope.png", "timeline.png"} <= set(s["plots"]) and not s["plots_not_drawn"]
    assert s["expected_defects"] is None                 # no scene: no agreement claimed
    # the scene and bearing its /diagnostics name (recordings since 2026-11-29): named, and where from
    source = ("the recording's /diagnostics (cage_hz, bpfo_hz, bpfi_hz, bsf_hz), mean over the recording, as it "
              "has no scene to take the bearing from (the recording has no bearing_sim scene; its /diagnostics "
              "name scene er16k_outer_race (ER-16K))")
    assert s["fault_frequencies_from"] == source
    assert s["diagnostics_scenes"] == [{"scene": "er16k_outer_race", "bearing": "ER-16K"}]
    assert s["scene_unknown"].endswith("; its /diagnostics name scene er16k_outer_race (ER-16K)")
    assert printed[-1] == f"{out}: fault lines looked for at the frequencies of {source}"
    assert f"Expected at the fault frequencies of {source}." in (out / "summary.md").read_text()

    bare = _rewritten_by_rosbags(outer[0], tmp_path / "bare", exclude_topics=["/diagnostics"])
    why = ("no verdict: no bearing to place the fault lines on (the recording has no bearing_sim scene) and no "
           "fault frequencies in its /diagnostics (cage_hz, bpfo_hz, bpfi_hz, bsf_hz)")
    _report_without_a_verdict(bare, tmp_path / "bare_report", why, capsys)


def _report_without_a_verdict(recording, out, why: str, capsys) -> dict:
    """``bearing-sim report`` of ``recording`` into ``out``: no verdict, and ``why`` said on the
    command line, in summary.json and summary.md; the summary."""
    assert cli.main(["report", str(recording), "--out", str(out)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == f"{out}: {why}"
    s = json.loads((out / "summary.json").read_text())
    assert s["verdict"] == "unknown" and s["plots_not_drawn"]["envelope.png"] == why
    assert f"Fault frequencies: none: {why[len('no verdict: '):]}." in (out / "summary.md").read_text()
    assert s["diagnostics_scenes"] == []
    return s


def _without_keys(keys):
    """A ``_copy_without`` ``rewrite`` that takes ``keys`` out of every /diagnostics status, as
    a recording made before them has it."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.serialization import deserialize_message, serialize_message

    def rewrite(topic, data):
        if topic != "/diagnostics":
            return data
        msg = deserialize_message(data, DiagnosticArray)
        for status in msg.status:
            status.values = [kv for kv in status.values if kv.key not in keys]
        return serialize_message(msg)
    return rewrite


def test_no_verdict_names_the_fault_frequency_keys_the_diagnostics_lack(outer, tmp_path, capsys):
    """A recording without the bearing_sim metadata whose /diagnostics give cage_hz, bpfo_hz and
    bpfi_hz but not bsf_hz (made before that key): no verdict, and the line said "no fault
    frequencies in its /diagnostics (cage_hz, bpfo_hz, bpfi_hz, bsf_hz)" though three are there.
    It names the one missing, and the three there."""
    old = tmp_path / "old.mcap"
    _copy_without(outer[0], old, lambda topic, k: False,
                  metadata=lambda m: {k: v for k, v in m.items() if k != "scene_yaml"},
                  rewrite=_without_keys({"bsf_hz", "scene", "bearing"}))
    why = ("no verdict: no bearing to place the fault lines on (the recording has no bearing_sim scene) and no "
           "bsf_hz in its /diagnostics (they give cage_hz, bpfo_hz, bpfi_hz; the lines need all four)")
    _report_without_a_verdict(old, tmp_path / "old_report", why, capsys)


class _CountedReads(dict):
    """A period's recorded frequencies that count how often they are read (``reads[0]``)."""

    def __init__(self, values, reads):
        super().__init__(values)
        self.reads = reads

    def __getitem__(self, key):
        self.reads[0] += 1
        return super().__getitem__(key)

    def items(self):
        self.reads[0] += 1
        return super().items()


def _hours_data(seconds: int, reads: list):
    """What ``verdict_timeline`` needs of ``_Data`` for ``seconds`` s of signal at 10 kHz: a state
    at 50 Hz, a ``shaft_speed`` command at 100 Hz and a ``/diagnostics`` period a second (their
    frequencies counting their reads), the speed ramping 1600 -> 2400 rpm."""
    from types import SimpleNamespace

    rpm = 2 * np.pi / 60
    fs, tables = 10_000.0, 100 * seconds
    state_t = np.arange(1, 50 * seconds + 1) / 50.0
    shaft = (1600 + 800 * state_t / seconds) * rpm
    cage = 0.4 * shaft
    periods = [(float(k), float(k + 1), _CountedReads({"ftf": 10.0 + k * 1e-3, "bpfo": 80.0, "bpfi": 120.0,
                                                       "bsf": 50.0}, reads)) for k in range(seconds)]
    return SimpleNamespace(t0_ns=0, samples=int(fs * seconds), sample_rate=fs, stamps=np.arange(tables) * NS // 100,
                           widths=np.full(tables, 100), cmd_t=np.arange(100 * seconds) / 100.0,
                           cmd_speed=(1600 + 800 * np.arange(100 * seconds) / 100.0 / seconds) * rpm,
                           state_t=state_t, shaft_w=shaft, cage_w=cage, shaft_angle=np.cumsum(shaft) / 50.0,
                           cage_angle=np.cumsum(cage) / 50.0, signal_frequency_periods=periods,
                           signal_frequencies={}, truth=[])


def test_the_verdict_timeline_of_a_long_recording_reads_each_period_for_the_windows_it_overlaps():
    """An hour's report places each one-second window's fault lines by the recorded /diagnostics
    periods it overlaps.  It moved every period to the window's speed and weighed all of them,
    in Python, for each window: quadratic in the length (a 30-min recording spent 80 s on it,
    an hour four times that).  Now each window reads the periods it overlaps, so the reads grow
    as the recording does: 4 x the length, 4 x the reads (they were 16 x)."""
    scene = load_scene("er16k_outer_race")
    counted = []
    for seconds in (60, 240):
        reads = [0]
        d = _hours_data(seconds, reads)
        empty = lambda bounds: (np.zeros(0) for _ in bounds)       # noqa: E731 - unscored windows
        timeline = report.verdict_timeline(d, np.zeros(0), scene, 1.0, d.cmd_speed.mean(), empty)
        assert len(timeline) == seconds
        counted.append(reads[0])
    assert counted[1] < 6 * counted[0], counted


def test_the_recorded_periods_give_the_frequencies_of_every_window_to_the_bit():
    """``RecordedPeriods.frequencies`` (each window reads the periods it overlaps) gives what
    ``recorded_frequencies(at_shaft_speed(...))`` of all the periods gives, bit for bit: windows
    across several periods, inside one, before and after all of them (the nearest), at a shaft
    speed and as recorded."""
    rng = np.random.default_rng(3)
    ends = np.cumsum(rng.uniform(0.3, 1.2, 40))
    periods = [(0.0 if k == 0 else float(ends[k - 1]), float(end),
                {"ftf": rng.uniform(9, 11), "bpfo": rng.uniform(70, 90), "bpfi": rng.uniform(110, 130),
                 **({"bsf": rng.uniform(40, 60)} if k % 7 else {})}) for k, end in enumerate(ends)]
    held = report.RecordedPeriods(periods)
    for start in [-3.0, -0.5, *rng.uniform(0, ends[-1], 60), ends[-1] - 0.1, ends[-1] + 2.0]:
        for length in (0.25, 1.0, 3.7):
            for shaft_hz in (None, 1.0, 26.7, float("nan"), 0.0):
                whole = report.at_shaft_speed(periods, shaft_hz) if shaft_hz is not None else periods
                assert held.frequencies(start, start + length, shaft_hz) == \
                    report.recorded_frequencies(whole, start, start + length)
    assert report.RecordedPeriods([]).frequencies(0.0, 1.0, 26.7) == {}


def test_a_truncated_recording_is_scanned_once_per_report(outer, tmp_path, monkeypatch):
    """A file without its footer is scanned as it opens: every chunk read and decompressed to
    find its messages.  The report opened it a second time to read the windows of its timeline
    beyond ``MAX_ANALYSIS_S``, scanning it all again (an hour's cut file: one more pass over
    gigabytes).  It is opened once now, and its timeline is the same."""
    from bearing_sim_ros.recording import reader

    rec, _ = outer
    data = rec.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) - 500])
    scans = []
    scan = reader._scan
    monkeypatch.setattr(reader, "_scan", lambda *args: scans.append(args[2]) or scan(*args))
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 1.0)
    s = build_report(cut, tmp_path / "o", window_s=0.5)
    assert scans == [str(cut)]
    assert s["analysed_s"] == pytest.approx(1.0) and len(s["timeline"]) == 4      # two of them read again
    assert s["timeline"] == build_report(rec, tmp_path / "whole", window_s=0.5)["timeline"]


def test_a_recording_longer_than_the_report_holds_is_decompressed_once(outer, tmp_path, monkeypatch):
    """The windows of the timeline past ``MAX_ANALYSIS_S`` were read from the file again: every
    chunk decompressed twice per report, a truncated file's three times with the scan as it opens
    (a 10-min recording: 747 chunks, 276 MB, decompressed again).  The report keeps those samples as
    it reads them (a temporary file in --out, gone after): once, twice a truncated file, and the
    timeline is that of the whole recording held in memory."""
    import zstandard

    rec, _ = outer
    data = rec.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) - 500])         # in its summary: every chunk there
    with open_recording(rec) as whole_file:
        chunks = len(whole_file.summary.chunk_indexes)
    whole = build_report(rec, tmp_path / "whole", window_s=0.5)["timeline"]
    decompressed = []
    decompress = zstandard.decompress
    monkeypatch.setattr(zstandard, "decompress", lambda *a, **k: decompressed.append(1) or decompress(*a, **k))
    # 1.03 s held: the window 1.0-1.5 s is partly in memory, partly kept (at 1.0 s every window
    # was one or the other, and one that lost its part in memory went unseen)
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 1.03)
    for path, passes in ((rec, 1), (cut, 2)):
        decompressed.clear()
        out = tmp_path / f"o_{path.stem}"
        s = build_report(path, out, window_s=0.5)
        assert len(decompressed) == passes * chunks, (path.name, len(decompressed), chunks)
        assert s["analysed_s"] == pytest.approx(1.03) and s["timeline"] == whole
        assert sorted(p.name for p in out.iterdir()) == sorted([*s["plots"], "summary.json", "summary.md"])


def test_a_full_disk_while_the_samples_past_those_held_are_kept_is_one_line(outer, tmp_path, monkeypatch, capsys):
    """The samples past ``MAX_ANALYSIS_S`` go to a temporary file in --out as the recording is
    read: a full disk there is one line naming --out and exit status 2, not a traceback."""
    import errno
    import io

    class FullDisk(io.BytesIO):
        def write(self, data):
            raise OSError(errno.ENOSPC, "No space left on device")

    rec, _ = outer
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 1.0)
    monkeypatch.setattr(report.tempfile, "TemporaryFile", lambda **kwargs: FullDisk())
    out = tmp_path / "o"
    code = cli.main(["report", str(rec), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err == f"error: --out = {str(out)!r}: cannot write (No space left on device)\n", err


class _LongerRecording:
    """A recording ``rec`` whose ``state``, ``shaft_speed`` and ``load`` messages come ``times`` x
    over (its waveform tables and /diagnostics once): what the report keeps of every message of
    an hour's recording, without an hour's file.  ``held``: the memory traced once all are read."""

    def __init__(self, rec, times: int):
        self.rec, self.times = rec, times
        self.path, self.metadata = rec.path, rec.metadata
        self.topics, self.parameters = rec.topics, rec.parameters

    def messages(self, topics=None):
        held = list(self.rec.messages(topics))
        yield from held
        repeated = [m for m in held if m[0] in ("/state", "/shaft_speed", "/load")]
        for _ in range(self.times - 1):
            yield from repeated
        self.held = tracemalloc.get_traced_memory()[0]


def test_what_the_report_keeps_of_every_message_is_a_few_bytes_a_value(outer):
    """The report keeps the whole recording's ``state`` (50 Hz), ``shaft_speed`` commands and
    ``load`` (100 Hz) and table stamps for its timeline.  It kept them as lists of Python floats,
    ints and (x, y) tuples while it read the file: 2 s of those messages (100 states of 5 values,
    200 commands and 200 loads) added 50 kB, 90 MB an hour.  Arrays of machine
    numbers hold 8 bytes a value: 8 kB."""
    rec_path, _ = outer
    held = []
    with open_recording(rec_path) as rec:
        for times in (10, 40):
            longer = _LongerRecording(rec, times)
            tracemalloc.start()
            report._Data(longer)
            tracemalloc.stop()
            held.append(longer.held)
    per_2_s = (held[1] - held[0]) / 30
    assert per_2_s < 20_000, per_2_s


def test_the_timeline_gives_each_defects_sizes_by_its_kind(tmp_path):
    """A scene with two defects, one of them appearing and growing: summary.md's "defect sizes"
    column gave the range of all sizes at once ("1" for a ball and an inner-race defect at full
    size, "0-1" for one at full size and one growing, which could be either); now each defect's
    by its kind, in the scene's order that summary.json's ``scene_defect_kinds`` gives (that of
    ``defect_sizes``)."""
    import yaml

    doc = yaml.safe_load(load_scene("b6205_ball_inner").source_text)
    assert [d["kind"] for d in doc["defects"]] == ["ball", "inner"]
    doc["defects"][1].update(onset_s=1.5, growth_s=2.0)
    (tmp_path / "grows.yaml").write_text(yaml.safe_dump(doc))
    out = tmp_path / "r.mcap"
    render(str(tmp_path / "grows.yaml"), 4.0, out, fidelity="kinematic", progress=False)
    s = build_report(out, tmp_path / "rep", window_s=1.0)
    assert s["scene_defect_kinds"] == ["ball", "inner"]
    md = (tmp_path / "rep" / "summary.md").read_text()
    rows = [line for line in md.splitlines() if re.match(r"\| \d+\.\d\d-\d+\.\d\d \|", line)]
    assert [row.split(" | ")[4] for row in rows] == ["ball 1, inner 0", "ball 1, inner 0.25", "ball 1, inner 0.75-1"], rows


def test_the_timeline_names_two_defects_of_one_kind_by_their_place():
    """Two outer-race pits said "outer 1, outer 0.5" in summary.md's defect sizes, which does not
    say which is which; now by their place in the scene, as a scene without kinds numbers them."""
    run = [{"defect_sizes": [1.0, 0.5]}, {"defect_sizes": [1.0, 0.75]}]
    assert report._sizes_text(run, ["outer", "outer"]) == "outer #1 1, outer #2 0.5-0.75"
    assert report._sizes_text(run, ["ball", "outer"]) == "ball 1, outer 0.5-0.75"
    assert report._sizes_text(run, []) == "#1 1, #2 0.5-0.75"
    assert report._sizes_text([{"defect_sizes": None}], ["outer"]) == "n/a"


def test_ground_truth_reading_at_the_edges_of_the_messages():
    """What a scorer asks of ``ground_truth`` where a time falls on a message's stamp or before
    the first one, and what the simulator writes for a kind with several defects:

    - a kind's onset is its earliest present defect's, in whatever order the scene lists them;
    - the faults just before ``t`` leave out a kind whose first sample is the one at ``t``, though
      the message stamped ``t`` lists it;
    - without onsets, the message stamped at ``t`` itself is the latest at or before ``t``;
    - ``truth_before`` a time before the first message is the first message (its defect sizes);
    - ``forget_before`` keeps the latest message at or before ``t``, which later times still read;
    - a fault there from the first sample, its onset 0.4 us after it by the rounding of
      ``simulated_s``, did not appear;
    - a window that ends on an exact onset (its last sample the one before the defect's first)
      does not call it."""
    from bearing_sim_ros import ground_truth as gt

    written = gt.diagnostics_values(["outer", "outer"], (1.0, 1.0), (2.5, 4.0))
    assert written["fault_onsets_s"] == "outer=2.500000"
    on_stamp = [gt.Truth(2.0, ("outer",), (1.0,), {"outer": 2.0})]
    assert gt.faults_at(on_stamp, 2.0) == () and gt.faults_at(on_stamp, 2.000001) == ("outer",)
    plain = [gt.Truth(1.0, (), (0.0,), None), gt.Truth(2.0, ("outer",), (1.0,), None),
             gt.Truth(3.0, ("outer",), (1.0,), None)]
    assert gt.faults_at(plain, 2.0) == ("outer",) and gt.faults_at(plain, 1.9) == ()
    assert gt.truth_before(plain, 2.0) is plain[1] and gt.truth_before(plain, 0.5) is plain[0]
    assert gt.truth_before([], 0.5) is None
    kept = list(plain)
    gt.forget_before(kept, 2.5)
    assert kept == plain[1:] and gt.faults_at(kept, 2.6) == ("outer",)
    t0, slack = 500_000_000, 1_000
    rounded = [gt.Truth(t0 + k * 1_000_000_000, ("outer",), (1.0,), {"outer": t0 + 400}) for k in (1, 2)]
    assert gt.appearances(rounded, t0, slack) == []
    exact = gt.Appearance("outer", 2.0, 2.0)
    assert gt.first_detection([(1.5, "healthy"), (2.0, "outer"), (2.5, "outer")], exact) == (2.5, 1)


def test_the_simulators_status_name_has_no_leading_slash():
    """``/diagnostics`` statuses are named ``<node>: simulator`` with the node's full name without
    its leading slash (README: ``rig1/bearing_sim: simulator``), as a node's fully qualified name
    gives it with one."""
    from bearing_sim_ros.ground_truth import status_name

    assert status_name("/rig1/bearing_sim") == status_name("rig1/bearing_sim") == "rig1/bearing_sim: simulator"


def test_no_samples_are_kept_past_those_held_where_no_timeline_can_be_made(outer, tmp_path, monkeypatch, capsys):
    """The samples past ``MAX_ANALYSIS_S`` go to a temporary file in --out for the timeline's
    windows; a recording that can have no timeline (no scene to take the bearing from and no
    /diagnostics to give the fault frequencies: another tool's) wrote them all the same, 216 MB an
    hour at 15 kHz that nothing read.  It writes none now, and its report is the same; the
    recording with its scene still keeps them."""
    rec, _ = outer
    made = []
    real = report.tempfile.TemporaryFile
    monkeypatch.setattr(report.tempfile, "TemporaryFile", lambda **kw: made.append(kw) or real(**kw))
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 1.0)
    bare = tmp_path / "bare.mcap"
    _copy_without(rec, bare, lambda topic, k: topic == "/diagnostics",
                  metadata=lambda m: {k: v for k, v in m.items() if k not in ("scene_yaml", "scene")})
    s = _report_without_a_verdict(bare, tmp_path / "o", "no verdict: no bearing to place the fault lines on (the "
                                  "recording has no bearing_sim scene) and no fault frequencies in its /diagnostics "
                                  "(cage_hz, bpfo_hz, bpfi_hz, bsf_hz)", capsys)
    assert made == [] and s["analysed_s"] == pytest.approx(1.0) and s["duration_s"] == pytest.approx(2.0)
    assert cli.main(["report", str(rec), "--out", str(tmp_path / "p")]) == 0
    assert len(made) == 1


def test_the_spectrum_shades_the_band_the_envelope_uses_and_says_it_at_1_khz(tmp_path, figures):
    """At a low sample rate the envelope's band-pass is clipped below Nyquist (1 kHz: 225-450 Hz,
    ``envelope.envelope_band``); spectrum.png shaded 2 kHz down to 0.45 x the rate instead (the
    450-500 Hz that were on its axis) and envelope.png's title said "2-5 kHz band".  The summary
    gives the band (``envelope_band_hz``; summary.md under "Fault lines")."""
    rec = tmp_path / "one_khz.mcap"
    render("er16k_outer_race", 1.0, rec, fidelity="kinematic", seed=1, sample_rate=1000.0, progress=False)
    assert cli.main(["report", str(rec), "--out", str(tmp_path / "o")]) == 0
    (ax,) = figures["spectrum.png"].axes
    (band,) = [p for p in ax.patches if p.get_label() == "envelope band"]
    xs = band.get_path().transformed(band.get_patch_transform()).vertices[:, 0] \
        if hasattr(band, "get_patch_transform") else band.get_xy()[:, 0]
    assert (min(xs), max(xs)) == pytest.approx((0.225, 0.45))           # kHz
    assert "(0.225-0.45 kHz band)" in figures["envelope.png"].axes[0].get_title()
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["envelope_band_hz"] == [225.0, 450.0]
    assert "The envelope of accel_y, band-passed to 225-450 Hz." in (tmp_path / "o" / "summary.md").read_text()


def test_plots_of_the_first_part_of_a_long_recording_say_so(outer, tmp_path, monkeypatch, capsys, figures):
    """The waveform, the spectra and the one verdict hold the first ``MAX_ANALYSIS_S`` (120 s) of a
    longer recording; its plots' time axis ended there without a word but summary.md's
    "analysed".  The titles, the command line and summary.json (``analysed_first_only``) say it;
    a recording held whole says nothing of it."""
    rec, _ = outer
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 1.0)
    out = tmp_path / "o"
    assert cli.main(["report", str(rec), "--out", str(out)]) == 0
    said = capsys.readouterr().out.splitlines()
    part = "the first 1.00 s of 2.00 s"
    assert f"{out}: waveform.png, spectrum.png, envelope.png and the one verdict are of {part} (the most the " \
           "report holds in memory); the verdict over time (timeline.png) covers all of it" in said, said
    for name in ("waveform.png", "spectrum.png", "envelope.png"):
        assert part in figures[name].axes[0].get_title(), name
    assert json.loads((out / "summary.json").read_text())["analysed_first_only"] is True
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 120.0)
    assert cli.main(["report", str(rec), "--out", str(tmp_path / "p")]) == 0
    assert "the first" not in capsys.readouterr().out and "the first" not in figures["waveform.png"].axes[0].get_title()


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_a_diagnostics_message_with_non_finite_fault_frequencies_places_no_line(outer, tmp_path, capsys, value):
    """Another writer's ``/diagnostics`` may say ``nan`` (or ``inf``) where a frequency is not
    known.  Taken as a number, one such message made the mean over the recording NaN, every
    window's recorded lines too (``RecordedPeriods``), and the report ended in an IndexError,
    "internal error", exit status 1.  Such a message gives no fault frequencies, as one without
    the keys: the report is that of the other messages."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.serialization import deserialize_message, serialize_message

    rec, _ = outer
    seen = []

    def second_one_not_finite(topic, data):
        if topic != "/diagnostics":
            return data
        msg = deserialize_message(data, DiagnosticArray)
        seen.append(topic)
        if len(seen) == 2:
            for status in msg.status:
                for kv in status.values:
                    if kv.key in report.RECORDED_KEYS:
                        kv.value = value
        return serialize_message(msg)

    odd = tmp_path / "odd.mcap"
    _copy_without(rec, odd, lambda topic, k: False, rewrite=second_one_not_finite)
    assert len(seen) >= 2
    assert cli.main(["report", str(rec), "--out", str(tmp_path / "a")]) == 0
    assert cli.main(["report", str(odd), "--out", str(tmp_path / "b")]) == 0, capsys.readouterr().err
    a, b = (json.loads((tmp_path / k / "summary.json").read_text()) for k in "ab")
    assert b["verdict"] == a["verdict"] == "outer"
    assert all(math.isfinite(v) for v in b["fault_frequencies_hz"].values())
    assert b["fault_frequencies_hz"] == pytest.approx(a["fault_frequencies_hz"], rel=1e-6)
    assert [w["verdict"] for w in b["timeline"]] == [w["verdict"] for w in a["timeline"]]


def test_a_recording_without_a_recorded_sample_rate_is_held_to_the_same_first_part(outer, tmp_path, monkeypatch):
    """Without the ``bearing_sim`` metadata (rewritten by rosbags) there is no ``sample_rate``
    parameter, and the report held every sample of the recording, whatever its length (1.3 GB
    of an hour at 15 kHz), not the first ``MAX_ANALYSIS_S``.  The first two tables' stamps give
    the rate for that now: it holds what the original's report holds, and its timeline, read
    past that part, is the original's."""
    rewritten = _rewritten_by_rosbags(outer[0], tmp_path / "rewritten")
    monkeypatch.setattr(report, "MAX_ANALYSIS_S", 1.0)
    s = build_report(rewritten, tmp_path / "a")
    original = build_report(outer[0], tmp_path / "b")
    assert original["analysed_s"] == pytest.approx(1.0) and s["analysed_s"] == pytest.approx(1.0)
    assert s["analysed_first_only"] and s["sample_rate_hz"] == pytest.approx(15000.0)
    assert [w["verdict"] for w in s["timeline"]] == [w["verdict"] for w in original["timeline"]]
    for mine, theirs in zip(s["timeline"], original["timeline"]):
        assert mine["prominences"] == pytest.approx(theirs["prominences"], rel=1e-6)


def test_the_windows_take_the_scenes_resonator_into_their_band_as_the_whole_does(tmp_path):
    """The 6000-size bearing (``small_bearing``) at 30 000 rpm with an inner-race pit and its
    resonator at 5 kHz: BPFI at 2.21 kHz moves the detector's band up, from 2.70 kHz, and its top
    is 1.25 x the resonator (6.25 kHz), not twice the span (5.39 kHz), which leaves the resonator
    at its edge (``envelope.detector_band``).  The whole recording's analysis gave the band the
    resonator; the verdict timeline's windows did not.  A recording of one window (1 s): that
    window is the whole, so its band and prominences are the whole's."""
    import yaml
    from conftest import small_bearing

    from bearing_sim_ros.scene import scene_from_dict

    scene = small_bearing(30000, 300.0, [{"kind": "inner", "width_mm": 1.0, "depth_mm": 0.1}])
    scene["structure"]["resonator"]["frequency_hz"] = 5000
    assert scene_from_dict(scene).structure.resonator_hz == 5000.0
    path = tmp_path / "fast.yaml"
    path.write_text(yaml.safe_dump(scene))
    rec = tmp_path / "fast.mcap"
    render(str(path), 1.0, rec, fidelity="kinematic", progress=False)
    s = build_report(rec, tmp_path / "out")
    assert s["envelope_band_hz"] == [pytest.approx(2695.6, abs=0.1), 6250.0], s["envelope_band_hz"]
    (window,) = s["timeline"]
    assert window["envelope_band_hz"] == pytest.approx(s["envelope_band_hz"], abs=0.01), window     # (summary rounds)
    whole = {fault: s["fault_lines"][line]["prominence"] for line, fault in (("bpfo", "outer"), ("bpfi", "inner"),
                                                                            ("2bsf", "ball"))}
    assert window["prominences"] == pytest.approx(whole, rel=1e-3), (window["prominences"], whole)


def _with_parameters(parameters_json: str):
    """``_copy_without``'s ``metadata``: the ``bearing_sim`` record's ``parameters`` replaced."""
    return lambda m: dict(m, parameters=parameters_json) if "parameters" in m else m


def _recorded_rate_cases() -> list:
    """Metadata ``parameters`` that give no usable sample rate: a NaN, a negative and an absurd
    ``sample_rate``, and parameters that are not a JSON mapping."""
    return [json.dumps({"sample_rate": math.nan}), json.dumps({"sample_rate": -15000.0}),
            json.dumps({"sample_rate": 1e300}), "[1, 2]", '"fast"']


@pytest.mark.parametrize("parameters", _recorded_rate_cases())
def test_a_recorded_sample_rate_that_is_no_rate_is_taken_from_the_stamps(parameters, outer, tmp_path, capsys):
    """A recording whose metadata's ``sample_rate`` is NaN or negative (a damaged or hand-edited
    file), or whose ``parameters`` are not a mapping, was a traceback and "internal error", exit 1
    (NaN: "cannot convert float NaN to integer"; a list: "'list' object has no attribute 'get'"),
    with an empty --out folder left behind; 1e300 gave a report of "0.00 s" analysed.  Such a
    value is taken as missing, as in another tool's recording: the tables' stamps give the rate,
    and the report is the original's."""
    rec, _ = outer
    odd = tmp_path / "odd.mcap"
    _copy_without(rec, odd, lambda topic, k: False, metadata=_with_parameters(parameters))
    assert cli.main(["report", str(rec), "--out", str(tmp_path / "a")]) == 0
    assert cli.main(["report", str(odd), "--out", str(tmp_path / "b")]) == 0, capsys.readouterr().err
    a, b = (json.loads((tmp_path / k / "summary.json").read_text()) for k in "ab")
    assert b["sample_rate_hz"] == pytest.approx(15000.0) and b["waveform_gaps"] == 0
    assert b["analysed_s"] == pytest.approx(a["analysed_s"]) and b["verdict"] == a["verdict"] == "outer"


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_a_waveform_with_non_finite_samples_is_one_line_not_a_verdict(value, outer, tmp_path, capsys):
    """A recording whose waveform table holds NaN (or infinite) samples (a damaged file, another
    writer's) went through the envelope analysis to a verdict of "healthy", exit status 0
    (infinity with numpy's "invalid value" warning).  It is one line naming the file, the topic,
    the table's log time and how many samples, exit status 2, and no --out folder."""
    from rclpy.serialization import deserialize_message, serialize_message
    from sensor_msgs.msg import PointCloud2

    from bearing_sim_ros.waveform import to_pointcloud2

    rec, _ = outer
    tables = []

    def spoil_the_fifth(topic, data):
        if topic != "/accel":
            return data
        tables.append(topic)
        if len(tables) != 5:
            return data
        msg = deserialize_message(data, PointCloud2)
        stamp, names, arr = from_pointcloud2(msg)
        arr = arr.copy()
        arr[3:6, -1] = value
        return serialize_message(to_pointcloud2(arr, names, stamp, msg.header.frame_id))

    odd = tmp_path / "odd.mcap"
    _copy_without(rec, odd, lambda topic, k: False, rewrite=spoil_the_fifth)
    code = cli.main(["report", str(odd), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"error: {odd}: the table on /accel logged at ") and \
        " s holds 3 non-finite samples (NaN or infinity) of " in err[0], err[0]
    assert not (tmp_path / "o").exists()
