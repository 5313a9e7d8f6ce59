"""Sensor functions and a control law for robots that talk: messages and the others' poses.

They read the robot's inbox (``ctx.obs.inbox``, :class:`mdle.core.messages.Inbox`), which a
team run fills; a robot alone has none, and then nothing has been received:
``received`` is false, ``message`` NaN, ``range_to`` inf and ``bearing_to`` NaN, so
comparisons with them stay false. The channel and robot arguments take any name; a
team run checks them against what the other plans send and the robots it has.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any

from mdle.atoms.registry import BOOL, Args, Context, Param, control_law, sensor
from mdle.core.backend import Command
from mdle.core.messages import relative
from mdle.core.pose import Pose
from mdle.core.units import ANGLE, LENGTH, SPEED

__all__ = ["received", "message", "range_to", "bearing_to", "pursue"]

_CHANNEL = Param("channel", any_name="channel", doc="a channel name, such as `go`")
_ROBOT = Param("robot", any_name="robot", doc="the name of another robot of the team")


@sensor(_CHANNEL, result=BOOL)
def received(args: Args, ctx: Context) -> bool:
    """Tell whether a message on the channel arrived after the tested element's start tick."""
    box = ctx.obs.inbox
    return box is not None and box.since(str(args["channel"]), ctx.obs.time - ctx.t)


@sensor(_CHANNEL, result=None)
def message(args: Args, ctx: Context) -> float:
    """Return the last number received on the channel, in its sender's units (NaN: none yet)."""
    box = ctx.obs.inbox
    return math.nan if box is None else box.value(str(args["channel"]))


def _other(args: Args, ctx: Context) -> tuple[Pose, Pose] | None:
    box = ctx.obs.inbox
    if box is None:
        return None
    other = box.pose_of(str(args["robot"]))
    return None if other is None else (box.me(ctx.obs.pose), other)


@sensor(_ROBOT, result=LENGTH)
def range_to(args: Args, ctx: Context) -> float:
    """Return the distance to the robot, from the last pose it sent (inf: none received)."""
    both = _other(args, ctx)
    return math.inf if both is None else relative(*both)[0]


@sensor(_ROBOT, result=ANGLE)
def bearing_to(args: Args, ctx: Context) -> float:
    """Return the robot's bearing from our heading, from its last pose (NaN: none received)."""
    both = _other(args, ctx)
    return math.nan if both is None else relative(*both)[1]


def _start_pursuit(args: Args, ctx: Context) -> dict[str, Any]:
    return {"trail": deque(), "last": None}


@control_law(_ROBOT,
             Param("gap", LENGTH, 1.0, doc="distance to keep behind the robot", low=0.0,
                   low_open=True),
             Param("v", SPEED, 0.4, doc="top speed", low=0.0, low_open=True),
             Param("reach", LENGTH, 0.3, doc="a trail point counts as passed this close",
                   low=0.0, low_open=True),
             start=_start_pursuit)
def pursue(args: Args, ctx: Context, state: dict[str, Any]) -> Command:
    """Follow the robot along the trail of poses it sends, ``gap`` behind it.

    Each new pose the robot sends is a point of its trail; the follower steers to the
    oldest point not yet passed (within ``reach``), ``omega = 2/s * bearing`` (at the
    robot's limit), at ``v * clip(range - gap, 0, 1 m) / 1 m * max(cos bearing, 0)``:
    it keeps to the leader's path rather than cutting its corners, and waits when closer
    than ``gap``. With no pose received yet it stands still.
    """
    box = ctx.obs.inbox
    if box is None:
        return Command(0.0, 0.0)
    leader = box.pose_of(str(args["robot"]))
    if leader is None:
        return Command(0.0, 0.0)
    trail: deque[Pose] = state["trail"]
    if leader is not state["last"]:
        state["last"] = leader
        trail.append(leader)
    me = box.me(ctx.obs.pose)
    reach = float(args["reach"])
    while len(trail) > 1 and relative(me, trail[0])[0] < reach:
        trail.popleft()
    _, bearing = relative(me, trail[0])
    dist, _ = relative(me, leader)
    wmax = ctx.limits.max_turn_rate
    omega = min(max(2.0 * bearing, -wmax), wmax)
    slack = min(max(dist - float(args["gap"]), 0.0), 1.0)
    v = float(args["v"]) * slack * max(math.cos(bearing), 0.0)
    return Command(v, omega)
