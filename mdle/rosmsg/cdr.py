"""CDR encoding (XCDR1, little endian) of the ROS 2 messages mdle records.

ROS 2 messages travel as CDR: a 4-byte encapsulation header, then the fields in order,
each aligned to its own size (counted from after the header), strings as a uint32 length
(with the terminating NUL) and the bytes, sequences as a uint32 count and the elements.

The messages written every tick (odometry, transforms, twist, pose, scan, string) have
constant frame names, so all their offsets are known in advance: a :class:`Layout`
gives their constant bytes and where their variable fields lie, from which
:mod:`mdle.record.tick` fills a whole batch of ticks with numpy. Rare messages (the
obstacle markers, the static transform) use the general :class:`CdrWriter`. Tests
check every message against the mcap-ros2-support decoder and against rosbags' Humble
and Jazzy type stores.
"""

from __future__ import annotations

import math
import struct
from typing import Any, Self

__all__ = ["ENCAPSULATION", "CdrWriter", "Layout", "encode_string", "quaternion", "string_blob",
           "time_parts"]

#: CDR encapsulation header: plain CDR, little endian, no options.
ENCAPSULATION = b"\x00\x01\x00\x00"
_NS = 1_000_000_000


def time_parts(ns: int) -> tuple[int, int]:
    """Return ``builtin_interfaces/Time`` (sec, nanosec) for a time in nanoseconds."""
    sec, nanosec = divmod(ns, _NS)
    return sec, nanosec


def quaternion(yaw: float) -> tuple[float, float, float, float]:
    """Return the unit quaternion (x, y, z, w) of a rotation by ``yaw`` about z (rad)."""
    half = 0.5 * yaw
    return 0.0, 0.0, math.sin(half), math.cos(half)


def string_blob(text: str) -> bytes:
    """Return a CDR string (uint32 length with the NUL, the UTF-8 bytes, NUL)."""
    data = text.encode("utf-8")
    return struct.pack("<I", len(data) + 1) + data + b"\x00"


class CdrWriter:
    """Write any message field by field (for rare messages; the tick's use :class:`Layout`)."""

    def __init__(self) -> None:
        self.buf = bytearray(ENCAPSULATION)

    def _align(self, size: int) -> None:
        pad = (-(len(self.buf) - 4)) % size
        if pad:
            self.buf += bytes(pad)

    def prim(self, code: str, *values: float | int | bool) -> Self:
        """Write primitives of struct code ``code`` (``i``, ``I``, ``f``, ``d``, ``?``...)."""
        size = struct.calcsize("<" + code)
        self._align(size)
        self.buf += struct.pack(f"<{len(values)}{code}", *values)
        return self

    def string(self, text: str) -> Self:
        """Write a string."""
        self._align(4)
        self.buf += string_blob(text)
        return self

    def count(self, n: int) -> Self:
        """Write a sequence length."""
        return self.prim("I", n)

    def time(self, ns: int) -> Self:
        """Write a ``builtin_interfaces/Time`` (or Duration)."""
        sec, nanosec = time_parts(ns)
        return self.prim("i", sec).prim("I", nanosec)

    def header(self, ns: int, frame: str) -> Self:
        """Write a ``std_msgs/Header``."""
        return self.time(ns).string(frame)

    def pose(self, x: float, y: float, yaw: float, z: float = 0.0) -> Self:
        """Write a ``geometry_msgs/Pose`` (or Transform) of a planar pose."""
        return self.prim("d", x, y, z, *quaternion(yaw))

    def bytes(self) -> bytes:
        """Return the message."""
        return bytes(self.buf)


class Layout(CdrWriter):
    """Lay out a message whose offsets are all fixed: constant bytes and named fields.

    Fields are added in order, each aligned as CDR aligns it (counted from after the
    encapsulation header the message starts with); constants are written as
    :class:`CdrWriter` writes them (:meth:`prim`, :meth:`string`). The result is a
    :attr:`template` (the constant bytes, zeros where the named fields go) and the named
    fields' numpy types and offsets (:attr:`fields`): a batch of such messages is the
    template repeated, its named fields filled a column at a time (:mod:`mdle.record.tick`).
    """

    _NUMPY = {"d": "<f8", "f": "<f4", "i": "<i4", "I": "<u4"}

    def __init__(self) -> None:
        super().__init__()
        #: name -> (numpy type, offset from the start of the message)
        self.fields: dict[str, tuple[Any, int]] = {}

    def field(self, name: str, code: str, count: int = 1) -> Self:
        """Add a named field of ``count`` primitives of struct code ``code`` (d, f, i, I)."""
        size = struct.calcsize("<" + code)
        self._align(size)
        kind = self._NUMPY[code]
        self.fields[name] = ((kind, count) if count != 1 else kind, len(self.buf))
        self.buf += bytes(size * count)
        return self

    def zeros(self, code: str, count: int = 1) -> Self:
        """Add ``count`` primitives of struct code ``code`` that are always 0.

        Zero of every CDR number type is all zero bytes.
        """
        return self.prim(code, *([0] * count))

    @property
    def template(self) -> bytes:
        """The message's bytes, zeros in the named fields."""
        return bytes(self.buf)


def encode_string(text: str) -> bytes:
    """Return a ``std_msgs/String``."""
    data = text.encode("utf-8")
    return ENCAPSULATION + struct.pack("<I", len(data) + 1) + data + b"\x00"
