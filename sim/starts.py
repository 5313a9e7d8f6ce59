"""Seeded start poses around a world's obstacles: collision courses and blind-side passes.

* :func:`collision_starts`: the robot 3-8 m from the nearest obstacle boundary (outside every
  obstacle), heading so that the straight line ahead hits an obstacle. A boundary point is
  drawn uniformly along the obstacles' outline and approached at an *incidence* drawn
  uniformly in +-75 deg of the inward normal there.
* :func:`blind_side_starts`: the robot 3-8 m from the obstacles, heading past them so that
  the straight line ahead misses them by a lateral gap of 0.4-2 m, with every obstacle on
  its **non-followed** side (on the left for right-hand following, on the right for
  left-hand following): the ladar's side ray never sees them unless the robot turns.
* :func:`tangential_starts`: the robot passing an outermost point of the obstacles (a tip, a
  pole, a plate's end, a leg) on the followed side, heading square to the direction in which
  that point is outermost, 0.45-1.2 m from it: half of them with the point exactly abeam
  (at -90 deg for right-hand following), the others 0.5-3 m before it.

The incidence reported for a collision course is measured at the face the straight line
actually hits first: the angle from that face's inward normal to the heading, positive when
the heading already leans the way the robot will follow the boundary (the boundary's
direction with the obstacle on the followed side), so a start at incidence -60 deg needs a
150 deg turn to put the obstacle on the followed side, one at +60 deg only a 30 deg turn.

>>> from mdle.sim.shapes import Circle
>>> from mdle.sim.world import World
>>> w = World("disc", obstacles=(Circle((0.0, 0.0), 2.0),))
>>> s = collision_starts(w, 3, seed=1)
>>> all(3.0 <= x.distance <= 8.0 and not x.blind for x in s)
True
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np

from mdle.sim.world import World

__all__ = ["DISTANCE", "GAP", "INCIDENCE", "PASS", "Start", "StartsError",
           "blind_side_starts", "collision_starts", "tangential_starts"]

#: Distance from the robot's centre to the nearest boundary at a start, metres.
DISTANCE = (3.0, 8.0)
#: Largest incidence of a collision course (either way), radians.
INCIDENCE = math.radians(75.0)
#: Lateral gap between a blind-side start's straight path and the obstacles, metres.
GAP = (0.4, 2.0)

#: Lateral distance from a tangential start's path to the point it passes, metres.
PASS = (0.45, 1.2)

_BATCH = 64          # candidates drawn at once
_MAX_BATCHES = 200   # bounded search (a start is found in the first batch in practice)



class StartsError(ValueError):
    """A shape offers fewer starts of the kind asked for than were asked for."""

@dataclass(frozen=True)
class Start:
    """A start pose and how it was drawn (metres, radians).

    Attributes
    ----------
    index : int
        Position in its list.
    x, y, theta : float
        The pose.
    blind : bool
        True for a blind-side start (the line ahead misses the obstacles, which lie on the
        non-followed side).
    distance : float
        Distance from the centre to the nearest boundary.
    incidence : float
        Collision course: the signed angle from the hit face's inward normal to the heading
        (module docstring); NaN for blind-side starts.
    ahead : float
        Collision course: distance along the heading to the hit; NaN for blind-side starts.
    gap : float
        Blind side: lateral gap between the straight path and the obstacles; NaN otherwise.
    """

    index: int
    x: float
    y: float
    theta: float
    blind: bool
    distance: float
    incidence: float = math.nan
    ahead: float = math.nan
    gap: float = math.nan


def _check_side(side: str) -> float:
    if side not in ("right", "left"):
        raise ValueError(f"side must be `right` or `left`, got `{side}`")
    return 1.0 if side == "right" else -1.0


def _outline(world: World) -> list[np.ndarray]:
    """Return the outer rings of the obstacles' union, counter-clockwise, closed (K, 2)."""
    import shapely
    from shapely.geometry.polygon import orient

    union = shapely.union_all([o.geometry() for o in world.obstacles])
    polys = getattr(union, "geoms", [union])
    return [np.asarray(orient(p, sign=1.0).exterior.coords) for p in polys]


