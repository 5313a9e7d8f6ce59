"""The per-tick fast paths agree with the general code they stand in for.

FanCaster (a ladar's scans) against RayCaster.cast, Ladar.scan against cast + measure,
ellipse_nearest_point against ellipse_nearest, and the Collider's few-ellipse and
many-ellipse branches against World.nearest_boundary.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from mdle.sim.collision import Collider
from mdle.sim.distance import ellipse_nearest, ellipse_nearest_point
from mdle.sim.ladar import LMS200, Ladar
from mdle.sim.raycast import FanCaster
from mdle.sim.shapes import Arc, Circle, Curve, Ellipse, Rectangle, Wall
from mdle.sim.world import World


def _mixed_world() -> World:
    return World("mix", obstacles=(
        Wall(((-6, -6), (6, -6), (6, 6), (-6, 6)), 0.2, True),
        Circle((1.0, 1.0), 0.5), Ellipse((-2.0, 2.0), (1.0, 0.5), 0.3),
        Arc((2.0, -2.0), 1.0, 0.5, 3.0, 0.1), Rectangle((0.0, -3.5), (1.0, 0.4), 0.2),
        Wall(((-4.0, -1.0), (-3.0, 0.5)), 1e-3)))


def _big_world() -> World:
    """More than 256 segments: the fan culls by bounding box first."""
    rng = np.random.default_rng(7)
    boxes = [Rectangle(tuple(rng.uniform(-15, 15, 2)), tuple(rng.uniform(0.2, 1.0, 2)),
                       float(rng.uniform(0, 3))) for _ in range(90)]
    return World("big", obstacles=(Wall(((-16, -16), (16, -16), (16, 16), (-16, 16)), 0.2,
                                        True), *boxes))


def _ring_world() -> World:
    pts = tuple((4 * math.cos(a), 3 * math.sin(a))
                for a in np.linspace(0, 2 * math.pi, 40, endpoint=False))
    return World("ring", obstacles=(Curve(pts, thickness=0.2, closed=True, spacing=0.05),))


@pytest.mark.parametrize("fov", [1.0, math.pi, 4.5, 2 * math.pi])
@pytest.mark.parametrize("make", [_mixed_world, _big_world, _ring_world])
def test_fan_matches_the_general_caster(fov: float, make: Callable[[], World]) -> None:
    world = make()
    rel = np.linspace(0.0, fov, 181)
    fan = world.caster.fan(rel, 10.0)
    rng = np.random.default_rng(int(fov * 100))
    checked = 0
    for _ in range(80):
        o = rng.uniform(-5.5, 5.5, 2)
        if world.inside(o):
            continue
        first = float(rng.uniform(-4, 4))
        ranges, hit = fan.cast(float(o[0]), float(o[1]), first)
        want = world.caster.cast(o, first + rel, 10.0, detail=False, rel=rel)
        assert np.array_equal(hit, want.hit)
        np.testing.assert_allclose(ranges[hit], want.ranges[hit], rtol=0, atol=1e-9)
        assert np.all(ranges[~hit] == 10.0)
        checked += 1
    assert checked > 40


def test_fan_is_exact_against_analytic_answers() -> None:
    # An angled thin wall and an ellipse, as in test_sim_raycast, through the fan path.
    alpha = math.radians(60.0)
    wall = Wall(((3.0 - 10 * math.cos(alpha), -10 * math.sin(alpha)),
                 (3.0 + 10 * math.cos(alpha), 10 * math.sin(alpha))), thickness=1e-3)
    rel = np.linspace(0.0, 1.8, 181)
    ranges, hit = World("w", obstacles=(wall,)).caster.fan(rel, 50.0).cast(0.0, 0.0, -1.0)
    n = np.array([math.sin(alpha), -math.cos(alpha)])
    d = np.column_stack([np.cos(rel - 1.0), np.sin(rel - 1.0)])
    assert hit.all()
    np.testing.assert_allclose(ranges, (3.0 * math.sin(alpha) - 0.5e-3) / (d @ n), rtol=0,
                               atol=1e-9)
    R, c = 1.3, np.array([4.0, 2.0])
    o = np.array([-1.0, 0.5])
    w = c - o
    dist = float(np.hypot(*w))
    half = math.asin(R / dist) * 0.999
    rel = np.linspace(0.0, 2 * half, 101)
    first = math.atan2(w[1], w[0]) - half
    ranges, hit = World("c", obstacles=(Circle(tuple(c), R),)).caster.fan(rel, 20.0).cast(
        float(o[0]), float(o[1]), first)
    d = np.column_stack([np.cos(first + rel), np.sin(first + rel)])
    tca = d @ w
    assert hit.all()
    np.testing.assert_allclose(ranges, tca - np.sqrt(R * R - (dist * dist - tca * tca)),
                               rtol=0, atol=1e-9)


def test_fan_hit_exactly_at_max_range_counts() -> None:
    # The beam at -30 degrees from (0, 5) meets the wall y = 0 at 10 m: a hit, as in cast.
    world = World("wall", obstacles=(Rectangle((0.0, -1.0), (200.0, 2.0)),))
    rel = np.array([0.0])
    ranges, hit = world.caster.fan(rel, 10.0).cast(0.0, 5.0, -math.pi / 6)
    assert hit.tolist() == [True]
    full = world.caster.cast(np.array([0.0, 5.0]), np.array([-math.pi / 6]), 10.0)
    assert full.hit.tolist() == [True]
    assert math.isclose(float(ranges[0]), 10.0, abs_tol=1e-12)


def test_fan_rejects_bad_fans() -> None:
    caster = _mixed_world().caster
    with pytest.raises(ValueError, match="ascend"):
        FanCaster(caster, np.array([0.0, 0.2, 0.1]), 10.0)
    with pytest.raises(ValueError, match="2 pi"):
        FanCaster(caster, np.array([0.0, 7.0]), 10.0)
    with pytest.raises(ValueError, match="max_range"):
        FanCaster(caster, np.array([0.0, 1.0]), math.inf)


def test_ladar_scan_equals_cast_then_measure() -> None:
    world = _mixed_world()
    a = Ladar(LMS200, np.random.default_rng(3), mount=(0.017, 0.008, 0.0))
    b = Ladar(LMS200, np.random.default_rng(3), mount=(0.017, 0.008, 0.0))
    fan = a.fan(world.caster)
    for x, y, th in [(0.0, 0.0, 0.0), (-4.5, 3.0, 2.0), (3.0, 3.0, -2.5), (0.0, -5.0, 1.0)]:
        fast = a.scan(fan, x, y, th, 1.5)
        ox, oy = b.origin(x, y, th)
        hits = world.caster.cast(np.array((ox, oy)), b.world_angles(th), 10.0, detail=False,
                                 rel=b.rel)
        slow = b.measure(hits, th, 1.5)
        assert np.array_equal(fast.valid, slow.valid)
        np.testing.assert_allclose(fast.ranges, slow.ranges, rtol=0, atol=1e-12)
        assert fast.stamp == 1.5 and not fast.ranges.flags.writeable


@pytest.mark.parametrize(("a", "b"), [(4.0, 2.0), (2.0, 4.0), (1.0, 1.0), (5.0, 0.3)])
def test_ellipse_nearest_point_matches_the_vectorised_form(a: float, b: float) -> None:
    rng = np.random.default_rng(1)
    pts = np.vstack([rng.uniform(-8, 8, (400, 2)), rng.uniform(-1, 1, (100, 2)) * (a, b),
                     [[0.0, 0.0], [0.5 * a, 0.0], [-0.5 * a, 0.0], [0.0, 0.5 * b],
                      [0.0, -0.5 * b], [a + 1, 0.0], [0.0, -b - 1], [a, 0.0], [0.0, b]]])
    ex, ey = ellipse_nearest(np.full(len(pts), a), np.full(len(pts), b), pts[:, 0], pts[:, 1])
    got = np.array([ellipse_nearest_point(a, b, float(x), float(y)) for x, y in pts])
    np.testing.assert_allclose(got[:, 0], ex, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got[:, 1], ey, rtol=0, atol=1e-12)
    np.testing.assert_allclose((got[:, 0] / a) ** 2 + (got[:, 1] / b) ** 2, 1.0, atol=1e-9)


@pytest.mark.parametrize("n_ellipses", [3, 20])
def test_collider_with_few_and_many_ellipses(n_ellipses: int) -> None:
    rng = np.random.default_rng(n_ellipses)
    shapes = [Ellipse(tuple(rng.uniform(-3, 3, 2)), tuple(rng.uniform(0.2, 0.8, 2)),
                      float(rng.uniform(0, 3))) for _ in range(n_ellipses)]
    world = World("eggs", obstacles=tuple(shapes))
    col = Collider(world.parts, radius=0.1)
    checked = 0
    for x, y in rng.uniform(-4, 4, (150, 2)):
        if world.inside((x, y)):
            continue
        d, owner = col.distance(float(x), float(y))
        n = world.nearest_boundary((x, y))
        assert math.isclose(d, n.distance, abs_tol=1e-9) and owner == n.obstacle
        checked += 1
    assert checked > 50


def test_fan_from_inside_an_ellipse_sees_its_far_side() -> None:
    # Not a robot's case (its body keeps the ladar outside), but the fan is general.
    world = World("egg", obstacles=(Ellipse((0.5, -0.2), (3.0, 1.5), 0.4),))
    rel = np.linspace(0.0, math.pi, 91)
    fan = world.caster.fan(rel, 10.0)
    for x, y in [(0.5, -0.2), (1.5, 0.3), (-1.0, -0.5)]:
        ranges, hit = fan.cast(x, y, 0.7)
        want = world.caster.cast(np.array((x, y)), 0.7 + rel, 10.0, detail=False)
        assert hit.all() and want.hit.all()
        np.testing.assert_allclose(ranges, want.ranges, rtol=0, atol=1e-9)


def test_collider_near_list_in_a_large_world_is_exact() -> None:
    # More than 256 segments: the collider keeps the segments near the robot and remakes
    # the list when the robot has moved away; along a walk with small steps and jumps the
    # answers equal the full computation.
    world = _big_world()
    assert world.parts.n_segments > 256
    col = Collider(world.parts, radius=0.25)
    rng = np.random.default_rng(11)
    p = np.array([0.3, -0.4])
    checked = 0
    for k in range(300):
        p = p + (rng.normal(0, 0.08, 2) if k % 25 else rng.uniform(-6, 6, 2))
        p = np.clip(p, -14.0, 14.0)
        if world.inside(p):
            continue
        d, owner = col.distance(float(p[0]), float(p[1]))
        n = world.nearest_boundary(p)
        assert math.isclose(d, n.distance, abs_tol=1e-12) and owner == n.obstacle
        checked += 1
    assert checked > 150


def test_fast_observation_and_scan_equal_the_dataclass_constructors() -> None:
    """observation() and plain_scan() fill every field as the dataclasses' own __init__ do."""
    from mdle.core.backend import Observation, Scan, observation, plain_scan
    from mdle.core.pose import Pose

    r, b, v = np.ones(3), np.zeros(3), np.ones(3, dtype=bool)
    fast = plain_scan(r, b, v, 0.5, 10.0)
    slow = Scan(ranges=r, bearings=b, valid=v, stamp=0.5, max_range=10.0)
    assert vars(fast) == vars(slow)
    truth = {"clearance": 1.0}
    got = observation(1.5, Pose(1.0, 2.0, 0.5), 0.3, -0.1, fast, True, truth)
    assert got == Observation(time=1.5, pose=Pose(1.0, 2.0, 0.5), v=0.3, omega=-0.1,
                              scan=fast, stalled=True, truth=truth)
    assert list(vars(got)) == list(vars(Observation(0.0, Pose())))  # every field, in order
    with pytest.raises(AttributeError):
        got.time = 0.0  # type: ignore[misc]  # still frozen


