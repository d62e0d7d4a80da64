"""Reading recordings back (``play`` and ``report``): a checked MCAP file, its channels, the
``bearing_sim`` metadata and its messages in log-time order.

Every problem with the file is a :class:`~bearing_sim_ros.errors.UserError` of one line: no such
file, an empty file, not an MCAP file, a truncated file (no footer: the writer never finished,
e.g. the process was killed hard), a corrupt chunk, a file that is not a ROS 2 recording.
"""
from __future__ import annotations

import importlib
import os
from dataclasses import dataclass

from ..errors import UserError
from ..paths import input_file

MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class ChannelInfo:
    topic: str
    msg_type: str          # 'sensor_msgs/msg/PointCloud2'
    qos_yaml: str          # offered_qos_profiles
    count: int


def get_message(msg_type: str):
    """The rclpy message class of 'pkg/msg/Type' (what rosidl_runtime_py's get_message does)."""
    parts = msg_type.split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3:
        raise UserError(f"message type {msg_type!r}: expected 'package/msg/Type'")
    pkg, kind, name = parts
    try:
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ImportError, AttributeError):
        raise UserError(f"message type {msg_type!r} is not installed in this environment "
                        f"(pip install ros-jazzy-{pkg.replace('_', '-')})") from None


class Recording:
    """An opened, checked MCAP recording.  Use as a context manager or call :meth:`close`."""

    def __init__(self, path):
        from mcap.reader import SeekingReader

        name = str(path)
        self.path = input_file(path, name, "expected an .mcap recording")
        size = self.path.stat().st_size
        try:
            self._stream = open(self.path, "rb")  # noqa: SIM115 - closed in close()
        except OSError as exc:
            raise UserError(f"{name}: cannot read it ({exc.strerror})") from None
        try:
            head = self._stream.read(8)
            if size == 0:
                # what a hard kill leaves of the file just begun (a split recording's last piece):
                # "not an MCAP file ... expected a recording made by the node" said the opposite
                raise UserError(f"{name}: empty file (0 bytes): its writer wrote nothing to it before it "
                                "stopped, e.g. the last file of a recording killed hard (kill -9)")
            if head != MAGIC:
                raise UserError(f"{name}: not an MCAP file (it does not start with the MCAP magic); "
                                "expected a recording made by `bearing-sim render` or the node's `record`")
            self._stream.seek(max(0, size - 8))
            if size < 16 or self._stream.read(8) != MAGIC:
                raise UserError(f"{name}: truncated MCAP recording ({size} bytes, no footer: the writer "
                                "never finished, e.g. a hard kill); `mcap recover` can salvage its complete chunks")
            self._stream.seek(0)
            self._reader = SeekingReader(self._stream, validate_crcs=True)
            try:
                header = self._reader.get_header()
                summary = self._reader.get_summary()
                metas = list(self._reader.iter_metadata())
                self.attachments = {a.name: a.data for a in self._reader.iter_attachments()}
            except Exception as exc:  # noqa: BLE001 - any failure to parse is a corrupt file
                raise UserError(f"{name}: corrupt MCAP recording ({exc.__class__.__name__}: "
                                f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None
            if header.profile != "ros2":
                raise UserError(f"{name}: MCAP profile {header.profile!r} is not 'ros2': not a ROS 2 recording")
            if summary is None:
                raise UserError(f"{name}: MCAP recording without a summary section; "
                                "`mcap recover` can rebuild it")
            stats = summary.statistics
            if stats is not None and sum(stats.channel_message_counts.values()) == stats.message_count:
                counts = stats.channel_message_counts
                self.message_count = int(stats.message_count)
                self.start_ns, self.end_ns = int(stats.message_start_time), int(stats.message_end_time)
            else:
                # the statistics record is optional in MCAP: without it (another writer's file)
                # the counts and times were 0, and play said "holds no messages" of one with some
                counts, self.message_count, self.start_ns, self.end_ns = self._count()
        except BaseException:
            self._stream.close()
            raise
        self.header = header
        self.summary = summary
        self.metadata = {}
        for m in metas:
            if m.name == "bearing_sim":
                self.metadata = dict(m.metadata)
        self.channels = {}
        for cid, ch in summary.channels.items():
            schema = summary.schemas.get(ch.schema_id)
            self.channels[cid] = ChannelInfo(ch.topic, schema.name if schema else "",
                                             ch.metadata.get("offered_qos_profiles", ""),
                                             int(counts.get(cid, 0)))

    def _count(self) -> tuple:
        """({channel id: messages}, messages, first log time ns, last log time ns) read from the
        messages themselves; times 0 without any."""
        counts, first, last = {}, None, None
        for _, _, channel_id, log_ns, _ in self._records():
            counts[channel_id] = counts.get(channel_id, 0) + 1
            first = log_ns if first is None else min(first, log_ns)
            last = log_ns if last is None else max(last, log_ns)
        return counts, sum(counts.values()), first or 0, last or 0

    # -----------------------------------------------------------------------------------------
    def topics(self) -> dict:
        """topic -> ChannelInfo."""
        return {c.topic: c for c in self.channels.values()}

    def messages(self, topics=None):
        """(topic, msg_type, log_time_ns, CDR bytes) in log-time order."""
        for topic, msg_type, _, log_ns, data in self._records(topics, log_time_order=True):
            yield topic, msg_type, log_ns, data

    def _records(self, topics=None, log_time_order=False):
        """(topic, msg_type, channel id, log_time_ns, CDR bytes) of the messages; a damaged file
        is a one-line UserError."""
        from mcap.exceptions import McapError

        try:
            for schema, channel, msg in self._reader.iter_messages(topics=topics, log_time_order=log_time_order):
                yield channel.topic, (schema.name if schema else ""), channel.id, int(msg.log_time), msg.data
        except (McapError, ValueError, KeyError, EOFError) as exc:
            raise UserError(f"{self.path}: corrupt MCAP recording ({exc.__class__.__name__}: "
                            f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None

    def parameters(self) -> dict:
        import json

        try:
            return json.loads(self.metadata.get("parameters", "{}"))
        except ValueError:
            return {}

    def close(self) -> None:
        self._stream.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def open_recording(path) -> Recording:
    """Open and check ``path`` (see :class:`Recording`)."""
    return Recording(os.fspath(path))
