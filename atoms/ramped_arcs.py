"""The arc a robot drives when its turn rate ramps towards the command instead of jumping.

The safety layer (:mod:`atoms.safety`) checks the arc of a command over its look-ahead. For
the ideal unicycle that arc has the commanded rate from the start. A robot whose turn rate
ramps at ``accel`` drives another path: its rate moves from the rate it has (``rate0``)
towards the command at ``accel`` and holds once there. Following on the Pioneer's left
(a robot seen to ramp its way back from turns away, :mod:`atoms.turn_shaping`), the
constant-rate arc of a turn back towards the boundary swings straight into the face the robot
is still turning away from, so the safety layer refused it and asked for more turn away,
one tick of ramp at a time, while the robot could not undo it: in a star's notch the turn
away grew to 2 rad/s and took over a second to unwind, and the robot swung out to 0.9-1.0 m
at rc 0.55. The arc the robot will really drive shows that the turn away under way already
clears the face.

The same holds for the next face's corner floor (:func:`atoms.corners.next_face_weight`),
which asks how far outside ``rc`` a full left turn from here passes the next face: for a
robot whose rate ramps, that turn is :func:`ramped_turn_margin`'s spiral, not the circle of
radius ``v / umax`` (3 cm on the Pioneer, so the floor never acted there and each turn at a
concave kink of the level set, ramped, came late).

>>> pts, heads = ramped_arc(0.3, 0.0, 1.0, math.inf, 0.8, 4)   # no limit: the plain arc
>>> heads.round(3).tolist()
[0.2, 0.4, 0.6, 0.8]
>>> pts, heads = ramped_arc(0.3, 1.0, -1.0, 1.74, 0.8, 4)      # turning away, asked back
>>> heads.round(3).tolist()                  # away for 0.57 s more, then back
[0.165, 0.261, 0.287, 0.243]
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

__all__ = ["Ramp", "ramped_arc", "heading_at", "ramped_turn_margin", "turn_margin",
           "turn_margin_on", "SUBSTEPS"]

#: Midpoint steps per sample interval (the heading is exact; the position is its integral).
SUBSTEPS = 4


@dataclass(frozen=True)
class Ramp:
    """How a robot's turn rate reaches a command: from ``rate`` (rad/s) at ``accel`` (rad/s^2)."""

    rate: float
    """The turn rate the robot has when the command starts to act."""
    accel: float
    """How fast it moves towards the command."""


def heading_at(t: float, rate0: float, rate: float, accel: float) -> float:
    """Return the heading turned after ``t`` seconds, the rate ramping from ``rate0`` to ``rate``.

    The rate moves towards ``rate`` at ``accel`` (rad/s^2; ``inf``: at once) and holds once
    there: the heading is the integral of that piecewise linear rate, exactly.
    """
    diff = rate - rate0
    if not accel < math.inf or diff == 0.0:
        return rate * t
    ramp = abs(diff) / accel  # how long the ramp lasts
    step = math.copysign(accel, diff)
    if t <= ramp:
        return rate0 * t + 0.5 * step * t * t
    return rate0 * ramp + 0.5 * step * ramp * ramp + rate * (t - ramp)


def ramped_arc(speed: float, rate0: float, rate: float, accel: float, lookahead: float,
               samples: int) -> tuple["np.ndarray", "np.ndarray"]:
    """Return the ``samples`` points after the start of a ramped arc and the headings there.

    Parameters
    ----------
    speed : float, m/s
        Constant forward speed.
    rate0, rate : float, rad/s
        The turn rate the robot has when the command acts, and the one commanded.
    accel : float, rad/s^2
        How fast the rate moves towards the command (``inf``: at once, the plain arc).
    lookahead : float, s
        How long the arc lasts; the samples are equally spaced in time.
    samples : int

    Returns
    -------
    (complex array (samples,), float array (samples,))
        The sample points ``x + iy`` (m, in the frame of the start) and the headings
        there (rad). Positions integrate the exact heading by the midpoint rule,
        :data:`SUBSTEPS` steps a sample, summed in order.
    """
    import numpy as np

    h = lookahead / (samples * SUBSTEPS)
    mids = (np.arange(samples * SUBSTEPS) + 0.5) * h
    path = np.cumsum(speed * h * np.exp(1j * _headings(mids, rate0, rate, accel)))
    ends = (np.arange(1, samples + 1) * SUBSTEPS) * h
    return path[SUBSTEPS - 1::SUBSTEPS], _headings(ends, rate0, rate, accel)


def _headings(t: "np.ndarray", rate0: float, rate: float, accel: float) -> "np.ndarray":
    """Return :func:`heading_at` at each of the times ``t`` (s), with the same roundings."""
    import numpy as np

    diff = rate - rate0
    if not accel < math.inf or diff == 0.0:
        return rate * t
    ramp = abs(diff) / accel
    step = math.copysign(accel, diff)
    return np.where(t <= ramp, rate0 * t + 0.5 * step * t * t,
                    rate0 * ramp + 0.5 * step * ramp * ramp + rate * (t - ramp))


def ramped_turn_margin(p: complex, rc: float, v: float, ramp: Ramp, umax: float,
                       samples: int = 16) -> float:
    """Return how far outside ``rc`` a full left turn started now passes ``p``, on a ramp.

    :func:`turn_margin` for a robot whose turn rate ramps: the left turn's rate
    climbs from ``ramp.rate`` to ``umax`` at ``ramp.accel`` instead of jumping to it, so its
    path is no circle of radius ``v / umax`` but a wider spiral. The distance from ``p`` to
    that path (sampled until the heading has turned half round, and the robot's place
    now), less ``rc``: negative when even the fastest turn the robot can make from here
    comes inside ``p``'s ``rc`` circle.
    """
    w0, a = ramp.rate, ramp.accel
    # when the heading has turned by pi: within the ramp (a quadratic), or after it
    t = (-w0 + math.sqrt(w0 * w0 + 2.0 * a * math.pi)) / a
    ramp_end = (umax - w0) / a
    if t > ramp_end:
        t = ramp_end + (math.pi - heading_at(ramp_end, w0, umax, a)) / umax
    import numpy as np

    points, _ = ramped_arc(v, w0, umax, a, t, samples)
    d = points - p  # hypot, as abs(complex) rounds (numpy's complex abs does not)
    return min(abs(p), float(np.hypot(d.real, d.imag).min())) - rc


def turn_margin(p: complex, rc: float, radius: float) -> float:
    """Return how far outside ``rc`` a full-rate left turn from here passes the point ``p``.

    The turning circle of radius ``radius`` has its centre at ``i radius`` in the law's frame;
    ``p`` stays at ``|p - i radius| - radius`` from it, if outside (the distance to the circle
    on either side). Zero when the turn ends tangent to ``p``'s ``rc`` circle; negative when
    even a full turn comes inside it.
    """
    return abs(abs(p - complex(0.0, radius)) - radius) - rc


def turn_margin_on(p: complex, rc: float, v: float, umax: float, ramp: Ramp | None) -> float:
    """Return :func:`turn_margin` for the robot's own full left turn.

    ``ramp`` None: the circle of radius ``v / umax``. Otherwise the rate climbs from
    ``ramp.rate`` at ``ramp.accel`` (:func:`ramped_turn_margin`).
    """
    if ramp is None:
        return turn_margin(p, rc, v / umax)
    return ramped_turn_margin(p, rc, v, ramp, umax)
