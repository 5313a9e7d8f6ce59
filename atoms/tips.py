"""A tip seen from one flank is a point: where a fit of the scan runs on past what it saw.

The whole-scan model (:mod:`atoms.closest`) fits a circle to the scan points around the
nearest one, ``q``, and follows the fitted boundary's point nearest to the robot. Inside the
ladar's field of view the nearest point of the boundary is always seen (nothing can hide it):
it lies among the points returned, or between two neighbouring beams. A fit whose nearest
point lies past the end of its points, where the ladar looked and saw nothing there, has
carried a face on beyond the boundary's end: the one flank of a tip that the robot sees, a
plate's end, the face behind a vertex. The nearest point is then ``q`` itself, as a point,
which is what the closest-point law asks at a tip (range ``|q|``, tangent perpendicular to
the line of sight, the curvature of a point).

Points are complex numbers ``x + iy`` in the law's frame (right-hand following), as in
:mod:`atoms.closest`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mdle.atoms.steering import FOV_EDGE

if TYPE_CHECKING:
    import numpy as np

__all__ = ["ends_at_nearest", "END_MARGIN"]

#: A fit's nearest point farther than this angle (times the range) past the end of the fitted
#: points is off the boundary: three LMS-200 beams, where one more beam would have seen a
#: boundary that went on (a tip lies within one beam of the last point on its flank, and on a
#: noisy scan the fit's nearest point scatters by about as much again).
END_MARGIN = math.radians(3.0)


def ends_at_nearest(w: "np.ndarray", foot: complex, at: complex, rq: float) -> bool:
    """Tell whether a fit's nearest point lies past the end of its points, where the scan saw none.

    Parameters
    ----------
    w : complex array (M,)
        The fitted points in the nearest point's frame (``s + i h``: ``s`` across the line of
        sight, ``h`` towards the robot; the nearest scan point ``q`` at 0).
    foot : complex
        The fitted boundary's point nearest to the robot, in the same frame.
    at : complex
        The same point in the law's frame.
    rq : float, m
        The range of ``q``.

    Returns
    -------
    bool
        True when ``foot`` lies beyond the last fitted point on its side by more than
        :data:`END_MARGIN` times the range and inside the ladar's field of view (within
        :data:`atoms.steering.FOV_EDGE` of its 180 deg): the beams there saw past it (nothing
        nearer, or nothing at all), so the boundary ends at ``q``.

    A circle fitted to one flank of a tip (the other is hidden behind it), to a plate's end
    or to the face behind a vertex carries on past the end of what was seen. Its nearest
    point then lies on the flank's extension: a straight face beside the robot, where the
    boundary is a point it should turn round. Measured on spike stars whose tips are closer
    than ``2 rc``, at 1 m/s: a third of the ticks on the scan followed such a line (curvature
    about -0.8 1/m instead of the point's -1.6 1/m), and the robot circled each tip about
    0.1 m outside ``rc``. Beyond the edge of the field of view the boundary is unseen, and the
    fit still carries a pole on along its circle there.

    >>> import numpy as np
    >>> flank = np.linspace(0.0, -0.2, 11) + 0.0j      # seen on one side of q only
    >>> ends_at_nearest(flank, complex(0.1, 0.0), complex(0.3, -0.45), 0.6)
    True
    >>> ends_at_nearest(flank, complex(-0.05, 0.0), complex(0.3, -0.45), 0.6)
    False
    """
    margin = END_MARGIN * rq
    s = foot.real
    if -margin <= s <= margin:
        return False  # at q (the common case: one comparison, no numpy call)
    end = float(w.real.max()) if s > 0.0 else float(w.real.min())
    if abs(s) <= abs(end) + margin:
        return False  # among the points fitted
    return abs(math.atan2(at.imag, at.real)) <= math.pi / 2.0 - FOV_EDGE
