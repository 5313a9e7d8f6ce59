"""Unwind look-ahead: on a robot that ramps its way back from a turn away, look past the ramp.

A Stage-based ARCOS server (AMRISim, MobileSim) jumps to a turn away from the boundary but
ramps every turn back towards it at its turn acceleration ``a`` (1.74 rad/s^2 on the
Pioneer 3-DX). Following on the left, the law turns away at each concave kink (the next
spike's flank ahead) and asks to turn back only once its heading is right; the robot then
goes on turning away for ``w / a`` seconds while the rate winds down, ``w^2 / 2a`` of heading
(0.8 rad from 1.7 rad/s) and about 0.3 m of path at 0.3 m/s, and swings out to 0.8-0.9 m
round the next tip before it turns back.

:func:`unwind_motion` is that motion, over the first :data:`SHARE` of the unwind: the pose
the robot reaches however soon a turn back is commanded. The law answers the boundary as
seen from there, so it starts turning back while the robot still turns away, by about as
much as the ramp will carry it on. Rates are in the law's (right-hand) frame, where a
positive rate turns away from the boundary.

>>> dx, dy, dth = unwind_motion(1.74, v=0.3, accel=1.74)   # 3/4 of one second of ramp
>>> round(dth, 3), round(math.hypot(dx, dy), 3)
(0.816, 0.219)
>>> unwind_motion(-0.5, v=0.3, accel=1.74)                 # a turn towards: nothing to unwind
(0.0, 0.0, 0.0)
>>> unwind_motion(1.0, v=0.3, accel=math.inf)              # turns at once
(0.0, 0.0, 0.0)
"""

from __future__ import annotations

import math

__all__ = ["unwind_motion", "SHARE", "STEPS"]

#: The share of the unwind's time looked past. The whole of it assumes the turn back starts
#: at once and nothing turns the law away again meanwhile, and over-corrects: on the P3-DX's
#: left lab study it left 578 of 588 runs within 0.10 m; 3/4 left 586 (587 engaged).
SHARE = 0.75
#: Midpoint steps of the unwind's integration (the rate falls linearly: a few suffice).
STEPS = 8


def unwind_motion(rate: float, v: float, accel: float) -> tuple[float, float, float]:
    """Return the motion ``(dx, dy, dth)`` while a turn away at ``rate`` winds down to zero.

    Parameters
    ----------
    rate : float, rad/s
        The turn rate predicted for when the command acts (law frame: positive away).
    v : float, m/s
        The speed meanwhile.
    accel : float, rad/s^2
        The robot's turn acceleration (``inf``: it turns back at once).

    Returns
    -------
    (float, float, float)
        The motion in the robot's frame now (m, m, rad): zero for a turn towards the
        boundary, no turn, or a robot without a finite positive turn acceleration.
    """
    if not (rate > 0.0 and 0.0 < accel < math.inf):
        return (0.0, 0.0, 0.0)
    h = SHARE * rate / accel / STEPS
    x = y = th = 0.0
    for i in range(STEPS):
        w = rate - accel * (i + 0.5) * h  # the rate at the step's middle
        mid = th + 0.5 * w * h
        x += v * h * math.cos(mid)
        y += v * h * math.sin(mid)
        th += w * h
    return (x, y, th)
