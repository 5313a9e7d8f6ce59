"""A simulated world: obstacles, start pose, robot and ladar profiles, seed; ground truth.

:class:`World` is immutable. Its derived data (primitives, ray caster, shapely
geometry) is built on first use and cached. Ground-truth queries: :meth:`World.cast`
(exact ranges, tangents and curvatures of rays), :meth:`World.nearest_boundary` and
:meth:`World.clearance`.

>>> from mdle.sim.shapes import Circle
>>> w = World("demo", obstacles=(Circle((3.0, 0.0), 1.0),))
>>> float(w.clearance((0.0, 0.0), radius=0.25))
1.75
>>> hits = w.cast((0.0, 0.0), [0.0])
>>> float(hits.ranges[0]), float(hits.curvatures[0])
(2.0, -1.0)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from mdle.core.pose import Pose
from mdle.sim.distance import nearest_boundary
from mdle.sim.ladar import LMS200, LadarProfile
from mdle.sim.maps import FloorPlan
from mdle.sim.raycast import RayCaster, RayHits
from mdle.sim.robot import RobotProfile
from mdle.sim.shapes import Circle, Parts, Shape

if TYPE_CHECKING:
    from shapely.geometry.base import BaseGeometry

__all__ = ["Nearest", "RobotPlace", "World"]

_TAU = 2.0 * math.pi
_DISC_BLOCK = 1 << 22   # point-disc pairs per block of :func:`_in_discs` (32 MB a temporary)


def _in_discs(pts: np.ndarray, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Tell which of ``pts`` (N, 2) lie strictly inside one of the discs, in blocks of points."""
    out = np.zeros(len(pts), dtype=bool)
    step = max(1, _DISC_BLOCK // len(radii))
    for k in range(0, len(pts), step):   # blocks bound the memory of N x C distances
        q = pts[k:k + step]
        d = np.hypot(q[:, 0:1] - centers[:, 0], q[:, 1:2] - centers[:, 1])
        out[k:k + step] = (d < radii).any(axis=1)
    return out


def _default_robot() -> RobotProfile:
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile

    return robot_profile(DEFAULT_ROBOT)


@dataclass(frozen=True)
class Nearest:
    """The nearest boundary point to a query point (or arrays of them, for many points).

    ``distance`` in metres (``inf`` in an empty world), ``point`` the (2,) or (N, 2)
    boundary point, ``obstacle`` the index into ``World.obstacles`` (-1 if none).
    """

    distance: float | np.ndarray
    point: np.ndarray
    obstacle: int | np.ndarray


@dataclass(frozen=True)
class RobotPlace:
    """One robot of a team: its name, profile, ladar and start pose (world frame)."""

    name: str
    profile: RobotProfile
    ladar: LadarProfile
    start: Pose


@dataclass(frozen=True, eq=False)
class World:
    """An immutable simulated world (SI units inside: metres, radians).

    Attributes
    ----------
    name : str
    obstacles : tuple of shapes (:mod:`sim.shapes`)
    start_pose : Pose
    seed : int
    robot : RobotProfile
    ladar : LadarProfile
    description : str
        One line for ``mdle worlds``.
    source : str or None
        The YAML file it came from.
    extent : (xmin, ymin, xmax, ymax) or None
        Plot extent given in the file; :attr:`bounds` falls back to the obstacles'.
    robots : tuple of RobotPlace
        The robots of a team world (``mdle run --team``), each with its name, profile,
        ladar and start; empty for a one-robot world.
    """

    name: str
    obstacles: tuple[Shape | FloorPlan, ...] = ()
    start_pose: Pose = field(default_factory=Pose)
    seed: int = 0
    robot: RobotProfile = field(default_factory=lambda: _default_robot())
    ladar: LadarProfile = LMS200
    description: str = ""
    source: str | None = None
    extent: tuple[float, float, float, float] | None = None
    robots: tuple[RobotPlace, ...] = ()

    # ------------------------------------------------------------- derived data
    @cached_property
    def parts(self) -> Parts:
        """All boundary primitives, owners indexing :attr:`obstacles`."""
        centers, radii, owners = self._discs
        if not len(radii):
            return Parts.concat([o.parts() for o in self.obstacles])
        # Circles as arrays, not one Parts each: 200,000 of them cost seconds otherwise.
        rest = [i for i, o in enumerate(self.obstacles) if not isinstance(o, Circle)]
        p = Parts.concat([self.obstacles[i].parts() for i in rest],
                         np.asarray(rest, dtype=np.intp))
        n = len(radii)
        arc_owner = np.concatenate([p.arc_owner, owners])
        order = np.argsort(arc_owner, kind="stable")   # obstacle order, as one concat gives

        def arcs(mine: np.ndarray, theirs: np.ndarray) -> np.ndarray:
            return np.concatenate([mine, theirs])[order]

        return dataclasses.replace(
            p, arc_center=arcs(p.arc_center, centers), arc_radius=arcs(p.arc_radius, radii),
            arc_start=arcs(p.arc_start, np.zeros(n)), arc_sweep=arcs(p.arc_sweep,
                                                                     np.full(n, _TAU)),
            arc_side=arcs(p.arc_side, np.full(n, -1.0)), arc_owner=arc_owner[order])

    @cached_property
    def _discs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The circles among the obstacles: centres (C, 2), radii (C,), obstacle indices."""
        owners = [i for i, o in enumerate(self.obstacles) if isinstance(o, Circle)]
        circles = [o for o in self.obstacles if isinstance(o, Circle)]
        centers = np.array([c.center for c in circles], dtype=float).reshape(-1, 2)
        radii = np.array([c.radius for c in circles], dtype=float)
        return centers, radii, np.asarray(owners, dtype=np.intp)

    @cached_property
    def caster(self) -> RayCaster:
        """The ray caster built once for this world."""
        return RayCaster(self.parts)

    @cached_property
    def geometry(self) -> BaseGeometry:
        """A shapely GeometryCollection of all obstacles (curves approximated; for plots)."""
        import shapely

        return shapely.GeometryCollection([o.geometry() for o in self.obstacles])

    @cached_property
    def _prepared(self) -> tuple[Any, np.ndarray] | None:
        """The obstacles other than circles, prepared, and an index of their boxes.

        None if there are none. A point is inside their union exactly when it is inside
        one of them, so no union is made: the union of 20,000 rectangles was 1.6 s of
        CPU in one call into GEOS, which no Ctrl-C can cut. Circles are tested in closed
        form (:meth:`inside`).
        """
        import shapely

        geoms = np.array([o.geometry() for o in self.obstacles if not isinstance(o, Circle)],
                         dtype=object)
        if not len(geoms):
            return None
        shapely.prepare(geoms)
        return shapely.STRtree(geoms), geoms

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) in metres: the file's extent, else obstacles + start."""
        if self.extent is not None:
            return self.extent
        xs = [self.start_pose.x, *(r.start.x for r in self.robots)]
        ys = [self.start_pose.y, *(r.start.y for r in self.robots)]
        centers, radii, _ = self._discs
        if len(radii):   # from the arrays: no polygon per circle
            xs += [float((centers[:, 0] - radii).min()), float((centers[:, 0] + radii).max())]
            ys += [float((centers[:, 1] - radii).min()), float((centers[:, 1] + radii).max())]
        others = [o.geometry() for o in self.obstacles if not isinstance(o, Circle)]
        if others:
            import shapely

            x0, y0, x1, y1 = shapely.total_bounds(others)
            xs += [float(x0), float(x1)]
            ys += [float(y0), float(y1)]
        pad = 1.0
        return (min(xs) - pad, min(ys) - pad, max(xs) + pad, max(ys) + pad)

    # ------------------------------------------------------------- ground truth
    def cast(self, origin_xy: np.ndarray | tuple[float, float], angles: np.ndarray | list[float],
             max_range: float = math.inf) -> RayHits:
        """Cast exact rays from ``origin_xy`` at world-frame ``angles`` (radians).

        Returns ranges (inf for misses), hit mask, boundary tangents (obstacle on the
        right, world frame), signed curvatures and the obstacle index of every ray. Rays
        are meant to start outside obstacles (as a ladar on the robot does): straight faces
        are culled when seen from behind, so a ray starting inside a polygon does not see it.
        """
        return self.caster.cast(np.asarray(origin_xy, dtype=float),
                                np.atleast_1d(np.asarray(angles, dtype=float)), max_range,
                                detail=True)

    def nearest_boundary(self, xy: np.ndarray | tuple[float, float]) -> Nearest:
        """Find the nearest obstacle boundary point to ``xy`` ((2,) or (N, 2), metres)."""
        q = np.asarray(xy, dtype=float)
        d, p, own = nearest_boundary(self.parts, q.reshape(-1, 2))
        if q.ndim == 1:
            return Nearest(float(d[0]), p[0], int(own[0]))
        return Nearest(d, p, own)

    def inside(self, xy: np.ndarray | tuple[float, float]) -> bool | np.ndarray:
        """Tell where ``xy`` lies inside an obstacle (True inside)."""
        import shapely

        q = np.asarray(xy, dtype=float)
        if not self.obstacles:
            return False if q.ndim == 1 else np.zeros(len(q), dtype=bool)
        pts = q.reshape(-1, 2)
        res = np.zeros(len(pts), dtype=bool)
        if self._prepared is not None:
            tree, geoms = self._prepared
            point, near = tree.query(shapely.points(pts))    # the boxes around each point
            within = shapely.contains_xy(geoms[near], pts[point, 0], pts[point, 1])
            res[point[within]] = True
        centers, radii, _ = self._discs
        if len(radii):
            res |= _in_discs(pts, centers, radii)
        return bool(res[0]) if q.ndim == 1 else res

    def clearance(self, xy: np.ndarray | tuple[float, float], radius: float = 0.0
                  ) -> float | np.ndarray:
        """Measure from a disc of ``radius`` at ``xy`` to the nearest obstacle, metres.

        Negative when the disc overlaps an obstacle (by the overlap depth, or minus the
        distance to the boundary plus the radius when the centre is inside one).
        """
        q = np.asarray(xy, dtype=float)
        d, _, _ = nearest_boundary(self.parts, q.reshape(-1, 2))
        ins = np.asarray(self.inside(q.reshape(-1, 2)))
        c = np.where(ins, -d, d) - radius
        return float(c[0]) if q.ndim == 1 else c
