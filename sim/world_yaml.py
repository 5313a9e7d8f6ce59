r"""World files: YAML (metres and degrees) to a validated :class:`sim.world.World`.

Loading validates everything and reports the first problem as a
:class:`mdle.core.errors.WorldError` naming the file, the line and column, and the key path
(``obstacles[3].points``) with what was wrong. Only ``yaml`` safe loading is used.
The format is documented in ``docs/worlds.md``. The YAML reading and value checks are
in :mod:`sim.yaml_doc` and :mod:`sim.yaml_values`, the sections in :mod:`sim.world_obstacles`
and :mod:`sim.world_robots`; this module builds the world from them.

>>> w = parse_world('''
... name: demo
... start: {x: 0, y: 0, theta: 90}
... obstacles:
...   - {type: circle, center: [3, 0], radius: 1}
... ''')
>>> w.name, round(w.start_pose.theta, 6), type(w.obstacles[0]).__name__
('demo', 1.570796, 'Circle')
>>> try:
...     parse_world("obstacles:\n  - {type: circle, center: [3, 0]}\n", file="bad.yaml")
... except WorldError as err:
...     print(err)
bad.yaml:2:5: error: obstacles[0]: missing key `radius` (a circle needs center, radius)
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from pathlib import Path
from typing import Any

from mdle.core.collector import collector_paused, release_in_slices
from mdle.core.errors import WorldError
from mdle.core.pose import Pose
from mdle.sim.world_obstacles import OBSTACLE_TYPES, _check_budget, _obstacle
from mdle.sim.world_robots import _ladar, _robot, _start
from mdle.sim.yaml_doc import MAX_YAML_DEPTH, _Doc, _yaml_value
from mdle.sim.yaml_values import _integer, _mapping, _number, _show, _string

# OBSTACLE_TYPES and MAX_YAML_DEPTH are re-exported: tests and docs read them from here.
__all__ = ["OBSTACLE_TYPES", "MAX_SEED", "MAX_YAML_DEPTH",
           "parse_world", "parse_world_robot", "read_world", "read_world_robot"]

_TOP_KEYS = ("name", "description", "seed", "start", "robot", "ladar", "extent", "obstacles",
             "robots", "map")
_TEAM_ROBOT_KEYS = ("name", "robot", "ladar", "start")
_ROBOT_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: Largest seed (the simulator's generator takes 64-bit seeds).
MAX_SEED = 2 ** 64 - 1


@collector_paused()  # a world of 200,000 obstacles: no collector pass over them
def parse_world(text: str, file: str = "<string>", default_name: str = "world") -> Any:
    """Parse and validate world YAML text into a :class:`sim.world.World`.

    Raises
    ------
    WorldError
        With the file, line, column, key path and problem of the first error found.
    """
    from mdle.sim.ladar import LMS200
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile
    from mdle.sim.world import World

    doc = _Doc(file, text)
    data = _yaml_value(doc)
    if data is None:
        data = {}
    top = _mapping(doc, "", data, _TOP_KEYS, "a world")
    name = _string(doc, "name", top["name"]) if "name" in top else default_name
    description = _string(doc, "description", top.get("description", ""))
    seed = _integer(doc, "seed", top["seed"], maximum=MAX_SEED) if "seed" in top else 0
    start = _start(doc, "start", top["start"]) if "start" in top else Pose()
    robot = (_robot(doc, "robot", top["robot"]) if "robot" in top
             else robot_profile(DEFAULT_ROBOT))
    ladar = _ladar(doc, "ladar", top["ladar"]) if "ladar" in top else LMS200
    extent = None
    if "extent" in top:
        e = top["extent"]
        if not isinstance(e, list) or len(e) != 4:
            raise doc.fail("extent", f"expected [xmin, ymin, xmax, ymax] in metres, got {_show(e)}")
        ex = tuple(_number(doc, f"extent[{i}]", e[i], coordinate=True) for i in range(4))
        if ex[2] <= ex[0] or ex[3] <= ex[1]:
            raise doc.fail("extent", "xmax and ymax must exceed xmin and ymin")
        extent = (ex[0], ex[1], ex[2], ex[3])
        if not (ex[0] <= start.x <= ex[2] and ex[1] <= start.y <= ex[3]):
            raise doc.fail("start" if "start" in top else "extent",
                           f"the start ({start.x:g}, {start.y:g}"
                           + ("" if "start" in top else "; no `start` is given")
                           + ") lies outside the world's "
                           f"extent [{ex[0]:g}, {ex[1]:g}, {ex[2]:g}, {ex[3]:g}] (xmin, ymin, "
                           "xmax, ymax): the robot would start off the map")
    obs_raw = top.get("obstacles", [])
    if obs_raw is None:
        obs_raw = []
    if not isinstance(obs_raw, list):
        raise doc.fail("obstacles", f"expected a list of obstacles, got {_show(obs_raw)}")
    _check_budget(doc, obs_raw)   # before any obstacle is built: see docs/limits.md
    obstacles = tuple(_obstacle(doc, f"obstacles[{i}]", o) for i, o in enumerate(obs_raw))
    if "map" in top:   # after the listed obstacles, which keep their indices
        obstacles += (_map(doc, top["map"]),)
    world = World(name=name, obstacles=obstacles, start_pose=start, seed=seed, robot=robot,
                  ladar=ladar, description=description,
                  source=None if file.startswith("<") else file, extent=extent)
    if "start" in top or "robots" not in top:  # a team's own start: only if given
        _check_start(doc, "start", world, robot, start, "the robot")
    if "robots" in top:
        team = _team(doc, top["robots"], robot, ladar)
        world = dataclasses.replace(world, robots=team)
        for i, r in enumerate(team):
            _check_start(doc, f"robots[{i}].start", world, r.profile, r.start,
                         f"robot `{r.name}`")
    release_in_slices(obs_raw)  # what the world was built from, without a long free
    release_in_slices(doc.marks)
    return world


def _map(doc: _Doc, v: Any) -> Any:
    """Read ``map:``, a ``map_server`` map (its YAML file) as one floor plan obstacle."""
    from mdle.sim.maps import load_map

    m = {"file": v} if isinstance(v, str) else _mapping(doc, "map", v, ("file", "tolerance"),
                                                          "a map: file and tolerance")
    path = "map" if isinstance(v, str) else "map.file"
    if "file" not in m:
        raise doc.fail("map", "missing key `file` (the map_server YAML file)")
    file = _string(doc, path, m["file"])
    tol = _number(doc, "map.tolerance", m["tolerance"], nonneg=True) if "tolerance" in m else None
    where = Path(doc.file).parent if not doc.file.startswith("<") else Path()
    full = Path(file) if Path(file).is_absolute() else where / file
    try:
        return load_map(full, tol)
    except WorldError as err:
        why = "; ".join(d.message for d in err.diagnostics)
        raise doc.fail(path, f"cannot load the map {file}: {why}") from None


def _check_start(doc: _Doc, path: str, world: Any, robot: Any, start: Pose, who: str) -> None:
    """Refuse a start where the robot's body overlaps or touches an obstacle."""
    from mdle.sim.collision import CONTACT

    if not world.obstacles:
        return
    clearance = world.clearance((start.x, start.y), robot.radius)
    if clearance <= CONTACT:  # touching counts: the simulator would stall it at t = 0
        near = int(world.nearest_boundary((start.x, start.y)).obstacle)
        what = _describe(world.obstacles[near], near)
        how = "overlaps" if clearance < 0 else "touches"
        raise doc.fail(path, f"{who} ({robot.name}, radius {robot.radius} m) at "
                       f"({start.x:g}, {start.y:g}) {how} {what}")


