"""A curve given as a polygon: its faces carry the curvature a robot following it meets."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.sim.shapes import Polygon, polygon_parts


def _rounded_rectangle(radius: float, step_deg: float) -> Polygon:
    pts = []
    for cx, cy, a0 in [(1.4, 0.4, 0), (-1.4, 0.4, 90), (-1.4, -0.4, 180), (1.4, -0.4, 270)]:
        for a in np.radians(np.arange(a0, a0 + 90.0 + 1e-9, step_deg)):
            pts.append((cx + radius * math.cos(a), cy + radius * math.sin(a)))
    return Polygon(tuple(pts))


def test_facets_of_a_rounded_corner_carry_its_curvature() -> None:
    parts = _rounded_rectangle(0.6, 5.0).parts()
    length = np.hypot(*(parts.seg_end - parts.seg_start).T)
    arc = length < 0.1
    # convex: negative, about -1/R on the corner's facets
    assert np.all(parts.seg_kappa[arc] < 0)
    assert np.median(parts.seg_kappa[arc]) == pytest.approx(-1 / 0.6, rel=0.02)
    # the long flat sides stay nearly flat
    assert np.all(np.abs(parts.seg_kappa[~arc]) < 0.2)


def test_a_true_polygon_keeps_flat_faces() -> None:
    hexagon = Polygon(tuple((2 * math.cos(a), 2 * math.sin(a))
                            for a in np.radians(np.arange(0, 360, 60))))
    assert np.all(hexagon.parts().seg_kappa == 0.0)
    square = Polygon(((0, 0), (1, 0), (1, 1), (0, 1)))
    assert np.all(polygon_parts(square.geometry()).seg_kappa == 0.0)


def test_a_many_sided_circle_is_a_circle() -> None:
    # 24 sides: 15 degrees a vertex, a sampled circle of radius 2 (convex: -1/2)
    ring = Polygon(tuple((2 * math.cos(a), 2 * math.sin(a))
                         for a in np.radians(np.arange(0, 360, 15))))
    assert ring.parts().seg_kappa == pytest.approx(np.full(24, -0.5), rel=0.02)
