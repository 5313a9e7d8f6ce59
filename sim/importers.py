"""Worlds from other tools' files: ROS ``map_server`` maps and IR-SIM worlds.

:func:`import_world` tells the two apart by their keys (a map's YAML has ``image``, an
IR-SIM world ``world``, ``robot`` or ``obstacle``) and returns a
:class:`sim.world.World`, which :func:`sim.world_dump.world_to_yaml` writes as a world
file (``mdle worlds import``).

IR-SIM worlds (its YAML configuration, SI units and radians as there):

* ``world``: ``width``, ``height`` and ``offset`` give the world's extent;
* ``robot``: the first robot's ``state`` ``[x, y, theta]`` is the start;
* ``obstacle``: each entry's ``state`` (or list of states, one per object; the last is
  repeated up to ``number``; default ``[1, 1, 0]``, as there) places its ``shape`` (or
  list of shapes, the same way) in the world: ``circle`` (``radius``, ``center`` in the
  body frame), ``rectangle`` (``length`` along the body's x, ``width`` along its y,
  centred), ``polygon`` (``vertices`` in the body frame) and ``linestring``
  (``vertices``: a wall of :data:`LINE_THICKNESS`).
  A ``random`` or ``circle`` distribution places objects with IR-SIM's own random
  draws, which cannot be reproduced: such an entry is refused, naming it, and so is a
  ``world.obstacle_map`` (an image scaled by IR-SIM's settings).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

from mdle.core.errors import WorldError
from mdle.core.pose import Pose

__all__ = ["LINE_THICKNESS", "import_irsim", "import_map", "import_world"]

#: Metres: the thickness given to an IR-SIM ``linestring`` (a line with no width there).
LINE_THICKNESS = 0.05
_IRSIM_TOP = ("world", "robot", "obstacle", "gui")
_SHAPES = ("circle", "rectangle", "polygon", "linestring")


def import_world(path: str | os.PathLike[str], tolerance: float | None = None,
                 name: str | None = None) -> Any:
    """Read a ``map_server`` map or an IR-SIM world file as a :class:`sim.world.World`.

    ``tolerance``: the outline's simplification for a map (metres; default one cell).

    Raises
    ------
    WorldError
        Unreadable, neither kind, or a bad entry (file, line, key path).
    """
    from mdle.sim.world_yaml import _world_text
    from mdle.sim.yaml_doc import _Doc, _yaml_value

    doc = _Doc(str(path), _world_text(path))
    data = _yaml_value(doc)
    if isinstance(data, dict) and "image" in data:
        return import_map(path, tolerance, name)
    if isinstance(data, dict) and any(k in data for k in ("world", "robot", "obstacle")):
        return _irsim(doc, data, name or Path(path).stem)
    raise WorldError(f"{path}: neither a map_server map (with `image`, `resolution`, "
                     "`origin`) nor an IR-SIM world (with `world`, `robot`, `obstacle`)")


def import_map(path: str | os.PathLike[str], tolerance: float | None = None,
               name: str | None = None) -> Any:
    """Read a ``map_server`` map as a world: its outlines, its extent, a start in the open.

    The start is the free point farthest from every obstacle and from the map's edge
    (``shapely.polylabel``), facing +x.
    """
    import shapely
    from shapely import affinity
    from shapely.ops import polylabel

    from mdle.sim.maps import load_map, read_image, read_map_info
    from mdle.sim.shapes import Polygon
    from mdle.sim.world import World

    info = read_map_info(path)
    rows, cols = read_image(info.image).shape
    plan = load_map(path, tolerance)
    frame = shapely.box(0.0, 0.0, cols * info.resolution, rows * info.resolution)
    frame = affinity.rotate(affinity.translate(frame, info.origin[0], info.origin[1]),
                            info.origin[2], origin=(info.origin[0], info.origin[1]),
                            use_radians=True)
    start = polylabel(_largest_room(plan.geom, frame), tolerance=info.resolution)
    polygons = tuple(Polygon(tuple(map(tuple, g.exterior.coords[:-1])), "",
                             tuple(tuple(map(tuple, r.coords[:-1])) for r in g.interiors))
                     for g in shapely.get_parts(plan.geom))
    x0, y0, x1, y1 = frame.bounds
    stem = name or Path(path).stem
    return World(stem, polygons,
                 Pose(start.x, start.y, 0.0) if start is not None else Pose(),
                 description=f"{stem}: imported from the map_server map {Path(path).name} "
                             f"({cols} x {rows} cells of {info.resolution:g} m)",
                 extent=(x0, y0, x1, y1))


def _largest_room(geom: Any, frame: Any) -> Any:
    """Return the largest free region: the largest hole of the outlines less what stands in it.

    A map without holes (no closed room) has the map's box less the outlines instead.
    """
    import shapely

    polys = shapely.get_parts(geom)
    holes = [shapely.Polygon(r) for p in polys for r in p.interiors]
    if not holes:
        return max(shapely.get_parts(frame.difference(geom)), key=lambda g: g.area)
    room = max(holes, key=lambda g: g.area)
    inside = polys[shapely.contains(room, shapely.point_on_surface(polys))]
    free = room.difference(shapely.union_all(inside)) if inside.shape[0] else room
    return max(shapely.get_parts(free), key=lambda g: g.area)


def import_irsim(path: str | os.PathLike[str], name: str | None = None) -> Any:
    """Read an IR-SIM world file as a world (see the module's notes)."""
    from mdle.sim.world_yaml import _world_text
    from mdle.sim.yaml_doc import _Doc, _yaml_value

    doc = _Doc(str(path), _world_text(path))
    return _irsim(doc, _yaml_value(doc), name or Path(path).stem)


def _irsim(doc: Any, data: Any, name: str) -> Any:
    from mdle.sim.world import World
    from mdle.sim.yaml_values import _mapping, _number, _show

    top = _mapping(doc, "", {} if data is None else data, _IRSIM_TOP, "an IR-SIM world")
    world = top.get("world") or {}
    if not isinstance(world, dict):
        raise doc.fail("world", f"expected the world's settings (width, height, offset), "
                       f"got {_show(world)}")
    if "obstacle_map" in world:
        raise doc.fail("world.obstacle_map", "an IR-SIM image map is not imported (its "
                       "scale comes from IR-SIM's own settings): save it as a map_server map "
                       "(an image and its YAML) and import that, or remove the key")
    extent = None
    if "width" in world or "height" in world:
        w = _number(doc, "world.width", world.get("width", 10), size=True)
        h = _number(doc, "world.height", world.get("height", 10), size=True)
        off = world.get("offset", [0, 0])
        if not isinstance(off, list) or len(off) != 2:
            raise doc.fail("world.offset", f"expected [x, y], got {_show(off)}")
        ox, oy = (_number(doc, f"world.offset[{i}]", off[i], coordinate=True) for i in (0, 1))
        extent = (ox, oy, ox + w, oy + h)
    start = Pose()
    robots = top.get("robot")
    if robots is not None:
        first = robots[0] if isinstance(robots, list) and robots else robots
        path = "robot[0]" if isinstance(robots, list) else "robot"
        if isinstance(first, dict) and "state" in first:
            x, y, th = _state(doc, f"{path}.state", first["state"])
            start = Pose(x, y, th)
    raw = top.get("obstacle") or []
    if isinstance(raw, dict):
        raw = [raw]
    if not isinstance(raw, list):
        raise doc.fail("obstacle", f"expected a list of obstacles, got {_show(raw)}")
    obstacles: list[Any] = []
    for i, entry in enumerate(raw):
        obstacles += _irsim_entry(doc, f"obstacle[{i}]", entry)
    return World(name, tuple(obstacles), start,
                 description=f"{name}: imported from an IR-SIM world", extent=extent)


def _state(doc: Any, path: str, v: Any) -> tuple[float, float, float]:
    from mdle.sim.yaml_values import _number, _show

    if not isinstance(v, list) or len(v) < 2 or isinstance(v[0], list):
        raise doc.fail(path, f"expected a state [x, y, theta], got {_show(v)}")
    x = _number(doc, f"{path}[0]", v[0], coordinate=True)
    y = _number(doc, f"{path}[1]", v[1], coordinate=True)
    th = _number(doc, f"{path}[2]", v[2], unit="rad") if len(v) > 2 else 0.0
    return x, y, th


def _irsim_entry(doc: Any, path: str, entry: Any) -> list[Any]:
    """One IR-SIM obstacle entry: ``number`` objects, each a state and a shape."""
    from mdle.sim.yaml_values import _integer, _show

    if not isinstance(entry, dict):
        raise doc.fail(path, f"expected an obstacle (shape, state, number), got {_show(entry)}")
    number = _integer(doc, f"{path}.number", entry.get("number", 1), minimum=1,
                      maximum=1_000_000)
    dist = entry.get("distribution") or {"name": "manual"}
    kind = dist.get("name", "manual") if isinstance(dist, dict) else dist
    if kind != "manual":
        raise doc.fail(f"{path}.distribution", f"a {kind!r} distribution places the "
                       "obstacles with IR-SIM's own random draws, which mdle cannot "
                       "reproduce: give each obstacle's `state` (distribution manual)")
    states = entry.get("state", [1, 1, 0])      # IR-SIM's default state
    state_list = states if isinstance(states, list) and states and isinstance(
        states[0], list) else [states]
    shapes = entry.get("shape")
    if shapes is None:
        raise doc.fail(path, "missing key `shape` (circle, rectangle, polygon or linestring)")
    shape_list = shapes if isinstance(shapes, list) else [shapes]
    if not shape_list:
        raise doc.fail(f"{path}.shape", "expected a shape, got an empty list")
    out = []
    for k in range(number):
        si = min(k, len(state_list) - 1)       # the last state and shape repeat
        hi = min(k, len(shape_list) - 1)
        s_path = f"{path}.state" + (f"[{si}]" if len(state_list) > 1 else "")
        h_path = f"{path}.shape" + (f"[{hi}]" if len(shape_list) > 1 else "")
        out.append(_irsim_shape(doc, h_path, shape_list[hi],
                                _state(doc, s_path, state_list[si])))
    return out


def _irsim_shape(doc: Any, path: str, v: Any, state: tuple[float, float, float]) -> Any:
    from mdle.sim import shapes
    from mdle.sim.yaml_values import _number, _point, _points, _show

    if not isinstance(v, dict) or v.get("name") not in _SHAPES:
        got = v.get("name") if isinstance(v, dict) else _show(v)
        raise doc.fail(f"{path}.name" if isinstance(v, dict) else path,
                       f"an IR-SIM shape is one of {', '.join(_SHAPES)}, got {got!r}")
    x, y, th = state
    c, s = math.cos(th), math.sin(th)

    def place(p: tuple[float, float]) -> tuple[float, float]:
        return (x + c * p[0] - s * p[1], y + s * p[0] + c * p[1])

    kind = v["name"]
    if kind == "circle":
        r = _number(doc, f"{path}.radius", v.get("radius", 0.2), size=True)
        centre = _point(doc, f"{path}.center", v["center"]) if "center" in v else (0.0, 0.0)
        return shapes.Circle(place(centre), r)
    if kind == "rectangle":
        length = _number(doc, f"{path}.length", v.get("length", 1.0), size=True)
        width = _number(doc, f"{path}.width", v.get("width", 1.0), size=True)
        return shapes.Rectangle((x, y), (length, width), th)
    if "vertices" not in v:
        raise doc.fail(path, f"missing key `vertices` (a {kind} needs them)")
    pts = _points(doc, f"{path}.vertices", v["vertices"], 3 if kind == "polygon" else 2,
                  f"a {kind}")
    placed = tuple(place(p) for p in pts)
    if kind == "polygon":
        shape: Any = shapes.Polygon(placed)
        g = shape.geometry()
        if not g.is_valid or g.area <= 0:
            raise doc.fail(f"{path}.vertices", "the polygon crosses itself or has no area")
        return shape
    return shapes.Wall(placed, LINE_THICKNESS)
