"""A split recording (the node's ``record_max_duration`` / ``record_max_size``: ``run_000.mcap``,
``run_001.mcap``, ...) is read as one by ``report`` and ``play``: given as its pieces in any order
or by the name it was recorded to.  Its report is the report of the same messages in one file; a
subscriber gets every table of every piece, contiguous across the seams, also looped.  Files that
are not the consecutive pieces of one recording are refused in one line, naming them; a hard
kill's last piece is read up to its last complete chunk, said in one line; one with no complete
chunk is left out, and said, when the pieces are found from the name."""
from __future__ import annotations

import json
import random
import subprocess

import numpy as np
import pytest
from test_play import WAIT, _subscriber

from bearing_sim_ros.analysis.report import build_report
from bearing_sim_ros.errors import UserError
from bearing_sim_ros.recording.reader import get_message, open_recording
from bearing_sim_ros.recording.recorder import Recorder, rotated_path
from bearing_sim_ros.recording.render import render
from bearing_sim_ros.recording.schemas import qos_from_yaml
from bearing_sim_ros.waveform import NS


def _split(src, base, seconds: float) -> list:
    """Write the messages of the recording ``src`` again to ``base`` as a split recording of
    ``seconds`` of log time per file, with ``src``'s metadata and attachments (as the node's
    recorder splits one); the pieces, in order."""
    from rclpy.serialization import deserialize_message

    base.parent.mkdir(parents=True, exist_ok=True)
    with open_recording(src) as rec:
        out = Recorder(base, rec.metadata, rec.attachments, rotate_seconds=seconds, start_time_ns=0)
        classes = {}
        for topic, info in rec.topics().items():
            out.add_topic(topic, info.msg_type, qos_from_yaml(info.qos_yaml))
            classes[topic] = get_message(info.msg_type)
        for topic, _type, log_ns, data in rec.messages():
            out.write(topic, deserialize_message(data, classes[topic]), log_ns)
    out.close()
    assert out.status["ok"] and out.status["dropped"] == 0, out.status
    return [rotated_path(base, k) for k in range(len(out.status["files"]))]


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """A 2 s render of the outer-race scene (one file) and the same messages split into pieces
    of 0.6 s of log time (which starts at 0 with the operating point: 0-0.59, 0.6-1.19,
    1.2-1.79, 1.8-2.0 s): (the file, the split's name, its pieces)."""
    d = tmp_path_factory.mktemp("split")
    src = d / "whole.mcap"
    render("er16k_outer_race", 2.0, src, fidelity="kinematic", seed=4, progress=False)
    pieces = _split(src, d / "pieces" / "run.mcap", 0.6)
    return src, d / "pieces" / "run.mcap", pieces


def test_the_split_is_four_complete_pieces(whole):
    _src, base, pieces = whole
    assert [p.name for p in pieces] == ["run_000.mcap", "run_001.mcap", "run_002.mcap", "run_003.mcap"]
    assert sorted(base.parent.iterdir()) == pieces and not base.exists()
    for k, piece in enumerate(pieces):
        with open_recording(piece) as rec:
            assert rec.metadata["file_index"] == str(k)


def test_a_split_recording_reads_as_the_recording_it_was_split_from(whole):
    """Its pieces in any order, or its name: the same messages in the same order as the file,
    the same metadata but for ``file_index``, the topics counted over every piece."""
    src, base, pieces = whole
    with open_recording(src) as rec:
        messages = list(rec.messages())
        expected = (rec.metadata, {t: (c.msg_type, c.count) for t, c in rec.topics().items()},
                    rec.message_count, rec.start_ns, rec.end_ns, rec.attachments)
    shuffled = list(pieces)
    random.Random(1).shuffle(shuffled)
    assert shuffled != pieces
    for given in (shuffled, base, str(base), [base]):
        with open_recording(given) as rec:
            assert rec.paths == pieces and rec.notes == []
            assert (rec.metadata, {t: (c.msg_type, c.count) for t, c in rec.topics().items()},
                    rec.message_count, rec.start_ns, rec.end_ns, rec.attachments) == expected
            assert list(rec.messages()) == messages
            accel = [m for m in messages if m[0] == "/accel"]
            assert list(rec.messages(["/accel"])) == accel and len(accel) == 200
            for topic in {m[0] for m in messages}:        # play's first and last table, per topic
                on = [(m[2], m[3]) for m in messages if m[0] == topic]
                assert rec.first_and_last(topic) == (on[0], on[-1]), topic
            assert rec.first_and_last("/nothing") is None
    with open_recording(pieces[1:3]) as rec:               # consecutive pieces are a recording too
        assert rec.path == f"{pieces[1]} .. {pieces[2]}"
        n = 0
        for p in pieces[1:3]:
            with open_recording(p) as piece:
                n += piece.message_count
        assert rec.message_count == sum(1 for _ in rec.messages()) == n
        assert list(rec.messages()) == [m for m in messages if pieces_span(pieces[1:3], m[2])]


