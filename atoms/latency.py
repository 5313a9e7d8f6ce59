"""Latency compensation for the steering law: predict where the robot will be when it acts.

On a real robot the law reads a scan that is already old (the LMS-200 and the serial link:
35-160 ms on a P3-DX behind ARCOS) and its command reaches the wheels late (the ARCOS cycle
and the status-packet delay: about 0.3 s before the turn rate follows, then the firmware's
acceleration ramp). A law that answers the geometry it *saw* turns too late and overshoots.

:class:`Predictor` keeps a short odometry and command history. Each tick,
:meth:`Predictor.predict` returns the rigid motion from the pose at which the scan was taken to
the pose predicted for the moment the new command starts to act: the odometry since the scan
(exact, from the history) followed by the motion the commands already in flight will cause
(integrated with the robot's acceleration limits from the measured speed and turn rate).
:func:`shift_front` and :func:`shift_side` move what each ray saw into that frame, so the
law answers the geometry it will meet. Everything is in the law's (right-hand) frame.

>>> p = Predictor()
>>> p.record_pose(0.0, (0.0, 0.0, 0.0))
>>> p.record_command(0.0, 1.0, 0.0)
>>> (dx, dy, dth) = p.predict(0.0, 0.0, (0.0, 0.0, 0.0), 1.0, 0.0, 0.5, math.inf, math.inf).moved
>>> round(dx, 6), round(dy, 6), round(dth, 6)
(0.5, 0.0, 0.0)
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import NamedTuple

from mdle.atoms.steering import MISS, Ray, wrap

__all__ = ["Predictor", "Prediction", "PoseAt", "CommandSent", "shift_front", "shift_side",
           "compose", "STILL"]

Pose3 = tuple[float, float, float]

#: How much history is kept (s): longer than any scan age or command latency worth predicting.
_HISTORY = 2.0
#: Times closer than this (s) are the same moment.
_SAME_TIME = 1e-9
#: No motion (what :meth:`Predictor.predict` answers for a scan taken now, without latency).
STILL: Pose3 = (0.0, 0.0, 0.0)
#: Integration step of the in-flight motion (s).
_STEP = 0.02
#: A ray whose hit would move further than this along the boundary is dropped (m): the local
#: line-and-curvature model of the boundary does not reach that far.
_MAX_SLIDE = 1.0


def compose(a: Pose3, b: Pose3) -> Pose3:
    """Return the pose ``b`` (given in the frame of ``a``) in ``a``'s parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])


def _relative(a: Pose3, b: Pose3) -> Pose3:
    """Return the pose ``b`` in the frame of ``a`` (both in one parent frame)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2]))


def _ramp(cur: float, target: float, rate: float, dt: float) -> float:
    step = rate * dt
    return target if abs(target - cur) <= step else cur + math.copysign(step, target - cur)


# Prediction, PoseAt and CommandSent are named tuples rather than frozen dataclasses: each
# tick makes one of each, and a frozen dataclass's __init__ costs twice a named tuple's.


class Prediction(NamedTuple):
    """Where the robot is predicted to be when a command sent now starts to act."""

    moved: Pose3
    """The motion from the pose at the scan to that moment, in the frame of the former."""
    pose: Pose3
    """The pose at that moment (odometry frame)."""
    omega: float
    """The turn rate at that moment: the measured one ramped through the commands in flight
    (rad/s)."""


class PoseAt(NamedTuple):
    """An odometry pose and when it was read."""

    time: float
    """Backend time (s)."""
    pose: Pose3
    """``(x, y, theta)`` in the law's frame (m, m, rad)."""


class CommandSent(NamedTuple):
    """A command and when it was sent."""

    time: float
    """Backend time (s)."""
    v: float
    """Speed (m/s)."""
    u: float
    """Turn rate in the law's frame (rad/s)."""


