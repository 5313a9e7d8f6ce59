"""A thing ahead that the circle followed passes clear of: no wall ahead to turn from.

The front ray (:func:`atoms.closest._with_front`) reads a hit straight ahead as a wall the
robot is about to meet, and turns it away (the two-ray law's gate, blend and floor). While
the robot circles a convex thing (a pole, a leg, a tip), a hit ahead is often the next
separate thing, and the circle it is on may pass it at ``rc`` or more: the next pole of a
row whose gap is about ``2 rc``, the far leg of a table. Turned away from it, the robot
leaves the circle it was on, the point it circled goes out of view behind it, and the next
thing becomes the nearest point, on the wrong side: the robot turns into it (0.15-0.35 m
from it in the lab suite's worst pole-row and table runs).

Where two things are ``g`` apart with ``g`` a little under ``2 rc``, their ``rc`` level sets
join at a kink of nearly 180 deg (:func:`atoms.fillet.kink_angle`), which no robot turning
at most ``umax`` follows closely: at 1 m/s and 3 rad/s the swing out of such a kink is about
0.09 m, where circling the one thing followed dips only ``2 rc - g`` into the other's
``rc`` band. So a hit ahead that the circle passes within :data:`LENS` x ``rc`` of ``rc``
still counts as clear: the robot goes on round what it circles.

Points are complex numbers ``x + iy`` in the law's frame (right-hand following; the caller
mirrors the left side), the heading along ``+x``.

>>> clear_ahead(1.2, complex(0.0, -0.5), 0.5, -10.0, 0.5)   # a pole beside, one 1.2 m ahead
True
>>> clear_ahead(0.7, complex(0.0, -0.5), 0.5, -10.0, 0.5)   # ... 0.7 m ahead: in the way
False
"""

from __future__ import annotations

import math

__all__ = ["clear_ahead", "LENS"]

#: A hit ahead counts as clear of the circle followed when the circle passes it no nearer
#: than ``(1 - LENS) rc``: the dip into a separate thing's ``rc`` band at a gap a little
#: under ``2 rc`` costs less than turning away from it.
LENS = 0.1


def clear_ahead(front_r: float, q: complex, r: float, kappa: float, rc: float) -> bool:
    """Tell whether the circle followed round ``q`` passes the front ray's hit at ``rc``.

    Parameters
    ----------
    front_r : float, m
        The front ray's range: the hit lies at ``front_r`` straight ahead.
    q : complex
        The nearest point followed, in the law's frame.
    r : float, m
        Its range (the robot's distance to the boundary followed).
    kappa : float, 1/m
        Its curvature (convex negative). Only a convex boundary is circled; a wall or a
        concave face is followed on towards what lies ahead, and the front ray decides.
    rc : float, m
        The following distance.

    Returns
    -------
    bool
        True when the circle through the robot round the centre of curvature (radius
        ``r + 1 / |kappa|``) passes the hit at least ``(1 - LENS) rc`` away.
    """
    if not (kappa < 0.0 and r > 0.0):
        return False
    rho = -1.0 / kappa
    radius = r + rho
    centre = q * (radius / r)  # on the line of sight, beyond q by the radius of curvature
    return abs(complex(front_r, 0.0) - centre) - radius >= (1.0 - LENS) * rc
