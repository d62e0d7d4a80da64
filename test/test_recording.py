"""The MCAP recorder: files that an independent reader (rosbags) and the mcap reader read back,
with complete schemas, QoS, metadata and attachments; off-thread writing that survives a full
disk; rotation; CDR padding zeroed without changing any value."""
from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from bearing_sim_ros import Simulator, UserError, load_scene
from bearing_sim_ros.messages import TYPES, BatchMessages, waveform_qos
from bearing_sim_ros.recording.reader import open_recording
from bearing_sim_ros.recording.recorder import Recorder, recording_metadata, rotated_path
from bearing_sim_ros.recording.schemas import message_definition, qos_from_yaml, qos_to_yaml
from bearing_sim_ros.waveform import from_pointcloud2


@pytest.fixture(scope="module")
def sim_msgs():
    scene = load_scene("er16k_outer_race")
    sim = Simulator(scene, fidelity="kinematic", seed=3)
    return scene, sim, BatchMessages(sim, start_ns=1_700_000_000 * 10**9)


def _record(path, scene, sim, msgs, batches=50, **kw):
    meta = recording_metadata(scene, {"sample_rate": sim.sample_rate}, sim.seed, sim.selection)
    rec = Recorder(path, meta, {"scene.yaml": scene.source_text.encode()}, **kw)
    qos = waveform_qos(0.01)
    rec.add_topic("accel", TYPES["accel"], qos)
    rec.add_topic("state", TYPES["state"], None)
    sent = []
    for _ in range(batches):
        b = sim.advance(150)
        m = msgs.accel(b)
        t = msgs.stamp_ns(b.index0 + b.n)
        rec.write("accel", m, t)
        rec.write("state", msgs.state(t), t)
        sent.append((t, b.accel.astype(np.float32)))
    rec.close()
    return rec, sent


def test_schemas_hold_every_dependency_and_parse_independently():
    from rosbags.typesys import get_types_from_msg

    for msg_type in set(TYPES.values()):
        text = message_definition(msg_type)
        types = get_types_from_msg(text, msg_type)       # rosbags parses the rosbag2 format
        assert msg_type in types
        # every complex field type of every definition is itself defined
        checked = 0
        for _name, (_consts, fields) in types.items():
            for _fname, (kind, detail) in fields:
                if kind.name in ("ARRAY", "SEQUENCE"):
                    kind, detail = detail[0]
                if kind.name == "NAME":
                    assert detail in types, f"{msg_type}: {detail} missing"
                    checked += 1
        assert checked > 0 or msg_type == "std_msgs/msg/Float64"
    pc2 = message_definition("sensor_msgs/msg/PointCloud2")
    assert "MSG: std_msgs/msg/Header" in pc2 and "MSG: builtin_interfaces/msg/Time" in pc2
    assert "MSG: sensor_msgs/msg/PointField" in pc2
    assert pc2.count("=" * 80) == 3


def test_qos_yaml_round_trip():
    from rclpy.qos import ReliabilityPolicy

    q = waveform_qos(0.01)
    text = qos_to_yaml(q)
    assert text.startswith("- history: keep_last\n  depth: 100\n  reliability: reliable")
    back = qos_from_yaml(text)
    assert back.depth == q.depth and back.reliability == ReliabilityPolicy.RELIABLE
    assert back.history == q.history and back.durability == q.durability


def test_every_message_reads_back_with_rosbags_and_mcap(tmp_path, sim_msgs):
    from rclpy.serialization import deserialize_message
    from rosbags.highlevel import AnyReader
    from sensor_msgs.msg import PointCloud2

    scene, sim, msgs = sim_msgs
    path = tmp_path / "run.mcap"
    rec, sent = _record(path, scene, sim, msgs)
    st = rec.status
    assert st["ok"] and st["messages"] == 100 and st["dropped"] == 0

    with AnyReader([path]) as reader:
        conns = {c.topic: c for c in reader.connections}
        assert set(conns) == {"/accel", "/state"}
        assert conns["/accel"].msgtype == "sensor_msgs/msg/PointCloud2"
        qos = conns["/accel"].ext.offered_qos_profiles[0]
        assert qos.depth == 100 and qos.reliability.name == "RELIABLE"
        got = []
        for conn, t, raw in reader.messages(connections=[conns["/accel"]]):
            m = reader.deserialize(raw, conn.msgtype)
            stamp, names, arr = from_pointcloud2(m)
            got.append((t, arr))
        assert len(got) == len(sent)
        for (t, arr), (t_sent, data) in zip(got, sent):
            assert t == t_sent                      # log time = publish time as given
            np.testing.assert_array_equal(arr, data)

    with open_recording(path) as r:
        assert r.metadata["scene"] == "er16k_outer_race"
        assert r.metadata["scene_yaml"] == scene.source_text
        assert r.metadata["seed"] == "3" and r.metadata["tier"] == "kinematic"
        # why that tier, with its figures (report prints them), and which scene file it was
        assert r.metadata["tier_reason"] == sim.selection.reason != "kinematic"
        assert float(r.metadata["tier_estimated_error"]) == sim.selection.estimated_error
        assert float(r.metadata["tier_tolerance"]) == sim.selection.tolerance
        assert r.metadata["scene_path"] == Path(scene.source_path).name == "er16k_outer_race.yaml"
        assert r.attachments["scene.yaml"].decode() == scene.source_text
        n = 0
        for topic, msg_type, t, data in r.messages(["/accel"]):
            m = deserialize_message(data, PointCloud2)
            np.testing.assert_array_equal(from_pointcloud2(m)[2], sent[n][1])
            n += 1
        assert n == len(sent)
        assert r.header.profile == "ros2"


def test_add_topic_takes_an_int_depth_like_rclpy(tmp_path):
    """``create_publisher(Float64, "/x", 10)``: rclpy takes an int as a keep-last depth, and so
    does the recorder; the file then offers the profile rclpy would use."""
    from rclpy.qos import QoSProfile
    from rosbags.highlevel import AnyReader
    from std_msgs.msg import Float64

    path = tmp_path / "depth.mcap"
    with Recorder(path, {"a": "b"}) as rec:
        rec.add_topic("/x", "std_msgs/msg/Float64", 10)
        rec.write("/x", Float64(data=1.5), 1)
        with pytest.raises(ValueError, match="/y: qos = -1: a depth must be >= 0"):
            rec.add_topic("/y", "std_msgs/msg/Float64", -1)
        with pytest.raises(TypeError, match="/y: qos = 'ten': expected"):
            rec.add_topic("/y", "std_msgs/msg/Float64", "ten")
    assert rec.status["ok"] and rec.status["messages"] == 1
    with AnyReader([path]) as reader:
        (conn,) = reader.connections
        assert conn.topic == "/x"
        offered = conn.ext.offered_qos_profiles[0]
    rclpy_default = QoSProfile(depth=10)
    assert offered.depth == 10 and offered.history.name == "KEEP_LAST"
    assert offered.reliability.name == rclpy_default.reliability.name == "RELIABLE"
    assert offered.durability.name == rclpy_default.durability.name == "VOLATILE"


def test_a_reader_looking_at_a_file_as_its_writer_starts_does_not_make_the_writer_refuse(tmp_path):
    """`report` and `play` ask whether a writer still holds a file (``being_written``: a shared
    lock tried for a moment).  A node that started its recording at that moment took the reader's
    lock for another writer's and refused to record ("another recording is being written to this
    file").  A writer tries its lock again for a while: a reader's 20 ms hold does not refuse it,
    and a writer that holds the file throughout still refuses the next."""
    import fcntl

    path = tmp_path / "watched.mcap"
    path.write_bytes(b"")
    reader = os.open(path, os.O_RDONLY)
    fcntl.flock(reader, fcntl.LOCK_SH | fcntl.LOCK_NB)      # what a reader holds for a moment
    release = threading.Timer(0.02, os.close, (reader,))
    release.start()
    try:
        writer = Recorder(path, {"a": "b"})
    finally:
        release.join()
    with pytest.raises(UserError, match=r"record = .*watched.mcap.*another recording is being written to this file"):
        Recorder(path, {"a": "b"})
    writer.close()
    assert writer.error == ""
    with open_recording(path) as rec:
        assert rec.message_count == 0


def test_unwritable_path_is_a_user_error(tmp_path):
    with pytest.raises(UserError, match="record = .*cannot write there"):
        Recorder(tmp_path / "missing_dir" / "x.mcap", {"a": "b"})


