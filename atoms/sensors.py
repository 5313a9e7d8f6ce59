"""Sensor functions for interrupts: ladar ranges, odometry, time, flags.

Each is ``fn(args, ctx) -> float | bool``, declared with :func:`atoms.registry.sensor`.
Ladar functions read the newest scan; with no scan (or no valid beam where asked) they
answer the sensor's maximum range, so ``range(0 deg) < 1 m`` stays false rather than
raising. numpy is imported on first use only.
"""

from __future__ import annotations

import math

from mdle.atoms.registry import BOOL, Args, Bounds, Context, Param, sensor
from mdle.core.units import ANGLE, LENGTH, SPEED, TIME, TURN_RATE

__all__ = ["range_", "min_range", "x", "y", "theta", "speed", "turn_rate", "t", "stalled",
           "dist_to", "bearing_to_point", "clear"]

_NO_SCAN_RANGE = math.inf
#: theta is wrapped to [-pi, pi] (the simulator reports [-pi, pi), a Pioneer's driver
#: either end): `theta > 200 deg` can never hold (a checker warning)
_HEADINGS = Bounds(-math.pi, math.pi)
#: ranges and distances are never negative
_DISTANCES = Bounds(0.0, math.inf)


@sensor(Param("angle", ANGLE, doc="bearing from the heading, counter-clockwise positive"),
        result=LENGTH, name="range", bounds=_DISTANCES)
def range_(args: Args, ctx: Context) -> float:
    """Return the range of the ladar beam nearest the bearing ``angle`` (max range: no return)."""
    import numpy as np

    scan = ctx.obs.scan
    if scan is None:
        return _NO_SCAN_RANGE
    i = int(np.argmin(np.abs(scan.bearings - float(args["angle"]))))
    return float(scan.ranges[i]) if scan.valid[i] else scan.max_range


@sensor(Param("start", ANGLE, doc="one end of the sector"),
        Param("end", ANGLE, doc="the other end of the sector"), result=LENGTH,
        bounds=_DISTANCES)
def min_range(args: Args, ctx: Context) -> float:
    """Return the smallest valid range over the beams with bearings in the sector [start, end]."""
    import numpy as np

    scan = ctx.obs.scan
    if scan is None:
        return _NO_SCAN_RANGE
    lo, hi = sorted((float(args["start"]), float(args["end"])))
    sel = (scan.bearings >= lo - 1e-9) & (scan.bearings <= hi + 1e-9) & scan.valid
    return float(np.min(scan.ranges, where=sel, initial=scan.max_range))


@sensor(result=LENGTH)
def x(args: Args, ctx: Context) -> float:
    """Return the odometry x, metres (0 at the run's start, forward of the start pose)."""
    return ctx.obs.pose.x


@sensor(result=LENGTH)
def y(args: Args, ctx: Context) -> float:
    """Return the odometry y, metres (0 at the run's start, left of the start pose)."""
    return ctx.obs.pose.y


@sensor(result=ANGLE, bounds=_HEADINGS)
def theta(args: Args, ctx: Context) -> float:
    """Return the odometry heading, radians in [-pi, pi] (0 at the run's start)."""
    return ctx.obs.pose.theta


@sensor(result=SPEED)
def speed(args: Args, ctx: Context) -> float:
    """Return the measured forward speed, m/s."""
    return ctx.obs.v


@sensor(result=TURN_RATE)
def turn_rate(args: Args, ctx: Context) -> float:
    """Return the measured turn rate, rad/s."""
    return ctx.obs.omega


@sensor(result=TIME)
def t(args: Args, ctx: Context) -> float:
    """Return the local time of the element whose interrupt is being tested, seconds."""
    return ctx.t


@sensor(result=BOOL)
def stalled(args: Args, ctx: Context) -> bool:
    """Tell whether the robot pushes against something and cannot move (Pioneer stall flag)."""
    return ctx.obs.stalled


@sensor(Param("x", LENGTH), Param("y", LENGTH), result=LENGTH, bounds=_DISTANCES)
def dist_to(args: Args, ctx: Context) -> float:
    """Return the distance from the robot to the point (x, y) of the odometry frame, metres."""
    p = ctx.obs.pose
    return math.hypot(float(args["x"]) - p.x, float(args["y"]) - p.y)


@sensor(Param("x", LENGTH), Param("y", LENGTH), result=ANGLE, name="bearing_to",
        bounds=_HEADINGS)
def bearing_to_point(args: Args, ctx: Context) -> float:
    """Return the bearing of the point (x, y) of the odometry frame from the heading.

    Radians in [-pi, pi], counter-clockwise positive: ``range(bearing_to(8 m, 0 m))``
    reads the beam pointing at the point. At the point itself, 0.
    """
    p = ctx.obs.pose
    dx, dy = float(args["x"]) - p.x, float(args["y"]) - p.y
    if dx == 0.0 and dy == 0.0:
        return 0.0
    return math.remainder(math.atan2(dy, dx) - p.theta, math.tau)


@sensor(Param("bearing", ANGLE, doc="direction of the way, from the heading"),
        Param("distance", LENGTH, low=0.0, finite=False, doc="how far the way must be clear"),
        Param("margin", LENGTH, 0.1, low=0.0, fixed=True,
              doc="room kept on each side of the robot's body"),
        result=BOOL)
def clear(args: Args, ctx: Context) -> bool:
    """Tell whether the way along ``bearing`` is free of ladar returns to ``distance``.

    The way is a corridor as wide as the robot's body plus ``margin`` on each side, from
    the robot's centre to ``distance`` ahead along the bearing (and half a width beyond,
    where the robot's front would be). A bearing outside the scan's field (behind an
    LMS-200) is not clear: nothing there can be seen. With no scan, not clear.
    """
    import numpy as np

    scan = ctx.obs.scan
    if scan is None:
        return False
    bearing = float(args["bearing"])
    half = ctx.limits.radius + float(args["margin"])
    reach = float(args["distance"])
    b = scan.bearings
    # the corridor's edges must be within the field, as seen at its far end
    side = math.atan2(half, max(reach, half))
    if bearing - side < float(b[0]) - 1e-9 or bearing + side > float(b[-1]) + 1e-9:
        return False
    hit = scan.valid
    rel = b - bearing
    along = scan.ranges * np.cos(rel)
    across = scan.ranges * np.sin(rel)
    blocked = hit & (along > 0.0) & (along < reach + half) & (np.abs(across) < half)
    return not bool(blocked.any())
