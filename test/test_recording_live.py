"""A recording made by the live node and stopped by SIGINT or SIGTERM is finalised and readable
(by the mcap reader and by rosbags), with the metadata record and contiguous waveform tables;
one killed hard (SIGKILL) is read up to its last complete chunk."""
from __future__ import annotations

import json
import signal
import subprocess

import numpy as np
import pytest
from test_node_support import FIRST_TABLE_S, Listener, read_recording, signal_when

from bearing_sim_ros.recording.reader import open_recording
from bearing_sim_ros.waveform import NS, from_pointcloud2


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_live_recording_stopped_by_a_signal_is_readable(sig, bearing_sim_exe, ros_env, tmp_path):
    from rclpy.serialization import deserialize_message
    from rosbags.highlevel import AnyReader
    from sensor_msgs.msg import PointCloud2

    out = tmp_path / "live.mcap"
    proc = subprocess.Popen([bearing_sim_exe, "node", "--ros-args", "-p", "scene:=er16k_outer_race",
                             "-p", "fidelity:=kinematic", "-p", f"record:={out}"],
                            env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    log, _ = signal_when(proc, lambda: out.exists() and out.stat().st_size > 200_000, sig, 0.5,
                         "the node never started recording")
    assert proc.returncode == 0, log
    with open_recording(out) as rec:                 # footer and summary present
        assert rec.metadata["scene"] == "er16k_outer_race"
        assert rec.metadata["tier"] == "kinematic"
        tables = [from_pointcloud2(deserialize_message(d, PointCloud2)) for _, _, _, d in rec.messages(["/accel"])]
    assert len(tables) >= 20
    stamps = np.array([t[0] for t in tables])
    widths = np.array([t[2].shape[0] for t in tables])
    assert np.all(np.abs(np.diff(stamps) - widths[:-1] * NS / 15000.0) <= 1)
    with AnyReader([out]) as reader:
        n = sum(1 for c, t, raw in reader.messages() if reader.deserialize(raw, c.msgtype) is not None)
    assert n > len(tables)


def test_a_remapped_and_namespaced_node_records_its_topics_under_their_names(bearing_sim_exe, ros_env, tmp_path):
    """``-r accel:=vibration -r __ns:=/rig1`` with ``record``: the node starts (it looked a
    recorded topic's type up by its name's last segment, and a remap made that a KeyError and an
    empty file), records every topic under its resolved name with its type, names each topic's
    role in the metadata, and the report finds the waveform on the remapped topic."""
    from rosbags.highlevel import AnyReader

    from bearing_sim_ros.analysis.report import build_report

    out = tmp_path / "remapped.mcap"
    proc = subprocess.run([bearing_sim_exe, "node", "--ros-args", "-r", "accel:=vibration", "-r", "__ns:=/rig1",
                           "-p", "scene:=er16k_outer_race", "-p", "fidelity:=kinematic", "-p", "duration:=2.0",
                           "-p", "real_time:=false", "-p", f"record:={out}"],
                          env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout
    with AnyReader([out]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert types == {"/rig1/vibration": "sensor_msgs/msg/PointCloud2",
                     "/rig1/contact_forces": "sensor_msgs/msg/PointCloud2",
                     "/rig1/state": "sensor_msgs/msg/JointState", "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
                     "/rig1/shaft_speed": "std_msgs/msg/Float64", "/rig1/load": "geometry_msgs/msg/WrenchStamped"}
    assert counts["/rig1/vibration"] == 200
    with open_recording(out) as rec:
        roles = json.loads(rec.metadata["topics"])     # each role -> the channel it is recorded on
    assert roles == {"accel": "/rig1/vibration", "contact_forces": "/rig1/contact_forces", "state": "/rig1/state",
                     "diagnostics": "/diagnostics", "shaft_speed": "/rig1/shaft_speed", "load": "/rig1/load"}
    # its status says which node it is: nodes in several namespaces share the one /diagnostics
    with AnyReader([out]) as reader:
        conn = next(c for c in reader.connections if c.topic == "/diagnostics")
        status = reader.deserialize(next(reader.messages([conn]))[2], conn.msgtype).status[0]
    assert (status.name, status.hardware_id) == ("rig1/bearing_sim: simulator", "rig1/bearing_sim")
    summary = build_report(out, tmp_path / "report")
    assert summary["analysed_s"] == pytest.approx(2.0) and summary["verdict"] == "outer"
    # the length is the signal's (was the log times' span, 1.99 s: the first table is logged when
    # its 10 ms batch is complete)
    assert summary["duration_s"] == pytest.approx(2.0, abs=1e-6)
    assert summary["log_time_span_s"] == pytest.approx(1.99, abs=0.005)


def test_a_recording_that_fails_on_the_way_is_logged_then_and_ends_with_status_2(bearing_sim_exe, ros_env, tmp_path):
    """A file-size limit of 300 kB (RLIMIT_FSIZE, SIGXFSZ ignored: writes past it fail with
    EFBIG, as on a full disk) stops the recording after about a second of a 3 s run: the node
    logs it when it happens, publishes on to the end, says it again at exit (once: the end of the
    run's line repeated it before) and ends with status 2 and one error line, so that a script
    that checks the status knows the file is short."""
    import resource

    def limit_file_size():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (300_000, 300_000))

    out = tmp_path / "short.mcap"
    args = [bearing_sim_exe, "node", "--ros-args", "-p", "scene:=er16k_outer_race", "-p", "fidelity:=kinematic",
            "-p", "real_time:=false"]
    # the same node once without the limit: on a cold cache numba writes its compiled kernels, and
    # under the limit those writes would fail instead of the recording's
    warm = subprocess.run([*args, "-p", "duration:=0.1"], env=ros_env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=300)
    assert warm.returncode == 0, warm.stdout
    # in real time, so that the node runs on for seconds after the file fills (as fast as
    # possible, 4 s of signal take 0.1 s: the writer thread's error may come after the last batch)
    proc = subprocess.run([*args[:-2], "-p", "duration:=3.0", "-p", f"record:={out}"], env=ros_env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120,
                          preexec_fn=limit_file_size)
    log = proc.stdout
    assert proc.returncode == 2, log
    lines = log.splitlines()
    failed = [i for i, line in enumerate(lines) if "recording failed, publishing goes on" in line]
    at_exit = [i for i, line in enumerate(lines) if "] [bearing_sim]: recording: " in line]
    assert len(failed) == 1 and "File too large" in lines[failed[0]], log
    assert len(at_exit) == 1 and failed[0] < at_exit[0], log     # said when it happened, then at exit
    # and only there: the end's line, just before the one at exit, said it too, at ERROR level;
    # it gives the rest of the status now, at its level (INFO, or WARN for an overrun)
    said = [line for line in lines if line.startswith("[") and "File too large" in line]
    assert len(said) == 2, log
    ended = [line for line in lines if "]: run ended: duration 3 s reached" in line]
    assert len(ended) == 1 and not ended[0].startswith("[ERROR]"), log
    assert lines[-1] == f"error: recording to {out} stopped: OSError: [Errno 27] File too large", log
    assert 100_000 < out.stat().st_size <= 300_000


@pytest.mark.parametrize("gone, sig", [("file", signal.SIGTERM), ("folder", signal.SIGINT)])
def test_a_recording_whose_file_is_deleted_while_the_node_runs_is_an_error(gone, sig, bearing_sim_exe, ros_env,
                                                                          tmp_path):
    """``record:=only.mcap`` (in the working folder) with the file deleted, or ``record:=runs/run.mcap``
    with the folder deleted, while the node runs: writes into a deleted file all succeed, and the
    node said ``recording ...: 2660 messages, ... 0.0 MB on disk (zstd), 0 dropped`` and exited 0
    with no file anywhere.  It is the failure a full disk is: ``/diagnostics`` says ``recording:
    error`` (level ERROR) while the node runs, the log says so once when it happens and again at
    exit (no line of success), and after the signal the node exits with status 2 and one error
    line naming the path and what happened."""
    import shutil
    import time

    if gone == "file":
        record, out = "only.mcap", tmp_path / "only.mcap"
        why = "the file was deleted"
    else:
        (tmp_path / "runs").mkdir()
        record = out = tmp_path / "runs" / "run.mcap"
        why = f"its folder {out.parent} was deleted"
    error = f"recording to {record} stopped: {why} while it was written"
    listener = Listener()
    removed = []

    def deleted_and_said():
        if not removed:
            if out.exists() and out.stat().st_size > 200_000:
                removed.append(time.monotonic())
                if gone == "file":
                    out.unlink()
                else:
                    shutil.rmtree(out.parent)
            return False
        return [d for d in list(listener.diagnostics) if d[0] > removed[0] and d[3]["recording"] == "error"]

    try:
        proc = subprocess.Popen([bearing_sim_exe, "node", "--ros-args", "-p", "scene:=er16k_outer_race",
                                 "-p", "fidelity:=kinematic", "-p", f"record:={record}"], cwd=tmp_path,
                                env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        log, _ = signal_when(proc, deleted_and_said, sig, 0.0,
                             "the node never recorded, or /diagnostics never said the recording failed",
                             timeout_s=FIRST_TABLE_S)
        said = deleted_and_said()
    finally:
        listener.close()
    _t, level, message, values, _stamp = said[0]
    # the failure first; overruns of a loaded machine may follow it
    assert level == 2 and message.split("; ")[0] == f"recording failed: {error}", said[0]
    assert values["recording_error"] == error, said[0]
    assert proc.returncode == 2, log
    lines = log.splitlines()
    assert [line.split("]: ", 1)[1] for line in lines if "] [bearing_sim]: recording" in line] == [
        f"recording failed, publishing goes on: {error}", f"recording: {error}"], log
    assert lines[-1] == f"error: {error}", log
    assert not out.exists()


def test_messages_the_live_node_drops_are_counted_in_diagnostics_and_at_exit(ros_env, tmp_path):
    """The node's recorder drops (and counts) what the disk cannot take, so that no batch waits for
    it.  With a queue limit of 0 bytes (set before the node starts) every batch's burst of writes
    finds the writer thread behind: each /diagnostics says how many were dropped in its second, as
    a warning, and the line at exit says how many in all and that the file has gaps; the count
    is exactly what the file lacks."""
    import sys

    out = tmp_path / "gaps.mcap"
    script = tmp_path / "no_queue.py"
    script.write_text("\n".join([
        "import sys",
        "from bearing_sim_ros.recording import recorder",
        "recorder.MAX_QUEUE_BYTES = 0          # a disk that never keeps up",
        "from bearing_sim_ros.nodes.bearing_sim_node import main",
        "sys.exit(main(sys.argv[1:]))",
        ""]))
    listener = Listener()
    try:
        r = subprocess.run([sys.executable, str(script), "--ros-args", "-p", "scene:=er16k_outer_race",
                            "-p", "fidelity:=kinematic", "-p", "duration:=3.0", "-p", f"record:={out}"],
                           env=ros_env, capture_output=True, text=True, timeout=120)
        diagnostics = list(listener.diagnostics)
    finally:
        listener.close()
    assert r.returncode == 0, r.stderr
    assert diagnostics, r.stderr
    for _t, level, message, values, _stamp in diagnostics:
        assert int(values["recording_dropped"]) > 0 and values["recording"] == "ok", values
        assert level == 1 and "recording dropped " in message and "in the last second" in message, message
    (exit_line,) = [line for line in r.stderr.splitlines() if "] [bearing_sim]: recording " in line]
    assert "[WARN]" in exit_line and exit_line.endswith("dropped: the disk did not keep up, the file has gaps")
    topics, _meta = read_recording(out)
    kept = sum(len(v) for v in topics.values())
    written = 300 * 4 + 150 + 3        # 300 batches: speed, load, accel, contact; state at 50 Hz; diagnostics
    assert f" {kept} messages, " in exit_line and f", {written - kept} dropped:" in exit_line, exit_line


def _split_node(bearing_sim_exe, out, duration: float | None, **params):
    """``bearing-sim node`` on er16k_outer_race, as fast as possible, recording to ``out`` in
    files of 0.5 s of recording (a subprocess; ``duration`` None = until stopped)."""
    args = [bearing_sim_exe, "node", "--ros-args", "-p", "scene:=er16k_outer_race", "-p", "fidelity:=kinematic",
            "-p", "real_time:=false", "-p", f"record:={out}", "-p", "record_max_duration:=0.5"]
    if duration is not None:
        args += ["-p", f"duration:={duration}"]
    for key, value in params.items():
        args += ["-p", f"{key}:={value}"]
    return args


def _accel_tables(path):
    """[(stamp ns, width)] of ``/accel`` in one file, read with ``rosbags`` (an independent reader),
    and {topic: messages} of every topic, each message deserialised."""
    from rosbags.highlevel import AnyReader

    tables, counts = [], {}
    with AnyReader([path]) as reader:
        for conn, _t, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
            if conn.topic == "/accel":
                tables.append((msg.header.stamp.sec * NS + msg.header.stamp.nanosec, msg.width))
    return tables, counts


def _assert_contiguous(tables) -> None:
    stamps = np.array([s for s, _w in tables], dtype=np.int64)
    widths = np.array([w for _s, w in tables], dtype=np.int64)
    assert np.all(np.diff(stamps) == widths[:-1] * NS // 15000), np.diff(stamps)[:10]


def test_a_split_live_recording_is_complete_files_that_continue_each_other(bearing_sim_exe, ros_env, tmp_path):
    """``record_max_duration:=0.5`` on a 2 s run: run_000.mcap .. run_003.mcap and nothing else,
    each complete on its own (footer and summary for the mcap reader; rosbags reads every
    message), each with the metadata that reproduces the run, the scene attached and every
    topic's channel and schema, whole batches; together their /accel tables continue each other
    to the nanosecond, 30000 samples, none lost or twice at the seams.  ``report`` reads one
    piece alone."""
    from bearing_sim_ros.analysis.report import build_report
    from bearing_sim_ros.scene import load_scene

    out = tmp_path / "run.mcap"
    proc = subprocess.run(_split_node(bearing_sim_exe, out, 2.0), env=ros_env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout
    pieces = [tmp_path / f"run_{k:03d}.mcap" for k in range(4)]
    assert sorted(tmp_path.iterdir()) == pieces, proc.stdout
    assert f"recording {pieces[0]} .. {pieces[-1]}, 4 files: " in proc.stdout, proc.stdout
    tables = []
    for k, piece in enumerate(pieces):
        with open_recording(piece) as rec:                       # footer and summary present
            meta, attachments, topics = rec.metadata, rec.attachments, rec.topics()
        assert meta["file_index"] == str(k) and meta["scene"] == "er16k_outer_race"
        assert json.loads(meta["parameters"])["record_max_duration"] == 0.5
        assert "-p record_max_duration:=0.5" in json.loads(meta["parameters"])["command"]
        assert attachments == {"er16k_outer_race.yaml": load_scene("er16k_outer_race").source_text.encode()}
        assert {t: c.msg_type for t, c in topics.items()} == {
            "/accel": "sensor_msgs/msg/PointCloud2", "/contact_forces": "sensor_msgs/msg/PointCloud2",
            "/state": "sensor_msgs/msg/JointState", "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
            "/shaft_speed": "std_msgs/msg/Float64", "/load": "geometry_msgs/msg/WrenchStamped"}
        piece_tables, counts = _accel_tables(piece)
        assert len(piece_tables) == 50                            # 0.5 s of 10 ms tables
        assert counts["/contact_forces"] == counts["/shaft_speed"] == counts["/load"] == 50   # whole batches
        tables += piece_tables
    _assert_contiguous(tables)
    assert sum(w for _s, w in tables) == 30000
    summary = build_report(pieces[2], tmp_path / "report")
    assert summary["analysed_s"] == pytest.approx(0.5) and summary["waveform_gaps"] == 0
    assert summary["verdict"] == "outer"


def test_a_hard_kill_loses_only_the_piece_being_written(bearing_sim_exe, ros_env, tmp_path):
    """SIGKILL in the middle of a split recording (no finalising at all): every piece but the
    last is complete and readable, and together they hold the stream from its first table on,
    contiguous; the last one is what a kill leaves: a file without its footer, read up to its
    last complete chunk, or an empty one (the writer's buffer never reached the disk), left out."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import PointCloud2

    out = tmp_path / "run.mcap"
    proc = subprocess.Popen(_split_node(bearing_sim_exe, out, None), env=ros_env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.STDOUT)
    # stop waiting at once when the node writes one file (a node that does not split)
    signal_when(proc, lambda: len(list(tmp_path.glob("run_*.mcap"))) >= 5 or out.exists(), signal.SIGKILL, 0.0,
                "the node never split its recording")
    assert proc.returncode == -signal.SIGKILL and not out.exists()
    pieces = sorted(tmp_path.glob("run_*.mcap"))
    tables = []
    for piece in pieces[:-1]:
        with open_recording(piece) as rec:
            assert rec.metadata["scene"] == "er16k_outer_race"
        tables += _accel_tables(piece)[0]
    assert len(tables) == 50 * (len(pieces) - 1)                  # 0.5 s in each
    _assert_contiguous(tables)
    # the last one has no footer (unless the kill came between two pieces): read up to its last
    # complete chunk, by the recording's name, its tables continue the others'; or, with none
    # (empty, or cut inside its first chunk), left out and said
    with open_recording(out) as rec:
        assert not rec.notes or rec.recovered is None
        if rec.notes:
            assert rec.notes == [f"{pieces[-1]} left out: " + (
                "empty file (0 bytes): its writer wrote nothing to it before it stopped, e.g. the last file of a "
                "recording killed hard (kill -9)" if pieces[-1].stat().st_size == 0 else
                f"truncated MCAP recording ({pieces[-1].stat().st_size} bytes, no footer) without a complete "
                "chunk: no message to read, e.g. the last file of a recording killed hard (kill -9) as it began")]
            assert rec.paths == pieces[:-1]
        else:
            assert rec.paths == pieces
            assert rec.recovered is None or rec.recovered.startswith(f"{pieces[-1]}: read as recovered: ")
            with open_recording(pieces[-1]) as piece:
                last = [from_pointcloud2(deserialize_message(d, PointCloud2)) for _, _, _, d in piece.messages(["/accel"])]
            _assert_contiguous(tables + [(stamp, arr.shape[0]) for stamp, _names, arr in last])


def _stream_counts(path) -> dict:
    """{topic: messages} of ``path`` read by the mcap library's own stream reader (what a colleague
    salvaged a killed file with): record after record until the cut, where it fails."""
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    topics, counts = {}, {}
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, validate_crcs=True).records:
                if isinstance(record, Channel):
                    topics[record.id] = record.topic
                elif isinstance(record, Message):
                    counts[topics[record.channel_id]] = counts.get(topics[record.channel_id], 0) + 1
        except Exception:  # noqa: BLE001 - the cut: EndOfFile, or a record cut short that does not parse
            pass
    return counts


def test_a_recording_killed_hard_is_reported_and_played_up_to_its_last_complete_chunk(
        bearing_sim_exe, ros_env, tmp_path):
    """SIGKILL (or a power cut) leaves the node's file without its footer and summary: report and
    play refused it in one line that pointed to `mcap recover`, another tool.  Now both read it up
    to its last complete chunk: the same messages the mcap library's stream reader finds before
    the cut, every topic's, the /accel tables contiguous from the first; report analyses them
    (exit 0) and play publishes them all, each saying in one line that the file was read as
    recovered."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import PointCloud2

    out = tmp_path / "killed.mcap"
    proc = subprocess.Popen([bearing_sim_exe, "node", "--ros-args", "-p", "scene:=er16k_outer_race",
                             "-p", "fidelity:=kinematic", "-p", "real_time:=false", "-p", f"record:={out}"],
                            env=ros_env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    signal_when(proc, lambda: out.exists() and out.stat().st_size > 1_200_000, signal.SIGKILL, 0.0,
                "the node never wrote 1.2 MB of recording")
    assert proc.returncode == -signal.SIGKILL
    with open_recording(out) as rec:
        recovered, count = rec.recovered, rec.message_count
        counts = {t: c.count for t, c in rec.topics().items()}
        tables = [from_pointcloud2(deserialize_message(d, PointCloud2)) for _, _, _, d in rec.messages(["/accel"])]
        assert rec.metadata["scene"] == "er16k_outer_race" and rec.attachments
    assert recovered.startswith(f"{out}: read as recovered: no footer and no summary ")
    assert f": {count} messages in its " in recovered
    assert counts == _stream_counts(out) and counts["/accel"] == len(tables) >= 100
    _assert_contiguous([(stamp, arr.shape[0]) for stamp, _names, arr in tables])

    report = subprocess.run([bearing_sim_exe, "report", str(out), "--out", str(tmp_path / "report")], env=ros_env,
                            capture_output=True, text=True, timeout=120)
    assert report.returncode == 0 and report.stderr == f"report: {recovered}\n", report.stderr
    summary = json.loads((tmp_path / "report" / "summary.json").read_text())
    assert summary["recovered"] == recovered and summary["messages"] == count
    assert summary["waveform_gaps"] == 0 and summary["verdict"] == "outer"
    assert summary["duration_s"] == pytest.approx(sum(arr.shape[0] for _s, _n, arr in tables) / 15000)

    play = subprocess.run([bearing_sim_exe, "play", str(out), "--rate", "50", "--wait", "0"], env=ros_env,
                          capture_output=True, text=True, timeout=120)
    assert play.returncode == 0, play.stderr
    assert f"play {recovered}\n" in play.stderr and f"play {out}: published {count} messages" in play.stderr, \
        play.stderr


def test_the_file_of_a_node_still_recording_is_reported_as_being_written_not_as_killed(
        bearing_sim_exe, ros_env, tmp_path):
    """A newcomer who reports the node's file while the node still records it (a second terminal,
    "Record the live node") was told the file's "writer never finished, e.g. a hard kill or a
    power cut" and looked for a crash that had not happened.  The writer holds the file: report
    and play read it as far as it is written and say that it is still being written; once the
    node ends, the same file is a finished one."""
    out = tmp_path / "live.mcap"
    proc = subprocess.Popen([bearing_sim_exe, "node", "--ros-args", "-p", "scene:=er16k_outer_race",
                             "-p", "fidelity:=kinematic", "-p", f"record:={out}"],
                            env=ros_env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    reports = []

    def report_while_it_records():
        if not (out.exists() and out.stat().st_size > 1_200_000):    # a few complete chunks
            return False
        report = subprocess.run([bearing_sim_exe, "report", str(out), "--out", str(tmp_path / "report")],
                                env=ros_env, capture_output=True, text=True, timeout=120)
        reports.append((report, json.loads((tmp_path / "report" / "summary.json").read_text())))
        return True

    _stdout, stderr = signal_when(proc, report_while_it_records, signal.SIGINT, 0.0,
                                  "the node never wrote 1.2 MB of recording")
    assert proc.returncode == 0, stderr
    report, summary = reports[0]
    line = (f"report: {out}: read as far as it is written: a recording still being written holds it (its "
            "footer and summary come when its writer ends); read up to byte ")
    assert report.returncode == 0 and report.stderr.startswith(line), report.stderr
    assert "killed" not in report.stderr and "never finished" not in report.stderr
    assert report.stderr.count("\n") == 1 and report.stderr.endswith("; the rest is not written yet\n")
    assert summary["recovered"] == report.stderr[len("report: "):-1] and summary["verdict"] == "outer"
    with open_recording(out) as rec:          # the node ended: its file is finished
        assert rec.recovered is None and rec.message_count > summary["messages"]


def test_a_file_held_by_its_writer_before_its_first_chunk_is_refused_as_not_written_yet(
        bearing_sim_exe, ros_env, tmp_path):
    """The first second of a node's recording holds no complete chunk: `report` on it said
    "e.g. the last file of a recording killed hard (kill -9) as it began" while the recording ran
    on.  A file its writer still holds is said to be one whose first chunk is not written yet,
    one line, exit status 2, for `report` and `play` alike."""
    from std_msgs.msg import Float64

    from bearing_sim_ros.recording.recorder import Recorder

    path = tmp_path / "starting.mcap"
    with Recorder(path, {"scene": "starting"}, start_time_ns=0) as rec:
        rec.add_topic("/x", "std_msgs/msg/Float64", 10)
        rec.write("/x", Float64(data=1.0), 0)           # in the open chunk, not yet written
        results = [subprocess.run(args, env=ros_env, capture_output=True, text=True, timeout=120) for args in
                   ([bearing_sim_exe, "report", str(path), "--out", str(tmp_path / "report")],
                    [bearing_sim_exe, "play", str(path), "--wait", "0"])]
    for result in results:
        assert result.returncode == 2, result.stderr
        assert result.stderr.startswith(f"error: {path}: a recording still being written holds it, and it has "
                                        "no complete chunk yet ("), result.stderr
        assert result.stderr.count("\n") == 1 and "killed" not in result.stderr
    with open_recording(path) as finished:           # written out as its writer ended
        assert finished.recovered is None and finished.message_count == 1
