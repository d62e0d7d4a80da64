"""Reading recordings back (``play`` and ``report``): a checked MCAP file, its channels, the
``bearing_sim`` metadata and its messages in log-time order; or the pieces of a split recording
(``run_000.mcap``, ``run_001.mcap``, ...: the node's ``record_max_duration`` /
``record_max_size``) read as one (:class:`SplitRecording`).

A truncated file (no footer and no summary: its writer never finished, e.g. the process was
killed hard or the machine lost power) is read as far as it goes, up to its last complete chunk,
and says so in ``recovered`` (one line: what was read, what is lost), which the commands print.
A file that a recording still being written holds (``recorder.being_written``: the node's file
while it runs) is read the same way, and ``recovered`` says that it is still being written.

Every problem with the file is a :class:`~bearing_sim_ros.errors.UserError` of one line: no such
file, an empty file, not an MCAP file, a file cut before its first chunk ends, a corrupt chunk
(also one before the cut of a truncated file: it is not skipped), a file that is not a ROS 2
recording; and of several files, one that is not a piece of a split recording, pieces of
different recordings, a piece missing between two given, a piece given twice, a truncated piece
before the last.
"""
from __future__ import annotations

import importlib
import os
from dataclasses import dataclass

from ..errors import UserError
from ..paths import input_file
from .recorder import FILE_INDEX, being_written, existing_pieces

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
    if kind != "msg":
        # rclpy's RuntimeError ("this might be a service or action") was a traceback
        raise UserError(f"message type {msg_type!r} is a {'service' if kind == 'srv' else kind}, not a message; "
                        "expected 'package/msg/Type'")
    try:
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ImportError, AttributeError):
        raise UserError(f"message type {msg_type!r} is not installed in this environment "
                        f"(pip install ros-jazzy-{pkg.replace('_', '-')})") from None


def deserialize(path, topic: str, msg_type: str, log_ns: int, data: bytes, cls):
    """The message of ``cls`` (of ``msg_type``) in ``data``, recorded on ``topic`` at ``log_ns`` in
    ``path``; bytes that are not that type (a damaged file whose CRCs still pass, another writer's
    under the type's name) are a one-line UserError naming the message, not rclpy's RMWError
    traceback."""
    from rclpy.serialization import deserialize_message

    try:
        return deserialize_message(data, cls)
    except Exception as exc:  # noqa: BLE001 - rclpy's RMWError, or a plain RuntimeError
        reason = (str(exc).splitlines() or [""])[0] or "unreadable"
        raise UserError(f"{path}: the {msg_type} on {topic} logged at {log_ns * 1e-9:.9f} s does not deserialize as "
                        f"that type ({exc.__class__.__name__}: {reason}); a damaged recording or another "
                        "writer's") from None


def _not_written_yet(name: str, size: int) -> UserError:
    """The line for a file that a recording still being written holds (``being_written``) before
    its first chunk is complete: said as such, not as the file of a writer killed as it began."""
    return UserError(f"{name}: a recording still being written holds it, and it has no complete chunk yet "
                     f"({size} bytes): no message to read yet; try again in a few seconds, or once its "
                     "writer ends")