def test_a_file_being_recorded_is_not_recorded_to_again_until_it_is_closed(tmp_path, sim_msgs):
    """Two recorders on one path (two nodes given one ``record``) wrote into the one file: the
    second is a UserError, the first's file stays whole, and once it is closed the path may be
    recorded to again (a new recording replaces an earlier one)."""
    scene, sim, msgs = sim_msgs
    path = tmp_path / "same.mcap"
    first = Recorder(path, {"a": "b"})
    first.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    with pytest.raises(UserError, match=r"record = .*same.mcap.*another recording is being written to this file"):
        Recorder(path, {"a": "b"})
    for _ in range(5):
        b = sim.advance(150)
        first.write("accel", msgs.accel(b), msgs.stamp_ns(b.index0 + b.n))
    first.close()
    assert first.error == ""
    with open_recording(path) as rec:
        assert rec.message_count == 5
    Recorder(path, {"a": "b"}).close()


@pytest.mark.parametrize("rotation", [{"rotate_bytes": -1}, {"rotate_seconds": -0.5},
                                      {"rotate_seconds": float("nan")}, {"rotate_seconds": float("inf")}])
def test_a_rotation_that_is_not_a_size_or_span_is_a_user_error(tmp_path, rotation):
    """A negative size would start a new file at every message, and a NaN or infinite span
    ended in a ValueError or OverflowError: each is refused in one line before any file is
    made."""
    with pytest.raises(UserError, match="expected numbers >= 0"):
        Recorder(tmp_path / "r.mcap", {"a": "b"}, **rotation)
    assert list(tmp_path.iterdir()) == []


def test_full_disk_is_recorded_in_status_and_never_raises(sim_msgs):
    """/dev/full accepts open() and fails every write with ENOSPC: the publisher keeps going."""
    scene, sim, msgs = sim_msgs
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    rec = Recorder("/dev/full", {"a": "b"})
    rec.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    for _ in range(200):                  # 200 x 1.2 kB > the 1 MB chunk: the chunk write fails
        b = sim.advance(150)
        m = msgs.accel(b)
        m.data = bytes(8000) + bytes(m.data)    # make each message big enough to fill a chunk fast
        rec.write("accel", m, 0)
    rec.close()
    st = rec.status
    assert not st["ok"]
    assert "No space left" in st["error"] and "\n" not in st["error"]
    assert st["dropped"] > 0
    # every write is accounted for: recorded (before the failing chunk) or counted as dropped,
    # those still queued when the disk failed included
    assert st["messages"] + st["dropped"] == 200
    rec.write("accel", m, 0)             # after close: counted, not raised
    rec.close()                          # idempotent


def test_rotation_by_duration_gives_complete_files(tmp_path, sim_msgs):
    scene, sim, msgs = sim_msgs
    base = tmp_path / "rot.mcap"
    rec, sent = _record(base, scene, sim, msgs, batches=100, rotate_seconds=0.25)
    files = rec.status["files"]
    assert files == [str(rotated_path(base, k)) for k in range(4)]
    assert [Path(f).name for f in files] == ["rot_000.mcap", "rot_001.mcap", "rot_002.mcap", "rot_003.mcap"]
    total = 0
    for k, f in enumerate(files):
        with open_recording(f) as r:
            assert r.metadata["file_index"] == str(k) and r.metadata["scene"] == "er16k_outer_race"
            # complete on its own: the scene file is attached to every file, not only the first
            assert r.attachments == {"scene.yaml": scene.source_text.encode()}
            total += sum(1 for _ in r.messages(["/accel"]))
            assert (r.end_ns - r.start_ns) < 0.25e9
    assert total == len(sent)


def test_zero_padding_changes_no_value_and_matches_an_independent_serialiser():
    """rosbags' serialiser writes zero padding: after zeroing, rclpy's bytes must equal it."""
    from rclpy.serialization import deserialize_message, serialize_message
    from rosbags.typesys import Stores, get_typestore
    from sensor_msgs.msg import JointState

    from bearing_sim_ros.recording.cdr import zero_padding

    ts = get_typestore(Stores.ROS2_JAZZY)
    for frame, names, pos, vel in [("abcdefg", [], [], [1.0]), ("ab", ["a", "bcd"], [1.5], []),
                                   ("bearing_accel", ["shaft"], [0.1, 0.2], [3.0, 4.0])]:
        m = JointState(name=names, position=pos, velocity=vel, effort=[])
        m.header.frame_id = frame
        raw = serialize_message(m)
        z = zero_padding(raw, "sensor_msgs/msg/JointState")
        assert deserialize_message(z, JointState) == m
        ref = ts.serialize_cdr(ts.deserialize_cdr(z, "sensor_msgs/msg/JointState"),
                               "sensor_msgs/msg/JointState")
        assert bytes(ref) == z[:len(ref)] and not any(z[len(ref):]) and len(z) - len(ref) < 4


def _cdr_fields_only(raw: bytes, msg_type: str, ts):
    """The message rosbags decodes from rclpy's ``raw`` (whose buffer rmw sizes from an estimate:
    up to 12 unused bytes after the last field, which rosbags refuses): the longest prefix it
    accepts.  Independent of ``cdr.py``."""
    for k in range(len(raw), len(raw) - 16, -1):
        try:
            return ts.deserialize_cdr(raw[:k], msg_type)
        except Exception:  # noqa: BLE001 - a longer prefix than the fields: try a shorter one
            continue
    raise AssertionError(f"rosbags reads no prefix of this {msg_type}")


def _with_garbage_where_no_value_is(clean: bytes, msg_type: str, little: bool, ts) -> bytes:
    """``clean`` (rosbags' zero-padded CDR) plus 3 + 8 bytes of slack, with 0xAA written into
    every zero byte that carries no value: a byte is taken for padding when garbage there
    leaves what rosbags decodes unchanged (it re-serialises to ``clean``).  This finds the
    alignment padding from the decoder, not from the walker under test."""
    def same(data):
        try:
            return bytes(ts.serialize_cdr(ts.deserialize_cdr(data[:len(clean)], msg_type), msg_type,
                                          little_endian=little)) == clean
        except Exception:  # noqa: BLE001 - garbage in a length or a value: not padding
            return False

    dirty = bytearray(clean)
    for i in range(4, len(clean)):          # after the 4-byte encapsulation header
        if clean[i] == 0:
            dirty[i] = 0xAA
            if not same(bytes(dirty)):
                dirty[i] = 0
    return bytes(dirty) + b"\xaa" * 11      # slack after the last field (rmw's estimate)


def test_zero_padding_zeroes_garbage_in_every_padding_byte_of_either_endianness(sim_msgs):
    """rclpy leaves whatever was in its buffer in the padding and after the last field; here
    that garbage is put in on purpose (0xAA in every byte that carries no value, as rosbags
    decodes it) into waveform tables, joint states, wrenches (float64 after a string: 8-byte
    alignment), diagnostics (nested sequences) and an Imu (fixed-size float64[9] arrays), little-
    and big-endian.  Zeroing must give rosbags' own zero-padded bytes, with at most 3 zero bytes
    after the last field; a prefix cut inside the fields (a layout the walk cannot finish) and an
    XCDR2 payload (other alignment rules) come back untouched: the recorder never changes a
    value byte."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from geometry_msgs.msg import WrenchStamped
    from rclpy.serialization import serialize_message
    from rosbags.typesys import Stores, get_typestore
    from sensor_msgs.msg import Imu, JointState

    from bearing_sim_ros.recording.cdr import zero_padding

    scene, sim, msgs = sim_msgs
    ts = get_typestore(Stores.ROS2_JAZZY)
    wrench = WrenchStamped()
    wrench.header.frame_id = "bearing"
    wrench.wrench.force.y, wrench.wrench.torque.z = -50.0, 0.25
    joints = JointState(name=["ab", "shaft"], position=[1.5], velocity=[], effort=[2.0, 3.0])
    joints.header.frame_id = "abcdefg"
    diag = DiagnosticArray(status=[DiagnosticStatus(level=b"\x01", name="bearing_sim: simulator",
                                                    values=[KeyValue(key="tier", value="kinematic"),
                                                            KeyValue(key="lag_s", value="0.0")])])
    imu = Imu(orientation_covariance=[0.5] * 9, angular_velocity_covariance=[-1.0] * 9)
    imu.header.frame_id = "x"
    imu.linear_acceleration.z = 9.81
    cases = [(msgs.accel(sim.advance(30)), TYPES["accel"]), (joints, TYPES["state"]),
             (wrench, TYPES["load"]), (diag, TYPES["/diagnostics"]), (imu, "sensor_msgs/msg/Imu")]
    for msg, msg_type in cases:
        decoded = _cdr_fields_only(serialize_message(msg), msg_type, ts)
        for little in (True, False):
            clean = bytes(ts.serialize_cdr(decoded, msg_type, little_endian=little))
            dirty = _with_garbage_where_no_value_is(clean, msg_type, little, ts)
            assert dirty.count(0xAA) > 11, msg_type       # padding inside the fields too
            z = zero_padding(dirty, msg_type)
            assert z[:len(clean)] == clean, (msg_type, little)
            assert len(z) - len(clean) < 4 and not any(z[len(clean):]), (msg_type, little)
            for cut in range(4, len(clean)):
                assert zero_padding(dirty[:cut], msg_type) == dirty[:cut], (msg_type, little, cut)
            xcdr2 = dirty[:1] + (b"\x07" if little else b"\x06") + dirty[2:]
            assert zero_padding(xcdr2, msg_type) == xcdr2, (msg_type, little)


def test_waveform_table_padding_is_zeroed_in_the_file(tmp_path, sim_msgs):
    """PointCloud2 has padding after each PointField's datatype and after is_bigendian."""
    scene, sim, msgs = sim_msgs
    path = tmp_path / "pad.mcap"
    _record(path, scene, sim, msgs, batches=5)
    with open_recording(path) as r:
        for _, _, _, data in r.messages(["/accel"]):
            # frame 'bearing_accel': PointField[0].datatype at 60, count at 64; see cdr.py
            assert data[61:64] == b"\0\0\0" and data[85:88] == b"\0\0\0" and data[93:96] == b"\0\0\0"


