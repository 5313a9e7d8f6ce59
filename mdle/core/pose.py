"""A planar pose: where a robot is and which way it faces.

Its own module because both sides of the seam need it: the observations a backend
gives (:mod:`mdle.core.backend`) and the poses a team's robots send each other
(:mod:`mdle.core.messages`).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Pose"]


@dataclass(frozen=True)
class Pose:
    """A planar pose in the odometry (world) frame: metres and radians."""

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0
