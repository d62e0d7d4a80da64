"""Cost of the live node: CPU per second of signal, batch compute time, worst lag, overruns.

    python -m bearing_sim_ros.nodes.node_bench --duration 60 --out bench_out/node
    python -m bearing_sim_ros.nodes.node_bench --duration 600 --tiers skidding     # the 10-min aim

For each tier, one after the other on the user's ``ROS_DOMAIN_ID`` (where it is unset, on one of
60-89 each), it starts ``bearing-sim node`` in real time (``fidelity`` forced to the tier,
recording to a temporary MCAP unless ``--no-record``) and ``--subscribers`` subscriber processes
that decode every ``accel`` and ``contact_forces`` table (two by default: the issue's target is
zero overruns over ten minutes with the skidding tier, recording and two subscribers on this
2-core machine).  It reads the node's own figures from ``/diagnostics`` and its CPU time from
``/proc/<pid>/stat`` (all threads: simulation, executor, DDS, MCAP writer) between the third and
the last diagnostics message, so start-up (imports, JIT cache load) is left out.

Figures: ``cpu_per_signal_s`` = CPU seconds the node process used per second of signal (1.0 =
one core fully busy); ``batch_compute`` = time the simulation thread spends on one batch (model,
messages, publishing, recording); ``worst_lag`` = how late the worst batch was published against
the moment of its last sample; ``overruns`` = batches not ready by that moment.  Timing on a
shared machine is noisy: repeat a run before believing a single overrun.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ..stale_dds_ports import clear_before_start
from ..teardown import say_on_stderr

DEFAULT_SCENES = {"kinematic": "er16k_outer_race", "skidding": "er16k_skidding"}


def _cpu_seconds(pid: int) -> float:
    """utime + stime of a process, all threads (Linux /proc)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _tier_available(scene: str, tier: str) -> str:
    """'' if the simulator can run ``scene`` on ``tier``, else the reason."""
    try:
        from .. import Simulator

        Simulator(scene, fidelity=tier).advance(150)
        return ""
    except Exception as exc:  # noqa: BLE001 - reported in the table
        return f"{exc.__class__.__name__}: {exc}".splitlines()[0]