@dataclass
class Predictor:
    """Odometry and command history of one atom, and the prediction made from it.

    Times are on the backend's clock (s), poses ``(x, y, theta)`` in the law's frame.
    """

    poses: deque[PoseAt] = field(default_factory=deque)
    commands: deque[CommandSent] = field(default_factory=deque)

    def record_pose(self, time: float, pose: Pose3) -> None:
        """Remember the odometry pose at ``time`` (once per tick, before :meth:`predict`)."""
        self.poses.append(PoseAt(time, pose))
        while self.poses[0].time < time - _HISTORY:
            self.poses.popleft()

    def record_command(self, time: float, v: float, u: float) -> None:
        """Remember the command sent at ``time`` (m/s, rad/s)."""
        self.commands.append(CommandSent(time, v, u))
        while len(self.commands) > 1 and self.commands[1].time <= time - _HISTORY:
            self.commands.popleft()

    def pose_at(self, time: float) -> Pose3 | None:
        """Return the odometry pose at ``time``, interpolated; None outside the history."""
        poses = self.poses
        if not poses or time < poses[0].time - 1e-9 or time > poses[-1].time + 1e-9:
            return None
        later = poses[-1]
        for item in reversed(poses):  # the scan is recent: search from the newest
            if item.time <= time:
                t0, p0 = item.time, item.pose
                t1, p1 = later.time, later.pose
                if t1 <= t0:
                    return p0
                w = (time - t0) / (t1 - t0)
                return (p0[0] + w * (p1[0] - p0[0]), p0[1] + w * (p1[1] - p0[1]),
                        p0[2] + w * wrap(p1[2] - p0[2]))
            later = item
        return None

    def _command_at(self, time: float, default: tuple[float, float]) -> tuple[float, float]:
        for c in reversed(self.commands):
            if c.time <= time + 1e-9:
                return (c.v, c.u)
        return default

    def predict(self, now: float, stamp: float, pose: Pose3, v: float, omega: float,
                latency: float, accel: float, turn_accel: float) -> Prediction:
        """Return the motion from the pose at ``stamp`` to the one ``latency`` after now.

        Returns that motion (in the frame of the pose at ``stamp``), the predicted pose
        itself (odometry frame) and the turn rate predicted for that moment.

        Parameters
        ----------
        now, stamp : float, s
            The tick's time and the scan's.
        pose : (x, y, theta)
            Odometry now.
        v, omega : float
            Measured speed (m/s) and turn rate (rad/s) now.
        latency : float, s
            Command latency: the commands sent within ``latency`` before now are still to
            act, each for as long as it was held.
        accel, turn_accel : float
            The robot's acceleration limits (m/s^2, rad/s^2; ``inf``: none).
        """
        # a scan stamped now (to the clock's rounding: a stamp and a time summed from the same
        # ticks differ in the last bits) was taken here: no motion since, nothing to look up
        seen = self.pose_at(stamp) if stamp < now - _SAME_TIME else None
        start = STILL if seen is None else _relative(seen, pose)
        if latency <= 0:
            return Prediction(start, pose, omega)
        n = max(1, math.ceil(latency / _STEP))
        h = latency / n
        x = y = th = 0.0
        cur = (v, omega)
        for i in range(n):
            tv, tu = self._command_at(now + (i + 0.5) * h - latency, cur)
            v = _ramp(v, tv, accel, h)
            omega = _ramp(omega, tu, turn_accel, h)
            mid = th + 0.5 * omega * h
            x += v * h * math.cos(mid)
            y += v * h * math.sin(mid)
            th += omega * h
        return Prediction(compose(start, (x, y, th)), compose(pose, (x, y, th)), omega)


def _moved(r_point: tuple[float, float], beta: float, d: Pose3) -> tuple[float, float, float]:
    """Return a boundary point and tangent angle (robot frame at the scan) in the frame ``d``."""
    c, s = math.cos(d[2]), math.sin(d[2])
    px, py = r_point[0] - d[0], r_point[1] - d[1]
    return c * px + s * py, -s * px + c * py, beta - d[2]


def shift_front(ray: Ray, d: Pose3) -> Ray:
    """Return what the front ray (bearing 0) would see after the motion ``d``.

    The boundary near the hit is its tangent line, whose direction turns with the curvature
    as the hit slides along it.
    """
    if not ray.hit or d == (0.0, 0.0, 0.0):
        return ray
    px, py, phi = _moved((ray.r, 0.0), ray.beta, d)
    sp = math.sin(phi)
    if abs(sp) < 1e-6:
        return MISS
    slide = -py / sp
    r = px + slide * math.cos(phi)
    if r <= 0 or abs(slide) > _MAX_SLIDE:
        return MISS
    return Ray(True, r, wrap(phi + ray.kappa * slide), ray.kappa)


def shift_side(ray: Ray, d: Pose3) -> Ray:
    """Return what the side ray (bearing -90 deg) would see after the motion ``d``."""
    if not ray.hit or d == (0.0, 0.0, 0.0):
        return ray
    px, py, phi = _moved((0.0, -ray.r), ray.beta, d)
    cp = math.cos(phi)
    if abs(cp) < 1e-6:
        return MISS
    slide = -px / cp
    r = -(py + slide * math.sin(phi))
    if r <= 0 or abs(slide) > _MAX_SLIDE:
        return MISS
    return Ray(True, r, wrap(phi + ray.kappa * slide), ray.kappa)
