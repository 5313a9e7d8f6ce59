"""A tick's ROS 2 messages as ready MCAP Message records, packed at once.

Every tick a run publishes its odometry (``/odom``), transforms (``/tf``), command
(``/cmd_vel``), in simulation the true pose (``/ground_truth``), and the trace's sample
line (``/mdle/state``). Their frame names are constant, so every byte of the five
Message records (the MCAP record header and the CDR message each) is at an offset known
in advance, except the state line's text, which comes last: :class:`TickRecords` packs
them with one precompiled :class:`struct.Struct` straight into the open chunk's buffer,
and the MCAP file indexes them as one :class:`~mdle.ros.mcap_file.RecordGroup`. A new
scan is one more record (:class:`ScanRecords`): header packed, the float32 ranges
copied in as they are.

Fields that are always zero (z, the quaternion's x and y, the covariances, a planar
twist's other axes) are struct pad bytes: nothing to pass or convert. The records'
bytes are exactly what a field-by-field CDR writer makes (tests decode them with
mcap-ros2-support and rosbags).
"""

from __future__ import annotations

import math
import struct

import numpy as np

from mdle.ros.cdr import ENCAPSULATION, Layout
from mdle.ros.mcap_file import McapFile, RecordGroup

__all__ = ["TickRecords", "ScanRecords"]

_MESSAGE = "BQHIQQ"  # MCAP Message record: opcode, length, channel, sequence, log, publish
_OP = 0x05
_NS = 1_000_000_000
_NO_INTENSITIES = b"\x00\x00\x00\x00"
_FLOAT32 = np.dtype("<f4")
_UNKNOWN = (math.nan, math.nan, math.nan)  # a simulated sample without its true pose


def _stamp(lay: Layout) -> Layout:
    """Add a ``builtin_interfaces/Time`` (sec, nanosec: two arguments)."""
    return lay.add("i").add("I")


def _planar_pose(lay: Layout) -> Layout:
    """Add a Pose or Transform of a planar pose: x, y, qz, qw (four arguments)."""
    return lay.add("d", 2).zeros("d", 3).add("d", 2)


def _planar_twist(lay: Layout) -> Layout:
    """Add a Twist: linear.x and angular.z (two arguments)."""
    return lay.add("d").zeros("d", 4).add("d")


class TickRecords:
    """Pack a tick's ``/odom``, ``/tf``, ``/cmd_vel``, ``/ground_truth`` and ``/mdle/state``.

    Parameters
    ----------
    out : McapFile
        The file; the channels become one record group in it.
    odom, tf, cmd, state, truth : int
        Channel ids (``truth`` 0 on a robot: no ``/ground_truth`` and no ``map -> odom``).
    frames : (map, odom, base)
        Frame names.
    """

    def __init__(self, out: McapFile, odom: int, tf: int, cmd: int, state: int, truth: int,
                 frames: tuple[str, str, str]) -> None:
        self._out = out
        map_, odom_f, base = frames
        self.simulation = bool(truth)
        fmt = "<"
        offsets = []
        size = 0
        lengths = []
        bodies = []
        # nav_msgs/Odometry: header, child frame, pose + covariance, twist + covariance
        lay = _stamp(Layout())
        self._f_odom = lay.string(odom_f)
        self._f_base = lay.string(base)
        _planar_twist(_planar_pose(lay).zeros("d", 36)).zeros("d", 36)
        bodies.append(lay)
        # tf2_msgs/TFMessage: odom -> base_link, in simulation map -> odom after it
        lay = Layout().add("I")
        _stamp(lay)
        lay.string(odom_f)
        lay.string(base)
        _planar_pose(lay)
        if truth:
            _stamp(lay)
            self._f_map = lay.string(map_)
            lay.string(odom_f)
            _planar_pose(lay)
        bodies.append(lay)
        bodies.append(_planar_twist(Layout()))  # geometry_msgs/Twist
        channels = [odom, tf, cmd]
        if truth:  # geometry_msgs/PoseStamped in map
            lay = _stamp(Layout())
            lay.string(map_)
            bodies.append(_planar_pose(lay))
            channels.append(truth)
        bodies.append(Layout().add("I"))  # std_msgs/String: its length; the text follows
        channels.append(state)
        for lay in bodies:
            body = lay.format
            n = struct.calcsize("<" + body)
            offsets.append(size)
            lengths.append(22 + n)  # a Message record's length counts from the channel id
            size += 31 + n
            fmt += _MESSAGE + body
        self._lengths = tuple(lengths)
        self._size = size  # the records' bytes before the state line's text
        self._pack_into = struct.Struct(fmt).pack_into
        self.group: RecordGroup = out.group(channels, offsets)
        self._channels = tuple(channels)

    def __call__(self, ns: int, x: float, y: float, theta: float, v: float, omega: float,
                 cmd_v: float, cmd_omega: float, truth: tuple[float, float, float] | None,
                 line: str) -> None:
        """Add the tick at ``ns``: odometry pose and speeds, command, true pose, state line.

        In simulation a sample without its true pose (none in a trace's record) gets NaN
        for it, in ``/ground_truth`` and in ``map -> odom``: unknown, as the trace says.
        """
        text = line.encode("utf-8")
        n = len(text) + 1
        sec, nsec = divmod(ns, _NS)
        half = 0.5 * theta
        qz, qw = math.sin(half), math.cos(half)
        group = self.group
        at = self._size
        buf, pos = self._out.reserve(group, ns, at + n)
        seq = group.count - 1
        lo, lt, lc = self._lengths[:3]
        co, ct, cc = self._channels[:3]
        enc, fo, fb = ENCAPSULATION, self._f_odom, self._f_base
        if self.simulation:
            tx, ty, tth = truth if truth is not None else _UNKNOWN
            # map -> odom: the true pose composed with the inverse of the odometry pose
            phi = tth - theta
            c, s = math.cos(phi), math.sin(phi)
            self._pack_into(
                buf, pos,
                _OP, lo, co, seq, ns, ns, enc, sec, nsec, fo, fb, x, y, qz, qw, v, omega,
                _OP, lt, ct, seq, ns, ns, enc, 2, sec, nsec, fo, fb, x, y, qz, qw,
                sec, nsec, self._f_map, fo, tx - c * x + s * y, ty - s * x - c * y,
                math.sin(0.5 * phi), math.cos(0.5 * phi),
                _OP, lc, cc, seq, ns, ns, enc, cmd_v, cmd_omega,
                _OP, self._lengths[3], self._channels[3], seq, ns, ns, enc, sec, nsec,
                self._f_map, tx, ty, math.sin(0.5 * tth), math.cos(0.5 * tth),
                _OP, 30 + n, self._channels[4], seq, ns, ns, enc, n)
        else:
            self._pack_into(
                buf, pos,
                _OP, lo, co, seq, ns, ns, enc, sec, nsec, fo, fb, x, y, qz, qw, v, omega,
                _OP, lt, ct, seq, ns, ns, enc, 1, sec, nsec, fo, fb, x, y, qz, qw,
                _OP, lc, cc, seq, ns, ns, enc, cmd_v, cmd_omega,
                _OP, 30 + n, self._channels[3], seq, ns, ns, enc, n)
        at += pos
        buf[at:at + n - 1] = text
        buf[at + n - 1] = 0