def subscriber_main() -> int:
    """A plain consumer: decode every table, count tables and gaps; JSON on stdout at the end."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from sensor_msgs.msg import PointCloud2

    from ..messages import TOPIC_ACCEL, TOPIC_CONTACT, waveform_qos
    from ..waveform import from_pointcloud2

    counts = {TOPIC_ACCEL: [0, 0, None], TOPIC_CONTACT: [0, 0, None]}   # tables, gaps, next stamp

    def on(topic):
        def cb(msg):
            stamp, _names, data = from_pointcloud2(msg)
            c = counts[topic]
            if c[2] is not None and stamp != c[2]:
                c[1] += 1
            c[0] += 1
            c[2] = stamp + data.shape[0] * 1_000_000_000 // 15000
        return cb

    rclpy.init()
    node = rclpy.create_node("bench_subscriber")
    for topic in counts:
        node.create_subscription(PointCloud2, topic, on(topic), waveform_qos(0.01))
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    print(json.dumps({t: {"tables": c[0], "gaps": c[1]} for t, c in counts.items()}), flush=True)
    return 0


def _users_domain(environ) -> int | None:
    """The ROS domain id that ``ROS_DOMAIN_ID`` gives (README: every terminal of one setup gets
    the same), None where it is unset.  The bench ran on 60-89 by its pid whatever the user set:
    ids the test suite takes too, so a bench beside ``make test`` could meet its nodes."""
    from ..errors import UserError
    from ..stale_dds_ports import domain_id_error

    error = domain_id_error(environ)
    if error:
        raise UserError(error)
    text = environ.get("ROS_DOMAIN_ID", "").strip()
    return int(text) if text else None


def bench_tier(tier: str, scene: str, duration: float, subscribers: int, record: bool, domain: int,
               compute_ahead: float | None = None) -> dict:
    """Run the node on one tier; return its figures."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    tmp = tempfile.mkdtemp(prefix="node_bench_")
    out = os.path.join(tmp, f"{tier}.mcap")
    params = {"scene": scene, "fidelity": tier, "duration": repr(float(duration)),
              "record": out if record else "''"}
    if compute_ahead is not None:
        params["compute_ahead"] = repr(float(compute_ahead))
    cmd = [sys.executable, "-m", "bearing_sim_ros.cli", "node", "--ros-args"]
    for k, v in params.items():
        cmd += ["-p", f"{k}:={v}"]
    # before the subscribers start, which the node's own clearing would come too late for
    clear_before_start(say_on_stderr, env)
    subs = [subprocess.Popen([sys.executable, "-m", "bearing_sim_ros.nodes.node_bench", "--subscriber"],
                             env=env, stdout=subprocess.PIPE, text=True) for _ in range(subscribers)]
    time.sleep(1.0)                   # let the subscribers come up: the node's first tables reach them
    node = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)

    os.environ["ROS_DOMAIN_ID"] = str(domain)
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    lis = rclpy.create_node("bench_listener", context=ctx)
    diags = []
    cpu_marks = []

    def on_diag(msg):
        values = {kv.key: kv.value for st in msg.status for kv in st.values}
        with open("/proc/loadavg") as f:
            values["machine_load_1min"] = f.read().split()[0]   # other users of the machine
        diags.append(values)
        if len(diags) >= 3:
            try:
                cpu_marks.append((float(values["simulated_s"]), _cpu_seconds(node.pid)))
            except (OSError, KeyError, IndexError):
                pass

    lis.create_subscription(DiagnosticArray, "/diagnostics", on_diag, 10)
    from rclpy.executors import SingleThreadedExecutor

    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(lis)
    deadline = time.monotonic() + duration + 60.0
    while node.poll() is None and time.monotonic() < deadline:
        ex.spin_once(timeout_sec=0.2)
    if node.poll() is None:
        node.send_signal(signal.SIGINT)
    node_err = node.communicate(timeout=30)[1]
    ex.shutdown(timeout_sec=1)
    lis.destroy_node()
    ctx.try_shutdown()
    received = []
    for p in subs:
        p.send_signal(signal.SIGINT)
        try:
            text = p.communicate(timeout=20)[0].strip().splitlines()
            received.append(json.loads(text[-1]) if text else {})
        except (subprocess.TimeoutExpired, ValueError):
            p.kill()
            received.append({})

    steady = diags[2:]
    res = {"tier": tier, "scene": scene, "duration_s": duration, "subscribers": subscribers,
           "compute_ahead_s": compute_ahead,
           "recording": record, "exit_status": node.returncode, "diagnostics": len(diags)}
    if node.returncode != 0:
        res["error"] = node_err.strip().splitlines()[-1] if node_err.strip() else "node failed"
    if len(cpu_marks) >= 2:
        (s0, c0), (s1, c1) = cpu_marks[0], cpu_marks[-1]
        res["cpu_per_signal_s"] = (c1 - c0) / (s1 - s0) if s1 > s0 else float("nan")
    if steady:
        last = diags[-1]
        f = lambda key: [float(d[key]) for d in steady if key in d]   # noqa: E731
        res.update({
            "overruns": int(last.get("overruns", 0)),
            "overruns_after_start": int(last.get("overruns", 0)) - int(diags[1].get("overruns", 0)),
            "worst_lag_ms": 1e3 * max(f("lag_s") or [float("nan")]),
            "worst_lag_incl_start_ms": 1e3 * float(last.get("worst_lag_s", "nan")),
            "batch_compute_mean_ms": 1e3 * sum(f("batch_compute_s")) / max(len(f("batch_compute_s")), 1),
            "batch_compute_worst_ms": 1e3 * max(f("batch_compute_worst_s") or [float("nan")]),
            "sim_thread_load": sum(f("sim_thread_load")) / max(len(f("sim_thread_load")), 1),
            "real_time_factor": sum(f("real_time_factor")) / max(len(f("real_time_factor")), 1),
            "recording_dropped": int(last.get("recording_dropped", 0)) if record else None,
            "tier_in_use": last.get("tier"),
            "machine_load_1min_mean": sum(f("machine_load_1min")) / max(len(f("machine_load_1min")), 1),
            "seconds_with_overruns": sum(1 for d in steady if int(d.get("overruns_last_period", 0)) > 0),
        })
    res["per_second"] = [{k: d.get(k) for k in ("simulated_s", "overruns_last_period", "lag_s",
                                                 "batch_compute_worst_s", "machine_load_1min")} for d in diags]
    res["subscriber_tables"] = [r.get("/accel", r.get("accel", {})).get("tables") for r in received]
    res["subscriber_gaps"] = [sum(v.get("gaps", 0) for v in r.values()) for r in received]
    if record and os.path.exists(out):
        res["recording_mb"] = os.path.getsize(out) / 1e6
    shutil.rmtree(tmp, ignore_errors=True)
    return res


