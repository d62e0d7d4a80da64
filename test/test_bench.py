"""`bearing-sim bench --quick`: the speed-against-error study end to end (table, JSON, plot)."""
import json
import math
import subprocess
from pathlib import Path

import pytest


def test_quick_bench_writes_table_json_and_plot(tmp_path, bearing_sim_exe):
    out = tmp_path / "bench"
    run = subprocess.run([bearing_sim_exe, "bench", "--quick", "--out", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads((out / "bench.json").read_text())
    rows = [r for r in result["rows"] if "diverged" not in r]
    families = {r["family"] for r in rows}
    assert {"kinematic default", "kinematic", "skidding default"} <= families
    assert result["reference"] == "reference" and result["machine"]["threads_used"] == 1
    for r in rows:
        assert r["real_time_factor"] > 0 and math.isfinite(r["error"])
        assert r["error"] == max(r["rms"], r["lines"], r["cage"])
    # the skidding tier's default solver is close to its own reference; the kinematic tier is
    # faster than the skidding tier on the same scenario
    for scenario in {r["scenario"] for r in rows}:
        kin = max(r["real_time_factor"] for r in rows if r["scenario"] == scenario and r["family"] == "kinematic")
        skid = [r for r in rows if r["scenario"] == scenario and r["family"] == "skidding default"][0]
        assert skid["error"] < 0.05 and kin > skid["real_time_factor"]
    table = (out / "bench.md").read_text()
    assert "| scenario | setting | real-time factor |" in table
    # the equal-error comparison: the fastest stable RK4 row at least as accurate as the default
    summary = result["default_against_rk4"]
    assert {s["scenario"] for s in summary} == {r["scenario"] for r in rows}
    for s in summary:
        rk4 = [r for r in rows if r["scenario"] == s["scenario"] and r["family"] == "skidding rk4"
               and r["error"] <= s["error"]]
        if rk4:
            best = max(rk4, key=lambda r: r["real_time_factor"])
            assert s["rk4"] == best["config"] and math.isclose(s["ahead"], s["rtf"] / best["real_time_factor"])
        else:
            assert s["rk4"] is None and s["ahead"] is None
    assert "## The default solver against fixed-step RK4" in table
    assert (out / "bench.png").stat().st_size > 10_000


def test_bench_bad_out_is_one_line(tmp_path, bearing_sim_exe):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    run = subprocess.run([bearing_sim_exe, "bench", "--quick", "--out", str(blocker / "sub")],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1, run.stderr


def test_round_robin_times_every_setting_in_turn_and_reports_a_divergence(monkeypatch):
    """Each setting gets ``repeats`` timed runs, taken in turn over the settings, with identical
    output; a setting that diverges (RK4 at the papers' 1e-5 s) becomes its one-line reason and
    does not stop the others."""
    import numpy as np

    from bearing_sim_ros import bench
    from bearing_sim_ros.bench import Config, Scenario, run_round_robin

    # a spy on the timed runs: which setting, in which order, and what each produced
    timed = []
    timed_run = bench._timed_run

    def record_timed_run(cfg, *args, **kwargs):
        cpu, batch = timed_run(cfg, *args, **kwargs)
        timed.append((cfg.label, batch.accel[:, -1].copy()))
        return cpu, batch

    monkeypatch.setattr(bench, "_timed_run", record_timed_run)
    scene = Scenario("ER-16K healthy 2000 rpm 200 N", "er16k_skidding").build()
    configs = [Config("kinematic x2", "kinematic", "kinematic", (("oversample", 2),)),
               Config("rk4 h=1e-05", "skidding rk4", "skidding", (("solver", "rk4"), ("rk4_step", 1e-5))),
               Config("default", "skidding default", "skidding")]
    runs = run_round_robin(configs, scene, 15000.0, 0.01, 0.02, 2)
    assert isinstance(runs["rk4 h=1e-05"], str) and "rk4_step" in runs["rk4 h=1e-05"]
    for label in ("kinematic x2", "default"):
        run = runs[label]
        assert len(run.repeats) == 2 and run.cpu > 0 and run.accel.shape == (300,)
    # in turn: setting 1, 2, then again (back to back, a burst of other work on the machine would
    # slow every repeat of one setting); the RK4 setting diverges in its warm-up, never timed
    assert [label for label, _ in timed] == ["kinematic x2", "default", "kinematic x2", "default"]
    # the repeats are the same run (same seed, fresh simulator), and the result is the last of them
    for label in ("kinematic x2", "default"):
        first, again = [accel for lab, accel in timed if lab == label]
        assert np.array_equal(first, again) and np.array_equal(runs[label].accel, again), label


def test_calibrate_fidelity_that_cannot_write_its_file_stops_before_the_work(tmp_path, bearing_sim_exe):
    """``--calibrate-fidelity`` rewrites the package's config/fidelity.yaml after about 4 minutes
    of work, and an unwritable one ended in a traceback then.  A copy of the package whose
    config/fidelity.yaml links to a path under a regular file: one line naming the file and why,
    exit 2, before anything is measured (no progress line), and nothing written to --out."""
    import os
    import shutil

    from bearing_sim_ros.paths import config_dir

    pkg = tmp_path / "pkg"
    source = Path(__file__).resolve().parent.parent / "bearing_sim_ros"
    shutil.copytree(source, pkg / "bearing_sim_ros", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(config_dir(), pkg / "config")
    blocker = tmp_path / "blocker"
    blocker.write_text("x")
    (pkg / "config" / "fidelity.yaml").unlink()
    (pkg / "config" / "fidelity.yaml").symlink_to(blocker / "fidelity.yaml")
    out = tmp_path / "out"
    run = subprocess.run([bearing_sim_exe, "bench", "--calibrate-fidelity", "--out", str(out)],
                         env=dict(os.environ, PYTHONPATH=str(pkg)), capture_output=True, text=True, timeout=60)
    assert run.returncode == 2, run.stderr
    assert run.stderr == (f"error: --calibrate-fidelity: cannot write '{blocker}/fidelity.yaml' "
                          "(Not a directory)\n"), run.stderr
    assert list(out.iterdir()) == [] and blocker.read_text() == "x"


def test_a_calibration_write_cut_short_leaves_the_file_as_it_was(tmp_path):
    """The calibration is written beside its file and moved onto it: a write that fails on the
    way (a file-size limit of 1000 bytes, as a full disk would) is one line naming the file, and
    leaves the file as it was and no temporary file (the simulator reads what is there)."""
    import sys

    target = tmp_path / "fidelity.yaml"
    target.write_text("floor: 0.01\n")
    code = "\n".join([
        "import resource, signal, sys",
        "from pathlib import Path",
        "from bearing_sim_ros.bench import write_calibration",
        "from bearing_sim_ros.errors import UserError",
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)",
        "resource.setrlimit(resource.RLIMIT_FSIZE, (1000, resource.RLIM_INFINITY))",
        "try:",
        "    write_calibration({'floor': 0.02, 'points': [{'chi': k / 7} for k in range(200)]}, Path(sys.argv[1]))",
        "except UserError as exc:",
        "    sys.exit(f'error: {exc}')",
    ])
    run = subprocess.run([sys.executable, "-c", code, str(target)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 1, run.stderr
    assert run.stderr == (f"error: --calibrate-fidelity: cannot write '{target}' (File too large); "
                          "the file there is as it was\n"), run.stderr
    assert target.read_text() == "floor: 0.01\n"
    assert [p.name for p in tmp_path.iterdir()] == ["fidelity.yaml"]


# ---- the error metrics and the table, on runs made up here (no simulation) -------------------
def _run(accel, cage_speed=50.0, cage_skid=0.0, cpu=0.5, repeats=(0.5,)):
    import numpy as np

    from bearing_sim_ros.bench import Run

    return Run(accel=np.asarray(accel, dtype=float), cage_speed=cage_speed, cage_skid=cage_skid,
               cpu=cpu, repeats=list(repeats))


def test_the_error_metrics_are_relative_to_the_reference():
    """Each metric of the README's table is the run's difference from the reference over the
    reference's value (not over the run's): a run 1.25 x the reference's amplitude is 25 % off in
    RMS and in waveform (20 % if divided by the run's); a cage 1.4 x as fast is 40 % off; the skid
    is the difference in percentage points; the error is the largest of RMS, lines and cage."""
    import numpy as np

    from bearing_sim_ros.bench import Scenario, errors

    fs = 15000.0
    scene = Scenario("healthy", "er16k_healthy").build()
    t = np.arange(int(0.4 * fs)) / fs
    ref_accel = np.sin(2 * np.pi * 1000.0 * t)
    ref = _run(ref_accel, cage_speed=50.0, cage_skid=5.0)
    err = errors(_run(1.25 * ref_accel, cage_speed=60.0, cage_skid=3.0), ref, scene, fs)
    assert err["rms"] == pytest.approx(0.25, rel=1e-9)
    assert err["waveform"] == pytest.approx(0.25, rel=1e-9)
    assert err["cage"] == pytest.approx(0.2, rel=1e-12)
    assert err["skid"] == pytest.approx(2.0, rel=1e-12)
    assert err["lines"] == 0.0                      # a healthy scene: no fault line to compare
    assert err["error"] == pytest.approx(0.25, rel=1e-9)
    faster = errors(_run(1.25 * ref_accel, cage_speed=70.0, cage_skid=8.0), ref, scene, fs)
    assert faster["cage"] == pytest.approx(0.4, rel=1e-12) and faster["error"] == pytest.approx(0.4, rel=1e-12)
    assert faster["skid"] == pytest.approx(3.0, rel=1e-12)
    # a cage turning the other way (a reversed shaft) is compared by magnitude of the reference
    backwards = errors(_run(ref_accel, cage_speed=-60.0), _run(ref_accel, cage_speed=-50.0), scene, fs)
    assert backwards["cage"] == pytest.approx(0.2, rel=1e-12) and backwards["rms"] == 0.0


def test_the_waveform_error_covers_exactly_the_first_20_ms():
    """The waveform metric is over the first 20 ms (300 samples at 15 kHz): a difference from
    sample 300 on does not count, one in sample 299 does, and its size is the norm of the
    difference over the norm of the reference's 300 samples."""
    import numpy as np

    from bearing_sim_ros.bench import Scenario, errors

    fs = 15000.0
    scene = Scenario("healthy", "er16k_healthy").build()
    ref_accel = np.ones(int(0.4 * fs))
    later = ref_accel.copy()
    later[300:] *= 3.0
    assert errors(_run(later), _run(ref_accel), scene, fs)["waveform"] == 0.0
    last = ref_accel.copy()
    last[299] += 6.0
    assert errors(_run(last), _run(ref_accel), scene, fs)["waveform"] == pytest.approx(6.0 / np.sqrt(300.0), rel=1e-12)


def test_the_line_error_is_the_worst_of_the_scenes_own_fault_lines(monkeypatch):
    """The line metric compares the envelope lines at the scene's fault frequencies, Hz at the
    scene's shaft speed (BPFO = n/2 f_r (1 - d cos(alpha)/D), computed here from the geometry),
    only for the defects the scene has (outer and ball: BPFO and 2 x BSF, not BPFI), and takes
    the largest relative difference (over the reference's height)."""
    import math as m

    import numpy as np

    from bearing_sim_ros import bench
    from bearing_sim_ros.analysis.envelope import Line
    from bearing_sim_ros.bench import Scenario, errors, scene_lines

    scene = Scenario("6205 ball+outer", "b6205_ball_outer").build()
    assert scene_lines(scene) == ["bpfo", "2bsf"]
    assert scene_lines(Scenario("inner", "er16k_inner_race").build()) == ["bpfi"]
    assert scene_lines(Scenario("outer", "er16k_outer_race").build()) == ["bpfo"]
    assert scene_lines(Scenario("healthy", "er16k_healthy").build()) == []
    heights = {"ref": {"bpfo": 1.0, "2bsf": 2.0, "bpfi": 5.0, "ftf": 1.0},
               "run": {"bpfo": 1.5, "2bsf": 2.2, "bpfi": 50.0, "ftf": 9.0}}
    asked = []

    def fake_fault_lines(x, fs, ff):
        asked.append(ff)
        which = "ref" if x[0] == 0.0 else "run"
        return {k: Line(expected_hz=0.0, found_hz=0.0, height=h, prominence=1.0) for k, h in heights[which].items()}

    monkeypatch.setattr(bench, "fault_lines", fake_fault_lines)
    fs = 15000.0
    ref_accel = np.zeros(6000)
    err = errors(_run(ref_accel + 1.0), _run(ref_accel), scene, fs)
    assert err["lines"] == pytest.approx(0.5, rel=1e-12)
    b = scene.bearing
    f_r = scene.shaft_speed / (2 * m.pi)
    bpfo = 0.5 * b.balls * f_r * (1 - b.ball_diameter * m.cos(b.contact_angle) / b.pitch_diameter)
    assert all(ff["bpfo"] == pytest.approx(bpfo, rel=1e-12) for ff in asked) and len(asked) == 2


def test_a_run_is_the_vertical_channel_the_mean_speeds_and_the_median_of_its_repeats():
    """A timed run keeps the last accelerometer channel (accel_y), the mean cage speed and skid
    over the batch, and the CPU seconds per second of signal of each repeat, the median for the
    real-time factor (not the mean: one repeat slowed by other work must not move it)."""
    from types import SimpleNamespace

    import numpy as np

    from bearing_sim_ros.bench import _as_run

    accel = np.column_stack([np.zeros(4), np.arange(4.0)])
    batch = SimpleNamespace(accel=accel, cage_speed=np.array([1.0, 2.0, 3.0, 10.0]),
                            extras={"cage_skid": np.array([0.0, 4.0])})
    run = _as_run(batch, [1.0, 9.0, 2.0], seconds=0.5)
    assert np.array_equal(run.accel, np.arange(4.0))
    assert run.cage_speed == 4.0 and run.cage_skid == 2.0
    assert run.cpu == 4.0 and run.repeats == [2.0, 18.0, 4.0]
    no_skid = _as_run(SimpleNamespace(accel=accel, cage_speed=np.ones(4), extras={}), [1.0], seconds=1.0)
    assert no_skid.cage_skid == 0.0


def test_the_study_reports_real_time_factors_as_the_inverse_of_the_cpu_per_second(monkeypatch):
    """A row's real-time factor is seconds of signal per CPU second (1 / cpu), for the setting
    and its repeats and for the reference; its errors are those of :func:`errors` against the
    reference of the same scenario."""
    import numpy as np

    from bearing_sim_ros import bench

    t = np.arange(6000) / 15000.0
    ref_accel = np.sin(2 * np.pi * 1000.0 * t)
    ref = _run(ref_accel, cage_speed=50.0, cage_skid=1.0, cpu=4.0, repeats=(4.0,))
    mine = _run(1.1 * ref_accel, cage_speed=55.0, cage_skid=1.5, cpu=0.25, repeats=(0.25, 0.5))
    healthy = bench.Scenario("healthy", "er16k_healthy")
    monkeypatch.setattr(bench, "QUICK_SCENARIOS", [healthy])
    monkeypatch.setattr(bench, "QUICK_KINEMATIC", [bench.KINEMATIC_DEFAULT])
    monkeypatch.setattr(bench, "skidding_configs", lambda quick: [])
    monkeypatch.setattr(bench, "run_config", lambda *a, **k: ref)
    monkeypatch.setattr(bench, "run_round_robin", lambda configs, *a, **k: {c.label: mine for c in configs})
    result = bench.study(quick=True)
    (row,) = result["rows"]
    assert row["real_time_factor"] == 4.0 and row["rtf_repeats"] == [4.0, 2.0]
    assert row["reference_real_time_factor"] == 0.25
    assert row["cage_skid"] == 1.5 and row["reference_cage_skid"] == 1.0
    assert row["rms"] == pytest.approx(0.1, rel=1e-9) and row["cage"] == pytest.approx(0.1, rel=1e-12)
    assert row["error"] == pytest.approx(0.1, rel=1e-9)


def _row(scenario, config, family, rtf, error):
    return {"scenario": scenario, "config": config, "family": family, "real_time_factor": rtf, "error": error,
            "rms": error, "lines": 0.0, "cage": 0.0, "skid": 0.0, "waveform": 0.0}


def test_the_default_is_set_against_the_fastest_rk4_at_least_as_accurate():
    """Per scenario, the RK4 row compared with the default is the fastest of those whose error is
    at most the default's (equal counts), diverged rows and other families left out; "ahead" is
    the default's real-time factor over that row's."""
    rows = [_row("A", "default", "skidding default", 10.0, 0.02),
            _row("A", "rk4 fast", "skidding rk4", 8.0, 0.03),        # faster but less accurate
            _row("A", "rk4 equal", "skidding rk4", 5.0, 0.02),       # as accurate: counts
            _row("A", "rk4 slow", "skidding rk4", 2.0, 0.001),
            _row("A", "kinematic x8", "kinematic", 100.0, 0.0),      # not RK4
            {"scenario": "A", "config": "rk4 h=1e-05", "family": "skidding rk4", "diverged": "rk4_step"},
            _row("B", "default", "skidding default", 3.0, 0.001),
            _row("B", "rk4 only", "skidding rk4", 6.0, 0.01)]
    from bearing_sim_ros.bench import default_against_rk4

    a, b = default_against_rk4(rows)
    assert (a["scenario"], a["rk4"], a["rk4_rtf"], a["rk4_error"]) == ("A", "rk4 equal", 5.0, 0.02)
    assert a["ahead"] == pytest.approx(2.0) and (a["rtf"], a["error"]) == (10.0, 0.02)
    assert (b["scenario"], b["rk4"], b["ahead"]) == ("B", None, None)


def test_the_table_puts_each_number_in_its_column():
    """A row of bench.md reads: real-time factor, error, RMS, lines, cage speed (percent), cage
    skid (percentage points, not percent) and waveform (a ratio), in the header's order."""
    from bearing_sim_ros.bench import markdown

    row = {"scenario": "S", "config": "default", "family": "skidding default", "real_time_factor": 12.34,
           "error": 0.0456, "rms": 0.0123, "lines": 0.0456, "cage": 0.0078, "skid": 0.25, "waveform": 0.5}
    result = {"machine": {"cpu": "x", "cores": 2, "python": "3", "numba": "0"}, "seconds": 0.5,
              "sample_rate": 15000.0, "settle": 0.2, "repeats": 3, "reference": "reference",
              "rows": [row, {"scenario": "S", "config": "rk4", "family": "skidding rk4", "diverged": "why"}]}
    text = markdown(result)
    assert "| S | default | 12.3x | 4.56% | 1.23% | 4.56% | 0.78% | 0.25 | 0.50 |" in text
    assert "| S | rk4 | diverged | - | - | - | - | - | - |" in text
    assert "median of 3 run(s)" in text and "0.5 s of signal at 15000 Hz after 0.2 s" in text


def test_a_scenario_turns_noise_off_and_sets_speed_in_rpm_and_a_downward_load():
    """A scenario's scene has no sensor noise (the error is the model's, not the dice's), its
    ``rpm`` as a shaft speed in rad/s (2 pi / 60 per rpm) and its ``load_n`` pointing down (-y)."""
    import math as m

    from bearing_sim_ros.bench import Scenario

    scene = Scenario("fast", "er16k_skidding", rpm=10000.0, load_n=10.0).build()
    assert scene.sensor.noise_density == 0.0
    assert scene.shaft_speed == pytest.approx(10000.0 * 2 * m.pi / 60, rel=1e-12)
    assert tuple(scene.radial_load) == (0.0, -10.0)


def test_only_the_seconds_after_settling_are_timed(monkeypatch):
    """The CPU time of a run is that of its ``seconds`` of signal, not of the settling before
    (a clock made up here advances 1 ms per simulated sample)."""
    from types import SimpleNamespace

    from bearing_sim_ros import bench

    clock = [0.0]

    class Sim:
        def advance(self, n):
            clock[0] += 1e-3 * n
            return SimpleNamespace(samples=n)

    monkeypatch.setattr(bench.time, "thread_time", lambda: clock[0])
    cfg = SimpleNamespace(simulator=lambda scene, sample_rate, seed: Sim())
    cpu, batch = bench._timed_run(cfg, None, 1000.0, settle=0.2, seconds=0.5)
    assert batch.samples == 500 and cpu == pytest.approx(0.5)


def test_the_quick_study_runs_the_quick_skidding_settings_and_the_full_one_adds_the_papers_rk4():
    """``--quick`` runs the skidding tier's settings named in QUICK_CONFIGS (whatever their place
    in the tier's list); the full study runs them all, with RK4 at the papers' 1e-5 s first."""
    from bearing_sim_ros.bench import QUICK_CONFIGS, skidding_configs
    from bearing_sim_ros.physics.skidding import BENCH_CONFIGS

    assert sorted(c.label for c in skidding_configs(quick=True)) == sorted(QUICK_CONFIGS)
    full = skidding_configs(quick=False)
    assert [c.label for c in full[1:]] == [label for label, _, _ in BENCH_CONFIGS]
    assert full[0].family == "skidding rk4" and dict(full[0].kwargs) == {"solver": "rk4", "rk4_step": 1e-5}
