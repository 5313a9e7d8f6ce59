"""Write a :class:`World` as world YAML (the format of ``docs/worlds.md``), to replay it.

Metres and degrees, as the files are written by hand; every number is written exactly
(shortest round-trip form), so points read back bit for bit and angles to one rounding of
the degree conversion. The robot and the ladar
are written by profile name (a profile changed in code keeps its name only).

>>> from mdle.sim.shapes import Circle
>>> from mdle.sim.world import World
>>> print(world_to_yaml(World("disc", obstacles=(Circle((3.0, 0.0), 1.0),))), end="")
name: disc
seed: 0
start: {x: 0, y: 0, theta: 0}
robot: pioneer2dx
ladar: lms200
obstacles:
  - {type: circle, center: [3, 0], radius: 1}
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable

from mdle.sim.maps import FloorPlan
from mdle.sim.shapes import Arc, Circle, Curve, Ellipse, Polygon, Rectangle, Shape, Wall
from mdle.sim.world import World

__all__ = ["world_to_yaml"]


def _num(x: float) -> str:
    x = float(x)
    return str(int(x)) if x.is_integer() and abs(x) < 1e15 else repr(x)  # shortest exact


def _deg(a: float) -> str:
    return _num(math.degrees(a))


def _pt(p: Iterable[float]) -> str:
    x, y = p
    return f"[{_num(x)}, {_num(y)}]"


def _pts(points: Iterable[Iterable[float]]) -> str:
    return "[" + ", ".join(_pt(p) for p in points) + "]"


def _obstacle(o: Shape | FloorPlan) -> str:
    if isinstance(o, FloorPlan):    # its polygons, one entry each
        return "\n".join(_obstacle(p) for p in _floor_polygons(o))
    if isinstance(o, Polygon):
        keys = f"type: polygon, points: {_pts(o.points)}"
        if o.holes:
            keys += ", holes: [" + ", ".join(_pts(h) for h in o.holes) + "]"
    elif isinstance(o, Rectangle):
        keys = (f"type: rectangle, center: {_pt(o.center)}, size: {_pt(o.size)}, "
                f"angle: {_deg(o.angle)}")
    elif isinstance(o, Circle):
        keys = f"type: circle, center: {_pt(o.center)}, radius: {_num(o.radius)}"
    elif isinstance(o, Ellipse):
        keys = (f"type: ellipse, center: {_pt(o.center)}, axes: {_pt(o.axes)}, "
                f"angle: {_deg(o.angle)}")
    elif isinstance(o, Wall):
        keys = (f"type: wall, points: {_pts(o.points)}, thickness: {_num(o.thickness)}, "
                f"closed: {str(o.closed).lower()}")
    elif isinstance(o, Arc):
        keys = (f"type: arc, center: {_pt(o.center)}, radius: {_num(o.radius)}, "
                f"start: {_deg(o.start)}, end: {_deg(o.start + o.sweep)}, "
                f"thickness: {_num(o.thickness)}")
    else:
        assert isinstance(o, Curve)
        keys = (f"type: curve, points: {_pts(o.points)}, closed: {str(o.closed).lower()}, "
                f"spacing: {_num(o.spacing)}")
        if o.thickness is not None:
            keys += f", thickness: {_num(o.thickness)}"
    if o.name:
        keys = f"name: {json.dumps(o.name)}, " + keys
    return "  - {" + keys + "}"


def _floor_polygons(plan: FloorPlan) -> list[Polygon]:
    """Return a floor plan's polygons as :class:`Polygon` obstacles (rings unclosed)."""
    import shapely

    out = []
    for i, g in enumerate(shapely.get_parts(plan.geom)):
        ext = [tuple(p) for p in g.exterior.coords[:-1]]
        holes = tuple(tuple(tuple(p) for p in r.coords[:-1]) for r in g.interiors)
        out.append(Polygon(tuple(ext), f"{plan.name}.{i}" if plan.name else "", holes))
    return out


def world_to_yaml(world: World) -> str:
    """Return world YAML text that loads back as ``world`` (start, seed, profiles, shapes)."""
    p = world.start_pose
    lines = [f"name: {json.dumps(world.name) if not world.name.isidentifier() else world.name}"]
    if world.description:
        lines.append(f"description: {json.dumps(world.description)}")
    lines += [f"seed: {int(world.seed)}",
              f"start: {{x: {_num(p.x)}, y: {_num(p.y)}, theta: {_deg(p.theta)}}}",
              f"robot: {world.robot.name}", f"ladar: {world.ladar.name}"]
    if world.extent is not None:
        lines.append(f"extent: {_pts([world.extent[:2], world.extent[2:]])}".replace(
            "], [", ", ").replace("[[", "[").replace("]]", "]"))
    lines.append("obstacles:" if world.obstacles else "obstacles: []")
    lines += [_obstacle(o) for o in world.obstacles]
    return "\n".join(lines) + "\n"
