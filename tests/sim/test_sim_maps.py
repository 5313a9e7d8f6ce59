"""ROS map_server maps (sim/maps.py), the `map:` key of a world file, and `mdle worlds import`.

The maps are written here as map_saver writes them: a binary PGM (P5) whose comment names
the creator, free cells 254, occupied 0 and unknown 205, the first row the map's top,
beside its YAML file.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from mdle.core.errors import WorldError
from mdle.sim.catalog import load_world
from mdle.sim.maps import (
    FloorPlan,
    load_map,
    occupied_cells,
    outline,
    read_image,
    read_map_info,
)
from mdle.sim.shapes import Parts, polygon_parts
from mdle.sim.world import World

FREE, OCCUPIED, UNKNOWN = 254, 0, 205


def _room(rows: int = 80, cols: int = 100) -> np.ndarray:
    """A room with 2-cell walls, unknown outside, and a 6 x 6 pillar; cell values as map_saver's."""
    img = np.full((rows, cols), UNKNOWN, dtype=np.uint8)
    img[10:70, 10:90] = OCCUPIED
    img[12:68, 12:88] = FREE
    img[30:36, 40:46] = OCCUPIED
    return img


def _save(folder: Path, img: np.ndarray, resolution: float = 0.05,
          origin: tuple[float, float, float] = (-2.0, -1.0, 0.0), name: str = "map",
          extra: str = "") -> Path:
    """Write ``img`` as map_saver does: NAME.pgm (P5) and NAME.yaml."""
    rows, cols = img.shape
    header = (f"P5\n# CREATOR: map_saver.cpp {resolution:.3f} m/pix\n{cols} {rows}\n255\n")
    (folder / f"{name}.pgm").write_bytes(header.encode() + img.tobytes())
    (folder / f"{name}.yaml").write_text(
        f"image: {name}.pgm\nresolution: {resolution:f}\n"
        f"origin: [{origin[0]:f}, {origin[1]:f}, {origin[2]:f}]\nnegate: 0\n"
        f"occupied_thresh: 0.65\nfree_thresh: 0.196\n{extra}\n")
    return folder / f"{name}.yaml"


def test_a_map_saver_map_loads_as_walls_with_a_room_inside(tmp_path: Path) -> None:
    plan = load_map(_save(tmp_path, _room()))
    geom = plan.geom
    # Two pieces: the walls (a ring: a polygon with the room as its hole) and the pillar.
    polys = sorted(shapely.get_parts(geom), key=lambda g: g.area)
    assert [len(p.interiors) for p in polys] == [0, 1]
    res = 0.05
    assert polys[0].area == pytest.approx(36 * res * res)
    assert polys[1].area == pytest.approx((60 * 80 - 56 * 76) * res * res)
    # Column c, row r spans x = -2 + c res, y = -1 + (rows - 1 - r) res: the pillar
    # (rows 30-35, columns 40-45) spans x in [0, 0.3], y in [1.2, 1.5].
    assert polys[0].bounds == pytest.approx((0.0, 1.2, 0.3, 1.5))


def test_a_ray_in_an_imported_map_meets_the_wall_where_the_cells_are(tmp_path: Path) -> None:
    (tmp_path / "room.world.yaml").write_text(
        "name: room\nmap: map.yaml\nstart: {x: 1.0, y: 0.0, theta: 0}\nrobot: ideal\n")
    _save(tmp_path, _room())
    world = load_world(str(tmp_path / "room.world.yaml"))
    assert isinstance(world.obstacles[-1], FloorPlan)
    # The room's inner east face is at column 88: x = -2 + 88 * 0.05 = 2.4 m.
    hits = world.cast((1.0, 0.0), [0.0, math.pi / 2, math.pi, -math.pi / 2])
    assert hits.ranges[0] == pytest.approx(1.4, abs=1e-9)
    # North: the top of row 12, y = -1 + (80 - 12) * 0.05 = 2.4; south: the bottom of
    # row 67, the last free one, y = -1 + (80 - 1 - 67) * 0.05 = -0.4.
    assert hits.ranges[1] == pytest.approx(2.4, abs=1e-9)
    assert hits.ranges[3] == pytest.approx(0.4, abs=1e-9)
    # West: inner face at column 12, x = -1.4.
    assert hits.ranges[2] == pytest.approx(2.4, abs=1e-9)
    assert world.clearance((1.0, 0.0)) == pytest.approx(0.4, abs=1e-9)


