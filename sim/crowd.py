"""The other robots of a team as seen by one robot: discs its ladar sees and its body meets.

Each robot's body is a disc (its profile's radius about the rotation centre), so the
others are a handful of circles that move from tick to tick. :class:`Discs` holds where
they are for one robot's step; :func:`cast_discs` intersects a fan of rays with all of
them at once (a (beams, discs) array: no loop over either); :class:`CrowdCollider` adds
them to the static world's clearance, so the swept motion of
:class:`sim.collision.Collider` stops at another robot exactly as at a wall.

>>> import numpy as np
>>> d = Discs(np.array([3.0]), np.array([0.0]), np.array([0.5]), np.array([7]))
>>> t, who = cast_discs(0.0, 0.0, np.array([0.0, 1.5]), d)
>>> t.tolist(), who.tolist()
([2.5, inf], [0, -1])
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.collision import Collider
from sim.shapes import Parts

__all__ = ["Discs", "NO_DISCS", "CrowdCollider", "cast_discs"]


@dataclass(frozen=True, eq=False)
class Discs:
    """Circles of the other robots: centres ``cx``, ``cy`` (m), radii ``r`` (m), owner ids."""

    cx: np.ndarray
    cy: np.ndarray
    r: np.ndarray
    owner: np.ndarray

    def __len__(self) -> int:
        return int(self.cx.shape[0])


NO_DISCS = Discs(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, dtype=np.intp))


def cast_discs(ox: float, oy: float, angles: np.ndarray, discs: Discs
               ) -> tuple[np.ndarray, np.ndarray]:
    """Intersect rays from ``(ox, oy)`` at world ``angles`` with the discs.

    Returns the distance to the nearest disc along each ray (``inf``: none ahead) and
    that disc's position in ``discs`` (-1: none). A ray starting inside a disc does not
    see it.
    """
    n = angles.shape[0]
    if not len(discs):
        return np.full(n, math.inf), np.full(n, -1, dtype=np.intp)
    wx = discs.cx - ox                       # (M,) centre relative to the origin
    wy = discs.cy - oy
    c = wx * wx + wy * wy - discs.r * discs.r
    proj = np.outer(np.cos(angles), wx)      # (B, M) centre's projection on each ray
    proj += np.outer(np.sin(angles), wy)
    disc = proj * proj - c                   # discriminant of t^2 - 2 proj t + c = 0
    ok = (disc >= 0.0) & (proj > 0.0) & (c > 0.0)
    t = np.where(ok, proj - np.sqrt(np.maximum(disc, 0.0)), math.inf)
    j = t.argmin(axis=1)
    best = t[np.arange(n), j]
    return best, np.where(np.isfinite(best), j, -1)


class CrowdCollider(Collider):
    """A :class:`Collider` for the static world plus the discs of the other robots.

    ``discs`` is set before each of the robot's steps (the others stand still while it
    moves). A disc's obstacle index is ``robot_base + owner`` (after the world's
    obstacles), so contacts name the robot touched.
    """

    def __init__(self, parts: Parts, radius: float, robot_base: int) -> None:
        super().__init__(parts, radius)
        self.robot_base = robot_base
        self.discs = NO_DISCS
        self._static_at: tuple[float, float, float, int] | None = None

    def clearance(self, x: float, y: float) -> tuple[float, int]:
        """Return the clearance to the nearest wall or robot, and its index."""
        at = self._static_at
        if at is not None and at[0] == x and at[1] == y:
            c, owner = at[2], at[3]          # the world is static: asked again at a tick
        else:
            c, owner = super().clearance(x, y)
            self._static_at = (x, y, c, owner)
        d = self.discs
        if len(d):
            gaps = np.hypot(d.cx - x, d.cy - y) - d.r - self.radius
            j = int(gaps.argmin())
            if gaps[j] < c:
                return float(gaps[j]), self.robot_base + int(d.owner[j])
        return c, owner

    def _outward(self, x: float, y: float) -> tuple[float, float]:
        """Return the unit vector away from the nearest wall or robot."""
        d = self.discs
        if len(d):
            gaps = np.hypot(d.cx - x, d.cy - y) - d.r
            j = int(gaps.argmin())
            if gaps[j] < Collider.distance(self, x, y)[0]:
                dx, dy = x - float(d.cx[j]), y - float(d.cy[j])
                n = math.hypot(dx, dy)
                return (dx / n, dy / n) if n > 0 else (0.0, 0.0)
        return super()._outward(x, y)
