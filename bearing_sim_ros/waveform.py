"""The waveform-table convention (INTERFACE.md) for ``accel`` and ``contact_forces``.

A batch of ``n`` samples of ``c`` channels is a ``sensor_msgs/msg/PointCloud2`` with height 1,
width n, one FLOAT32 ``PointField`` per channel, point_step 4c, little-endian, sample-major,
is_dense true; ``header.stamp`` is the time of sample 0.  Stamps come from the absolute sample
index, so consecutive batches are contiguous to the nanosecond with no drift.

Everything here works on whole arrays: no per-sample Python objects.
"""
from __future__ import annotations

import numpy as np

NS = 1_000_000_000


def sample_time_ns(start_ns: int, index: int, sample_rate: float) -> int:
    """Time (ns) of sample ``index`` counted from ``start_ns``: index / sample_rate (the rate
    taken to the mHz) rounded down to the ns, from the index each time (never accumulating)."""
    return int(start_ns) + (int(index) * NS * 1000 // int(round(sample_rate * 1000)))


def make_fields(channels):
    from sensor_msgs.msg import PointField

    return [PointField(name=name, offset=4 * k, datatype=PointField.FLOAT32, count=1)
            for k, name in enumerate(channels)]


def to_pointcloud2(data: np.ndarray, channels, stamp_ns: int, frame_id: str, fields=None):
    """A waveform table from an (n, c) array.  ``fields`` may be a cached ``make_fields``."""
    from sensor_msgs.msg import PointCloud2

    arr = np.ascontiguousarray(data, dtype="<f4")
    n, c = arr.shape
    msg = PointCloud2()
    msg.header.stamp.sec = int(stamp_ns // NS)
    msg.header.stamp.nanosec = int(stamp_ns % NS)
    msg.header.frame_id = frame_id
    msg.height = 1
    msg.width = n
    msg.fields = fields if fields is not None else make_fields(channels)
    msg.is_bigendian = False
    msg.point_step = 4 * c
    msg.row_step = 4 * c * n
    msg.data = arr.tobytes()
    msg.is_dense = True
    return msg


FLOAT32 = 7        # sensor_msgs/msg/PointField.FLOAT32, without importing the message here


def from_pointcloud2(msg) -> tuple:
    """(stamp_ns, channel names, (n, c) float32 array) from a waveform table.

    Accepts any object with the PointCloud2 attributes (an rclpy message or a ``rosbags``
    deserialised one).  Each column is the field at its own offset, in the order of ``fields``
    (a table whose offsets are not in field order is still read right).  Anything that is not a
    waveform table (big-endian, more than one row, a field that is not one FLOAT32, offsets that
    are not 4 bytes per channel, a data length that is not width x point_step) is a ValueError
    of one line, not numbers read wrongly."""
    names = [f.name for f in msg.fields]
    c = len(names)
    width = int(msg.width)
    # the fields' type first: a FLOAT64 table's point_step is not 4 x channels either, and that
    # was all its reason said
    bad = [f.name for f in msg.fields if f.datatype != FLOAT32 or f.count != 1]
    if bad:
        raise ValueError(f"not a waveform table: field(s) {', '.join(bad)} not one FLOAT32 each")
    if msg.point_step != 4 * c or msg.is_bigendian or msg.height != 1:
        raise ValueError(f"not a waveform table: point_step {msg.point_step}, channels {c}, "
                         f"height {msg.height}, big-endian {msg.is_bigendian}")
    offsets = [int(f.offset) for f in msg.fields]
    if sorted(offsets) != list(range(0, 4 * c, 4)):
        raise ValueError(f"not a waveform table: field offsets {offsets}, expected 0, 4, .. {4 * c - 4} "
                         "in any order")
    raw = msg.data
    buf = raw.tobytes() if hasattr(raw, "tobytes") else bytes(raw)
    if len(buf) != width * 4 * c:
        raise ValueError(f"not a waveform table: {len(buf)} bytes of data, expected width {width} x "
                         f"point_step {4 * c} = {width * 4 * c}")
    arr = np.frombuffer(buf, dtype="<f4").reshape(width, c)
    if offsets != list(range(0, 4 * c, 4)):
        arr = arr[:, [o // 4 for o in offsets]]
    stamp = msg.header.stamp
    return int(stamp.sec) * NS + int(stamp.nanosec), names, arr