def test_the_faces_are_the_polygons_rings_with_the_solid_on_the_right() -> None:
    occupied = np.zeros((30, 30), dtype=bool)
    occupied[2:28, 2:28] = True
    occupied[8:20, 8:20] = False             # a hole
    occupied[12:15, 12:15] = True            # an island in the hole
    geom = outline(occupied, 0.1, (0.0, 0.0, 0.0), 0.0)
    ours, ref = FloorPlan(geom).parts(), polygon_parts(geom)

    def faces(p: Parts) -> set[tuple[float, ...]]:
        return {tuple(r) for r in np.hstack([p.seg_start, p.seg_end]).round(9).tolist()}

    assert faces(ours) == faces(ref) and len(faces(ours)) == 12


def test_the_outline_is_simplified_within_its_tolerance() -> None:
    yy, xx = np.mgrid[0:200, 0:200]
    disc = (xx - 100) ** 2 + (yy - 100) ** 2 <= 80 ** 2       # a staircase circle
    exact = outline(disc, 0.05, (0.0, 0.0, 0.0), 0.0)
    coarse = outline(disc, 0.05, (0.0, 0.0, 0.0), 0.1)
    assert shapely.get_num_coordinates(coarse) < shapely.get_num_coordinates(exact) / 4
    # Every point of either outline lies within the tolerance of the other.
    assert exact.hausdorff_distance(coarse) <= 0.1 + 1e-9


def test_negate_thresholds_and_modes_read_the_shades_as_map_server_does() -> None:
    from mdle.sim.maps import MapInfo

    shades = np.array([[0, 60, 100, 200, 254, 255]], dtype=np.float32)
    info = MapInfo("x.pgm", 0.05, (0.0, 0.0, 0.0))
    # p = (255 - c) / 255 > 0.65: c < 89.25.
    assert occupied_cells(shades, info).tolist() == [[True, True, False, False, False, False]]
    neg = MapInfo("x.pgm", 0.05, (0.0, 0.0, 0.0), negate=True)
    assert occupied_cells(shades, neg).tolist() == [[False, False, False, True, True, True]]
    raw = MapInfo("x.pgm", 0.05, (0.0, 0.0, 0.0), mode="raw")
    assert occupied_cells(shades, raw).tolist() == [[False, False, True, False, False, False]]


def test_png_16_bit_and_text_pgm_images_read_the_same(tmp_path: Path) -> None:
    from PIL import Image

    img = _room(20, 24)
    Image.fromarray(img).save(tmp_path / "a.png")
    rgb = np.repeat(img[:, :, None], 3, axis=2)
    Image.fromarray(rgb).save(tmp_path / "b.png")
    wide = img.astype(">u2") * 257
    (tmp_path / "c.pgm").write_bytes(b"P5 24 20 65535\n" + wide.tobytes())
    text = "P2\n# a comment\n24 20\n255\n" + "\n".join(" ".join(map(str, r)) for r in img)
    (tmp_path / "d.pgm").write_text(text)
    for name in ("a.png", "b.png", "c.pgm", "d.pgm"):
        assert np.array_equal(read_image(tmp_path / name), img.astype(np.float32)), name


def test_the_origins_yaw_turns_the_map_about_its_corner(tmp_path: Path) -> None:
    straight = load_map(_save(tmp_path, _room(), origin=(1.0, 2.0, 0.0), name="a")).geom
    turned = load_map(_save(tmp_path, _room(), origin=(1.0, 2.0, math.pi / 2), name="b")).geom
    from shapely import affinity

    expect = affinity.rotate(straight, 1.570796, origin=(1.0, 2.0), use_radians=True)
    assert turned.symmetric_difference(expect).area < 1e-9


@pytest.mark.parametrize("yaml, problem", [
    ("resolution: 0.05\norigin: [0, 0, 0]\n", "missing key `image`"),
    ("image: map.pgm\nresolution: 0.05\norigin: [0, 0]\n", r"origin: expected \[x, y, yaw\]"),
    ("image: map.pgm\nresolution: -1\norigin: [0, 0, 0]\n", "resolution: must be positive"),
    ("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nmode: fuzzy\n",
     "unknown mode 'fuzzy'"),
    ("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 2\n",
     "negate: expected 0 or 1"),
    ("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 1.5\n",
     "between 0 and 1"),
    ("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nfree_thresh: 0.9\n",
     "must not exceed occupied_thresh"),
    ("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\ncolour: red\n",
     "unknown key `colour`"),
])
def test_a_bad_map_yaml_is_refused_with_its_file_line_and_key(
        tmp_path: Path, yaml: str, problem: str) -> None:
    path = tmp_path / "map.yaml"
    path.write_text(yaml)
    with pytest.raises(WorldError, match=problem) as err:
        read_map_info(path)
    assert str(path) in str(err.value)


