"""``bearing-sim report`` draws its plots from nothing but the file (the recording's samples, their
spectra and envelope spectrum) and finds the recorded fault; bad inputs end with exit status 2 and
one line."""
from __future__ import annotations

import json

import numpy as np
import pytest

from bearing_sim_ros import cli, load_scene
from bearing_sim_ros.analysis import report
from bearing_sim_ros.analysis.envelope import envelope_spectrum
from bearing_sim_ros.analysis.report import build_report
from bearing_sim_ros.recording.reader import open_recording
from bearing_sim_ros.recording.render import render
from bearing_sim_ros.waveform import NS, from_pointcloud2


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


def test_report_draws_plots_and_finds_the_outer_race_fault(outer, monkeypatch):
    import matplotlib.image as mpimg

    rec, out = outer
    # keep each figure as it is saved: what is drawn on it is checked below, against the recording
    figures = {}
    save = report._save

    def keep_and_save(plt, fig, path):
        figures[path.name] = fig
        return save(plt, fig, path)

    monkeypatch.setattr(report, "_save", keep_and_save)
    code = cli.main(["report", str(rec), "--out", str(out)])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    for name in ("waveform.png", "spectrum.png", "envelope.png", "operating_point.png"):
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


def test_report_of_a_healthy_bearing_says_healthy(tmp_path):
    # (not er16k_healthy: at its clearance and load it rings at BPFO by varying compliance, seed
    # 000 Fig. 9, and the envelope detector calls that "outer"; see test_kinematic.py)
    rec = tmp_path / "healthy.mcap"
    render("cwru_6205_normal", 2.0, rec, fidelity="kinematic", progress=False)
    s = build_report(rec, tmp_path / "out")
    assert s["verdict"] == "healthy" and s["expected_defects"] == []
    assert "agrees with the scene" in (tmp_path / "out" / "summary.md").read_text()


@pytest.mark.parametrize("kind", ["not_mcap", "truncated"])
def test_report_bad_files_exit_2_with_one_line(kind, outer, tmp_path, capsys):
    rec, _ = outer
    bad = tmp_path / "bad.mcap"
    if kind == "not_mcap":
        bad.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(100))
    else:
        data = rec.read_bytes()
        bad.write_bytes(data[: len(data) - 500])
    code = cli.main(["report", str(bad), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert ("not an MCAP file" if kind == "not_mcap" else "truncated") in err[0]


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
