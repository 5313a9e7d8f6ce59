"""The faces' grid (sim/faceindex.py) and the ladar's walk through it (sim/_kernels.c).

The walk must give the numbers of the plain cast (every face within range, culled by
bounding box) bit for bit, and of the numpy path; and it must read only the faces along
the beams, however large the world.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.core.backend import Command
from mdle.core.pose import Pose
from mdle.sim import raycast
from mdle.sim.backend import SimBackend
from mdle.sim.faceindex import PAD, FaceGrid
from mdle.sim.raycast import COMPILED, FanCaster
from mdle.sim.shapes import Polygon, Rectangle, Wall
from mdle.sim.world import World
from tests.sim.conftest import boxes_world

needs_walk = pytest.mark.skipif(not COMPILED or raycast._GRID_WALK is None,
                                reason="this install has no compiled fan cast")


def _rooms(side: int, seed: int = 0) -> World:
    """``side`` x ``side`` rooms of 5 m with a door in two walls, a table and a round bin each."""
    rng = np.random.default_rng(seed)
    shapes: list[Rectangle | Polygon | Wall] = []
    ring = np.linspace(0.0, 2 * math.pi, 16, endpoint=False)
    for i in range(side):
        for j in range(side):
            x0, y0 = 5.0 * i, 5.0 * j
            d = float(rng.uniform(1.5, 3.5))
            shapes += [Rectangle((x0 + (d - 0.5) / 2, y0), (d - 0.5, 0.1)),
                       Rectangle((x0 + (d + 5.5) / 2, y0), (4.5 - d, 0.1)),
                       Rectangle((x0, y0 + (d - 0.5) / 2), (0.1, d - 0.5)),
                       Rectangle((x0, y0 + (d + 5.5) / 2), (0.1, 4.5 - d)),
                       Rectangle((x0 + 1.2, y0 + 3.8), (0.8, 0.5), float(rng.uniform(0, 3)))]
            shapes.append(Polygon(tuple((x0 + 4.0 + 0.3 * math.cos(a),
                                         y0 + 1.0 + 0.3 * math.sin(a)) for a in ring)))
    shapes.append(Wall(((0, 0), (5.0 * side, 0), (5.0 * side, 5.0 * side), (0, 5.0 * side)),
                       0.2, True))
    middle = 5.0 * (side // 2) + 2.5
    return World(f"rooms{side}", tuple(shapes), Pose(middle, middle, 0.0))


def test_every_face_is_listed_in_each_cell_it_passes_through() -> None:
    rng = np.random.default_rng(4)
    s0 = rng.uniform(-20, 20, (300, 2))
    s1 = s0 + rng.uniform(-6, 6, (300, 2))
    grid = FaceGrid.build(s0, s1, cell=0.7)
    listed = {(int(c), int(f)) for c in range(grid.nx * grid.ny)
              for f in grid.faces[grid.start[c]:grid.start[c + 1]]}
    # Points finely along each face, and just off its ends by less than the pad.
    for f in range(300):
        e = s1[f] - s0[f]
        off = 0.5 * PAD / float(np.hypot(*e))
        pts = s0[f] + np.linspace(-off, 1 + off, 400)[:, None] * e
        cells = np.floor((pts - (grid.x0, grid.y0)) / grid.cell).astype(int)
        for ix, iy in cells:
            assert (iy * grid.nx + ix, f) in listed
    assert grid.start[0] == 0 and grid.start[-1] == grid.faces.shape[0]
    assert (np.diff(grid.start) >= 0).all()


def test_the_grid_refuses_what_it_cannot_index() -> None:
    with pytest.raises(ValueError, match="one or more faces"):
        FaceGrid.build(np.zeros((0, 2)), np.zeros((0, 2)))
    with pytest.raises(ValueError, match="finite"):
        FaceGrid.build(np.array([[0.0, math.nan]]), np.array([[1.0, 1.0]]))
    with pytest.raises(ValueError, match="cell must be finite and positive"):
        FaceGrid.build(np.array([[0.0, 0.0]]), np.array([[1.0, 1.0]]), cell=0.0)


def test_a_huge_sparse_world_keeps_its_cells_bounded() -> None:
    s0 = np.array([[0.0, 0.0], [1e5, 1e5]])
    grid = FaceGrid.build(s0, s0 + 0.01)
    assert grid.nx * grid.ny <= 4_100_000


@needs_walk
@pytest.mark.parametrize("beams", [181, 361, 7])
@pytest.mark.parametrize("fov", [1.0, math.pi, 4.5, 2 * math.pi])
@pytest.mark.parametrize("make", [lambda: boxes_world(300, 20, 1), lambda: _rooms(6)],
                         ids=["boxes", "rooms"])
def test_the_walk_gives_the_plain_casts_numbers_bit_for_bit(
        beams: int, fov: float, make: object) -> None:
    assert callable(make)
    world = make()
    rel = np.linspace(0.0, fov, beams)
    walk = world.caster.fan(rel, 8.0, True, True)
    plain = world.caster.fan(rel, 8.0, True, False)
    ref = world.caster.fan(rel, 8.0, False)
    assert walk._grid is not None and plain._grid is None
    rng = np.random.default_rng(beams)
    lo, hi = np.asarray(world.bounds).reshape(2, 2)
    hits = 0
    for _ in range(60):
        o = rng.uniform(lo - 5.0, hi + 5.0)    # outside the grid's box too
        first = float(rng.uniform(-7.0, 7.0))
        r1, h1 = walk.cast(float(o[0]), float(o[1]), first)
        r2, h2 = plain.cast(float(o[0]), float(o[1]), first)
        r3, h3 = ref.cast(float(o[0]), float(o[1]), first)
        assert np.array_equal(r1, r2) and np.array_equal(h1, h2)
        assert np.array_equal(r1, r3) and np.array_equal(h1, h3)
        hits += int(h1.sum())
    assert hits > 60 * beams // 10


@needs_walk
def test_a_scan_reads_the_faces_along_its_beams_not_the_whole_map() -> None:
    small, large = _rooms(4), _rooms(30)
    read = []
    for world in (small, large):
        fan = world.caster.fan(np.linspace(0.0, math.pi, 181), 8.0, True)
        p = world.start_pose
        met = []
        for k in range(8):
            fan.cast(p.x, p.y, k * 0.8)
            met.append(fan._walker.met)
        read.append(sum(met))
    n_large = large.caster._s0.shape[0]
    assert n_large > 20_000
    # The same rooms around the robot: the same faces met, in a world 56 times larger.
    assert 0 < read[1] <= 1.2 * read[0] and read[1] < 0.01 * 8 * n_large, (read, n_large)


@needs_walk
def test_a_seeded_run_in_a_large_world_is_the_same_with_the_grid_or_without() -> None:
    world = _rooms(8)
    runs = []
    for indexed in (True, False):
        backend = SimBackend(world, seed=5, robot="ideal")
        assert (backend._fan is not None)
        backend._fan = world.caster.fan(backend._ladar.rel, backend._ladar.profile.max_range,
                                        True, indexed)
        path = []
        for k in range(300):
            obs = backend.observe()
            omega = 0.6 if obs.scan is not None and obs.scan.ranges[80:100].min() < 1.0 else 0.0
            backend.command(Command(0.4, omega + 0.1 * math.sin(0.05 * k)))
            backend.advance(0.1)
            path.append((obs.pose.x, obs.pose.y,
                         None if obs.scan is None else obs.scan.ranges.tobytes()))
        runs.append(path)
    assert runs[0] == runs[1]
    assert sum(p[2] is not None for p in runs[0]) > 250


@needs_walk
def test_hostile_origins_never_take_the_walk_outside_its_arrays() -> None:
    fan = _rooms(3).caster.fan(np.linspace(0.0, math.pi, 181), 8.0, True)
    odd = [math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300, 0.0, 7.5]
    for x in odd:
        for y in odd:
            for first in (0.0, 1.0, math.nan, 1e300):
                ranges, hit = fan.cast(x, y, first)
                assert ranges.shape == hit.shape == (181,)


@needs_walk
def test_the_walk_refuses_arrays_that_do_not_fit() -> None:
    world = _rooms(3)
    fan = world.caster.fan(np.linspace(0.0, math.pi, 181), 8.0, True)
    grid = world.caster.grid
    walk = raycast._GRID_WALK
    assert grid is not None and walk is not None
    best, ranges, hit = np.zeros(181), np.zeros(181), np.zeros(181, dtype=bool)

    def make(**change: object) -> object:
        args = {"zw": fan._zw, "front_min": world.caster._front_min, "dconj": fan._dconj,
                "box": grid.box, "start": grid.start, "faces": grid.faces, "best": best,
                "ranges": ranges, "hit": hit}
        args.update(change)
        return walk(*args.values(), 1e-10, True, 8.0, 1e-9, fan._inv_none, fan._inv_hit, 8.0)

    with pytest.raises(ValueError, match="box and cells do not fit"):
        make(box=np.array([grid.x0, grid.y0, grid.cell, grid.nx + 1.0, float(grid.ny)]))
    with pytest.raises(ValueError, match="zw: expected"):
        make(zw=fan._zw[:, :-1].copy())
    with pytest.raises(ValueError, match="best: expected 180"):
        make(dconj=fan._dconj[:-1].copy())
    with pytest.raises(ValueError, match="start: expected intp"):
        make(start=grid.start.astype(np.int32))
    with pytest.raises(ValueError, match="hit: expected"):
        make(hit=np.zeros(181))
    with pytest.raises(ValueError, match="not C-contiguous"):
        make(best=np.zeros(181)[::-1])
    # Faces the world lacks are skipped, never read.
    w = make(faces=np.full_like(grid.faces, 10**9))
    w.faces(7.5, 7.5, 1 + 0j, 7.5 + 7.5j)      # type: ignore[attr-defined]
    assert (best == 0.0).all()
    with pytest.raises(TypeError, match="takes 4 arguments"):
        w.scan(7.5, 7.5, 1 + 0j)                # type: ignore[attr-defined]


def test_without_the_compiled_loop_the_fan_casts_as_before() -> None:
    world = _rooms(3)
    fan = FanCaster(world.caster, np.linspace(0.0, math.pi, 181), 8.0, compiled=False)
    assert fan._grid is None
    r, h = fan.cast(7.5, 7.5, 0.3)
    assert h.any() and (r <= 8.0).all()
