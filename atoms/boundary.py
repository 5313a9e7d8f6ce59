"""The boundary as the steering law sees it: range, tangent, curvature at the front and side rays.

:func:`boundary_view` turns one scan into a :class:`BoundaryView` for following on the right or
on the left; :func:`cached_view` computes it once per tick (in ``ctx.cache``) for every control
law and sensor function that asks. The sensor functions ``boundary_range(side)``,
``boundary_curvature(side)`` and ``boundary_tangent(side)`` read it.

Conventions (control-law.md):

* The view's rays are in the **law's frame**: right-hand following as is; for the left side the
  scan is mirrored (``y -> -y``, beam order reversed), so the right-hand law runs unchanged and
  its turn rate is negated. In that frame tangents are oriented with the obstacle on the right
  (convex curvature negative); a front hit has ``sin(beta) > 0`` and a side hit ``cos(beta) > 0``.
* The sensor functions answer in the robot's own frame with the side's orientation: for
  ``right`` the tangent angle ``phi - theta`` (obstacle on the right of the tangent) and the
  curvature (convex negative); for ``left`` the obstacle-on-left orientation of control-law.md
  (``phi_L = phi_R + pi``, ``kappa_L = -kappa_R``: convex positive).
* With an oracle scan (``Scan.tangents``/``Scan.curvatures`` filled, simulation with
  ``sensing="exact"``) the exact values at the two beams are used. Otherwise: the front ray takes
  the averaged geometric estimate (centred windows 7-9, or a one-sided chord near a surface's
  end); the side ray, where no beams exist beyond -90 deg, a local quadratic fitted over beams
  over the first ``side_span`` (30 deg) of beams (see :func:`_side_ray`). Windows never leave
  one connected surface.

numpy is imported on first use (this module declares sensor functions the checker loads).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any

from mdle.atoms.memo import ByIdentity
from mdle.atoms.registry import Args, Context, Param, sensor
from mdle.atoms.steering import MISS, Ray
from mdle.units import ANGLE, CURVATURE, LENGTH

if TYPE_CHECKING:
    import numpy as np

    from mdle.backend import Scan

__all__ = ["Side", "BoundaryView", "boundary_view", "cached_view", "parse_side",
           "boundary_range", "boundary_curvature", "boundary_tangent", "SIDES"]


class Side(enum.Enum):
    """Which side the followed boundary is on."""

    RIGHT = "right"
    LEFT = "left"


SIDES: tuple[str, ...] = tuple(s.value for s in Side)
#: Beams further than this from the wanted bearing do not count as that ray (radians).
_BEARING_TOL = math.radians(1.5)


def parse_side(value: Any) -> Side:
    """Convert ``right``/``left`` (a symbol or a :class:`Side`) to a :class:`Side`.

    >>> parse_side("left")
    <Side.LEFT: 'left'>
    """
    if isinstance(value, Side):
        return value
    try:
        return Side(str(value))
    except ValueError:
        raise ValueError(f"side must be one of {', '.join(SIDES)}, not {value!r}") from None


@dataclass(frozen=True)
class BoundaryView:
    """The rays the steering law reads, in the law's (right-hand, possibly mirrored) frame.

    Attributes
    ----------
    front, side : atoms.steering.Ray
    exact : bool
        True when the values come from an oracle scan (no estimation noise).
    max_range : float, metres
    """

    front: "Ray"
    side: "Ray"
    exact: bool
    max_range: float


@dataclass(frozen=True, eq=False)
class _Layout:
    """Which beams the view reads, for one bearing layout, side, side span and window set.

    Law-frame beam ``j`` is original beam ``j`` (right) or ``n-1-j`` (left). The view reads
    two runs of beams: the side run ``0 .. n_side-1`` and the front run ``f0 .. f1`` around
    the front beam ``c``. Both are gathered into one short array (``take``, original-frame
    indices), with their unit directions and link limits per unit range; the pair
    ``join, join+1`` (the last side beam and the first front beam) are not neighbours in the
    scan (``join`` is -1 without a side run). ``gap`` is the depth gap always accepted
    between neighbours (m).
    """

    c: int
    c_ok: bool
    s_ok: bool
    n_span: int
    n_side: int
    f0: int
    take: np.ndarray
    unit: np.ndarray
    spacing: np.ndarray
    join: int
    gap: float


@lru_cache(maxsize=32)
def _layout(key: bytes, left: bool, side_span: float, wmax: int) -> _Layout:
    """Return the :class:`_Layout` of the bearings ``key``.

    A pure function, memoised: one sensor always sends the same bearings.
    """
    import numpy as np

    from mdle.atoms.estimators import DEFAULT_GAP, DEFAULT_GAP_FACTOR

    b = np.frombuffer(key, dtype=np.float64)
    n = b.size
    if left:
        b = -b[::-1]
    c = int(np.argmin(np.abs(b)))
    c_ok = bool(abs(b[c]) <= _BEARING_TOL)
    s_ok = bool(abs(b[0] + np.pi / 2) <= _BEARING_TOL)
    step = abs(float(b[1] - b[0])) if n > 1 else 1.0
    n_span = max(4, int(round(side_span / step))) if step > 0 else 4
    n_side = min(n_span, n - 1) + 1 if s_ok else 0
    f0, f1 = (max(c - wmax, 0), min(c + wmax, n - 1)) if c_ok else (0, -1)
    law = np.concatenate((np.arange(n_side), np.arange(f0, f1 + 1)))
    take = n - 1 - law if left else law
    bl = b[law]
    unit = np.empty(bl.size, dtype=np.complex128)
    np.cos(bl, out=unit.real)
    np.sin(bl, out=unit.imag)
    spacing = DEFAULT_GAP_FACTOR * np.abs(bl[1:] - bl[:-1])
    for a in (take, unit, spacing):
        a.setflags(write=False)
    return _Layout(c, c_ok, s_ok, n_span, n_side, f0, take, unit, spacing, n_side - 1,
                   DEFAULT_GAP)


def _layout_of(bearings: Any, left: bool, side_span: float, windows: tuple[Any, ...]
               ) -> tuple[_Layout, tuple[int, ...]]:
    """Return the :class:`_Layout` of a bearing array and the windows as ints."""
    import numpy as np

    wins = tuple(int(w) for w in windows)
    b = np.ascontiguousarray(bearings, dtype=float)
    return _layout(b.tobytes(), left, float(side_span), max(wins)), wins


#: :func:`_layout_of` by the bearing array itself (a sensor's fixed bearings).
_layouts = ByIdentity(_layout_of, size=32)


def _run(links: list[bool], first: int, last: int, backwards: bool) -> int:
    """Count the consecutive links that hold from ``first`` on (towards ``last``, exclusive)."""
    seg = links[first:last]
    if backwards:
        seg.reverse()
    seg.append(False)
    return seg.index(False)


def _side_ray(z: "np.ndarray", r0: float) -> "Ray":
    """Fit the side ray to the first surface's beams 0..n (beam 0 at -90 deg), all valid.

    ``z`` holds their points as complex ``x + iy`` in the law frame.

    A quadratic ``h = a + b s + c s^2`` is fitted by least squares in the frame of the
    total-least-squares line through the points (centred, scaled by the span), and its slope
    and curvature are taken at the hit point, beam 0. Windows of three points (the paper's
    one-sided ``(P0, Pw, P2w)``) are far noisier at the side ray: at 0.5 m with 0.8 % range
    noise they give a curvature std of about 1.3 1/m and a tangent std of 6 deg; the fit over
    ``span = 30`` beams (about 0.27 m of wall) gives 0.22 1/m and 1.9 deg.

    Both fits are closed-form moments (no SVD): the line's direction is half the angle of
    ``sum(q^2)`` (``q`` the centred points as complex numbers, ``sum(q^2) = sxx - syy +
    2i sxy``), and the quadratic solves its 3x3 normal equations by Cramer's rule (falling
    back to ``lstsq`` when they are singular).
    """
    import numpy as np

    m = z.size
    if m < 5:
        return MISS
    total = complex(np.add.reduce(z))
    inv = 1.0 / m  # the mean as numpy's complex division by m computes it
    q = z - complex(total.real * inv, total.imag * inv)
    sq = complex(np.dot(q, q))  # unconjugated: sxx - syy + 2i sxy
    if not (math.isfinite(sq.real) and math.isfinite(sq.imag)):
        return MISS
    ang = 0.5 * math.atan2(sq.imag, sq.real)
    first, last = z[::m - 1].tolist()
    d = last - first  # orient the line first -> last point
    if math.cos(ang) * d.real + math.sin(ang) * d.imag < 0:
        ang += math.pi
    ang = math.atan2(math.sin(ang), math.cos(ang))
    w = q * complex(math.cos(ang), -math.sin(ang))  # s + i h in the line's frame
    s, h = w.real, w.imag
    scale = float(np.maximum.reduce(np.abs(s)))
    if not scale > 0:
        return MISS
    x = np.empty((3, m))
    x[0] = 1.0
    np.divide(s, scale, out=x[1])
    np.multiply(x[1], x[1], out=x[2])
    (a00, a01, a02), (_, a11, a12), (_, _, a22) = (x @ x.T).tolist()
    b0, b1, b2 = (x @ h).tolist()
    # Cramer's rule on the symmetric normal equations [[a00 a01 a02] [a01 a11 a12] [a02 a12 a22]]
    m00 = a11 * a22 - a12 * a12
    m01 = a01 * a22 - a12 * a02
    m02 = a01 * a12 - a11 * a02
    det = a00 * m00 - a01 * m01 + a02 * m02
    if abs(det) > 1e-12 * a00 * a11 * a22:
        c1 = (a00 * (b1 * a22 - a12 * b2) - b0 * (a01 * a22 - a12 * a02)
              + a02 * (a01 * b2 - b1 * a02)) / det
        c2 = (a00 * (a11 * b2 - b1 * a12) - a01 * (a01 * b2 - b1 * a02)
              + b0 * m02) / det
    else:  # fewer than three distinct abscissae: the minimum-norm solution, as lstsq gives
        coef = np.linalg.lstsq(x.T, h, rcond=None)[0]
        c1, c2 = float(coef[1]), float(coef[2])
    slope = (c1 + 2.0 * c2 * float(x[1, 0])) / scale
    kappa = 2.0 * c2 / scale ** 2 / (1.0 + slope * slope) ** 1.5
    return Ray(True, r0, ang + math.atan(slope), float(kappa))


def _front_ray(z: "np.ndarray", c: int, right: int, left: int, r0: float,
               windows: tuple[int, ...], exact: bool = False) -> "Ray | None":
    """Compute the front ray at local beam ``c`` of the points ``z`` (complex, law frame).

    Its surface extends ``right`` beams before and ``left`` beams after it.

    The averaged geometric estimate over the windows that fit (curvature of each window's
    circle and its tangent at the middle point, as :func:`atoms.estimators.geometric_curvature`
    computes them for the whole scan).
    ``right`` and ``left`` may be capped at ``max(windows)`` (all the estimate reads) unless
    ``exact``; None when no window gives an estimate and the one-sided chord needs the
    surface's true extent on both sides (only for degenerate, coincident points).
    """
    reach = min(right, left)
    ws = [w for w in windows if w <= reach] or ([reach] if reach >= 1 else [])
    if ws:
        # at most a few windows at one beam: Python complex arithmetic, where numpy's
        # per-call overhead on 3-element arrays would cost several times more
        pts = z[c - max(ws): c + max(ws) + 1].tolist()
        mid = max(ws)
        p = pts[mid]
        t_sum, k_sum, count = 0j, 0.0, 0
        for w in ws:
            u, v = p - pts[mid - w], pts[mid + w] - p
            chord = u + v
            av_c = abs(v) * abs(chord)
            den = abs(u) * av_c
            if not den > 0:  # coincident points: no circle
                continue
            cross = u.real * v.imag - u.imag * v.real
            dot = chord.real * v.real + chord.imag * v.imag
            # the circle's tangent at p: u turned by half the arc it spans (see estimators)
            t_sum += u * complex(abs(dot), cross) / av_c
            k_sum += 2.0 * cross / den
            count += 1
        if count:
            return Ray(True, r0, math.atan2(t_sum.imag, t_sum.real), k_sum / count)
    m = min(max(right, left), max(windows))
    if m >= 1:
        if not exact and min(left, right) >= max(windows):
            return None  # both capped: the side with the longer surface is not known here
        chord = complex(z[c + m] - z[c] if left >= right else z[c] - z[c - m])
        return Ray(True, r0, math.atan2(chord.imag, chord.real), 0.0)
    return Ray(True, r0, math.pi / 2.0, 0.0)  # an isolated return: a surface facing the robot


def boundary_view(scan: "Scan | None", side: Side | str = Side.RIGHT,
                  windows: Sequence[int] = (7, 8, 9),
                  side_span: float = math.radians(30.0)) -> BoundaryView:
    """Compute the front and side rays for following ``side`` from one scan.

    Only the beams the two rays need are read (the side fit's span from -90 deg, the front
    beam and its windows), with the scan's connectivity rule (:func:`atoms.estimators.surfaces`)
    applied to them.

    Parameters
    ----------
    scan : Scan or None
        None (no ladar yet) gives two misses.
    side : Side or "right" | "left"
    windows : sequence of int, beams
        Windows of the averaged geometric estimate (front ray).
    side_span : float, radians
        Bearing span of the beams in the side ray's local quadratic fit (30 beams on an
        LMS-200 at 1 deg).

    Returns
    -------
    BoundaryView (law frame; see the module docstring).

    Example: a wall 0.5 m to the right, parallel to the heading, seven beams.

    >>> import numpy as np
    >>> from mdle.backend import Scan
    >>> b = np.radians([-90.0, -80, -70, -60, -50, -40, 0])
    >>> r = np.append(0.5 / np.sin(-b[:6]), 10.0)
    >>> v = boundary_view(Scan(r, b, r < 10, 0.0, 10.0), "right", windows=(1,))
    >>> v.side.hit, round(v.side.r, 3), round(abs(v.side.beta), 6), round(abs(v.side.kappa), 6)
    (True, 0.5, 0.0, 0.0)
    >>> v.front.hit
    False
    """
    import numpy as np

    side = parse_side(side)
    if scan is None or scan.ranges.size == 0:
        return BoundaryView(MISS, MISS, False, math.inf if scan is None else scan.max_range)
    left = side is Side.LEFT
    lay, wins = _layouts(scan.bearings, left, side_span,
                         windows if type(windows) is tuple else tuple(windows))
    ranges = np.asarray(scan.ranges, dtype=float)
    valid = np.asarray(scan.valid, dtype=bool)
    n = ranges.size
    if scan.tangents is not None and scan.curvatures is not None:
        tangents, curvatures = scan.tangents, scan.curvatures

        def oracle(j: int) -> Ray:
            i = n - 1 - j if left else j  # law-frame beam j is original beam i
            r = float(ranges[i])
            if not (valid[i] and math.isfinite(r) and r > 0):
                return MISS
            t, k = float(tangents[i]), float(curvatures[i])
            if left:  # mirrored: the tangent reflects, the curvature keeps its sign
                t = math.pi - t
            if not (math.isfinite(t) and math.isfinite(k)):
                return MISS
            return Ray(True, r, math.atan2(math.sin(t), math.cos(t)), k)
        side_ray = oracle(0) if lay.s_ok else MISS
        if side_ray.hit and lay.n_side > 1:
            k = _turning_ahead(ranges, valid, tangents, curvatures, lay, left)
            if k is not None:
                side_ray = Ray(True, side_ray.r, side_ray.beta, side_ray.kappa + k)
        return BoundaryView(oracle(lay.c) if lay.c_ok else MISS, side_ray, True,
                            scan.max_range)
    r = ranges[lay.take]
    ok = valid[lay.take]
    ok &= r > 0
    # NaN where invalid; an infinite range stays, and neither is ever linked to a neighbour
    # (NaN and inf compare False below) nor taken as a ray's own beam (checked there)
    r = np.where(ok, r, np.nan)
    z = r * lay.unit
    lim = lay.spacing * r[:-1]
    np.maximum(lim, lay.gap, out=lim)
    links = (np.abs(z[1:] - z[:-1]) < lim).tolist()
    ns = lay.n_side
    if 0 <= lay.join < len(links):
        links[lay.join] = False  # the side run's last beam and the front run's first
    side_ray = MISS
    if ns:
        r0 = float(r[0])
        if math.isfinite(r0):
            end0 = _run(links, 0, ns - 1, backwards=False)
            side_ray = _side_ray(z[:min(end0, lay.n_span) + 1], r0)
    front = MISS
    cl = ns + lay.c - lay.f0
    if lay.c_ok:
        rc = float(r[cl])
        if math.isfinite(rc):
            right = _run(links, ns, cl, backwards=True)
            ahead = _run(links, cl, len(links), backwards=False)
            ray = _front_ray(z[ns:], cl - ns, right, ahead, rc, wins)
            if ray is None:  # degenerate window (coincident points): read the whole scan
                bearings = np.asarray(scan.bearings, dtype=float)
                ray = _front_full(ranges, bearings, valid, left, lay.c, rc, wins)
            front = ray
    return BoundaryView(front, side_ray, False, scan.max_range)


def _turning_ahead(ranges: "np.ndarray", valid: "np.ndarray", tangents: "np.ndarray",
                   curvatures: "np.ndarray", lay: _Layout, left: bool) -> float | None:
    """Return the curvature of the vertices ahead on the side ray's surface, spread (1/m).

    Over the boundary the side run's beams hit (from the side ray forward, up to the
    surface's end or ``side_span``), the exact tangent's total turning less what the exact
    curvature accounts for (the turning at vertices: a polygon's corners, a sampled curve's
    facet joints), divided by that length. Added to the exact curvature at the hit, it is
    the curvature a path following at about ``rc`` meets next: a polygon's exact curvature
    is 0 up to each vertex, so nothing anticipated the turn, and a sampled curve's facets
    are flat however fine the sampling. With it, both read as the noisy scan's fit sees them,
    and a smooth boundary is unchanged. None when the window has fewer than two beams on
    the side ray's surface.
    """
    import numpy as np

    ns = lay.n_side
    idx = lay.take[:ns]
    r = ranges[idx]
    ok = valid[idx] & np.isfinite(r) & (r > 0)
    z = np.where(ok, r, np.nan) * lay.unit[:ns]
    step = np.abs(z[1:] - z[:-1])
    link = step < np.maximum(lay.spacing[:ns - 1] * r[:-1], lay.gap)
    end = int(np.argmin(link)) if not link.all() else ns - 1  # beams 0..end on one surface
    if end < 1:
        return None
    t = tangents[idx[:end + 1]]
    if left:
        t = np.pi - t
    k = curvatures[idx[:end + 1]]
    seg = step[:end]
    # convex turning only: a concave corner ahead is the front ray's (its gate and floor)
    turn = min(float(np.angle(np.exp(1j * np.diff(t))).sum()
                     - (0.5 * (k[1:] + k[:-1]) * seg).sum()), 0.0)
    length = float(seg.sum())
    return turn / length if length > 0 and math.isfinite(turn) else None


def _front_full(ranges: "np.ndarray", bearings: "np.ndarray", valid: "np.ndarray", left: bool,
                c: int, r0: float, windows: tuple[int, ...]) -> "Ray":
    """Run :func:`_front_ray` with the true extent of the front beam's surface (whole scan)."""
    import numpy as np

    from mdle.atoms.estimators import surfaces

    if left:
        ranges, bearings, valid = ranges[::-1], -bearings[::-1], valid[::-1]
    s = surfaces(ranges, bearings, valid)
    z = np.ascontiguousarray(s.points).view(np.complex128).reshape(-1)
    ray = _front_ray(z, c, c - int(s.start[c]), int(s.end[c]) - c, r0, windows, exact=True)
    assert ray is not None
    return ray


