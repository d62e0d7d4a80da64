"""``bearing-sim run`` (what ``make run`` calls): live node, recording, one-screen summary."""
from __future__ import annotations

import re
import subprocess

import numpy as np
import pytest

from test_node_support import NS, assert_diverged_and_recorded, read_recording, render_run_up

from bearing_sim_ros.analysis.report import build_report


def _raw_message_bytes(path) -> int:
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        return sum(len(message.data) for _schema, _channel, message in make_reader(f).iter_messages())


def test_run_records_and_summarises(ros_env, bearing_sim_exe, tmp_path):
    out = tmp_path / "runs" / "r.mcap"
    out.parent.mkdir()
    r = subprocess.run([bearing_sim_exe, "run", "--scene", "er16k_outer_race", "--duration", "3",
                        "--out", str(out)], env=ros_env, capture_output=True, text=True, timeout=90)
    assert r.returncode == 0, r.stdout + r.stderr
    text = r.stdout
    assert "verdict: outer-race fault" in text, text
    row = re.search(r"BPFO\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+<- detected", text)
    assert row, text
    theory, found, _prom = map(float, row.groups())
    assert found == pytest.approx(theory, rel=0.005)
    for other in ("BPFI", "2xBSF"):
        assert re.search(rf"{re.escape(other)}\s+[\d.]+\s+[\d.]+\s+[\d.]+\s*$", text, re.M), other   # not detected
    rtf = float(re.search(r"real-time factor ([\d.]+)", text).group(1))
    assert rtf == pytest.approx(1.0, abs=0.05)
    assert str(out) in text
    topics, meta = read_recording(out)
    accel = [m for _t, m in topics["/accel"]]
    assert sum(m.width for m in accel) == 45000                     # 3 s at 15 kHz, whole
    stamps = np.array([m.header.stamp.sec * NS + m.header.stamp.nanosec for m in accel])
    assert np.all(np.diff(stamps) == 10_000_000)
    assert meta["bearing_sim"]["scene"] == "er16k_outer_race"
    assert "skid ratios" not in text                                # the kinematic tier has none
    # the sizes, each named: serialised message bytes and the file (the summary and the node's log)
    sizes = f"{_raw_message_bytes(out) / 1e6:.1f} MB of messages, {out.stat().st_size / 1e6:.1f} MB on disk (zstd)"
    assert f"recording: {out} ({sizes}, " in text, text
    assert f"recording {out}: " in r.stderr and f"messages, {sizes}, 0 dropped" in r.stderr, r.stderr


