"""The robot a plan is checked against: its speed and turn-rate limits, and how it was chosen.

A control law's speed or turn rate given as a constant (``go(3 m/s)``) that the robot
cannot reach is clamped by the robot, so the plan does not do what it says (a 3 m/s dash
on a 2.2 m/s Pioneer covers less ground than planned and its interrupts fire late). The
checker warns about such constants when it knows the robot (:class:`KnownRobot`).

>>> r = KnownRobot("pioneer2dx", 2.2, 2.2, math.radians(500), "the default robot")
>>> excess(r, SPEED, 3.0)
'the top speed of `pioneer2dx` (the default robot) is 2.2 m/s'
>>> excess(r, SPEED, -1.0) is None, excess(r, TURN_RATE, math.radians(600))
(True, 'the largest turn rate of `pioneer2dx` (the default robot) is 500 deg/s')
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from mdle.core.units import SPEED, TURN_RATE, Dim

__all__ = ["KnownRobot", "excess", "SPEED", "TURN_RATE"]

#: Constants within this fraction above a limit are not worth a warning (rounding).
_SLACK = 1e-9


@dataclass(frozen=True)
class KnownRobot:
    """A robot's limits (SI: m/s, rad/s) and how the robot was chosen.

    ``how`` completes "`NAME` (...)" in a message: ``the default robot``,
    ``--robot``, ``the robot of world `corridor```.
    """

    name: str
    max_speed: float
    max_reverse_speed: float
    max_turn_rate: float
    how: str

    @classmethod
    def of(cls, profile: Any, how: str) -> KnownRobot:
        """Take the limits of a :class:`sim.robot.RobotProfile` (or anything with them)."""
        return cls(str(profile.name), float(profile.max_speed),
                   float(profile.max_reverse_speed), float(profile.max_turn_rate), how)


def excess(robot: KnownRobot, dim: Dim, value: float) -> str | None:
    """Say which limit ``value`` (SI) goes beyond, or None when the robot can do it.

    ``dim`` is the parameter's dimension: a speed (negative: reverse) or a turn rate
    (either sign); any other dimension has no limit here.
    """
    if not math.isfinite(value):
        return None
    who = f"`{robot.name}` ({robot.how})"
    if dim == SPEED:
        reverse = value < 0
        limit = robot.max_reverse_speed if reverse else robot.max_speed
        if abs(value) <= limit * (1 + _SLACK):
            return None
        what = "top reverse speed" if reverse else "top speed"
        return f"the {what} of {who} is {limit:.4g} m/s"
    if dim == TURN_RATE:
        if abs(value) <= robot.max_turn_rate * (1 + _SLACK):
            return None
        return (f"the largest turn rate of {who} is "
                f"{math.degrees(robot.max_turn_rate):.4g} deg/s")
    return None
