"""Concave corners of the ``rc`` level set: how much the next face's law is weighed in.

The whole-scan model (:mod:`atoms.closest`) follows the nearest point ``q`` of everything the
scan shows; the next face ``p`` is the nearest point of another face or thing ahead. Its own
law is blended in so that the robot turns before a concave corner of the level set rather
than at it. Whether there is such a corner depends on what lies between them:

* a recess (a gap between two things, a notch, a room's corner: :func:`recessed`) and
  ``|p - q| < 2 rc``: one level set with a concave corner, anticipated from the turning
  circle;
* a recess and ``|p - q| >= 2 rc``: two closed level sets; the robot circles the one it
  follows, and the next face has no weight;
* the scan running along the chord ``q p``: one face (the far face of a convex corner seen
  edge on among them); the plain weight.

Points are complex numbers ``x + iy`` in the law's frame (right-hand following).

>>> import numpy as np
>>> wall = np.linspace(-3.0, 3.0, 61) - 0.5j   # a wall seen end to end: no recess
>>> recessed(wall, complex(0.0, -0.5), complex(0.8, -0.5), 0.5)
False
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mdle.atoms.ramped_arcs import Ramp, turn_margin_on

if TYPE_CHECKING:
    import numpy as np

__all__ = ["next_face_weight", "recessed", "RANGE_NOISE", "CHORD_TOLERANCE"]

#: The LMS-200's range noise, a fraction of the range (its data sheet's 0.8 %).
RANGE_NOISE = 0.008
#: The scan between the point followed and the next face counts as recessed (a concave
#: corner of the level set between them) beyond this distance from their chord (m).
CHORD_TOLERANCE = 0.05


def next_face_weight(z: "np.ndarray", q: complex, p: complex, r: float, r_next: float,
                     v: float, rc: float, umax: float, ramp: Ramp | None = None) -> float:
    """Return the weight of the next face's law against the nearest point's (unclipped).

    The weight is ``(r + rc - r_next) / rc``: 0 until the next face comes within ``rc`` of
    the distance kept now, 1 when it is as near. Where the scan between the point followed
    ``q`` and the next face ``p`` lies beyond their chord (:func:`recessed`: a gap between
    two things, a notch, a room's corner), their ``rc`` level sets are

    * one curve with a concave corner when ``p`` and ``q`` are closer than ``2 rc``: the
      weight is then at least ``1 - m / rc``, where ``m`` is how far outside ``rc`` the next
      face stays on a full left turn from here (the margin to the turning circle of radius
      ``v / umax``). At 1 m/s the nearest point jumps to a table's next leg when that leg is
      already at ``rc``: too late to turn without it. With ``ramp`` (a robot whose turn
      rate ramps, :mod:`atoms.ramped_arcs`) the full left turn is the ramped one, whose
      path is wider: on the Pioneer (8.7 rad/s) the circle of radius ``v / umax`` is 3 cm
      and the floor never rose above the plain weight;
    * two closed curves when they are farther apart: the robot circles the one it follows,
      and the next face has no weight.

    Where the scan runs along the chord (one face, the far face of a convex corner seen edge
    on) the weight is as above, without the floor.

    The law uses the weight clipped to ``[0, 1]``. The scan is looked at (:func:`recessed`,
    a dozen numpy calls) only where its answer changes that: not when the floor is no more
    than the plain weight or the plain weight is 1 or more, nor when the plain weight is 0
    or less for two things apart.
    """
    w = (r + rc - r_next) / rc
    close = abs(p - q) < 2.0 * rc
    if not (close or r < 2.0 * rc):
        return w  # still approaching both (farther than 2 rc from the one)
    if not close:  # two closed level sets if recessed: no weight
        return w if w <= 0.0 or not recessed(z, q, p, rc) else 0.0
    radius = v / umax if umax > 0.0 else math.inf
    if not math.isfinite(radius) or w >= 1.0:
        return w
    # a robot whose rate ramps turns on a wider path than the circle of radius v / umax
    m = turn_margin_on(p, rc, v, umax, ramp)
    floor = 1.0 - m / rc
    if floor <= w or not recessed(z, q, p, rc):
        return w
    return floor


def recessed(z: "np.ndarray", q: complex, p: complex, rc: float) -> bool:
    """Tell whether the scan between bearings of ``q`` and ``p`` lies beyond the chord ``q p``.

    True when a point seen between them lies more than :data:`CHORD_TOLERANCE` (plus five
    times the range noise) beyond the chord, on the side away from the robot, or when the
    scan leaves a gap in the chord: more than ``rc / 2`` of it uncovered (the level set of
    points along it dips by less than 4 cm at rc 0.5 m for less) between two points that
    beams without a return separate (more than 1.75 times the scan's median beam spacing
    apart in bearing: a face seen at grazing incidence is sampled sparsely too, but by
    neighbouring beams).
    """
    import numpy as np

    ang = np.angle(z)
    a, b = math.atan2(q.imag, q.real), math.atan2(p.imag, p.real)
    inside = (ang > min(a, b)) & (ang < max(a, b))
    between = z[inside]
    chord = p - q
    length = abs(chord)
    # each point's place along the chord and its distance beyond it (the robot at 0 lies on
    # the other side), from one complex product
    w = (between - q) * (chord.conjugate() / length)
    if (chord.conjugate() * -q).imag > 0.0:
        w = w.conjugate()
    # five times the range noise on top: the chord's ends are noisy minima (about two sigma
    # nearer than the face) and the farthest of some fifty noisy points lies about 2.5 sigma
    # beyond it, so a far wall seen end to end is no notch
    if bool((w.imag > CHORD_TOLERANCE + 5.0 * RANGE_NOISE * abs(between)).any()):
        return True
    along = np.concatenate(([0.0], w.real, [length]))
    # bearings beyond the field of view are unknown, not a gap: the far face of a convex
    # corner behind the robot runs on along the chord
    first, last = float(ang[0]), float(ang[-1])
    bearing = np.concatenate(([min(max(a, first), last)], ang[inside],
                              [min(max(b, first), last)]))
    order = np.argsort(along)
    stretch = np.diff(along[order])
    turn = np.abs(np.diff(bearing[order]))
    spacing = math.inf
    if ang.shape[0] > 1:
        # the median beam spacing (np.median would import numpy.ma in the middle of a run)
        steps = np.diff(ang)
        spacing = float(np.partition(steps, steps.shape[0] // 2)[steps.shape[0] // 2])
    return bool(((stretch > 0.5 * rc) & (turn > 1.75 * spacing)).any())
