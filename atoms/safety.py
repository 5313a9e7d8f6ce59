"""The full-scan safety layer on top of the boundary-following law (:mod:`atoms.steering`).

The two rays the law reads are blind to the left and between them, so the arc the law
commands is checked against every scan point and, if it comes too close, replaced by the
admissible turn rate nearest to it among those that keep the obstacle on the followed side
(slower, or turning on the spot, before the blind side).

Scan points are complex numbers here (``x + iy``, robot frame): a shift is one subtraction,
a rotation one product, and every sample-to-point offset of an arc one broadcast
subtraction. Each numpy call costs about as much as arithmetic on a few hundred numbers, so
the check of the law's own arc, made every tick, is a handful of calls (see
:func:`filter_complex`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mdle.atoms import searches
from mdle.atoms.ramped_arcs import Ramp, ramped_arc

if TYPE_CHECKING:
    import numpy as np

__all__ = ["filter_complex"]


def _arc(speed: float, rate: float, lookahead: float, samples: int) -> list[complex]:
    """Return the ``samples`` points after the start of the arc at ``(speed, rate)``.

    The arc lasts ``lookahead`` seconds; its samples are equally spaced along it, at arc
    lengths ``s = k L / samples`` (``L = speed lookahead``). On a curve of curvature ``c``
    they are ``(e^(i c s) - 1) / (i c)``, the powers of one unit step (a product each, in
    plain floats: the law's own arc is checked every tick, and a few numpy calls would cost
    more than the arithmetic); on a straight arc, ``s``. The heading at a sample is ``c s``.
    """
    length = speed * lookahead
    c = rate / speed
    if abs(c) < 1e-9:  # straight (within 1e-10 m over a few metres)
        return [complex(length * (k + 1) / samples, 0.0) for k in range(samples)]
    h = c * length / samples
    step, p, scale = complex(math.cos(h), math.sin(h)), 1.0 + 0.0j, complex(0.0, -1.0 / c)
    out = []
    for _ in range(samples):
        p *= step
        out.append((p - 1.0) * scale)
    return out


def _own_clearance(near: "np.ndarray", speed: float, rate: float, lookahead: float,
                   samples: int, ramp: Ramp | None = None) -> float:
    """Return the clearance (m, before the body radius) of the one arc at ``(speed, rate)``.

    ``near``: the scan points (complex, (M,)). The common case of every tick (the law's own
    arc is admissible), without the side bookkeeping of :func:`_arc_clearance`: one
    broadcast subtraction for every sample-to-point offset, its modulus, and the smallest.
    """
    import numpy as np

    arc = _arc(speed, rate, lookahead, samples) if ramp is None else \
        ramped_arc(speed, ramp.rate, rate, ramp.accel, lookahead, samples)[0]
    d = np.abs(np.subtract(np.array(arc)[:, None], near))
    return float(d.item(d.argmin()))


def _arc_clearance(near: "np.ndarray", speed: float, rates: "np.ndarray", lookahead: float,
                   samples: int, ramp: Ramp | None = None) -> tuple["np.ndarray", "np.ndarray"]:
    """Compute the clearance (m, before the body radius) of arcs at ``speed`` and ``rates``.

    ``near``: the scan points (complex, (M,)); the arcs are :func:`_arc`'s. Returns the
    clearances (K,) and, for each arc, on which side of it its nearest scan point lies: the
    sign of the cross product of the arc's heading there with the point (K,), positive on
    the left.
    """
    import numpy as np

    # the few candidate arcs of a tick whose own arc failed: one arc at a time is cheap enough
    if ramp is None:
        arc = np.array([_arc(speed, float(u), lookahead, samples) for u in rates])  # (K, S)
        s = np.arange(1, samples + 1) * (speed * lookahead / samples)  # arc lengths (S,)
        th = np.multiply.outer(rates / speed, s)                       # headings there (K, S)
    else:
        ramped = [ramped_arc(speed, ramp.rate, float(u), ramp.accel, lookahead, samples)
                  for u in rates]
        arc = np.array([a for a, _ in ramped])
        th = np.array([h for _, h in ramped])
    d = np.subtract(near, arc.reshape(-1, 1)).reshape(rates.size, -1)  # (K, S * M): to points
    re, im = d.real, d.imag
    d2 = re * re
    d2 += im * im
    nearest = d2.argmin(axis=1)
    k = np.arange(rates.size)
    # the offset in the frame of the arc's heading there: its imaginary part is the cross
    cross = (d[k, nearest] * np.exp(-1j * th[k, nearest // near.shape[0]])).imag
    return np.sqrt(d2[k, nearest]), cross


def _admissible(near: "np.ndarray", speed: float, rates: "np.ndarray", u: float,
                lookahead: float, samples: int, radius: float, need: float,
                side: int, ramp: Ramp | None = None) -> float | None:
    """Return the rate nearest to ``u`` whose arc clears ``need`` on the followed side.

    None if there is none. The rates are tried nearest to ``u`` first (ties: the lower),
    a few, then the rest: the pick is the first admissible in that order, and usually
    among the few (the law's own rate just failed; a small change of it mostly does).
    """
    import numpy as np

    order = np.argsort(np.abs(rates - u), kind="stable")
    for part in (order[:_FEW], order[_FEW:]):
        if part.size == 0:
            break
        clear, cross = _arc_clearance(near, speed, rates[part], lookahead, samples, ramp)
        ok = np.flatnonzero((clear - radius >= need) & (cross * side > 0))
        if ok.size:
            return float(rates[part[ok[0]]])
    return None


#: How many candidate rates (nearest to the law's) are tried before the rest.
_FEW = 8


def filter_complex(z: "np.ndarray", v: float, u: float, umax: float, radius: float,
                   margin: float, lookahead: float, candidates: int = 25, samples: int = 8,
                   side: int = -1, ramp: Ramp | None = None) -> tuple[float, float, float]:
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
    Only scan points within reach of the arc (its length, the radius, the margin and 5 cm)
    are read; with none, the clearance is ``inf``.

    Parameters
    ----------
    z : (M,) complex array, metres
        Robot-frame scan points ``x + iy`` (valid beams only).
    v, u : float
        The law's speed (m/s) and turn rate (rad/s).
    umax : float, rad/s
    radius, margin : float, metres
    lookahead : float, seconds
    candidates, samples : int
    side : int
        The followed side: -1 right, +1 left.
    ramp : Ramp or None
        How the robot's turn rate reaches a command (:mod:`atoms.ramped_arcs`): every arc
        is then the one driven while the rate ramps from ``ramp.rate``. None: the rate is
        the command's from the start (the ideal unicycle; the arcs as always).

    Returns
    -------
    (v, u, clearance)
        The command to send and the predicted clearance of the law's own arc (m).
    """
    import numpy as np

    if z.shape[0] == 0 or v <= 0 or lookahead <= 0:
        return v, u, math.inf
    # abs(z) < reach, as the whole-scan model's compiled search answers it (numpy's answer)
    near = z[searches.within(z, 0j, v * lookahead + radius + margin + 0.05)]
    if near.shape[0] == 0:
        return v, u, math.inf
    own = _own_clearance(near, v, u, lookahead, samples, ramp) - radius
    if own >= margin:  # admissible whatever the robot's distance now (need <= margin)
        return v, u, own
    now = float(np.fmin.reduce(np.abs(z))) - radius  # the nearest of all (NaN aside) is near
    need = min(margin, now - 1e-3)
    if own >= need:
        return v, u, own
    rates = np.linspace(-umax, umax, candidates)
    for factor in (1.0, 0.5, 0.25):
        pick = _admissible(near, v * factor, rates, u, lookahead, samples, radius, need, side,
                           ramp)
        if pick is not None:
            return v * factor, pick, own
    return 0.0, -side * umax, own  # turn on the spot towards the followed side
