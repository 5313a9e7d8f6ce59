"""ROS 2 messages to mdle's values and back: scans, odometry, commands, transforms.

Everything mdle holds is SI in REP-103 axes, as ROS 2 is, so the conversions are about
layout: a ``LaserScan`` is a fan of float32 ranges from ``angle_min`` in the laser's
frame, with no return as +inf (REP-117) or beyond ``range_max``; an mdle :class:`Scan`
holds bearings in the robot frame (the laser mount's yaw added, as the simulator's ladar
does), the no-return beams at ``max_range`` and a validity mask. Odometry's pose is in
its ``header.frame_id`` (``odom``, REP-105), its twist in ``child_frame_id``
(``base_link``): forward speed ``linear.x``, turn rate ``angular.z``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from mdle.core.backend import Command, Scan
from mdle.core.pose import Pose
from mdle.ros2 import types as msg

__all__ = ["mount_from_transforms", "odometry_message", "odometry_values", "ScanReader",
           "scan_message", "seconds", "static_transform", "time_of", "twist_message",
           "yaw_of"]


def time_of(t: float) -> msg.Time:
    """Return a ``builtin_interfaces/Time`` for ``t`` seconds (never below 0)."""
    ns = max(0, round(t * 1e9))
    sec, nanosec = divmod(ns, 1_000_000_000)
    return msg.Time(sec, nanosec)


def seconds(stamp: msg.Time) -> float:
    """Return a ``builtin_interfaces/Time`` in seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def yaw_of(q: msg.Quaternion) -> float:
    """Return the rotation about z of a quaternion (its yaw, rad)."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _quaternion(yaw: float) -> msg.Quaternion:
    return msg.Quaternion(0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def twist_message(cmd: Command) -> msg.Twist:
    """Return the ``geometry_msgs/Twist`` of a command."""
    return msg.Twist(msg.Vector3(float(cmd.v), 0.0, 0.0), msg.Vector3(0.0, 0.0, float(cmd.omega)))


def odometry_message(t: float, pose: Pose, v: float, omega: float, odom: str, base: str,
                     pose_covariance: Iterable[float] | None = None,
                     twist_covariance: Iterable[float] | None = None) -> msg.Odometry:
    """Return ``nav_msgs/Odometry``: ``pose`` in frame ``odom``, the twist in ``base``.

    The covariances are 36 numbers each (row-major x y z roll pitch yaw); zeros if not given.
    """
    return msg.Odometry(
        msg.Header(time_of(t), odom), base,
        msg.PoseWithCovariance(msg.Pose(msg.Point(pose.x, pose.y, 0.0),
                                        _quaternion(pose.theta)),
                               _covariance(pose_covariance)),
        msg.TwistWithCovariance(msg.Twist(msg.Vector3(v, 0.0, 0.0),
                                          msg.Vector3(0.0, 0.0, omega)),
                                _covariance(twist_covariance)))


def _covariance(values: Iterable[float] | None) -> list[float]:
    out = [0.0] * 36 if values is None else [float(x) for x in values]
    if len(out) != 36:
        raise ValueError(f"a covariance has 36 numbers, got {len(out)}")
    return out


def odometry_values(m: msg.Odometry) -> tuple[Pose, float, float]:
    """Return the pose (x, y, yaw), forward speed and turn rate of an odometry message."""
    p = m.pose.pose
    tw = m.twist.twist
    return Pose(p.position.x, p.position.y, yaw_of(p.orientation)), tw.linear.x, tw.angular.z


def static_transform(t: float, parent: str, child: str,
                     mount: tuple[float, float, float]) -> msg.TransformStamped:
    """Return the transform ``parent -> child`` of a planar pose (x, y, yaw)."""
    x, y, yaw = mount
    return msg.TransformStamped(msg.Header(time_of(t), parent), child,
                                msg.Transform(msg.Vector3(x, y, 0.0), _quaternion(yaw)))


def mount_from_transforms(transforms: Iterable[msg.TransformStamped], base: str,
                          laser: str) -> tuple[float, float, float] | None:
    """Return the planar pose of frame ``laser`` in frame ``base``, or None if not linked.

    Follows the chain of transforms from ``laser`` up to ``base`` (``base_link ->
    laser_mount -> laser``, say), composing their x, y and yaw.
    """
    parent_of = {tf.child_frame_id.lstrip("/"): tf for tf in transforms}
    x = y = yaw = 0.0
    frame = laser.lstrip("/")
    target = base.lstrip("/")
    for _ in range(len(parent_of) + 1):
        if frame == target:
            return x, y, yaw
        tf = parent_of.get(frame)
        if tf is None:
            return None
        tr = tf.transform
        a = yaw_of(tr.rotation)
        c, s = math.cos(a), math.sin(a)
        # the pose so far, seen from the parent frame
        x, y, yaw = tr.translation.x + c * x - s * y, tr.translation.y + s * x + c * y, yaw + a
        frame = tf.header.frame_id.lstrip("/")
    return None


def scan_message(scan: Scan, mount_yaw: float, frame: str, t: float,
                 period: float) -> msg.LaserScan:
    """Return the ``sensor_msgs/LaserScan`` of a scan (no return: +inf, REP-117).

    The bearings are the robot frame's; the message's angles are the laser's, so the
    mount's yaw is taken off.
    """
    b = scan.bearings
    n = len(b)
    step = float(b[1] - b[0]) if n > 1 else 0.0
    ranges = np.where(scan.valid, scan.ranges, np.inf).astype(np.float32)
    return msg.LaserScan(msg.Header(time_of(t), frame), float(b[0] - mount_yaw),
                         float(b[-1] - mount_yaw), step, 0.0, float(period), 0.0,
                         float(scan.max_range), ranges.tolist(), [])


class ScanReader:
    """Turns ``LaserScan`` messages into :class:`Scan`; keeps the bearings of one layout."""

    def __init__(self) -> None:
        self._key: tuple[float, float, int, float] | None = None
        self._bearings = np.zeros(0)
        self._reverse = False

    def scan(self, m: msg.LaserScan, mount_yaw: float, stamp: float) -> Scan:
        """Return the scan of message ``m``; ``stamp`` on the backend's clock.

        Beams that are not finite or lie outside [range_min, range_max] are not valid and
        hold ``range_max``; a laser that turns clockwise (negative increment) is read in
        reverse, so bearings always increase.

        Raises
        ------
        ValueError
            A scan no laser sends: no beams, or angles that are not finite numbers, or
            several beams with no angle between them.
        """
        ranges = np.asarray(m.ranges, dtype=np.float64)
        n = len(ranges)
        if n == 0:
            raise ValueError("a scan without beams")
        if not (math.isfinite(m.angle_min) and math.isfinite(m.angle_increment)
                and (n == 1 or m.angle_increment != 0.0)):
            raise ValueError(f"a scan of {n} beams from angle {m.angle_min} by "
                             f"{m.angle_increment} rad")
        key = (m.angle_min, m.angle_increment, n, mount_yaw)
        if key != self._key:
            bearings: np.ndarray = m.angle_min + m.angle_increment * np.arange(n) + mount_yaw
            self._reverse = m.angle_increment < 0
            if self._reverse:
                bearings = bearings[::-1].copy()
            bearings.setflags(write=False)
            self._bearings, self._key = bearings, key
        if self._reverse:
            ranges = ranges[::-1].copy()
        top = float(m.range_max) if math.isfinite(m.range_max) and m.range_max > 0 else 0.0
        with np.errstate(invalid="ignore"):
            valid = np.isfinite(ranges) & (ranges >= m.range_min) & (ranges <= top)
        ranges[~valid] = top
        ranges.setflags(write=False)
        valid.setflags(write=False)
        return Scan(ranges, self._bearings, valid, stamp, top)
