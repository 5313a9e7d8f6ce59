"""The boundary from the whole scan: the nearest boundary point on the followed side.

The two-ray law of :mod:`atoms.steering` sees the world through the beams at 0 and -90 deg.
A thin pole beside the robot, a tip between the rays or two things closer than ``2 rc`` are
invisible to it or wrongly shaped in it. This module is the closest-point formulation of the
same group's companion work (Zhang, Justh and Krishnaprasad, "Boundary following using
gyroscopic control", CDC 2004): the law reads the range ``r``, the tangent angle ``beta``
and the curvature ``kappa`` of the **nearest point of everything seen** on the followed
side, estimated from the scan points around it.

Following ``r = rc`` to the nearest point of the union of the scan points is following the
``rc`` level set of their distance function. Where two things are closer than ``2 rc`` that
level set is one curve with a concave corner over the gap: the nearest point jumps from one
to the other there, so the robot neither squeezes in between nor weaves. The cusp between
two touching discs is such a corner too.

Everything is in the law's frame (right-hand following; the left side is mirrored by the
caller), as for :mod:`atoms.steering`: ``beta`` is the tangent's angle from the heading
(the boundary oriented with the obstacle on its right), ``kappa`` is convex negative, and the
nearest point lies at bearing ``beta - pi/2``.

The pieces:

* :func:`nearest_point`: the nearest followed-side scan point and a local quadratic fit of the
  points around it (range, tangent, curvature);
* :func:`atoms.tips.ends_at_nearest`: whether that fit runs on past the end of what the scan
  saw (a tip seen from one flank), where the nearest point is a point;
* :func:`closest_law`: the closest-point CLF law, with ``V = 4 sin^2(beta/4) + g(r)``;
* :func:`step`: one tick: the nearest point of the scan, or of the memory when the point the
  robot turns around has left the ladar's field of view, the front ray's anticipation of a
  concave corner ahead, and the search for a boundary that was lost.

The searches over the scan points (the nearest point, the fit's window, the next face) are
:mod:`atoms.searches`'s, compiled where the install built them (the same answers).

>>> g = Gains()
>>> near = Ray(True, 0.5, 0.0, -1.0)       # on a circle of radius 1, rc = 0.5 away
>>> round(closest_law(near, 1.0, 0.5, g, 3.0), 6)  # the offset-curve rate v k / (1 - k rc)
-0.666667
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mdle.atoms import corners, fillet, pinch, searches
from mdle.atoms.ramped_arcs import Ramp
from mdle.atoms.steering import (
    CORNER,
    FOLLOW,
    FOV_EDGE,
    MISS,
    SEARCH,
    Gains,
    Memory,
    Ray,
    _valid_front,
    clf_law,
    f_gain,
    wrap,
)
from mdle.atoms.tips import ends_at_nearest

if TYPE_CHECKING:
    import numpy as np

__all__ = ["nearest_point", "closest_law", "step", "FIT_RADIUS", "REACH"]


#: Points within this many ``rc`` of the nearest point are fitted (0.25 m at rc 0.5: about
#: as much wall as the two-ray law's 30-degree side window, and no more than one pole).
FIT_RADIUS = 0.5
#: With nothing on the followed side, a point on the other side counts up to this many
#: ``rc`` away (the two-ray law's front gate): anything the safety layer can swerve for.
REACH = 3.0
#: A point is the nearest of its face when no beam within this many on either side is nearer.
WINDOW = 10
#: Neighbouring points farther apart than this lie on different surfaces (m).
JUMP = 0.2
#: The curvature of a point (a vertex, a tip, a pole seen by one beam): a circle of 1 cm.
POINT_KAPPA = -100.0
#: A fit whose residuals exceed this fraction of the range (plus 3 mm) is no circle: the
#: nearest point is taken as a point (1.5 times the LMS-200's 0.8 % range noise).
FIT_TOLERANCE = 0.012


def nearest_point(z: "np.ndarray", radius: float) -> Ray:
    """Return the nearest boundary point on the right of ``z`` as a :class:`Ray`.

    Parameters
    ----------
    z : complex array (M,)
        Scan points ``x + iy`` in the law's frame (right-hand; the caller mirrors for left).
    radius : float, m
        The points within this distance of the nearest one are fitted.

    Returns
    -------
    Ray
        ``r`` the distance to the fitted boundary, ``beta`` its tangent's angle from the
        heading, ``kappa`` its curvature there (convex negative); :data:`MISS` when no
        point lies on the right.

    A circle (or a line) ``h = a + b s + c (s^2 + h^2)`` is fitted by least squares in the
    frame of the nearest point ``q`` (``s`` perpendicular to the line of sight, ``h`` towards
    the robot), linear in ``a, b, c`` (a Kasa fit, stable for a straight wall, where
    ``c = 0``). The boundary's nearest point to the robot is then the fitted circle's: the
    range is ``-G(P) / M`` with ``G(s, h) = c (s^2 + h^2) + b s - h + a`` at the robot and
    ``M = |grad G| / 2 + sqrt(b^2 / 4 + 1/4 - a c)``, its direction ``grad G``, and the
    curvature ``2 c / sqrt(1 + b^2 - 4 a c)``. A pole or a vertex at the edge of the ladar's
    field of view is seen on one side only: the circle through its points carries on where
    the boundary does. The nearest of several noisy points is biased towards the robot (a
    minimum); the fit is not. With fewer than three points (a pole seen by one or two beams)
    the point itself is used: range ``|q|``, tangent perpendicular to the line of sight, and
    the curvature of a point (a circle of radius 1 cm).

    >>> import numpy as np
    >>> s = np.linspace(-0.3, 0.3, 31)
    >>> wall = s - 0.5j                       # a wall 0.5 m to the right, along the heading
    >>> ray = nearest_point(wall, 0.25)
    >>> round(ray.r, 6), round(ray.beta, 6), round(ray.kappa, 6)
    (0.5, 0.0, 0.0)
    """
    x, y = z.real, z.imag
    d2 = x * x
    d2 += y * y
    return _nearest(z, d2, radius)[0]


def _nearest(z: "np.ndarray", d2: "np.ndarray", radius: float, reach_rc: float = 0.0
             ) -> tuple[Ray, "np.ndarray | None"]:
    """Return :func:`nearest_point` given the squared ranges, and the fitted points' mask.

    With nothing on the right, the nearest point on the left counts if it lies within
    :data:`REACH` x ``reach_rc``.
    """
    if z.shape[0] == 0:
        return MISS, None
    # the followed (right) side only; squared ranges (a square root costs as much as a call)
    k = searches.nearest_right(z, d2)
    r2 = float(d2[k]) if k >= 0 else math.inf
    if not r2 < math.inf:
        # nothing on the followed side: something seen near on the other side is followed
        # too (the law turns to put it on the followed side), up to the reach
        k = int(d2.argmin())
        r2 = float(d2[k])
        if not r2 < (REACH * reach_rc) ** 2:
            return MISS, None
    if not r2 > 0.0:
        return MISS, None
    q = z.item(k)  # a Python complex (complex(z[k]) makes a numpy scalar first)
    rq = math.sqrt(r2)
    n = q / rq  # unit line of sight, robot -> q
    t = complex(-n.imag, n.real)  # the tangent, obstacle on its right: i n
    sel = searches.within(z, q, radius)
    near = z[sel]
    for _ in range(2):
        # a window across a vertex or a cusp is no circle: halve it, then take the point
        ray = _fit(near, q, rq, t, radius)
        if ray is not None:
            return ray, sel
        radius *= 0.5
        near = near[abs(near - q) < radius]
    return Ray(True, rq, math.atan2(t.imag, t.real), POINT_KAPPA), sel


def _fit(near: "np.ndarray", q: complex, rq: float, t: complex, radius: float) -> Ray | None:
    """Fit a circle to the points ``near`` around ``q``; None if they are not on one.

    See :func:`nearest_point`; ``t`` is the unit tangent at ``q`` (``i q / |q|``).
    """
    import numpy as np

    m = near.shape[0]
    if m < 3:
        return None
    w = (near - q) * t.conjugate()  # s + i h: s along t, h along i t = -n (towards the robot)
    uu = (w * w.conjugate()).real  # s^2 + h^2
    s1h0 = complex(np.add.reduce(w))  # sum s + i sum h
    s2h1 = complex(np.dot(w.real, w))  # sum s^2 + i sum s h
    suuh = complex(np.dot(uu, w))  # sum s u + i sum u h
    u1 = float(np.add.reduce(uu))
    u2 = float(np.dot(uu, uu))
    h2 = u1 - s2h1.real  # sum h^2
    fit = _solve3(float(m), s1h0.real, u1, s2h1.real, suuh.real, u2,
                  s1h0.imag, s2h1.imag, suuh.imag)
    if fit is None:
        return None
    a, b, c = fit
    # residual sum of squares from the normal equations: a vertex or a cusp is no circle,
    # and a tip is what the robot turns around as a point
    rss = h2 - a * s1h0.imag - b * s2h1.imag - c * suuh.imag
    tol = FIT_TOLERANCE * rq + 0.003
    if rss > m * tol * tol:
        return None
    # the robot is at s = 0, h = rq
    gs, gh = 0.5 * b, c * rq - 0.5  # grad G / 2 there
    half = math.hypot(gs, gh)
    root2 = 0.25 * b * b + 0.25 - a * c
    if not (half > 0.0 and root2 > 0.0):
        return None
    r = -(c * rq * rq - rq + a) / (half + math.sqrt(root2))
    # direction robot -> nearest point in the local frame is grad G; the tangent is i times it
    nl = complex(gs, gh) / half
    foot = complex(0.0, rq) + r * nl  # the fitted nearest point, local frame
    if not (r > 0.0 and abs(foot) <= radius):
        return None  # no extrapolation beyond the fitted points
    if ends_at_nearest(w, foot, q + foot * t, rq):
        # a tip, a plate's end or a vertex seen from one side: the boundary ends at q, and
        # the level set turns round it as round a point
        return Ray(True, rq, math.atan2(t.imag, t.real), POINT_KAPPA)
    tan_ = complex(-nl.imag, nl.real) * t  # back into the law's frame
    kappa = c / math.sqrt(root2)
    beta = math.atan2(tan_.imag, tan_.real)
    if not (math.isfinite(beta) and math.isfinite(kappa)):
        return None
    return Ray(True, r, beta, kappa)


def next_nearest(z: "np.ndarray", d2: "np.ndarray", fitted: "np.ndarray") -> Ray:
    """Return the nearest point of another face or object than the one followed, as a point.

    ``d2`` holds the points' squared ranges, ``fitted`` marks the points around the
    nearest one (:func:`nearest_point`'s fit). A point is the nearest of its face when its
    range is the least of the :data:`WINDOW` beams on either side (a local minimum of the
    distance to the robot: the line of sight is perpendicular to the boundary there). The
    nearest such point outside ``fitted`` and less than 45 deg left of the heading is the
    next face the robot will meet: the next pillar of a row, the far disc of a cusp, the far
    wall of a concave corner. Returned with the tangent perpendicular to the line of sight
    and the curvature of a point; :data:`MISS` when there is none.
    """
    if z.shape[0] == 0:
        return MISS
    k = searches.next_face(z, d2, fitted, WINDOW, JUMP)
    if k < 0:
        return MISS
    p = z.item(k)
    return Ray(True, math.sqrt(float(d2[k])), math.atan2(p.real, -p.imag), POINT_KAPPA)


def _solve3(m: float, s1: float, u1: float, s2: float, su: float, u2: float, h0: float,
            h1: float, h2: float) -> tuple[float, float, float] | None:
    """Solve ``[[m s1 u1] [s1 s2 su] [u1 su u2]] (a b c) = (h0 h1 h2)`` (Cramer's rule).

    A line (``c = 0``) when the matrix is singular (points on a line through ``q``), None when
    that is singular too.
    """
    c00 = s2 * u2 - su * su
    c01 = s1 * u2 - su * u1
    c02 = s1 * su - s2 * u1
    det = m * c00 - s1 * c01 + u1 * c02
    if abs(det) > 1e-12 * max(m * s2 * u2, 1e-300):
        a = (h0 * c00 - s1 * (h1 * u2 - su * h2) + u1 * (h1 * su - s2 * h2)) / det
        b = (m * (h1 * u2 - su * h2) - h0 * c01 + u1 * (s1 * h2 - h1 * u1)) / det
        c = (m * (s2 * h2 - h1 * su) - s1 * (s1 * h2 - h1 * u1) + h0 * c02) / det
        return a, b, c
    det2 = m * s2 - s1 * s1
    if abs(det2) > 1e-12 * max(m * s2, 1e-300):
        return (h0 * s2 - s1 * h1) / det2, (m * h1 - s1 * h0) / det2, 0.0
    return None


def closest_law(near: Ray, v: float, rc: float, g: Gains, umax: float) -> float:
    """Return the closest-point CLF law's turn rate for the nearest point ``near`` (rad/s).

    With ``r``, ``beta``, ``kappa`` the nearest point's range, tangent angle and curvature,
    the nearest point moves along the boundary as the robot drives, and

        r' = -v sin(beta),   beta' = v k cos(beta) - u,   k = kappa / (1 - kappa r)

    (``k`` is the curvature of the level set through the robot). For
    ``V = 4 sin^2(beta/4) + g(r)`` with ``g' = f`` this law,

        u = v k cos(beta) - 2 v f(r) cos(beta/2) + mu sin(beta/2),

    gives ``dV/dt = -mu sin^2(beta/2) <= 0``; on ``beta = 0`` it keeps ``beta' = 2 v f``, so
    the only invariant set there is ``r = rc``. On it ``u = v k``, the turn rate of the curve
    offset by ``rc``. Near it the distance error obeys ``e'' + (mu/2) e' + 2 kf v^2 e = 0``
    whatever the curvature (the two-ray law's ``(1 - ks rs)^2`` is absent).
    """
    return closest_rate(near.r, near.beta, _offset_curvature(near.kappa, near.r, g), v, rc, g,
                        umax)


def _offset_curvature(kappa: float, r: float, g: Gains) -> float:
    """Return ``kappa / (1 - kappa r)``, concave curvature clamped (``1 - kappa r >= margin``)."""
    den = 1.0 - kappa * r
    margin = g.conc_margin
    return kappa / (margin if den < margin else den)


def closest_rate(r: float, beta: float, k: float, v: float, rc: float, g: Gains,
                 umax: float) -> float:
    """Return :func:`closest_law` given the level set's curvature ``k`` (1/m)."""
    u = v * k * math.cos(beta) - 2.0 * v * f_gain(r, rc, g) * math.cos(beta / 2.0) \
        + g.mu * math.sin(beta / 2.0)
    return -umax if -umax > u else (umax if umax < u else u)


def step(front: Ray, z: "np.ndarray", pose: tuple[float, float, float], t: float, dt: float,
         mem: Memory, v: float, rc: float, g: Gains, umax: float | None = None,
         filter_kappa: bool = True, turn_accel: float = math.inf,
         turn_rate: float | None = None) -> tuple[float, Ray]:
    """Run one tick of right-hand following on the nearest boundary point.

    Parameters
    ----------
    front : Ray
        The front ray (0 deg), right-hand convention: it anticipates a concave corner ahead,
        as in the two-ray law (front gate, blend and floor).
    z : complex array (M,)
        The scan points in the law's frame.
    pose : (x, y, theta)
        Odometry pose (m, m, rad) in the law's frame.
    t, dt : float, s
        Time since the atom started, and the tick length.
    mem : Memory
        Per-atom state, updated in place (``mem.mode``: follow while the scan's nearest point
        is used, corner while a remembered one behind the ladar's field of view is nearer,
        search while nothing is seen on the followed side).
    v, rc : float
        Speed (m/s) and following distance (m).
    g : Gains
    umax : float, rad/s, optional
    filter_kappa : bool
        Low-pass the level set's curvature (for estimates from a noisy scan).
    turn_accel : float, rad/s^2
        The robot's turn acceleration limit (a sharp kink's fillet needs the full rate at
        once: :mod:`atoms.fillet`).
    turn_rate : float or None, rad/s
        The turn rate the robot is predicted to have when this command acts (law frame;
        None: unknown). With a finite ``turn_accel`` the next face's corner floor turns on
        the ramp from it (:func:`atoms.corners.next_face_weight`).

    Returns
    -------
    (float, Ray)
        Turn rate u, rad/s, within +-umax, and the nearest point the law followed
        (:data:`MISS` when none).
    """
    umax = g.umax if umax is None else umax
    # the pinch rules (atoms/pinch.py) weigh a full-rate turn, as the fillet does: a robot
    # that ramps to it for seconds keeps the rules as they were
    quick = not turn_accel < math.inf or fillet.full_rate_at_once(0.0, umax, turn_accel)
    x, y, theta = pose
    front = _valid_front(front, rc, g)
    d2 = searches.squared_ranges(z)  # shared by the nearest point and the next face
    near, fitted = _nearest(z, d2, FIT_RADIUS * rc, rc)
    kept = _remembered(mem, x, y, theta)
    mode = FOLLOW
    if kept.hit:
        if not near.hit:
            # nothing on the followed side: circle the boundary point seen last, until the
            # scan shows the boundary again (a deflection, a face ending, a start that grazed)
            near, mode = kept, SEARCH
        elif kept.r < near.r - pinch.bridge_margin(near.beta, near.kappa == POINT_KAPPA,
                                                   g.bridge, quick) and _unseen(z, kept):
            # the point turned around (a vertex, the near side of a thin pole) is at the edge
            # of the ladar's field of view or beyond it: the faces it still sees are farther
            near, mode = kept, CORNER
    mem.mode = mode
    mem.time = t
    if not near.hit:
        if front.hit:  # seen ahead but nothing on the followed side yet: turn it there
            mem.seen = (x + front.r * math.cos(theta), y + front.r * math.sin(theta))
            mem.seen_at = t
            return _with_front(front, MISS, 0.0, v, rc, g, umax), MISS
        return 0.0, MISS  # nothing seen yet: straight on (the paper's virtual boundary)
    bearing = theta + near.beta - math.pi / 2.0
    foot = (x + near.r * math.cos(bearing), y + near.r * math.sin(bearing))
    k = _offset_curvature(near.kappa, near.r, g)
    if mode == FOLLOW:
        last = mem.near
        jump = last is None or math.hypot(foot[0] - last[0], foot[1] - last[1]) > g.kappa_reset
        if filter_kappa and g.tau > 0 and not jump and mem.kappa is not None:
            k = mem.kappa + (k - mem.kappa) * min(1.0, dt / g.tau)
        mem.kappa = k
        mem.near = foot
        mem.seen, mem.seen_at = foot, t
    u = closest_rate(near.r, near.beta, k, v, rc, g, umax)
    q = _point_of(near)
    if mode != FOLLOW:  # the point followed is remembered: the faces seen are all ahead
        fitted = searches.within(z, q, FIT_RADIUS * rc)
    ahead = next_nearest(z, d2, fitted) if fitted is not None else MISS
    p = _point_of(ahead) if ahead.hit else None
    # the pinch rules (atoms/pinch.py) while a small convex thing is circled
    circling = quick and near.kappa < 0.0 and -1.0 / near.kappa <= rc
    if circling and p is not None and umax > 0.0 \
            and pinch.circle_on(p, q, near.r, near.beta, near.kappa, rc, v / umax):
        ahead, p = MISS, None  # near a pinch, going on round costs less than turning
    turn = None
    # how the robot's turn rate climbs, where it does not jump (None: at once, or unknown)
    ramp = Ramp(turn_rate, turn_accel) if turn_rate is not None \
        and turn_accel < math.inf else None
    if (p is not None or mem.fillet is not None) and mode != SEARCH:
        # a sharp concave kink of the level set ahead, followed on: the fillet decides, on
        # the full rate reached at once or on the robot's ramp to it
        at_once = fillet.full_rate_at_once(u, umax, turn_accel)
        if at_once or ramp is not None:
            turn, onto = fillet.fillet_rate(z, q, p, near.r, near.beta, u, v, rc, umax,
                                            _local(mem.fillet, x, y, theta),
                                            None if at_once else ramp)
            mem.fillet = _odometry(onto, x, y, theta)
    if turn is not None:
        u = turn
    elif p is not None and not (quick and pinch.apart_behind(q, p, near.r, rc)):
        # the next face: its own law's turn rate, weighed in as it comes within rc of the
        # distance kept now (a concave corner of the rc level set ahead: turn before it)
        w = corners.next_face_weight(z, q, p, near.r, ahead.r, v, rc, umax, ramp)
        if w > 0.0:
            u_next = closest_rate(ahead.r, ahead.beta, _offset_curvature(POINT_KAPPA, ahead.r, g),
                                  v, rc, g, umax)
            if u_next > u:
                u += (w if w < 1.0 else 1.0) * (u_next - u)
    if turn is None and quick and p is not None and mode != SEARCH and u < umax \
            and umax > 0.0 and fillet.notch_turn(z, q, p, rc, v, umax):
        u = umax  # a notch's kink past the tip rounded: turn in time (atoms/fillet.py)
    if circling and front.hit and p is None \
            and pinch.clear_ahead(front.r, q, near.r, near.beta, near.kappa, rc):
        # nothing ahead to turn onto, and the circle followed passes what the front ray
        # hits: no wall to turn from
        front = MISS
    return _with_front(front, near, u, v, rc, g, umax), near


def _local(point: tuple[float, float] | None, x: float, y: float, theta: float
           ) -> complex | None:
    """Return an odometry-frame point in the law's frame at pose ``(x, y, theta)``."""
    if point is None:
        return None
    return complex(point[0] - x, point[1] - y) * complex(math.cos(theta), -math.sin(theta))


def _odometry(point: complex | None, x: float, y: float, theta: float
              ) -> tuple[float, float] | None:
    """Return a law-frame point in the odometry frame (the inverse of :func:`_local`)."""
    if point is None:
        return None
    w = point * complex(math.cos(theta), math.sin(theta))
    return (x + w.real, y + w.imag)


def _point_of(ray: Ray) -> complex:
    """Return the law-frame point a nearest-point ray stands for (bearing ``beta - pi/2``)."""
    return ray.r * complex(math.sin(ray.beta), -math.cos(ray.beta))


def _unseen(z: "np.ndarray", kept: Ray) -> bool:
    """Tell whether the scan leaves a remembered point standing (it may be out of view).

    True when the point lies at or beyond an edge of the ladar's 180 degrees (within
    :data:`atoms.steering.FOV_EDGE`: behind the robot, on either side), or when the beams at
    its bearing (within 1 deg) returned a point no farther than it (by 5 cm): the scan did
    not see through it.
    """
    import numpy as np

    bearing = wrap(kept.beta - math.pi / 2.0)
    if abs(bearing) > math.pi / 2.0 - FOV_EDGE:  # at the edge of the field of view or behind
        return True
    ang = np.angle(z)
    at = z[abs(ang - bearing) < math.radians(1.0)]
    return at.shape[0] > 0 and float(abs(at).min()) <= kept.r + 0.05


def _remembered(mem: Memory, x: float, y: float, theta: float) -> Ray:
    """Return the remembered nearest point, seen from the pose now, as a point (a vertex)."""
    p = mem.near if mem.near is not None else mem.seen
    if p is None:
        return MISS
    dx, dy = p[0] - x, p[1] - y
    r = math.hypot(dx, dy)
    if not r > 0.0:
        return MISS
    return Ray(True, r, wrap(math.atan2(dy, dx) - theta + math.pi / 2.0), POINT_KAPPA)


def _with_front(front: Ray, near: Ray, u: float, v: float, rc: float, g: Gains,
                umax: float) -> float:
    """Blend in the two-ray law's front law (gate, blend, floor) when the front ray hits."""
    if not front.hit:
        return u
    side = near if near.hit and math.cos(near.beta) > g.c_min else MISS
    gate = g.front_gate * rc
    w = min(max((gate - front.r) / (g.blend * gate), 0.0), 1.0)
    if w > 0.0:
        u = (1.0 - w) * u + w * clf_law(front, side, v, rc, g, umax)
    radius = v / umax if umax > 0 else math.inf
    margin = front.r * math.sin(front.beta) - radius * (1.0 - math.cos(front.beta))
    soft, hard = g.floor_soft * rc, g.floor_hard * rc
    floor = umax * min(max((soft - margin) / (soft - hard), 0.0), 1.0)
    return max(u, floor) if floor > 0 else u
