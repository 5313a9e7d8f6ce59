"""Seeded random obstacles for experiments: one shape per ``(seed, index)``.

Families (``FAMILIES``), sizes like the seed paper's (about 1-6 m across):

* ``star``: a star-shaped polygon, 5-12 vertices at random radii around a centre.
* ``nonconvex``: the outline of 2-4 overlapping random rectangles (not star-shaped in general).
* ``rounded-rect``: a rounded rectangle kept exact (two rectangles and four discs: straight
  faces and true circular corners, so rays get the corners' curvature analytically).
* ``rounded-rect-facets``: the same outline as a polygon whose vertices turn about 5 deg each.
* ``superellipse``: ``|x/a|^n + |y/b|^n = 1`` (n 2.5-5) as a smooth closed curve
  (:class:`sim.shapes.Curve`, faces carrying the curve's curvature).
* ``superellipse-facets``: the same as a polygon whose vertices turn about 5 deg each.
* ``plate``: a thin plate, 1-6 m long and 5-10 cm thick.
* ``arc-wall``: a circular wall (exact ring sector), radius 1.5-5 m, 60-200 deg.
* ``sine-wall``: a sine-shaped wall 4-10 m long, tightest bend radius at least 0.8 m.
* ``l-shape``, ``t-shape``, ``u-shape``: solid letters 2-6 m across, arms 0.4-1.5 m.
* ``cluster``: 2-4 small obstacles (discs, boxes, small stars) with 0.4-2 m gaps between them.

What a lab meets, and the seed paper's shapes do not contain (``LAB_FAMILIES``, drawn only
when asked for by name: the study's ``lab`` suite):

* ``pole``: one thin pole, radius 2-10 cm.
* ``pole-row``: 3-7 poles or pillars (radius 2-15 cm) in a line, gaps 0.7-1.65 m between
  them (0.7-1.5 x 2 rc at rc 0.5 m, 0.64-1.5 x 2 rc at 0.55 m).
* ``spike-star``: a star polygon of 5-10 spikes whose tips are 20-40 deg sharp.
* ``disc-chain``: 3-7 discs of mixed radii (0.15-0.8 m), each touching or overlapping the last
  (cusps where they meet).
* ``thin-plate``: a plate 1-4 m long and 1-3 cm thick.
* ``table``: four legs (discs of radius 2-5 cm or square legs 4-8 cm wide) at the corners of a
  table 0.6-1.8 m by 0.5-1.2 m.

The family of shape ``index`` is ``FAMILIES[index % len(FAMILIES)]``, so any run of
consecutive indices covers the families evenly. Everything is drawn from
``numpy.random.default_rng((seed, index))``: the same pair always gives the same shape.

>>> s = generate_shape(0, 0)
>>> s.family, s.name, len(s.obstacles)
('star', 'star-0-0', 1)
>>> generate_shape(0, 0) == s
True
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from mdle.core.pose import Pose
from mdle.sim.robot import RobotProfile
from mdle.sim.shapes import Arc, Circle, Curve, Polygon, Rectangle, Shape
from mdle.sim.world import World

if TYPE_CHECKING:
    from shapely.geometry.base import BaseGeometry

__all__ = ["FAMILIES", "LAB_FAMILIES", "FACET_TURN", "GeneratedShape", "generate_shape",
           "generate_shapes"]

FAMILIES: tuple[str, ...] = (
    "star", "nonconvex", "rounded-rect", "rounded-rect-facets", "superellipse",
    "superellipse-facets", "plate", "arc-wall", "sine-wall", "l-shape", "t-shape", "u-shape",
    "cluster",
)

#: Thin, sharp and clustered obstacles of a real room (drawn by name, not by index).
LAB_FAMILIES: tuple[str, ...] = (
    "pole", "pole-row", "spike-star", "disc-chain", "thin-plate", "table",
)

#: Turn at each vertex of the faceted (sampled) curves, radians.
FACET_TURN = math.radians(5.0)

_ATTEMPTS = 50  # redraws before giving up on a family (never reached in practice: tests)


@dataclass(frozen=True)
class GeneratedShape:
    """One generated obstacle set: its family, where it came from, and its shapes (metres).

    Attributes
    ----------
    seed, index : int
        The pair it was drawn from.
    family : str
        One of :data:`FAMILIES`.
    obstacles : tuple of shapes
        Solid obstacles around the origin (one, or 2-4 for a cluster; a rounded rectangle is
        made of six overlapping pieces whose union is the shape).
    """

    seed: int
    index: int
    family: str
    obstacles: tuple[Shape, ...]

    @property
    def name(self) -> str:
        """``family-seed-index``, e.g. ``star-0-13``."""
        return f"{self.family}-{self.seed}-{self.index}"

    def geometry(self) -> BaseGeometry:
        """Return the union of the obstacles as one shapely geometry (curves approximated)."""
        import shapely

        return shapely.union_all([o.geometry() for o in self.obstacles])

    def world(self, start: Pose | None = None, robot: RobotProfile | None = None) -> World:
        """Return a :class:`World` with these obstacles.

        ``start`` defaults to a clear pose 4 m beyond the shapes' right edge, heading at them;
        ``robot`` to the ideal unicycle.
        """
        if robot is None:
            from mdle.sim.profiles import robot_profile

            robot = robot_profile("ideal")
        if start is None:
            x0, y0, x1, y1 = self.geometry().bounds
            start = Pose(x1 + 4.0, 0.5 * (y0 + y1), math.pi)
        return World(self.name, obstacles=self.obstacles, start_pose=start, robot=robot,
                     description=f"generated {self.family} (seed {self.seed}, index {self.index})")


def generate_shape(seed: int, index: int, family: str | None = None) -> GeneratedShape:
    """Draw shape ``index`` of ``seed`` (family by index unless given).

    Raises
    ------
    ValueError
        A negative seed or index, or an unknown family.
    """
    if seed < 0 or index < 0:
        raise ValueError(f"seed and index must be >= 0, got seed {seed}, index {index}")
    family = FAMILIES[index % len(FAMILIES)] if family is None else family
    if family not in _BUILDERS:
        raise ValueError(f"unknown shape family `{family}` (one of: "
                         f"{', '.join(FAMILIES + LAB_FAMILIES)})")
    rng = np.random.default_rng((seed, index))
    for _ in range(_ATTEMPTS):
        obstacles = _BUILDERS[family](rng)
        if _valid(obstacles):
            return GeneratedShape(seed, index, family, obstacles)
    raise RuntimeError(f"no valid {family} shape in {_ATTEMPTS} draws (seed {seed}, "
                       f"index {index})")


def generate_shapes(seed: int, count: int) -> list[GeneratedShape]:
    """Return shapes ``0 .. count-1`` of ``seed``."""
    return [generate_shape(seed, i) for i in range(count)]


# ------------------------------------------------------------------------------- checks
def _valid(obstacles: tuple[Shape, ...]) -> bool:
    """Tell whether every piece is a valid shapely polygon with area, and the whole is too."""
    import shapely

    geoms = [o.geometry() for o in obstacles]
    if not geoms or not all(g.is_valid and g.area > 1e-4 and g.geom_type == "Polygon"
                            for g in geoms):
        return False
    return bool(shapely.union_all(geoms).is_valid)


# ------------------------------------------------------------------------------- helpers
def _rotate(points: np.ndarray, angle: float, offset: tuple[float, float] = (0.0, 0.0)
            ) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]]) + np.asarray(offset)


def _tuple_points(points: np.ndarray) -> tuple[tuple[float, float], ...]:
    return tuple((float(x), float(y)) for x, y in points)


def _equal_turn(dense: np.ndarray, step: float = FACET_TURN) -> np.ndarray:
    """Pick vertices of a closed convex curve, one each time its tangent has turned ``step``.

    ``dense`` is a fine counter-clockwise sampling (K, 2) of the curve. The loop's 360 deg
    are split into equal turns of about ``step``; the dense point nearest the middle of each
    is kept, so straight stretches collapse and every vertex turns by about ``step``.
    """
    d = np.roll(dense, -1, axis=0) - dense
    heading = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    turned = heading - heading[0]
    n = max(3, round(2 * math.pi / step))
    targets = (np.arange(n) + 0.5) * (2 * math.pi / n)
    keep = np.unique(np.clip(np.searchsorted(turned, targets), 0, len(dense) - 1))
    return dense[keep]


def _rounded_rect_outline(w: float, h: float, r: float, per_turn: float) -> np.ndarray:
    """Sample a rounded rectangle's outline counter-clockwise, corners every ``per_turn`` rad."""
    n = max(2, math.ceil((math.pi / 2) / per_turn)) + 1
    pts = []
    for cx, cy, a0 in ((w / 2 - r, -h / 2 + r, -math.pi / 2), (w / 2 - r, h / 2 - r, 0.0),
                       (-w / 2 + r, h / 2 - r, math.pi / 2), (-w / 2 + r, -h / 2 + r, math.pi)):
        a = a0 + np.linspace(0.0, math.pi / 2, n)
        pts.append(np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)]))
    return np.vstack(pts)