def _team(doc: _Doc, v: Any, robot: Any, ladar: Any) -> tuple[Any, ...]:
    """Read ``robots:``, the robots of a team: names unique, starts apart."""
    from mdle.sim.world import RobotPlace

    if not isinstance(v, list) or not v:
        raise doc.fail("robots", f"expected a list of robots (name, start, and optionally "
                       f"robot and ladar), got {_show(v)}")
    out: list[Any] = []
    for i, raw in enumerate(v):
        path = f"robots[{i}]"
        m = _mapping(doc, path, raw, _TEAM_ROBOT_KEYS, "a robot: name, start, robot, ladar")
        for key in ("name", "start"):
            if key not in m:
                raise doc.fail(path, f"missing key `{key}` (a robot needs a name and a start)")
        name = _string(doc, f"{path}.name", m["name"])
        if not _ROBOT_NAME.fullmatch(name):
            raise doc.fail(f"{path}.name", f"a robot's name is a plan name (letters, digits, "
                           f"`_`, not starting with a digit), got {name!r}")
        if any(r.name == name for r in out):
            raise doc.fail(f"{path}.name", f"robot `{name}` is listed twice")
        place = RobotPlace(name,
                           _robot(doc, f"{path}.robot", m["robot"]) if "robot" in m else robot,
                           _ladar(doc, f"{path}.ladar", m["ladar"]) if "ladar" in m else ladar,
                           _start(doc, f"{path}.start", m["start"]))
        for other in out:
            gap = math.hypot(place.start.x - other.start.x, place.start.y - other.start.y)
            if gap < place.profile.radius + other.profile.radius:
                raise doc.fail(f"{path}.start", f"robot `{name}` at ({place.start.x:g}, "
                               f"{place.start.y:g}) overlaps robot `{other.name}` at "
                               f"({other.start.x:g}, {other.start.y:g}): centres {gap:.3g} m "
                               f"apart, radii {place.profile.radius:g} + "
                               f"{other.profile.radius:g} m")
        out.append(place)
    return tuple(out)


