"""`bearing-sim bench --quick`: the speed-against-error study end to end (table, JSON, plot)."""
import json
import math
import subprocess


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