def _superellipse(a: float, b: float, n: float, samples: int = 4000) -> np.ndarray:
    """Sample ``|x/a|^n + |y/b|^n = 1`` densely, counter-clockwise."""
    t = np.linspace(0.0, 2 * math.pi, samples, endpoint=False)
    c, s = np.cos(t), np.sin(t)
    return np.column_stack([a * np.sign(c) * np.abs(c) ** (2 / n),
                            b * np.sign(s) * np.abs(s) ** (2 / n)])


# ------------------------------------------------------------------------------ families
def _star(rng: np.random.Generator) -> tuple[Shape, ...]:
    n = int(rng.integers(5, 13))
    big = rng.uniform(1.0, 3.0)
    angles = 2 * math.pi * (np.arange(n) + rng.uniform(-0.3, 0.3, n)) / n + rng.uniform(0, 6.3)
    if rng.random() < 0.5:  # spiky: alternate outer tips and inner notches
        radii = np.where(np.arange(n) % 2 == 0, rng.uniform(0.75, 1.0, n),
                         rng.uniform(0.35, 0.6, n)) * big
    else:
        radii = rng.uniform(0.4, 1.0, n) * big
    pts = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
    return (Polygon(_tuple_points(pts), name="star"),)


def _nonconvex(rng: np.random.Generator) -> tuple[Shape, ...]:
    import shapely

    pieces = int(rng.integers(2, 5))
    union = Rectangle((0.0, 0.0), (rng.uniform(1.5, 4.0), rng.uniform(0.6, 1.5)),
                      rng.uniform(0, math.pi)).geometry()
    for _ in range(pieces - 1):
        edge = union.exterior
        p = edge.interpolate(rng.uniform(0, edge.length))
        box = Rectangle((p.x, p.y), (rng.uniform(1.0, 3.5), rng.uniform(0.5, 1.4)),
                        rng.uniform(0, math.pi)).geometry()
        union = shapely.union(union, box)
    union = shapely.Polygon(union.exterior).simplify(0.02)  # fill any hole, drop slivers
    x0, y0, x1, y1 = union.bounds
    scale = min(1.0, 6.0 / max(x1 - x0, y1 - y0))
    c = union.centroid
    pts = (np.asarray(union.exterior.coords)[:-1] - (c.x, c.y)) * scale
    if union.area / union.convex_hull.area > 0.9:  # nearly convex: not what this family is for
        return (Polygon(((0.0, 0.0), (1.0, 0.0), (0.0, 0.0))),)  # invalid: redraw
    return (Polygon(_tuple_points(pts), name="nonconvex"),)


