"""``bearing-sim bench``: speed against error (a work-precision study).

For a fixed set of scenarios and for each tier / solver setting, the study measures the
real-time factor on one core (median of repeats, after compilation) and the error against the
``"reference"`` solver on the same scenario, seed and duration.  Sensor noise is switched off
so that the error is the model's and the integrator's, not the dice's.

Error metrics (all relative to the reference; README "Speed against error"):

    rms        |RMS(a) - RMS(a_ref)| / RMS(a_ref) of accel_y
    lines      largest relative difference of the envelope line heights at the scene's fault
               frequencies (scenes with defects only)
    cage       |mean cage speed - reference| / reference
    skid       |cage skid ratio - reference| in percentage points
    waveform   ||a - a_ref|| / ||a_ref|| over the first 20 ms after settling (phase-sensitive:
               a model whose balls slip differently drifts in phase; this is the strictest)
    error      max(rms, lines, cage): the number the plot and the fidelity choice use
"""
from __future__ import annotations

import json
import os
import platform
import statistics as stats
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .analysis.envelope import fault_lines
from .errors import UserError
from .paths import output_folder, replace_file, replaceable_file, save_figure, writing_into
from .scene import RPM, load_scene


@dataclass(frozen=True)
class Scenario:
    label: str
    scene: str
    rpm: float | None = None
    load_n: float | None = None      # downward radial load (N)

    def build(self):
        scene = load_scene(self.scene)
        changes = {"sensor": replace(scene.sensor, noise_density=0.0)}
        if self.rpm is not None:
            changes["shaft_speed"] = self.rpm * RPM
        if self.load_n is not None:
            changes["radial_load"] = (0.0, -float(self.load_n))
        return replace(scene, **changes)


@dataclass(frozen=True)
class Config:
    label: str
    family: str              # "kinematic", "skidding default", "skidding rk4", "reference"
    fidelity: str
    kwargs: tuple = ()       # extra Simulator keyword arguments, as (key, value) pairs

    def simulator(self, scene, sample_rate, seed):
        from .simulator import Simulator

        return Simulator(scene, sample_rate=sample_rate, fidelity=self.fidelity, seed=seed, **dict(self.kwargs))


SCENARIOS = [
    Scenario("ER-16K healthy 1600 rpm 50 N", "er16k_healthy"),
    Scenario("ER-16K inner 1600 rpm 50 N", "er16k_inner_race"),
    Scenario("ER-16K outer 1600 rpm 50 N", "er16k_outer_race"),
    Scenario("ER-16K healthy 2000 rpm 200 N", "er16k_skidding"),
    Scenario("ER-16K healthy 2000 rpm 2000 N", "er16k_skidding", load_n=2000.0),
    Scenario("ER-16K healthy 10000 rpm 10 N", "er16k_skidding", rpm=10000.0, load_n=10.0),
    Scenario("CWRU 6205 outer 1797 rpm", "cwru_6205_or007_6"),
    Scenario("6205 ball+outer 1750 rpm 2000 N", "b6205_ball_outer"),
]
QUICK_SCENARIOS = [SCENARIOS[2], SCENARIOS[3]]

# the kinematic tier as a user gets it (one or two steps per output sample from the bearing mode),
# then at fixed steps per output sample
KINEMATIC_DEFAULT = Config("kinematic default", "kinematic default", "kinematic")
KINEMATIC_STEPS = [Config(f"kinematic x{m}", "kinematic", "kinematic", (("oversample", m),)) for m in (1, 2, 4, 8)]
KINEMATIC = [KINEMATIC_DEFAULT] + KINEMATIC_STEPS
QUICK_KINEMATIC = [KINEMATIC_DEFAULT, KINEMATIC_STEPS[1]]


QUICK_CONFIGS = ("rk4 h=4e-06", "default")     # the skidding settings of ``--quick``


def skidding_configs(quick: bool) -> list:
    """Settings of the skidding tier's solvers: the tier lists them as ``BENCH_CONFIGS``
    [(label, family, kwargs)]; the full study adds the papers' RK4 at 1e-5 s."""
    from .physics.skidding import BENCH_CONFIGS

    listed = list(BENCH_CONFIGS)
    if quick:
        listed = [c for c in listed if c[0] in QUICK_CONFIGS]
    configs = [Config(label, family, "skidding", tuple(kw.items())) for label, family, kw in listed]
    if not quick:   # the papers' method at the papers' step, to show where it stands
        configs.insert(0, Config("rk4 h=1e-05 (seed 000)", "skidding rk4", "skidding",
                                 (("solver", "rk4"), ("rk4_step", 1e-5))))
    return configs


