"""The seed paper's steering atom: ``follow_boundary(side, rc, v, ...)``.

Constant speed ``v``; the turn rate comes from the curvature-based CLF law of control-law.md
(:mod:`atoms.steering`) fed by the boundary view of this tick (:mod:`atoms.boundary`), with every
safeguard there (grazing-ray rejection, curvature clamps, front-range blend, front floor,
corner mode with odometry memory, saturation at the robot's turn-rate limit) and a full-scan
safety layer on top. Left-side following mirrors the law. Per-atom state (the corner memory
and the curvature filter) is made when the atom starts.

Each tick writes ``ctx.cache["trace"]``: front/side range (m), tangent (rad) and curvature (1/m)
in the side's convention (see :mod:`atoms.boundary`; left: convex positive), the side ray's
bearing (-pi/2 right, +pi/2 left: plots draw the boundary on that side), ``rc``, hit flags,
the mode (0 follow, 1 corner), the law's turn rate, whether the safety layer overrode it and
the predicted clearance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mdle.atoms import closest, safety, steering
from mdle.atoms.boundary import SIDES, Side, cached_beams, cached_view, parse_side
from mdle.atoms.latency import STILL, Predictor, compose, shift_front, shift_side
from mdle.atoms.ramped_arcs import Ramp
from mdle.atoms.registry import Args, Context, Param, Report, control_law, sensor
from mdle.atoms.steering import Gains, Memory
from mdle.atoms.turn_shaping import TurnShaper
from mdle.atoms.unwind import unwind_motion
from mdle.core.backend import Command
from mdle.core.units import ANGLE, CURVATURE, LENGTH, NONE, SPEED, TIME, TURN_RATE

if TYPE_CHECKING:
    from mdle.atoms.latency import Predictor
    from mdle.atoms.steering import Gains, Memory, Ray

__all__ = ["follow_boundary", "lost", "FollowState", "start_follow", "scan_points_cached",
           "scan_points_complex"]

#: The trace's ``mode`` field: 0 follow, 1 corner (circling a vertex), 2 search (the boundary
#: was lost: circling the point seen last).
_MODE_CODES = {"follow": 0.0, "corner": 1.0, "search": 2.0}


@dataclass
class FollowState:
    """Per-atom state of ``follow_boundary``: the side, the gains and the law's memory."""

    side: Side
    gains: "Gains"
    memory: "Memory"
    t0: float = 0.0
    """Backend time (s) at which the atom started: local time is ``obs.time - t0``."""
    latency: float | None = None
    """Command latency predicted over (s); None: no prediction (``latency = 0 s``)."""
    predictor: "Predictor | None" = None
    scan_model: bool = True
    """Follow the nearest boundary point of the whole scan (:mod:`atoms.closest`); False: the
    paper's two rays."""
    shaper: TurnShaper = field(default_factory=TurnShaper)
    """What the atom has seen of the robot's answer to turns away (:mod:`atoms.turn_shaping`)."""


def start_follow(args: Args, ctx: Context) -> FollowState:
    """Make the per-atom state when a ``follow_boundary`` atom starts."""
    umax = min(float(args["umax"]), ctx.limits.max_turn_rate)
    kf = float(args["kf"])
    # critical damping of e'' + (mu/2) e' + 2 kf v^2 e = 0 at this speed (docs/steering.md):
    # the approach then takes the same path length whatever v
    mu = 4.0 * float(args["zeta"]) * abs(float(args["v"])) * math.sqrt(2.0 * max(kf, 0.0))
    gains = Gains(mu=mu, kf=kf, umax=umax, tau=float(args["tau"]),
                  scaled_damping=str(args.get("damping", "scaled")) == "scaled")
    latency = float(args["latency"])
    if math.isinf(latency):
        latency = ctx.limits.command_latency
    predict = float(args["latency"]) != 0.0
    return FollowState(parse_side(args["side"]), gains, Memory(), ctx.obs.time - ctx.t,
                       latency if predict else None, Predictor() if predict else None,
                       str(args.get("model", "scan")) == "scan")


