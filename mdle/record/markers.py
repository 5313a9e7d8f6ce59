"""Lines for a 3-D panel: obstacle outlines in ``map``, and the robot's path.

Each obstacle ring (a polygon's outline and holes, a wall's line) becomes a LINE_STRIP
marker of a ``visualization_msgs/MarkerArray`` at z = 0, so the world shows under the
robot in a 3-D panel (Foxglove, RViz); the path goes out piece by piece, a
``visualization_msgs/Marker`` each.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

import numpy as np

from mdle.rosmsg.cdr import ENCAPSULATION, CdrWriter

__all__ = ["PathPieces", "obstacle_markers", "outlines", "path_marker"]

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


class PathPieces:
    """:func:`path_marker`'s bytes, made fast: the constant parts laid out once.

    A piece of path goes out every few ticks; the general writer takes tens of
    microseconds for one, so its constant bytes (namespace, type, pose, scale, colour,
    and everything after the points) are made once per frame, and a piece patches its
    stamp, id and point count in and packs its points with numpy. Tests check it gives
    :func:`path_marker`'s bytes.
    """

    def __init__(self, frame: str) -> None:
        w = CdrWriter().header(0, frame).string("path").prim("i")  # aligned for the id
        self._id_at = len(w.buf)
        _ = w.prim("i", 0, LINE_STRIP, ADD).pose(0.0, 0.0, 0.0).prim("d", _WIDTH, 0.0, 0.0)
        w.prim("f", *_PATH_COLOUR).time(0).prim("?", False).prim("I")
        self._count_at = len(w.buf)
        w.count(0).prim("d")  # the points' doubles start 8-aligned
        self._head = bytes(w.buf)
        # after the points the offset is 8-aligned again, as at the start of a writer
        tail = CdrWriter().count(0).string("").header(0, "").string("").count(0).count(0)
        tail.string("").string("").string("").count(0).prim("?", False)
        self._tail = tail.bytes()[len(ENCAPSULATION):]

    def piece(self, ns: int, marker_id: int, xy: np.ndarray) -> bytes:
        """Return the ``Marker`` of the points ``xy`` (n x 2), stamped ``ns``."""
        head = bytearray(self._head)
        sec, nsec = divmod(ns, 1_000_000_000)
        struct.pack_into("<iI", head, 4, sec, nsec)
        struct.pack_into("<i", head, self._id_at, marker_id)
        struct.pack_into("<I", head, self._count_at, len(xy))
        xyz = np.zeros((len(xy), 3), "<f8")
        xyz[:, :2] = xy
        return bytes(head) + xyz.tobytes() + self._tail