def reference_config() -> Config:
    """The converged solution errors are measured against: the skidding tier's reference."""
    return Config("reference", "reference", "skidding", (("solver", "reference"),))


@dataclass
class Run:
    accel: np.ndarray
    cage_speed: float
    cage_skid: float
    cpu: float               # CPU s of the simulating thread per second of signal (median)
    repeats: list


def _timed_run(cfg: Config, scene, sample_rate: float, settle: float, seconds: float, seed: int = 0):
    """Simulate ``settle + seconds`` and time the ``seconds`` part: (CPU s, the timed batch).
    Timed in CPU time of the calling thread, which does all of the simulator's work: wall time
    counts other work on the machine, and the process's CPU time counts OpenBLAS's worker
    threads, which spin on the other core for a while after the BLAS calls of a model's set-up
    (up to 2x)."""
    sim = cfg.simulator(scene, sample_rate, seed)
    sim.advance(int(settle * sample_rate))
    t0 = time.thread_time()
    batch = sim.advance(int(seconds * sample_rate))
    return time.thread_time() - t0, batch


def _warm_up(cfg: Config, scene, sample_rate: float, seed: int = 0) -> None:
    """Compile (or load from the cache) outside the timing."""
    cfg.simulator(scene, sample_rate, seed).advance(max(1, int(0.002 * sample_rate)))


def _as_run(batch, cpus: list, seconds: float) -> Run:
    skid = batch.extras.get("cage_skid")
    return Run(accel=batch.accel[:, -1].copy(), cage_speed=float(np.mean(batch.cage_speed)),
               cage_skid=float(np.mean(skid)) if skid is not None else 0.0,
               cpu=stats.median(cpus) / seconds, repeats=[c / seconds for c in cpus])


def run_config(cfg: Config, scene, sample_rate: float, settle: float, seconds: float, repeats: int,
               seed: int = 0) -> Run:
    """One setting on one scene, timed ``repeats`` times back to back (see :func:`_timed_run`);
    the real-time factor from the median."""
    _warm_up(cfg, scene, sample_rate, seed)
    cpus, batch = [], None
    for _ in range(repeats):
        cpu, batch = _timed_run(cfg, scene, sample_rate, settle, seconds, seed)
        cpus.append(cpu)
    return _as_run(batch, cpus, seconds)


def run_round_robin(configs: list, scene, sample_rate: float, settle: float, seconds: float,
                    repeats: int, seed: int = 0) -> dict:
    """Every setting on one scene, timed ``repeats`` times in turn (setting 1, 2, ..., then again)
    rather than each ``repeats`` times back to back: a burst of other work on a shared machine
    then slows one repeat of several settings, which the median drops, instead of every repeat of
    one setting.  Returns label -> :class:`Run`, or the one-line reason where a setting failed
    (e.g. RK4 beyond its stability limit)."""
    out, cpus, last = {}, {}, {}
    for cfg in configs:
        try:
            _warm_up(cfg, scene, sample_rate, seed)
            cpus[cfg.label] = []
        except UserError as exc:
            out[cfg.label] = str(exc)
    for _ in range(repeats):
        for cfg in configs:
            if cfg.label not in cpus:
                continue
            try:
                cpu, last[cfg.label] = _timed_run(cfg, scene, sample_rate, settle, seconds, seed)
            except UserError as exc:
                out[cfg.label] = str(exc)
                del cpus[cfg.label]
                continue
            cpus[cfg.label].append(cpu)
    for label, c in cpus.items():
        out[label] = _as_run(last[label], c, seconds)
    return out


def scene_lines(scene) -> list:
    kinds = {d.kind for d in scene.defects}
    return [k for kind, k in (("outer", "bpfo"), ("inner", "bpfi"), ("ball", "2bsf")) if kind in kinds]


