"""The simulated world as ``visualization_msgs/MarkerArray``: obstacle outlines in ``map``.

Each obstacle ring (a polygon's outline and holes, a wall's line) becomes a LINE_STRIP
marker at z = 0, so the world shows under the robot in a 3-D panel (Foxglove, RViz).
"""

from __future__ import annotations

from typing import Any

from mdle.ros.cdr import CdrWriter

__all__ = ["obstacle_markers", "outlines"]

LINE_STRIP = 4
ADD = 0
_WIDTH = 0.03                      # m, the drawn line width
_COLOUR = (0.55, 0.55, 0.6, 1.0)   # grey, opaque


def outlines(world: Any) -> list[list[tuple[float, float]]]:
    """Return every obstacle outline of a :class:`sim.World` as a list of (x, y) points.

    Closed rings end where they start.
    """
    import shapely

    out: list[list[tuple[float, float]]] = []
    for part in shapely.get_parts(world.geometry):
        for g in shapely.get_parts(part):
            if g.geom_type == "Polygon":
                for ring in (g.exterior, *g.interiors):
                    out.append([(float(x), float(y)) for x, y in ring.coords])
            elif g.geom_type in ("LineString", "LinearRing"):
                out.append([(float(x), float(y)) for x, y in g.coords])
    return [line for line in out if len(line) >= 2]


def obstacle_markers(world: Any, ns: int, frame: str = "map") -> bytes:
    """Return the CDR MarkerArray of the world's obstacles, stamped ``ns``."""
    lines = outlines(world)
    w = CdrWriter().count(len(lines))
    for i, points in enumerate(lines):
        w.header(ns, frame).string("obstacles").prim("i", i, LINE_STRIP, ADD)
        w.pose(0.0, 0.0, 0.0)
        w.prim("d", _WIDTH, 0.0, 0.0)           # scale: x is the line width
        w.prim("f", *_COLOUR)
        w.time(0)                               # lifetime 0: forever
        w.prim("?", False)                      # frame_locked
        w.count(len(points))
        for x, y in points:
            w.prim("d", x, y, 0.0)
        w.count(0)                              # colors (one for all: `color`)
        w.string("")                            # texture_resource
        w.header(0, "").string("").count(0)     # texture: an empty CompressedImage
        w.count(0)                              # uv_coordinates
        w.string("").string("")                 # text, mesh_resource
        w.string("").count(0)                   # mesh_file: name, data
        w.prim("?", False)                      # mesh_use_embedded_materials
    return w.bytes()
