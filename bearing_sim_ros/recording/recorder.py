"""MCAP recorder: ROS 2 messages to a file that rosbag2, Foxglove and ``rosbags`` read.

    rec = Recorder("run.mcap", recording_metadata(scene, params, seed, sim.selection),
                   attachments={"scene.yaml": scene.source_text.encode()})
    rec.add_topic("/accel", "sensor_msgs/msg/PointCloud2", qos)
    rec.write("/accel", msg, log_time_ns)      # never raises; never blocks unless when_full="wait"
    rec.close()                                # finalise (idempotent)

The file: profile ``ros2``, ``cdr`` messages serialised by rclpy itself, ``ros2msg`` schemas with
every dependency (``schemas.message_definition``; alignment padding zeroed, ``cdr.py``),
``offered_qos_profiles`` channel metadata in
rosbag2's YAML, a metadata record ``bearing_sim`` (how the recording was made) and the given
attachments (the scene file).  Chunked and zstd-compressed.

Threading: ``write`` serialises in the caller's thread and appends to a deque (atomic in CPython,
no lock), so publishing never waits for the disk and a signal handler that interrupts ``write``
can still call ``close``.  A background thread drains the deque into the MCAP writer.  A write
error (full disk, path gone) stops recording: the error goes into ``status``, queued messages
are counted as dropped, and nothing is raised into the publisher.  So does a file deleted while
it is written (itself or its folder, or replaced by another file: writing into it fails no
write): the writer thread looks at it (``os.fstat``: no link left; and at its path) every
``CHECK_PATH_S`` and before it finalises the file (``_check_in_place``).  A file moved away is
finished where it went.

A disk slower than the producer: once ``max_queue_bytes`` (default ``MAX_QUEUE_BYTES``) of
serialised messages wait for it, ``when_full`` decides.  ``"drop"`` (the live node, which must
never hold up a real-time batch): the message is dropped and counted (``status["dropped"]``).
``"wait"`` (``render``, which has no deadline and must lose nothing): ``write`` waits until the
writer thread has drained the queue below the limit (back-pressure; polled, no lock), or until
``stopped()`` (a signal noted), and then queues the message beyond the limit.

Rotation (optional): ``rotate_bytes`` (bytes on disk per file, as rosbag2's ``--max-bag-size``)
and ``rotate_seconds`` (log-time span per file, as ``--max-bag-duration``) start a new file
``<stem>_001.mcap``, ``<stem>_002.mcap``... (the first is ``<stem>_000.mcap``).  Every file is
complete on its own (schemas, channels, metadata, attachments), so a hard kill loses at most the
file being written.  A new file starts only where the log time moves on: the messages of one
instant (the node's batch: its tables, state, inputs and diagnostics) stay in one file.  The size
counts what is on disk plus the chunk being filled, before compression (it shrinks when written),
so a file ends at most one instant's messages past ``rotate_bytes``, and its index comes on top.
Pieces of an earlier split recording under the same name are not replaced: two recordings'
pieces would mix in one folder (``existing_pieces``).

Replace when done (optional, ``replace_when_done``; what ``render`` uses): each file is written
as ``<name>.<pid>.partial`` beside it and moved onto its name (``os.replace``) once finalised
(a name that is a symbolic link: beside and onto the file it points to),
so the name only ever holds a complete file, and an earlier recording there stays until the new
one is complete; ``discard`` (a failed render) removes the partial file and leaves the name
alone.  A device or a pipe (/dev/null) is written directly.  Without it (the live node) the file
grows under its own name while it is written.

One writer per name: each holds the file it writes (the name, or its partial file) with a lock,
and a recorder whose name another is writing (a render's held partial file, a node's held file)
ends at start with a UserError, before it writes anything (``_open_held``); the partial file of a
render killed hard (held by nobody, its process gone) is removed then.  A finished piece of a
split recording whose writer holds a later piece counts as written too (``_later_piece_held``).
"""
from __future__ import annotations

import atexit
import contextlib
import errno
import glob
import json
import math
import os
import re
import stat
import threading
import time
from collections import deque
from pathlib import Path

from ..errors import UserError
from ..paths import MCAP_MAGIC, check_replaceable, output_file
from ..teardown import say_on_stderr, signal_noted
from .cdr import zero_padding
from .schemas import message_definition, qos_to_yaml

PROFILE = "ros2"
METADATA_NAME = "bearing_sim"
FILE_INDEX = "file_index"       # metadata key: the piece's number in a split recording (rotated_path)
MAX_QUEUE_BYTES = 512 * 1024 * 1024   # beyond this the disk is not keeping up: drop or wait
WHEN_FULL = ("drop", "wait")          # what ``write`` does when the queue holds max_queue_bytes
CHUNK_BYTES = 1024 * 1024             # MCAP chunk size (uncompressed)
_POLL_S = 0.02                        # writer thread wake-up period (s)
_WAIT_POLL_S = 0.002                  # a waiting producer's wake-up period (when_full="wait", s)
PIPE_NOTICE_S = 1.0                   # s without a reader of a named pipe before saying the recording waits
_PIPE_POLL_S = 0.05                   # how often a named pipe is tried for a reader (s)
FINISH_NOTICE_S = 2.0                 # s a close waits for the writer thread before saying what it waits for
CHECK_PATH_S = 1.0                    # how often the writer thread looks whether its file was deleted (s)
# a split recording's files (the node's record_max_size, run's --max-file-size; bytes on disk):
# below this one would hold little more than the metadata and the attached scene (a scene with a
# long profile takes hundreds of kB), and a file would start at every batch
SPLIT_MIN_BYTES = 1_000_000
SPLIT_MAX_BYTES = 10**15


