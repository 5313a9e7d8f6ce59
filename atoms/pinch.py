"""Gaps near ``2 rc``: go on round the thing circled, or turn onto the next.

Two things ``g`` apart make one ``rc`` level set with a concave kink of
``2 asin(g / 2 rc)`` between them (:func:`atoms.fillet.kink_angle`) when ``g < 2 rc``, two
closed curves when farther apart. Near ``g = 2 rc`` the kink is nearly a reversal, which no
robot turning at most ``umax`` follows closely, and the measured gap (two noisy points a
few millimetres either side of it) flips from one side of ``2 rc`` to the other from tick
to tick. In the lab suite's worst table and pole-row runs at 1 m/s the robot, circling one
leg or pole, turned hard onto the next one once it read that gap as under ``2 rc``, when
even a full-rate turn would pass it 0.1-0.35 m inside ``rc``; the leg it circled went out
of view behind it, the next one became the nearest point on the wrong side, and the robot
turned into it (0.15-0.35 m from it for a second or two).

Both ways round a near pinch cost something: going on round the thing circled dips into
the next thing's ``rc`` band by ``2 rc - g`` at most; turning onto it swings out of the
kink (the least-radius arc tangent to both ``rc`` circles, :mod:`atoms.fillet`) or, once
the turn is overdue, passes it inside ``rc``. The rules here take the cheaper one, from
what the scan shows:

* :func:`circle_on`: the next face's law (the blend, its floor, the fillet) is weighed in
  only while turning onto it costs less than going on round what is circled;
* :func:`clear_ahead`: the front ray's hit is no wall to turn from when the circle followed
  passes it no nearer than ``(1 - LENS) rc``.

Both apply only while the robot circles a small convex thing (radius of curvature at most
``rc``: a pole, a leg, a tip) and is engaged on it (within :data:`atoms.fillet.ENGAGED` x
``rc`` of ``rc``, its tangent within :data:`atoms.fillet.ALONG` of the heading): then the
circle through the robot round the centre of curvature is the path it is on. A wall or a
longer face is followed on towards what lies ahead, and the rules of
:mod:`atoms.corners` and the front ray decide as before.

Points are complex numbers ``x + iy`` in the law's frame (right-hand following; the caller
mirrors the left side), the heading along ``+x``.

>>> pole = complex(0.0, -0.5)         # a pole abeam at rc 0.5, circled
>>> clear_ahead(1.2, pole, 0.5, 0.0, -10.0, 0.5), clear_ahead(0.7, pole, 0.5, 0.0, -10.0, 0.5)
(True, False)
>>> # a pole of radius 0.1 (centre 0.6 m off) and the next one's nearest point ahead:
>>> circle_on(complex(0.648, -1.464), pole, 0.5, 0.0, -10.0, 0.5, 1.0 / 3.0)  # 2 cm into rc
True
>>> circle_on(complex(0.6, -1.0), pole, 0.5, 0.0, -10.0, 0.5, 1.0 / 3.0)  # 0.38 m into rc
False
"""

from __future__ import annotations

import math

from mdle.atoms import fillet
from mdle.atoms.steering import FOV_EDGE

__all__ = ["apart_behind", "bridge_margin", "circle_on", "clear_ahead", "circle_clearance",
           "fillet_swing", "LENS"]

#: A hit ahead counts as clear of the circle followed when the circle passes it no nearer
#: than ``(1 - LENS) rc``: the dip into a separate thing's ``rc`` band costs less than the
#: swing out of turning away from it (about 0.09 m at 1 m/s and 3 rad/s, rc 0.5).
LENS = 0.1


def circle_clearance(p: complex, q: complex, r: float, beta: float, kappa: float,
                     rc: float) -> float | None:
    """Return how far outside ``rc`` the circle followed round ``q`` passes the point ``p``.

    The circle through the robot round ``q``'s centre of curvature (radius
    ``r + 1 / |kappa|``); negative when it passes inside ``rc``. None when the robot does
    not circle a small convex thing, engaged on it (see the module's conditions).
    """
    if not (kappa < 0.0 and r > 0.0) or -1.0 / kappa > rc:
        return None
    if abs(r - rc) > fillet.ENGAGED * rc or math.cos(beta) < math.cos(fillet.ALONG):
        return None
    radius = r - 1.0 / kappa
    centre = q * (radius / r)  # on the line of sight, beyond q by the radius of curvature
    return abs(abs(p - centre) - radius) - rc


def clear_ahead(front_r: float, q: complex, r: float, beta: float, kappa: float,
                rc: float) -> bool:
    """Tell whether the circle followed round ``q`` passes the front ray's hit at ``rc``.

    Parameters
    ----------
    front_r : float, m
        The front ray's range: the hit lies at ``front_r`` straight ahead.
    q : complex
        The nearest point followed, in the law's frame.
    r, beta, kappa : float
        Its range (m), tangent angle from the heading (rad) and curvature (1/m, convex
        negative).
    rc : float, m
        The following distance.

    Returns
    -------
    bool
        True when the robot circles a small convex thing, engaged on it, and the circle
        passes the hit at least ``(1 - LENS) rc`` away (:func:`circle_clearance`).
    """
    clearance = circle_clearance(complex(front_r, 0.0), q, r, beta, kappa, rc)
    return clearance is not None and clearance >= -LENS * rc


