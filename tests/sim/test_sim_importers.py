"""IR-SIM worlds (sim/importers.py): shapes, states and units as IR-SIM reads them.

The worlds are written here in the format of IR-SIM's own examples: a `world` block
(width, height, offset), a `robot` with a `state`, and `obstacle` entries with a `shape`
(or a list of shapes) and a `state` (or a list of states), `number` objects each.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mdle.core.errors import WorldError
from mdle.sim.catalog import load_world
from mdle.sim.importers import LINE_THICKNESS, import_irsim, import_world
from mdle.sim.shapes import Circle, Polygon, Rectangle, Wall

WORLD = """\
world:
  height: 10  # the height of the world
  width: 12   # the width of the world
  step_time: 0.1
  sample_time: 0.1
  offset: [-1, -2]
  collision_mode: 'stop'

robot:
  - kinematics: {name: 'diff'}
    shape: {name: 'circle', radius: 0.2}
    state: [1, 1, 0.5]
    goal: [9, 9, 0]
    behavior: {name: 'dash'}

obstacle:
  - number: 3
    distribution: {name: 'manual'}
    shape:
      - {name: 'circle', radius: 1.0}
      - {name: 'rectangle', length: 1.5, width: 1.2}
    state:
      - [5, 5, 0]
      - [4, 1, 1.5707963267948966]
      - [8, 2, 0]

  - shape: {name: 'polygon', vertices: [[0, 0], [1, 0], [0.5, 1]]}
    state: [6, 7, 3.141592653589793]

  - shape: {name: 'linestring', vertices: [[5, 5], [4, 0], [1, 6]]}
    state: [0, 0, 0]
    unobstructed: True
"""


def test_an_irsim_world_becomes_the_same_shapes_in_the_same_places(tmp_path: Path) -> None:
    path = tmp_path / "irsim_world.yaml"
    path.write_text(WORLD)
    world = import_irsim(path)
    assert world.extent == (-1.0, -2.0, 11.0, 8.0)
    assert (world.start_pose.x, world.start_pose.y, world.start_pose.theta) == (1, 1, 0.5)
    kinds = [type(o) for o in world.obstacles]
    assert kinds == [Circle, Rectangle, Rectangle, Polygon, Wall]
    circle, rect, last = world.obstacles[:3]
    assert isinstance(circle, Circle) and circle.center == (5, 5) and circle.radius == 1.0
    # A rectangle's length lies along its body x, turned by its state's theta.
    assert isinstance(rect, Rectangle) and rect.size == (1.5, 1.2)
    x0, y0, x1, y1 = rect.geometry().bounds
    assert (x1 - x0, y1 - y0) == pytest.approx((1.2, 1.5))
    assert isinstance(last, Rectangle) and last.center == (8, 2)   # the last shape repeats
    poly = world.obstacles[3]
    assert isinstance(poly, Polygon)
    assert poly.points[1] == pytest.approx((5.0, 7.0))   # (1, 0) turned by pi from (6, 7)
    wall = world.obstacles[4]
    assert isinstance(wall, Wall) and wall.thickness == LINE_THICKNESS
    assert wall.points == ((5, 5), (4, 0), (1, 6))
    # The circle is hit where IR-SIM has it: from (7.5, 5) heading -x, 1.5 m to its edge.
    assert world.cast((7.5, 5.0), [math.pi]).ranges[0] == pytest.approx(1.5, abs=1e-9)


def test_mdle_worlds_import_reads_an_irsim_world(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli import main

    path = tmp_path / "irsim_world.yaml"
    path.write_text(WORLD.replace("state: [1, 1, 0.5]", "state: [1, -1, 0.5]"))
    out = tmp_path / "w.yaml"
    assert main(["worlds", "import", str(path), "-o", str(out)]) == 0
    assert "5 obstacles" in capsys.readouterr().out
    world = load_world(str(out))
    assert len(world.obstacles) == 5 and world.start_pose.y == -1


@pytest.mark.parametrize("entry, problem", [
    ("  - number: 4\n    distribution: {name: 'random'}\n    shape: {name: 'circle'}\n",
     r"obstacle\[0\].distribution: a 'random' distribution places the obstacles with "
     "IR-SIM's own random draws"),
    ("  - shape: {name: 'hexagon'}\n    state: [1, 1, 0]\n",
     r"obstacle\[0\].shape.name: an IR-SIM shape is one of circle, rectangle, polygon, "
     "linestring, got 'hexagon'"),
    ("  - state: [1, 1, 0]\n", r"obstacle\[0\]: missing key `shape`"),
    ("  - shape: {name: 'polygon'}\n", r"obstacle\[0\].shape: missing key `vertices`"),
    ("  - shape: {name: 'circle', radius: -1}\n", r"obstacle\[0\].shape.radius: must be positive"),
    ("  - shape: {name: 'polygon', vertices: [[0, 0], [1, 1], [1, 0], [0, 1]]}\n",
     "the polygon crosses itself"),
    ("  - shape: {name: 'circle'}\n    state: [1]\n",
     r"obstacle\[0\].state: expected a state \[x, y, theta\]"),
])
def test_what_mdle_cannot_import_is_named(tmp_path: Path, entry: str, problem: str) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("world: {width: 10, height: 10}\nobstacle:\n" + entry)
    with pytest.raises(WorldError, match=problem) as err:
        import_irsim(path)
    assert "bad.yaml:" in str(err.value)


def test_an_irsim_image_map_is_refused_in_words(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text("world:\n  width: 10\n  height: 10\n  obstacle_map: 'cave.png'\n")
    with pytest.raises(WorldError, match=r"m.yaml:4:\d+: error: world.obstacle_map: an "
                                         "IR-SIM image map is not imported"):
        import_irsim(path)


def test_a_file_of_neither_kind_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "x.yaml"
    path.write_text("name: a world of mdle's own\nobstacles: []\n")
    with pytest.raises(WorldError, match="neither a map_server map .* nor an IR-SIM world"):
        import_world(path)


def test_a_circle_offset_in_its_body_frame_turns_with_its_state(tmp_path: Path) -> None:
    path = tmp_path / "c.yaml"
    path.write_text("obstacle:\n  - shape: {name: 'circle', radius: 0.5, center: [1, 0]}\n"
                    f"    state: [2, 3, {math.pi / 2}]\n")
    (c,) = import_irsim(path).obstacles
    assert isinstance(c, Circle) and c.center == pytest.approx((2.0, 4.0))