def _rounded_dims(rng: np.random.Generator) -> tuple[float, float, float, float]:
    w, h = rng.uniform(1.5, 6.0), rng.uniform(1.0, 4.0)
    r = rng.uniform(0.2, 0.45 * min(w, h))
    return w, h, r, rng.uniform(0, math.pi)


def _rounded_rect(rng: np.random.Generator) -> tuple[Shape, ...]:
    w, h, r, ang = _rounded_dims(rng)
    corners = _rotate(np.array([[w / 2 - r, h / 2 - r], [-w / 2 + r, h / 2 - r],
                                [-w / 2 + r, -h / 2 + r], [w / 2 - r, -h / 2 + r]]), ang)
    return (Rectangle((0.0, 0.0), (w, h - 2 * r), ang, name="rounded-rect"),
            Rectangle((0.0, 0.0), (w - 2 * r, h), ang, name="rounded-rect"),
            *(Circle((float(x), float(y)), r, name="rounded-rect") for x, y in corners))


def _rounded_rect_facets(rng: np.random.Generator) -> tuple[Shape, ...]:
    w, h, r, ang = _rounded_dims(rng)
    pts = _rotate(_rounded_rect_outline(w, h, r, FACET_TURN), ang)
    return (Polygon(_tuple_points(_dedupe(pts)), name="rounded-rect-facets"),)