def test_rotation_by_size(tmp_path, sim_msgs):
    """``rotate_bytes`` is the size of each file on disk (as rosbag2's --max-bag-size), not its
    messages' serialised bytes (zstd takes them to about a third): a file ends past it by less
    than one instant's messages (here a batch: 1.8 kB) and its summary (the schemas again and the
    chunk index: 5.8 kB here), and holds whole instants."""
    scene, sim, msgs = sim_msgs
    base = tmp_path / "size.mcap"
    # 80 batches x (1.3 kB accel + 0.5 kB state) = 144 kB of messages
    rec, sent = _record(base, scene, sim, msgs, batches=80, rotate_bytes=20_000)
    files = rec.status["files"]
    assert len(files) >= 4
    total = 0
    for k, f in enumerate(files):
        size = Path(f).stat().st_size
        assert size < 20_000 + 1_800 + 6_000, (f, size)
        if k < len(files) - 1:
            assert size > 15_000, (f, size)            # near the size asked, not a third of it
        with open_recording(f) as r:
            accel = [t for _, _, t, _ in r.messages(["/accel"])]
            assert accel == [t for _, _, t, _ in r.messages(["/state"])]     # whole batches
            total += len(accel)
    assert total == len(sent)


# PointField datatypes (sensor_msgs/msg/PointField.msg constants) as numpy types
_POINTFIELD_NUMPY = {7: "<f4", 8: "<f8"}


def _decode_by_fields(m):
    """A waveform table decoded as a generic PointCloud2 reader would: by each field's name,
    offset and datatype, point_step and row_step (not by this package's ``from_pointcloud2``)."""
    assert m.height == 1 and not m.is_bigendian and m.is_dense
    assert m.row_step == m.point_step * m.width and len(m.data) == m.row_step
    assert all(f.count == 1 for f in m.fields)
    dtype = np.dtype({"names": [f.name for f in m.fields],
                      "formats": [_POINTFIELD_NUMPY[f.datatype] for f in m.fields],
                      "offsets": [f.offset for f in m.fields], "itemsize": m.point_step})
    rows = np.frombuffer(bytes(m.data), dtype=dtype)
    return [f.name for f in m.fields], np.stack([rows[name] for name in dtype.names], axis=1)


def test_tables_and_state_read_back_by_their_own_layout(tmp_path, sim_msgs):
    """Through rosbags and a reader that knows only the PointCloud2 layout: ``accel`` holds
    accel_x, accel_y and ``contact_forces`` inner_00..inner_08, outer_00..outer_08 (README), each
    a float32 at 4 x its column, stamped at the ROS time of the batch's first sample (start +
    index / 15 kHz); ``state`` lists shaft, cage, balls, the cage turning at (1 - d/D_m) / 2 of
    the shaft (pure rolling, kinematic tier) in angle and speed, every joint's angle advancing by
    its speed."""
    from rosbags.highlevel import AnyReader

    scene, sim, msgs = sim_msgs
    nb = sim.bearing.balls
    path = tmp_path / "tables.mcap"
    rec = Recorder(path, {"a": "b"})
    for topic in ("accel", "contact_forces", "state"):
        rec.add_topic(topic, TYPES[topic], None)
    sent = []
    for _ in range(3):
        b = sim.advance(150)
        t = msgs.stamp_ns(b.index0 + b.n)
        rec.write("accel", msgs.accel(b), t)
        rec.write("contact_forces", msgs.contact_forces(b), t)
        rec.write("state", msgs.state(t), t)
        sent.append(b)
    rec.close()
    got = {}
    with AnyReader([path]) as reader:
        for conn, _t, raw in reader.messages():
            got.setdefault(conn.topic, []).append(reader.deserialize(raw, conn.msgtype))
    assert {k: len(v) for k, v in got.items()} == {"/accel": 3, "/contact_forces": 3, "/state": 3}
    contact_names = [f"inner_{j:02d}" for j in range(nb)] + [f"outer_{j:02d}" for j in range(nb)]
    ratio = (1.0 - scene.bearing.ball_diameter / scene.bearing.pitch_diameter) / 2.0
    for b, a, c, s in zip(sent, got["/accel"], got["/contact_forces"], got["/state"]):
        first_sample_ns = 1_700_000_000 * 10**9 + b.index0 * 10**9 // 15000
        for m, names, data in ((a, ["accel_x", "accel_y"], b.accel), (c, contact_names, b.contact_forces)):
            assert m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == first_sample_ns
            got_names, table = _decode_by_fields(m)
            assert got_names == names
            np.testing.assert_array_equal(table, np.asarray(data, dtype=np.float32))
        assert list(s.name) == ["shaft", "cage"] + [f"ball_{j:02d}" for j in range(nb)]
        assert s.position[1] / s.position[0] == pytest.approx(ratio, rel=1e-6)
        assert s.velocity[1] / s.velocity[0] == pytest.approx(ratio, rel=1e-9)
    # every joint, the balls too, is an angle advancing by its speed x the 10 ms between states
    # (speeds are constant here: constant shaft speed, kinematic tier)
    position = np.array([s.position for s in got["/state"]])
    velocity = np.array([s.velocity for s in got["/state"]])
    assert position.shape == velocity.shape == (3, 2 + nb)
    np.testing.assert_allclose(np.diff(position, axis=0), 0.01 * velocity[1:], rtol=1e-6)


def test_messages_are_numbered_per_channel_and_published_at_their_log_time(tmp_path):
    """MCAP sequence numbers count each channel's messages from 0 (readers find gaps by them);
    publish time = log time; the scene attachment is YAML; a write after close is dropped and
    counted."""
    from mcap.reader import make_reader
    from std_msgs.msg import Float64

    path = tmp_path / "seq.mcap"
    rec = Recorder(path, {"a": "b"}, {"scene.yaml": b"name: x\n"}, start_time_ns=0)
    rec.add_topic("/a", "std_msgs/msg/Float64", 10)
    rec.add_topic("/b", "std_msgs/msg/Float64", 10)
    for k in range(4):
        rec.write("/a", Float64(data=float(k)), 1000 + k)
        if k % 2:
            rec.write("/b", Float64(data=-float(k)), 2000 + k)
    rec.close()
    rec.write("/a", Float64(data=9.0), 5000)
    assert rec.status["messages"] == 6 and rec.status["dropped"] == 1
    seqs = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        for _schema, channel, message in reader.iter_messages():
            seqs.setdefault(channel.topic, []).append(message.sequence)
            assert message.publish_time == message.log_time
        (att,) = list(reader.iter_attachments())
    assert seqs == {"/a": [0, 1, 2, 3], "/b": [0, 1]}
    assert att.name == "scene.yaml" and att.media_type == "application/yaml"