def _describe(shape: Any, index: int) -> str:
    label = f"obstacles[{index}] ({shape.kind}"
    return label + (f" `{shape.name}`)" if shape.name else ")")


def read_world(path: str | os.PathLike[str]) -> Any:
    """Read and validate a world file (WorldError if unreadable or invalid).

    Only a regular file of at most :data:`mdle.core.userfile.MAX_FILE_BYTES` is read.
    """
    return parse_world(_world_text(path), file=str(path), default_name=Path(path).stem)


def read_world_robot(path: str | os.PathLike[str]) -> Any:
    """Read only the robot of a world file (see :func:`parse_world_robot`)."""
    return parse_world_robot(_world_text(path), file=str(path))


def parse_world_robot(text: str, file: str = "<string>") -> Any:
    """Return the :class:`sim.robot.RobotProfile` a world's YAML names (the default if none).

    Only the YAML, the top-level keys and ``robot`` are checked: no obstacle is built,
    so this needs neither numpy nor shapely.

    Raises
    ------
    WorldError
        Not YAML, an unknown top-level key, or a bad ``robot`` entry.
    """
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile

    doc = _Doc(file, text)
    data = _yaml_value(doc, only=frozenset({"robot"}))
    top = _mapping(doc, "", {} if data is None else data, _TOP_KEYS, "a world")
    return _robot(doc, "robot", top["robot"]) if "robot" in top else robot_profile(DEFAULT_ROBOT)


def _world_text(path: str | os.PathLike[str]) -> str:
    from mdle.core.userfile import UserFileError, read_user_file

    p = Path(path)
    try:
        data = read_user_file(p)
    except UserFileError as err:
        if err.reason == "no such file":
            raise WorldError(f"world file not found: {p}") from None
        raise WorldError(f"cannot read world file {p}: {err.reason}") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise WorldError(f"cannot read world file {p}: not UTF-8 text (byte "
                         f"0x{data[err.start]:02x} at offset {err.start})") from None
