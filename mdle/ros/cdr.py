"""CDR encoding (XCDR1, little endian) of the ROS 2 messages mdle records.

ROS 2 messages travel as CDR: a 4-byte encapsulation header, then the fields in order,
each aligned to its own size (counted from after the header), strings as a uint32 length
(with the terminating NUL) and the bytes, sequences as a uint32 count and the elements.

The messages written every tick (odometry, transforms, twist, pose, scan, string) have
constant frame names, so all their offsets are known in advance: each is packed by one
precompiled :class:`struct.Struct` (a :class:`Layout`), the scan's ranges as one float32
array. Rare messages (the obstacle markers, the static transform) use the general
:class:`CdrWriter`. Tests check every encoder against the mcap-ros2-support decoder and
against rosbags' Humble and Jazzy type stores.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

__all__ = ["ENCAPSULATION", "CdrWriter", "Layout", "OdometryEncoder", "PoseStampedEncoder",
           "ScanEncoder", "TransformsEncoder", "encode_string", "encode_twist", "quaternion",
           "time_parts"]

#: CDR encapsulation header: plain CDR, little endian, no options.
ENCAPSULATION = b"\x00\x01\x00\x00"
_NS = 1_000_000_000
_COVARIANCE = bytes(36 * 8)  # 36 float64 zeros: no covariance known


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


class Layout:
    """Build a :class:`struct.Struct` format for a message whose offsets are all fixed.

    Fields are added in order; each is aligned as CDR aligns it (padding ``x`` bytes
    inserted), counted from after the encapsulation header, which the format starts
    with (one ``4s`` argument: :data:`ENCAPSULATION`).
    """

    def __init__(self) -> None:
        self._fmt = ["<4s"]
        self._offset = 0

    def _align(self, size: int) -> None:
        pad = (-self._offset) % size
        if pad:
            self._fmt.append(f"{pad}x")
            self._offset += pad

    def add(self, code: str, count: int = 1) -> Layout:
        """Add ``count`` primitives of struct code ``code`` (one argument each)."""
        size = struct.calcsize("<" + code)
        self._align(size)
        self._fmt.append(f"{count}{code}" if count != 1 else code)
        self._offset += size * count
        return self

    def blob(self, data: bytes, align: int = 1) -> bytes:
        """Add constant bytes (one ``s`` argument) aligned to ``align``; returns them."""
        self._align(align)
        self._fmt.append(f"{len(data)}s")
        self._offset += len(data)
        return data

    def string(self, text: str) -> bytes:
        """Add a constant string; returns the bytes to pass for it."""
        return self.blob(string_blob(text), 4)

    @property
    def offset(self) -> int:
        """Bytes so far after the encapsulation header."""
        return self._offset

    def compile(self) -> struct.Struct:
        """Return the struct."""
        return struct.Struct("".join(self._fmt))


class CdrWriter:
    """Write any message field by field (for rare messages; the tick's use :class:`Layout`)."""

    def __init__(self) -> None:
        self.buf = bytearray(ENCAPSULATION)

    def _align(self, size: int) -> None:
        pad = (-(len(self.buf) - 4)) % size
        if pad:
            self.buf += bytes(pad)

    def prim(self, code: str, *values: float | int | bool) -> CdrWriter:
        """Write primitives of struct code ``code`` (``i``, ``I``, ``f``, ``d``, ``?``...)."""
        size = struct.calcsize("<" + code)
        self._align(size)
        self.buf += struct.pack(f"<{len(values)}{code}", *values)
        return self

    def string(self, text: str) -> CdrWriter:
        """Write a string."""
        self._align(4)
        self.buf += string_blob(text)
        return self

    def count(self, n: int) -> CdrWriter:
        """Write a sequence length."""
        return self.prim("I", n)

    def time(self, ns: int) -> CdrWriter:
        """Write a ``builtin_interfaces/Time`` (or Duration)."""
        sec, nanosec = time_parts(ns)
        return self.prim("i", sec).prim("I", nanosec)

    def header(self, ns: int, frame: str) -> CdrWriter:
        """Write a ``std_msgs/Header``."""
        return self.time(ns).string(frame)

    def pose(self, x: float, y: float, yaw: float, z: float = 0.0) -> CdrWriter:
        """Write a ``geometry_msgs/Pose`` (or Transform) of a planar pose."""
        return self.prim("d", x, y, z, *quaternion(yaw))

    def bytes(self) -> bytes:
        """Return the message."""
        return bytes(self.buf)


def encode_string(text: str) -> bytes:
    """Return a ``std_msgs/String``."""
    data = text.encode("utf-8")
    return ENCAPSULATION + struct.pack("<I", len(data) + 1) + data + b"\x00"


_TWIST = struct.Struct("<4s6d")


def encode_twist(v: float, omega: float) -> bytes:
    """Return a ``geometry_msgs/Twist``: forward speed (m/s), turn rate (rad/s)."""
    return _TWIST.pack(ENCAPSULATION, v, 0.0, 0.0, 0.0, 0.0, omega)


class OdometryEncoder:
    """``nav_msgs/Odometry`` in ``frame`` of ``child`` (twist in the child frame)."""

    def __init__(self, frame: str = "odom", child: str = "base_link") -> None:
        lay = Layout().add("i").add("I")
        self._frame = lay.string(frame)
        self._child = lay.string(child)
        lay.add("d", 7)
        lay.blob(_COVARIANCE, 8)
        lay.add("d", 6)
        lay.blob(_COVARIANCE, 8)
        self._pack = lay.compile().pack

    def __call__(self, ns: int, x: float, y: float, yaw: float, v: float, omega: float
                 ) -> bytes:
        """Encode the pose (m, rad) and velocities (m/s, rad/s) at time ``ns``."""
        sec, nanosec = divmod(ns, _NS)
        half = 0.5 * yaw
        return self._pack(ENCAPSULATION, sec, nanosec, self._frame, self._child,
                          x, y, 0.0, 0.0, 0.0, math.sin(half), math.cos(half), _COVARIANCE,
                          v, 0.0, 0.0, 0.0, 0.0, omega, _COVARIANCE)


class PoseStampedEncoder:
    """``geometry_msgs/PoseStamped`` of a planar pose in ``frame``."""

    def __init__(self, frame: str = "map") -> None:
        lay = Layout().add("i").add("I")
        self._frame = lay.string(frame)
        lay.add("d", 7)
        self._pack = lay.compile().pack

    def __call__(self, ns: int, x: float, y: float, yaw: float) -> bytes:
        """Encode the pose (m, rad) at time ``ns``."""
        sec, nanosec = divmod(ns, _NS)
        half = 0.5 * yaw
        return self._pack(ENCAPSULATION, sec, nanosec, self._frame, x, y, 0.0, 0.0, 0.0,
                          math.sin(half), math.cos(half))


class TransformsEncoder:
    """``tf2_msgs/TFMessage`` of planar transforms between fixed frames, all at one time.

    ``pairs`` are (parent, child) frame names; :meth:`__call__` takes one (x, y, yaw) per
    pair, the child's pose in the parent frame.
    """

    def __init__(self, pairs: Sequence[tuple[str, str]]) -> None:
        lay = Layout().add("I")
        self._names: list[tuple[bytes, bytes]] = []
        for parent, child in pairs:
            lay.add("i").add("I")
            p = lay.string(parent)
            c = lay.string(child)
            lay.add("d", 7)
            self._names.append((p, c))
        self._n = len(pairs)
        self._pack = lay.compile().pack

    def __call__(self, ns: int, *poses: tuple[float, float, float]) -> bytes:
        """Encode the transforms at time ``ns``."""
        sec, nanosec = divmod(ns, _NS)
        args: list[object] = [ENCAPSULATION, self._n]
        for (p, c), (x, y, yaw) in zip(self._names, poses, strict=True):
            half = 0.5 * yaw
            args += (sec, nanosec, p, c, x, y, 0.0, 0.0, 0.0, math.sin(half), math.cos(half))
        return self._pack(*args)


class ScanEncoder:
    """``sensor_msgs/LaserScan`` with a fixed beam geometry; ranges as float32.

    Angles in radians in the scan's frame, ranges in metres; ``scan_time`` and
    ``time_increment`` are 0 (a simulated scan is taken at one instant; a real one's
    sweep timing is not known here) and there are no intensities.
    """

    def __init__(self, frame: str, angle_min: float, angle_max: float, angle_increment: float,
                 range_min: float, range_max: float, count: int) -> None:
        self.count = count
        lay = Layout().add("i").add("I")
        frame_blob = lay.string(frame)
        lay.add("f", 7).add("I")
        self._head = lay.compile()
        mid = self._head.pack(ENCAPSULATION, 0, 0, frame_blob, angle_min, angle_max,
                              angle_increment, 0.0, 0.0, range_min, range_max, count)
        self._stamp = struct.Struct("<4siI")
        self._mid = mid[self._stamp.size:]

    def __call__(self, ns: int, ranges: np.ndarray) -> bytes:
        """Encode a scan taken at ``ns``; ``ranges`` (float32, little endian) its beams."""
        sec, nanosec = divmod(ns, _NS)
        if len(ranges) != self.count:
            raise ValueError(f"a scan of {len(ranges)} beams, the laser has {self.count}")
        return b"".join((self._stamp.pack(ENCAPSULATION, sec, nanosec), self._mid,
                         ranges.tobytes(), b"\x00\x00\x00\x00"))
