"""Obstacle shapes, kept exact: polygons, rectangles, circles, ellipses, walls, arcs, curves.

Every shape is a frozen dataclass in SI units (metres, radians) that knows two things:
its boundary as *primitives* for the ray caster and the distance queries
(:class:`Parts`: straight segments, circular arcs, ellipses), and a shapely geometry
for plots and for the start-pose check. Circles, ellipses and arcs stay analytic, so a
ray that hits them gets the exact range, tangent and curvature.

Orientation convention (control-law.md): every boundary piece is oriented with the
obstacle on its **right**, i.e. clockwise around a solid obstacle. The tangent of a hit
is the direction of travel along that oriented boundary, and the signed curvature is
negative on convex boundaries (a circle of radius R has curvature -1/R) and positive on
concave ones (the inside face of a ring wall).

>>> c = Circle((0.0, 0.0), 2.0)
>>> p = c.parts()
>>> p.arc_radius.tolist(), p.arc_side.tolist()
([2.0], [-1.0])
>>> Rectangle((0.0, 0.0), (2.0, 1.0)).parts().seg_start.shape
(4, 2)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Union

import numpy as np

if TYPE_CHECKING:
    from shapely.geometry.base import BaseGeometry

__all__ = [
    "Arc",
    "Circle",
    "Curve",
    "Ellipse",
    "Parts",
    "Polygon",
    "Rectangle",
    "Shape",
    "Wall",
    "polygon_parts",
]

Point = tuple[float, float]
_TAU = 2.0 * math.pi
_CIRCLE_QUAD_SEGS = 64  # shapely approximation of curved shapes: plots only, never ray casts


@dataclass(frozen=True, eq=False)
class Parts:
    """The boundary primitives of one or more shapes, as flat arrays.

    Attributes
    ----------
    seg_start, seg_end : (S, 2) float arrays, metres
        Straight boundary segments, oriented with the obstacle on the right.
    seg_kappa : (S,) float array, 1/m
        Curvature assigned to each segment: 0 on true polygons, the sampled curvature of
        the smooth curve on :class:`Curve` faces.
    arc_center : (A, 2), arc_radius, arc_start, arc_sweep, arc_side : (A,) float arrays
        Circular arcs: the points ``center + radius * (cos a, sin a)`` for ``a`` in
        ``[start, start + sweep]`` (radians, sweep in (0, 2 pi]). ``side`` is -1 where the
        obstacle is inside the circle (a convex face, curvature -1/R) and +1 where it is
        outside (a concave face, curvature +1/R).
    ell_center : (E, 2), ell_axes : (E, 2), ell_angle : (E,) float arrays
        Solid ellipses: semi-axes (a, b) and the rotation of the a axis (radians).
    seg_owner, arc_owner, ell_owner : int arrays
        Index of the shape each primitive came from (filled in by :meth:`concat`).
    """

    seg_start: np.ndarray
    seg_end: np.ndarray
    seg_kappa: np.ndarray
    arc_center: np.ndarray
    arc_radius: np.ndarray
    arc_start: np.ndarray
    arc_sweep: np.ndarray
    arc_side: np.ndarray
    ell_center: np.ndarray
    ell_axes: np.ndarray
    ell_angle: np.ndarray
    seg_owner: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    arc_owner: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    ell_owner: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))

    @staticmethod
    def make(segments: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
             arcs: list[tuple[Point, float, float, float, float]] | None = None,
             ellipses: list[tuple[Point, float, float, float]] | None = None) -> Parts:
        """Build parts from segment arrays, arc tuples and ellipse tuples.

        Arcs are ``(center, r, start, sweep, side)``; ellipses ``(center, a, b, angle)``.
        """
        if segments is None:
            segments = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))
        arcs = arcs or []
        ellipses = ellipses or []
        s0, s1, k = (np.asarray(a, dtype=float) for a in segments)
        return Parts(
            seg_start=s0.reshape(-1, 2), seg_end=s1.reshape(-1, 2), seg_kappa=k.reshape(-1),
            arc_center=np.array([a[0] for a in arcs], dtype=float).reshape(-1, 2),
            arc_radius=np.array([a[1] for a in arcs], dtype=float),
            arc_start=np.array([a[2] for a in arcs], dtype=float),
            arc_sweep=np.array([a[3] for a in arcs], dtype=float),
            arc_side=np.array([a[4] for a in arcs], dtype=float),
            ell_center=np.array([e[0] for e in ellipses], dtype=float).reshape(-1, 2),
            ell_axes=np.array([(e[1], e[2]) for e in ellipses], dtype=float).reshape(-1, 2),
            ell_angle=np.array([e[3] for e in ellipses], dtype=float),
        )

    @staticmethod
    def concat(parts: list[Parts], index: np.ndarray | None = None) -> Parts:
        """Concatenate the parts of several shapes, recording which shape owns what.

        The owner of ``parts[k]``'s primitives is ``k``, or ``index[k]`` when given.
        """
        shape_of = np.arange(len(parts), dtype=np.intp) if index is None else index
        def cat(name: str, width: int | None = None) -> np.ndarray:
            arrays = [getattr(p, name) for p in parts]
            if not arrays:
                return np.zeros((0, width) if width else 0)
            return np.concatenate(arrays, axis=0)

        def owners(name: str) -> np.ndarray:
            counts = [len(getattr(p, name)) for p in parts]
            return np.repeat(shape_of, counts).astype(np.intp, copy=False)

        return Parts(
            seg_start=cat("seg_start", 2), seg_end=cat("seg_end", 2), seg_kappa=cat("seg_kappa"),
            arc_center=cat("arc_center", 2), arc_radius=cat("arc_radius"),
            arc_start=cat("arc_start"), arc_sweep=cat("arc_sweep"), arc_side=cat("arc_side"),
            ell_center=cat("ell_center", 2), ell_axes=cat("ell_axes", 2),
            ell_angle=cat("ell_angle"),
            seg_owner=owners("seg_start"), arc_owner=owners("arc_radius"),
            ell_owner=owners("ell_angle"),
        )

    @property
    def n_segments(self) -> int:
        """Number of straight segments."""
        return int(self.seg_start.shape[0])


#: Largest turn (rad) at a polygon vertex that joins two facets of a sampled curve.
FACET_TURN = math.radians(30.0)


def polygon_parts(geom: BaseGeometry, smooth: bool = False) -> Parts:
    """Split a shapely (Multi)Polygon's rings into segments, solid on the right.

    shapely's ``orient(sign=1)`` puts the interior on the left of every ring (exterior
    counter-clockwise, holes clockwise); reversing each ring puts it on the right.

    A vertex where the boundary turns by at most :data:`FACET_TURN` joins two facets of a
    sampled curve (a rounded corner, a many-sided "circle"); a sharper one is a corner.
    Each face gets the mean of the sampled curvature (the circle through the neighbouring
    vertices) at its facet joints, and 0 between two corners: a true polygon's faces are
    flat, and a curve given as a polygon has the curvature a robot following it meets,
    as if it were given as a curve. With ``smooth`` (rings sampled from smooth curves)
    every vertex is a facet joint.
    """
    from shapely.geometry.polygon import orient

    starts: list[np.ndarray] = []
    ends: list[np.ndarray] = []
    kappas: list[np.ndarray] = []
    polys = getattr(geom, "geoms", [geom])
    for poly in polys:
        poly = orient(poly, sign=1.0)
        for ring in [poly.exterior, *poly.interiors]:
            pts = np.asarray(ring.coords)[::-1]  # closed ring, reversed: solid on the right
            starts.append(pts[:-1])
            ends.append(pts[1:])
            v = pts[:-1]
            prv, nxt = np.roll(v, 1, axis=0), np.roll(v, -1, axis=0)
            k = _menger(prv, v, nxt)
            if not smooth:
                a, b = v - prv, nxt - v
                turn = np.abs(np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
                                         (a * b).sum(axis=1)))
                joint = turn <= FACET_TURN
                k = np.where(joint, k, 0.0)
                both = joint & np.roll(joint, -1)
                kn = np.roll(k, -1)
                # a face between a corner and a joint takes the joint's curvature
                kappas.append(np.where(both, 0.5 * (k + kn), k + kn))
            else:
                kappas.append(0.5 * (k + np.roll(k, -1)))
    s0 = np.concatenate(starts) if starts else np.zeros((0, 2))
    s1 = np.concatenate(ends) if ends else np.zeros((0, 2))
    k = np.concatenate(kappas) if kappas else np.zeros(0)
    return Parts.make((s0, s1, k))


def _rot(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class Polygon:
    """A solid simple polygon (vertices in either winding, metres), less its ``holes`` (rings)."""

    points: tuple[Point, ...]
    name: str = ""
    holes: tuple[tuple[Point, ...], ...] = ()
    kind = "polygon"

    def geometry(self) -> BaseGeometry:
        """Return the shapely polygon."""
        import shapely

        return shapely.Polygon(self.points, self.holes or None)

    def parts(self) -> Parts:
        """Return the boundary segments, clockwise (solid on the right), curvature 0."""
        return polygon_parts(self.geometry())


@dataclass(frozen=True)
class Rectangle:
    """A solid rectangle: centre (m), size (width along the rotated x, height; m), angle (rad)."""

    center: Point
    size: tuple[float, float]
    angle: float = 0.0
    name: str = ""
    kind = "rectangle"

    def corners(self) -> np.ndarray:
        """Return the (4, 2) corners, counter-clockwise."""
        w, h = self.size[0] / 2.0, self.size[1] / 2.0
        local = np.array([[-w, -h], [w, -h], [w, h], [-w, h]])
        return local @ _rot(self.angle).T + np.asarray(self.center, dtype=float)

    def geometry(self) -> BaseGeometry:
        """Return the shapely polygon."""
        import shapely

        return shapely.Polygon(self.corners())

    def parts(self) -> Parts:
        """Return the four boundary segments, clockwise, curvature 0."""
        return polygon_parts(self.geometry())


@dataclass(frozen=True)
class Circle:
    """A solid disc: centre and radius, metres."""

    center: Point
    radius: float
    name: str = ""
    kind = "circle"

    def geometry(self) -> BaseGeometry:
        """Return a shapely polygon approximating the disc (plots only)."""
        import shapely

        return shapely.Point(self.center).buffer(self.radius, quad_segs=_CIRCLE_QUAD_SEGS)

    def parts(self) -> Parts:
        """Return one full convex arc."""
        return Parts.make(arcs=[(self.center, self.radius, 0.0, _TAU, -1.0)])


@dataclass(frozen=True)
class Ellipse:
    """A solid ellipse: centre (m), semi-axes ``(a, b)`` (m), rotation of the a axis (rad)."""

    center: Point
    axes: tuple[float, float]
    angle: float = 0.0
    name: str = ""
    kind = "ellipse"

    def geometry(self) -> BaseGeometry:
        """Return a shapely polygon approximating the ellipse (plots only)."""
        import shapely

        t = np.linspace(0.0, _TAU, 4 * _CIRCLE_QUAD_SEGS, endpoint=False)
        local = np.column_stack([self.axes[0] * np.cos(t), self.axes[1] * np.sin(t)])
        return shapely.Polygon(local @ _rot(self.angle).T + np.asarray(self.center))

    def parts(self) -> Parts:
        """Return one analytic ellipse."""
        return Parts.make(ellipses=[(self.center, self.axes[0], self.axes[1], self.angle)])


@dataclass(frozen=True)
class Wall:
    """A polyline with a thickness (m): a straight wall, or a room outline if ``closed``.

    The wall is the polyline buffered by half the thickness with flat ends and mitred
    joints, so its faces are exact straight segments.
    """

    points: tuple[Point, ...]
    thickness: float
    closed: bool = False
    name: str = ""
    kind = "wall"

    def geometry(self) -> BaseGeometry:
        """Return the shapely polygon of the wall (with a hole when closed)."""
        import shapely

        pts = list(self.points)
        line = shapely.LinearRing(pts) if self.closed else shapely.LineString(pts)
        return line.buffer(self.thickness / 2.0, cap_style="flat", join_style="mitre",
                           mitre_limit=10.0)

    def parts(self) -> Parts:
        """Return the boundary segments of the buffered polyline, solid on the right."""
        return polygon_parts(self.geometry())


@dataclass(frozen=True)
class Arc:
    """A curved wall: a ring sector around ``center``.

    The sector lies between ``radius -+ thickness/2``, from angle ``start``
    counter-clockwise to ``end`` (radians).
    """

    center: Point
    radius: float
    start: float
    end: float
    thickness: float
    name: str = ""
    kind = "arc"

    @property
    def sweep(self) -> float:
        """Angular extent, radians, in (0, 2 pi]."""
        s = (self.end - self.start) % _TAU
        return s if s > 0 else _TAU

    def geometry(self) -> BaseGeometry:
        """Return a shapely polygon approximating the ring sector (plots only)."""
        import shapely

        n = max(8, int(4 * _CIRCLE_QUAD_SEGS * self.sweep / _TAU))
        t = self.start + np.linspace(0.0, self.sweep, n + 1)
        ro, ri = self.radius + self.thickness / 2, self.radius - self.thickness / 2
        c = np.asarray(self.center)
        outer = c + ro * np.column_stack([np.cos(t), np.sin(t)])
        inner = c + ri * np.column_stack([np.cos(t[::-1]), np.sin(t[::-1])])
        if self.sweep >= _TAU - 1e-12:
            return shapely.Polygon(outer[:-1], [inner[:-1]])
        return shapely.Polygon(np.vstack([outer, inner]))

    def parts(self) -> Parts:
        """Return the outer arc (convex), inner arc (concave) and, unless closed, two end caps."""
        ro, ri = self.radius + self.thickness / 2, self.radius - self.thickness / 2
        arcs = [(self.center, ro, self.start, self.sweep, -1.0),
                (self.center, ri, self.start, self.sweep, +1.0)]
        if self.sweep >= _TAU - 1e-12:
            return Parts.make(arcs=arcs)
        c = np.asarray(self.center, dtype=float)
        u0 = np.array([math.cos(self.start), math.sin(self.start)])
        u1 = np.array([math.cos(self.end), math.sin(self.end)])
        # Clockwise around the sector: outer arc backwards, cap at start outer->inner,
        # inner arc forwards, cap at end inner->outer.
        s0 = np.array([c + ro * u0, c + ri * u1])
        s1 = np.array([c + ri * u0, c + ro * u1])
        return Parts.make((s0, s1, np.zeros(2)), arcs=arcs)


def _catmull_rom(points: np.ndarray, closed: bool, spacing: float) -> np.ndarray:
    """Sample a centripetal Catmull-Rom spline through ``points`` about every ``spacing`` m."""
    p = np.asarray(points, dtype=float)
    if closed:
        ext = np.vstack([p[-1], p, p[0], p[1]])
    else:
        ext = np.vstack([2 * p[0] - p[1], p, 2 * p[-1] - p[-2]])
    out = []
    for i in range(len(ext) - 3):  # loop over control spans, off the tick path
        p0, p1, p2, p3 = ext[i:i + 4]
        t0 = 0.0
        t1 = t0 + max(float(np.linalg.norm(p1 - p0)), 1e-12) ** 0.5
        t2 = t1 + max(float(np.linalg.norm(p2 - p1)), 1e-12) ** 0.5
        t3 = t2 + max(float(np.linalg.norm(p3 - p2)), 1e-12) ** 0.5
        n = max(2, math.ceil(float(np.linalg.norm(p2 - p1)) / spacing))
        t = np.linspace(t1, t2, n, endpoint=False)[:, None]
        a1 = (t1 - t) / (t1 - t0) * p0 + (t - t0) / (t1 - t0) * p1
        a2 = (t2 - t) / (t2 - t1) * p1 + (t - t1) / (t2 - t1) * p2
        a3 = (t3 - t) / (t3 - t2) * p2 + (t - t2) / (t3 - t2) * p3
        b1 = (t2 - t) / (t2 - t0) * a1 + (t - t0) / (t2 - t0) * a2
        b2 = (t3 - t) / (t3 - t1) * a2 + (t - t1) / (t3 - t1) * a3
        out.append((t2 - t) / (t2 - t1) * b1 + (t - t1) / (t2 - t1) * b2)
    if not closed:
        out.append(p[-1:])
    return np.vstack(out)


def _menger(prev: np.ndarray, cur: np.ndarray, nxt: np.ndarray) -> np.ndarray:
    """Return the signed curvature of the circle through three points (positive: left turn)."""
    a = cur - prev
    b = nxt - cur
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    den = (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
           * np.linalg.norm(nxt - prev, axis=1))
    return np.divide(2.0 * cross, den, out=np.zeros_like(cross), where=den > 0)


@dataclass(frozen=True)
class Curve:
    """A smooth curve through control points (centripetal Catmull-Rom).

    Sampled every ``spacing`` metres: a wall of the given thickness, or, when ``closed``
    and without a thickness, a solid smooth blob.

    Faces are straight segments between samples; each carries the curvature of the
    sampled face (circle through neighbouring samples) as ground truth, accurate to
    O(spacing^2) against the spline.
    """

    points: tuple[Point, ...]
    thickness: float | None = None
    closed: bool = False
    spacing: float = 0.05
    name: str = ""
    kind = "curve"

    def samples(self) -> np.ndarray:
        """Return (K, 2) samples of the centre line (without repeating the first when closed)."""
        return _catmull_rom(np.asarray(self.points, dtype=float), self.closed, self.spacing)

    def _ring(self) -> tuple[np.ndarray, np.ndarray]:
        """Return the clockwise boundary ring (K, 2) and a mask of its sharp corners."""
        c = self.samples()
        if self.thickness is None:  # a closed solid blob
            ring, corner = c, np.zeros(len(c), dtype=bool)
        else:
            h = self.thickness / 2.0
            nxt = np.roll(c, -1, axis=0) if self.closed else np.vstack([c[1:], 2 * c[-1] - c[-2]])
            prv = np.roll(c, 1, axis=0) if self.closed else np.vstack([2 * c[0] - c[1], c[:-1]])
            tang = nxt - prv
            tang /= np.linalg.norm(tang, axis=1, keepdims=True)
            normal = np.column_stack([-tang[:, 1], tang[:, 0]])
            left, right = c + h * normal, c - h * normal
            if self.closed:
                # Two rings make an annulus: handled via shapely (faces straight, kappa from
                # each ring separately below is simpler to get from the open form); use both.
                return np.vstack([left, right]), np.zeros(2 * len(c), dtype=bool)
            ring = np.vstack([left, right[::-1]])
            corner = np.zeros(len(ring), dtype=bool)
            corner[[0, len(c) - 1, len(c), len(ring) - 1]] = True
        # Orient clockwise (solid on the right): signed area < 0.
        x, y = ring[:, 0], ring[:, 1]
        area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
        if area > 0:
            ring, corner = ring[::-1], corner[::-1]
        return ring, corner

    def geometry(self) -> BaseGeometry:
        """Return the shapely polygon of the sampled curve (exactly the faces the rays see)."""
        import shapely

        if self.closed and self.thickness is not None:
            c = self.samples()
            return shapely.LinearRing(c).buffer(self.thickness / 2.0, join_style="mitre")
        ring, _ = self._ring()
        return shapely.Polygon(ring)

    def parts(self) -> Parts:
        """Return the faces as segments, each with its sampled curvature; flat end caps get 0."""
        if self.closed and self.thickness is not None:
            return polygon_parts(self.geometry(), smooth=True)
        ring, corner = self._ring()
        prv, nxt = np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0)
        k_vertex = _menger(prv, ring, nxt)
        k_next = np.roll(k_vertex, -1)
        c0, c1 = corner, np.roll(corner, -1)
        # A face's curvature: mean of its two vertices', ignoring cap corners.
        k = np.where(c0 & c1, 0.0, np.where(c0, k_next, np.where(c1, k_vertex,
                                                                   0.5 * (k_vertex + k_next))))
        return Parts.make((ring, nxt, k))


# The shapes a world's YAML draws; an imported map's obstacle is a sim.maps.FloorPlan,
# which is built from these (so it lives above them) and is a world's obstacle too.
Shape = Union[Polygon, Rectangle, Circle, Ellipse, Wall, Arc, Curve]
