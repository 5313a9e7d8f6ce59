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
  over the first ``side_span`` (30 deg) of beams (both in :mod:`atoms.ray_fits`). Windows
  never leave one connected surface.

numpy is imported on first use (this module declares sensor functions the checker loads).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, NamedTuple

from mdle.atoms.memo import ByIdentity
from mdle.atoms.ray_fits import front_ray as _front_ray
from mdle.atoms.ray_fits import side_ray as _side_ray
from mdle.atoms.registry import Args, Context, Param, sensor
from mdle.atoms.steering import MISS, Ray
from mdle.core.units import ANGLE, CURVATURE, LENGTH

if TYPE_CHECKING:
    import numpy as np

    from mdle.core.backend import Scan

__all__ = ["Side", "BoundaryView", "boundary_view", "cached_view", "cached_beams",
           "parse_side", "boundary_range", "boundary_curvature", "boundary_tangent", "SIDES"]


class Side(enum.Enum):
    """Which side the followed boundary is on."""

    RIGHT = "right"
    LEFT = "left"


SIDES: tuple[str, ...] = tuple(s.value for s in Side)
_SIDE_NAMES: dict[str, Side] = {s.value: s for s in Side}
#: Beams further than this from the wanted bearing do not count as that ray (radians).
_BEARING_TOL = math.radians(1.5)


def parse_side(value: Any) -> Side:
    """Convert ``right``/``left`` (a symbol or a :class:`Side`) to a :class:`Side`.

    >>> parse_side("left")
    <Side.LEFT: 'left'>
    """
    if value is Side.RIGHT or value is Side.LEFT:
        return value
    side = _SIDE_NAMES.get(value) if type(value) is str else None
    if side is not None:  # a dict of names: calling the Enum costs ten times more
        return side
    try:
        return Side(str(value))
    except ValueError:
        raise ValueError(f"side must be one of {', '.join(SIDES)}, not {value!r}") from None


# A named tuple rather than a frozen dataclass, as atoms.steering.Ray: one is made every tick.
class BoundaryView(NamedTuple):
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
    ``n_side-1, n_side`` (the last side beam and the first front beam) are not neighbours in
    the scan. ``gap`` is the depth gap always accepted
    between neighbours (m), ``gaps`` that gap per neighbouring pair (numpy takes the larger
    of two arrays for less than of an array and a scalar), ``cl`` the front beam's place
    in ``take``.
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
    gap: float
    gaps: np.ndarray
    cl: int


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
    gaps = np.full(spacing.size, DEFAULT_GAP)
    for a in (take, unit, spacing, gaps):
        a.setflags(write=False)
    return _Layout(c, c_ok, s_ok, n_span, n_side, f0, take, unit, spacing, DEFAULT_GAP, gaps,
                   n_side + c - f0)


def _layout_of(bearings: Any, left: bool, side_span: float, windows: tuple[Any, ...]
               ) -> tuple[_Layout, tuple[int, ...]]:
    """Return the :class:`_Layout` of a bearing array and the windows as ints."""
    import numpy as np

    wins = tuple(int(w) for w in windows)
    b = np.ascontiguousarray(bearings, dtype=float)
    return _layout(b.tobytes(), left, float(side_span), max(wins)), wins


#: :func:`_layout_of` by the bearing array itself (a sensor's fixed bearings).
_layouts = ByIdentity(_layout_of, size=32)


#: What :func:`atoms.estimators.beam_points` returns: points, mask, ranges.
Beams = tuple["np.ndarray", "np.ndarray", "np.ndarray"]


def boundary_view(scan: "Scan | None", side: Side | str = Side.RIGHT,
                  windows: Sequence[int] = (7, 8, 9),
                  side_span: float = math.radians(30.0)) -> BoundaryView:
    """Compute the front and side rays for following ``side`` from one scan.

    Only the beams the two rays need are read (the side fit's span from -90 deg, the front
    beam and its windows), with the scan's connectivity rule (:func:`atoms.estimators.surfaces`)
    applied to them; nothing more when neither ray's own beam saw a surface.

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
    >>> from mdle.core.backend import Scan
    >>> b = np.radians([-90.0, -80, -70, -60, -50, -40, 0])
    >>> r = np.append(0.5 / np.sin(-b[:6]), 10.0)
    >>> v = boundary_view(Scan(r, b, r < 10, 0.0, 10.0), "right", windows=(1,))
    >>> v.side.hit, round(v.side.r, 3), round(abs(v.side.beta), 6), round(abs(v.side.kappa), 6)
    (True, 0.5, 0.0, 0.0)
    >>> v.front.hit
    False
    """
    return _view_of(scan, parse_side(side) is Side.LEFT, windows, side_span, None)