def table(results) -> str:
    head = ("| tier | scene | signal s | CPU s per signal s | batch compute mean / worst ms | "
            "worst lag ms (after start / incl.) | overruns (after start / all) | seconds with overruns | RTF | "
            "subscribers' gaps | rec. dropped | machine load (1 min avg) |")
    rows = [head, "|---" * (head.count("|") - 1) + "|"]
    for r in results:
        if "skipped" in r:
            rows.append(f"| {r['tier']} | {r['scene']} | skipped: {r['skipped']} " + "|" * 10)
            continue
        rows.append(
            f"| {r['tier']} | {r['scene']} | {r['duration_s']:g} | {r.get('cpu_per_signal_s', float('nan')):.3f} | "
            f"{r.get('batch_compute_mean_ms', float('nan')):.2f} / {r.get('batch_compute_worst_ms', float('nan')):.1f} | "
            f"{r.get('worst_lag_ms', float('nan')):.1f} / {r.get('worst_lag_incl_start_ms', float('nan')):.1f} | "
            f"{r.get('overruns_after_start', '?')} / {r.get('overruns', '?')} | {r.get('seconds_with_overruns', '?')} | "
            f"{r.get('real_time_factor', float('nan')):.4f} | "
            f"{r.get('subscriber_gaps')} | {r.get('recording_dropped')} | {r.get('machine_load_1min_mean', float('nan')):.2f} |")
    return "\n".join(rows)


def main(argv=None) -> int:
    """The command.  A mistake (a duration that is not a positive number, a misspelt --scene) is
    one line on stderr and exit status 2, as for ``bearing-sim``, before any node starts: a
    negative --duration ran and printed a table of nan, a misspelt scene a table of tiers
    "skipped", both with exit status 0."""
    from ..cli import EXIT_USER, _Parser, _in_range, _nonnegative, _positive
    from ..errors import UserError

    p = _Parser(prog="python -m bearing_sim_ros.nodes.node_bench", description=__doc__.split("\n")[0])
    p.add_argument("--duration", type=_positive(float), default=60.0, help="seconds of real-time signal per tier, > 0")
    p.add_argument("--tiers", nargs="+", default=["kinematic", "skidding"], choices=["kinematic", "skidding"])
    p.add_argument("--scene", default=None, help="one scene for every tier (default: er16k_outer_race / er16k_skidding)")
    p.add_argument("--subscribers", type=_nonnegative(int), default=2)
    p.add_argument("--no-record", action="store_true")
    # the node's compute_ahead parameter's range, so that the node does not refuse it after the start
    p.add_argument("--compute-ahead", type=_in_range(0.0, 2.0, "s"), default=None,
                   help="the node's compute_ahead (s, 0 to 2); default: the node's")
    p.add_argument("--out", default=None, help="folder for node_bench.md and node_bench.json")
    p.add_argument("--subscriber", action="store_true", help=argparse.SUPPRESS)
    try:
        args = p.parse_args(argv)
        if args.scene is not None and not args.subscriber:
            from ..scene import load_scene

            load_scene(args.scene)      # a scene that does not load is a mistake, not a tier to skip
        if args.out and not args.subscriber:
            from ..paths import output_folder

            output_folder(args.out)     # before the minutes of the run, not after them
        domain = _users_domain(os.environ)
    except UserError as exc:
        say_on_stderr(f"error: {exc}")
        return EXIT_USER
    if args.subscriber:
        return subscriber_main()
    results = []
    for k, tier in enumerate(args.tiers):
        scene = args.scene or DEFAULT_SCENES[tier]
        why = _tier_available(scene, tier)
        if why:
            results.append({"tier": tier, "scene": scene, "skipped": why})
            print(f"{tier}: skipped ({why})", flush=True)
            continue
        # one tier after the other, the processes of the one before ended: the user's domain
        # serves them all; without one, each its own, as before
        tier_domain = domain if domain is not None else 60 + os.getpid() % 30 + k
        print(f"{tier}: {scene}, {args.duration:g} s real time, {args.subscribers} subscribers, "
              f"recording {'off' if args.no_record else 'on'}, ROS domain {tier_domain} ...", flush=True)
        results.append(bench_tier(tier, scene, args.duration, args.subscribers, not args.no_record, tier_domain,
                                  args.compute_ahead))
    text = table(results)
    print(text)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "node_bench.md").write_text(text + "\n")
        (out / "node_bench.json").write_text(json.dumps(results, indent=2) + "\n")
        print(f"wrote {out / 'node_bench.md'} and {out / 'node_bench.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
