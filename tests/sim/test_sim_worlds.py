"""Every reference world loads; malformed worlds give the documented messages."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mdle import sim
from mdle.core.errors import WorldError
from mdle.sim.shapes import Circle, Ellipse
from mdle.sim.world_yaml import parse_world

REFERENCE = {"arrow", "cabinet", "corridor", "default", "ellipse", "empty", "garden", "hexagon",
             "office", "square", "trashcan", "u-shape", "wall"}


def test_reference_world_names() -> None:
    assert REFERENCE <= set(sim.list_worlds())


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_every_reference_world_loads(name: str) -> None:
    world = sim.load_world(name)
    assert world.name == name
    assert world.description
    assert world.obstacles
    start = world.start_pose
    # The body starts clear of every obstacle, and a backend can be built and scans.
    assert world.clearance((start.x, start.y), world.robot.radius) > 0
    backend = sim.SimBackend(world)
    obs = backend.observe()
    assert obs.scan is not None and obs.scan.ranges.shape == (181,)
    assert obs.scan.valid.any()


@pytest.mark.parametrize("name", ["ellipse", "hexagon", "square", "u-shape", "arrow"])
def test_paper_shapes_start_on_a_collision_course(name: str) -> None:
    world = sim.load_world(name)
    s = world.start_pose
    assert (s.x, s.y) == (-9.0, 0.3) and s.theta == 0.0
    assert world.robot.name == "ideal"
    hits = world.cast((s.x, s.y), [s.theta])
    assert hits.hit[0]                     # straight ahead runs into the obstacle


def test_paper_shape_dimensions() -> None:
    ell = sim.load_world("ellipse").obstacles[0]
    assert isinstance(ell, Ellipse)
    assert ell.axes == (4.0, 2.0)
    u = sim.load_world("u-shape").geometry
    x0, y0, x1, y1 = u.bounds
    assert (x1 - x0, y1 - y0) == (5.0, 4.0)
    assert math.isclose(u.area, 5 * 4 - 2 * 2.5)
    hexagon = sim.load_world("hexagon").geometry
    assert 4.5 < hexagon.bounds[2] - hexagon.bounds[0] < 5.5


def test_corridor_has_four_recessed_doors() -> None:
    world = sim.load_world("corridor")
    doors = [o for o in world.obstacles if o.name.startswith("door")]
    assert len(doors) == 4
    # A ray straight down (to the right wall) at a door sees 5 cm further than at the wall.
    wall = world.cast((1.0, 0.0), [-math.pi / 2]).ranges[0]
    door = world.cast((3.45, 0.0), [-math.pi / 2]).ranges[0]
    assert math.isclose(door - wall, 0.05, abs_tol=1e-12)


def test_garden_legs_make_a_hump() -> None:
    world = sim.load_world("garden")
    names = {o.name for o in world.obstacles}
    assert {"left leg", "right leg", "garden wall"} <= names


def test_load_world_by_path(tmp_path: Path) -> None:
    p = tmp_path / "mine.yaml"
    p.write_text("obstacles:\n  - {type: circle, center: [3, 0], radius: 1}\n")
    world = sim.load_world(p)
    assert world.name == "mine" and world.source == str(p)
    circle = sim.load_world(str(p)).obstacles[0]
    assert isinstance(circle, Circle) and circle.radius == 1.0


def test_numbers_written_without_a_dot_are_numbers() -> None:
    # YAML 1.1 reads 1e-3 as text; a world file means the number.
    w = parse_world("start: [1e1, -2E-1, 0]\n")
    assert (w.start_pose.x, w.start_pose.y) == (10.0, -0.2)


def test_units_are_metres_and_degrees() -> None:
    w = parse_world("start: [1, 2, 90]\nrobot: {profile: ideal, max_turn_rate: 90}\n"
                    "ladar: {fov: 90, beams: 91}\n"
                    "obstacles:\n  - {type: rectangle, center: [5, 0], size: [1, 2], angle: 45}\n")
    assert math.isclose(w.start_pose.theta, math.pi / 2)
    assert math.isclose(w.robot.max_turn_rate, math.pi / 2)
    assert math.isclose(w.ladar.fov, math.pi / 2) and w.ladar.beams == 91
    assert math.isclose(w.obstacles[0].angle, math.pi / 4)


BAD = [
    ('obstacles:\n  - {type: [1]}\n',
     ('bad.yaml:2:12: error: obstacles[0].type: unknown obstacle type [1]; one of: polygon, '
      'rectangle, circle, ellipse, wall, arc, curve')),
    ('? [1, 2]\n: 3\n', 'bad.yaml:1:3: error: keys must be names, got [1, 2]'),
    ('obstacles:\n  - {type: curve, points: [[0, 0], [10, 0]], thickness: 1, spacing: 1e-4}\n',
     'bad.yaml:2:69: error: obstacles[0].spacing: too fine for a curve 10 m long'),
    ('obstacles:\n  - {type: circle, center: [5, 0], radius: 1e-9}\n',
     'bad.yaml:2:44: error: obstacles[0].radius: must be between 0.0001 m and 100000 m, got 1e-9'),
    ('obstacles:\n  - {type: circle, center: [3, 0]}\n',
     ('bad.yaml:2:5: error: obstacles[0]: missing key `radius` (a circle needs center, '
      'radius)')),
    ('obstacles:\n  - type: polygon\n    points: [[0, 0], [1, 0]]\n',
     'bad.yaml:3:13: error: obstacles[0].points: a polygon needs at least 3 points, got 2'),
    ('obstacles:\n  - {type: circel, center: [0, 0], radius: 1}\n',
     ("bad.yaml:2:12: error: obstacles[0].type: unknown obstacle type 'circel' (did you "
      'mean `circle`?); one of: polygon, rectangle, circle, ellipse, wall, arc, curve')),
    ('obstacles:\n  - {type: circle, center: [0, 0], radius: -1}\n',
     'bad.yaml:2:44: error: obstacles[0].radius: must be positive, got -1'),
    ('obstacles:\n  - {type: circle, center: [0, 0], radius: big}\n',
     "bad.yaml:2:44: error: obstacles[0].radius: expected a number, got 'big'"),
    ('obstacle: []\n',
     'bad.yaml:1:1: error: obstacle: unknown key `obstacle` (did you mean `obstacles`?)'),
    ('robot: pioner\n',
     'bad.yaml:1:8: error: robot: unknown robot profile `pioner` (did you mean `pioneer2dx`?)'),
    ('ladar: {noise: pink}\n',
     ("bad.yaml:1:16: error: ladar.noise: unknown noise model 'pink'; one of: relative, "
      'absolute, none')),
    ('obstacles: [\n',
     ("bad.yaml:2:1: error: not valid YAML: expected the node content, but found '<stream "
      "end>'")),
    ('- 1\n- 2\n',
     'bad.yaml:1:1: error: expected a mapping (a world), got a list of 2'),
    ('obstacles:\n  - {type: circle, center: [0, 0], radius: 1}\n',
     ('bad.yaml:1:1: error: start: the robot (pioneer2dx, radius 0.25 m) at (0, 0) '
      'overlaps obstacles[0] (circle)')),
    ('obstacles:\n  - {type: polygon, points: [[0, 0], [1, 1], [1, 0], [0, 1]]}\n',
     'bad.yaml:2:29: error: obstacles[0].points: the polygon crosses itself or has no area'),
    ('seed: 1\nseed: 2\n',
     'bad.yaml:2:1: error: seed: key given twice'),
    ('obstacles:\n  - {type: circle, centre: [0, 0], radius: 1}\n',
     ('bad.yaml:2:20: error: obstacles[0].centre: unknown key `centre` (did you mean '
      '`center`?)')),
    (('start: {x: 0, y: 0, theta: 0}\nobstacles:\n  - {type: ellipse, center: [5, 0], axes: '
      '[1]}\n'),
     ('bad.yaml:3:43: error: obstacles[0].axes: expected semi-axes [a, b] in metres, got a '
      'list of 1')),
    ('obstacles:\n  - {type: wall, points: [[0, 0], [1, 0]], thickness: 0}\n',
     'bad.yaml:2:55: error: obstacles[0].thickness: must be positive, got 0'),
    ('obstacles:\n  - {type: curve, points: [[5, 0], [6, 1]]}\n',
     ('bad.yaml:2:5: error: obstacles[0]: missing key `thickness` (an open curve is a wall '
      'and needs one)')),
    ('seed: -3\n',
     'bad.yaml:1:7: error: seed: must be at least 0, got -3'),
    ('start: [0, 0]\n',
     'bad.yaml:1:8: error: start: expected [x, y, theta] (m, m, deg), got a list of 2'),
    ('obstacles:\n  - {type: arc, center: [5, 0], radius: 1, start: 0, end: 0}\n',
     'bad.yaml:2:59: error: obstacles[0].end: must differ from `start`'),
    # issue 12.17: a start off the map; a unit written where it is implied
    ('extent: [0, 0, 10, 10]\nstart: {x: 12, y: 3, theta: 0}\n',
     ("bad.yaml:2:8: error: start: the start (12, 3) lies outside the world's extent "
      "[0, 0, 10, 10] (xmin, ymin, xmax, ymax): the robot would start off the map")),
    ('extent: [1, 1, 10, 10]\n',
     "bad.yaml:1:9: error: extent: the start (0, 0; no `start` is given) lies outside"),
    ('obstacles:\n  - {type: rectangle, center: [0, 3], size: [1.6 m, 2]}\n',
     ("bad.yaml:2:46: error: obstacles[0].size[0]: expected a number, got '1.6 m': metres "
      "are implied, not written; write `1.6`")),
    ('obstacles:\n  - {type: circle, center: [0, 3], radius: 40 cm}\n',
     ("bad.yaml:2:44: error: obstacles[0].radius: expected a number, got '40 cm': metres are "
      "implied, not written; write `0.4`")),
    ('start: {x: 0, y: 0, theta: 1.5 s}\n',
     ("bad.yaml:1:28: error: start.theta: expected a number, got '1.5 s': this takes a number "
      "of degrees, with no unit written")),
    ('robot: {profile: ideal, max_speed: 1 m/s}\n',
     ("bad.yaml:1:36: error: robot.max_speed: expected a number, got '1 m/s': metres per "
      "second are implied, not written; write `1`")),
]


@pytest.mark.parametrize(("text", "message"), BAD)
def test_malformed_worlds_give_the_documented_message(text: str, message: str) -> None:
    with pytest.raises(WorldError) as info:
        parse_world(text, file="bad.yaml")
    assert str(info.value).startswith(message)
    d = info.value.diagnostics[0]
    assert d.span is not None and d.span.file == "bad.yaml"
    assert info.value.sources["bad.yaml"] == text


def test_unknown_world_name_suggests() -> None:
    with pytest.raises(WorldError, match=r"unknown world `corridr` \(did you mean `corridor`\?\)"):
        sim.load_world("corridr")


def test_missing_world_file() -> None:
    with pytest.raises(WorldError, match="world file not found: nowhere/x.yaml"):
        sim.load_world("nowhere/x.yaml")


def test_world_is_immutable() -> None:
    world = sim.load_world("square")
    with pytest.raises(AttributeError):
        world.name = "other"  # type: ignore[misc]  # writing a frozen field is the point


def test_ladar_must_sit_on_the_body() -> None:
    with pytest.raises(WorldError, match=r"robot.ladar_mount: the ladar at \(0.5, 0\) m must sit "
                                         r"within the body \(radius 0.25 m\)"):
        parse_world("robot: {profile: pioneer2dx, ladar_mount: [0.5, 0, 0]}\n")
    with pytest.raises(WorldError, match=r"robot.radius: the ladar at \(0.017, 0.008\) m"):
        parse_world("robot: {profile: pioneer2dx, radius: 0}\n")


def test_a_robot_name_too_long_for_a_file_name_is_an_unknown_profile() -> None:
    with pytest.raises(WorldError, match="unknown robot profile"):
        parse_world("robot: " + "a" * 5000 + "\n", file="bad.yaml")