def test_run_on_a_healthy_skidding_scene_explains_the_ball_pass_line_and_shows_skid(ros_env, bearing_sim_exe,
                                                                                   tmp_path):
    """er16k_skidding has no defect and asks for skid ratios: the summary says the BPFO line is the
    ball-pass line, not a fault, and shows the recording's mean skid ratios."""
    out = tmp_path / "skid.mcap"
    r = subprocess.run([bearing_sim_exe, "run", "--scene", "er16k_skidding", "--duration", "3",
                        "--out", str(out)], env=ros_env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    text = r.stdout
    assert "skidding tier" in text, text
    assert re.search(r"BPFO\s+[\d.]+\s+[\d.]+\s+[\d.]+\s+<- detected", text), text   # the line is there
    assert "verdict: outer-race fault" not in text, text
    assert re.search(r"verdict: this scene has no defect; the line at BPFO \(x\d+\) is the ball-pass "
                     r"\(varying compliance\) line", text), text
    assert "compare line heights with a healthy baseline" in text, text
    # the skid ratios: the mean of what the recording's /diagnostics hold
    topics, _meta = read_recording(out)
    recorded = {}
    for _t, msg in topics["/diagnostics"]:
        for kv in msg.status[0].values:
            if kv.key in ("ball_skid_ratio", "cage_skid_ratio"):
                recorded.setdefault(kv.key[: -len("_ratio")], []).append(float(kv.value))
    assert set(recorded) == {"ball_skid", "cage_skid"}
    line = re.search(r"skid ratios, mean of the recording's /diagnostics \(skidding tier\): "
                     r"ball_skid ([\d.e+-]+) %, cage_skid ([\d.e+-]+) %", text)
    assert line, text
    for key, shown in zip(("ball_skid", "cage_skid"), map(float, line.groups())):
        assert shown == pytest.approx(np.mean(recorded[key]), rel=5e-3), key


def test_run_splits_its_recording_and_summarises_across_the_pieces(ros_env, bearing_sim_exe, tmp_path):
    """``--max-file-duration 0.5`` (the node's record_max_duration) for 2 s: r_000.mcap, ... each
    0.5 s or so, contiguous across the seams, and the summary analyses the last 2 s across them
    (the last piece alone holds less than the 1 s it needs) and names them all; the ``report``
    it suggests reads them all."""
    out = tmp_path / "r.mcap"
    r = subprocess.run([bearing_sim_exe, "run", "--duration", "2", "--out", str(out), "--max-file-duration", "0.5"],
                       env=ros_env, capture_output=True, text=True, timeout=90)
    assert r.returncode == 0, r.stdout + r.stderr
    pieces = sorted(tmp_path.iterdir())
    assert len(pieces) >= 4 and [p.name for p in pieces] == [f"r_{k:03d}.mcap" for k in range(len(pieces))]
    stamps = []
    for piece in pieces:
        topics, meta = read_recording(piece)
        stamps += [m.header.stamp.sec * NS + m.header.stamp.nanosec for _t, m in topics["/accel"]]
    assert len(stamps) == 200 and np.all(np.diff(stamps) == 10_000_000)
    assert "envelope analysis of the last 2.0 s" in r.stdout and "verdict: outer-race fault" in r.stdout, r.stdout
    assert f"recording: {pieces[0]} .. {pieces[-1]}, {len(pieces)} files (" in r.stdout, r.stdout
    # what it says to run next reads the whole recording: the name it was made to
    assert (f"  next: bearing-sim report {out} --out {tmp_path / 'r_report'}   |   bearing-sim play {out}"
            in r.stdout), r.stdout
    summary = build_report(out, tmp_path / "r_report")
    assert summary["files"] == [str(p) for p in pieces]
    assert summary["analysed_s"] == pytest.approx(2.0) and summary["waveform_gaps"] == 0


def test_the_next_commands_of_the_summary_run_as_printed_with_a_space_in_the_path(ros_env, bearing_sim_exe, tmp_path):
    """``next: bearing-sim report ... | bearing-sim play ...`` named a path with a space unquoted:
    pasted, ``report`` took ``my`` and ``run.mcap`` as two arguments.  Split as a shell splits it,
    the report command runs and writes its folder."""
    import shlex

    out = tmp_path / "my runs" / "my run.mcap"
    out.parent.mkdir()
    r = subprocess.run([bearing_sim_exe, "run", "--duration", "1", "--out", str(out)],
                       env=ros_env, capture_output=True, text=True, timeout=90)
    assert r.returncode == 0, r.stdout + r.stderr
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("  next: "))
    report, play = (shlex.split(part) for part in line.removeprefix("  next: ").split("   |   "))
    assert play == ["bearing-sim", "play", str(out)], line
    assert report[:3] == ["bearing-sim", "report", str(out)], line
    r = subprocess.run([bearing_sim_exe, *report[1:]], env=ros_env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (tmp_path / "my runs" / "my run_report").is_dir()


def test_run_whose_recording_is_deleted_says_so_and_ends_with_status_2(ros_env, bearing_sim_exe, tmp_path):
    """``--out`` deleted while ``run`` records: the node in the process notices (as ``bearing-sim
    node`` does: ``test_recording_live.py``), says it in its log when it happens and at exit, and
    ``run`` ends with status 2 and one error line naming ``--out`` and what happened, no summary."""
    import time

    from test_node_support import FIRST_TABLE_S

    out = tmp_path / "r.mcap"
    proc = subprocess.Popen([bearing_sim_exe, "run", "--duration", "5", "--out", str(out)], env=ros_env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        end = time.monotonic() + FIRST_TABLE_S
        while not (out.exists() and out.stat().st_size > 200_000) and time.monotonic() < end:
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        out.unlink()
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    error = f"recording to {out} stopped: the file was deleted while it was written"
    assert proc.returncode == 2, stdout + stderr
    assert f"]: recording failed, publishing goes on: {error}" in stderr, stderr
    assert stderr.splitlines()[-1] == f"error: --out = '{out}': {error}", stderr
    assert "verdict" not in stdout and not out.exists(), stdout


@pytest.mark.parametrize("case", ["unknown scene", "missing output folder", "the scene's own file",
                                  "files too small", "shorter than a sample"])
def test_run_user_mistakes_are_one_line(ros_env, bearing_sim_exe, tmp_path, case):
    if case == "unknown scene":
        args, word = ["--scene", "nope", "--duration", "1", "--out", str(tmp_path / "x.mcap")], "nope"
    elif case == "the scene's own file":
        # ``run --scene my.yaml --out my.yaml`` made the scene file a recording
        scene = tmp_path / "my.yaml"
        scene.write_text(_shipped_scene_text())
        args, word = ["--scene", str(scene), "--duration", "1", "--out", str(scene)], "is the scene's own file"
    elif case == "shorter than a sample":
        # under half a sample it rounded to none, the node's "forever": a run "for 1e-05 s" ran on
        args = ["--duration", "0.00001", "--out", str(tmp_path / "x.mcap")]
        word = "--duration = 1e-05 s: shorter than one sample at 15000 Hz"
    elif case == "files too small":
        # in run's words, not the node parameter's (record_max_size)
        args = ["--duration", "1", "--out", str(tmp_path / "x.mcap"), "--max-file-size", "1000"]
        word = "--max-file-size = 1000 bytes: 0 (one file) or at least 1000000 (1 MB)"
    else:
        # named by the option the user gave, not the node parameter behind it
        args, word = ["--duration", "1", "--out", "/no/such/folder/r.mcap"], "--out = '/no/such/folder/r.mcap'"
    r = subprocess.run([bearing_sim_exe, "run", *args], env=ros_env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stdout + r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and word in lines[0], r.stderr
    assert "Traceback" not in r.stderr
    if case == "the scene's own file":
        assert (tmp_path / "my.yaml").read_text() == _shipped_scene_text()


def _shipped_scene_text() -> str:
    from bearing_sim_ros.scene import load_scene

    return load_scene("er16k_outer_race").source_text


def test_the_verdict_line_says_when_a_scene_defect_appears():
    """The growing CWRU scene's pit appears at 5 s: a 3 s run's healthy verdict is not set
    against a defect it never held ("the scene's defects: outer" before), and one whose
    analysed stretch holds the onset says so; a defect there from the start is named as before."""
    from bearing_sim_ros import load_scene
    from bearing_sim_ros.run import _verdict_lines

    growing, fixed = load_scene("cwru_6205_or007_6_growing"), load_scene("cwru_6205_or007_6")
    healthy = {"verdict": "healthy"}
    assert _verdict_lines(growing, healthy, 3.0, 3.0) == [
        "verdict: healthy (threshold x4 the local floor; the scene's defects: outer (from 5 s, after this run))"]
    assert _verdict_lines(growing, healthy, 8.0, 5.0)[0].endswith("outer (from 5 s, inside the analysed stretch))")
    assert _verdict_lines(growing, healthy, 60.0, 10.0)[0].endswith("outer (from 5 s))")
    assert _verdict_lines(fixed, {"verdict": "outer"}, 3.0, 3.0) == [
        "verdict: outer-race fault (threshold x4 the local floor; the scene's defects: outer)"]


def test_a_defect_appearing_at_an_end_of_the_analysed_stretch_is_placed_on_the_right_side():
    """The signal spans [0, end) and the stretch analysed [end - analysed, end): a defect whose
    first sample is at ``end`` is after the run (the verdict never saw it), and one whose first
    sample is the stretch's first was there through all of it, as one from earlier."""
    from bearing_sim_ros import load_scene
    from bearing_sim_ros.run import _verdict_lines

    growing, healthy = load_scene("cwru_6205_or007_6_growing"), {"verdict": "healthy"}
    assert _verdict_lines(growing, healthy, 5.0, 3.0)[0].endswith("outer (from 5 s, after this run))")
    assert _verdict_lines(growing, healthy, 8.0, 3.0)[0].endswith("outer (from 5 s))")
    assert _verdict_lines(growing, healthy, 8.0, 3.0 + 1e-9)[0].endswith(
        "outer (from 5 s, inside the analysed stretch))")


def test_a_fault_verdict_on_a_healthy_scene_is_explained_in_the_reports_words():
    """An inner-race verdict on a scene without a defect: the summary says what the detector said
    and then, in ``report``'s own words (``analysis.envelope.no_defect_note``), what the line is
    not and what to do; it had a sentence of its own, without the advice."""
    from bearing_sim_ros import load_scene
    from bearing_sim_ros.analysis.envelope import no_defect_note
    from bearing_sim_ros.run import _verdict_lines

    inner = {"verdict": "inner"}
    what, advice = no_defect_note(inner["verdict"])
    assert _verdict_lines(load_scene("er16k_healthy"), inner, 3.0, 3.0) == [
        f"verdict: the detector says inner-race fault (threshold x4 the local floor); {what},", f"  {advice}"]


def test_run_stopped_by_ctrl_c_states_the_signal_it_recorded(ros_env, bearing_sim_exe, tmp_path):
    """``--duration 0`` ended with Ctrl-C: the node drops the batches it computed ahead that were
    not due yet (the file ends where the published stream ends), and the summary's ``s of
    signal`` is that stream's, the recording's.  It gave the simulator's time, up to
    ``compute_ahead`` (50 ms) more than anyone received: 4.39 s of signal over a 4.34 s file."""
    import signal

    from test_node_support import signal_when

    out = tmp_path / "r.mcap"
    proc = subprocess.Popen([bearing_sim_exe, "run", "--duration", "0", "--out", str(out)],
                            env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stdout, stderr = signal_when(proc, lambda: out.exists() and out.stat().st_size > 200_000,
                                 signal.SIGINT, 1.0, "no recording")
    assert proc.returncode == 0, stdout + stderr
    topics, _meta = read_recording(out)
    recorded_s = sum(m.width for _t, m in topics["/accel"]) / 15000.0
    said = re.search(r"([\d.]+) s of signal in", stdout)
    assert said, stdout
    assert float(said.group(1)) == pytest.approx(recorded_s, abs=0.006), (stdout, recorded_s)


def test_run_whose_terminal_closes_finalises_and_exits_without_an_internal_error(ros_env, bearing_sim_exe, tmp_path):
    """``bearing-sim run`` in a terminal window that is closed (an SSH session that drops): the
    SIGHUP ended the run and finalised the recording, but the summary then went to a terminal
    that fails every write (EIO): a traceback and "internal error", exit 1.  Now it exits 0, as
    the node does on SIGHUP, and says nothing more (nobody can read it)."""
    from test_node_support import on_a_terminal_that_closes

    from bearing_sim_ros.recording.reader import open_recording

    out = tmp_path / "r.mcap"
    with open(tmp_path / "stderr.txt", "w+") as err:
        status = on_a_terminal_that_closes([bearing_sim_exe, "run", "--duration", "0", "--out", str(out)], ros_env,
                                           lambda: out.exists() and out.stat().st_size > 200_000, 1.0,
                                           "no recording", stderr=err)
        err.seek(0)
        said = err.read()
    assert status == 0, said
    assert "Traceback" not in said and "internal error" not in said, said
    assert "run ended by SIGHUP" in said, said
    with open_recording(out) as rec:
        assert rec.recovered is None and rec.topics()["/accel"].count > 0         # finalised


def test_run_whose_terminal_closes_as_it_writes_a_line_exits_0(ros_env, bearing_sim_exe, tmp_path):
    """``bearing-sim run`` in a terminal that closes as it writes its first line: the write failed
    (EIO) before the hangup's SIGHUP was handled, and the OSError ended it as an internal error,
    exit 1.  Now the line goes nowhere and the SIGHUP ends the run: 0, the recording finalised.
    The moment made exact: ``closed_as_it_writes``."""
    from test_node_support import closed_as_it_writes

    from bearing_sim_ros.recording.reader import open_recording

    out = tmp_path / "r.mcap"
    with open(tmp_path / "stderr.txt", "w+") as err:
        status = closed_as_it_writes([bearing_sim_exe, "run", "--duration", "0", "--out", str(out)], ros_env,
                                     "bearing-sim run: ", tmp_path, err)
        err.seek(0)
        said = err.read()
    assert status == 0, said
    assert "Traceback" not in said and "internal error" not in said, said
    with open_recording(out) as rec:
        assert rec.recovered is None            # finalised


def test_run_whose_solver_diverges_says_it_in_one_line_and_keeps_the_recording(ros_env, bearing_sim_exe,
                                                                                diverging_scene, tmp_path):
    """``bearing-sim run`` on a scene whose skidding solver diverges at 0.32 s was a traceback and
    "internal error"; now one line with the scene key to try, exit 2, the recording finalised."""
    out = tmp_path / "run.mcap"
    r = subprocess.run([bearing_sim_exe, "run", "--scene", str(diverging_scene(0.3)), "--duration", "2",
                        "--out", str(out)], env=ros_env, capture_output=True, text=True, timeout=120)
    assert_diverged_and_recorded(r, out, "fidelity: {tier: kinematic} in the scene")


def _summary_of(recording, scene) -> str:
    """``bearing-sim run``'s summary of ``recording`` (a render standing in for the node's: the
    same topics), with made-up figures of the node."""
    from bearing_sim_ros.run import ANALYSIS_MAX_S, _record_tail, summarise

    figures = {"signal_s": 3.0, "wall_s": 3.0, "rtf": 1.0, "overruns": 0, "worst_lag": 0.0, "files": str(recording),
               "sizes": "-", "dropped": 0, "tier_values": {"tier": "kinematic", "tier_switches": 0}}
    return summarise(scene, _record_tail([recording], ANALYSIS_MAX_S), figures, str(recording))


def test_the_summary_looks_for_the_lines_where_the_cage_of_state_puts_them(skidding_outer_race):
    """At 10000 rpm / 10 N the ER-16K's cage skids 7 %: the summary looked for the lines at pure
    rolling (BPFO 595 Hz, the line at 552) and said "ball fault" (2xBSF x294) of this outer-race
    pit, as the live ``bearing-sim run`` of this scene did.  Now it takes the cage's speed from
    ``state``: an outer-race fault, BPFO expected within 1 Hz of where it is found."""
    from bearing_sim_ros import load_scene

    scene, recording = skidding_outer_race
    text = _summary_of(recording, load_scene(str(scene)))
    assert "verdict: outer-race fault" in text, text
    expected, found = map(float, re.search(r"BPFO +([\d.]+) +([\d.]+)", text).groups())
    assert abs(expected - found) < 1.0 and expected < 560, text
    # the shaft's frequency said is the recorded speed's, 10000 rpm = 166.67 Hz (rad/s over 2 pi)
    assert "at shaft 166.67 Hz (10000 rpm)" in text, text


def test_the_summary_looks_for_a_ball_pit_where_the_balls_spin_puts_it(skidding_ball_pit):
    """On the skidding tier at 2000 rpm / 200 N the ER-16K's balls spin 2.2 % slower than pure
    rolling, and a ball pit's 2xBSF line with them (151.3 Hz, not 154.75: outside the detector's
    +-1 % search).  The summary looked at pure rolling's and said "healthy" (2xBSF x0.5) of this
    pit, where report and monitor, which take the spin from /diagnostics' bsf_hz, said ball.  Now
    it takes it from there too: a ball fault, the line found where it looks, 1-3 % below pure
    rolling."""
    from bearing_sim_ros import load_scene

    scene, recording = skidding_ball_pit
    text = _summary_of(recording, load_scene(str(scene)))
    assert "\nverdict: ball fault (" in text, text
    expected, found, height = map(float, re.search(r"2xBSF +([\d.]+) +([\d.]+) +([\d.]+)", text).groups())
    pure = 2 * load_scene(str(scene)).fault_frequencies()["bsf"]
    assert abs(expected - found) < 1.0 and 0.97 * pure < expected < 0.99 * pure and height > 10, (pure, text)


def test_the_summary_counts_a_line_on_another_faults_sideband_for_that_fault(skidding_inner_pit_1000rpm):
    """On the skidding tier at 1000 rpm / 200 N the ER-16K's balls spin about 5 % slow and 2xBSF
    falls on an inner pit's BPFI - 1 x shaft line, which stands higher than BPFI: the summary said
    "ball fault" of this inner pit.  Now that line counts for the inner race, and the summary says
    so under the lines."""
    from bearing_sim_ros import load_scene

    scene, recording = skidding_inner_pit_1000rpm
    text = _summary_of(recording, load_scene(str(scene)))
    assert "\nverdict: inner-race fault (" in text, text
    assert "\n  2xBSF sits on BPFI - 1 x shaft rate, a sideband of the inner fault's line: counted for inner, not ball\n" \
        in text, text


def test_the_summary_tracks_a_ball_pit_on_the_balls_spin_over_a_speed_step(skidding_ball_pit_speed_step):
    """A speed step from 1000 to 2000 rpm on the skidding tier takes the balls' skid from about
    4.8 % to 3 %, and a ball pit's 2xBSF line moves by 2 % in orders of the shaft: judged at the
    stretch's mean spin, the summary called the pit healthy (2xBSF x3.0).  Now it takes each
    /diagnostics period's spin, as monitor and report do: ball fault, 2xBSF detected."""
    from bearing_sim_ros import load_scene

    scene, recording = skidding_ball_pit_speed_step
    text = _summary_of(recording, load_scene(str(scene)))
    assert " by order tracking, " in text and "\nverdict: ball fault (" in text, text
    assert re.search(r"2xBSF +[\d.]+ +[\d.]+ +[\d.]+  <- detected", text), text


def test_the_summary_of_a_stretch_whose_speed_stepped_is_in_orders(tmp_path):
    """A speed command from 1600 to 3000 rpm in the analysed stretch smears every envelope line;
    the summary judged it at the lines of the mean speed, where neither half has them, and called
    this outer-race pit a ball fault; then it said there was no verdict.  Now it judges the
    stretch in orders of the shaft (order tracking, as report does): an outer-race fault, and
    one line says how it got there."""
    from bearing_sim_ros import load_scene
    from bearing_sim_ros.recording.render import render

    scene = tmp_path / "step.yaml"
    scene.write_text(load_scene("er16k_outer_race").source_text
                     + "profile:\n  - {t: 1.5, shaft_speed_rpm: 1600}\n  - {t: 1.51, shaft_speed_rpm: 3000}\n")
    recording = tmp_path / "step.mcap"
    render(str(scene), 3.0, recording, progress=False)
    text = _summary_of(recording, load_scene(str(scene)))
    assert ("envelope analysis of the last 3.0 s (accel_x, accel_y, band 2-5 kHz) by order tracking, axis accel_y: "
            "the shaft and cage speeds moved by 61 % in it (1600-3000 rpm), which smears the lines in Hz; in orders "
            "of the shaft (114 revolutions) they hold still:") in text, text
    assert "\nverdict: outer-race fault (" in text, text


def test_the_summary_of_a_run_up_is_in_orders(outer_run_up):
    """er16k_outer_race run up from 1000 to 3000 rpm over 4 s (its lines move 89 % in Hz): the
    summary said "no verdict".  Now BPFO stands at its order (3.572 events per shaft revolution)
    and the verdict is an outer-race fault."""
    from bearing_sim_ros import load_scene

    text = _summary_of(outer_run_up, load_scene("er16k_outer_race"))
    assert "by order tracking, axis accel_y: the shaft and cage speeds moved by 89 % in it (1009-2999 rpm)" in text, text
    assert "  line   theory order found order  x floor\n" in text, text
    expected, found, height = map(float, re.search(r"BPFO +([\d.]+) +([\d.]+) +([\d.]+)  <- detected", text).groups())
    assert expected == 3.572 and abs(found - expected) < 0.005 and height > 50, text
    assert "\nverdict: outer-race fault (threshold x4 the local floor; the scene's defects: outer)" in text, text


def test_the_summary_gives_no_verdict_where_the_speed_moved_and_state_is_too_sparse(tmp_path):
    """The same run-up with ``state`` at 5 Hz (a speed step between two states would be drawn as a
    smooth turn): no order tracking, no verdict, and the summary says why."""
    from bearing_sim_ros import load_scene

    text = _summary_of(render_run_up(tmp_path, "er16k_outer_race", 2.0, state_rate=5.0), load_scene("er16k_outer_race"))
    assert ("envelope analysis of the last 2.0 s: no verdict: the shaft and cage speeds moved by" in text
            and "; no order tracking: state samples up to 0.2 s apart" in text and "\nverdict:" not in text), text


def test_the_summary_states_the_band_the_envelope_used_at_a_low_sample_rate(tmp_path):
    """At 4 kHz the detector's 2-5 kHz band is clipped to 0.9-1.8 kHz (``envelope.envelope_band``);
    the summary said "band 2-5 kHz" whatever band was used.  It states the band used."""
    from bearing_sim_ros import load_scene
    from bearing_sim_ros.recording.render import render

    recording = tmp_path / "slow.mcap"
    render("er16k_outer_race", 2.0, recording, fidelity="kinematic", seed=1, sample_rate=4000.0, progress=False)
    text = _summary_of(recording, load_scene("er16k_outer_race"))
    assert "(accel_x, accel_y, band 0.9-1.8 kHz) at shaft 26.67 Hz (1600 rpm)" in text, text
    assert "2-5 kHz" not in text, text