def scan_points_cached(ctx: Context) -> Any:
    """Return the robot-frame points (M, 2) of this tick's valid beams, once per tick.

    From the tick's :func:`atoms.boundary.cached_beams`, which the boundary view shares.
    """
    pts = ctx.cache.get("scan_points")
    if pts is None:
        import mdle.atoms.estimators as est  # numpy, on first use (not `from`: no __path__ probe)

        beams = cached_beams(ctx)
        if beams is None:
            import numpy as np

            pts = np.zeros((0, 2))
        else:
            pts = est.points_of(beams[0], beams[1])
        ctx.cache["scan_points"] = pts
    return pts


def scan_points_complex(ctx: Context) -> Any:
    """Return this tick's valid scan points as complex ``x + iy`` (M,), once per tick.

    :func:`scan_points_cached` without the round trip through (M, 2) floats: the beams'
    complex points, selected (what the safety layer's complex path reads).
    """
    z = ctx.cache.get("scan_points_z")
    if z is None:
        beams = cached_beams(ctx)
        if beams is None:
            import numpy as np

            z = np.zeros(0, dtype=complex)
        else:
            z = beams[0][beams[1]]
        ctx.cache["scan_points_z"] = z
    return z


#: With ``model = scan`` the side fields describe the nearest boundary point the law followed.
_NEAREST = {"front": "", "side": " (model = scan: the nearest boundary point followed)"}
#: What ``follow_boundary`` records each tick (``ctx.cache["trace"]``), with units.
REPORTS = {
    **{f"{ray}_{key}": report for ray in ("front", "side") for key, report in (
        ("hit", Report(flag=True, doc=f"the {ray} ray sees the boundary" + _NEAREST[ray])),
        ("range", Report(LENGTH, f"distance along the {ray} ray (0 without a hit)"
                                 + _NEAREST[ray])),
        ("tangent", Report(ANGLE, f"boundary direction at the {ray} hit")),
        ("curvature", Report(CURVATURE, f"boundary curvature at the {ray} hit")))},
    "side_bearing": Report(ANGLE, "where the side ray looks (the followed side), or where "
                           "the nearest point followed lies (model = scan)"),
    "rc": Report(LENGTH, "the distance kept from the boundary"),
    "mode": Report(codes=tuple(_MODE_CODES), doc="what the law is doing"),
    "lost": Report(TIME, "how long the boundary has been lost"),
    "u_law": Report(TURN_RATE, "the law's turn rate, before the safety layer"),
    "safety": Report(flag=True, doc="the safety layer replaced the law's command"),
    "predicted_clearance": Report(LENGTH, "clearance along the arc the safety layer checked",
                                  absent=-1.0),
}