def _one_line(exc: BaseException) -> str:
    return f"{exc.__class__.__name__}: {exc}".replace("\n", " ")


class _NotAtItsPath(Exception):
    """The file being written was deleted (itself, its folder, or replaced by another file), or
    a partial file is not at its name; the message says which (``Recorder._check_in_place``)."""


def _normalise_topic(topic: str) -> str:
    """rosbag2 records fully qualified names; a relative name is taken as in the root namespace
    (the node should pass its publisher's resolved ``topic_name``)."""
    return topic if topic.startswith("/") else "/" + topic


def _qos_profile(qos, topic: str):
    """The QoSProfile for ``qos`` as rclpy reads it: a profile as it is, an int as a keep-last
    depth (``Node._validate_qos_or_depth_parameter``), None as no profile."""
    from rclpy.qos import QoSProfile

    if qos is None or isinstance(qos, QoSProfile):
        return qos
    if isinstance(qos, int) and not isinstance(qos, bool):
        if qos < 0:
            raise ValueError(f"{topic}: qos = {qos}: a depth must be >= 0")
        return QoSProfile(depth=qos)
    raise TypeError(f"{topic}: qos = {qos!r}: expected an rclpy QoSProfile, an int depth or None")


def sizes_text(status: dict) -> str:
    """'6.5 MB of messages, 2.3 MB on disk (zstd)' for a closed recording's ``status``: what
    the messages weigh serialised, and what the files take after chunk compression."""
    on_disk = sum(os.path.getsize(p) for p in status["files"] if os.path.exists(p))
    return f"{megabytes(status['bytes'])} of messages, {megabytes(on_disk)} on disk (zstd)"


def megabytes(n_bytes: int) -> str:
    """A size in MB (10^6 bytes): one decimal from 1 MB up (``13.0 MB``), two significant digits
    below (``0.045 MB``), where one decimal said "0.0 MB" of a short render's 45 kB; nothing
    at all is ``0.0 MB``.  Always MB, so that a script reads one unit."""
    size = n_bytes / 1e6
    if size >= 1.0 or size <= 0.0:
        return f"{size:.1f} MB"
    decimals = 1 - math.floor(math.log10(size))           # the second significant digit's place
    return f"{size:.{decimals}f} MB"


def rotated_path(path: Path, index: int) -> Path:
    """``run.mcap`` -> ``run_003.mcap``."""
    return path.with_name(f"{path.stem}_{index:03d}{path.suffix or '.mcap'}")


def existing_pieces(path) -> list:
    """The files of a split recording to ``path`` that exist (``run_000.mcap``, ``run_001.mcap``,
    ...; ``rotated_path``), in order."""
    path = Path(path)
    suffix = path.suffix or ".mcap"
    name = re.compile(rf"{re.escape(path.stem)}_(\d{{3,}}){re.escape(suffix)}")
    found = [(int(m.group(1)), p) for p in path.parent.glob(f"{glob.escape(path.stem)}_*{glob.escape(suffix)}")
             if (m := name.fullmatch(p.name))]
    return [p for _index, p in sorted(found)]


def split_error(max_duration: float, max_size: int, batch_duration: float,
                names=("record_max_duration", "record_max_size")):
    """None if a split recording's ``max_duration`` (s per file) and ``max_size`` (bytes on disk
    per file) are usable with batches of ``batch_duration`` (s), else a one-line reason naming
    them as ``names`` (the node's parameters; ``run``'s options).  Their ranges are checked where
    they are declared; this refuses a split so fine that every batch would be a file."""
    if 0 < max_duration < batch_duration:
        return (f"{names[0]} = {max_duration!r} s: 0 (one file) or at least one batch, "
                f"batch_duration = {batch_duration:g} s")
    if 0 < max_size < SPLIT_MIN_BYTES:
        return (f"{names[1]} = {max_size!r} bytes: 0 (one file) or at least {SPLIT_MIN_BYTES} "
                f"({SPLIT_MIN_BYTES / 1e6:g} MB)")
    return None


def files_text(status: dict) -> str:
    """Where a recording went, for a log line: ``runs/run.mcap``, or for a split one
    ``runs/run_000.mcap .. runs/run_004.mcap, 5 files``."""
    files = status["files"] or [status["path"]]
    if len(files) == 1:
        return str(files[0])
    return f"{files[0]} .. {files[-1]}, {len(files)} files"


_PARTIAL_SUFFIX = re.compile(r"\.(\d+)\.partial")   # after the final name: replace_when_done's <name>.<pid>.partial


def _busy(where: str, later_piece: Path | None = None) -> UserError:
    if later_piece is not None:
        return UserError(f"{where}: a piece of a split recording that is still being written (now to "
                         f"{later_piece.name}); give another path, or wait until that recording ends")
    return UserError(f"{where}: another recording is being written to this file (two renders, nodes or runs "
                     "given the same path?); give each its own, or wait until the other ends")


