"""The fillet at a sharp concave kink of the ``rc`` level set: when to turn, at full rate.

Where two things (a star's neighbouring tips, two legs) are closer than ``2 rc`` their
``rc`` level set is one curve with a concave kink between them: the arc round the point
followed ``q`` meets the arc round the next one ``p`` at an angle ``2 asin(|p - q| / 2 rc)``
(74-106 deg for tips 0.6-0.8 m apart at rc 0.5). A robot that turns at most ``umax`` cannot
follow a kink; the path nearest to it is the **fillet**: the arc of the least turning radius
``R = v / umax`` tangent to both ``rc`` circles. The robot circles ``q`` on its own law until
its full-rate left turning circle (for the boundary on the right: centre ``i R`` in the law's
frame) touches ``p``'s ``rc`` circle, then turns at full rate and ends tangent to it.

Blending the next point's law in over the last ``rc`` before the kink, as
:func:`atoms.corners.next_face_weight` does, starts that turn early and slowly: the robot
swings out to 0.65-0.7 m at each kink and no kink is recovered before the next (the distance
error's time constant at 1 m/s is about one arc). The fillet is used only where its
construction holds:

* the robot is **engaged** on ``q``: within :data:`ENGAGED` x ``rc`` of ``rc`` and moving along
  its circle (the tangent within :data:`ALONG` of the heading). While capturing, the turning
  circle says nothing about the path;
* ``p`` and ``q`` are closer than ``2 rc`` and a recess lies between them
  (:func:`atoms.corners.recessed`): one level set with a concave kink;
* the kink is **sharp**: at least :data:`SHARP`. A shallower kink (a wide gap in a pole row)
  is rounded well enough by the blend;
* the turn is **not overdue**: it starts where the turning circle touches ``p``'s circle, not
  once it lies well inside it (a next leg seen late: the arc would not end tangent);
* the robot reaches the full rate **at once** (:func:`full_rate_at_once`), or its turn rate
  is known to ramp at a known rate from a known rate (a :class:`~atoms.ramped_arcs.Ramp`):
  then the full turn is the ramped one, a spiral wider than the circle, and the turn starts
  where that spiral touches ``p``'s circle (:func:`turn_margin_on`). Without it, the
  Pioneer cut each kink of a star whose tips are 0.92-1.0 x ``2 rc`` apart to 0.36 m at rc
  0.55, then circled the next tip 0.15 m inside rc: its distance loop (0.6 rad/s at 0.3
  m/s) had not recovered before the next kink.

Once started, the turn goes on, ``p`` remembered by the caller, until ``p`` is abeam or is
the point followed with the robot heading along its circle (:func:`fillet_rate`).

Where the tips are a little more than ``2 rc`` apart (1.0-1.3 x) the level set runs into the
notch and its kink lies between the two flanks' offsets, just past the tip's arc: the robot
rounding the tip is ``2 rc`` or more from the next flank's point, and :func:`notch_turn`
says when the full left turn is due there.

Points are complex numbers ``x + iy`` in the law's frame (right-hand following; the caller
mirrors the left side).

>>> round(math.degrees(kink_angle(0.7, 0.5)), 1)      # tips 0.7 m apart at rc 0.5
88.9
>>> round(turn_margin(complex(0.6, -0.5), 0.5, 1.0 / 3.0), 3)  # p ahead: 0.19 m to go
0.194
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mdle.atoms import corners
from mdle.atoms.ramped_arcs import Ramp, turn_margin, turn_margin_on

if TYPE_CHECKING:
    import numpy as np

__all__ = ["fillet_rate", "full_rate_at_once", "kink_angle", "notch_turn", "turn_margin",
           "turn_margin_on",
           "ENGAGED", "ALONG", "SHARP"]

#: The robot counts as engaged on the point followed within this many ``rc`` of ``rc``.
ENGAGED = 0.3
#: ... and with the point's tangent within this angle of the heading (rad).
ALONG = math.radians(35.0)
#: The fillet is used at kinks of the level set at least this sharp (rad).
SHARP = math.radians(60.0)
#: The ramp to the full rate may take at most this share of the sharpest fillet's arc.
RAMP_SHARE = 0.1
#: A fillet under way goes on while a full-rate turn passes the point turned onto within
#: this many ``rc`` of ``rc`` (the tick's step and the point's noise).
ONTO_SLACK = 0.1
#: The point followed is the one turned onto when within this many ``rc`` of it (the fit's
#: window, :data:`atoms.closest.FIT_RADIUS`).
FIT = 0.5


def kink_angle(gap: float, rc: float) -> float:
    """Return the turn of the ``rc`` level set at the kink between two points ``gap`` apart.

    The ``rc`` circles round two points closer than ``2 rc`` cross where both radii are
    ``rc``; the tangents there are perpendicular to the radii, so the level set turns by the
    angle between them, ``2 asin(gap / 2 rc)`` (0 for coincident points, 180 deg at ``2 rc``,
    where the circles only touch). NaN-free: a gap of ``2 rc`` or more gives ``pi``.
    """
    return 2.0 * math.asin(min(gap / (2.0 * rc), 1.0))


def full_rate_at_once(u: float, umax: float, turn_accel: float) -> bool:
    """Tell whether the robot reaches a full-rate left turn from ``u`` fast enough for an arc.

    The plain fillet is an arc at the full rate, started at the last moment: it holds for a robot
    whose ramp from the rate now to ``umax`` takes no more than :data:`RAMP_SHARE` of the
    time the arc takes at the sharpest kink it is used for (:data:`SHARP`), ``SHARP /
    umax``. The ideal unicycle (no limit) turns at once; the Pioneer 3-DX (8.7 rad/s, at most
    1.7 rad/s^2) would need about five seconds, and fillets on its ramped turn instead
    (:func:`turn_margin_on`).
    """
    if not turn_accel < math.inf:
        return True
    return (umax - u) / turn_accel <= RAMP_SHARE * SHARP / umax


def fillet_rate(z: "np.ndarray", q: complex, p: complex | None, r: float, beta: float,
                u: float, v: float, rc: float, umax: float,
                target: complex | None = None, ramp: Ramp | None = None
                ) -> tuple[float | None, complex | None]:
    """Return the turn rate at a sharp concave kink, and the point the fillet turns onto.

    Parameters
    ----------
    z : complex array (M,)
        The scan points in the law's frame (right-hand).
    q : complex
        The point followed.
    p : complex or None
        The next face's nearest point (None: no next face).
    r, beta : float
        The range (m) and tangent angle (rad) of the point followed.
    u : float, rad/s
        The point followed's own law (what is kept until the turn).
    v, rc, umax : float
        Speed (m/s), following distance (m), the largest turn rate (rad/s).
    target : complex or None
        The point a fillet under way turns onto, as seen now (None: no fillet under way).
    ramp : Ramp or None
        How the robot's turn rate climbs to ``umax`` (None: at once).

    Returns
    -------
    (float or None, complex or None)
        The turn rate: ``umax`` while the fillet turns (from when a full-rate left turn is the
        last that keeps ``p`` outside ``rc`` until ``p`` is abeam: the path ends tangent to
        its ``rc`` circle), ``u`` just before it; None where the fillet does not apply (see
        the module's conditions) and the next face's blend decides. Then the point turned
        onto (None once the turn is over), for the caller to remember.
    """
    if not (umax > 0.0 and v > 0.0):
        return None, None
    if target is not None and _under_way(q, beta, target, rc, v, umax, ramp):
        # under way: the nearest point may already be the one turned onto, whose own law
        # (heading in by up to half the kink) would cut inside its rc circle
        return umax, target
    if p is None:
        return None, None
    if abs(r - rc) > ENGAGED * rc or math.cos(beta) < math.cos(ALONG):
        return None, None  # capturing: the turning circle says nothing about the path yet
    gap = abs(p - q)
    if not gap < 2.0 * rc or kink_angle(gap, rc) < SHARP:
        return None, None
    margin = turn_margin_on(p, rc, v, umax, ramp)
    # the recess test is a dozen numpy calls: asked last, and only where the answer matters
    # (the blend would weigh the next face in, or the turn is near)
    if margin > rc and abs(p) >= r + rc:
        return None, None
    if not corners.recessed(z, q, p, rc):
        return None, None
    if margin < -ONTO_SLACK * rc:
        # already well past the tick where the turn should have started (a next face seen
        # late, or the robot off its circle): no fillet fits; the blend decides
        return None, None
    return (umax, p) if margin <= 0.0 else (u, None)


def notch_turn(z: "np.ndarray", q: complex, p: complex, rc: float, v: float,
               umax: float) -> bool:
    """Tell whether a full left turn must start now onto a next face ``2 rc`` or more away.

    Between two tips 1.0-1.3 x ``2 rc`` apart the ``rc`` level set runs into the notch: the
    offsets of its two flanks meet at a concave kink of 110-130 deg, only 0.3-0.5 m past
    the arc round the tip. The robot rounding the tip still follows the tip itself (or
    remembers it), ``2 rc`` or more from the next flank's nearest point ``p``, so neither the
    fillet nor the next face's weight applies (two things that far apart have level sets of
    their own). Its own law went on turning right round the tip until the next flank was
    nearest, then at 70-85 deg and ``rc`` + 0.1 m: even a full turn from there cut the next
    tip to 0.36 m. A full left turn is due from the tick it is the last that keeps ``p``
    outside ``rc`` (:func:`turn_margin` at most 0), ``p`` ahead, with a recess between
    (:func:`atoms.corners.recessed`). A robot on its circle round ``q`` passes a separate
    thing ``2 rc`` or more from it at ``rc`` or more, so the turn is due there only at the
    edge (a pole of a row, a table's leg: in the lab suite some such runs moved by 0.01-0.03 m
    of the mean |d - rc|, either way, all under 0.05 m).
    For a robot that turns at full rate at once.

    >>> import numpy as np
    >>> notch_turn(np.array([0.7 - 0.3j]), -0.4 - 0.4j, 0.7 - 0.3j, 0.5, 1.0, 3.0)  # 0.11 m to go
    False
    """
    if p.real <= 0.0 or abs(p - q) < 2.0 * rc:
        return False  # behind, or near enough for the fillet and the weight to decide
    if turn_margin(p, rc, v / umax) > 0.0:
        return False
    # the recess test (a dozen numpy calls) only where the turn is due
    return corners.recessed(z, q, p, rc)


def _under_way(q: complex, beta: float, target: complex, rc: float, v: float, umax: float,
               ramp: Ramp | None) -> bool:
    """Tell whether a fillet onto ``target`` goes on: until the path is tangent to its circle.

    It is over once ``target`` is abeam or behind, once the point followed is the one turned
    onto and the robot heads along its circle or out (``beta <= 0``), or once even a full
    turn would pass it well outside ``rc`` (:data:`ONTO_SLACK`: the fillet was started on a
    point that moved).
    """
    if target.real <= 0.0:
        return False
    if abs(q - target) < FIT * rc and beta <= 0.0:
        return False
    return turn_margin_on(target, rc, v, umax, ramp) <= ONTO_SLACK * rc