def test_a_fan_cast_from_many_places_at_once_equals_each_cast_bit_for_bit() -> None:
    world = World("boxes", obstacles=(
        Wall(((-6, -6), (6, -6), (6, 6), (-6, 6)), 0.2, True),
        Rectangle((2.0, 1.0), (1.0, 0.5), 0.3), Rectangle((-2.5, -1.0), (0.4, 2.0), 1.1)))
    fan = Ladar(LMS200, np.random.default_rng(0), mount=(0.02, 0.01, 0.0)).fan(world.caster)
    assert fan.batchable()
    rng = np.random.default_rng(4)
    ox, oy = rng.uniform(-5.5, 5.5, 60), rng.uniform(-5.5, 5.5, 60)
    first = rng.uniform(-7.0, 7.0, 60)   # every heading: the intervals' wrap included
    ranges, hit = fan.cast_many(ox, oy, first)
    assert ranges.shape == hit.shape == (60, LMS200.beams)
    for s in range(60):
        want_r, want_h = fan.cast(float(ox[s]), float(oy[s]), float(first[s]))
        assert np.array_equal(ranges[s], want_r) and np.array_equal(hit[s], want_h)
    assert not Ladar(LMS200, np.random.default_rng(0)).fan(_mixed_world().caster).batchable()


