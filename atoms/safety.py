"""The full-scan safety layer on top of the boundary-following law (:mod:`atoms.steering`).

The two rays the law reads are blind to the left and between them, so the arc the law
commands is checked against every scan point and, if it comes too close, replaced by the
admissible turn rate nearest to it among those that keep the obstacle on the followed side
(slower, or turning on the spot, before the blind side).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

__all__ = ["safety_filter"]


def _arc_clearance(near: "np.ndarray", speed: float, rates: "np.ndarray", lookahead: float,
                   samples: int) -> tuple["np.ndarray", "np.ndarray"]:
    """Compute the clearance (m, before the body radius) of arcs at ``speed`` and ``rates``.

    Each arc lasts ``lookahead`` seconds and is sampled at ``samples`` points after the start.
    Returns the clearances (K,) and, for each arc, on which side of it its nearest scan point
    lies: the sign of the cross product of the arc's heading there with the point (K,),
    positive on the left.
    """
    import numpy as np

    length = speed * lookahead
    s = np.linspace(length / samples, length, samples)
    c = rates / speed                                            # (K,) curvature of each arc
    th = c[:, None] * s[None, :]                                 # (K, S)
    straight = np.abs(c) < 1e-9
    cs = np.where(straight, 1.0, c)[:, None]
    ax = np.where(straight[:, None], s[None, :], np.sin(th) / cs)
    ay = np.where(straight[:, None], 0.0, (1.0 - np.cos(th)) / cs)
    dx = near[:, 0] - ax[..., None]                              # (K, S, M): arc -> point
    dy = near[:, 1] - ay[..., None]
    d2 = (dx * dx + dy * dy).reshape(rates.size, -1)
    nearest = d2.argmin(axis=1)
    k = np.arange(rates.size)
    sk = nearest // near.shape[0]
    cross = (np.cos(th[k, sk]) * dy.reshape(rates.size, -1)[k, nearest]
             - np.sin(th[k, sk]) * dx.reshape(rates.size, -1)[k, nearest])
    return np.sqrt(d2[k, nearest]), cross


def _own_clearance(near: "np.ndarray", speed: float, rate: float, lookahead: float,
                   samples: int) -> float:
    """Return the clearance (m, before the body radius) of the one arc at ``(speed, rate)``.

    The common case of every tick (the law's own arc is admissible), without the candidate
    bookkeeping of :func:`_arc_clearance`: the few samples are computed in plain floats, and
    the points taken as complex numbers, so that one subtraction gives every sample-to-point
    offset and three more calls their squared lengths (never a reduction over a short axis,
    which numpy runs as one inner loop per row).
    """
    import numpy as np

    length = speed * lookahead
    c = rate / speed
    if abs(c) < 1e-9:
        arc = [complex(length * (k + 1) / samples, 0.0) for k in range(samples)]
    else:
        arc = [complex(math.sin(c * si) / c, (1.0 - math.cos(c * si)) / c)
               for si in [length * (k + 1) / samples for k in range(samples)]]
    d = np.subtract(arc, np.ascontiguousarray(near, dtype=float).view(np.complex128))  # (M, S)
    re, im = d.real, d.imag
    d2 = re * re
    d2 += im * im
    return math.sqrt(np.minimum.reduce(d2, axis=None))


def safety_filter(points: "np.ndarray", v: float, u: float, umax: float, radius: float,
                  margin: float, lookahead: float, candidates: int = 25,
                  samples: int = 8, side: int = -1) -> tuple[float, float, float]:
    """Apply the full-scan safety layer: keep ``(v, u)`` unless its arc nears the scan.

    The arc the robot drives at ``(v, u)`` over ``lookahead`` seconds is sampled and its
    clearance (distance to the nearest scan point minus the body ``radius``) computed. It is
    admissible if that is at least ``margin``, or, when the robot is already closer than
    ``margin``, if the arc gets no closer than it is now. An admissible command stands.
    Otherwise the turn rate is replaced by the admissible one nearest to ``u`` among
    ``candidates`` rates over +-umax whose nearest scan point lies on the followed ``side``
    (-1 right, +1 left): the followed side wins, so a robot that meets a face at an awkward
    angle is never deflected along it with the obstacle on its blind side. Such a rate is
    sought at full speed, else at half, a quarter, and finally the robot turns on the spot
    towards the followed side (which never gets closer and puts what is ahead on that
    side); so it also never drives into a dead end it cannot turn out of (a
    constant-speed unicycle cannot turn round in a wedge narrower than its turning circle).

    Parameters
    ----------
    points : (M, 2) float array, metres
        Robot-frame scan points (valid beams only).
    v, u : float
        The law's speed (m/s) and turn rate (rad/s).
    umax : float, rad/s
    radius, margin : float, metres
    lookahead : float, seconds
    candidates, samples : int

    Returns
    -------
    (v, u, clearance)
        The command to send and the predicted clearance of the law's own arc (m).
    """
    import numpy as np

    if points.shape[0] == 0 or v <= 0 or lookahead <= 0:
        return v, u, math.inf
    reach = v * lookahead + radius + margin + 0.05
    dist = np.hypot(points[:, 0], points[:, 1])  # one call, not three
    near = points[dist < reach]
    if near.shape[0] == 0:
        return v, u, math.inf
    now = float(np.fmin.reduce(dist)) - radius  # the nearest of all (NaN aside) is near
    need = min(margin, now - 1e-3)
    own = _own_clearance(near, v, u, lookahead, samples) - radius
    if own >= need:
        return v, u, own
    rates = np.linspace(-umax, umax, candidates)
    for factor in (1.0, 0.5, 0.25):
        clear, cross = _arc_clearance(near, v * factor, rates, lookahead, samples)
        ok = (clear - radius >= need) & (cross * side > 0)
        if ok.any():
            pick = np.flatnonzero(ok)[np.argmin(np.abs(rates[ok] - u))]
            return v * factor, float(rates[pick]), own
    return 0.0, -side * umax, own  # turn on the spot towards the followed side