def errors(run: Run, ref: Run, scene, sample_rate: float) -> dict:
    a, r = run.accel, ref.accel
    rms_a, rms_r = float(np.sqrt(np.mean(a * a))), float(np.sqrt(np.mean(r * r)))
    ff = scene.bearing.fault_frequencies(scene.shaft_hz)
    if scene.defects:
        la, lr = fault_lines(a, sample_rate, ff), fault_lines(r, sample_rate, ff)
        line_err = max(abs(la[k].height - lr[k].height) / max(lr[k].height, 1e-12) for k in scene_lines(scene))
    else:
        line_err = 0.0      # no fault line to compare: a healthy scene's lines are noise-level
    w = min(a.size, int(0.02 * sample_rate))
    wave = float(np.linalg.norm(a[:w] - r[:w]) / max(np.linalg.norm(r[:w]), 1e-12))
    out = {
        "rms": abs(rms_a - rms_r) / max(rms_r, 1e-12),
        "lines": float(line_err),
        "cage": abs(run.cage_speed - ref.cage_speed) / max(abs(ref.cage_speed), 1e-12),
        "skid": abs(run.cage_skid - ref.cage_skid),
        "waveform": wave,
    }
    out["error"] = max(out["rms"], out["lines"], out["cage"])
    return out


def study(quick: bool = False, sample_rate: float = 15000.0, progress=None) -> dict:
    scenarios = QUICK_SCENARIOS if quick else SCENARIOS
    settle, seconds, repeats = (0.1, 0.4, 1) if quick else (0.2, 0.5, 3)
    configs = QUICK_KINEMATIC if quick else KINEMATIC
    configs = configs + skidding_configs(quick)
    ref_cfg = reference_config()
    rows = []
    for sc in scenarios:
        scene = sc.build()
        ref = run_config(ref_cfg, scene, sample_rate, settle, seconds, 1)
        if progress:
            progress(f"{sc.label}: reference {1 / ref.cpu:.2f}x real time")
        runs = run_round_robin(configs, scene, sample_rate, settle, seconds, repeats)
        for cfg in configs:
            run = runs[cfg.label]
            if isinstance(run, str):          # e.g. RK4 beyond its stability limit
                rows.append({"scenario": sc.label, "config": cfg.label, "family": cfg.family,
                             "diverged": run})
                if progress:
                    progress(f"  {cfg.label:<24} diverged")
                continue
            err = errors(run, ref, scene, sample_rate)
            row = {"scenario": sc.label, "config": cfg.label, "family": cfg.family,
                   "real_time_factor": 1.0 / run.cpu, "rtf_repeats": [1.0 / w for w in run.repeats],
                   **err, "cage_skid": run.cage_skid, "reference_cage_skid": ref.cage_skid,
                   "reference_real_time_factor": 1.0 / ref.cpu}
            rows.append(row)
            if progress:
                progress(f"  {cfg.label:<24} {row['real_time_factor']:8.1f}x  error {row['error']:.2%}")
    return {
        "machine": machine_facts(),
        "sample_rate": sample_rate,
        "seconds": seconds,
        "settle": settle,
        "repeats": repeats,
        "reference": ref_cfg.label,
        "quick": quick,
        "rows": rows,
    }


def machine_facts() -> dict:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import numba

    return {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "numba": numba.__version__, "threads_used": 1}