def _super_dims(rng: np.random.Generator) -> tuple[float, float, float, float]:
    return rng.uniform(1.0, 3.0), rng.uniform(0.6, 2.5), rng.uniform(2.5, 5.0), rng.uniform(0, 6.3)


def _superellipse_smooth(rng: np.random.Generator) -> tuple[Shape, ...]:
    a, b, n, ang = _super_dims(rng)
    ctrl = _rotate(_equal_turn(_superellipse(a, b, n), math.radians(3.0)), ang)
    return (Curve(_tuple_points(ctrl), closed=True, spacing=0.05, name="superellipse"),)


def _superellipse_facets(rng: np.random.Generator) -> tuple[Shape, ...]:
    a, b, n, ang = _super_dims(rng)
    pts = _rotate(_equal_turn(_superellipse(a, b, n)), ang)
    return (Polygon(_tuple_points(pts), name="superellipse-facets"),)


def _plate(rng: np.random.Generator) -> tuple[Shape, ...]:
    return (Rectangle((0.0, 0.0), (rng.uniform(1.0, 6.0), rng.uniform(0.05, 0.10)),
                      rng.uniform(0, math.pi), name="plate"),)


def _arc_wall(rng: np.random.Generator) -> tuple[Shape, ...]:
    radius = rng.uniform(1.5, 5.0)
    sweep = rng.uniform(math.radians(60.0), math.radians(200.0))
    start = rng.uniform(0, 2 * math.pi)
    mid = start + sweep / 2
    # centre the wall's middle on the origin
    center = (-radius * math.cos(mid), -radius * math.sin(mid))
    return (Arc(center, radius, start, start + sweep, rng.uniform(0.05, 0.3), name="arc-wall"),)


def _sine_wall(rng: np.random.Generator) -> tuple[Shape, ...]:
    length = rng.uniform(4.0, 10.0)
    wavelength = rng.uniform(3.5, 7.0)
    k = 2 * math.pi / wavelength
    # the tightest bend (radius 1 / (A k^2)) stays >= 0.8 m: followable on its concave side
    amplitude = rng.uniform(0.25, min(1.2, 1.0 / (0.8 * k * k)))
    x = np.linspace(-length / 2, length / 2, max(9, math.ceil(length / 0.25)))
    y = amplitude * np.sin(k * x + rng.uniform(0, 2 * math.pi))
    pts = _rotate(np.column_stack([x, y]), rng.uniform(0, math.pi))
    return (Curve(_tuple_points(pts), thickness=rng.uniform(0.1, 0.3), spacing=0.05,
                  name="sine-wall"),)


def _letter(points: np.ndarray, rng: np.random.Generator, name: str) -> tuple[Shape, ...]:
    lo, hi = points.min(axis=0), points.max(axis=0)
    pts = _rotate(points - (lo + hi) / 2, rng.uniform(0, 2 * math.pi))
    return (Polygon(_tuple_points(pts), name=name),)


def _l_shape(rng: np.random.Generator) -> tuple[Shape, ...]:
    w, h = rng.uniform(2.0, 6.0), rng.uniform(2.0, 6.0)
    a = rng.uniform(0.5, min(1.5, 0.45 * min(w, h)))
    pts = np.array([[0, 0], [w, 0], [w, a], [a, a], [a, h], [0, h]], dtype=float)
    return _letter(pts, rng, "l-shape")


