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
from typing import TYPE_CHECKING, Any

from atoms.registry import Args, Context, Param, sensor
from mdle.units import ANGLE, CURVATURE, LENGTH

if TYPE_CHECKING:
    import numpy as np

    from atoms.steering import Ray
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
    """``right``/``left`` (a symbol or a :class:`Side`) as a :class:`Side`.

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


def _side_ray(pts: "np.ndarray", end0: int, r0: float, span: int) -> "Ray":
    """Side ray from beams 0..n of the first surface (law frame, beam 0 at -90 deg).

    A quadratic ``h = a + b s + c s^2`` is fitted by least squares in the frame of the
    total-least-squares line through the points (centred, scaled by the span), and its slope
    and curvature are taken at the hit point, beam 0. Windows of three points (the paper's
    one-sided ``(P0, Pw, P2w)``) are far noisier at the side ray: at 0.5 m with 0.8 % range
    noise they give a curvature std of about 1.3 1/m and a tangent std of 6 deg; the fit over
    ``span = 30`` beams (about 0.27 m of wall) gives 0.22 1/m and 1.9 deg.
    """
    import numpy as np

    from atoms.estimators import principal_direction
    from atoms.steering import MISS, Ray

    n = min(end0, span)
    if n + 1 < 5:
        return MISS
    p = pts[: n + 1]
    ang = principal_direction(p)
    if not math.isfinite(ang):
        return MISS
    q = p - p.mean(0)
    c, sn = math.cos(ang), math.sin(ang)
    s = q[:, 0] * c + q[:, 1] * sn
    h = q[:, 1] * c - q[:, 0] * sn
    scale = float(np.max(np.abs(s)))
    if scale <= 0:
        return MISS
    x = s / scale
    coef, *_ = np.linalg.lstsq(np.stack((np.ones_like(x), x, x * x), axis=1), h, rcond=None)
    slope = (coef[1] + 2.0 * coef[2] * x[0]) / scale
    kappa = 2.0 * coef[2] / scale ** 2 / (1.0 + slope * slope) ** 1.5
    return Ray(True, r0, ang + math.atan(slope), float(kappa))


def _front_ray(pts: "np.ndarray", start: int, c: int, end: int, r0: float,
               windows: Sequence[int]) -> "Ray":
    """Front ray at beam ``c`` on the surface ``start..end`` (law frame)."""
    import numpy as np

    from atoms.estimators import menger
    from atoms.steering import Ray

    reach = min(c - start, end - c)
    ws = np.asarray([w for w in windows if w <= reach] or ([reach] if reach >= 1 else []))
    if ws.size:
        k = menger(pts[c - ws], pts[c], pts[c + ws])
        ok = np.isfinite(k)
        if ok.any():
            u = pts[c] - pts[c - ws[ok]]
            au = np.hypot(u[:, 0], u[:, 1])
            s = np.clip(0.5 * au * k[ok], -1.0, 1.0)
            # tangent of the circle through the window at its middle point (see estimators)
            tx = (u[:, 0] * np.sqrt(1 - s * s) - u[:, 1] * s).sum()
            ty = (u[:, 1] * np.sqrt(1 - s * s) + u[:, 0] * s).sum()
            return Ray(True, r0, math.atan2(ty, tx), float(k[ok].mean()))
    right, left = c - start, end - c
    m = min(max(right, left), max(windows))
    if m >= 1:
        chord = pts[c + m] - pts[c] if left >= right else pts[c] - pts[c - m]
        return Ray(True, r0, math.atan2(chord[1], chord[0]), 0.0)
    return Ray(True, r0, math.pi / 2.0, 0.0)  # an isolated return: a surface facing the robot


def boundary_view(scan: "Scan | None", side: Side | str = Side.RIGHT,
                  windows: Sequence[int] = (7, 8, 9),
                  side_span: float = math.radians(30.0)) -> BoundaryView:
    """The front and side rays for following ``side``, from one scan.

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

    from atoms.estimators import surfaces
    from atoms.steering import MISS, Ray

    side = parse_side(side)
    if scan is None or scan.ranges.size == 0:
        return BoundaryView(MISS, MISS, False, math.inf if scan is None else scan.max_range)
    ranges = np.asarray(scan.ranges, dtype=float)
    bearings = np.asarray(scan.bearings, dtype=float)
    valid = np.asarray(scan.valid, dtype=bool)
    tangents, curvatures = scan.tangents, scan.curvatures
    if side is Side.LEFT:  # mirror y -> -y and reverse the beam order
        ranges, bearings, valid = ranges[::-1], -bearings[::-1], valid[::-1]
        if tangents is not None:
            tangents = np.pi - np.asarray(tangents)[::-1]
        if curvatures is not None:
            curvatures = np.asarray(curvatures)[::-1]
    valid = valid & np.isfinite(ranges) & (ranges > 0)
    c = int(np.argmin(np.abs(bearings)))
    c_ok = abs(bearings[c]) <= _BEARING_TOL and valid[c]
    s_ok = abs(bearings[0] + np.pi / 2) <= _BEARING_TOL and valid[0]
    exact = tangents is not None and curvatures is not None
    if exact:
        def oracle(j: int) -> Ray:
            t, k = float(tangents[j]), float(curvatures[j])  # type: ignore[index]
            if not (math.isfinite(t) and math.isfinite(k)):
                return MISS
            return Ray(True, float(ranges[j]), math.atan2(math.sin(t), math.cos(t)), k)
        return BoundaryView(oracle(c) if c_ok else MISS, oracle(0) if s_ok else MISS, True,
                            scan.max_range)
    s = surfaces(ranges, bearings, valid)
    front = _front_ray(s.points, int(s.start[c]), c, int(s.end[c]), float(ranges[c]), windows) \
        if c_ok else MISS
    step = abs(float(bearings[1] - bearings[0])) if bearings.size > 1 else 1.0
    n_span = max(4, int(round(side_span / step))) if step > 0 else 4
    side_ray = _side_ray(s.points, int(s.end[0]), float(ranges[0]), n_span) if s_ok else MISS
    return BoundaryView(front, side_ray, False, scan.max_range)


