"""Turn-away shaping: the law never asks for a turn away faster than the robot can ramp it.

The steering law's reflexes turn away from the boundary for a tick or two: the front floor
asks for the full turn rate (8.7 rad/s on a Pioneer) when a face comes up ahead, the front
blend and the next face's weight ask for sharp turns at a concave corner. A firmware that
ramps symmetrically smooths such a spike into a small swerve. Some do not: the Stage-based
ARCOS servers (AMRISim, MobileSim) take a positive turn rate commanded negative *at once*
and ramp the other way at 100 deg/s^2, so on one side a one-tick spike away becomes a full
turn rate that takes seconds to undo (8.7 rad/s at 1.74 rad/s^2: 5 s), and the robot spins
off the boundary it was following.

:func:`limit_turn_away` caps each command's turn away from the boundary at what the robot's
turn acceleration reaches in one tick from the rate it turns at now: the larger (further
away) of the last command and the measured turn rate, so the cap never holds the robot back
behind what a ramping firmware would do anyway. Turns towards the boundary pass as the law
asks: they are what rounds a tip in time, and the safety layer guards them. A robot without
a turn-acceleration limit (the ideal unicycle) is not shaped at all. Everything is in the
law's (right-hand) frame, where a positive turn rate turns away from the boundary.

>>> round(limit_turn_away(8.7, last=0.5, measured=0.3, accel=1.74, dt=0.1), 6)  # a spike
0.674
>>> limit_turn_away(-2.0, last=0.5, measured=0.3, accel=1.74, dt=0.1)  # towards: as asked
-2.0
>>> limit_turn_away(8.7, last=0.5, measured=0.3, accel=math.inf, dt=0.1)  # ideal robot
8.7
"""

from __future__ import annotations

import math

__all__ = ["limit_turn_away"]


def limit_turn_away(u: float, last: float | None, measured: float, accel: float,
                    dt: float) -> float:
    """Return the turn rate ``u`` with its turn away capped at one tick of the robot's ramp.

    Parameters
    ----------
    u : float, rad/s
        The turn rate asked for, law frame (positive: away from the boundary).
    last : float or None, rad/s
        The last turn rate commanded (law frame); None before the first command.
    measured : float, rad/s
        The turn rate measured now (odometry, law frame).
    accel : float, rad/s^2
        The robot's turn acceleration limit (``inf``: none, nothing is shaped).
    dt : float, s
        The tick's length.

    Returns
    -------
    float
        ``min(u, max(last, measured) + accel dt)``; ``u`` itself without a last command, a
        finite positive acceleration or a positive tick.
    """
    if last is None or not (0.0 < accel < math.inf) or not dt > 0.0:
        return u
    top = max(last, measured) + accel * dt
    return top if u > top else u