def test_a_bad_image_is_refused_with_its_name(tmp_path: Path) -> None:
    path = _save(tmp_path, _room())
    pgm = tmp_path / "map.pgm"
    pgm.write_bytes(pgm.read_bytes()[:500])
    with pytest.raises(WorldError, match="holds .* bytes of the 8000 they need"):
        load_map(path)
    pgm.write_bytes(b"P5 garbage")
    with pytest.raises(WorldError, match="not a PGM image"):
        load_map(path)
    pgm.write_bytes(b"GIF89a not really")
    with pytest.raises(WorldError, match="not an image mdle can read"):
        load_map(path)
    pgm.unlink()
    with pytest.raises(WorldError, match="cannot read map image .*map.pgm: no such file"):
        load_map(path)
    _save(tmp_path, np.full((10, 10), FREE, dtype=np.uint8))
    with pytest.raises(WorldError, match="no occupied cell"):
        load_map(path)


def test_a_world_files_bad_map_names_the_world_file_and_the_key(tmp_path: Path) -> None:
    (tmp_path / "w.yaml").write_text("name: w\nmap: nowhere.yaml\n")
    with pytest.raises(WorldError, match=r"w.yaml:2:\d+: error: map: cannot load the map "
                                         r"nowhere.yaml: cannot read map file .*nowhere.yaml: "
                                         "no such file"):
        load_world(str(tmp_path / "w.yaml"))
    (tmp_path / "v.yaml").write_text("name: v\nmap: {file: m.yaml, tolerance: -1}\n")
    with pytest.raises(WorldError, match="map.tolerance: must not be negative"):
        load_world(str(tmp_path / "v.yaml"))


def test_a_building_map_loads_as_one_obstacle_that_casts(tmp_path: Path) -> None:
    # 1000 x 1000 cells (a 50 m building at 5 cm): rooms of 4 m with doors, and pillars.
    img = np.full((1000, 1000), FREE, dtype=np.uint8)
    for k in range(0, 1000, 80):
        img[k:k + 3, :] = OCCUPIED
        img[:, k:k + 3] = OCCUPIED
        img[k:k + 3, k + 20:k + 38] = FREE
    img[40::80, 40::80] = OCCUPIED
    plan = load_map(_save(tmp_path, img))
    world = World("building", (plan,))
    assert world.parts.n_segments > 400 and len(world.obstacles) == 1
    assert np.isfinite(world.cast((2.0, 2.0), [0.3]).ranges[0])
    # A ladar's scans there: through the faces' grid, the plain cast's numbers.
    rel = np.linspace(0.0, math.pi, 181)
    walk = world.caster.fan(rel, 8.0, None, True)
    plain = world.caster.fan(rel, 8.0, None, False)
    rng = np.random.default_rng(2)
    for _ in range(30):
        x, y, first = rng.uniform(0.5, 49.5), rng.uniform(0.5, 49.5), rng.uniform(-4, 4)
        (r1, h1), (r2, h2) = walk.cast(x, y, first), plain.cast(x, y, first)
        assert np.array_equal(r1, r2) and np.array_equal(h1, h2)


