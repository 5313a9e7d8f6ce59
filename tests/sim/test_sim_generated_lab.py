"""The lab suite of generated obstacles (thin, sharp, clustered) and the tangential starts."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from mdle.sim.generated import FAMILIES, LAB_FAMILIES, GeneratedShape, generate_shape
from mdle.sim.shapes import Circle, Polygon, Rectangle
from mdle.sim.starts import PASS, tangential_starts


def _shapes(family: str) -> list[GeneratedShape]:
    return [generate_shape(seed, index, family) for seed in range(3) for index in range(8)]


def test_lab_families_are_drawn_by_name_only() -> None:
    assert not set(LAB_FAMILIES) & set(FAMILIES)
    assert generate_shape(0, 3, "pole") == generate_shape(0, 3, "pole")
    assert generate_shape(0, 3) == generate_shape(0, 3, FAMILIES[3])  # the paper suite as before


@pytest.mark.parametrize("family", LAB_FAMILIES)
def test_every_lab_shape_is_valid_geometry(family: str) -> None:
    for s in _shapes(family):
        assert s.family == family and s.obstacles
        for o in s.obstacles:
            g = o.geometry()
            assert g.is_valid and g.area > 1e-4, s.name


def test_poles_and_rows_have_their_radii_and_gaps() -> None:
    for s in _shapes("pole"):
        (pole,) = s.obstacles
        assert isinstance(pole, Circle) and 0.02 <= pole.radius <= 0.10
    for s in _shapes("pole-row"):
        assert 3 <= len(s.obstacles) <= 7
        poles = [o for o in s.obstacles if isinstance(o, Circle)]
        assert len(poles) == len(s.obstacles)
        c = np.array([o.center for o in poles])
        radius = poles[0].radius
        gaps = np.linalg.norm(np.diff(c, axis=0), axis=1) - 2 * radius
        assert 0.02 <= radius <= 0.15 and gaps.min() >= 0.7 and gaps.max() <= 1.65


def test_spike_stars_have_tips_of_20_to_40_degrees() -> None:
    for s in _shapes("spike-star"):
        (star,) = s.obstacles
        assert isinstance(star, Polygon)
        p = np.asarray(star.points)
        n = len(p)
        for i in range(0, n, 2):  # the tips are the even vertices
            a, b = p[i - 1] - p[i], p[(i + 1) % n] - p[i]
            angle = math.degrees(math.acos(a @ b / np.linalg.norm(a) / np.linalg.norm(b)))
            assert 20.0 - 1e-6 <= angle <= 40.0 + 1e-6, s.name


def test_disc_chains_touch_or_overlap_plates_are_thin_tables_have_four_legs() -> None:
    for s in _shapes("disc-chain"):
        assert all(isinstance(o, Circle) and 0.15 <= o.radius <= 0.8 for o in s.obstacles)
        union = shapely.union_all([o.geometry() for o in s.obstacles])
        assert union.geom_type == "Polygon", s.name  # one chain, cusps where discs meet
    for s in _shapes("thin-plate"):
        (plate,) = s.obstacles
        assert isinstance(plate, Rectangle) and 0.01 <= plate.size[1] <= 0.03
    for s in _shapes("table"):
        assert len(s.obstacles) == 4
        union = shapely.union_all([o.geometry() for o in s.obstacles])
        assert union.geom_type == "MultiPolygon"  # four separate legs


@pytest.mark.parametrize("side", ["right", "left"])
def test_tangential_starts_pass_an_outermost_point_on_the_followed_side(side: str) -> None:
    sign = 1.0 if side == "right" else -1.0
    abeam = 0
    for s in _shapes("spike-star")[:6] + _shapes("pole-row")[:6]:
        world = s.world()
        union = s.geometry()
        starts = tangential_starts(world, 5, seed=(3, s.index), side=side)
        assert [st.index for st in starts] == list(range(5))
        assert tangential_starts(world, 5, seed=(3, s.index), side=side) == starts
        for st in starts:
            assert PASS[0] <= st.gap <= PASS[1] and math.isnan(st.incidence)
            assert st.distance >= 0.4 and not union.contains(shapely.Point(st.x, st.y))
            h = np.array([math.cos(st.theta), math.sin(st.theta)])
            followed = sign * np.array([h[1], -h[0]])  # right of the heading (left: mirrored)
            # the point passed: outermost along the followed side's direction, gap away
            rel = np.asarray(union.exterior.coords if union.geom_type == "Polygon" else
                             np.vstack([g.exterior.coords for g in union.geoms])) - (st.x, st.y)
            side_offset = rel @ followed
            k = int(np.argmin(np.abs(side_offset - st.gap)))
            assert side_offset[k] == pytest.approx(st.gap, abs=0.02)
            assert (rel @ followed).min() >= st.gap - 0.02  # nothing nearer across the path
            abeam += abs(float(rel[k] @ h)) < 0.02
    assert abeam >= 10  # about half start with the point exactly abeam


def test_tangential_starts_put_the_point_abeam_of_the_ladar() -> None:
    # the Pioneer's ladar sits 17 mm ahead of its centre: abeam of the centre, a plate's end
    # face would start outside the ladar's 180 degrees and never be seen
    world = generate_shape(0, 4, "thin-plate").world()
    plain = tangential_starts(world, 8, seed=5)
    ahead = tangential_starts(world, 8, seed=5, ladar=0.017)
    for a, b in zip(plain, ahead, strict=True):
        shift = complex(b.x - a.x, b.y - a.y)
        assert abs(shift) == pytest.approx(0.017)
        assert math.cos(math.atan2(shift.imag, shift.real) - a.theta) == pytest.approx(-1.0)