_PIECE_NAME = re.compile(r"(.+)_(\d{3,})(\.[^.]*)?")     # rotated_path's run_003.mcap


def _later_piece_held(final: Path) -> Path | None:
    """Where ``final`` is named as a piece of a split recording (``run_001.mcap``, ``rotated_path``)
    and a later piece of it (``run_004.mcap``) is held by its writer, that piece, else None.  The
    node holds only the piece it writes: a render or a node given a finished piece of a recording
    still running replaced it, and the recording lost it without a word."""
    match = _PIECE_NAME.fullmatch(final.name)
    if match is None:
        return None
    index = int(match.group(2))
    base = final.with_name(match.group(1) + (match.group(3) or ""))
    # The writer rotates as we look: it closes its piece (its lock goes) and then makes and holds
    # the next (``_maybe_rotate``), and a held piece is tried for about 40 ms (``_flock_soon``),
    # so a look that began on run_002 found it free and missed run_003 (a CI run: a node given
    # run_001.mcap of a recording that split every 0.5 s replaced it).  So the newest pieces are
    # looked at first, the pieces listed again after each look until no new one comes, and once
    # more after a rotation's pause (where there was a later piece).
    checked = set()
    paused = False
    while True:
        later = [piece for piece in existing_pieces(base)
                 if int(_PIECE_NAME.fullmatch(piece.name).group(2)) > index and piece not in checked]
        if not later:
            if paused or not checked:       # no later piece at all: no recording of it runs on
                return None
            time.sleep(LOCK_TRIES * LOCK_RETRY_S)
            paused = True
            continue
        paused = False
        for piece in reversed(later):
            if _held(piece):
                return piece
            checked.add(piece)


def _writer_of(final: Path, mine: Path, where: str) -> UserError | None:
    """The refusal (``_busy``) where another recording is being written to ``final`` beside ours
    (``_other_writer``) or ``final`` is a finished piece of a split recording still running
    (``_later_piece_held``), else None."""
    later_piece = _later_piece_held(final)
    if later_piece is not None or _other_writer(final, mine):
        return _busy(where, later_piece)
    return None


def being_written(path) -> bool:
    """Whether a recording still being written holds ``path`` (a node's or ``run``'s file, or a
    piece of a split recording being written), for a reader: ``report`` and ``play`` read such a
    file as far as it is written, and say so, not that its writer was killed."""
    return _held(Path(path), shared=True)


def _held(path: Path, shared: bool = False) -> bool:
    """Whether the regular file ``path`` is held by a writer (``_open_held``'s lock): tried with a
    lock of our own (``_flock_soon``: held only where it stays held for about 40 ms), released at
    once.  A file that cannot be opened is not taken for held.
    ``shared``: tried with a shared lock (a reader's), which another reader's try does not block,
    so that two readers at once do not take each other for a writer."""
    import fcntl

    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)     # a pipe put there must not block
    except OSError:
        return False
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return False
        return not _flock_soon(fd, fcntl.LOCK_SH if shared else fcntl.LOCK_EX)
    finally:
        os.close(fd)


# A lock tried by ``_held`` lasts a moment, and a writer that tries its own just then must not take
# it for another writer's (a reader's ``being_written`` while a node starts its file made the node
# refuse to record): a lock is tried again for up to about 40 ms before it counts as held.
# A writer's lock is held for the whole recording.
LOCK_TRIES = 5
LOCK_RETRY_S = 0.01