@control_law(
    Param("side", default="right", choices=SIDES, doc="side the boundary is on: right or left"),
    Param("rc", LENGTH, 0.5, doc="distance to keep from the boundary", low=0.0, low_open=True),
    Param("v", SPEED, 0.3, doc="constant forward speed", low=0.0, low_open=True),
    Param("zeta", NONE, 1.0, doc="damping ratio of the distance loop (mu = 4 zeta v sqrt(2 kf))",
          low=0.0, low_open=True),
    Param("kf", NONE, 2.0, doc="distance gain of f(z) = kf (z - rc), 1/m^2", low=0.0,
          low_open=True),
    Param("umax", TURN_RATE, math.inf, doc="turn-rate limit (default: the robot's)", low=0.0,
          low_open=True, finite=False, commanded=False),
    Param("damping", default="scaled", choices=("scaled", "paper"),
          doc="scaled: quicker return to rc on curves and from far away; paper: as derived"),
    Param("model", default="scan", choices=("scan", "rays"),
          doc="scan: the nearest boundary point of the whole scan; rays: the paper's two rays"),
    Param("tau", TIME, 0.2, doc="low-pass time constant of estimated curvature (0: none)",
          low=0.0),
    Param("margin", LENGTH, 0.15, doc="clearance the safety layer keeps ahead (0: off)",
          low=0.0),
    Param("lookahead", TIME, 0.8, doc="how far ahead the safety layer checks the arc", low=0.0),
    Param("latency", TIME, math.inf,
          doc="command latency to predict over (default: the robot's; 0 s: no prediction, "
              "not even of the scan's age, and no turn-away shaping)", low=0.0, finite=False),
    start=start_follow,
    reports=REPORTS,
)
def follow_boundary(args: Args, ctx: Context, state: FollowState | None) -> Command:
    """Follow a boundary at distance rc on one side at constant speed (the paper's atom)."""
    if state is None:  # run without start (a bare call): make the state now
        state = start_follow(args, ctx)
    g = state.gains
    v = float(args["v"])
    rc = float(args["rc"])
    # the whole-scan model reads the side from every scan point: the side ray's fit is skipped
    view = cached_view(ctx, state.side, with_side=not state.scan_model)
    obs = ctx.obs
    pose = obs.pose
    left = state.side is Side.LEFT
    sgn = -1.0 if left else 1.0
    law_pose = (pose.x, sgn * pose.y, sgn * pose.theta)
    front, side = view.front, view.side
    moved = STILL
    acting_rate: float | None = None  # the turn rate when this command acts (law frame)
    pred = state.predictor
    if pred is not None and state.latency is not None:
        # answer the boundary as it will be when this command acts, not as it was scanned
        pred.record_pose(obs.time, law_pose)
        stamp = obs.scan.stamp if obs.scan is not None else obs.time
        ahead = pred.predict(obs.time, stamp, law_pose, obs.v, sgn * obs.omega,
                             state.latency, ctx.limits.max_accel, ctx.limits.max_turn_accel)
        moved, law_pose, acting_rate = ahead.moved, ahead.pose, ahead.omega
        if moved != STILL:
            front, side = shift_front(front, moved), shift_side(side, moved)
    z = scan_points_complex(ctx)  # the safety layer and the corner search read complex points
    if moved != STILL:
        z = _into(z, moved[0], sgn * moved[1], sgn * moved[2])
    # the law and the safety layer read the scan in the law's frame, so the left side is the
    # right side's exact mirror image (ties included)
    zl = z if sgn > 0 else _mirrored(z)
    zs = zl  # what the safety layer reads: the scan as when the command acts
    if state.scan_model and acting_rate is not None and state.shaper.jumps:
        front, zl, law_pose = _past_unwind(front, zl, law_pose, acting_rate, v,
                                           ctx.limits.max_turn_accel)
    if state.scan_model:
        u, side = closest.step(front, zl, law_pose, ctx.t, ctx.dt, state.memory, v, rc, g,
                               g.umax, filter_kappa=not view.exact,
                               turn_accel=ctx.limits.max_turn_accel, turn_rate=acting_rate)
    else:
        u = steering.step(front, side, law_pose, ctx.t, ctx.dt, state.memory, v, rc, g,
                          g.umax, filter_kappa=not view.exact,
                          near=lambda: _nearest_on_side(zl))
    u_law, v_law = sgn * u, v
    clearance = math.inf
    margin = float(args["margin"])
    if margin > 0 and v > 0:
        v, u, clearance = safety.filter_complex(zs, v, u, g.umax, ctx.limits.radius, margin,
                                                float(args["lookahead"]), side=-1,
                                                ramp=_ramp_back(state, acting_rate, ctx))
    u_safe = sgn * u  # what the safety layer let through (robot frame)
    turn_accel = ctx.limits.max_turn_accel
    if acting_rate is not None and turn_accel < math.inf:
        # a turn away no faster than the robot ramps one: a firmware that jumps to it turns a
        # one-tick spike into seconds of spinning off the boundary (atoms/turn_shaping.py)
        state.shaper.observe(obs.time, sgn * obs.omega, turn_accel)
        u = state.shaper.limit(u, acting_rate, turn_accel, ctx.dt)
    u *= sgn
    if pred is not None and state.latency is not None and state.latency > 0.0:
        # the commands in flight are read only to predict over a latency (Predictor.predict)
        pred.record_command(obs.time, v, sgn * u)
    f = view.front  # the trace shows what was measured (the side: what the law followed)
    s = side if state.scan_model else view.side
    if f.hit:
        fh, fr, fb, fk = 1.0, f.r, sgn * f.beta, sgn * f.kappa
    else:
        fh = fr = fb = fk = 0.0
    if s.hit:
        sh, sr, sb, sk = 1.0, s.r, sgn * s.beta, sgn * s.kappa
    else:
        sh = sr = sb = sk = 0.0
    mem = state.memory
    ctx.cache["trace"] = {
        "front_hit": fh, "front_range": fr, "front_tangent": fb, "front_curvature": fk,
        "side_hit": sh, "side_range": sr, "side_tangent": sb, "side_curvature": sk,
        # where the side ray looks (the followed side), or where the nearest point lies
        "side_bearing": sgn * (steering.wrap(s.beta - math.pi / 2) if state.scan_model and s.hit
                               else -math.pi / 2),
        "rc": rc,  # the distance it keeps: plots draw |d - rc| from the trace alone
        "mode": _MODE_CODES[mem.mode],
        "lost": mem.lost_for(ctx.t),
        "u_law": u_law,
        "safety": float(u_safe != u_law or v != v_law),
        "predicted_clearance": clearance if clearance < math.inf else -1.0,
    }
    return Command(v, u)


