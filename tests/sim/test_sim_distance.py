"""Exact clearance and nearest boundary points, against dense sampling of the boundary."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.sim.collision import Collider
from mdle.sim.distance import ellipse_nearest
from mdle.sim.shapes import Arc, Circle, Ellipse, Rectangle, Wall
from mdle.sim.world import World


def _sampled_ellipse_distance(a: float, b: float, pts: np.ndarray) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, 100001)
    cx, cy = a * np.cos(t), b * np.sin(t)
    return np.array([np.min(np.hypot(cx - x, cy - y)) for x, y in pts])


@pytest.mark.parametrize(("a", "b"), [(4.0, 2.0), (2.0, 4.0), (1.0, 1.0), (5.0, 0.3)])
def test_ellipse_nearest_point_outside_and_inside(a: float, b: float) -> None:
    rng = np.random.default_rng(0)
    pts = rng.uniform(-8, 8, (40, 2))
    pts = np.vstack([pts, [[0.0, 0.0], [0.5 * a, 0.0], [0.0, 0.5 * b], [a + 1, 0.0]]])
    ex, ey = ellipse_nearest(np.full(len(pts), a), np.full(len(pts), b), pts[:, 0], pts[:, 1])
    # On the ellipse ...
    np.testing.assert_allclose((ex / a) ** 2 + (ey / b) ** 2, 1.0, atol=1e-9)
    # ... and at least as near as the best of 100,001 samples of the ellipse.
    d = np.hypot(ex - pts[:, 0], ey - pts[:, 1])
    assert np.all(d <= _sampled_ellipse_distance(a, b, pts) + 1e-12)


def test_world_clearance_and_nearest_boundary() -> None:
    world = World("mix", obstacles=(
        Circle((0.0, 5.0), 1.0),
        Rectangle((5.0, 0.0), (2.0, 2.0)),
        Ellipse((-6.0, 0.0), (2.0, 1.0), math.radians(90)),
        Arc((0.0, -8.0), 2.0, 0.0, math.pi, 0.2),
    ))
    n = world.nearest_boundary((0.0, 0.0))
    assert math.isclose(n.distance, 4.0, abs_tol=1e-12) and n.obstacle == 1   # rectangle at x=4
    np.testing.assert_allclose(n.point, [4.0, 0.0], atol=1e-12)
    # Ellipse turned 90 degrees: its a axis is vertical; nearest from (-3, 0) is (-5, 0).
    n = world.nearest_boundary((-3.0, 0.0))
    assert math.isclose(n.distance, 2.0, abs_tol=1e-9) and n.obstacle == 2
    # Arc wall from above its apex: outer face at radius 2.1.
    n = world.nearest_boundary((0.0, -4.0))
    assert math.isclose(n.distance, 4.0 - 2.1, abs_tol=1e-12) and n.obstacle == 3
    # Below the arc's open side the nearest points are the end caps.
    n = world.nearest_boundary((3.0, -9.0))
    assert math.isclose(n.distance, math.hypot(3.0 - 2.1, 1.0), abs_tol=1e-12)
    # Clearance of a disc, negative inside an obstacle.
    assert math.isclose(world.clearance((0.0, 3.0), radius=0.5), 0.5, abs_tol=1e-12)
    assert math.isclose(world.clearance((5.0, 0.5), radius=0.0), -0.5, abs_tol=1e-12)
    many = world.nearest_boundary(np.array([[0.0, 0.0], [-3.0, 0.0]]))
    assert isinstance(many.distance, np.ndarray)
    assert many.distance.shape == (2,) and many.point.shape == (2, 2)


def test_collider_matches_world_distance() -> None:
    world = World("room", obstacles=(
        Wall(((-5, -5), (5, -5), (5, 5), (-5, 5)), 0.2, True),
        Circle((1.0, 1.0), 0.5), Ellipse((-2.0, 2.0), (1.0, 0.5), 0.3),
        Arc((2.0, -2.0), 1.0, 0.5, 3.0, 0.1)))
    col = Collider(world.parts, radius=0.25)
    rng = np.random.default_rng(3)
    for x, y in rng.uniform(-4.5, 4.5, (200, 2)):
        if world.inside((x, y)):
            continue
        d, _ = col.distance(float(x), float(y))
        n = world.nearest_boundary((x, y))
        assert math.isclose(d, n.distance, abs_tol=1e-9)
        assert math.isclose(col.clearance(float(x), float(y))[0], d - 0.25)


def test_empty_world() -> None:
    world = World("nothing")
    assert math.isinf(world.clearance((0.0, 0.0)))
    assert world.nearest_boundary((0.0, 0.0)).obstacle == -1
    assert not world.cast((0.0, 0.0), [0.0, 1.0]).hit.any()
