"""``bearing-sim report`` draws its plots from nothing but the file and finds the recorded fault;
bad inputs end with exit status 2 and one line."""
from __future__ import annotations

import json

import pytest

from bearing_sim_ros import cli, load_scene
from bearing_sim_ros.analysis.report import build_report
from bearing_sim_ros.recording.render import render


@pytest.fixture(scope="module")
def outer(tmp_path_factory):
    d = tmp_path_factory.mktemp("report")
    rec = d / "outer.mcap"
    render("er16k_outer_race", 2.0, rec, fidelity="kinematic", seed=1, progress=False)
    return rec, d / "out"


def test_report_draws_plots_and_finds_the_outer_race_fault(outer):
    import matplotlib.image as mpimg

    rec, out = outer
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
    md = (out / "summary.md").read_text()
    assert "OUTER" in md and "![envelope.png](envelope.png)" in md and "| BPFO | 95.25 |" in md


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
