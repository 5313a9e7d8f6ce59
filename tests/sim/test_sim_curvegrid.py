"""Arcs and ellipses in a grid: a cast tests the curves in range, with the same numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.sim.faceindex import PAD, BoxGrid
from mdle.sim.raycast import COMPILED, RayCaster
from mdle.sim.shapes import Parts, Rectangle


def _field(seed: int, circles: int = 1500, ellipses: int = 400, arcs: int = 300,
           boxes: int = 20) -> Parts:
    """Curves of every kind scattered over 120 x 120 m, some overlapping, and a few boxes."""
    rng = np.random.default_rng(seed)
    tau = 2 * math.pi
    arc_list = [((float(x), float(y)), float(r), 0.0, tau, -1.0)
                for x, y, r in zip(rng.uniform(-60, 60, circles), rng.uniform(-60, 60, circles),
                                   rng.uniform(0.05, 1.5, circles), strict=True)]
    # arcs of rings: convex and concave faces, partial sweeps, a few large
    arc_list += [((float(x), float(y)), float(r), float(a), float(s), float(side))
                 for x, y, r, a, s, side in zip(
                     rng.uniform(-60, 60, arcs), rng.uniform(-60, 60, arcs),
                     rng.choice([0.3, 2.0, 9.0], arcs), rng.uniform(-4, 4, arcs),
                     rng.uniform(0.2, tau, arcs), rng.choice([-1.0, 1.0], arcs), strict=True)]
    ell_list = [((float(x), float(y)), float(a), float(b), float(t))
                for x, y, a, b, t in zip(rng.uniform(-60, 60, ellipses),
                                         rng.uniform(-60, 60, ellipses),
                                         rng.uniform(0.1, 3.0, ellipses),
                                         rng.uniform(0.1, 1.0, ellipses),
                                         rng.uniform(-4, 4, ellipses), strict=True)]
    rects = [Rectangle((float(x), float(y)), (1.0, 0.5), 0.3).parts()
             for x, y in rng.uniform(-50, 50, (boxes, 2))]
    return Parts.concat([Parts.make(arcs=arc_list, ellipses=ell_list), *rects])


def _origins(seed: int, n: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    # inside the field, at its edges and well outside it
    return np.concatenate([rng.uniform(-62, 62, (n, 2)), rng.uniform(-90, 90, (n // 4, 2))])


def test_a_box_is_listed_in_every_cell_it_covers() -> None:
    rng = np.random.default_rng(3)
    lo = rng.uniform(-20, 20, (500, 2))
    hi = lo + rng.exponential(0.8, (500, 2))
    g = BoxGrid.build(lo, hi)
    for i in range(500):
        ix0, iy0 = np.floor((lo[i] - PAD - (g.x0, g.y0)) / g.cell).astype(int)
        ix1, iy1 = np.floor((hi[i] + PAD - (g.x0, g.y0)) / g.cell).astype(int)
        for ix in range(ix0, min(ix1, g.nx - 1) + 1):
            for iy in range(iy0, min(iy1, g.ny - 1) + 1):
                cell = iy * g.nx + ix
                assert i in g.items[g.start[cell]:g.start[cell + 1]]


def test_near_holds_every_box_within_reach() -> None:
    rng = np.random.default_rng(4)
    centre = rng.uniform(-30, 30, (2000, 2))
    r = rng.uniform(0.01, 2.0, 2000)
    g = BoxGrid.build(centre - r[:, None], centre + r[:, None])
    for x, y, reach in zip(rng.uniform(-40, 40, 200), rng.uniform(-40, 40, 200),
                           rng.uniform(0.1, 12, 200), strict=True):
        found = g.near(float(x), float(y), float(reach))
        within = np.flatnonzero(np.hypot(*(centre - (x, y)).T) - r <= reach)
        assert np.isin(within, found).all()
        assert (np.diff(found) > 0).all()                 # ascending, each once
        assert found.shape[0] < 2000 or reach > 30
    assert g.near(math.nan, 0.0, 5.0).tolist() == list(range(2000))
    assert g.near(0.0, 0.0, math.inf).tolist() == list(range(2000))
    assert g.near(1e9, 1e9, 5.0).shape == (0,)


def test_the_grid_refuses_what_it_cannot_index() -> None:
    with pytest.raises(ValueError, match="one or more boxes"):
        BoxGrid.build(np.zeros((0, 2)), np.zeros((0, 2)))
    with pytest.raises(ValueError, match="finite boxes"):
        BoxGrid.build(np.array([[0.0, math.nan]]), np.array([[1.0, 1.0]]))
    with pytest.raises(ValueError, match="finite boxes"):
        BoxGrid.build(np.array([[2.0, 0.0]]), np.array([[1.0, 1.0]]))
    with pytest.raises(ValueError, match="finite and positive"):
        BoxGrid.build(np.array([[0.0, 0.0]]), np.array([[1.0, 1.0]]), cell=0.0)


def test_a_huge_box_among_small_ones_keeps_the_cells_bounded() -> None:
    lo = np.concatenate([np.random.default_rng(5).uniform(0, 1000, (3000, 2)), [[-1e5, -1e5]]])
    hi = lo + np.concatenate([np.full((3000, 2), 0.01), [[2e5, 2e5]]])
    g = BoxGrid.build(lo, hi)
    assert g.nx * g.ny <= 4_000_000 and g.items.shape[0] <= 16 * 3001 + 4_000_000
    assert 3000 in g.near(500.0, 500.0, 1.0)


@pytest.mark.parametrize("max_range", [8.0, 30.0, math.inf])
def test_any_rays_cast_the_same_with_the_curves_grid_or_without(max_range: float) -> None:
    parts = _field(1)
    fast, plain = RayCaster(parts), RayCaster(parts, curve_grids=False)
    assert fast.arc_grid is not None and fast.ellipse_grid is not None
    assert plain.arc_grid is None and plain.ellipse_grid is None
    angles = np.linspace(-math.pi, math.pi, 181, endpoint=False)
    hits = 0
    for o in _origins(2, 60):
        a, b = fast.cast(o, angles, max_range), plain.cast(o, angles, max_range)
        for name in ("ranges", "hit", "tangents", "curvatures", "owner"):
            assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
        hits += int(a.hit.sum())
    assert hits > 1000


@pytest.mark.parametrize("compiled", [False, True] if COMPILED else [False])
def test_a_ladars_fan_casts_the_same_with_the_curves_grid_or_without(compiled: bool) -> None:
    parts = _field(6)
    rel = np.linspace(0.0, math.pi, 181)
    fast = RayCaster(parts).fan(rel, 10.0, compiled)
    plain = RayCaster(parts, curve_grids=False).fan(rel, 10.0, compiled)
    hits = same = 0
    for (x, y), first in zip(_origins(7, 200), np.linspace(-7, 7, 250), strict=True):
        r1, h1 = fast.cast(float(x), float(y), float(first))
        r2, h2 = plain.cast(float(x), float(y), float(first))
        # The ellipses of the cells in range make a smaller matrix product than all of
        # them, which BLAS may round otherwise: the same within the casts' tolerance.
        np.testing.assert_allclose(r1, r2, rtol=0, atol=1e-9)
        edge = np.abs(r2 - 10.0) <= 1e-9
        assert np.array_equal(h1[~edge], h2[~edge])
        hits += int(h1.sum())
        same += int((r1 == r2).sum())
    assert hits > 2000 and same > 0.9 * 250 * 181


def test_a_cast_reads_the_curves_in_range_not_all_of_them() -> None:
    caster = RayCaster(_field(8, circles=20_000, ellipses=2000, arcs=0))
    assert caster.arc_grid is not None and caster.ellipse_grid is not None
    # a 10 m reach over 120 x 120 m: about 3 % of the area
    assert caster.arc_grid.near(0.0, 0.0, 10.0).shape[0] < 2_000
    assert caster.ellipse_grid.near(0.0, 0.0, 10.0).shape[0] < 200


@pytest.mark.parametrize("segments", [True, False])
def test_clearance_queries_are_the_same_with_the_curves_grid_or_without(segments: bool
                                                                        ) -> None:
    from mdle.sim.collision import Collider

    # without segments a query has no first bound: the grid's search widens until it holds
    # a curve as near as its reach
    parts = _field(9, boxes=20 if segments else 0)
    assert (parts.seg_start.shape[0] > 0) == segments
    fast, plain = Collider(parts, 0.25), Collider(parts, 0.25, curve_grids=False)
    for x, y in _origins(10, 300):
        assert fast.distance(float(x), float(y)) == plain.distance(float(x), float(y))
    assert fast._arc_grid is not None and fast._ellipse_grid is not None
    assert plain._arc_grid is None
    nan = fast.distance(math.nan, 0.0)
    assert math.isnan(nan[0]) or nan == plain.distance(math.nan, 0.0)
