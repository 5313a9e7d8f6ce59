"""Pose-feedback control laws: ``goto(x, y, v)`` and ``heading(theta)``.

Both read odometry only (``ctx.obs.pose``) and respect the robot's turn-rate limit.
End them with an interrupt: ``dist_to(x, y) < 0.1 m`` for goto, ``abs``-free forms such as a
timer or ``theta`` thresholds for heading; they hold still once there.
"""

from __future__ import annotations

import math
from typing import Any

from mdle.atoms.registry import Args, Context, Param, control_law
from mdle.core.backend import Command
from mdle.core.units import ANGLE, LENGTH, SPEED, TURN_RATE

__all__ = ["goto", "heading"]


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


@control_law(Param("x", LENGTH, doc="goal x in the odometry frame"),
             Param("y", LENGTH, doc="goal y in the odometry frame"),
             Param("v", SPEED, 0.3, doc="cruising speed", low=0.0, low_open=True),
             Param("tol", LENGTH, 0.05, doc="stop within this distance of the goal", low=0.0))
def goto(args: Args, ctx: Context, state: Any) -> Command:
    """Drive to the point (x, y): turn toward it, slow down within a metre, stop at tol.

    ``omega = k * e`` with ``e`` the bearing error (k = 2/s, clipped at the robot's limit);
    ``v`` scaled by ``max(cos e, 0)`` (no driving while facing away) and by distance / 1 m
    near the goal, so the robot converges instead of circling it.
    """
    p = ctx.obs.pose
    dx = float(args["x"]) - p.x
    dy = float(args["y"]) - p.y
    dist = math.hypot(dx, dy)
    if dist <= float(args["tol"]):
        return Command(0.0, 0.0)
    e = _wrap(math.atan2(dy, dx) - p.theta)
    wmax = ctx.limits.max_turn_rate
    omega = min(max(2.0 * e, -wmax), wmax)
    v = float(args["v"]) * max(math.cos(e), 0.0) * min(1.0, dist / 1.0)
    return Command(v, omega)


@control_law(Param("theta", ANGLE, doc="heading to turn to, odometry frame"),
             Param("rate", TURN_RATE, 1.0, doc="largest turn rate", low=0.0, low_open=True,
                   commanded=False))
def heading(args: Args, ctx: Context, state: Any) -> Command:
    """Turn on the spot to the heading theta (proportional, 2/s, capped at rate); hold there."""
    e = _wrap(float(args["theta"]) - ctx.obs.pose.theta)
    wmax = min(float(args["rate"]), ctx.limits.max_turn_rate)
    return Command(0.0, min(max(2.0 * e, -wmax), wmax))