def _view_of(scan: "Scan | None", left: bool, windows: Sequence[int], side_span: float,
             ctx: Context | None, with_side: bool = True) -> BoundaryView:
    """Compute :func:`boundary_view`; the scan's :func:`cached_beams` of ``ctx`` if given.

    ``with_side`` False: the front ray only (the side is a miss), for a law that reads the
    side from the whole scan (:mod:`atoms.closest`).
    """
    import numpy as np

    if scan is None or scan.ranges.size == 0:
        return BoundaryView(MISS, MISS, False, math.inf if scan is None else scan.max_range)
    lay, wins = _layouts(scan.bearings, left, side_span,
                         windows if type(windows) is tuple else tuple(windows))
    if scan.tangents is not None and scan.curvatures is not None:
        return _oracle_view(scan, lay, left)
    if ctx is None:
        from mdle.atoms.estimators import beam_points

        beams: Beams = beam_points(scan.ranges, scan.bearings, scan.valid)
    else:
        beams = cached_beams(ctx)  # type: ignore[assignment]  # a scan is there
    z_all, _, r_all = beams
    ns, cl = lay.n_side, lay.cl
    if not with_side and not (lay.c_ok and math.isfinite(r_all.item(lay.take.item(cl)))):
        # the front ray alone, and its own beam saw nothing: no beam to gather (most ticks)
        return BoundaryView(MISS, MISS, False, scan.max_range)
    # NaN where a beam saw no surface: never linked to a neighbour (NaN compares False
    # below) nor taken as a ray's own beam (checked here)
    r = r_all[lay.take]
    r0 = r.item(0) if ns else math.nan
    rc = r.item(cl) if lay.c_ok else math.nan
    side_hit, front_hit = with_side and math.isfinite(r0), math.isfinite(rc)
    side_ray = front = MISS
    if not (side_hit or front_hit):  # neither ray's own beam saw a surface: nothing to read
        return BoundaryView(front, side_ray, False, scan.max_range)
    z = z_all[lay.take]
    if left:
        z = z.conjugate()  # mirrored: y -> -y (the beam order is reversed by take)
    lim = np.maximum(lay.spacing * r[:-1], lay.gaps)
    # links[j]: beams j and j+1 lie on one surface, as bytes 0/1 (searched in C below); the
    # runs never cross the pair (n_side-1, n_side): they are not neighbours in the scan
    links = (np.abs(z[1:] - z[:-1]) < lim).tobytes()
    if side_hit:  # the side run: beams 0 .. end0 linked from beam 0
        end0 = links.find(0, 0, ns - 1)
        side_ray = _side_ray(z[:min(end0 if end0 >= 0 else ns - 1, lay.n_span) + 1], r0)
    if front_hit:  # the front run: linked beams before and after the front beam
        k = links.rfind(0, ns, cl)
        right = cl - 1 - k if k >= 0 else cl - ns
        k = links.find(0, cl)
        ahead = (k if k >= 0 else len(links)) - cl
        ray = _front_ray(z, cl, right, ahead, rc, wins)
        if ray is None:  # degenerate window (coincident points): read the whole scan
            bearings = np.asarray(scan.bearings, dtype=float)
            ray = _front_full(np.asarray(scan.ranges, dtype=float), bearings,
                              np.asarray(scan.valid, dtype=bool), left, lay.c, rc, wins)
        front = ray
    return BoundaryView(front, side_ray, False, scan.max_range)


def _oracle_view(scan: "Scan", lay: _Layout, left: bool) -> BoundaryView:
    """Return the view of an oracle scan: the exact values at the two beams."""
    import numpy as np

    ranges = np.asarray(scan.ranges, dtype=float)
    valid = np.asarray(scan.valid, dtype=bool)
    tangents, curvatures = scan.tangents, scan.curvatures
    assert tangents is not None and curvatures is not None
    n = ranges.size

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
    return BoundaryView(oracle(lay.c) if lay.c_ok else MISS, side_ray, True, scan.max_range)


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
    """Run :func:`atoms.ray_fits.front_ray` with the front surface's true extent (whole scan)."""
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
                side_span: float = math.radians(30.0), with_side: bool = True) -> BoundaryView:
    """Return :func:`boundary_view` of this tick's scan, computed once per tick and side.

    ``with_side`` False: the front ray only (the side ray is a miss, its fit skipped).
    """
    left = parse_side(side) is Side.LEFT
    key = ("boundary", left, tuple(windows), side_span, with_side)  # no Enum.__hash__
    view = ctx.cache.get(key)
    if view is None:
        view = _view_of(ctx.obs.scan, left, windows, side_span, ctx, with_side)
        ctx.cache[key] = view
    return view


def cached_beams(ctx: Context) -> "Beams | None":
    """Return :func:`atoms.estimators.beam_points` of this tick's scan, once per tick.

    The boundary view and the safety layer's scan points share it; None without a scan.
    """
    beams = ctx.cache.get("beams")
    if beams is None:
        scan = ctx.obs.scan
        if scan is None:
            return None
        import mdle.atoms.estimators as est  # numpy, on first use (not `from`: no __path__ probe)

        beams = est.beam_points(scan.ranges, scan.bearings, scan.valid)
        ctx.cache["beams"] = beams
    return beams


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