def test_settling_scans_as_one_block_draws_and_rounds_as_each_ladar_alone() -> None:
    from mdle.sim.ladar import LMS200_IDEAL, settle_rows

    rng = np.random.default_rng(9)
    ranges = rng.uniform(0.0, 12.0, (3, LMS200.beams))
    valid = ranges < 10.0
    ranges[~valid] = LMS200.max_range
    block, block_valid = ranges.copy(), valid.copy()
    settle_rows([Ladar(LMS200, np.random.default_rng(s)) for s in range(3)], block,
                block_valid)
    for s in range(3):
        r, v = ranges[s].copy(), valid[s].copy()
        Ladar(LMS200, np.random.default_rng(s)).settle(r, v)
        assert np.array_equal(block[s], r)
    assert not block.flags.writeable and not block_valid.flags.writeable
    with pytest.raises(ValueError, match="one profile"):
        settle_rows([Ladar(LMS200, rng), Ladar(LMS200_IDEAL, rng)], ranges.copy(),
                    valid.copy())


def test_a_half_turn_fan_sees_a_face_that_wraps_round_behind_it() -> None:
    # A face passing within 1e-9 m of the ladar, from its left beam round behind it to past
    # its right beam: its bearing interval, measured from the fan's reference direction,
    # ends more than a turn up, so its copy one turn down holds the first beam. A half
    # turn (the LMS-200's fan) must check for that, as wider fans do.
    h = 5e-4
    world = World("w", obstacles=(Wall(((-4e-10 - h, 5.0), (2e-10 - h, -5.0)), 2 * h),))
    rel = np.linspace(0.0, math.pi, 181)
    ranges, hit = world.caster.fan(rel, 10.0).cast(0.0, 0.0, -math.pi / 2)
    want = world.caster.cast(np.array([0.0, 0.0]), -math.pi / 2 + rel, 10.0, detail=False,
                             rel=rel)
    assert hit[0] and np.array_equal(hit, want.hit)
    np.testing.assert_allclose(ranges[hit], want.ranges[hit], rtol=0, atol=1e-9)
