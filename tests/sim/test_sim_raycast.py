"""Ray casts against analytic answers (to 1e-9), and the sparse caster against brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.sim.raycast import RayCaster
from mdle.sim.shapes import Arc, Circle, Curve, Ellipse, Parts, Polygon, Rectangle, Shape, Wall
from mdle.sim.world import World

TOL = 1e-9


def caster_of(*shapes: Shape) -> RayCaster:
    return RayCaster(Parts.concat([s.parts() for s in shapes]))


def test_circle_range_tangent_curvature_exact() -> None:
    R, c = 1.3, np.array([4.0, 2.0])
    o = np.array([-1.0, 0.5])
    rng = np.random.default_rng(0)
    w = c - o
    dist = float(np.hypot(*w))
    half = math.asin(R / dist)
    # Rays within the visible cone: analytic range from the quadratic.
    angles = math.atan2(w[1], w[0]) + rng.uniform(-half * 0.999, half * 0.999, 200)
    hits = caster_of(Circle(tuple(c), R)).cast(o, angles)
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    tca = d @ w
    expected = tca - np.sqrt(R * R - (dist * dist - tca * tca))
    assert hits.hit.all()
    assert hits.curvatures is not None and hits.tangents is not None   # detail is the default
    np.testing.assert_allclose(hits.ranges, expected, rtol=0, atol=TOL)
    np.testing.assert_allclose(hits.curvatures, -1.0 / R, rtol=0, atol=TOL)
    # Clockwise tangent: perpendicular to the radius, rotated by -pi/2.
    p = o + expected[:, None] * d
    radial = np.arctan2(p[:, 1] - c[1], p[:, 0] - c[0])
    diff = np.angle(np.exp(1j * (hits.tangents - (radial - math.pi / 2))))
    assert np.abs(diff).max() < 1e-9


def test_circle_misses_outside_cone() -> None:
    hits = caster_of(Circle((5.0, 0.0), 1.0)).cast(np.zeros(2), np.array([0.3, -0.3, math.pi]))
    assert not hits.hit.any()
    assert np.isinf(hits.ranges).all()
    assert hits.tangents is not None and hits.curvatures is not None
    assert np.isnan(hits.tangents).all() and np.isnan(hits.curvatures).all()


def test_ellipse_range_and_curvature_exact() -> None:
    a, b, phi = 4.0, 2.0, math.radians(25.0)
    c = np.array([1.0, -0.5])
    o = np.array([-9.0, 0.3])
    angles = np.linspace(-0.12, 0.1, 301)
    hits = caster_of(Ellipse(tuple(c), (a, b), phi)).cast(o, angles)
    # Independent answer: bisection along each ray on the implicit equation.
    u = np.array([math.cos(phi), math.sin(phi)])
    v = np.array([-math.sin(phi), math.cos(phi)])

    def f(p: np.ndarray) -> np.ndarray:
        q = p - c
        return (q @ u / a) ** 2 + (q @ v / b) ** 2 - 1.0

    d = np.column_stack([np.cos(angles), np.sin(angles)])
    lo, hi = np.zeros(len(angles)), hits.ranges.copy()
    assert hits.hit.all()
    # The hit must lie on the ellipse, and no point before it inside.
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        inside = f(o + mid[:, None] * d) < 0
        hi = np.where(inside, mid, hi)
        lo = np.where(inside, lo, mid)
    np.testing.assert_allclose(hits.ranges, hi, rtol=0, atol=TOL)
    np.testing.assert_allclose(f(o + hits.ranges[:, None] * d), 0.0, atol=1e-12)
    # Curvature from the parametric formula at the hit point.
    assert hits.curvatures is not None
    q = o + hits.ranges[:, None] * d - c
    t = np.arctan2((q @ v) / b, (q @ u) / a)
    kappa = -a * b / (a * a * np.sin(t) ** 2 + b * b * np.cos(t) ** 2) ** 1.5
    np.testing.assert_allclose(hits.curvatures, kappa, rtol=0, atol=TOL)


def test_angled_wall_exact() -> None:
    # A thin wall along the line through (3, 0) at 60 degrees.
    alpha = math.radians(60.0)
    wall = Wall(((3.0 - 10 * math.cos(alpha), -10 * math.sin(alpha)),
                 (3.0 + 10 * math.cos(alpha), 10 * math.sin(alpha))), thickness=1e-3)
    angles = np.linspace(-1.0, 0.8, 181)
    hits = caster_of(wall).cast(np.zeros(2), angles)
    # Face nearer the origin: the line shifted by half the thickness towards it.
    n = np.array([math.sin(alpha), -math.cos(alpha)])      # unit normal into the wall
    c0 = 3.0 * math.sin(alpha) - 0.5e-3                       # distance of the near face
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    expected = c0 / (d @ n)
    assert hits.hit.all()
    assert hits.curvatures is not None and hits.tangents is not None
    np.testing.assert_allclose(hits.ranges, expected, rtol=0, atol=TOL)
    np.testing.assert_allclose(hits.curvatures, 0.0, atol=0)
    # Obstacle on the right: travelling along the near face, the wall is to the right.
    right = np.column_stack([np.sin(hits.tangents), -np.cos(hits.tangents)])
    assert np.all(right @ n > 0.999999)  # the right-hand normal points into the wall


def test_concave_arc_inside_ring() -> None:
    ring = Arc((0.0, 0.0), 5.0, 0.0, 2 * math.pi, 0.2)
    angles = np.linspace(-math.pi, math.pi, 37)
    hits = caster_of(ring).cast(np.array([1.0, 0.0]), angles)
    assert hits.hit.all()
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    r = 4.9
    tca = d @ np.array([-1.0, 0.0])
    expected = tca + np.sqrt(r * r - (1.0 - tca * tca))
    np.testing.assert_allclose(hits.ranges, expected, atol=TOL)
    assert hits.curvatures is not None
    np.testing.assert_allclose(hits.curvatures, 1.0 / r, atol=TOL)


def test_partial_arc_respects_its_span() -> None:
    arc = Arc((0.0, 0.0), 3.0, 0.0, math.pi / 2, 0.1)   # first quadrant only
    hits = caster_of(arc).cast(np.zeros(2), np.array([math.pi / 4, -math.pi / 4, math.pi]))
    assert hits.hit.tolist() == [True, False, False]
    assert abs(hits.ranges[0] - 2.95) < TOL


def test_max_range_marks_far_hits_as_misses() -> None:
    hits = caster_of(Circle((12.0, 0.0), 1.0)).cast(np.zeros(2), np.array([0.0]), 10.0)
    assert not hits.hit[0] and math.isinf(hits.ranges[0])


def _brute(parts: Parts, o: np.ndarray, angs: np.ndarray) -> np.ndarray:
    d = np.column_stack([np.cos(angs), np.sin(angs)])
    p = parts.seg_start - o
    e = parts.seg_end - parts.seg_start
    den = d[:, 0, None] * e[:, 1] - d[:, 1, None] * e[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (p[:, 0] * e[:, 1] - p[:, 1] * e[:, 0]) / den
        s = (p[:, 0] * d[:, 1, None] - p[:, 1] * d[:, 0, None]) / den
    ok = (t > 1e-12) & (s >= 0) & (s <= 1)
    return np.where(ok, t, np.inf).min(axis=1)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sparse_segments_match_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shapes = [Rectangle(tuple(rng.uniform(-10, 10, 2)), tuple(rng.uniform(0.1, 2, 2)),
                        float(rng.uniform(0, 3))) for _ in range(25)]
    world = World("random", obstacles=tuple(shapes))
    checked = 0
    for _ in range(60):
        o = rng.uniform(-12, 12, 2)
        if world.inside(o):
            continue
        angs = float(rng.uniform(-math.pi, math.pi)) + np.linspace(-math.pi / 2, math.pi / 2, 181)
        got = world.caster.cast(o, angs).ranges
        want = _brute(world.parts, o, angs)
        assert np.array_equal(np.isinf(got), np.isinf(want))
        fin = np.isfinite(want)
        np.testing.assert_allclose(got[fin], want[fin], rtol=0, atol=TOL)
        checked += 1
    assert checked > 30


def test_unsorted_angles_and_full_circle() -> None:
    world = World("box", obstacles=(Wall(((-3, -3), (3, -3), (3, 3), (-3, 3)), 0.2, True),))
    rng = np.random.default_rng(5)
    angs = rng.uniform(-math.pi, math.pi, 400)
    got = world.cast((0.5, -0.2), angs)
    want = _brute(world.parts, np.array([0.5, -0.2]), angs)
    assert got.hit.all()
    np.testing.assert_allclose(got.ranges, want, atol=TOL)


def test_beam_through_a_vertex_is_not_lost() -> None:
    sq = Polygon(((1.0, -1.0), (3.0, -1.0), (3.0, 1.0), (1.0, 1.0)))
    # Rays aimed exactly at the corners (1, -1) and (1, 1).
    hits = caster_of(sq).cast(np.zeros(2), np.array([-math.pi / 4, math.pi / 4]))
    assert hits.hit.all()
    np.testing.assert_allclose(hits.ranges, math.sqrt(2.0), atol=TOL)


def test_curve_faces_carry_sampled_curvature() -> None:
    # A closed smooth blob through points on a circle of radius 2: curvature near -1/2.
    pts = tuple((2 * math.cos(a), 2 * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 36,
                                                                          endpoint=False))
    blob = Curve(pts, thickness=None, closed=True, spacing=0.02)
    hits = caster_of(blob).cast(np.array([-6.0, 0.0]), np.linspace(-0.2, 0.2, 21))
    assert hits.hit.all()
    assert hits.curvatures is not None
    assert np.all(np.abs(hits.curvatures + 0.5) < 0.03)


def test_rectangle_owner_and_orientation() -> None:
    world = World("two", obstacles=(Circle((0.0, 5.0), 1.0), Rectangle((5.0, 0.0), (1.0, 1.0))))
    hits = world.cast((0.0, 0.0), [0.0, math.pi / 2, math.pi])
    assert hits.owner is not None and hits.tangents is not None
    assert hits.owner.tolist() == [1, 0, -1]
    # Facing the rectangle's west face (x = 4.5) from the west: obstacle on the right means
    # travelling north along it.
    assert abs(hits.tangents[0] - math.pi / 2) < TOL


def test_closed_curve_wall_faces_curvature_both_sides() -> None:
    pts = tuple((3 * math.cos(a), 3 * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 36,
                                                                          endpoint=False))
    ring = Curve(pts, thickness=0.2, closed=True, spacing=0.05)
    world = World("ring", obstacles=(ring,))
    inside = world.cast((0.0, 0.0), np.linspace(0, 6, 13))
    assert inside.hit.all()
    assert inside.curvatures is not None
    np.testing.assert_allclose(inside.ranges, 2.9, atol=2e-3)
    np.testing.assert_allclose(inside.curvatures, 1 / 2.9, atol=0.02)     # concave inner face
    outside = world.cast((5.0, 0.0), [math.pi])
    assert outside.curvatures is not None
    np.testing.assert_allclose(outside.curvatures, -1 / 3.1, atol=0.02)   # convex outer face


def test_polygons_agree_with_shapely_intersections() -> None:
    import shapely

    rng = np.random.default_rng(11)
    shapes = []
    for _ in range(12):
        c = rng.uniform(-8, 8, 2)
        hull = shapely.MultiPoint(c + rng.normal(0, 0.8, (7, 2))).convex_hull
        shapes.append(Polygon(tuple(map(tuple, np.asarray(hull.exterior.coords)[:-1]))))
    world = World("hulls", obstacles=tuple(shapes))
    union = shapely.union_all([s.geometry() for s in shapes])
    o = np.array([0.3, -0.2])
    while world.inside(o):
        o = o + 0.5
    angles = np.linspace(-math.pi, math.pi, 721)
    hits = world.cast(o, angles)
    for a, r, h in zip(angles, hits.ranges, hits.hit, strict=True):
        ray = shapely.LineString([o, o + 50 * np.array([math.cos(a), math.sin(a)])])
        inter = ray.intersection(union.boundary)
        if inter.is_empty:
            assert not h
            continue
        d = shapely.Point(o).distance(inter)        # the nearest crossing of any boundary
        assert h and abs(r - d) < 1e-9