class ScanRecords:
    """Pack ``sensor_msgs/LaserScan`` records of one beam geometry; ranges as float32.

    Angles in radians in the scan's frame, ranges in metres, times in seconds; no
    intensities. ``group`` is the ``/scan`` channel's record group.
    """

    def __init__(self, out: McapFile, group: RecordGroup, frame: str, angle_min: float,
                 angle_max: float, angle_increment: float, range_min: float,
                 range_max: float, count: int, scan_time: float = 0.0,
                 time_increment: float = 0.0) -> None:
        self._out = out
        self.group = group
        self.count = count
        self._nbytes = 4 * count
        lay = _stamp(Layout())
        frame_blob = lay.string(frame)
        lay.add("f", 7).add("I")
        at_stamp = struct.calcsize("<4siI")
        # everything after the stamp is constant for this geometry: one blob
        self._mid = lay.compile().pack(
            ENCAPSULATION, 0, 0, frame_blob, angle_min, angle_max, angle_increment,
            time_increment, scan_time, range_min, range_max, count)[at_stamp:]
        body = len(self._mid) + at_stamp + 4 * count + 4
        self._length = 22 + body
        self._channel = group.channels[0]
        packer = struct.Struct(f"<{_MESSAGE}4siI{len(self._mid)}s")
        self._pack_into = packer.pack_into
        self._head = packer.size

    def __call__(self, ns: int, stamp: int, ranges: np.ndarray) -> None:
        """Add a scan seen at ``ns``, taken at ``stamp``; ``ranges`` little-endian float32.

        The ranges are appended as they lie in memory: a C-contiguous array (as
        :func:`mdle.trace.scan_ranges` and :func:`mdle.trace.decode_ranges` make them).
        """
        if ranges.dtype is not _FLOAT32 or ranges.nbytes != self._nbytes:
            if len(ranges) != self.count:
                raise ValueError(f"a scan of {len(ranges)} beams, the laser has {self.count}")
            raise ValueError("scan ranges must be little-endian float32")
        sec, nsec = divmod(stamp, _NS)
        head = self._head
        buf, pos = self._out.reserve(self.group, ns, head + self._nbytes + 4)
        self._pack_into(buf, pos, _OP, self._length, self._channel, self.group.count - 1, ns,
                        ns, ENCAPSULATION, sec, nsec, self._mid)
        at = pos + head + self._nbytes
        buf[pos + head:at] = ranges.data
        buf[at:at + 4] = _NO_INTENSITIES