def test_a_non_default_qos_profile_is_recorded_as_offered(tmp_path):
    """Best effort, transient local, 1.5 s deadline, 2 ms lifespan, manual liveliness with a 3 s
    lease: rosbags reads each from the file, and the recorder's own reader (``play``) gives the
    same profile back."""
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, LivelinessPolicy, QoSProfile, ReliabilityPolicy
    from rosbags.highlevel import AnyReader
    from std_msgs.msg import Float64

    q = QoSProfile(depth=7, reliability=ReliabilityPolicy.BEST_EFFORT,
                   durability=DurabilityPolicy.TRANSIENT_LOCAL,
                   deadline=Duration(seconds=1, nanoseconds=500_000_000),
                   lifespan=Duration(nanoseconds=2_000_000),
                   liveliness=LivelinessPolicy.MANUAL_BY_TOPIC,
                   liveliness_lease_duration=Duration(seconds=3))
    path = tmp_path / "qos.mcap"
    with Recorder(path, {"a": "b"}) as rec:
        rec.add_topic("/x", "std_msgs/msg/Float64", q)
        rec.write("/x", Float64(data=1.0), 1)
    with AnyReader([path]) as reader:
        (conn,) = reader.connections
        offered = conn.ext.offered_qos_profiles[0]
    assert offered.depth == 7 and offered.reliability.name == "BEST_EFFORT"
    assert offered.durability.name == "TRANSIENT_LOCAL" and offered.liveliness.name == "MANUAL_BY_TOPIC"
    assert (offered.deadline.sec, offered.deadline.nsec) == (1, 500_000_000)
    assert (offered.lifespan.sec, offered.lifespan.nsec) == (0, 2_000_000)
    assert (offered.liveliness_lease_duration.sec, offered.liveliness_lease_duration.nsec) == (3, 0)
    with open_recording(path) as r:
        (info,) = r.channels.values()
    back = qos_from_yaml(info.qos_yaml)
    assert (back.depth, back.reliability, back.durability, back.liveliness) == \
        (7, q.reliability, q.durability, q.liveliness)
    assert back.deadline == q.deadline and back.lifespan == q.lifespan
    assert back.liveliness_lease_duration == q.liveliness_lease_duration


def test_the_queue_limit_bounds_the_backlog_not_the_recording(tmp_path, monkeypatch):
    """``MAX_QUEUE_BYTES`` caps what waits for the disk; a recorder whose writer keeps up records
    far more than that in total without dropping anything."""
    import time

    from std_msgs.msg import Float64

    from bearing_sim_ros.recording import recorder as recorder_module

    monkeypatch.setattr(recorder_module, "MAX_QUEUE_BYTES", 100)
    with Recorder(tmp_path / "q.mcap", {"a": "b"}) as rec:
        rec.add_topic("/x", "std_msgs/msg/Float64", 10)
        for k in range(30):                   # 30 x 12 bytes of CDR: 3.6 x the limit in total
            rec.write("/x", Float64(data=float(k)), k)
            deadline = time.monotonic() + 5.0
            while rec.status["messages"] < k + 1 and time.monotonic() < deadline:
                time.sleep(0.002)
    assert rec.status["messages"] == 30 and rec.status["dropped"] == 0


def test_a_file_of_another_profile_is_not_a_ros2_recording(tmp_path):
    from mcap.writer import Writer

    path = tmp_path / "json.mcap"
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile="", library="test")
        w.finish()
    with pytest.raises(UserError, match="is not 'ros2': not a ROS 2 recording"):
        open_recording(path)


def test_from_pointcloud2_refuses_what_is_not_a_waveform_table(sim_msgs):
    """``monitor`` and ``report`` read tables with ``from_pointcloud2``: a big-endian table, a
    point step that is not 4 bytes per channel, or more than one row would be read as the wrong
    numbers, so each is refused with a one-line reason instead."""
    from sensor_msgs.msg import PointField

    from bearing_sim_ros.waveform import to_pointcloud2

    scene, sim, msgs = sim_msgs
    b = sim.advance(20)
    stamp, names, arr = from_pointcloud2(msgs.accel(b))
    np.testing.assert_array_equal(arr, b.accel.astype(np.float32))
    for attr, value in (("is_bigendian", True), ("point_step", 12), ("height", 2), ("width", 21)):
        m = to_pointcloud2(b.accel, ["accel_x", "accel_y"], stamp, "f")
        setattr(m, attr, value)
        with pytest.raises(ValueError, match="not a waveform table") as exc:
            from_pointcloud2(m)
        assert "\n" not in str(exc.value)
    # a field of another type, or offsets that are not the channels' 4-byte slots
    for field, attr, value in ((1, "datatype", PointField.INT32), (0, "count", 2), (1, "offset", 8),
                               (1, "offset", 0)):
        m = to_pointcloud2(b.accel, ["accel_x", "accel_y"], stamp, "f")
        setattr(m.fields[field], attr, value)
        with pytest.raises(ValueError, match="not a waveform table") as exc:
            from_pointcloud2(m)
        assert "\n" not in str(exc.value)
    # a FLOAT64 table, laid out consistently (8 bytes per channel): the reason is its type; it said
    # "point_step 16, channels 2, height 1, big-endian False", which did not say what was wrong
    m = to_pointcloud2(b.accel, ["accel_x", "accel_y"], stamp, "f")
    for k, f in enumerate(m.fields):
        f.datatype, f.offset = PointField.FLOAT64, 8 * k
    m.point_step, m.row_step, m.data = 16, 16 * m.width, b.accel.astype("<f8").tobytes()
    with pytest.raises(ValueError, match="not a waveform table: field.s. accel_x, accel_y not one FLOAT32 each"):
        from_pointcloud2(m)


def test_from_pointcloud2_reads_each_column_at_its_own_offset(sim_msgs):
    """A table whose fields are listed in another order than their offsets (legal PointCloud2)
    gives each name the column at that field's offset, not the column at its list position."""
    from bearing_sim_ros.waveform import to_pointcloud2

    scene, sim, msgs = sim_msgs
    b = sim.advance(20)
    m = to_pointcloud2(b.accel, ["accel_x", "accel_y"], 0, "f")
    m.fields = [m.fields[1], m.fields[0]]             # accel_y (offset 4) listed first
    _, names, arr = from_pointcloud2(m)
    assert names == ["accel_y", "accel_x"]
    np.testing.assert_array_equal(arr[:, 0], b.accel[:, 1].astype(np.float32))
    np.testing.assert_array_equal(arr[:, 1], b.accel[:, 0].astype(np.float32))


def test_a_frame_id_given_to_batch_messages_is_the_frame_of_every_message(sim_msgs):
    """The node's ``frame_id`` parameter reaches ``BatchMessages``: tables and state carry it;
    without it (None or ''), the scene's sensor frame."""
    scene, sim, _ = sim_msgs
    b = sim.advance(15)
    for given, frame in (("rig/left", "rig/left"), (None, scene.sensor.frame_id), ("", scene.sensor.frame_id)):
        msgs = BatchMessages(sim, start_ns=0, frame_id=given)
        got = [msgs.accel(b).header.frame_id, msgs.contact_forces(b).header.frame_id,
               msgs.state(0).header.frame_id]
        assert got == [frame] * 3, given
    assert scene.sensor.frame_id != "rig/left"


def test_each_dependency_is_defined_once():
    """rosbag2's format lists every type the message needs once: WrenchStamped uses Vector3 twice
    (force and torque) and DiagnosticArray a Header and KeyValue inside DiagnosticStatus; each
    ``MSG:`` section names a distinct type, and together exactly the types rosbags finds needed."""
    from rosbags.typesys import get_types_from_msg

    for msg_type in sorted(set(TYPES.values())):
        text = message_definition(msg_type)
        sections = [line[len("MSG: "):] for line in text.splitlines() if line.startswith("MSG: ")]
        assert len(sections) == len(set(sections)), (msg_type, sections)
        assert set(sections) == set(get_types_from_msg(text, msg_type)) - {msg_type}, msg_type
    assert message_definition("geometry_msgs/msg/WrenchStamped").count("MSG: geometry_msgs/msg/Vector3") == 1