def test_the_report_of_the_pieces_is_the_report_of_the_whole(whole, tmp_path):
    src, base, pieces = whole
    one = build_report(src, tmp_path / "one")
    split = build_report([pieces[3], pieces[0], pieces[2], pieces[1]], tmp_path / "split")
    named = build_report(base, tmp_path / "named")
    assert one["files"] == [str(src)] and one["files_left_out"] == []
    assert split["files"] == named["files"] == [str(p) for p in pieces]
    assert named["file"] == f"{base} (run_000.mcap .. run_003.mcap)"
    same = ("duration_s", "messages", "topics", "analysed_s", "waveform_gaps", "statistics", "fault_lines",
            "verdict", "timeline", "fault_onset_s", "first_detection_s", "scene", "parameters")
    for s in (split, named):
        assert {k: s[k] for k in same} == {k: one[k] for k in same}
    assert one["analysed_s"] == pytest.approx(2.0) and one["waveform_gaps"] == 0 and one["verdict"] == "outer"
    md = (tmp_path / "named" / "summary.md").read_text()
    assert f"| files | `{pieces[0]}` .. `{pieces[3]}`: 4 pieces of a split recording, read as one |" in md
    # a piece alone is a recording of its own, as before
    assert build_report(pieces[2], tmp_path / "piece")["analysed_s"] == pytest.approx(0.6)


def pieces_span(pieces, log_ns: int) -> bool:
    """Whether ``log_ns`` lies within the log times of ``pieces`` (first to last message)."""
    with open_recording(pieces[0]) as first, open_recording(pieces[-1]) as last:
        return first.start_ns <= log_ns <= last.end_ns


def _refusal(given) -> str:
    with pytest.raises(UserError) as info:
        open_recording(given).close()
    text = str(info.value)
    assert "\n" not in text
    return text


def test_the_name_of_a_split_recording_given_with_files_says_so(whole, bearing_sim_exe, tmp_path):
    """``report run.mcap run_001.mcap``: the name the recording was split from (no such file, its
    pieces found from it when given alone) among other files was "run.mcap: no such file", which
    reads as a typo in a name that works alone.  Now one line says what it is and the two ways
    to give it; the command line's status is 2."""
    _src, base, pieces = whole
    line = (f"{base}: the name that split recording run_000.mcap .. run_003.mcap was recorded to, given with "
            "other files; give that name alone (it reads all 4 pieces) or its pieces, not both")
    for given in ([base, pieces[1]], [pieces[0], base], [base, base]):
        assert _refusal(given) == line
    for command in (["report", str(base), str(pieces[1]), "--out", str(tmp_path / "r")],
                    ["play", str(pieces[0]), str(base)]):
        done = subprocess.run([bearing_sim_exe, *command], capture_output=True, text=True, timeout=120)
        assert (done.returncode, done.stderr) == (2, f"error: {line}\n")