def markdown(result: dict) -> str:
    m = result["machine"]
    lines = [
        "# Speed against error",
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores (one used), Python {m['python']}, numba {m['numba']}. "
        f"{result['seconds']:g} s of signal at {result['sample_rate']:g} Hz after {result['settle']:g} s of "
        f"settling, median of {result['repeats']} run(s) taken in turn over the settings, in CPU time of the "
        f"simulating thread; errors against "
        f"`{result['reference']}`, sensor noise off.",
        "",
        "| scenario | setting | real-time factor | error | RMS | lines | cage speed | cage skid (pp) | waveform |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in result["rows"]:
        if "diverged" in r:
            lines.append(f"| {r['scenario']} | {r['config']} | diverged | - | - | - | - | - | - |")
            continue
        lines.append(
            f"| {r['scenario']} | {r['config']} | {r['real_time_factor']:.1f}x | {r['error']:.2%} | {r['rms']:.2%} | "
            f"{r['lines']:.2%} | {r['cage']:.2%} | {r['skid']:.2f} | {r['waveform']:.2f} |")
    lines.append("")
    summary = default_against_rk4(result["rows"])
    if summary:
        lines += ["## The default solver against fixed-step RK4", "",
                  "RK4 at equal error: the fastest RK4 row that did not diverge and is at least as accurate "
                  "as the default (RK4 cannot go faster: beyond its stability limit it diverges).", "",
                  "| scenario | default | default error | RK4 at equal error | its error | default ahead by |",
                  "| --- | ---: | ---: | --- | ---: | ---: |"]
        for s in summary:
            rk = f"{s['rk4']} ({s['rk4_rtf']:.2f}x)" if s["rk4"] else "none as accurate"
            ahead = f"{s['ahead']:.1f}x" if s["ahead"] else "-"
            rk_err = f"{s['rk4_error']:.2%}" if s["rk4"] else "-"
            lines.append(f"| {s['scenario']} | {s['rtf']:.1f}x | {s['error']:.2%} | {rk} | {rk_err} | {ahead} |")
        lines.append("")
    return "\n".join(lines)


def default_against_rk4(rows: list) -> list:
    """Per scenario: the default solver's real-time factor and error, and the fastest stable RK4
    row with an error at most the default's (the equal-error comparison of the work-precision
    plot).  RK4 cannot take a step beyond its stability limit, so where every stable RK4 row is
    more accurate than the default the comparison is at that limit."""
    out = []
    for sc in dict.fromkeys(r["scenario"] for r in rows):
        mine = [r for r in rows if r["scenario"] == sc and r["config"] == "default" and "diverged" not in r]
        if not mine:
            continue
        d = mine[0]
        rk = [r for r in rows if r["scenario"] == sc and r["family"] == "skidding rk4" and "diverged" not in r
              and r["error"] <= d["error"]]
        best = max(rk, key=lambda r: r["real_time_factor"]) if rk else None
        out.append({"scenario": sc, "rtf": d["real_time_factor"], "error": d["error"],
                    "rk4": best["config"] if best else None,
                    "rk4_rtf": best["real_time_factor"] if best else None,
                    "rk4_error": best["error"] if best else None,
                    "ahead": d["real_time_factor"] / best["real_time_factor"] if best else None})
    return out


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    result = {**result, "rows": [r for r in result["rows"] if "diverged" not in r]}
    families = sorted({r["family"] for r in result["rows"]})
    markers = dict(zip(families, "osD^v<>"))
    scenarios = sorted({r["scenario"] for r in result["rows"]})
    colors = dict(zip(scenarios, plt.cm.tab10.colors))
    for r in result["rows"]:
        ax.loglog(r["real_time_factor"], max(r["error"], 1e-5), markers[r["family"]],
                  color=colors[r["scenario"]], alpha=0.85)
    for sc in scenarios:
        for fam in families:
            pts = sorted((r["real_time_factor"], max(r["error"], 1e-5)) for r in result["rows"]
                         if r["scenario"] == sc and r["family"] == fam)
            if len(pts) > 1:
                ax.loglog(*zip(*pts), "-", color=colors[sc], alpha=0.4)
    ax.axvline(1.0, color="k", lw=0.8, ls=":")
    ax.axhline(0.01, color="k", lw=0.8, ls=":")
    ax.set_xlabel("real-time factor (x real time, one core)")
    ax.set_ylabel("error against the reference (max of RMS, line heights, cage speed)")
    ax.set_title("Speed against error")
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], marker=markers[f], ls="", color="0.3", label=f) for f in families]
    handles += [Line2D([], [], color=colors[s], label=s) for s in scenarios]
    ax.legend(handles=handles, fontsize=7, loc="best")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)


# operating points of the fidelity calibration: ER-16K from heavy load / low speed (almost pure
# rolling) to light load / high speed (seed 000 Fig. 17 and beyond), plus the CWRU and seed 004
# bearings at their own operating points
CALIBRATION_POINTS = [
    Scenario("ER-16K 600 rpm 2000 N", "er16k_skidding", rpm=600.0, load_n=2000.0),
    Scenario("ER-16K 1000 rpm 2000 N", "er16k_skidding", rpm=1000.0, load_n=2000.0),
    Scenario("ER-16K 2000 rpm 2000 N", "er16k_skidding", rpm=2000.0, load_n=2000.0),
    Scenario("ER-16K 1600 rpm 1000 N", "er16k_skidding", rpm=1600.0, load_n=1000.0),
    Scenario("ER-16K 2000 rpm 200 N", "er16k_skidding"),
    Scenario("ER-16K 3000 rpm 200 N", "er16k_skidding", rpm=3000.0, load_n=200.0),
    Scenario("ER-16K 5000 rpm 200 N", "er16k_skidding", rpm=5000.0, load_n=200.0),
    Scenario("ER-16K 1600 rpm 50 N", "er16k_skidding", rpm=1600.0, load_n=50.0),
    Scenario("ER-16K 10000 rpm 10 N", "er16k_skidding", rpm=10000.0, load_n=10.0),
    Scenario("CWRU 6205 healthy 1797 rpm", "cwru_6205_normal"),
    Scenario("6205 healthy 1750 rpm 2000 N", "b6205_ball_outer"),
]


