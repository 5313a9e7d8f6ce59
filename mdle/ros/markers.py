"""Lines for a 3-D panel: obstacle outlines in ``map``, and the robot's path.

Each obstacle ring (a polygon's outline and holes, a wall's line) becomes a LINE_STRIP
marker of a ``visualization_msgs/MarkerArray`` at z = 0, so the world shows under the
robot in a 3-D panel (Foxglove, RViz); the path goes out piece by piece, a
``visualization_msgs/Marker`` each.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from mdle.ros.cdr import CdrWriter

__all__ = ["obstacle_markers", "outlines", "path_marker"]

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


_PATH_COLOUR = (0.1, 0.45, 0.9, 1.0)  # blue, opaque


def _line(w: CdrWriter, ns: int, frame: str, name: str, marker_id: int,
          points: Sequence[tuple[float, float]], colour: tuple[float, ...]) -> None:
    """Write one LINE_STRIP ``Marker`` (z = 0) of ``points``."""
    w.header(ns, frame).string(name).prim("i", marker_id, LINE_STRIP, ADD)
    w.pose(0.0, 0.0, 0.0)
    w.prim("d", _WIDTH, 0.0, 0.0)           # scale: x is the line width
    w.prim("f", *colour)
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


def obstacle_markers(world: Any, ns: int, frame: str = "map") -> bytes:
    """Return the CDR MarkerArray of the world's obstacles, stamped ``ns``."""
    lines = outlines(world)
    w = CdrWriter().count(len(lines))
    for i, points in enumerate(lines):
        _line(w, ns, frame, "obstacles", i, points, _COLOUR)
    return w.bytes()


def path_marker(ns: int, frame: str, marker_id: int,
                points: Sequence[tuple[float, float]]) -> bytes:
    """Return a CDR ``Marker``: a piece of the robot's path (a LINE_STRIP in ``frame``).

    Each piece has its own id and lives forever, so a tool draws the whole path so far
    from small messages; a piece starts where the one before ended.
    """
    w = CdrWriter()
    _line(w, ns, frame, "path", marker_id, points, _PATH_COLOUR)
    return w.bytes()