def _t_shape(rng: np.random.Generator) -> tuple[Shape, ...]:
    w, stem = rng.uniform(2.5, 6.0), rng.uniform(1.5, 5.0)
    a = rng.uniform(0.5, 1.5)
    b = rng.uniform(0.5, min(1.5, 0.5 * w))
    pts = np.array([[-b / 2, 0], [b / 2, 0], [b / 2, stem], [w / 2, stem], [w / 2, stem + a],
                    [-w / 2, stem + a], [-w / 2, stem], [-b / 2, stem]], dtype=float)
    return _letter(pts, rng, "t-shape")


def _u_shape(rng: np.random.Generator) -> tuple[Shape, ...]:
    a = rng.uniform(0.4, 1.2)
    w = rng.uniform(max(2.5, 2 * a + 1.2), 6.0)   # slot at least 1.2 m wide
    depth = rng.uniform(2.0, 5.0)
    pts = np.array([[-w / 2, 0], [w / 2, 0], [w / 2, depth], [w / 2 - a, depth],
                    [w / 2 - a, a], [-w / 2 + a, a], [-w / 2 + a, depth], [-w / 2, depth]],
                   dtype=float)
    return _letter(pts, rng, "u-shape")


def _cluster_member(rng: np.random.Generator) -> tuple[Shape, float]:
    """Draw one small obstacle centred on the origin; return it and its bounding radius."""
    kind = int(rng.integers(0, 3))
    if kind == 0:
        r = rng.uniform(0.3, 1.0)
        return Circle((0.0, 0.0), r, name="cluster"), r
    if kind == 1:
        w, h = rng.uniform(0.5, 2.0), rng.uniform(0.5, 2.0)
        return (Rectangle((0.0, 0.0), (w, h), rng.uniform(0, math.pi), name="cluster"),
                0.5 * math.hypot(w, h))
    (star,) = _star(rng)
    pts = np.asarray(star.points) * 0.4 if isinstance(star, Polygon) else np.zeros((0, 2))
    return (Polygon(_tuple_points(pts), name="cluster"),
            float(np.max(np.linalg.norm(pts, axis=1))))  # a small star, 0.8-2.4 m across


def _shifted(shape: Shape, offset: np.ndarray) -> Shape:
    """Move a cluster member (disc, box or polygon) by ``offset`` metres."""
    dx, dy = float(offset[0]), float(offset[1])
    if isinstance(shape, (Circle, Rectangle)):
        return replace(shape, center=(shape.center[0] + dx, shape.center[1] + dy))
    assert isinstance(shape, Polygon)
    return replace(shape, points=_tuple_points(np.asarray(shape.points) + (dx, dy)))


def _cluster(rng: np.random.Generator) -> tuple[Shape, ...]:
    import shapely

    count = int(rng.integers(2, 5))
    first, rho = _cluster_member(rng)
    members: list[tuple[Shape, np.ndarray, float]] = [(first, np.zeros(2), rho)]
    for _ in range(200):  # bounded: a draw that does not fit is simply redrawn
        if len(members) == count:
            break
        _, c, rho = members[int(rng.integers(0, len(members)))]
        shape, new_rho = _cluster_member(rng)
        direction = rng.uniform(0, 2 * math.pi)
        # the new member's bounding disc sits 0.4-2 m beyond the chosen member's
        centre = c + (rho + new_rho + rng.uniform(0.4, 2.0)) * np.array(
            [math.cos(direction), math.sin(direction)])
        moved = _shifted(shape, centre)
        gaps = [shapely.distance(moved.geometry(), m.geometry()) for m, _, _ in members]
        if 0.4 <= min(gaps) <= 2.5:
            members.append((moved, centre, new_rho))
    return tuple(m for m, _, _ in members)