@pytest.mark.parametrize("avoid", [False, True])
def test_avoid_ros_namespace_conventions_is_recorded_as_offered(tmp_path, avoid):
    """A publisher with ``avoid_ros_namespace_conventions`` true is outside the ROS namespace
    (no ``rt/`` prefix) and no ROS subscriber matches it: a recording that said true for the
    node's topics would make ``play`` and ``ros2 bag play`` publish where nobody listens.  The
    file says what was offered (rosbags reads it) and ``play``'s reader gives it back."""
    from rclpy.qos import QoSProfile
    from rosbags.highlevel import AnyReader
    from std_msgs.msg import Float64

    path = tmp_path / "avoid.mcap"
    with Recorder(path, {"a": "b"}) as rec:
        rec.add_topic("/x", "std_msgs/msg/Float64", QoSProfile(depth=3, avoid_ros_namespace_conventions=avoid))
        rec.write("/x", Float64(data=1.0), 1)
    with AnyReader([path]) as reader:
        (conn,) = reader.connections
        assert conn.ext.offered_qos_profiles[0].avoid_ros_namespace_conventions is avoid
    with open_recording(path) as r:
        (info,) = r.channels.values()
    assert qos_from_yaml(info.qos_yaml).avoid_ros_namespace_conventions is avoid


# offered_qos_profiles as rosbag2 wrote them before Jazzy's metadata version 9: enum values as
# integers (history 3 = unknown, as discovery reports it), depth 0, and the infinite durations as
# Foxy (2147483647 s + 4294967295 ns) or Humble (rmw's 9223372036 s + 854775807 ns) wrote them
_ROSBAG2_INTEGER_QOS = """- history: 3
  depth: 0
  reliability: {reliability}
  durability: {durability}
  deadline:
    sec: {sec}
    nsec: {nsec}
  lifespan:
    sec: {sec}
    nsec: {nsec}
  liveliness: 1
  liveliness_lease_duration:
    sec: {sec}
    nsec: {nsec}
  avoid_ros_namespace_conventions: false"""


@pytest.mark.parametrize("reliability, durability, sec, nsec",
                         [(1, 1, 2147483647, 4294967295), (2, 2, 9223372036, 854775807)],
                         ids=["latched_foxy", "sensor_humble"])
def test_qos_of_older_rosbag2_recordings_is_read_as_it_was_offered(reliability, durability, sec, nsec):
    """``play`` publishes with the recorded profile: from an older rosbag2 file's integers a
    latched topic (reliable, transient local) stays latched and a sensor topic (best effort,
    volatile) stays best effort; 'unknown' history becomes keep-last (a publisher cannot be
    created with 'unknown'); the infinite durations become 'none' (0), not centuries."""
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, ReliabilityPolicy

    q = qos_from_yaml(_ROSBAG2_INTEGER_QOS.format(reliability=reliability, durability=durability,
                                                  sec=sec, nsec=nsec))
    assert q.reliability == {1: ReliabilityPolicy.RELIABLE, 2: ReliabilityPolicy.BEST_EFFORT}[reliability]
    assert q.durability == {1: DurabilityPolicy.TRANSIENT_LOCAL, 2: DurabilityPolicy.VOLATILE}[durability]
    assert q.history == HistoryPolicy.KEEP_LAST and q.depth == 10
    assert q.liveliness == LivelinessPolicy.AUTOMATIC
    assert q.deadline == q.lifespan == q.liveliness_lease_duration == Duration()
    assert q.avoid_ros_namespace_conventions is False


def test_messages_come_back_in_log_time_order_with_their_counts(tmp_path):
    """``Recording.messages`` yields in log-time order even when the messages were written out of
    it (the recorder takes log times as given, and a file from another writer need not be sorted;
    ``play`` paces by this order), and each channel's count (report's and run's per-topic figures)
    is the number of messages rosbags finds."""
    from rosbags.highlevel import AnyReader
    from std_msgs.msg import Float64

    path = tmp_path / "order.mcap"
    times = {"/a": [30, 10, 50, 20], "/b": [40, 5]}
    with Recorder(path, {"a": "b"}) as rec:
        for topic in times:
            rec.add_topic(topic, "std_msgs/msg/Float64", 10)
        for k in range(4):
            for topic, ts in times.items():
                if k < len(ts):
                    rec.write(topic, Float64(data=float(ts[k])), ts[k])
    with open_recording(path) as r:
        got = [(t, topic) for topic, _type, t, _data in r.messages()]
        counts = {c.topic: c.count for c in r.channels.values()}
    assert got == sorted((t, topic) for topic, ts in times.items() for t in ts)
    with AnyReader([path]) as reader:
        found = {}
        for conn, _t, _raw in reader.messages():
            found[conn.topic] = found.get(conn.topic, 0) + 1
    assert counts == found == {"/a": 4, "/b": 2}


def test_a_rotated_file_that_would_replace_what_is_not_a_recording_stops_the_recording(tmp_path, sim_msgs):
    """Each file is checked as it is opened: ``rot_001.mcap`` made someone's notes while the
    first file is written, the recording stops there with one line in ``status`` that names the
    argument's value and the file, and the notes are kept."""
    scene, sim, msgs = sim_msgs
    base = tmp_path / "rot.mcap"
    rec = Recorder(base, {"a": "b"}, rotate_seconds=0.1)
    rec.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    rotated_path(base, 1).write_text("not a recording\n")
    for _ in range(40):
        b = sim.advance(150)
        rec.write("accel", msgs.accel(b), msgs.stamp_ns(b.index0 + b.n))
    rec.close()
    st = rec.status
    assert not st["ok"] and "\n" not in st["error"]
    assert f"record = '{base}' (file {rotated_path(base, 1)}): exists and is not an MCAP recording" in st["error"]
    assert rotated_path(base, 1).read_text() == "not a recording\n"
    with open_recording(rotated_path(base, 0)) as r:                   # the first file is complete
        assert r.metadata["file_index"] == "0"


def test_a_split_recording_never_mixes_with_the_pieces_of_an_earlier_one(tmp_path, sim_msgs):
    """A split recording to ``rot.mcap`` where ``rot_000.mcap`` .. ``rot_009.mcap`` of an earlier
    one lie would replace the first few and leave the rest beside them as if they followed: it
    is refused in one line before anything is written, and the earlier pieces stay as they were.
    One file (no split) to that name is not concerned; a piece that is not an MCAP file (notes)
    is refused alike."""
    scene, sim, msgs = sim_msgs
    base = tmp_path / "rot.mcap"
    _record(base, scene, sim, msgs, batches=100, rotate_seconds=0.1)
    earlier = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert len(earlier) == 10
    with pytest.raises(UserError, match=rf"^record = '{base}': {rotated_path(base, 0)} and 9 more exist, and a "
                                        r"split recording does not replace .*give another path or remove them first$"):
        Recorder(base, {"a": "b"}, rotate_seconds=0.1)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == earlier
    Recorder(base, {"a": "b"}).close()                                 # one file: rot.mcap
    notes = tmp_path / "notes_000.mcap"
    notes.write_text("my notes\n")
    with pytest.raises(UserError, match=rf"notes.mcap': {notes} exists, "):
        Recorder(tmp_path / "notes.mcap", {"a": "b"}, rotate_bytes=10**6)
    assert notes.read_text() == "my notes\n"


def test_an_empty_file_is_said_to_be_empty(tmp_path):
    """The last piece of a split recording killed hard is often empty (its first bytes were still
    in the writer's buffer): the reader said it was "not an MCAP file ... expected a recording made
    by the node's record", which it is."""
    empty = tmp_path / "run_004.mcap"
    empty.write_bytes(b"")
    with pytest.raises(UserError, match=rf"^{empty}: empty file \(0 bytes\): its writer wrote nothing to it "
                                        r"before it stopped, e\.g\. the last file of a recording killed hard"):
        open_recording(empty)


@pytest.mark.parametrize("offset", [53, 60])
def test_a_chunk_that_does_not_decompress_is_a_corrupt_recording(tmp_path, offset):
    """A byte flipped in a chunk's compressed data (its zstd frame header, or the data) fails to
    decompress before the chunk's CRC is checked: report and play ended with a ZstdError traceback
    and "internal error" (exit 1) where every other damage is one line, exit 2."""
    from mcap.reader import SeekingReader

    from bearing_sim_ros.recording.render import render

    path = tmp_path / "run.mcap"
    render("er16k_outer_race", 0.2, path, fidelity="kinematic", progress=False)
    data = bytearray(path.read_bytes())
    with open(path, "rb") as f:
        chunk = SeekingReader(f).get_summary().chunk_indexes[0]
    # 53 bytes into a zstd chunk record: its compressed records begin (opcode, lengths, times, CRC,
    # the compression's name)
    data[chunk.chunk_start_offset + offset] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(UserError, match=rf"^{path}: corrupt MCAP recording \(ZstdError: "):
        with open_recording(path) as rec:
            for _ in rec.messages():
                pass


