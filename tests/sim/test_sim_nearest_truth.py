"""The true curvature at a point's nearest boundary point: faces, corners, arcs, ellipses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.sim.nearest_truth import nearest_curvature
from mdle.sim.shapes import Circle, Curve, Ellipse, Parts, Polygon, Wall


def _parts(*shapes: object) -> Parts:
    return Parts.concat([s.parts() for s in shapes])  # type: ignore[attr-defined]


def test_a_polygon_face_is_straight_and_a_vertex_is_a_corner() -> None:
    tri = Polygon(((0.0, 0.0), (4.0, 0.0), (0.0, 3.0)))
    q = np.array([[2.0, -0.5],        # below the bottom face
                  [-1.0, -1.0],       # beyond the right-angle vertex
                  [5.0, -0.2],        # beyond the sharp vertex at (4, 0)
                  [2.5, 2.0]])        # off the hypotenuse
    d, k = nearest_curvature(tri.parts(), q)
    assert d[:3] == pytest.approx([0.5, math.sqrt(2.0), math.hypot(1.0, 0.2)])
    assert d[3] == pytest.approx(abs(3 * 2.5 + 4 * 2.0 - 12) / 5)
    assert k[0] == 0.0 and k[3] == 0.0
    assert np.isneginf(k[1]) and np.isneginf(k[2])


def test_a_disc_and_an_ellipse_give_their_own_curvature() -> None:
    disc = Circle((0.0, 0.0), 0.5)
    d, k = nearest_curvature(disc.parts(), np.array([[1.5, 0.0], [0.0, -0.9]]))
    assert d == pytest.approx([1.0, 0.4]) and k == pytest.approx([-2.0, -2.0])
    ell = Ellipse((1.0, -1.0), (4.0, 2.0), math.pi / 2)  # a axis along y
    d, k = nearest_curvature(ell.parts(), np.array([[1.0, 4.0], [4.0, -1.0]]))
    # at the end of the a axis a / b^2, at the end of the b axis b / a^2
    assert d == pytest.approx([1.0, 1.0]) and k == pytest.approx([-1.0, -0.125])


def test_the_nearest_of_several_shapes_wins() -> None:
    parts = _parts(Circle((0.0, 0.0), 1.0), Polygon(((3.0, -1.0), (5.0, -1.0), (5.0, 1.0),
                                                       (3.0, 1.0))))
    d, k = nearest_curvature(parts, np.array([[1.9, 0.0], [2.2, 0.0], [2.9, 1.1]]))
    assert d[:2] == pytest.approx([0.9, 0.8])
    assert k[0] == pytest.approx(-1.0) and k[1] == 0.0 and np.isneginf(k[2])


def test_a_wall_end_is_a_corner_and_a_sampled_curve_has_no_corners() -> None:
    wall = Wall(((0.0, 0.0), (3.0, 0.0)), 0.02)  # a flat 2 cm end face
    d, k = nearest_curvature(wall.parts(), np.array([[1.5, 0.5], [3.5, 0.0], [3.5, 0.5]]))
    assert k[0] == 0.0 and k[1] == 0.0 and np.isneginf(k[2])
    # a closed curve sampled from a circle of radius 1: facets carry about -1 everywhere,
    # including at the joints between them
    ring = tuple((math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 24,
                                                                 endpoint=False))
    blob = Curve(ring, closed=True, spacing=0.05)
    angles = np.linspace(0.0, 2 * math.pi, 50, endpoint=False)
    q = 1.5 * np.column_stack([np.cos(angles), np.sin(angles)])
    d, k = nearest_curvature(blob.parts(), q)
    assert np.isfinite(k).all() and np.abs(k + 1.0).max() < 0.1


def test_no_obstacles_gives_no_answer() -> None:
    d, k = nearest_curvature(Parts.make(), np.array([[0.0, 0.0]]))
    assert np.isinf(d[0]) and np.isnan(k[0])
