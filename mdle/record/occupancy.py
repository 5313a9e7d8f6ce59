"""The simulated world as ``nav_msgs/OccupancyGrid`` (``/map``), as map_server serves one.

The obstacles are rasterised on a grid of :data:`RESOLUTION` over the world's bounds
and a margin: a cell is occupied (100) when an obstacle covers its centre or passes
within half a cell of it (so a wall, a line with no area, shows), free (0) otherwise.
The world is fully known, so no cell is unknown (-1). Row-major from the origin, the
cell at the lower left corner, frame ``map``, as REP-105 and the message say.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mdle.rosmsg.cdr import CdrWriter

__all__ = ["RESOLUTION", "occupancy_grid"]

#: Metres per cell.
RESOLUTION = 0.05
_MARGIN = 0.5       # m of free space around the obstacles' bounds
_MAX_CELLS = 4_000_000  # a larger world gets coarser cells


def occupancy_grid(world: Any, ns: int, frame: str = "map") -> bytes:
    """Return the CDR OccupancyGrid of a :class:`sim.World`'s obstacles, stamped ``ns``."""
    import shapely

    geometry = world.geometry
    if geometry.is_empty:
        x0, y0, x1, y1 = -1.0, -1.0, 1.0, 1.0
    else:
        x0, y0, x1, y1 = (float(b) for b in geometry.bounds)
    x0, y0, x1, y1 = x0 - _MARGIN, y0 - _MARGIN, x1 + _MARGIN, y1 + _MARGIN
    res = RESOLUTION
    while math.ceil((x1 - x0) / res) * math.ceil((y1 - y0) / res) > _MAX_CELLS:
        res *= 2.0
    width, height = math.ceil((x1 - x0) / res), math.ceil((y1 - y0) / res)
    cx = x0 + (np.arange(width) + 0.5) * res
    cy = y0 + (np.arange(height) + 0.5) * res
    gx, gy = np.meshgrid(cx, cy)  # row-major: rows of constant y, from the bottom
    cells = np.zeros(gx.shape, np.int8)
    if not geometry.is_empty:
        near = shapely.buffer(geometry, 0.5 * res)
        shapely.prepare(near)
        cells[shapely.intersects_xy(near, gx, gy)] = 100
    w = CdrWriter().header(ns, frame)
    w.time(0)                                  # map_load_time
    w.prim("f", res).prim("I", width, height)
    w.pose(x0, y0, 0.0)                        # the lower left corner of cell (0, 0)
    w.count(width * height)
    w.buf += cells.tobytes()
    return w.bytes()