def _dedupe(points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Drop consecutive duplicate vertices (where a corner arc meets the next one)."""
    nxt = np.roll(points, -1, axis=0)
    keep = np.linalg.norm(nxt - points, axis=1) > tol
    return points[keep]


# ------------------------------------------------------------------ what a lab is made of
def _pole(rng: np.random.Generator) -> tuple[Shape, ...]:
    return (Circle((0.0, 0.0), rng.uniform(0.02, 0.10), name="pole"),)


def _pole_row(rng: np.random.Generator) -> tuple[Shape, ...]:
    count = int(rng.integers(3, 8))
    radius = rng.uniform(0.02, 0.15)
    heading = rng.uniform(0, math.pi)
    direction = np.array([math.cos(heading), math.sin(heading)])
    centres = [np.zeros(2)]
    for _ in range(count - 1):  # each gap drawn on its own: a row is never quite regular
        centres.append(centres[-1] + (2 * radius + rng.uniform(0.7, 1.65)) * direction)
    middle = 0.5 * (centres[0] + centres[-1])
    return tuple(Circle((float(c[0] - middle[0]), float(c[1] - middle[1])), radius,
                        name="pole-row") for c in centres)


def _spike_star(rng: np.random.Generator) -> tuple[Shape, ...]:
    n = int(rng.integers(5, 11))
    outer = rng.uniform(0.8, 2.0)
    half = math.radians(rng.uniform(20.0, 40.0)) / 2  # half the tip angle
    # the inner radius that makes the edge from a tip to the next notch meet the tip's
    # axis at ``half``: tan(half) = r_i sin(pi/n) / (outer - r_i cos(pi/n))
    tan = math.tan(half)
    inner = outer * tan / (math.sin(math.pi / n) + tan * math.cos(math.pi / n))
    turn = rng.uniform(0, 2 * math.pi)
    angles = turn + np.pi * np.arange(2 * n) / n
    radii = np.where(np.arange(2 * n) % 2 == 0, outer, inner)
    pts = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
    return (Polygon(_tuple_points(pts), name="spike-star"),)


def _disc_chain(rng: np.random.Generator) -> tuple[Shape, ...]:
    count = int(rng.integers(3, 8))
    discs = [(np.zeros(2), rng.uniform(0.15, 0.8))]
    heading = rng.uniform(0, 2 * math.pi)
    for _ in range(count - 1):
        c, r = discs[-1]
        r_new = rng.uniform(0.15, 0.8)
        heading += rng.uniform(-1.0, 1.0)  # a winding chain
        # touching (0.999) to overlapping by a quarter of the radii: cusps where they meet
        step = (r + r_new) * rng.uniform(0.75, 0.999)
        discs.append((c + step * np.array([math.cos(heading), math.sin(heading)]), r_new))
    middle = np.mean([c for c, _ in discs], axis=0)
    return tuple(Circle((float(c[0] - middle[0]), float(c[1] - middle[1])), float(r),
                        name="disc-chain") for c, r in discs)


def _thin_plate(rng: np.random.Generator) -> tuple[Shape, ...]:
    return (Rectangle((0.0, 0.0), (rng.uniform(1.0, 4.0), rng.uniform(0.01, 0.03)),
                      rng.uniform(0, math.pi), name="thin-plate"),)


def _table(rng: np.random.Generator) -> tuple[Shape, ...]:
    w, h = rng.uniform(0.6, 1.8), rng.uniform(0.5, 1.2)
    ang = rng.uniform(0, math.pi)
    corners = _rotate(np.array([[-w, -h], [w, -h], [w, h], [-w, h]]) / 2, ang)
    if rng.uniform() < 0.5:
        r = rng.uniform(0.02, 0.05)
        return tuple(Circle((float(x), float(y)), r, name="table") for x, y in corners)
    side = rng.uniform(0.04, 0.08)
    return tuple(Rectangle((float(x), float(y)), (side, side), ang, name="table")
                 for x, y in corners)


_BUILDERS: dict[str, Callable[[np.random.Generator], tuple[Shape, ...]]] = {
    "star": _star,
    "nonconvex": _nonconvex,
    "rounded-rect": _rounded_rect,
    "rounded-rect-facets": _rounded_rect_facets,
    "superellipse": _superellipse_smooth,
    "superellipse-facets": _superellipse_facets,
    "plate": _plate,
    "arc-wall": _arc_wall,
    "sine-wall": _sine_wall,
    "l-shape": _l_shape,
    "t-shape": _t_shape,
    "u-shape": _u_shape,
    "cluster": _cluster,
    "pole": _pole,
    "pole-row": _pole_row,
    "spike-star": _spike_star,
    "disc-chain": _disc_chain,
    "thin-plate": _thin_plate,
    "table": _table,
}