def _take(n: int, candidates: Iterator[Start], world: World, what: str) -> list[Start]:
    """Return the first ``n`` starts of ``candidates``, numbered in order.

    The candidates are drawn lazily, batch by batch, so a search stops as soon as it has
    ``n`` (and draws the same numbers as one that stops there).

    Raises
    ------
    ValueError
        The candidates ran out (their bounded search ended) before ``n``.
    """
    found: list[Start] = []
    for start in candidates:
        found.append(replace(start, index=len(found)))
        if len(found) == n:
            return found
    raise StartsError(f"world `{world.name}`: found only {len(found)} of {n} {what}")


def collision_starts(world: World, n: int, seed: int | tuple[int, ...] = 0,
                     side: str = "right") -> list[Start]:
    """Draw ``n`` seeded starts on a collision course with the world's obstacles.

    ``side`` only orients the reported incidence (positive: leaning the followed way).

    Raises
    ------
    ValueError
        An empty world, a bad side, or no start found (a world too cramped for 3 m).
    """
    sign = _check_side(side)
    if not world.obstacles:
        raise ValueError(f"world `{world.name}` has no obstacles to start towards")
    return _take(n, _collision_courses(world, np.random.default_rng(seed), sign), world,
                 "collision-course starts 3-8 m from the obstacles")


def _collision_courses(world: World, rng: np.random.Generator, sign: float) -> Iterator[Start]:
    rings = _outline(world)
    seg_a = np.vstack([r[:-1] for r in rings])
    seg_b = np.vstack([r[1:] for r in rings])
    seg_len = np.linalg.norm(seg_b - seg_a, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg_len)])
    for _ in range(_MAX_BATCHES):
        s = rng.uniform(0.0, cum[-1], _BATCH)
        k = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg_len) - 1)
        f = ((s - cum[k]) / np.maximum(seg_len[k], 1e-12))[:, None]
        p = seg_a[k] + f * (seg_b[k] - seg_a[k])
        t = (seg_b[k] - seg_a[k]) / np.maximum(seg_len[k], 1e-12)[:, None]
        inward = np.column_stack([-t[:, 1], t[:, 0]])  # left of a CCW ring: the solid side
        theta = np.arctan2(inward[:, 1], inward[:, 0]) + rng.uniform(-INCIDENCE, INCIDENCE,
                                                                      _BATCH)
        back = rng.uniform(DISTANCE[0], DISTANCE[1] + 2.0, _BATCH)
        xy = p - back[:, None] * np.column_stack([np.cos(theta), np.sin(theta)])
        near = world.nearest_boundary(xy)
        dist = np.asarray(near.distance)
        ok = (dist >= DISTANCE[0]) & (dist <= DISTANCE[1]) & ~np.asarray(world.inside(xy))
        for i in np.flatnonzero(ok):
            hit = world.cast(xy[i], [theta[i]])
            if not bool(hit.hit[0]):
                continue
            assert hit.tangents is not None
            th = float(theta[i])
            normal_in = float(hit.tangents[0]) - math.pi / 2  # obstacle on the tangent's right
            inc = math.remainder(th - normal_in, 2 * math.pi) * sign
            yield Start(0, float(xy[i, 0]), float(xy[i, 1]), math.remainder(th, 2 * math.pi),
                        False, float(dist[i]), incidence=inc, ahead=float(hit.ranges[0]))


def blind_side_starts(world: World, n: int, seed: int | tuple[int, ...] = 0,
                      side: str = "right") -> list[Start]:
    """Draw ``n`` seeded starts whose straight path passes the obstacles on the blind side.

    For ``side="right"`` (right-hand following) every obstacle lies left of the path, the
    nearest 0.4-2 m from it; for ``"left"`` the picture is mirrored.

    Raises
    ------
    ValueError
        An empty world, a bad side, or no start found.
    """
    sign = _check_side(side)
    if not world.obstacles:
        raise ValueError(f"world `{world.name}` has no obstacles to pass")
    return _take(n, _blind_passes(world, np.random.default_rng(seed), sign), world,
                 "blind-side starts 3-8 m from the obstacles")