def cached_view(ctx: Context, side: Side | str, windows: Sequence[int] = (7, 8, 9),
                side_span: float = math.radians(30.0)) -> BoundaryView:
    """:func:`boundary_view` of this tick's scan, computed once per tick and side."""
    side = parse_side(side)
    key = ("boundary", side, tuple(windows), side_span)
    view = ctx.cache.get(key)
    if view is None:
        view = boundary_view(ctx.obs.scan, side, windows, side_span)
        ctx.cache[key] = view
    return view  # type: ignore[no-any-return]


_SIDE = Param("side", default="right", choices=SIDES,
              doc="which side the boundary is on: right or left")


@sensor(_SIDE, result=LENGTH)
def boundary_range(args: Args, ctx: Context) -> float:
    """Range to the boundary along the side ray (-90 deg for right, +90 deg for left).

    The sensor's maximum range when that ray sees no surface (or no scan has arrived).
    """
    view = cached_view(ctx, str(args["side"]))
    return view.side.r if view.side.hit else view.max_range


@sensor(_SIDE, result=CURVATURE)
def boundary_curvature(args: Args, ctx: Context) -> float:
    """Signed curvature of the boundary where the side ray hits it, 1/m.

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
    """Angle of the boundary's tangent at the side ray's hit, from the heading, radians.

    Oriented as for :func:`boundary_curvature`; 0 when following it exactly, and 0 (the
    virtual boundary, aligned with the heading) with no hit.
    """
    side = parse_side(args["side"])
    view = cached_view(ctx, side)
    if not view.side.hit:
        return 0.0
    return view.side.beta if side is Side.RIGHT else -view.side.beta
