"""Generated obstacles and their starts: deterministic, valid, and as described."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from mdle.sim.generated import FACET_TURN, FAMILIES, GeneratedShape, generate_shape
from mdle.sim.shapes import Circle, Curve, Polygon, Rectangle
from mdle.sim.starts import DISTANCE, GAP, blind_side_starts, collision_starts

SEEDS = range(6)
INDICES = range(2 * len(FAMILIES))


@pytest.fixture(scope="module")
def shapes() -> list[GeneratedShape]:
    return [generate_shape(s, i) for s in SEEDS for i in INDICES]


def test_same_seed_and_index_give_the_same_shape() -> None:
    for i in range(len(FAMILIES)):
        assert generate_shape(7, i) == generate_shape(7, i)
    assert generate_shape(7, 0) != generate_shape(8, 0)
    assert generate_shape(7, 0) != generate_shape(7, len(FAMILIES))


def test_families_cycle_with_the_index() -> None:
    assert [generate_shape(3, i).family for i in range(len(FAMILIES))] == list(FAMILIES)
    assert generate_shape(3, 5, family="plate").family == "plate"


@pytest.mark.parametrize("bad", [(-1, 0), (0, -2)])
def test_negative_seed_or_index_is_refused(bad: tuple[int, int]) -> None:
    with pytest.raises(ValueError, match=">= 0"):
        generate_shape(*bad)


def test_unknown_family_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown shape family `blob`"):
        generate_shape(0, 0, family="blob")


def test_every_shape_is_valid_geometry_of_the_papers_size(shapes: list[GeneratedShape]) -> None:
    for s in shapes:
        for o in s.obstacles:
            g = o.geometry()
            assert g.is_valid and g.geom_type == "Polygon" and g.area > 0, s.name
            assert shapely.Polygon(g.exterior).is_valid, s.name  # no self-intersection
        union = s.geometry()
        assert union.is_valid, s.name
        x0, y0, x1, y1 = union.bounds
        size = max(x1 - x0, y1 - y0)
        assert 0.9 <= size <= 11.0, (s.name, size)
        assert math.hypot((x0 + x1) / 2, (y0 + y1) / 2) < 6.0, s.name  # near the origin


def test_families_have_their_character(shapes: list[GeneratedShape]) -> None:
    for s in shapes:
        g = s.geometry()
        if s.family == "plate":
            (r,) = s.obstacles
            assert isinstance(r, Rectangle)
            assert 0.05 <= min(r.size) <= 0.10 and 1.0 <= max(r.size) <= 6.0
        elif s.family in ("nonconvex", "l-shape", "t-shape", "u-shape", "arc-wall", "sine-wall"):
            assert g.area < 0.95 * g.convex_hull.area, s.name
        elif s.family == "cluster":
            assert 2 <= len(s.obstacles) <= 4
            parts = [o.geometry() for o in s.obstacles]
            gaps = [shapely.distance(a, b) for i, a in enumerate(parts) for b in parts[i + 1:]]
            assert min(gaps) >= 0.4 - 1e-9, s.name
            for i, a in enumerate(parts):  # each member has a neighbour within 2.5 m
                assert min(shapely.distance(a, b) for j, b in enumerate(parts) if j != i) <= 2.5
        elif s.family == "rounded-rect":
            assert sum(isinstance(o, Circle) for o in s.obstacles) == 4
            assert g.geom_type == "Polygon"
        elif s.family == "superellipse":
            (c,) = s.obstacles
            assert isinstance(c, Curve) and c.closed and c.thickness is None


def _turns(points: np.ndarray) -> np.ndarray:
    d = np.roll(points, -1, axis=0) - points
    h = np.arctan2(d[:, 1], d[:, 0])
    return np.abs(np.remainder(np.diff(np.append(h, h[0])) + np.pi, 2 * np.pi) - np.pi)


def test_faceted_curves_turn_about_five_degrees_per_vertex(shapes: list[GeneratedShape]) -> None:
    for s in shapes:
        if not s.family.endswith("-facets"):
            continue
        (p,) = s.obstacles
        assert isinstance(p, Polygon)
        turns = _turns(np.asarray(p.points))
        assert turns.max() <= FACET_TURN * 1.25, (s.name, math.degrees(turns.max()))
        assert abs(turns.sum() - 2 * math.pi) < 1e-6  # convex: the turns add up to one loop
        assert np.median(turns) >= FACET_TURN * 0.75


def test_world_of_a_shape_starts_clear_of_it() -> None:
    for i in range(len(FAMILIES)):
        w = generate_shape(1, i).world()
        assert w.clearance((w.start_pose.x, w.start_pose.y)) >= 3.9
        assert w.obstacles == generate_shape(1, i).obstacles


def _ahead(x: float, y: float, th: float, length: float = 60.0) -> shapely.LineString:
    return shapely.LineString([(x, y), (x + length * math.cos(th), y + length * math.sin(th))])


@pytest.mark.parametrize("side", ["right", "left"])
def test_collision_starts_are_clear_and_head_into_the_obstacle(
        shapes: list[GeneratedShape], side: str) -> None:
    incidences = []
    for s in shapes[:: 3]:
        world = s.world()
        union = s.geometry()
        starts = collision_starts(world, 6, seed=(1, s.index), side=side)
        assert len(starts) == 6 and [x.index for x in starts] == list(range(6))
        for st in starts:
            assert not st.blind
            p = shapely.Point(st.x, st.y)
            assert not union.contains(p)
            assert DISTANCE[0] - 0.01 <= union.exterior.distance(p) if union.geom_type == \
                "Polygon" else True
            assert DISTANCE[0] <= st.distance <= DISTANCE[1]
            assert abs(float(world.clearance((st.x, st.y))) - st.distance) < 1e-9
            assert _ahead(st.x, st.y, st.theta).intersects(union), s.name  # shapely's view
            assert st.ahead >= st.distance - 1e-9
            assert abs(st.incidence) < math.pi / 2
            incidences.append(st.incidence)
    inc = np.degrees(incidences)
    assert inc.min() < -40 and inc.max() > 40  # a spread, both ways


def test_collision_starts_do_not_depend_on_the_side_but_incidence_flips() -> None:
    w = generate_shape(2, 9).world()
    r = collision_starts(w, 4, seed=5, side="right")
    left = collision_starts(w, 4, seed=5, side="left")
    assert [(a.x, a.y, a.theta) for a in r] == [(b.x, b.y, b.theta) for b in left]
    assert [a.incidence for a in r] == [-b.incidence for b in left]
    assert collision_starts(w, 4, seed=5) == r  # deterministic


@pytest.mark.parametrize("side", ["right", "left"])
def test_blind_side_starts_pass_the_obstacle_on_the_non_followed_side(
        shapes: list[GeneratedShape], side: str) -> None:
    for s in shapes[1:: 3]:
        world = s.world()
        union = s.geometry()
        starts = blind_side_starts(world, 5, seed=(2, s.index), side=side)
        assert blind_side_starts(world, 5, seed=(2, s.index), side=side) == starts
        for st in starts:
            assert st.blind and math.isnan(st.incidence)
            assert DISTANCE[0] <= st.distance <= DISTANCE[1]
            assert not _ahead(st.x, st.y, st.theta, 80.0).intersects(union), s.name
            # every boundary point lies on the non-followed side of the path line
            ring = np.vstack([np.asarray(g.exterior.coords)
                              for g in getattr(union, "geoms", [union])])
            lateral = (-math.sin(st.theta) * (ring[:, 0] - st.x)
                       + math.cos(st.theta) * (ring[:, 1] - st.y))
            if side == "right":
                assert lateral.min() >= GAP[0] - 1e-6
            else:
                assert lateral.max() <= -GAP[0] + 1e-6
            assert GAP[0] <= st.gap <= GAP[1]


def test_starts_refuse_an_empty_world_and_a_bad_side() -> None:
    from mdle.sim.world import World

    with pytest.raises(ValueError, match="no obstacles"):
        collision_starts(World("empty"), 1)
    with pytest.raises(ValueError, match="no obstacles"):
        blind_side_starts(World("empty"), 1)
    with pytest.raises(ValueError, match="side must be"):
        collision_starts(generate_shape(0, 0).world(), 1, side="up")