def cached_view(ctx: Context, side: Side | str, windows: Sequence[int] = (7, 8, 9),
                side_span: float = math.radians(30.0)) -> BoundaryView:
    """Return :func:`boundary_view` of this tick's scan, computed once per tick and side."""
    side = parse_side(side)
    key = ("boundary", side is Side.LEFT, tuple(windows), side_span)  # no Enum.__hash__
    view = ctx.cache.get(key)
    if view is None:
        view = boundary_view(ctx.obs.scan, side, windows, side_span)
        ctx.cache[key] = view
    return view


_SIDE = Param("side", default="right", choices=SIDES,
              doc="which side the boundary is on: right or left")


@sensor(_SIDE, result=LENGTH)
def boundary_range(args: Args, ctx: Context) -> float:
    """Return the range to the boundary along the side ray (-90 deg for right, +90 deg for left).

    The sensor's maximum range when that ray sees no surface (or no scan has arrived).
    """
    view = cached_view(ctx, str(args["side"]))
    return view.side.r if view.side.hit else view.max_range


@sensor(_SIDE, result=CURVATURE)
def boundary_curvature(args: Args, ctx: Context) -> float:
    """Return the signed curvature of the boundary where the side ray hits it, 1/m.

    Right: the boundary oriented with the obstacle on its right (convex negative); left:
    obstacle on its left (convex positive). 0 (the paper's virtual boundary) with no hit.
    """
    side = parse_side(args["side"])
    view = cached_view(ctx, side)
    if not view.side.hit:
        return 0.0
    return view.side.kappa if side is Side.RIGHT else -view.side.kappa


@sensor(_SIDE, result=ANGLE)
def boundary_tangent(args: Args, ctx: Context) -> float:
    """Return the angle of the boundary's tangent at the side ray's hit from the heading, rad.

    Oriented as for :func:`boundary_curvature`; 0 when following it exactly, and 0 (the
    virtual boundary, aligned with the heading) with no hit.
    """
    side = parse_side(args["side"])
    view = cached_view(ctx, side)
    if not view.side.hit:
        return 0.0
    return view.side.beta if side is Side.RIGHT else -view.side.beta
