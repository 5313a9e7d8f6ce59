"""The curvature-based boundary-following law (control-law.md), as plain numeric functions.

Everything is written for **right-hand** following (obstacle on the robot's right); left-hand
following mirrors its inputs and negates the turn rate (see :mod:`atoms.boundary` and
:mod:`atoms.follow`). Conventions, from control-law.md section 2:

* a :class:`Ray` carries the range ``r`` (m), the angle ``beta = phi - theta`` of the boundary's
  tangent relative to the heading (rad; tangents oriented with the obstacle on their right) and
  the signed curvature ``kappa`` (1/m; convex obstacles negative);
* a front hit from free space has ``sin(beta) > 0``, a side hit ``cos(beta) > 0``;
* the turn rate ``u`` is counter-clockwise positive.

The pieces:

* :func:`clf_law`: the CLF split law (curvature feedforward ``-B/A`` plus damping of the angle
  terms), with the concave clamps;
* grazing-ray rejection, the front-range gate with its linear blend, and the front floor (a
  soft emergency left turn), applied by :func:`step` to the rays of each tick;
* :func:`corner_law`: circling a remembered vertex (corner mode);
* :func:`step`: one tick with the mode state machine (follow, corner, search) and odometry
  memory: a boundary seen once and lost is searched for, never abandoned;

The full-scan safety layer that :mod:`atoms.follow` puts on top of the law is
:func:`atoms.safety.filter_complex`.

>>> g = Gains()
>>> side = Ray(True, 0.5, 0.0, -1.0)            # on a circle of radius 1, rc = 0.5 away
>>> round(step(MISS, side, (0.0, 0.0, 0.0), 0.0, 0.02, Memory(), 1.0, 0.5, g), 6)
-0.666667
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from collections.abc import Callable


__all__ = [
    "Ray",
    "MISS",
    "Gains",
    "Memory",
    "SideHit",
    "f_gain",
    "clf_law",
    "corner_law",
    "step",
    "wrap",
    "FOLLOW",
    "CORNER",
    "SEARCH",
    "FOV_EDGE",
]

FOLLOW = "follow"
CORNER = "corner"
SEARCH = "search"

#: The margin (rad) within which a point at or beyond an edge of the ladar's 180 degrees may
#: lie where the ladar did not look: the whole-scan model's memory counts a remembered point
#: there (circling a vertex keeps it at -90 deg, where the beam passes just behind), and a
#: fit's nearest point there may be a boundary that goes on unseen (:mod:`atoms.tips`).
FOV_EDGE = math.radians(2.0)


def wrap(a: float) -> float:
    """Wrap an angle to (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


# A named tuple rather than a frozen dataclass (as mdle.runtime.events.Sample): a tick
# makes several, and a frozen dataclass's __init__ costs about twice a named tuple's.
class Ray(NamedTuple):
    """What one ray of the law sees.

    A hit flag, the range (m), the tangent angle from the heading (rad, obstacle-on-right
    orientation) and the signed curvature (1/m, convex negative).
    """

    hit: bool
    r: float = math.nan
    beta: float = 0.0
    kappa: float = 0.0


#: A ray that saw nothing (the paper's virtual boundary takes over).
MISS = Ray(False)


@dataclass(frozen=True)
class Gains:
    """Gains and safeguard thresholds of the law (control-law.md section 5).

    SI units; the thresholds marked "x rc" are multiples of the following distance ``rc``.

    Attributes
    ----------
    mu : float, 1/s
        Damping of the angle terms (zeta = mu / (4 sqrt(2 kf)) on a straight wall).
    kf : float, 1/m^2
        Slope of ``f(z) = kf (z - rc)``, clipped at ``+-fmax`` (1/m).
    umax : float, rad/s
        Turn-rate saturation.
    s_min, c_min : float
        Grazing rejection: a front hit needs ``sin(beta) > s_min``, a side hit
        ``cos(beta) > c_min``.
    a0_min, a0_max : float
        Clamp of the front ray's rotation gain ``a0 = 1 - k0 r0 / sin b0``.
    conc_margin, d_min : float
        Concave clamps: ``1 - ks rs / cos bs >= conc_margin`` and ``D >= d_min``.
    eps_a : float
        Tikhonov regulariser of ``-B/A`` when the front ray hits.
    front_gate, blend : float
        Front hits count up to ``front_gate`` x rc; the front law is blended in linearly over the
        last ``blend`` fraction of that range.
    floor_hard, floor_soft : float, x rc
        Front floor: full left turn once the margin to the turning envelope is below
        ``floor_hard``, none above ``floor_soft``.
    corner_reach, corner_jump : float, x rc
        Corner mode starts only if the last side range was below ``corner_reach`` and the
        side ray is lost (a miss or a range jump above ``corner_jump``) ...
    corner_turn_jump : float, rad
        ... or the side tangent turned clockwise by more than this in the world frame.
    corner_exit_angle, corner_exit_range : float, rad and x rc
        Corner mode ends when the side ray is back on a face aligned with the path or turning
        towards it, ``bs > -`` exit angle, no farther than ``rs - d <`` exit range (d: distance
        to the remembered vertex; the paper: ``|bs|`` and ``|rs - d|`` below them) ...
    corner_max_turn : float, rad
        ... or after turning this much (or when the front ray hits).
    tau : float, s
        Low-pass time constant for estimated side curvature (0: none; exact data need none).
    kappa_reset : float, m
        The filter restarts when the side range jumps more than this.
    search_ahead : float, rad
        A lost boundary is searched for once the point seen last is further than this from
        the heading (closer to the heading, driving straight on approaches it).
    bridge : float, m
        In corner mode, a scan point on the followed side nearer than both ``rc`` and the
        vertex circled, by more than this, becomes the point circled (a notch narrower than
        ``2 rc`` is bridged, as the rc level set does).
    scaled_damping : bool
        Scale the side law's damping by ``min(1, rc/rs) / max(1, 1 - ks rs / cos bs)`` and, on
        a convex boundary, its distance term ``f`` by ``min(1 - ks rc, 2)^2`` (a quicker return
        to rc on convex curves, a line rather than a spiral from far away); False: the paper's
        damping and gain.
    """

    mu: float = 8.0
    kf: float = 2.0
    fmax: float = 2.0
    umax: float = 3.0
    s_min: float = 0.05
    c_min: float = 0.05
    a0_min: float = 0.5
    a0_max: float = 10.0
    conc_margin: float = 0.2
    d_min: float = 0.1
    eps_a: float = 0.05
    front_gate: float = 3.0
    blend: float = 0.4
    floor_hard: float = 0.5
    floor_soft: float = 1.5
    corner_reach: float = 2.0
    corner_jump: float = 0.5
    corner_turn_jump: float = math.radians(20.0)
    corner_exit_angle: float = math.radians(10.0)
    corner_exit_range: float = 0.25
    corner_max_turn: float = 1.9 * math.pi
    tau: float = 0.2
    kappa_reset: float = 0.3
    search_ahead: float = math.radians(75.0)
    bridge: float = 0.05
    scaled_damping: bool = True


@dataclass(frozen=True)
class SideHit:
    """The last valid side hit, as corner mode reads it (odometry frame of the law)."""

    r: float
    """Side range (m)."""
    tangent: float
    """World angle of the boundary's tangent there (rad)."""
    x: float
    """Where the side ray hit (m)."""
    y: float
    t: float
    """Local time of the hit (s)."""


@dataclass
class Memory:
    """Per-atom state of the law: the mode, the corner memory and the curvature filter.

    Made when the atom starts, dropped when it ends (never shared between atoms).
    """

    mode: str = FOLLOW
    last_side: SideHit | None = None
    """The last valid side hit (None: none yet)."""
    corner: tuple[float, float] = (0.0, 0.0)
    """The point circled in corner and search mode (odometry frame, m)."""
    turned: float = 0.0
    kappa: float | None = None
    last_rs: float = math.nan
    time: float = 0.0
    seen: tuple[float, float] | None = None
    """The boundary point a valid ray saw last (odometry frame, m); None: never seen."""
    seen_at: float = math.nan
    """Local time (s) at which a valid ray last saw the boundary (NaN: never)."""
    near: tuple[float, float] | None = None
    """The whole-scan model's nearest boundary point last seen (odometry frame, m)."""
    fillet: tuple[float, float] | None = None
    """The point a fillet turns onto while it is under way (odometry frame, m; None: none)."""

    def lost_for(self, t: float) -> float:
        """Return how long (s) the boundary has been lost at local time ``t``.

        0 while a ray sees it, and 0 if it was never seen (nothing to search for yet).
        """
        return 0.0 if self.seen is None else max(t - self.seen_at, 0.0)


def f_gain(z: float, rc: float, g: Gains) -> float:
    """Return the CLF's distance term ``f(z) = clip(kf (z - rc), -fmax, fmax)`` (1/m)."""
    return min(max(g.kf * (z - rc), -g.fmax), g.fmax)


def clf_law(front: Ray, side: Ray, v: float, rc: float, g: Gains, umax: float) -> float:
    """Return the CLF split law for already-validated rays (pass :data:`MISS` for a missing one).

    With the front missing this is the exact closed form
    ``u = v (ks - 2 f cos(bs/2)) / D + mu (1 - ks rs / cos bs) sin(bs/2)``,
    for which ``dV/dt = -mu sin^2(bs/2) as D / cos bs <= 0``; with a front hit the feedforward
    is the regularised ``-B A / (A^2 + eps^2)``. Returns the turn rate, rad/s, within +-umax.
    """
    # (runs every tick: the clamps are written out as min(max(x, lo), hi) evaluates them)
    fhit = front.hit
    if fhit:
        b0 = front.beta
        a0 = 1.0 - front.kappa * front.r / math.sin(b0)
        lo, hi = g.a0_min, g.a0_max
        a0 = lo if lo > a0 else a0
        a0 = hi if hi < a0 else a0
    else:
        b0 = a0 = 0.0
    if side.hit:
        bs, rs = side.beta, side.r
        cb = math.cos(bs)
        ks = side.kappa
        cap = (1.0 - g.conc_margin) * cb / rs
        ks = cap if cap < ks else ks
        as_ = 1.0 - ks * rs / cb
        f = f_gain(rs, rc, g)
        if g.scaled_damping and not fhit and ks < 0.0:
            # near rc the distance term acts through 1 / (1 - ks rs)^2, which softens the
            # return to rc on a convex curve (2.25x on radius 1 at rc 0.5): restore the wall's
            # stiffness with a gain that is constant along a constant-curvature boundary (so
            # this is still the CLF law, of a V with distance gain kf c)
            c = 1.0 - ks * rc if ks * rc > -1.0 else 2.0
            f *= c * c
    else:
        bs, rs, cb, ks, as_, f = 0.0, rc, 1.0, 0.0, 0.0, 0.0
    tb = math.sin(bs) / cb
    s1 = math.sin(b0 / 2.0)
    s2 = math.sin((b0 - bs) / 2.0)  # not wrapped: V uses quarter angles
    a_th = -a0 * s1 + s2 * (as_ - a0)
    a = a_th - f * rs * tb
    if fhit:
        b = -v * (s2 * ks / cb + f * tb)
        u_ff = -b * a / (a * a + g.eps_a * g.eps_a)
    else:
        ch = math.cos(bs / 2.0)
        d = cb - ks * rs + 2.0 * f * rs * ch
        d_min = g.d_min
        d = d_min if d_min > d else d
        u_ff = v * (ks - 2.0 * f * ch) / d
    if a * a_th > 0:
        damp = -a_th / (a0 if a0 > 1.0 else 1.0)
    else:
        aa = abs(a)
        damp = -a / (aa if aa > 1.0 else 1.0)
    if g.scaled_damping and not fhit and side.hit:
        # Any positive damping keeps dV/dt <= 0; two state-dependent scalings make the
        # distance converge faster. On a convex curve the angle term carries the factor
        # as = 1 - ks rs / cos bs > 1, which damps the return to rc as much as 2-3x
        # (measured on a circle): divide it out. Beyond rc the damping fades as rc / rs,
        # so the approach from far is a line at about 2 asin(v / (mu rc)) to the boundary
        # instead of a slow spiral (the paper's law needs over 40 s from 4.5 m at kf = 2).
        q = rc / rs
        damp *= (q if q < 1.0 else 1.0) / (1.0 if 1.0 > as_ else as_)
    u = u_ff + g.mu * damp
    u = -umax if -umax > u else u
    return umax if umax < u else u


def _valid_front(front: Ray, rc: float, g: Gains) -> Ray:
    if not front.hit or not math.isfinite(front.r):
        return MISS
    b0 = wrap(front.beta)
    if math.sin(b0) <= g.s_min or front.r > g.front_gate * rc:
        return MISS
    return front if b0 == front.beta else Ray(True, front.r, b0, front.kappa)


def _valid_side(side: Ray, g: Gains) -> Ray:
    if not side.hit or not math.isfinite(side.r) or side.r <= 0:
        return MISS
    bs = wrap(side.beta)
    if math.cos(bs) <= g.c_min:
        return MISS
    return side if bs == side.beta else Ray(True, side.r, bs, side.kappa)


def _blend_and_floor(front: Ray, side: Ray, v: float, rc: float, g: Gains, umax: float) -> float:
    if not front.hit:
        return clf_law(MISS, side, v, rc, g, umax)
    gate = g.front_gate * rc
    w = min(max((gate - front.r) / (g.blend * gate), 0.0), 1.0)
    u = clf_law(front, side, v, rc, g, umax) if w >= 1.0 else \
        (1.0 - w) * clf_law(MISS, side, v, rc, g, umax) + w * clf_law(front, side, v, rc, g, umax)
    # front floor: margin from the robot's tightest left-turn circle to the boundary's tangent
    radius = v / umax if umax > 0 else math.inf
    margin = front.r * math.sin(front.beta) - radius * (1.0 - math.cos(front.beta))
    soft, hard = g.floor_soft * rc, g.floor_hard * rc
    floor = umax * min(max((soft - margin) / (soft - hard), 0.0), 1.0)
    return max(u, floor) if floor > 0 else u


def corner_law(d: float, e: float, v: float, rc: float, g: Gains, umax: float) -> float:
    """Circle a point at distance ``d`` (m) seen at ``e = bearing + pi/2`` (rad).

    ``e`` is 0 when the point is straight to the right;
    ``u = -v cos(e)/d - 2 v f(d) cos(e/2) + mu sin(e/2)``, for which
    ``V_c = 4 sin^2(e/4) + g(d)`` has ``dV_c/dt = -mu sin^2(e/2)``.
    """
    d = max(d, 1e-3)
    u = -v * math.cos(e) / d - 2.0 * v * f_gain(d, rc, g) * math.cos(e / 2.0) \
        + g.mu * math.sin(e / 2.0)
    return min(max(u, -umax), umax)


def step(front: Ray, side: Ray, pose: tuple[float, float, float], t: float, dt: float,
         mem: Memory, v: float, rc: float, g: Gains, umax: float | None = None,
         filter_kappa: bool = True,
         near: "Callable[[], tuple[float, float] | None] | None" = None,
         ) -> float:
    """Run one tick of right-hand following with the corner mode and the curvature filter.

    Parameters
    ----------
    front, side : Ray
        Raw rays in the right-hand convention.
    pose : (x, y, theta)
        Odometry pose (m, m, rad), in the right-hand frame (mirrored for left following).
    t, dt : float, s
        Time since the atom started, and the tick length.
    mem : Memory
        Per-atom state, updated in place.
    v, rc : float
        Speed (m/s) and following distance (m).
    g : Gains
    umax : float, rad/s, optional
    filter_kappa : bool
        Low-pass the side curvature (for estimates from a noisy scan).
    near : function or None
        Returns the nearest scan point on the followed side as (distance, bearing) (m, rad
        in this frame) or None, for bridging notches in corner mode (see :class:`Gains`
        ``bridge``). Called only in corner mode: the search costs a pass over the scan.

    Returns
    -------
    float
        Turn rate u, rad/s, within +-umax. ``mem.mode`` tells which law produced it.
    """
    umax = g.umax if umax is None else umax
    x, y, theta = pose
    front = _valid_front(front, rc, g)
    side = _valid_side(side, g)
    if side.hit and filter_kappa and g.tau > 0:
        jump = not math.isfinite(mem.last_rs) or abs(side.r - mem.last_rs) > g.kappa_reset
        if mem.kappa is None or jump:
            mem.kappa = side.kappa
        else:
            mem.kappa += (side.kappa - mem.kappa) * min(1.0, dt / g.tau)
        side = Ray(True, side.r, side.beta, mem.kappa)
    mem.last_rs = side.r if side.hit else math.nan
    mem.time = t

    last = mem.last_side
    if mem.mode == FOLLOW and not front.hit and last is not None \
            and last.r < g.corner_reach * rc:
        lost = (not side.hit or side.r - last.r > g.corner_jump * rc
                or wrap(theta + side.beta - last.tangent) < -g.corner_turn_jump)
        if lost:
            mem.mode = CORNER
            mem.corner = (last.x, last.y)
            mem.turned = 0.0
    if mem.mode == FOLLOW and not front.hit and not side.hit and mem.seen is not None \
            and _abeam_or_behind(mem.seen, x, y, theta, g.search_ahead):
        # Both rays miss after the boundary was seen (a face ended beyond corner reach, a
        # deflection, a start that grazed the obstacle) and the point seen last is no longer
        # ahead: circle it, with the obstacle on the followed side, until a ray finds the
        # boundary again. (While it is ahead, driving straight on closes in on it.)
        mem.mode = SEARCH
        mem.corner = mem.seen
    nearest = near() if mem.mode == CORNER and near is not None else None
    if nearest is not None:
        # The point circled is a vertex seen earlier; a scan point on the followed side that
        # is nearer (the far face of a notch narrower than 2 rc) is what the rc level set
        # turns around now: circle it instead, so the robot bridges the notch rather than
        # following into it until the safety layer stops it.
        dc = math.hypot(mem.corner[0] - x, mem.corner[1] - y)
        if nearest[0] < min(dc, rc) - g.bridge:
            a = theta + nearest[1]
            mem.corner = (x + nearest[0] * math.cos(a), y + nearest[0] * math.sin(a))
    if mem.mode == CORNER:
        # the side is back on a face aligned with the path or converging on it (the far side
        # of a gap narrower than 2 rc, met obliquely) no farther than the vertex: follow it.
        # Circling the vertex on, the robot was held straight on towards that face.
        back = side.hit and side.beta > -g.corner_exit_angle \
            and side.r - math.hypot(mem.corner[0] - x, mem.corner[1] - y) \
            < g.corner_exit_range * rc
        if front.hit or back:
            mem.mode = FOLLOW
        elif mem.turned > g.corner_max_turn:
            mem.mode = SEARCH  # circled the vertex and never found the side: keep searching
        else:
            u = _circle(mem, x, y, theta, v, rc, g, umax)
            mem.turned += abs(u) * dt
            return u
    if mem.mode == SEARCH:
        if front.hit or side.hit:
            mem.mode = FOLLOW
        else:
            return _circle(mem, x, y, theta, v, rc, g, umax)
    if side.hit:
        ang = theta - math.pi / 2.0
        sx, sy = x + side.r * math.cos(ang), y + side.r * math.sin(ang)
        mem.last_side = SideHit(side.r, theta + side.beta, sx, sy, t)
        mem.seen, mem.seen_at = (sx, sy), t
    elif front.hit:
        mem.seen = (x + front.r * math.cos(theta), y + front.r * math.sin(theta))
        mem.seen_at = t
    return _blend_and_floor(front, side, v, rc, g, umax)


def _abeam_or_behind(point: tuple[float, float], x: float, y: float, theta: float,
                     ahead: float) -> bool:
    """Return True unless ``point`` lies within ``ahead`` (rad) of the heading."""
    return math.cos(math.atan2(point[1] - y, point[0] - x) - theta) < math.cos(ahead)


def _circle(mem: Memory, x: float, y: float, theta: float, v: float, rc: float, g: Gains,
            umax: float) -> float:
    """Return the point-circling law's turn rate around ``mem.corner`` (corner and search)."""
    cx, cy = mem.corner
    d = math.hypot(cx - x, cy - y)
    e = wrap(math.atan2(cy - y, cx - x) - theta + math.pi / 2.0)
    return corner_law(d, e, v, rc, g, umax)