class Recording:
    """An opened, checked MCAP recording.  Use as a context manager or call :meth:`close`.

    ``recovered``: None for a finished file; for a truncated one (no footer), the line that says
    it was read up to its last complete record and what is lost (its counts and times are those
    of the messages read)."""

    def __init__(self, path):
        from mcap.reader import SeekingReader

        name = str(path)
        self.path = input_file(path, name, "expected an .mcap recording")
        self.paths = [self.path]           # as SplitRecording's: the files read
        self.notes: list = []              # as SplitRecording's: none left out
        size = self.path.stat().st_size
        try:
            self._stream = open(self.path, "rb")  # noqa: SIM115 - closed in close()
        except OSError as exc:
            raise UserError(f"{name}: cannot read it ({exc.strerror})") from None
        try:
            head = self._stream.read(8)
            if (size == 0 or head != MAGIC) and MAGIC.startswith(head) and being_written(self.path):
                raise _not_written_yet(name, size)      # its writer's first bytes still in its buffer
            if size == 0:
                # what a hard kill leaves of the file just begun (a split recording's last piece):
                # "not an MCAP file ... expected a recording made by the node" said the opposite
                raise UserError(f"{name}: empty file (0 bytes): its writer wrote nothing to it before it "
                                "stopped, e.g. the last file of a recording killed hard (kill -9)")
            if head != MAGIC:
                raise UserError(f"{name}: not an MCAP file (it does not start with the MCAP magic); "
                                "expected a recording made by `bearing-sim render` or the node's `record`")
            self._stream.seek(max(0, size - 8))
            finished = size >= 16 and self._stream.read(8) == MAGIC
            self._stream.seek(0)
            self.recovered = None          # what a truncated file lost (read up to its last complete record)
            if finished:
                self._reader = SeekingReader(self._stream, validate_crcs=True)
                try:
                    header = self._reader.get_header()
                    summary = self._reader.get_summary()
                    metas = list(self._reader.iter_metadata())
                    self.attachments = {a.name: a.data for a in self._reader.iter_attachments()}
                except Exception as exc:  # noqa: BLE001 - any failure to parse is a corrupt file
                    raise UserError(f"{name}: corrupt MCAP recording ({exc.__class__.__name__}: "
                                    f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None
            if not finished or summary is None:
                # no footer (a hard kill, a power cut: the summary is written last), or another
                # writer's file without a summary: its records read in file order, up to the
                # last complete one (what `mcap recover` salvages, without that tool)
                scan = _scan(self._stream, size, name)
                header, summary, metas, self.attachments = scan.header, scan.summary, scan.metas, scan.attachments
                self._reader = _indexed_reader(self._stream, summary)
                writing = not finished and being_written(self.path)    # a node or `run` recording to it now
                if not finished and not summary.chunk_indexes:
                    # nothing to read, and perhaps not even the metadata that says what it is
                    if writing:
                        raise _not_written_yet(name, size)
                    raise UserError(f"{name}: truncated MCAP recording ({size} bytes, no footer) without a complete "
                                    "chunk: no message to read, e.g. the last file of a recording killed hard "
                                    "(kill -9) as it began")
                if not finished:
                    self.recovered = scan.recovered_text(name, size, writing)
            if header.profile != "ros2":
                raise UserError(f"{name}: MCAP profile {header.profile!r} is not 'ros2': not a ROS 2 recording")
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

    def first_and_last(self, topic: str):
        """The first and the last message on ``topic``, in log-time order, each as (log_time_ns,
        CDR bytes), read from the chunks that hold them (not the whole file); None without any."""
        first = self.first(topic)
        return None if first is None else (first, self.last(topic))

    def first(self, topic: str):
        """The first message on ``topic`` in log-time order as (log_time_ns, CDR bytes), read from
        the chunk that holds it; None without any."""
        record = next(self._records([topic], log_time_order=True), None)
        return None if record is None else (record[3], record[4])

    def last(self, topic: str):
        """The last message on ``topic`` in log-time order as (log_time_ns, CDR bytes), read from
        the chunk that holds it; None without any."""
        if self.summary.chunk_indexes:
            record = next(self._records([topic], log_time_order=True, reverse=True), None)
        else:
            # messages outside chunks (another writer's, MCAP allows it): the mcap reader streams
            # them in file order whatever ``reverse`` says, and gave the first as the last
            record = None
            for record in self._records([topic], log_time_order=True):
                pass
        return None if record is None else (record[3], record[4])

    def _records(self, topics=None, log_time_order=False, reverse=False):
        """(topic, msg_type, channel id, log_time_ns, CDR bytes) of the messages (``reverse``:
        the last first); a damaged file is a one-line UserError."""
        from mcap.exceptions import McapError
        from zstandard import ZstdError

        try:
            for schema, channel, msg in self._reader.iter_messages(topics=topics, log_time_order=log_time_order,
                                                                   reverse=reverse):
                yield channel.topic, (schema.name if schema else ""), channel.id, int(msg.log_time), msg.data
        # ZstdError: a chunk whose compressed bytes are damaged fails to decompress before its CRC
        # is checked (it was a traceback and "internal error")
        except (McapError, ZstdError, ValueError, KeyError, EOFError) as exc:
            raise UserError(f"{self.path}: corrupt MCAP recording ({exc.__class__.__name__}: "
                            f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None

    def parameters(self) -> dict:
        """The node's parameters from the ``bearing_sim`` metadata (JSON); {} where there are none
        or they are not a JSON mapping (another writer's or a hand-edited file's: a list there was
        an AttributeError traceback in ``report`` and ``play``)."""
        import json

        try:
            parameters = json.loads(self.metadata.get("parameters", "{}"))
        except ValueError:
            return {}
        return parameters if isinstance(parameters, dict) else {}

    def close(self) -> None:
        self._stream.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# MCAP records in a data section (opcodes 0x01-0x0F are the specification's; 0x00 is reserved)
_OPCODES = range(0x01, 0x10)


class _Scan:
    """What :func:`_scan` read of a file: its ``header``, a ``summary`` built from its records
    (schemas, channels, statistics, an index of its complete chunks), ``metas`` and
    ``attachments``; where it stopped (``end``: the byte after the last complete record) and why
    (``ended``)."""

    def __init__(self):
        from mcap.summary import Summary

        self.header = None
        self.summary = Summary()
        self.metas: list = []
        self.attachments: dict = {}
        self.end = 8
        self.zeros = False         # the rest after ``end`` is zero bytes
        self.ended = ""            # "footer", "data end" or "" (cut inside or after a record)
        self.counts: dict = {}     # channel id -> messages
        self.first_ns = self.last_ns = None

    def recovered_text(self, name: str, size: int, writing: bool = False) -> str:
        """One line: what was read of the truncated file ``name`` (``size`` bytes) and what is lost;
        or, where a recording still being written holds it (``writing``), what was read so far."""
        chunks = len(self.summary.chunk_indexes)
        read = (f"{sum(self.counts.values())} messages in its {chunks} complete chunk{'s' if chunks > 1 else ''}, "
                f"{(self.last_ns - self.first_ns) * 1e-9:.2f} s of log time")
        if writing:
            # not cut: "its writer never finished, e.g. a hard kill" sent a user who reported the
            # node's file while it ran looking for a crash that had not happened
            return (f"{name}: read as far as it is written: a recording still being written holds it (its "
                    f"footer and summary come when its writer ends); read up to byte {self.end} of {size}: "
                    f"{read}; the rest is not written yet")
        lost = ("its data section complete, only the summary lost" if self.ended == "data end" else
                f"the last {size - self.end} bytes (zeros: never written, e.g. a power cut) lost" if self.zeros else
                f"the last {size - self.end} bytes (an incomplete record) lost" if size > self.end else
                "it ends after a complete record: what its writer had not written yet is lost")
        return (f"{name}: read as recovered: no footer and no summary (its writer never finished, e.g. a hard kill "
                f"or a power cut); read up to byte {self.end} of {size}: {read}; {lost}")


def _scan(stream, size: int, name: str) -> _Scan:
    """Read the MCAP file ``stream`` (``size`` bytes) record by record from the start, without its
    summary: every chunk is decompressed and its CRC checked.  Stops at the footer, the data end,
    or where the rest is not a complete record (the cut of a truncated file: a record whose length
    runs past the end, or zeros, which a power cut leaves in blocks never written).  A complete
    record that does not parse (a CRC that fails, a chunk that does not decompress, an opcode
    MCAP does not have) is a corrupt file: the records after it would be skipped unsaid."""
    import struct

    from mcap.data_stream import ReadDataStream
    from mcap.exceptions import McapError
    from mcap.records import Attachment, Channel, Chunk, ChunkIndex, Header, Metadata, Schema, Statistics
    from zstandard import ZstdError

    from io import BytesIO

    scan = _Scan()
    summary = scan.summary

    def read(opcode: int, length: int, pos: int) -> None:
        body = ReadDataStream(BytesIO(stream.read(length)))
        if scan.header is None and opcode != 0x01:
            raise McapError(f"expected the header record at byte 8, found opcode 0x{opcode:02x}")
        if opcode == 0x01:
            scan.header = Header.read(body)
        elif opcode == 0x02:
            scan.ended = "footer"
        elif opcode == 0x0F:
            scan.ended = "data end"
        elif opcode == 0x03:
            schema = Schema.read(body)
            summary.schemas[schema.id] = schema
        elif opcode == 0x04:
            channel = Channel.read(body)
            summary.channels[channel.id] = channel
        elif opcode == 0x05:
            # not damage: an unchunked writer's file, whose messages the index built here (of
            # chunks) cannot reach
            raise UserError(f"{name}: MCAP recording without a summary and with its messages outside chunks "
                            f"(from byte {pos}): this reader reads only chunked files without their summary; "
                            "`mcap recover` can rebuild it")
        elif opcode == 0x06:
            chunk = Chunk.read(body)
            defined, messages = _chunk_contents(chunk)
            channels = {**summary.channels, **{r.id: r for r in defined if isinstance(r, Channel)}}
            times = [log_ns for _, log_ns in messages]
            undefined = next((channel_id for channel_id, _ in messages if channel_id not in channels), None)
            if undefined is not None:
                raise McapError(f"a message on channel {undefined}, which no channel record before it defines "
                                f"(chunk at byte {pos})")
            # only once the whole chunk checks: one a power cut left zeros in the end of adds nothing
            summary.schemas.update({r.id: r for r in defined if isinstance(r, Schema)})
            summary.channels.update(channels)
            for channel_id, _ in messages:
                scan.counts[channel_id] = scan.counts.get(channel_id, 0) + 1
            first, last = (min(times), max(times)) if times else (None, None)
            if first is not None:
                # no message index offsets: the reader looks into the chunk for any topic
                summary.chunk_indexes.append(ChunkIndex(
                    chunk_length=9 + length, chunk_start_offset=pos, compression=chunk.compression,
                    compressed_size=len(chunk.data), message_end_time=last, message_index_length=0,
                    message_index_offsets={}, message_start_time=first,
                    uncompressed_size=chunk.uncompressed_size))
                scan.first_ns = first if scan.first_ns is None else min(scan.first_ns, first)
                scan.last_ns = last if scan.last_ns is None else max(scan.last_ns, last)
        elif opcode == 0x0C:
            scan.metas.append(Metadata.read(body))
        elif opcode == 0x09:
            attachment = Attachment.read(body)
            scan.attachments[attachment.name] = attachment.data

    zeros_from = _zero_tail(stream, size)
    pos = 8
    stream.seek(pos)
    try:
        while pos + 9 <= size:
            if pos >= zeros_from:
                scan.zeros = True                       # blocks a power cut left unwritten
                break
            opcode, length = struct.unpack("<BQ", stream.read(9))
            if opcode not in _OPCODES:
                raise McapError(f"no MCAP record has opcode 0x{opcode:02x} (at byte {pos})")
            if pos + 9 + length > size:
                break                                   # the record the writer was writing
            try:
                read(opcode, length, pos)
            except (McapError, ZstdError, ValueError, KeyError, struct.error):
                if pos + 9 + length <= zeros_from:
                    raise
                scan.zeros = True                       # a record whose end a power cut left zeros
                break
            pos += 9 + length
            scan.end = pos
            if scan.ended:
                break
    except (McapError, ZstdError, ValueError, KeyError, struct.error) as exc:
        raise UserError(f"{name}: corrupt MCAP recording ({exc.__class__.__name__}: "
                        f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None
    if scan.header is None:
        raise UserError(f"{name}: truncated MCAP recording ({size} bytes): it ends before the end of its first "
                        "record, nothing in it to read")
    summary.statistics = Statistics(
        attachment_count=len(scan.attachments), channel_count=len(summary.channels),
        channel_message_counts=dict(scan.counts), chunk_count=len(summary.chunk_indexes),
        message_count=sum(scan.counts.values()), message_end_time=scan.last_ns or 0,
        message_start_time=scan.first_ns or 0, metadata_count=len(scan.metas), schema_count=len(summary.schemas))
    return scan


def _chunk_contents(chunk) -> tuple:
    """(the schema and channel records in ``chunk``, its messages' (channel id, log time ns) in
    order): what ``breakup_chunk`` finds of them, the chunk decompressed and its CRC checked the
    same way, without making a record of each message (the scan needs their channels and times
    only; making them took a quarter of the time to open a cut file: 3.4 s of 150 MB, 2.5 s now).
    A record that runs past the end of the chunk is an McapError."""
    import struct
    from io import BytesIO

    from mcap.data_stream import ReadDataStream
    from mcap.exceptions import McapError
    from mcap.records import Channel, Schema
    from mcap.stream_reader import get_chunk_data_stream

    stream, size = get_chunk_data_stream(chunk, validate_crc=True)
    data = stream.read(size)
    defined, messages = [], []
    record, message = struct.Struct("<BQ"), struct.Struct("<HIQ")     # opcode, length; channel, sequence, log time
    pos = 0
    while pos < size:
        opcode, length = record.unpack_from(data, pos)
        body = pos + record.size
        if body + length > size or (opcode == 0x05 and length < 22):
            raise McapError(f"a record (opcode 0x{opcode:02x}, {length} bytes) runs past the end of its chunk")
        if opcode == 0x05:
            channel_id, _sequence, log_ns = message.unpack_from(data, body)
            messages.append((channel_id, log_ns))
        elif opcode in (0x03, 0x04):
            kind = Schema if opcode == 0x03 else Channel
            defined.append(kind.read(ReadDataStream(BytesIO(data[body:body + length]))))
        pos = body + length
    return defined, messages


def _zero_tail(stream, size: int) -> int:
    """Where the zero bytes at the end of ``stream`` (``size`` bytes) begin: ``size`` without any.
    Read backwards a MiB at a time."""
    end = size
    while end > 0:
        start = max(0, end - (1 << 20))
        stream.seek(start)
        block = stream.read(end - start).rstrip(b"\0")
        if block:
            return start + len(block)
        end = start
    return 0


def _indexed_reader(stream, summary):
    """A reader of ``stream``'s messages by ``summary`` (what :func:`_scan` built of a file
    without its own): the mcap library's, in log-time order as for any file."""
    from mcap.reader import SeekingReader

    class IndexedReader(SeekingReader):
        def get_summary(self):
            return summary

        def iter_messages(self, *args, **kwargs):
            # without chunks it would read the whole file as a stream, into the cut
            if summary.chunk_indexes:
                yield from super().iter_messages(*args, **kwargs)

    stream.seek(0)
    return IndexedReader(stream, validate_crcs=True)


class SplitRecording:
    """The pieces of one split recording, checked and read as one recording: the same interface
    as :class:`Recording` (``path``, ``metadata``, ``attachments``, ``topics()``,
    ``messages()``, ``message_count``, ``start_ns``, ``end_ns``, ``parameters()``, ``close()``),
    the pieces in the order of their ``file_index``, their messages one piece after the other.

    ``paths``: the pieces, in any order; a run of consecutive pieces (``run_002.mcap`` ..
    ``run_004.mcap``) is a recording too.  ``named``: the path the split recording was made to
    (``run.mcap``), when the pieces were found from it: then a last piece that cannot be read
    (empty, or cut before its first complete chunk: what a hard kill leaves of a file just begun)
    is left out and said in ``notes`` instead of failing the whole recording.  A last piece cut
    later (no footer: the file being written when the recording was killed) is read as recovered,
    up to its last complete chunk, and said in ``recovered`` (None otherwise): it is the end of
    the signal.  A piece cut before the last is refused: the pieces after it would follow a gap.

    The pieces' ``bearing_sim`` metadata must be the same but for ``file_index`` (it holds no
    wall clock, so two runs of one command have the same: such pieces mixed show as gaps in
    the waveform tables, which ``report`` counts)."""

    def __init__(self, paths, named=None):
        self.notes: list = []
        given = [os.fspath(p) for p in paths]
        seen: dict = {}
        for p in given:
            key = os.path.realpath(p)
            if key in seen:
                raise UserError(f"{p}: given twice (as {seen[key]!r} too); give each piece of a split "
                                "recording once")
            seen[key] = p
        self._pieces: list = []
        try:
            for k, p in enumerate(given):
                try:
                    self._pieces.append(Recording(p))
                except UserError as exc:
                    if named is None:
                        raise UserError(f"{exc}{_without_the_last_piece(p)}") from None
                    if k != len(given) - 1 or k == 0:
                        raise
                    self.notes.append(f"{p} left out: {str(exc).split(': ', 1)[-1]}")
            self._check_and_order()
            for r in self._pieces[:-1]:
                if r.recovered:
                    raise UserError(f"{r.path}: truncated MCAP recording (no footer: its writer never finished), "
                                    f"and not the last of the pieces given ({FILE_INDEX} {r.metadata[FILE_INDEX]}): "
                                    "the pieces after it would follow a gap; give the pieces up to it")
        except BaseException:
            self.close()
            raise
        first, last = self._pieces[0], self._pieces[-1]
        self.recovered = last.recovered
        self.paths = [r.path for r in self._pieces]
        names = first.path.name if first is last else f"{first.path.name} .. {last.path.name}"
        self.path = f"{first.path} .. {last.path}" if named is None else f"{named} ({names})"
        self.metadata = _without_index(first.metadata)
        self.attachments = first.attachments
        self.message_count = sum(r.message_count for r in self._pieces)
        starts = [r.start_ns for r in self._pieces if r.message_count]
        ends = [r.end_ns for r in self._pieces if r.message_count]
        self.start_ns, self.end_ns = (starts[0], ends[-1]) if starts else (0, 0)

    def _check_and_order(self) -> None:
        """Pieces of one recording (metadata alike but for the index), ordered by index, none
        missing between the first and the last, consecutive in log time."""
        indexed = []
        for r in self._pieces:
            index = r.metadata.get(FILE_INDEX, "")
            if not index.isdigit():
                raise UserError(f"{r.path}: not a piece of a split recording (its bearing_sim metadata has no "
                                f"{FILE_INDEX}); several files are read together only when they are the pieces "
                                "of one split recording (the node's record_max_duration / record_max_size)")
            indexed.append((int(index), r))
        indexed.sort(key=lambda item: item[0])
        ref = indexed[0][1]
        common = _without_index(ref.metadata)
        for (i_prev, prev), (i, r) in zip(indexed, indexed[1:]):
            if i == i_prev:
                raise UserError(f"{prev.path} and {r.path}: both are piece {i} ({FILE_INDEX}); "
                                "give the pieces of one split recording")
            if i != i_prev + 1:
                missing = ", ".join(str(k) for k in range(i_prev + 1, i))
                raise UserError(f"{prev.path} .. {r.path}: the pieces between them are missing "
                                f"({FILE_INDEX} {missing}); give consecutive pieces of the recording")
        for _i, r in indexed[1:]:
            mine = _without_index(r.metadata)
            differ = sorted(k for k in set(common) | set(mine) if common.get(k) != mine.get(k))
            if differ:
                raise UserError(f"{ref.path} and {r.path} are pieces of different recordings (their "
                                f"bearing_sim metadata differ in {', '.join(differ)}); give the pieces of "
                                "one split recording")
        timed = [r for _i, r in indexed if r.message_count]
        for prev, r in zip(timed, timed[1:]):
            if r.start_ns < prev.end_ns:
                raise UserError(f"{prev.path} and {r.path}: the later piece starts before the earlier one "
                                "ends (log times); not consecutive pieces of one recording")
        self._pieces = [r for _i, r in indexed]

    def topics(self) -> dict:
        """topic -> ChannelInfo, its messages counted over every piece."""
        merged: dict = {}
        for r in self._pieces:
            for topic, info in r.topics().items():
                have = merged.get(topic)
                if have is not None and have.msg_type != info.msg_type:
                    raise UserError(f"{r.path}: {topic} is {info.msg_type}, an earlier piece has it as "
                                    f"{have.msg_type}; not pieces of one recording")
                merged[topic] = info if have is None else ChannelInfo(
                    topic, have.msg_type, have.qos_yaml, have.count + info.count)
        return merged

    def messages(self, topics=None):
        """(topic, msg_type, log_time_ns, CDR bytes), piece after piece, each in log-time order."""
        for r in self._pieces:
            yield from r.messages(topics)

    def first_and_last(self, topic: str):
        """``Recording.first_and_last`` over the pieces: the first piece's first message on
        ``topic`` and the last piece's last (of those that have one)."""
        # each end from the one piece that holds it: first_and_last per piece read the first
        # piece's last message and the last piece's first as well, two chunks for nothing
        first = next((m for m in (r.first(topic) for r in self._pieces) if m), None)
        if first is None:
            return None
        return first, next(m for m in (r.last(topic) for r in reversed(self._pieces)) if m)

    def parameters(self) -> dict:
        return self._pieces[0].parameters()

    def close(self) -> None:
        for r in self._pieces:
            r.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _without_the_last_piece(piece) -> str:
    """Where ``piece``, given by hand with other files and unreadable, is the last piece of a
    split recording (what a hard kill leaves of the file being written: ``run_*.mcap`` after a
    ``kill -9``), how to read the pieces before it: "" otherwise.  The error alone pointed to
    ``mcap recover``, a tool of its own, where the recording's name reads them."""
    import re
    from pathlib import Path

    piece = Path(piece)
    split = re.fullmatch(r"(.+)_\d{3,}(\.mcap)", piece.name)
    if split is None:
        return ""
    named = piece.with_name(split.group(1) + split.group(2))
    pieces = existing_pieces(named)
    if len(pieces) < 2 or os.path.lexists(named) or os.path.realpath(pieces[-1]) != os.path.realpath(piece):
        return ""
    return (f"; it is the last piece of {named}: give the pieces before it, or {named}, which reads all "
            f"{len(pieces) - 1} of them and leaves it out")


def _without_index(metadata: dict) -> dict:
    """A piece's ``bearing_sim`` metadata without its ``file_index``: the recording's."""
    return {k: v for k, v in metadata.items() if k != FILE_INDEX}


def recorded_sample_rate(rec) -> float | None:
    """The output sample rate (Hz) that ``rec``'s metadata gives (its ``sample_rate`` parameter)
    where it is one the node can run at (a number in ``simulator.SAMPLE_RATE_RANGE``), else None,
    as for a recording without it (another tool's): then its waveform tables' stamps tell the
    rate.  A NaN or negative one (a damaged or hand-edited file) was a traceback in ``report``
    and ``play``, and 1e300 a report of "0.00 s" analysed."""
    from ..simulator import SAMPLE_RATE_RANGE

    value = rec.parameters().get("sample_rate")
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        return None
    try:
        rate = float(value)
    except ValueError:
        return None
    lo, hi = SAMPLE_RATE_RANGE
    return rate if lo <= rate <= hi else None      # NaN compares false: None


def open_recording(path) -> Recording | SplitRecording:
    """Open and check a recording (see :class:`Recording`): ``path`` one file, or several (a
    list: the pieces of one split recording, in any order, :class:`SplitRecording`), or the path
    a split recording was made to (``run.mcap``, which does not exist, for ``run_000.mcap``,
    ``run_001.mcap``, ...)."""
    paths = [path] if isinstance(path, (str, os.PathLike)) else list(path)
    if not paths:
        raise UserError("no recording given: expected an .mcap file")
    if len(paths) > 1:
        for p in paths:
            # the name a split recording was made to, among other files (`play run.mcap
            # run_001.mcap`): it was "run.mcap: no such file", though alone it reads all its pieces
            pieces = [] if os.path.lexists(p) else existing_pieces(p)
            if pieces:
                raise UserError(f"{os.fspath(p)}: the name that split recording {pieces[0].name} .. {pieces[-1].name} "
                                f"was recorded to, given with other files; give that name alone (it reads all "
                                f"{len(pieces)} pieces) or its pieces, not both")
        return SplitRecording(paths)
    one = os.fspath(paths[0])
    if not os.path.lexists(one):
        pieces = existing_pieces(one)
        if pieces:
            return SplitRecording(pieces, named=one)
    return Recording(one)