def _flock_soon(fd: int, operation: int) -> bool:
    """Whether ``flock(fd, operation)`` (``LOCK_EX`` or ``LOCK_SH``, without blocking) was taken,
    tried ``LOCK_TRIES`` times ``LOCK_RETRY_S`` (s) apart; False where another holds it throughout."""
    import fcntl

    for attempt in range(LOCK_TRIES):
        try:
            fcntl.flock(fd, operation | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            if attempt + 1 < LOCK_TRIES:
                time.sleep(LOCK_RETRY_S)
    return False


def _gone(pid: int) -> bool:
    """Whether no process ``pid`` runs (on this machine)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (OSError, OverflowError):
        return False                      # another user's process (EPERM): it runs
    return False


def _other_writer(final: Path, mine: Path) -> bool:
    """Whether another recording is being written to ``final``, beside ours (``mine``: the file we
    hold, ``final`` itself or our partial file): ``final`` held by a node writing it directly, or
    a partial file ``<final>.<pid>.partial`` held by a render.  A partial file nobody holds whose
    process is gone (a render killed with ``kill -9``) is removed on the way: it is no recording,
    and would otherwise stay beside it for ever.  One whose process still runs is left alone: its
    render may have created it and not yet taken its lock."""
    if mine != final and _held(final):
        return True
    for partial in final.parent.glob(f"{glob.escape(final.name)}.*.partial"):
        match = _PARTIAL_SUFFIX.fullmatch(partial.name[len(final.name):])
        if partial == mine or not match:
            continue
        if _held(partial):
            return True
        if _gone(int(match.group(1))) and _is_recording_or_empty(partial):
            with contextlib.suppress(OSError):
                partial.unlink()
    return False


def _is_recording_or_empty(path: Path) -> bool:
    """Whether ``path`` starts as an MCAP file does, or as far as it goes (an empty file)."""
    try:
        with open(path, "rb") as f:
            return MCAP_MAGIC.startswith(f.read(len(MCAP_MAGIC)))
    except OSError:
        return False


def _open_for_writing(path: Path, where: str, stopped) -> int:
    """A descriptor of ``path`` opened for writing (created if missing), blocking as usual once
    open.  A named pipe without a reader is waited for: a plain open waits in the kernel until a
    program opens it for reading, without a word, and the commands' signal handlers only note a
    signal (Python then opens again): ``render --out pipe`` and ``node -p record:=pipe`` with
    nobody reading sat there through Ctrl-C and SIGTERM, for ever.  So it is tried without
    blocking every ``_PIPE_POLL_S``; after ``PIPE_NOTICE_S`` one line on stderr tells that the
    recording waits for a reader; once ``stopped()`` (a signal noted) the wait ends with an
    InterruptedError."""
    started = time.monotonic()
    told = False
    while True:
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_NONBLOCK, 0o666)
        except OSError as exc:
            # ENXIO: a pipe without a reader, or a socket (which never opens: said as it is)
            if exc.errno != errno.ENXIO or not stat.S_ISFIFO(os.stat(path).st_mode):
                raise
        else:
            os.set_blocking(fd, True)
            return fd
        if stopped():
            raise InterruptedError(errno.EINTR, "stopped while it waited for a reader of the pipe")
        if not told and time.monotonic() - started >= PIPE_NOTICE_S:
            say_on_stderr(f"{where}: a named pipe that no program reads yet; the recording waits for one "
                          "to open it (Ctrl-C to stop)")
            told = True
        time.sleep(_PIPE_POLL_S)


def _open_held(path: Path, where: str, final: Path, stopped):
    """``path`` opened for writing from its start, a regular file held with an exclusive lock
    (``flock``, released as it is closed) and emptied only once it is held.  Two nodes given one
    ``record`` path (a parameters file for several, ``/**: record: run.mcap``) both wrote into the
    one file, and both said they had recorded it: the file held one, the other was lost.  The
    second now gets a one-line UserError (``where``: ``record = 'run.mcap'``) and the first's file
    is untouched.  A named pipe is held too, and nothing more; a device (/dev/null) is opened
    as it is.

    ``final``: the name that ``path``, a partial file (``replace_when_done``), is moved onto at
    the end (``path`` itself where it is no partial file).  Two renders to one ``--out`` held two partial files and moved each onto the name:
    the last was kept, the other lost without a word; and a render moved its file onto the one a
    node was writing there.  So once ``path`` is held, another writer of the name
    (``_other_writer``) refuses this one, before it empties anything.  Each looks only after
    taking its own lock, so two starting at once cannot both miss each other: then both may
    refuse, which loses nothing.  A named pipe without a reader is waited for, said after a second
    and ended by ``stopped()`` (``_open_for_writing``)."""
    import fcntl

    if not os.path.lexists(path):
        # a writer known already refuses this one before it makes a file: a node refused so left
        # an empty file at its record path.  The same check after the lock (below) stays, for a
        # writer that starts in between
        refusal = _writer_of(final, path, where)
        if refusal is not None:
            raise refusal
    fd = _open_for_writing(path, where, stopped)
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISREG(mode) or stat.S_ISFIFO(mode):
            # a named pipe too: two recordings into one interleave their bytes, and its reader
            # gets neither (both writers exited 0)
            if not _flock_soon(fd, fcntl.LOCK_EX):
                raise _busy(where)
        if stat.S_ISREG(mode):
            # a node's file moved aside by a render finishing meanwhile is not at its name any more
            refusal = _writer_of(final, path, where) or (_busy(where) if _replaced(path, fd) else None)
            if refusal is not None:
                if path != final:       # our partial file (its name is our pid's); a node's new
                    with contextlib.suppress(OSError):     # empty file stays: a render may be
                        path.unlink()                      # moving its own onto the name
                raise refusal
            os.ftruncate(fd, 0)
        return os.fdopen(fd, "wb")
    except BaseException:
        os.close(fd)
        raise


def _replaced(path: Path, fd: int) -> bool:
    """Whether another file is at ``path`` now than the open file ``fd`` (a render finishing
    meanwhile moved its own onto the name).  Nothing there is no other writer: the folder was moved
    or the file deleted as it was opened, and the recording goes on into the open file (a split
    recording's next piece then fails, and says so).  That was taken for "another recording is
    being written to this file" when a folder moved away just as a piece was opened."""
    try:
        there = os.stat(path)
    except FileNotFoundError:
        return False
    except OSError:
        return True
    mine = os.fstat(fd)
    return (there.st_dev, there.st_ino) != (mine.st_dev, mine.st_ino)


class Recorder:
    """Record ROS 2 messages to MCAP off the publishing path (see the module docstring).

    path: output file (``.mcap``); metadata: the ``bearing_sim`` record (str -> str);
    attachments: name -> bytes (e.g. the scene YAML); rotate_bytes: start a new file once this
    one holds this many bytes on disk (0 = never); rotate_seconds: after this span of log time
    (s, 0 = never);
    start_time_ns: log time of the attachments (default: now; offline renders pass 0 so that the
    file does not depend on the wall clock); argument: how errors name the path (the node's
    ``record`` parameter, render's ``--out``); keep: paths never written (the scene's file);
    replace_when_done: write each file under a temporary name and move it onto its own once
    finalised (see the module docstring); when_full: "drop" (count) or "wait" (back-pressure) once
    max_queue_bytes (bytes of serialised messages; default MAX_QUEUE_BYTES) wait for the disk;
    stopped: a callable, true once the caller was asked to stop (default: a signal noted by the
    command's ``teardown.CommandSignals``), which ends a wait for a named pipe's reader with a
    KeyboardInterrupt (``_open_for_writing``: said on stderr after ``PIPE_NOTICE_S``).
    Each file is checked as it is opened (``paths.check_replaceable``): an existing file that is
    not an MCAP recording is not replaced (the first file: a UserError; a rotated one: the
    recording stops with that error).  With rotation, existing pieces of that name are a
    UserError before anything is written (``existing_pieces``).
    """

    def __init__(self, path, metadata: dict, attachments: dict | None = None,
                 rotate_bytes: int = 0, rotate_seconds: float = 0.0,
                 start_time_ns: int | None = None, argument: str = "record", keep=(),
                 replace_when_done: bool = False, when_full: str = "drop",
                 max_queue_bytes: int | None = None, stopped=signal_noted):
        if when_full not in WHEN_FULL:
            raise ValueError(f"when_full = {when_full!r}: allowed values are {', '.join(WHEN_FULL)}")
        if rotate_bytes < 0 or not math.isfinite(rotate_seconds) or rotate_seconds < 0:
            raise UserError(f"rotation = {rotate_bytes!r} bytes / {rotate_seconds!r} s: "
                            "expected numbers >= 0 (0 = no rotation)")
        self._base = output_file(path, argument, check=False)     # each file is checked as it is opened
        self._argument = argument
        self._keep = tuple(str(k) for k in keep if k)
        self._replace_when_done = bool(replace_when_done)
        self._writing = None              # (path written, its final name) of the open file
        self._discard = False
        self._rotate = bool(rotate_bytes or rotate_seconds)
        self._wait_when_full = when_full == "wait"
        self._stopped = stopped
        self._max_queue_bytes = MAX_QUEUE_BYTES if max_queue_bytes is None else int(max_queue_bytes)
        self._rotate_bytes = int(rotate_bytes)
        self._rotate_ns = int(round(rotate_seconds * 1e9))
        self._metadata = {str(k): str(v) for k, v in metadata.items()}
        self._attachments = dict(attachments or {})
        self._start_ns = time.time_ns() if start_time_ns is None else int(start_time_ns)
        # state shared with the writer thread: single-writer fields only (see the docstring)
        self._queue: deque = deque()
        self._enqueued_bytes = 0          # by producers
        self._drained_bytes = 0           # by the writer thread
        self._dropped = 0                 # by producers
        self._dropped_writer = 0          # by the writer thread (counters are single-writer too)
        self._messages = 0
        self._bytes = 0
        self._error = ""
        self._closing = False
        self._closed = False
        self._topics: dict = {}           # topic -> (type, qos yaml); also read by the writer
        self._aliases: dict = {}          # topic as given -> normalised
        self._files: list = []
        self._file_index = 0
        # open the first file now so that an unwritable path is the caller's error, at once
        self._writer = None
        self._stream = None
        if self._rotate:
            self._refuse_earlier_pieces()
        try:
            self._open_file()
        except InterruptedError:
            raise KeyboardInterrupt from None     # stopped while a named pipe waited for its reader
        except OSError as exc:
            # a missing folder by its name, and the system's reason without the file's: render's
            # error named its temporary <out>.<pid>.partial, a path the user never gave
            folder = Path(path).parent
            why = (f"its folder {str(folder)!r} does not exist; create it first"
                   if isinstance(exc, FileNotFoundError) and not folder.is_dir() else exc.strerror or _one_line(exc))
            raise UserError(f"{argument} = {str(path)!r}: cannot write there ({why})") from None
        self._thread = threading.Thread(target=self._run, name="mcap-writer", daemon=True)
        self._thread.start()
        atexit.register(self.close)

    # ---- producer side (any thread) -----------------------------------------------------------
    def add_topic(self, topic: str, msg_type: str, qos) -> None:
        """Declare a channel: ``msg_type`` like 'sensor_msgs/msg/PointCloud2'; ``qos`` what it
        is published with (recorded as ``offered_qos_profiles``): an rclpy QoSProfile, or an int,
        a keep-last depth, as ``create_publisher`` takes it; None records no profile."""
        name = _normalise_topic(topic)
        definition = message_definition(msg_type)      # fail now, in the caller, if unknown
        qos = _qos_profile(qos, name)
        self._aliases[topic] = name
        self._aliases[name] = name
        if name in self._topics:
            return
        self._topics[name] = (msg_type, qos_to_yaml(qos), definition)
        self._queue.append(("topic", name, None, 0))

    def write(self, topic: str, msg, log_time_ns: int) -> None:
        """Queue ``msg`` for ``topic`` with log time = publish time ``log_time_ns``.  Never raises
        into the publisher; waits for the disk only with ``when_full="wait"`` and a full queue."""
        if self._closing or self._error:
            self._dropped += 1
            return
        name = self._aliases.get(topic)
        if name is None:
            self._dropped += 1
            return
        try:
            from rclpy.serialization import serialize_message

            data = serialize_message(msg)
        except Exception as exc:  # noqa: BLE001 - a bad message must not stop the publisher
            self._set_error(f"cannot serialise a message on {name}: {_one_line(exc)}")
            self._dropped += 1
            return
        if self._queue_full():
            if not self._wait_when_full:
                self._dropped += 1
                return
            # the writer thread drains the queue (or, once recording has failed, discards it) and
            # ends only after close; a stop asked for (a signal that render only notes) ends the
            # wait too: into a pipe whose reader stopped reading, render sat deaf to Ctrl-C and
            # SIGTERM.  The message is queued all the same (the file stays whole), and close says
            # what it waits for
            while self._queue_full() and self._thread.is_alive() and not self._stopped():
                time.sleep(_WAIT_POLL_S)
            if self._closing or self._error:
                self._dropped += 1
                return
        self._enqueued_bytes += len(data)
        self._queue.append(("msg", name, data, int(log_time_ns)))

    def _queue_full(self) -> bool:
        return self._enqueued_bytes - self._drained_bytes > self._max_queue_bytes

    def discard(self) -> None:
        """Stop without finalising the open file: with ``replace_when_done`` its partial file is
        removed and its final name left as it was (an earlier recording stays).  Files already
        finalised (rotation) are kept."""
        self._discard = True
        self.close()

    def close(self) -> None:
        """Write everything queued and finalise the file(s).  Idempotent; does not take any lock
        that ``write`` holds, so it may run from a signal or shutdown handler."""
        if self._closed:
            return
        self._closing = True
        self._queue.append(("close", None, None, 0))
        if threading.current_thread() is not self._thread:
            # the file's end must be written, however long that takes (a kill loses it), but not
            # without a word: a pipe whose reader stopped reading held a node's Ctrl-C for as long
            # as it stopped, and the node said nothing
            self._thread.join(FINISH_NOTICE_S)
            if self._thread.is_alive():
                queued_mb = (self._enqueued_bytes - self._drained_bytes) / 1e6
                say_on_stderr(f"recording {self._current_path()}: still finishing after {FINISH_NOTICE_S:g} s "
                              f"({queued_mb:.1f} MB queued): waiting for the disk, or for the pipe's reader, "
                              "to take the rest (killed now, the file would have no end)")
                self._thread.join()
        self._closed = True
        try:
            atexit.unregister(self.close)
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass

    @property
    def status(self) -> dict:
        """ok, error (one line), path (current file), messages and bytes written, dropped, files."""
        return {"ok": not self._error, "error": self._error, "path": str(self._current_path()),
                "messages": self._messages, "bytes": self._bytes, "dropped": self._dropped + self._dropped_writer,
                "files": [str(p) for p in self._files]}

    @property
    def error(self) -> str:
        """The first error (one line) that stopped the recording, "" while it is fine."""
        return self._error

    @property
    def closed(self) -> bool:
        return self._closed

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---- writer thread ---------------------------------------------------------------------
    def _current_path(self) -> Path:
        return rotated_path(self._base, self._file_index) if self._rotate else self._base

    def _where(self, path: Path) -> str:
        """How an error names ``path``: by the argument's value, and the piece when rotating."""
        where = f"{self._argument} = {str(self._base)!r}"
        return f"{where} (file {path})" if self._rotate else where

    def _refuse_earlier_pieces(self) -> None:
        # replacing run_000..run_002 of an earlier run of ten pieces would leave run_003.. beside
        # this run's, as if they were its continuation
        pieces = existing_pieces(self._base)
        if pieces:
            more = f" and {len(pieces) - 1} more exist" if len(pieces) > 1 else " exists"
            raise UserError(f"{self._argument} = {str(self._base)!r}: {pieces[0]}{more}, and a split "
                            "recording does not replace pieces of its name (two recordings' pieces would mix); "
                            "give another path or remove them first")

    def _set_error(self, text: str) -> None:
        if not self._error:
            self._error = text

    def _open_file(self) -> None:
        from mcap.writer import CompressionType, Writer

        path = self._current_path()
        check_replaceable(path, self._where(path), self._keep)
        final = path
        if self._replace_when_done and path.is_symlink():
            # the file the link points to is the one replaced (created, where the link dangles),
            # as a shell's > and paths.replacing (report's files) do: os.replace onto the link put
            # a regular file in its place and left its target as it was
            final = Path(os.path.realpath(path))
        written = final
        if self._replace_when_done and (not final.exists() or final.is_file()):
            written = final.with_name(f"{final.name}.{os.getpid()}.partial")
        # rotating (the writer thread), a close ends a wait for a pipe's reader too: as a write error
        stream = _open_held(written, self._where(path), final=final,
                            stopped=lambda: self._closing or self._stopped())
        if not stream.seekable():
            stream = _Counted(stream)     # a pipe: the MCAP writer asks where each record starts
        self._writing = (written, final)
        self._written_at = written.absolute()    # the name checked against the open file (a chdir moves no file)
        try:
            writer = Writer(stream, chunk_size=self._chunk_bytes(), compression=CompressionType.ZSTD)
            writer.start(profile=PROFILE, library=f"bearing_sim_ros {self._metadata.get('package_version', '')}".strip())
            meta = dict(self._metadata)
            if self._rotate:
                meta[FILE_INDEX] = str(self._file_index)
            writer.add_metadata(METADATA_NAME, meta)
            for name, data in sorted(self._attachments.items()):
                media = "application/yaml" if name.endswith((".yaml", ".yml")) else "application/octet-stream"
                writer.add_attachment(create_time=self._start_ns, log_time=self._start_ns, name=name,
                                      media_type=media, data=bytes(data))
        except BaseException:
            stream.close()
            self._remove_partial()
            raise
        self._stream, self._writer = stream, writer
        self._schema_ids: dict = {}
        self._channel_ids: dict = {}
        self._seq: dict = {}
        self._file_t0 = self._file_t1 = None     # log time of the first and last message (ns)
        self._file_pos = stream.tell() if self._rotate_bytes else 0   # bytes in the file
        self._open_chunk = 0              # message bytes since the file last grew: the open chunk
        self._files.append(path)
        for name in list(self._topics):
            self._register(name)

    def _chunk_bytes(self) -> int:
        """MCAP chunk size (uncompressed bytes).  A file split by size counts its open chunk before
        compression: smaller chunks keep that estimate, and so the files, within a few percent of
        ``rotate_bytes`` (1 MB chunks made 1 MB files of 0.38 MB)."""
        if not self._rotate_bytes:
            return CHUNK_BYTES
        return max(4096, min(CHUNK_BYTES, self._rotate_bytes // 16))

    def _register(self, name: str) -> None:
        if name in self._channel_ids:     # already registered by a rotation that saw it first
            return
        msg_type, qos_yaml, definition = self._topics[name]
        sid = self._schema_ids.get(msg_type)
        if sid is None:
            sid = self._writer.register_schema(name=msg_type, encoding="ros2msg",
                                               data=definition.encode("utf-8"))
            self._schema_ids[msg_type] = sid
        self._channel_ids[name] = self._writer.register_channel(
            topic=name, message_encoding="cdr", schema_id=sid,
            metadata={"offered_qos_profiles": qos_yaml})
        self._seq[name] = 0

    def _close_file(self) -> None:
        writer, stream = self._writer, self._stream
        self._writer = self._stream = None
        if writer is None:
            return
        try:
            writer.finish()
            stream.flush()
            if stat.S_ISREG(os.fstat(stream.fileno()).st_mode):
                # a pipe or a device (/dev/null), written directly, has nothing to sync and
                # refuses fsync (EINVAL): that failed every recording to one
                os.fsync(stream.fileno())
            # finalised in a file that was deleted meanwhile is lost all the same; and a partial
            # file replaced by another must not be moved onto the name
            self._check_in_place(stream)
            written, path = self._writing
            if written != path:
                # moved while still held: a writer starting in between would find the partial
                # file free and the name not yet ours, miss this recording and replace it
                os.replace(written, path)
                self._writing = None
        finally:
            stream.close()
        if written != path:
            try:                          # the rename itself on disk (best effort)
                fd = os.open(path.parent, os.O_RDONLY)
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)
            except OSError:
                pass

    def _check_in_place(self, stream) -> None:
        """Raise ``_NotAtItsPath`` if the open regular file ``stream`` is lost: deleted (no link
        left, ``st_nlink`` 0; its folder deleted, or another file put at its name), where every
        write still succeeds into a file nobody will find.  A file moved away (or its folder) is
        not lost and is finished where it went, unless it is ``replace_when_done``'s partial
        file, which must be at its name (same device and inode) to be moved onto the final one.
        A path that cannot be looked at (permissions) is not taken for gone."""
        mine = os.fstat(stream.fileno())
        if not stat.S_ISREG(mine.st_mode):
            return                        # a pipe or a device, written directly
        partial = self._writing is not None and self._writing[0] != self._writing[1]
        if mine.st_nlink and not partial:
            return
        written = self._written_at
        what = f"its temporary file {written.name}" if partial else "the file"
        try:
            there = os.stat(written)
        except OSError as exc:
            if mine.st_nlink and not isinstance(exc, (FileNotFoundError, NotADirectoryError)):
                return
            there = None
        if there is not None and (there.st_dev, there.st_ino) == (mine.st_dev, mine.st_ino):
            return
        if there is not None:
            raise _NotAtItsPath(f"{what} was replaced by another file while it was written")
        # its links again: deleted between the fstat above and the stat, it would read as moved
        mine = os.fstat(stream.fileno())
        if mine.st_nlink:
            raise _NotAtItsPath(f"{what} was moved away while it was written")
        if not os.path.isdir(written.parent):
            raise _NotAtItsPath(f"its folder {written.parent} was deleted while it was written")
        raise _NotAtItsPath(f"{what} was deleted while it was written")

    def _fail(self, exc: Exception, doing: str = "stopped") -> None:
        """Stop recording on ``exc`` (a write error, a file deleted): the error in ``status``,
        the open file closed, a partial file removed (not what is at its name instead)."""
        if isinstance(exc, _NotAtItsPath):
            self._set_error(f"recording to {self._current_path()} stopped: {exc}")
            self._writing = None          # what is at the name now is not this recording's: left alone
        else:
            self._set_error(f"recording to {self._current_path()} {doing}: {_one_line(exc)}")
        self._abandon_file()

    def _remove_partial(self) -> None:
        """Remove the temporary file of ``replace_when_done`` (never a file under its own name)."""
        if self._writing is not None and self._writing[0] != self._writing[1]:
            try:
                self._writing[0].unlink(missing_ok=True)
            except OSError:
                pass
        self._writing = None

    def _abandon_file(self) -> None:
        stream = self._stream
        self._writer = self._stream = None
        if stream is not None:
            try:
                stream.close()
            except OSError:
                pass
        self._remove_partial()

    def _maybe_rotate(self, log_time_ns: int) -> None:
        # only where the log time moves on: one instant's messages (a batch) stay together
        if not self._rotate or self._file_t0 is None or log_time_ns == self._file_t1:
            return
        if ((self._rotate_bytes and self._file_pos + self._open_chunk >= self._rotate_bytes)
                or (self._rotate_ns and log_time_ns - self._file_t0 >= self._rotate_ns)):
            self._close_file()
            self._file_index += 1
            self._open_file()

    def _handle(self, kind, name, data, log_time_ns) -> None:
        if kind == "topic":
            self._register(name)
            return
        self._maybe_rotate(log_time_ns)
        if self._file_t0 is None:
            self._file_t0 = log_time_ns
        self._file_t1 = log_time_ns
        # rclpy leaves CDR alignment padding uninitialised: zero it so that equal messages give
        # equal bytes (byte-identical renders; better compression too)
        data = zero_padding(data, self._topics[name][0])
        seq = self._seq[name]
        self._seq[name] = seq + 1
        self._writer.add_message(channel_id=self._channel_ids[name], log_time=log_time_ns,
                                 data=data, publish_time=log_time_ns, sequence=seq)
        self._messages += 1
        self._bytes += len(data)
        if self._rotate_bytes:
            pos = self._stream.tell()
            if pos != self._file_pos:     # a chunk went to the file, this message with it
                self._file_pos, self._open_chunk = pos, 0
            else:
                self._open_chunk += len(data)

    def _run(self) -> None:
        queue = self._queue
        next_check = time.monotonic() + CHECK_PATH_S
        while True:
            if self._stream is not None and not self._discard and time.monotonic() >= next_check:
                next_check = time.monotonic() + CHECK_PATH_S
                try:
                    self._check_in_place(self._stream)
                except Exception as exc:  # noqa: BLE001 - as a write error: record, stop, never raise
                    self._fail(exc)
            if not queue:
                time.sleep(_POLL_S)
                continue
            kind, name, data, log_time_ns = queue.popleft()
            if data is not None:
                self._drained_bytes += len(data)
            if kind == "close":
                break
            if self._error or self._discard:
                if kind == "msg":
                    self._dropped_writer += 1
                continue
            try:
                self._handle(kind, name, data, log_time_ns)
            except Exception as exc:  # noqa: BLE001 - full disk, path gone: record, stop, never raise
                if kind == "msg":
                    self._dropped_writer += 1
                self._fail(exc)
        if not self._error and not self._discard:
            try:
                self._close_file()
            except Exception as exc:  # noqa: BLE001
                self._fail(exc, "could not be finalised")
        else:
            self._abandon_file()


class _Counted:
    """A stream that cannot ``tell`` (a pipe), with its position counted: the MCAP writer asks
    where records start (bytes from the file's start) for the summary's indexes."""

    def __init__(self, stream):
        self._stream = stream
        self._position = 0

    def write(self, data) -> int:
        self._stream.write(data)
        self._position += memoryview(data).nbytes
        return memoryview(data).nbytes

    def tell(self) -> int:
        return self._position

    def __getattr__(self, name):        # flush, fileno, close
        return getattr(self._stream, name)


# --------------------------------------------------------------------------------------------
def _fmt(value) -> str:
    if isinstance(value, float):
        return repr(value)
    return str(value)


def recording_metadata(scene, params: dict, seed: int, selection, topics: dict | None = None) -> dict:
    """The ``bearing_sim`` metadata record: how to reproduce this recording.

    scene: the :class:`~bearing_sim_ros.scene.Scene`; params: the node parameters or render
    arguments (JSON-encoded, sorted); seed; selection: ``Simulator.selection`` (tier, reason,
    estimated error, tolerance); topics: each topic's role (``messages.TOPIC_*``) -> the name it
    is recorded under, which a namespace or a remap changes (JSON, key ``topics``: the role
    without a leading slash -> the channel's fully qualified name, ``{"accel": "/rig1/vibration",
    "diagnostics": "/diagnostics", ...}``).  Only deterministic content (no wall clock)."""
    from .. import __version__

    roles = {str(role).strip("/"): _normalise_topic(str(name)) for role, name in (topics or {}).items()}
    extra = {"topics": json.dumps(roles, sort_keys=True)} if roles else {}
    return {**extra,
        "scene": scene.name,
        "scene_description": scene.description,
        "scene_yaml": scene.source_text,
        "scene_path": os.path.basename(scene.source_path) if scene.source_path else "",
        "parameters": json.dumps(params, sort_keys=True, default=_fmt),
        "package": "bearing_sim_ros",
        "package_version": __version__,
        "seed": str(int(seed)),
        "tier": str(selection.tier),
        "tier_reason": str(selection.reason),
        "tier_estimated_error": _fmt(float(selection.estimated_error)),
        "tier_tolerance": _fmt(float(selection.tolerance)),
        "ros_distro": "jazzy",
    }