def test_the_first_file_is_checked_before_anything_is_written(tmp_path):
    kept = tmp_path / "scene.yaml"
    kept.write_text("name: x\n")
    with pytest.raises(UserError, match=r"^record = '.*scene.yaml': is the scene's own file"):
        Recorder(kept, {"a": "b"}, keep=[str(kept)])
    with pytest.raises(UserError, match="exists and is not an MCAP recording"):
        Recorder(kept, {"a": "b"})
    assert kept.read_text() == "name: x\n"


def test_a_second_recording_into_one_named_pipe_is_refused(tmp_path):
    """Two renders given one named pipe as --out both wrote into it and both exited 0: its reader
    got their bytes interleaved, a corrupt file (``report``: RecordLengthLimitExceeded).  The
    second is refused at start as for a file; the pipe is free again once the first is done."""
    import os

    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)     # there, so that the writers' opens go through
    try:
        first = Recorder(fifo, {"a": "b"}, argument="--out", replace_when_done=True)
        with pytest.raises(UserError) as refused:
            Recorder(fifo, {"a": "b"}, argument="--out", replace_when_done=True)
        assert str(refused.value) == (f"--out = '{fifo}': another recording is being written to this file (two "
                                      "renders, nodes or runs given the same path?); give each its own, or wait "
                                      "until the other ends")
        first.discard()
        Recorder(fifo, {"a": "b"}, argument="--out").discard()
    finally:
        os.close(reader)
    assert [p.name for p in tmp_path.iterdir()] == ["pipe.mcap"]