def _ramp_back(state: FollowState, rate: float | None, ctx: Context) -> Ramp | None:
    """Return how the robot's turn rate reaches a command, for the safety layer's arcs.

    On a robot known to jump to turns away (:mod:`atoms.turn_shaping`), hence to ramp its
    way back, whose turns away the shaper ramps too: every change of rate ramps at the
    robot's turn acceleration, from the rate predicted for when the command acts. Checked as
    if the command took at once, a turn back looked like a swing into the face the robot is
    still turning away from, and the layer wound the turn away up instead
    (:mod:`atoms.ramped_arcs`). None elsewhere (the arcs as always).
    """
    if rate is None or not state.shaper.jumps:
        return None
    return Ramp(rate, ctx.limits.max_turn_accel)


def _past_unwind(front: Ray, z: Any, pose: tuple[float, float, float], rate: float, v: float,
                 accel: float) -> tuple[Ray, Any, tuple[float, float, float]]:
    """Return the front ray, scan points and pose seen from where a turn away winds down.

    On a robot known to jump to turns away (:mod:`atoms.turn_shaping`), hence one that ramps
    its way back, a turn away at ``rate`` (law frame) goes on for ``rate / accel`` whatever
    is commanded: the law answers the boundary as seen from where most of it
    (:data:`atoms.unwind.SHARE`) has wound down (:mod:`atoms.unwind`).
    """
    d = unwind_motion(rate, v, accel)
    if d == STILL:
        return front, z, pose
    return shift_front(front, d), _into(z, d[0], d[1], d[2]), compose(pose, d)


def _nearest_on_side(z: Any) -> tuple[float, float] | None:
    """Return (distance, bearing) of the nearest scan point on the followed (right) side.

    ``z``: the scan points in the law's frame (complex, (M,); :func:`_mirrored` for left
    following). Distances are compared squared, as ``x x + y y`` (not the modulus, which
    rounds differently): the scan's ranges come in millimetres, so two beams are often
    equally near, and this picks the same one whichever way the points were made.
    """
    import numpy as np

    if z.shape[0] == 0:
        return None
    x, y = z.real, z.imag
    d2 = x * x  # full-length operations only (a reduction over the short axis is slow)
    d2 += y * y
    d2 = np.where(y < 0.0, d2, math.inf)  # never the other side
    k = int(d2.argmin())
    r2 = float(d2[k])
    if not r2 < math.inf:
        return None
    return math.sqrt(r2), math.atan2(float(y[k]), float(x[k]))


def _mirrored(z: Any) -> Any:
    """Return robot-frame scan points (complex, (M,)) in the left side's mirrored law frame.

    ``y -> -y`` *and* the beam order reversed, so the law reads the mirror image of the
    scan beam for beam: the scan runs right to left, and the law's argmin ties (ranges are
    whole millimetres: ties are common) and neighbour windows go by beam order. Conjugating
    alone would break every tie towards the other end of the scan than on the right side.
    """
    return z[::-1].conjugate()


def _into(z: Any, dx: float, dy: float, dth: float) -> Any:
    """Return robot-frame points (complex, (M,)) in the frame moved by ``(dx, dy, dth)``."""
    # as complex numbers: a shift and a rotation, two calls (no small arrays to build)
    return (z - complex(dx, dy)) * complex(math.cos(dth), -math.sin(dth))


@sensor(result=TIME)
def lost(args: Args, ctx: Context) -> float:
    """Return how long the running ``follow_boundary`` has lost its boundary (s).

    0 while one of its rays sees the boundary, before it has seen any, and when no
    ``follow_boundary`` atom runs; otherwise the time since a ray last saw it (the atom is
    searching meanwhile). ``(follow_boundary(...), lost > 5 s, 2 min)`` gives up a search.
    """
    state = ctx.atom
    if not isinstance(state, FollowState):
        return 0.0
    return state.memory.lost_for(ctx.obs.time - state.t0)