def test_files_that_are_not_the_consecutive_pieces_of_one_recording_are_refused(whole, tmp_path):
    src, base, pieces = whole
    text = _refusal([pieces[0], pieces[2]])
    assert text.startswith(f"{pieces[0]} .. {pieces[2]}: the pieces between them are missing (file_index 1)")
    text = _refusal([pieces[1], base.parent / "." / "run_001.mcap"])
    assert text.startswith(f"{base.parent / '.' / 'run_001.mcap'}: given twice")
    text = _refusal([src, pieces[0]])
    assert text.startswith(f"{src}: not a piece of a split recording (its bearing_sim metadata has no file_index)")
    # another recording's pieces: another seed
    other_src = tmp_path / "other.mcap"
    render("er16k_outer_race", 1.0, other_src, fidelity="kinematic", seed=5, progress=False)
    other = _split(other_src, tmp_path / "other" / "run.mcap", 0.5)
    text = _refusal([pieces[0], other[1]])
    assert text == (f"{pieces[0]} and {other[1]} are pieces of different recordings (their bearing_sim "
                    "metadata differ in parameters, seed); give the pieces of one split recording")
    # the same messages split twice, 1 s and 0.6 s a piece: 0-0.99 s, then 0.6-1.19 s
    coarse = _split(src, tmp_path / "coarse" / "run.mcap", 1.0)
    text = _refusal([coarse[0], pieces[1]])
    assert text.startswith(f"{coarse[0]} and {pieces[1]}: the later piece starts before the earlier one ends")
    # a name with no pieces and no file is still "no such file"
    assert _refusal(tmp_path / "nothing.mcap").startswith(f"{tmp_path / 'nothing.mcap'}: no such file")


def _copied(whole, folder) -> tuple:
    """The split recording of ``whole`` copied into ``folder``, to be broken there: (its name,
    its pieces)."""
    _src, _base, pieces = whole
    copies = [folder / p.name for p in pieces]
    for p, copy in zip(pieces, copies):
        copy.write_bytes(p.read_bytes())
    return folder / "run.mcap", copies


