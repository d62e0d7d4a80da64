"""`bearing-sim bench --quick`: the speed-against-error study end to end (table, JSON, plot)."""
import json
import math
import subprocess
from pathlib import Path


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
