"""Open-loop and simple feedback control laws: go, turn, arc, stop.

Each is a function ``step(args, ctx, state) -> Command`` declared with
:func:`atoms.registry.control_law`. Values are SI; the backend clamps them to the
robot's limits.
"""

from __future__ import annotations

from typing import Any

from mdle.atoms.registry import Args, Context, Param, control_law
from mdle.core.backend import Command
from mdle.core.units import SPEED, TURN_RATE

__all__ = ["go", "turn", "arc", "stop"]


@control_law(Param("v", SPEED, doc="forward speed (negative: reverse)"))
def go(args: Args, ctx: Context, state: Any) -> Command:
    """Drive straight at speed ``v``."""
    return Command(float(args["v"]), 0.0)


@control_law(Param("rate", TURN_RATE, doc="turn rate, counter-clockwise positive"))
def turn(args: Args, ctx: Context, state: Any) -> Command:
    """Turn on the spot at ``rate``."""
    return Command(0.0, float(args["rate"]))


@control_law(Param("v", SPEED, doc="forward speed"),
             Param("omega", TURN_RATE, doc="turn rate, counter-clockwise positive"))
def arc(args: Args, ctx: Context, state: Any) -> Command:
    """Drive an arc of radius ``v / omega`` (left for positive ``omega``)."""
    return Command(float(args["v"]), float(args["omega"]))


@control_law()
def stop(args: Args, ctx: Context, state: Any) -> Command:
    """Stand still."""
    return Command(0.0, 0.0)