def _blind_passes(world: World, rng: np.random.Generator, sign: float) -> Iterator[Start]:
    verts = np.vstack(_outline(world))
    for _ in range(_MAX_BATCHES):
        theta = rng.uniform(-math.pi, math.pi, _BATCH)
        h = np.column_stack([np.cos(theta), np.sin(theta)])
        left = np.column_stack([-h[:, 1], h[:, 0]])
        across = verts @ left.T           # (V, B): every vertex's offset left of each path
        along = verts @ h.T
        gap = rng.uniform(GAP[0], GAP[1], _BATCH)
        # right-hand following: the path runs ``gap`` right of the obstacles' rightmost point
        lateral = np.where(sign > 0, across.min(axis=0) - gap, across.max(axis=0) + gap)
        back = along.min(axis=0) - rng.uniform(DISTANCE[0], DISTANCE[1], _BATCH)
        xy = back[:, None] * h + lateral[:, None] * left
        dist = np.asarray(world.nearest_boundary(xy).distance)
        ok = (dist >= DISTANCE[0]) & (dist <= DISTANCE[1]) & ~np.asarray(world.inside(xy))
        for i in np.flatnonzero(ok):
            if bool(world.cast(xy[i], [theta[i]]).hit[0]):
                continue  # the polygon approximation of a curve let the path graze it
            yield Start(0, float(xy[i, 0]), float(xy[i, 1]), float(theta[i]), True,
                        float(dist[i]), gap=float(gap[i]))


def tangential_starts(world: World, n: int, seed: int | tuple[int, ...] = 0,
                      side: str = "right", ladar: float = 0.0) -> list[Start]:
    """Draw ``n`` seeded starts passing an outermost point of the obstacles tangentially.

    A direction ``e`` is drawn uniformly; the obstacles' outermost point ``P`` that way (the
    vertex of their outline furthest along ``e``: a spike's tip, a pole, a plate's end face)
    is passed at a lateral distance drawn in :data:`PASS`, heading square to ``e`` with
    ``P`` on the followed side (on the right for ``side="right"``). Half the starts have
    ``P`` exactly abeam of the ladar (``ladar`` metres ahead of the robot's centre: ``P`` at
    its -90 deg beam), the others start 0.5-3 m before that. Nothing else may be nearer
    than 0.4 m. ``gap`` records the lateral distance, ``incidence`` is NaN (a pass, not an
    approach), ``distance`` the distance to the nearest boundary.

    Raises
    ------
    ValueError
        An empty world, a bad side, or no start found.
    """
    sign = _check_side(side)
    if not world.obstacles:
        raise ValueError(f"world `{world.name}` has no obstacles to pass")
    return _take(n, _tangential_passes(world, np.random.default_rng(seed), sign, ladar), world,
                 "tangential starts")


def _tangential_passes(world: World, rng: np.random.Generator, sign: float,
                       ladar: float) -> Iterator[Start]:
    verts = np.vstack(_outline(world))
    for _ in range(_MAX_BATCHES):
        out = rng.uniform(-math.pi, math.pi, _BATCH)
        e = np.column_stack([np.cos(out), np.sin(out)])
        tip = verts[np.argmax(verts @ e.T, axis=0)]
        # heading square to e with the tip on the followed side: e turned -90 deg (right)
        theta = out - sign * math.pi / 2
        h = np.column_stack([np.cos(theta), np.sin(theta)])
        gap = rng.uniform(PASS[0], PASS[1], _BATCH)
        before = np.where(rng.uniform(size=_BATCH) < 0.5, 0.0,
                          rng.uniform(0.5, 3.0, _BATCH))
        xy = tip + gap[:, None] * e - (before + ladar)[:, None] * h
        dist = np.asarray(world.nearest_boundary(xy).distance)
        ok = (dist >= 0.4) & ~np.asarray(world.inside(xy))
        for i in np.flatnonzero(ok):
            yield Start(0, float(xy[i, 0]), float(xy[i, 1]),
                        math.remainder(float(theta[i]), 2 * math.pi), False, float(dist[i]),
                        gap=float(gap[i]))