def test_a_hard_kills_last_piece_is_read_as_far_as_it_goes_and_left_out_without_a_chunk(whole, tmp_path):
    """What a kill leaves of the file being written (no footer): it was left out, and its
    messages with it, though they are the end of the signal.  Now it is read up to its last
    complete chunk (here its one chunk, the cut in its summary), said in ``recovered``; a last
    piece cut before its first chunk ends has no message and is left out, as an empty one is,
    and said in ``files_left_out``."""
    base, copies = _copied(whole, tmp_path)
    data = copies[-1].read_bytes()
    copies[-1].write_bytes(data[: len(data) - 100])         # cut in its summary: every message there
    s = build_report(base, tmp_path / "report")
    assert s["files"] == [str(p) for p in copies] and s["files_left_out"] == []
    assert s["analysed_s"] == pytest.approx(2.0) and s["waveform_gaps"] == 0
    assert s["recovered"].startswith(f"{copies[3]}: read as recovered: no footer and no summary (its writer never "
                                     "finished, e.g. a hard kill or a power cut); read up to byte ")
    assert s["recovered"].endswith("its data section complete, only the summary lost")
    assert f"| recovered | {s['recovered']} |" in (tmp_path / "report" / "summary.md").read_text()
    for given in (base, copies, [copies[2], copies[3]]):    # by name or by hand alike
        with open_recording(given) as rec:
            assert rec.recovered == s["recovered"] and rec.paths[-1] == copies[3] and rec.notes == []
    copies[-1].write_bytes(data[: len(data) // 2])           # cut inside its one chunk
    s = build_report(base, tmp_path / "report")
    # the tables logged at 0.01-1.79 s (each at its batch's end)
    assert s["files"] == [str(p) for p in copies[:3]] and s["analysed_s"] == pytest.approx(1.79)
    assert s["recovered"] is None
    assert s["files_left_out"] == [f"{copies[3]} left out: truncated MCAP recording ({len(data) // 2} bytes, no "
                                   "footer) without a complete chunk: no message to read, e.g. the last file of a "
                                   "recording killed hard (kill -9) as it began"]
    assert f"| left out | {s['files_left_out'][0]} |" in (tmp_path / "report" / "summary.md").read_text()
    assert "without a complete chunk" in _refusal(copies)
    copies[0].write_bytes(b"")                               # a broken first piece is not left out
    assert _refusal(base) == f"{copies[0]}: empty file (0 bytes): its writer wrote nothing to it before it " \
                             "stopped, e.g. the last file of a recording killed hard (kill -9)"


def test_a_hard_kills_last_piece_given_by_hand_says_how_to_read_the_pieces_before_it(whole, tmp_path):
    """``report runs/run_*.mcap`` after a ``kill -9``: a last piece with nothing to read (empty,
    or cut before its first chunk ends) is an error, and it said only that `mcap recover`
    (another tool, not installed with this one) could salvage it.  Now the line says that it is
    the last piece of ``runs/run.mcap`` and how to read the pieces before it.  A piece cut before
    the last is refused, as the pieces after it would follow a gap; a truncated file that is no
    piece is read as recovered, alone."""
    base, copies = _copied(whole, tmp_path)
    hint = f"; it is the last piece of {base}: give the pieces before it, or {base}, which reads all 3 of them and " \
           "leaves it out"
    data = copies[-1].read_bytes()
    for broken in (data[: len(data) // 2], b""):
        copies[-1].write_bytes(broken)
        for given in (copies, [copies[3], copies[2]], [copies[2], copies[3]]):
            text = _refusal(given)
            assert text.startswith(f"{copies[3]}: ") and text.endswith(hint), text
            assert ("without a complete chunk" if broken else "empty file (0 bytes)") in text, text
    # a piece in the middle: cut before its chunk ends, or after (then it has messages)
    middle = copies[1].read_bytes()
    copies[1].write_bytes(middle[: len(middle) // 2])
    assert not _refusal([copies[0], copies[1]]).endswith(hint)
    copies[1].write_bytes(middle[: len(middle) - 100])
    assert _refusal([copies[2], copies[1], copies[0]]) == (
        f"{copies[1]}: truncated MCAP recording (no footer: its writer never finished), and not the last of the "
        "pieces given (file_index 1): the pieces after it would follow a gap; give the pieces up to it")
    with open_recording([copies[0], copies[1]]) as rec:      # up to it
        assert rec.recovered.startswith(f"{copies[1]}: read as recovered: ")
    lone = tmp_path / "lone.mcap"
    lone.write_bytes(data[: len(data) - 100])
    with open_recording(lone) as rec:
        assert rec.recovered.startswith(f"{lone}: read as recovered: ") and rec.message_count > 0


def test_report_and_play_take_several_files_on_the_command_line(whole, bearing_sim_exe, ros_env, tmp_path):
    """``report F_*.mcap`` (the shell's order) and the split's name; ``play`` of the name: every
    table of every piece reaches a subscriber in another process, contiguous across the seams,
    and looped once more past the end; the log line says how many files."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import PointCloud2

    src, base, pieces = whole
    r = subprocess.run([bearing_sim_exe, "report", *map(str, pieces), "--out", str(tmp_path / "r")], env=ros_env,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stderr == "" and "verdict outer" in r.stdout, r.stdout + r.stderr
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["files"] == [str(p) for p in pieces]

    with open_recording(src) as rec:
        stamps = [deserialize_message(d, PointCloud2).header.stamp for _, _, _, d in rec.messages(["/accel"])]
    recorded = [s.sec * NS + s.nanosec for s in stamps]
    want = len(recorded) + 50                                   # into the second pass
    sub, result = _subscriber(tmp_path, ros_env, want, 60)
    args = [bearing_sim_exe, "play", str(base), "--rate", "4", "--loop", *WAIT]
    play = subprocess.Popen(args, env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        sub.wait(timeout=90)
    finally:
        play.terminate()
        _out, err = play.communicate(timeout=30)
        if sub.poll() is None:
            sub.kill()
            sub.wait()
    assert play.returncode == 0, err
    assert f"play {base} (run_000.mcap .. run_003.mcap): " in err and " messages in 4 files on " in err, err
    got = np.array([[s, w] for s, w, _crc, _t in json.loads(result.read_text())["/accel"]], dtype=np.int64)
    assert len(got) >= want
    assert list(got[:len(recorded), 0]) == recorded                  # every table of every piece, in order
    assert np.all(np.diff(got[:, 0]) == got[:-1, 1] * NS // 15000)   # contiguous, the seams and the loop's too


def test_play_of_files_that_do_not_belong_together_is_one_line_and_status_2(whole, bearing_sim_exe, ros_env):
    src, _base, pieces = whole
    r = subprocess.run([bearing_sim_exe, "play", str(pieces[0]), str(pieces[2])], env=ros_env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stdout == "", r
    assert r.stderr.strip().splitlines() == [
        f"error: {pieces[0]} .. {pieces[2]}: the pieces between them are missing (file_index 1); give "
        "consecutive pieces of the recording"], r.stderr