def apart_behind(q: complex, p: complex, r: float, rc: float) -> bool:
    """Tell whether a point circled out of view and the next face ``2 rc`` apart are two things.

    Two things ``2 rc`` or more apart have level sets of their own unless a face runs on
    from the one to the other; :func:`atoms.corners.next_face_weight` asks the scan whether
    one does (:func:`atoms.corners.recessed`). A point followed at or beyond an edge of the
    ladar's 180 deg (a pole or a vertex rounded from memory) cannot be told that way: the
    scan has no bearings there. But no face runs from it to ``p`` either: one that did would
    pass the robot nearer than it, in view, and be followed instead. So the next face gets
    no weight. (With the plain weight, 0.5-0.8, that the recess test left it, the robot
    circling the last pole seen turned towards the next one, 2.2-2.4 rc away.) Only while
    the robot is within ``2 rc`` of ``q``, as for the recess test.

    >>> apart_behind(complex(-0.2, -0.45), complex(0.9, 0.1), 0.5, 0.5)
    True
    >>> apart_behind(complex(0.1, -0.5), complex(0.9, 0.5), 0.51, 0.5)   # in view
    False
    """
    if not (r < 2.0 * rc and abs(p - q) >= 2.0 * rc):
        return False
    return abs(math.atan2(q.imag, q.real)) > 0.5 * math.pi - FOV_EDGE


def fillet_swing(gap: float, rc: float, radius: float) -> float:
    """Return how far outside ``rc`` a full-rate turn round a kink swings at its middle.

    The arc of radius ``radius`` tangent to the ``rc`` circles of two points ``gap`` apart
    has its centre on their bisector, ``rc + radius`` from both; its point nearest the
    chord lies ``sqrt(gap^2 / 4 + (h - radius)^2)`` from either point, with ``h`` the
    centre's distance from the chord. 0 for coincident points and for a robot that turns
    on the spot; about 0.1 m at ``2 rc`` with rc 0.5 and a turning radius of 1/3 m.

    >>> round(fillet_swing(0.8, 0.5, 1.0 / 3.0), 3), round(fillet_swing(1.0, 0.5, 1.0 / 3.0), 3)
    (0.064, 0.101)
    """
    half = 0.5 * min(gap, 2.0 * rc)
    h = math.sqrt(max((rc + radius) ** 2 - half * half, 0.0))
    return math.hypot(half, h - radius) - rc


def circle_on(p: complex, q: complex, r: float, beta: float, kappa: float, rc: float,
              radius: float) -> bool:
    """Tell whether going on round ``q`` costs less than turning onto the next face ``p``.

    Parameters
    ----------
    p : complex
        The next face's nearest point, in the law's frame.
    q : complex
        The nearest point followed.
    r, beta, kappa : float
        Its range (m), tangent angle from the heading (rad) and curvature (1/m, convex
        negative).
    rc : float, m
        The following distance.
    radius : float, m
        The least turning radius ``v / umax``.

    Returns
    -------
    bool
        True when the robot circles a small convex thing, engaged on it, and its circle
        (:func:`circle_clearance`) dips into ``p``'s ``rc`` band by no more than turning
        onto ``p`` would miss ``rc``: outward by the swing of the fillet
        (:func:`fillet_swing`) while the turn can still start in time, inward by as much
        as a full-rate turn from here passes inside ``rc`` once it is overdue
        (:func:`atoms.fillet.turn_margin`).
    """
    clearance = circle_clearance(p, q, r, beta, kappa, rc)
    if clearance is None:
        return False
    if clearance >= 0.0:
        return True  # the circle passes p outside rc: two closed level sets
    late = fillet.turn_margin(p, rc, radius)
    turn = fillet_swing(abs(p - q), rc, radius) if late >= 0.0 else -late
    return -clearance <= turn


def bridge_margin(beta: float, is_point: bool, fitted: float, quick: bool) -> float:
    """Return how much nearer a remembered point must be than the nearest one to be circled on.

    A fitted face on the followed side must be farther by the bridge margin ``fitted`` (its
    estimate is sound), a point (``is_point``) by 5 mm. A point on the other side (its
    tangent angle ``beta`` beyond a right angle: nothing seen on the followed side, the law
    would turn round to put it there) by nothing: going on round the point circled, which has
    just left the ladar's view behind the robot, beats that reversal. (With the margin, a
    table leg or pole circled from inside a gap near ``2 rc`` gave way to the next one on
    the left, 0.5 m off, and the robot turned into it.) ``quick``: the robot turns at full
    rate at once (:func:`atoms.fillet.full_rate_at_once`); one that ramps keeps the margins.
    """
    if quick and beta > 0.5 * math.pi:
        return 0.0
    return 0.005 if is_point else fitted