def calibrate_fidelity(sample_rate: float = 15000.0, settle: float = 0.3, seconds: float = 0.6,
                       progress=None, points=CALIBRATION_POINTS) -> dict:
    """Measure the kinematic tier's error against the skidding reference over ``points`` and fit
    the fidelity estimate (see fidelity.py) to its cage-speed error, the error that skidding
    causes (every fault frequency moves with the cage).  Defects are removed: the estimate is
    about skidding, not about a particular defect.  RMS and line-height differences are
    recorded beside it."""
    from .fidelity import clearance_ratio, fit, skid_index

    ref_cfg = reference_config()
    rows = []
    for sc in points:
        scene = replace(sc.build(), defects=())
        ref = run_config(ref_cfg, scene, sample_rate, settle, seconds, 1)
        run = run_config(KINEMATIC_DEFAULT, scene, sample_rate, settle, seconds, 1)
        err = errors(run, ref, scene, sample_rate)
        chi = skid_index(scene, scene.shaft_speed, scene.radial_load)
        rows.append({"scenario": sc.label, "skid_index": chi, "clearance_ratio": clearance_ratio(scene),
                     "cage": err["cage"], "rms": err["rms"],
                     "lines": err["lines"], "error": err["error"], "reference_cage_skid": ref.cage_skid})
        if progress:
            progress(f"{sc.label:<32} chi {chi:9.3g}  kinematic cage-speed error {err['cage']:.3%} "
                     f"(rms {err['rms']:.1%}, lines {err['lines']:.1%})")
    # the estimate is of the error skidding causes: the cage speed, hence every fault frequency
    model = fit([(r["skid_index"], r["clearance_ratio"], max(r["cage"], 1e-5)) for r in rows])
    return {**model, "points": rows, "reference": ref_cfg.label, "seconds": seconds,
            "settle": settle, "sample_rate": sample_rate, "machine": machine_facts(),
            "source": "bearing-sim bench --calibrate-fidelity"}


def write_calibration(result: dict, path: Path, where: str = "--calibrate-fidelity") -> None:
    """Write the calibration ``result`` to ``path`` atomically (``paths.replace_file``): the
    simulator reads config/fidelity.yaml, and a write cut short (full disk) must leave the file it
    had, not half of a new one.  A failure is a one-line UserError starting with ``where``."""
    import yaml

    head = ("# Fidelity calibration: the kinematic tier's cage-speed (fault-frequency) error against the\n"
            "# skidding tier's reference, error = floor + scale * skid_index^power (bearing_sim_ros/fidelity.py).\n"
            "# Written by `bearing-sim bench --calibrate-fidelity --out DIR`; do not edit by hand.\n")
    try:
        replace_file(path, head + yaml.safe_dump(json.loads(json.dumps(result)), sort_keys=False))
    except OSError as exc:
        raise UserError(f"{where}: cannot write {str(path)!r} ({exc.strerror or exc.__class__.__name__}); "
                        "the file there is as it was") from None


def bench_command(args) -> int:
    out = output_folder(args.out)
    import sys

    say = lambda msg: print(msg, file=sys.stderr, flush=True)  # noqa: E731
    if getattr(args, "calibrate_fidelity", False):
        from .paths import config_dir

        # before minutes of work (an installed package's config/ may be read-only)
        target = replaceable_file(config_dir() / "fidelity.yaml", "--calibrate-fidelity")
        result = calibrate_fidelity(progress=say)
        copy = out / "fidelity.yaml"
        write_calibration(result, copy, f"--out = {str(out)!r}")    # first: kept if the target fails
        try:
            write_calibration(result, target)
        except UserError as exc:
            raise UserError(f"{exc}; the new calibration is in {str(copy)!r}") from None
        print(f"fit: error = {result['floor']:.4g} + {result['clearance_gain']:.4g} C_r/d "
              f"+ {result['scale']:.4g} chi^{result['power']:.3g} "
              f"(worst point off by x{result['worst_factor']:.2f}); wrote {target}")
        return 0
    result = study(quick=args.quick, progress=say)
    result["default_against_rk4"] = default_against_rk4(result["rows"])
    with writing_into(out):           # after minutes of work: one line, not a traceback
        replace_file(out / "bench.json", json.dumps(result, indent=2))
        replace_file(out / "bench.md", markdown(result))
        plot(result, out / "bench.png")
    print(markdown(result))
    print(f"wrote {out / 'bench.md'}, {out / 'bench.json'}, {out / 'bench.png'}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    import argparse

    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true")
    p.add_argument("--out", default="bench_out")
    raise SystemExit(bench_command(p.parse_args()))