def test_mdle_worlds_import_writes_a_world_a_plan_runs_in(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    from mdle.cli import main
    from mdle.lang import load_text
    from mdle.runtime import run_named
    from mdle.sim.backend import SimBackend

    source = _save(tmp_path, _room())
    monkeypatch.chdir(tmp_path)
    assert main(["worlds", "import", str(source), "--tolerance", "0"]) == 0
    out = capsys.readouterr().out
    assert "map.world.yaml: 2 obstacles" in out
    world = load_world(str(tmp_path / "map.world.yaml"))
    # The start is the free point farthest from everything: inside the room.
    assert world.clearance((world.start_pose.x, world.start_pose.y)) > 1.0
    plan = load_text("atom go_ = (go(0.4 m/s), min_range(-30 deg, 30 deg) < 0.6 m, 20 s)\n"
                     "atom spin = (turn(60 deg/s), never, 1.5 s)\n"
                     "plan main = ((go_, spin)..., never, 40 s)\n")
    result = run_named(plan, "main", SimBackend(world, seed=1, robot="pioneer2dx"), rate=10)
    assert not result.collided
    assert result.min_clearance is not None and result.min_clearance > 0.0
    # It refuses to write over its source, and a bad tolerance, in words.
    assert main(["worlds", "import", str(source), "-o", str(source)]) == 1
    assert "would overwrite its source" in capsys.readouterr().err
    assert main(["worlds", "import", str(source), "--tolerance", "-1"]) == 1
    assert "--tolerance is a length" in capsys.readouterr().err


def test_the_shipped_floor_plan_was_imported_from_a_map() -> None:
    world = load_world("floorplan")
    assert "map_server" in world.description
    assert world.parts.n_segments > 150
    assert world.clearance((world.start_pose.x, world.start_pose.y),
                           world.robot.radius) > 0.3


def test_a_polygon_with_holes_reads_writes_and_casts() -> None:
    from mdle.sim.world_dump import world_to_yaml
    from mdle.sim.world_yaml import parse_world

    text = ("name: ring\nstart: {x: 1.5, y: 1.5, theta: 0}\nrobot: ideal\nobstacles:\n"
            "  - {type: polygon, points: [[0, 0], [4, 0], [4, 4], [0, 4]], "
            "holes: [[[1, 1], [3, 1], [3, 3], [1, 3]]]}\n")
    world = parse_world(text)
    assert world.cast((1.5, 1.5), [0.0, math.pi]).ranges.tolist() == [1.5, 0.5]
    again = parse_world(world_to_yaml(world))
    assert again.obstacles == world.obstacles
    with pytest.raises(WorldError, match=r"obstacles\[0\].holes: the polygon crosses itself, "
                                         "or its holes cross it"):
        parse_world(text.replace("[[[1, 1], [3, 1]", "[[[1, 1], [5, 1]"))
    with pytest.raises(WorldError, match=r"obstacles\[0\].holes\[0\]: a hole needs at least 3"):
        parse_world(text.replace("[[[1, 1], [3, 1], [3, 3], [1, 3]]]", "[[[1, 1], [3, 1]]]"))


def test_a_floor_plan_is_written_back_as_its_polygons(tmp_path: Path) -> None:
    from mdle.sim.world_dump import world_to_yaml
    from mdle.sim.world_yaml import parse_world

    (tmp_path / "w.yaml").write_text("name: w\nmap: map.yaml\nstart: {x: 1.0, y: 0.0}\n")
    _save(tmp_path, _room())
    world = load_world(str(tmp_path / "w.yaml"))
    again = parse_world(world_to_yaml(world))
    assert len(again.obstacles) == 2
    rays = np.linspace(-math.pi, math.pi, 91)
    assert np.allclose(again.cast((1.0, 0.0), rays).ranges, world.cast((1.0, 0.0), rays).ranges,
                       rtol=0, atol=1e-12)


@pytest.mark.parametrize("band", [1, 7, 64, 10_000])
def test_a_map_read_in_bands_is_the_map_read_at_once(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, band: int) -> None:
    # Large maps are read in bands of rows (a signal is acted on between them): any cut
    # gives the same shades, cells and outline as one pass over the whole image.
    from mdle.sim import maps
    from mdle.sim.maps import MapInfo

    rng = np.random.default_rng(band)
    img = _room(60, 50)
    img[rng.random(img.shape) < 0.05] = OCCUPIED
    img[0, :] = OCCUPIED  # a run on the first row and on the last column
    img[:, -1] = OCCUPIED
    wide = img.astype(">u2") * 3  # maxval 765: the shades are scaled band by band too
    (tmp_path / "w.pgm").write_bytes(b"P5 50 60 765\n" + wide.tobytes())
    _save(tmp_path, img)
    info = MapInfo("x.pgm", 0.05, (0.0, 0.0, 0.0))
    whole_shades = read_image(tmp_path / "map.pgm")
    whole_wide = read_image(tmp_path / "w.pgm")
    whole_cells = occupied_cells(whole_shades, info)
    whole = outline(whole_cells, 0.05, (1.0, 2.0, 0.0))
    monkeypatch.setattr(maps, "BAND_CELLS", band)
    assert np.array_equal(read_image(tmp_path / "map.pgm"), whole_shades)
    assert np.array_equal(read_image(tmp_path / "w.pgm"), whole_wide)
    assert np.array_equal(occupied_cells(whole_shades, info), whole_cells)
    raw = MapInfo("x.pgm", 0.05, (0.0, 0.0, 0.0), mode="raw")
    monkeypatch.setattr(maps, "BAND_CELLS", 1 << 20)
    raw_whole = occupied_cells(whole_shades / 2.55, raw)
    monkeypatch.setattr(maps, "BAND_CELLS", band)
    assert np.array_equal(occupied_cells(whole_shades / 2.55, raw), raw_whole)
    banded = outline(whole_cells, 0.05, (1.0, 2.0, 0.0))
    assert banded.equals(whole) and banded.area == whole.area > 0