def test_replace_when_done_moves_each_finished_file_onto_its_name(tmp_path, sim_msgs):
    """``replace_when_done`` (render's): the files are written as ``<name>.<pid>.partial`` and
    moved onto their names once finalised, rotation included; ``discard`` removes the partial file
    and leaves what the name held."""
    scene, sim, msgs = sim_msgs
    base = tmp_path / "rot.mcap"
    rec, _sent = _record(base, scene, sim, msgs, batches=40, rotate_seconds=0.25, replace_when_done=True)
    assert rec.status["ok"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rot_000.mcap", "rot_001.mcap"]
    for k in range(2):
        with open_recording(rotated_path(base, k)) as r:
            assert r.metadata["file_index"] == str(k)
    earlier = rotated_path(base, 0).read_bytes()
    one = tmp_path / "rot_000.mcap"
    rec = Recorder(one, {"a": "b"}, replace_when_done=True)
    rec.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    rec.write("accel", msgs.accel(sim.advance(150)), 0)
    assert one.read_bytes() == earlier                           # untouched while written
    rec.discard()
    assert one.read_bytes() == earlier
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rot_000.mcap", "rot_001.mcap"]



@pytest.mark.parametrize("when_full", ["drop", "wait"])
def test_a_writer_that_falls_behind_costs_counted_messages_or_holds_the_producer_up(tmp_path, when_full):
    """A burst of 100 writes against a queue limit of 5 messages (60 bytes of CDR): the writer
    thread, which sleeps 20 ms whenever it finds the queue empty, falls behind for real.  "drop"
    (the live node's) loses messages and counts exactly those it lost; "wait" (render's) holds the
    producer up and loses none.  The file reads back with rosbags: every message sent, or those
    not dropped, in the order sent."""
    from rosbags.highlevel import AnyReader
    from std_msgs.msg import Float64

    path = tmp_path / "burst.mcap"
    with Recorder(path, {"a": "b"}, when_full=when_full, max_queue_bytes=60) as rec:
        rec.add_topic("/x", "std_msgs/msg/Float64", 10)
        for k in range(100):
            rec.write("/x", Float64(data=float(k)), k)
    with AnyReader([path]) as reader:
        kept = [reader.deserialize(raw, conn.msgtype).data for conn, _t, raw in reader.messages()]
    st = rec.status
    assert st["ok"] and st["messages"] == len(kept), st
    if when_full == "wait":
        assert st["dropped"] == 0 and kept == list(range(100))
    else:
        assert st["dropped"] == 100 - len(kept) > 0, st
        assert kept == sorted(set(kept)) and set(kept) <= set(range(100))


def _until(predicate, timeout: float = 10.0):
    end = time.monotonic() + timeout
    while not predicate() and time.monotonic() < end:
        time.sleep(0.01)
    return predicate()


def _write_batches(rec, sim, msgs, batches: int) -> None:
    for _ in range(batches):
        b = sim.advance(150)
        rec.write("accel", msgs.accel(b), msgs.stamp_ns(b.index0 + b.n))


def test_a_file_deleted_while_it_is_written_stops_the_recording_while_it_runs(tmp_path, sim_msgs, monkeypatch):
    """Writing into a file that was deleted fails no write: the recording went on into a file
    nobody would find, and ``status`` said ok to the end.  The writer thread compares the open
    file with its path every ``CHECK_PATH_S``: the recording stops with one line naming the path
    while it runs, as on a full disk, and later messages are counted as dropped."""
    from bearing_sim_ros.recording import recorder

    monkeypatch.setattr(recorder, "CHECK_PATH_S", 0.02)
    scene, sim, msgs = sim_msgs
    path = tmp_path / "run.mcap"
    rec = Recorder(path, {"a": "b"})
    rec.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    _write_batches(rec, sim, msgs, 20)
    path.unlink()
    assert _until(lambda: rec.error), rec.status                  # noticed before close
    assert rec.error == f"recording to {path} stopped: the file was deleted while it was written"
    _write_batches(rec, sim, msgs, 5)
    rec.close()
    st = rec.status
    assert not st["ok"] and st["dropped"] >= 5 and st["messages"] + st["dropped"] == 25, st
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("how", ["file", "folder", "replaced"])
def test_a_file_no_longer_at_its_path_when_finalised_is_an_error(tmp_path, sim_msgs, monkeypatch, how):
    """Deleted, its folder deleted, or replaced by another file just before ``close`` (no check
    on the way): finalising says so instead of success, and leaves the other file alone."""
    from bearing_sim_ros.recording import recorder

    monkeypatch.setattr(recorder, "CHECK_PATH_S", 1e9)
    scene, sim, msgs = sim_msgs
    folder = tmp_path / "runs"
    folder.mkdir()
    path = folder / "run.mcap"
    rec = Recorder(path, {"a": "b"})
    rec.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    _write_batches(rec, sim, msgs, 20)
    if how == "folder":
        import shutil

        shutil.rmtree(folder)
    else:
        path.unlink()
        if how == "replaced":
            path.write_text("someone else's file\n")
    rec.close()
    why = {"file": "the file was deleted", "folder": f"its folder {folder} was deleted",
           "replaced": "the file was replaced by another file"}[how]
    assert rec.status["error"] == f"recording to {path} stopped: {why} while it was written"
    if how == "replaced":
        assert path.read_text() == "someone else's file\n"


def test_a_partial_file_replaced_while_it_is_written_is_not_moved_onto_the_name(tmp_path, sim_msgs, monkeypatch):
    """``replace_when_done`` (render's): the partial file replaced by another (same name, another
    file) was moved onto the name as if it were the recording.  Now the recording fails, the name
    keeps the earlier recording, and the other file is left where it is."""
    from bearing_sim_ros.recording import recorder

    monkeypatch.setattr(recorder, "CHECK_PATH_S", 1e9)
    scene, sim, msgs = sim_msgs
    path = tmp_path / "run.mcap"
    Recorder(path, {"a": "b"}).close()
    earlier = path.read_bytes()
    rec = Recorder(path, {"a": "b"}, replace_when_done=True)
    rec.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    _write_batches(rec, sim, msgs, 20)
    (partial,) = tmp_path.glob("run.mcap.*.partial")
    partial.unlink()
    partial.write_text("someone else's file\n")
    rec.close()
    assert rec.status["error"] == (f"recording to {path} stopped: its temporary file {partial.name} was "
                                   "replaced by another file while it was written")
    assert path.read_bytes() == earlier and partial.read_text() == "someone else's file\n"


def test_a_file_moved_away_while_it_is_written_is_finished_where_it_went(tmp_path, sim_msgs, monkeypatch):
    """Moved (or its folder moved) is not lost: the recording goes on in it and finalises it
    there, as before (a split recording's next piece then fails to open: test_node.py)."""
    from bearing_sim_ros.recording import recorder

    monkeypatch.setattr(recorder, "CHECK_PATH_S", 0.02)
    scene, sim, msgs = sim_msgs
    path, moved = tmp_path / "run.mcap", tmp_path / "kept.mcap"
    rec = Recorder(path, {"a": "b"})
    rec.add_topic("accel", TYPES["accel"], waveform_qos(0.01))
    _write_batches(rec, sim, msgs, 10)
    path.rename(moved)
    _write_batches(rec, sim, msgs, 10)
    time.sleep(0.1)                       # a few checks on the way
    rec.close()
    assert rec.status["ok"], rec.status
    with open_recording(moved) as r:
        assert sum(1 for _ in r.messages(["/accel"])) == 20


@pytest.fixture(scope="module")
def three_chunks(tmp_path_factory):
    """A 2 s render (three chunks) and its chunk index: (the file's bytes, its messages in log-time
    order, its metadata and attachments, [(chunk start, chunk end)] in bytes, the data end's start)."""
    from mcap.reader import SeekingReader

    from bearing_sim_ros.recording.render import render

    path = tmp_path_factory.mktemp("chunks") / "whole.mcap"
    render("er16k_outer_race", 2.0, path, fidelity="kinematic", seed=4, progress=False)
    with open_recording(path) as rec:
        whole = (list(rec.messages()), rec.metadata, rec.attachments)
    with open(path, "rb") as f:
        summary = SeekingReader(f).get_summary()
        chunks = [(c.chunk_start_offset, c.chunk_start_offset + c.chunk_length) for c in summary.chunk_indexes]
    assert len(chunks) == 3
    return path.read_bytes(), *whole, chunks


def test_a_truncated_recording_is_read_up_to_its_last_complete_chunk(three_chunks, tmp_path):
    """What a kill -9 or a power cut leaves (no footer, no summary) was refused ("`mcap recover` can
    salvage its complete chunks", a tool not installed with this one).  Now it is read as far as it
    goes: the messages of its complete chunks, in the same order as from the whole file, with its
    metadata and attachments, and ``recovered`` says so in one line: what was read, what is lost."""
    data, messages, metadata, attachments, chunks = three_chunks
    cut = tmp_path / "cut.mcap"
    _, (s1, e1), (s2, _e2) = chunks             # each chunk followed by its message index records
    for size, read, lost in [((s1 + e1) // 2, s1, "an incomplete record"),      # inside the second chunk
                             (s2, s2, None),                                     # between two records
                             (s2 + 5, s2, "an incomplete record"),               # inside a record's opcode/length
                             (len(data) - 100, None, "summary")]:                # in the summary section
        cut.write_bytes(data[:size])
        with open_recording(cut) as rec:
            got = list(rec.messages())
            assert got == messages[:len(got)] and len(got) == rec.message_count > 0
            assert sum(c.count for c in rec.topics().values()) == rec.message_count
            assert (rec.start_ns, rec.end_ns) == (got[0][2], max(m[2] for m in got))
            assert (rec.metadata, rec.attachments) == (metadata, attachments)
            assert rec.recovered.startswith(f"{cut}: read as recovered: no footer and no summary (its writer never "
                                            "finished, e.g. a hard kill or a power cut); read up to byte ")
            assert "\n" not in rec.recovered
            assert f"{rec.message_count} messages in its " in rec.recovered
            assert f"{(rec.end_ns - rec.start_ns) * 1e-9:.2f} s of log time" in rec.recovered
            if lost == "summary":
                assert len(got) == len(messages)
                assert rec.recovered.endswith("its data section complete, only the summary lost")
            elif lost is None:
                # the first two chunks' messages and span (they depend on the messages' sizes)
                in_two_chunks = (f"{len(got)} messages in its 2 complete chunks, "
                                 f"{(rec.end_ns - rec.start_ns) * 1e-9:.2f} s of log time")
                assert len(got) < len(messages)
                assert rec.recovered.endswith(f"read up to byte {read} of {size}: {in_two_chunks}; it ends after a "
                                              "complete record: what its writer had not written yet is lost")
            else:
                assert f"read up to byte {read} of {size}: " in rec.recovered
                assert rec.recovered.endswith(f"the last {size - read} bytes ({lost}) lost")
    # a power cut: the size grew, the blocks were never written (zeros), after a record or inside
    # a chunk (which then neither decompresses nor checks, and is not corrupt but cut)
    for size, zeros_from in [(s2 + 50_000, s2), (len(data), s2 + 1000)]:
        cut.write_bytes(data[:zeros_from] + bytes(size - zeros_from))
        with open_recording(cut) as rec:
            assert rec.message_count == sum(1 for _ in rec.messages()) and rec.recovered.endswith(
                f"read up to byte {s2} of {size}: {in_two_chunks}; "
                f"the last {size - s2} bytes (zeros: never written, e.g. a power cut) lost")


def test_what_is_not_a_recording_is_still_refused_when_it_is_cut(three_chunks, tmp_path):
    """A file cut inside its first record or chunk holds nothing to read, and a chunk before the
    cut that does not check (CRC, compression) is a corrupt file: read up to it, the chunks after
    it would be lost unsaid.  One line each."""
    data, _messages, _metadata, _attachments, chunks = three_chunks
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:12])
    with pytest.raises(UserError, match=rf"^{cut}: truncated MCAP recording \(12 bytes\): it ends before the end "
                                        r"of its first record, nothing in it to read$"):
        open_recording(cut)
    (s0, e0), (s1, e1), _ = chunks
    cut.write_bytes(data[:(s0 + e0) // 2])
    with pytest.raises(UserError, match=rf"^{cut}: truncated MCAP recording \({(s0 + e0) // 2} bytes, no footer\) "
                                        r"without a complete chunk: no message to read, e\.g\. the last file of a "
                                        r"recording killed hard \(kill -9\) as it began$"):
        open_recording(cut)
    broken = bytearray(data[:(s1 + e1) // 2])
    broken[s0 + 60] ^= 0xFF                            # the first chunk's compressed data
    cut.write_bytes(bytes(broken))
    with pytest.raises(UserError, match=rf"^{cut}: corrupt MCAP recording \((ZstdError|CRCValidationError): "):
        open_recording(cut)
    broken = bytearray(data[:(s1 + e1) // 2])
    broken[s1] = 0x42                                  # the second chunk's opcode: no such record
    cut.write_bytes(bytes(broken))
    with pytest.raises(UserError, match=rf"^{cut}: corrupt MCAP recording \(McapError: no MCAP record has "
                                        rf"opcode 0x42 \(at byte {s1}\)\)$"):
        open_recording(cut)


def test_a_finished_file_without_a_summary_is_read_when_it_is_chunked(tmp_path):
    """Another writer's finished file without a summary section (allowed by MCAP) was refused
    ("`mcap recover` can rebuild it"); its chunks are now read as a truncated file's are, and
    nothing is said lost.  One whose messages are outside chunks is still refused, in one line."""
    import struct

    from mcap.writer import IndexType, Writer

    path = tmp_path / "no_summary.mcap"
    for chunked in (True, False):
        with open(path, "wb") as f:
            writer = Writer(f, index_types=IndexType.NONE, repeat_channels=False, repeat_schemas=False,
                            use_statistics=False, use_summary_offsets=False, use_chunking=chunked)
            writer.start(profile="ros2")
            channel = writer.register_channel("/x", "cdr", writer.register_schema("std_msgs/msg/Float64", "ros2msg",
                                                                                  b"float64 data"))
            for k in range(5):
                writer.add_message(channel, log_time=k * 10**9, data=b"\0\1\0\0" + struct.pack("<d", k),
                                   publish_time=k * 10**9)
            writer.finish()
        if chunked:
            with open_recording(path) as rec:
                assert rec.recovered is None and rec.message_count == 5
                assert [m[2] for m in rec.messages()] == [k * 10**9 for k in range(5)]
        else:
            with pytest.raises(UserError, match=rf"^{path}: MCAP recording without a summary and with its messages "
                                                r"outside chunks \(from byte \d+\): this reader reads only chunked"):
                open_recording(path)


def test_opening_a_truncated_recording_makes_no_message_record(three_chunks, tmp_path, monkeypatch):
    """Opening a file without its footer scans it: every chunk decompressed and checked, to
    count its messages and find their times.  The scan made an mcap Message (its data copied)
    of every message only to read its channel and log time: a quarter of the time to open a cut
    file.
    It reads those where they lie now; the messages are made when they are read."""
    from mcap.records import Message

    data, messages, *_ = three_chunks
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) - 100])
    made = []
    read = Message.read
    monkeypatch.setattr(Message, "read", staticmethod(lambda *args: made.append(1) or read(*args)))
    with open_recording(cut) as rec:
        assert rec.message_count == len(messages) and made == []
        assert list(rec.messages()) == messages and len(made) == len(messages)


def test_sample_times_are_the_index_over_the_rate_to_the_mhz_rounded_down_to_the_ns():
    """``sample_time_ns``: index / rate from the index itself.  1024.1 Hz is 1024100 mHz, though
    1024.1 * 1000 is 1024099.99.. in floating point (taken as 1024099 mHz, sample 10241 came
    9764 ns after 10 s); a day at 15 kHz ends exactly a day on; 1 / 15 kHz = 66666.6 ns is
    66666 ns."""
    from bearing_sim_ros.waveform import NS, sample_time_ns

    assert sample_time_ns(0, 10241, 1024.1) == 10 * NS
    start = 1_700_000_000 * NS
    assert sample_time_ns(start, 15000 * 86400, 15000.0) == start + 86400 * NS
    assert [sample_time_ns(start, k, 15000.0) - start for k in (0, 1, 2, 3)] == [0, 66666, 133333, 200000]


def test_a_table_with_more_data_than_its_width_says_is_not_a_waveform_table(sim_msgs):
    """Data longer than width x point_step (a width that undercounts its samples) is refused in
    the reader's own line, as data shorter is, not numpy's "cannot reshape array"."""
    from bearing_sim_ros.waveform import to_pointcloud2

    _scene, sim, _msgs = sim_msgs
    b = sim.advance(20)
    m = to_pointcloud2(b.accel, ["accel_x", "accel_y"], 0, "f")
    m.width = 19
    with pytest.raises(ValueError, match=r"^not a waveform table: 160 bytes of data, expected width 19 x "
                                         r"point_step 8 = 152$"):
        from_pointcloud2(m)


def test_a_close_that_waits_for_a_pipes_reader_says_what_it_waits_for(tmp_path, capsys):
    """A recording into a pipe whose reader stopped reading (SIGSTOP, a stalled consumer) or onto a
    stalled disk: the node's Ctrl-C waited in ``close`` for as long as it stalled, without a
    word (30 s and more).  The file's end is still waited for, but after ``FINISH_NOTICE_S`` one
    line says what for; and once the reader reads, the recording ends whole."""
    import os
    import threading

    from mcap.reader import make_reader
    from std_msgs.msg import String

    from bearing_sim_ros.recording.recorder import FINISH_NOTICE_S

    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)       # there, but it reads nothing yet
    try:
        rec = Recorder(fifo, {"a": "b"})
        rec.add_topic("/x", "std_msgs/msg/String", 10)
        for i in range(8):              # 1.6 MB that zstd cannot shrink much: more than a pipe holds
            rec.write("/x", String(data=os.urandom(100_000).hex()), i + 1)
        closer = threading.Thread(target=rec.close, daemon=True)
        closer.start()
        said = ""
        deadline = time.monotonic() + FINISH_NOTICE_S + 30
        while "still finishing" not in said and time.monotonic() < deadline:
            said += capsys.readouterr().err
            time.sleep(0.1)
        assert closer.is_alive()
        assert f"recording {fifo}: still finishing after {FINISH_NOTICE_S:g} s (" in said, said
        assert "waiting for the disk, or for the pipe's reader, to take the rest" in said, said
        os.set_blocking(reader, True)
        data = b"".join(iter(lambda: os.read(reader, 1 << 20), b""))
        closer.join(30)
    finally:
        os.close(reader)
    assert not closer.is_alive() and rec.status["ok"], rec.status
    (tmp_path / "copy.mcap").write_bytes(data)
    with open(tmp_path / "copy.mcap", "rb") as f:
        assert make_reader(f).get_summary().statistics.message_count == 8


def test_a_write_that_waits_for_a_stalled_pipe_ends_once_a_stop_is_asked_for(tmp_path):
    """``when_full="wait"`` (render) into a pipe whose reader stopped reading: once the queue was
    full, ``write`` waited for the reader, and render's Ctrl-C and SIGTERM (only noted, acted on
    at the batch's end) were not heard: 30 s after a Ctrl-C the render still ran, without a word.
    ``stopped()`` now ends the wait; the message is queued all the same, and the file comes out
    whole once the reader reads."""
    import os
    import threading

    from mcap.reader import make_reader
    from std_msgs.msg import String

    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)       # there, but it reads nothing yet
    stop = threading.Event()
    written = []
    try:
        rec = Recorder(fifo, {"a": "b"}, when_full="wait", max_queue_bytes=1_000_000, stopped=stop.is_set)
        rec.add_topic("/x", "std_msgs/msg/String", 10)

        def produce():
            for i in range(40):         # 8 MB that zstd cannot shrink much: the queue fills
                rec.write("/x", String(data=os.urandom(100_000).hex()), i + 1)
                written.append(i)

        producer = threading.Thread(target=produce, daemon=True)
        producer.start()
        before = -1
        while len(written) != before:   # until it stops making progress: waiting on the full queue
            before = len(written)
            producer.join(1.0)
        assert producer.is_alive() and len(written) < 40, len(written)
        stop.set()
        producer.join(10)
        assert not producer.is_alive(), "write still waits after the stop"
        closer = threading.Thread(target=rec.close, daemon=True)
        closer.start()
        os.set_blocking(reader, True)
        data = b"".join(iter(lambda: os.read(reader, 1 << 20), b""))
        closer.join(30)
    finally:
        os.close(reader)
    assert rec.status["ok"] and rec.status["dropped"] == 0, rec.status
    (tmp_path / "copy.mcap").write_bytes(data)
    with open(tmp_path / "copy.mcap", "rb") as f:
        assert make_reader(f).get_summary().statistics.message_count == 40


def test_a_file_whose_folder_moved_as_it_was_opened_is_no_other_writers(tmp_path):
    """The recorder refuses a file that another writer put at its name between its open and its
    check (a render finishing meanwhile), but a name that is simply gone (the folder moved, the
    file deleted, just as a split recording's piece was opened: CI caught a node test there) is no
    other writer: the recording goes on into the open file.  It said "another recording is being
    written to this file (two renders, nodes or runs given the same path?)"."""
    from bearing_sim_ros.recording.recorder import _replaced

    folder = tmp_path / "runs"
    folder.mkdir()
    path = folder / "run_001.mcap"
    fd = os.open(path, os.O_WRONLY | os.O_CREAT)
    try:
        assert not _replaced(path, fd)
        folder.rename(tmp_path / "moved")              # gone from its name: nobody else's
        assert not _replaced(path, fd)
        folder.mkdir()
        other = folder / "other.mcap"
        other.write_bytes(b"")
        os.replace(other, path)                         # another file moved onto the name
        assert _replaced(path, fd)
    finally:
        os.close(fd)


def test_a_piece_of_a_split_recording_that_rotates_as_it_is_looked_at_is_still_refused(tmp_path):
    """A render or a node given a finished piece (``run_001.mcap``) of a split recording still
    running is refused (``_later_piece_held``: a later piece is held).  The writer rotates as it
    is looked at: it closes its piece (the lock goes) and then makes and holds the next one, and a
    held piece is tried for about 40 ms, so a look that began on ``run_002`` found it free and
    missed ``run_003``: a CI run's node replaced ``run_001.mcap`` of a recording that split every
    0.5 s.  Here the writer (a thread with its own locks) rotates 15 ms into the look."""
    import fcntl

    from bearing_sim_ros.recording.recorder import _later_piece_held

    for i in range(3):
        (tmp_path / f"run_{i:03d}.mcap").write_bytes(b"")
    held = os.open(tmp_path / "run_002.mcap", os.O_RDONLY)
    fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
    fds = [held]

    def rotate():
        fd = os.open(tmp_path / "run_003.mcap", os.O_RDWR | os.O_CREAT)
        os.close(held)                                  # the old piece closed first, as _maybe_rotate
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        fds.append(fd)

    timer = threading.Timer(0.015, rotate)
    timer.start()
    try:
        found = _later_piece_held(tmp_path / "run_001.mcap")
    finally:
        timer.join()
        for fd in fds[1:]:
            os.close(fd)
    assert found is not None and found.name in ("run_002.mcap", "run_003.mcap"), found
    # the recording over (nothing held): a finished piece may be replaced, as any recording
    assert _later_piece_held(tmp_path / "run_001.mcap") is None
