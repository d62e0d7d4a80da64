"""Canonical CDR: zero the alignment padding, so that a recording is byte-identical run to run.

rclpy's serialisation (Fast-CDR) skips over the padding that aligns a field to its size and
leaves whatever was in the freshly allocated buffer there: the same message serialises to
different bytes each time (e.g. the 6 bytes after ``frame_id`` in a WrenchStamped).  The values
decode identically, but an offline render must be byte-identical for the same seed.  This walks
the payload with the type's ``.msg`` definition (XCDR1, little or big endian, alignment counted
from the end of the 4-byte encapsulation header, as Fast-CDR does) and zeroes the padding only.
Message bytes themselves are never changed: when the walk runs past the end of the buffer (a
layout this walker does not know), the payload is returned untouched.  Unused bytes after the
last field (rmw sizes the buffer from an estimate) are dropped down to the padding to a multiple
of 4, which is zeroed: ``rosbags`` rejects a payload with more than 3 bytes after its last field.
"""
from __future__ import annotations

import struct
from functools import lru_cache

from .schemas import PRIMITIVES, _ARRAY, _BOUND, _split_type, msg_text, qualified_type

SIZES = {"bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2,
         "int32": 4, "uint32": 4, "float32": 4, "int64": 8, "uint64": 8, "float64": 8}


@lru_cache(maxsize=None)
def _fields(msg_type: str) -> tuple:
    """(base type, array) per field of ``msg_type``: array None (scalar), -1 (sequence, bounded or
    not) or N (fixed size); base is a primitive name or 'pkg/msg/Type'."""
    package, name = _split_type(msg_type)
    out = []
    for line in msg_text(package, name).splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        if len(parts) < 2 or "=" in parts[1] or (len(parts) > 2 and parts[2].startswith("=")):
            continue                       # a constant: not serialised
        token = parts[0]
        array = None
        m = _ARRAY.search(token)
        if m:
            inner = m.group(0)[1:-1]
            array = int(inner) if inner.isdigit() else -1
            token = token[:m.start()]
        token = _BOUND.sub("", token)
        if token not in PRIMITIVES:
            token = qualified_type(token, package)
        out.append((token, array))
    if not out:                            # an empty ROS 2 message carries one uint8
        out.append(("uint8", None))
    return tuple(out)


class _Unknown(Exception):
    pass


class _Walker:
    def __init__(self, buf: bytearray, little: bool):
        self.buf = buf
        self.pos = 4                       # after the encapsulation header
        self.u32 = struct.Struct("<I" if little else ">I")

    def align(self, size: int) -> None:
        origin = self.pos - 4
        pad = (-origin) % size
        if pad:
            end = self.pos + pad
            if end > len(self.buf):
                raise _Unknown
            self.buf[self.pos:end] = bytes(pad)
            self.pos = end

    def count(self) -> int:
        self.align(4)
        if self.pos + 4 > len(self.buf):
            raise _Unknown
        n = self.u32.unpack_from(self.buf, self.pos)[0]
        self.pos += 4
        return n

    def value(self, base: str) -> None:
        if base == "string":
            n = self.count()
            self.pos += n
        elif base == "wstring":
            raise _Unknown                 # not used by our types; leave such messages alone
        elif base in SIZES:
            size = SIZES[base]
            self.align(size)
            self.pos += size
        else:
            self.message(base)
        if self.pos > len(self.buf):
            raise _Unknown

    def values(self, base: str, n: int) -> None:
        if n and base in SIZES:            # a primitive array: contiguous, aligned once
            self.align(SIZES[base])
            self.pos += n * SIZES[base]
            if self.pos > len(self.buf):
                raise _Unknown
            return
        for _ in range(n):
            self.value(base)

    def message(self, msg_type: str) -> None:
        for base, array in _fields(msg_type):
            if array is None:
                self.value(base)
            elif array == -1:
                self.values(base, self.count())
            else:
                self.values(base, array)


def zero_padding(data: bytes, msg_type: str) -> bytes:
    """``data`` (a CDR payload of ``msg_type``) with its alignment padding set to zero and unused
    trailing bytes dropped (see the module docstring)."""
    if len(data) < 4 or data[0] != 0 or data[1] not in (0, 1):
        return data
    buf = bytearray(data)
    walker = _Walker(buf, little=data[1] == 1)
    try:
        walker.message(msg_type)
    except (_Unknown, struct.error):
        return data
    # rmw sizes the buffer from an estimate that aligns even empty sequences, so bytes past the
    # last field may belong to no field at all (seen: 4 and 8 after an empty float64[]).  Readers
    # allow at most the padding to a multiple of 4 (rosbags rejects more), so drop the rest and
    # zero that padding
    end = min(len(buf), walker.pos + (-walker.pos) % 4)
    buf[walker.pos:end] = bytes(end - walker.pos)
    return bytes(buf[:end])
