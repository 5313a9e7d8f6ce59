"""Vectorised ray casting against exact boundary primitives (segments, arcs, ellipses).

Over 500 lines: two casters of one method (any rays, and a ladar's fixed fan), which
must agree to the bit; tests compare them.

The hot path of the simulator. Segments use an angular-interval method: each segment
subtends an interval of bearings as seen from the ray origin, so only the beams inside
that interval are intersected with it (``searchsorted`` on the sorted beam angles), and
the cost scales with the number of (beam, segment) pairs that can actually meet rather
than with beams x segments. Segments out of range are culled by bounding box first.
Arcs and ellipses are intersected densely and analytically; where a world has more than
256 of them, a grid of their boxes (:class:`sim.faceindex.BoxGrid`) first picks those of
the cells within range, so a scan's cost follows the curves in view (the same numbers;
in a ladar's fan, ellipses within rounding: a smaller matrix product).

:class:`FanCaster` is the same method specialised for a ladar, whose fan of beams never
changes: it works in the fan's own frame, where the beam directions are constants, and
needs 25 numpy calls per scan (the fixed cost of a call, about 3,500 instructions, is half
of what a scan of a small world costs; the rest is mostly the arctan2 and the binary
searches of the faces' intervals). Where the install built ``sim/_kernels.c`` (an
optional build; :data:`COMPILED`), the faces go through one compiled call instead, which
gives the same numbers bit for bit. At 100 segments (benchmarks/sim.py's world) a scan
costs about 64,000 instructions compiled and 224,000 in numpy. In a world of more than
256 faces the compiled fan walks each beam through a grid of the faces
(:mod:`sim.faceindex`, the C ``GridWalk``) up to its first hit, so a scan's cost follows
what the ladar sees, not the size of the map (docs/performance.md). A fan's ellipses go
through one compiled call too, where probes find that it gives numpy's numbers (its own
complex absolute value, its BLAS product of the beams, its in-place products): 2.8 us a
scan of Figure 1's world against 17.9 us in numpy.

All angles are in the world frame (radians, counter-clockwise); ranges in metres.

>>> import numpy as np
>>> from mdle.sim.shapes import Circle, Parts
>>> caster = RayCaster(Parts.concat([Circle((5.0, 0.0), 1.0).parts()]))
>>> hits = caster.cast(np.array([0.0, 0.0]), np.array([0.0, np.pi / 2]))
>>> hits.ranges.tolist(), hits.hit.tolist()
([4.0, inf], [True, False])
>>> round(float(hits.curvatures[0]), 12), round(float(hits.tangents[0]), 12)
(-1.0, 1.570796326795)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property
from typing import Any

import numpy as np

from mdle.sim.faceindex import BoxGrid, FaceGrid
from mdle.sim.shapes import Parts

__all__ = ["COMPILED", "COMPILED_ELLIPSES", "MAX_RANGE_SLACK", "FanCaster", "RayCaster", "RayHits"]

_TAU = 2.0 * math.pi
_EPS_ANGLE = 1e-10   # widen segment intervals so a beam through a vertex is never lost
_T_MIN = 1e-12       # a hit must lie strictly ahead of the origin
_CULL_ABOVE = 256    # bounding-box culling pays off only in larger worlds
#: A hit at ``max_range`` counts, give or take this relative rounding (a few ulps), so
#: that a hit exactly at the limit counts in every code path, however it was rounded.
MAX_RANGE_SLACK = 1e-15
#: Metres: the grid walk stops at a cell whose far side lies this much beyond the nearest
#: hit found (far above rounding, below :data:`sim.faceindex.PAD`).
_GRID_TOL = 1e-9


def _compiled_faces() -> Callable[..., None] | None:
    """Return the fan cast's face loop in C (sim/_kernels.c), or None where it was not built.

    It is an optional build (pyproject.toml): an install without a C compiler casts with
    numpy, which gives the same numbers.
    """
    try:
        from mdle.sim._kernels import faces
    except ImportError:
        return None
    return faces


def _numpy_complex_rounding() -> bool | None:
    """How numpy rounds complex products here: fused (True), plain (False), or mixed (None).

    numpy's SIMD loops compute ``a.re b.re - a.im b.im`` with a fused multiply-add where
    the CPU has one; the compiled face loop must round as numpy does to cast the same
    numbers, and it divides a complex by a real as a product with the reciprocal, as numpy
    does. Both are checked on inputs where the roundings differ, at several lengths (SIMD
    body and scalar tail); None (anything else) leaves the numpy path in charge.
    """
    u = 1.0 + 2.0 ** -30
    verdicts: set[bool | None] = set()
    for n in (1, 3, 8, 17):
        a = np.full(n, complex(u, 1.0))
        re = np.multiply(a, a).real
        fused, plain = 2.0 ** -29 + 2.0 ** -60, u * u - 1.0
        verdicts.update(True if x == fused else False if x == plain else None for x in re)
        q = np.divide(np.full(n, complex(5.0, 5.0)), np.full(n, 3.0))
        if not (q.real == 5.0 * (1.0 / 3.0)).all():     # 5 / 3 rounds the other way
            verdicts.add(None)
    return verdicts.pop() if len(verdicts) == 1 else None


@dataclass(frozen=True)
class _EllipseKernels:
    """The compiled ellipses of sim/_kernels.c: what a fan and the probes call."""

    cast: Callable[..., None]       #: ``ellipses``: lower a scan's ranges to the hits
    scan: Callable[..., None]       #: ``ellipse_scan``: a whole scan of ellipses only
    absolute: Callable[..., None]   #: numpy's complex absolute value
    product: Callable[..., None]    #: numpy's matmul of the beams and the ellipses


def _compiled_ellipses() -> _EllipseKernels | None:
    """Return the compiled ellipse cast and its parts (sim/_kernels.c), or None."""
    try:
        from mdle.sim._kernels import absolute, beam_product, ellipse_scan, ellipses
    except ImportError:
        return None
    return _EllipseKernels(ellipses, ellipse_scan, absolute, beam_product)


def _numpy_abs_rounding(absolute: Callable[..., None]) -> bool | None:
    """How numpy's complex absolute value rounds here: fused (True), plain (False), or neither.

    numpy computes ``|z|`` with its own vectorised loop (the larger part times
    ``sqrt(1 + ratio**2)``, the square added with a fused multiply-add where the CPU has
    one), which differs from libm's ``hypot`` for about a third of values. The compiled
    ``absolute`` follows that loop, fused or plain: each is checked against ``np.abs`` on
    values where the two differ, on zeros, tiny and huge parts, infinities and NaNs, at
    several lengths (SIMD body and tail). None (neither matches) leaves the ellipses to
    numpy.
    """
    rng = np.random.default_rng(27)
    parts = rng.standard_normal((2, 64)) * 10.0 ** rng.uniform(-8.0, 8.0, (2, 64))
    special = [0.0, -0.0, 5e-324, 1e-310, 1e300, 1.7e308, math.inf, -math.inf, math.nan]
    re = np.concatenate([parts[0], np.repeat(special, len(special)), [3.0, 1.0]])
    im = np.concatenate([parts[1], np.tile(special, len(special)), [4.0, 1.0 + 2.0 ** -26]])
    z = np.empty(re.shape[0], dtype=complex)
    z.real, z.imag = re, im                     # (re + 1j * im would mix inf and NaN parts)
    verdicts: set[bool | None] = set()
    for n in (1, 3, 8, 17, z.shape[0]):
        want = np.abs(z[:n])
        found: bool | None = None
        for fused in (True, False):
            got = np.empty(n)
            absolute(z[:n], got, fused)
            if np.array_equal(got, want, equal_nan=True) and (
                    np.signbit(got) == np.signbit(want)).all():
                found = fused
                break
        verdicts.add(found)
    return verdicts.pop() if len(verdicts) == 1 else None


def _exact_product(a: complex, b: complex, fused: bool) -> complex:
    """Return ``a b`` rounded as numpy's fused (or plain) complex product rounds it."""
    if not fused:
        return complex(a.real * b.real - a.imag * b.imag, a.real * b.imag + a.imag * b.real)
    # a fused multiply-add, x y + z rounded once: exact in fractions, then one rounding
    re = Fraction(a.real) * Fraction(b.real) + Fraction(-(a.imag * b.imag))
    im = Fraction(a.real) * Fraction(b.imag) + Fraction(a.imag * b.real)
    return complex(float(re), float(im))


def _numpy_inplace_rounding(n: int) -> bool | None:
    """How numpy rounds ``a *= b`` for complex arrays of ``n`` numbers: fused, plain or neither.

    Its loop picks a path by the arrays' length and overlap: with numpy 2.4 on x86-64, a
    single number in place takes a plain scalar loop, longer arrays the fused SIMD one.
    Checked against exact products on random numbers (32 at least).
    """
    rng = np.random.default_rng(n)
    left = {True, False}                        # the roundings every product agrees with
    for _ in range(max(1, 32 // max(n, 1))):
        a = rng.standard_normal(n) + 1j * rng.standard_normal(n)
        b = rng.standard_normal(n) + 1j * rng.standard_normal(n)
        got = a.copy()
        got *= b
        left = {fused for fused in left
                if all(_exact_product(complex(x), complex(y), fused) == complex(z)
                       for x, y, z in zip(a, b, got, strict=True))}
    return left.pop() if len(left) == 1 else None


def _compiled_grid_walk() -> Callable[..., Any] | None:
    """Return the grid walk's type in C (``GridWalk``), or None where it was not built."""
    try:
        from mdle.sim._kernels import GridWalk
    except ImportError:
        return None
    return GridWalk


_KERNEL = _compiled_faces()
_GRID_WALK = _compiled_grid_walk()
_FUSED = _numpy_complex_rounding() if _KERNEL is not None else None
#: Whether scans use the compiled face loop (False: the numpy path, the same numbers).
COMPILED = _FUSED is not None
_ELL = _compiled_ellipses() if COMPILED else None
_ABS_FUSED = _numpy_abs_rounding(_ELL.absolute) if _ELL is not None else None
#: Whether a fan's ellipses may use the compiled cast (each fan also checks the product of
#: its beams; :attr:`FanCaster.compiled_ellipses`). False: numpy, the same numbers.
COMPILED_ELLIPSES = _ELL is not None and _ABS_FUSED is not None


def _in_reach(grid: BoxGrid | None, x: float, y: float, max_range: float
              ) -> np.ndarray | None:
    """Return the curves of the cells within ``max_range`` of ``(x, y)``; None: all of them.

    The square searched is widened well beyond rounding, so that it holds every curve
    whose distance, as the cast computes it, passes the cast's own test.
    """
    if grid is None or not math.isfinite(max_range):
        return None
    return grid.near(x, y, max_range * (1.0 + 1e-9) + 1e-9)


@dataclass(frozen=True, eq=False)
class RayHits:
    """What a fan of rays hit (ground truth).

    Attributes
    ----------
    ranges : (B,) float array, metres
        Distance to the first boundary along each ray; ``inf`` where nothing was hit
        (or nothing within ``max_range``).
    hit : (B,) bool array
        True where a boundary was hit within ``max_range``.
    tangents : (B,) float array, radians, or None
        World-frame direction of the boundary at the hit, oriented with the obstacle on
        the right; NaN where nothing was hit. None when not requested.
    curvatures : (B,) float array, 1/m, or None
        Signed boundary curvature at the hit (negative on convex faces); NaN where
        nothing was hit. None when not requested.
    owner : (B,) int array or None
        Index of the obstacle hit (in the world's ``obstacles``), -1 where none.
    """

    ranges: np.ndarray
    hit: np.ndarray
    tangents: np.ndarray | None = None
    curvatures: np.ndarray | None = None
    owner: np.ndarray | None = None


class RayCaster:
    """Casts fans of rays against a fixed set of boundary primitives.

    Built once per world (the primitives never change); :meth:`cast` allocates only
    its outputs and pair arrays proportional to the work actually done.

    Parameters
    ----------
    parts : Parts
        The world's boundary primitives, as :meth:`sim.shapes.Parts.concat` returns them.
    curve_grids : bool
        Where there are more than 256 arcs (or ellipses), index them in a grid
        (:attr:`arc_grid`, :attr:`ellipse_grid`), so that a cast tests only those of the
        cells in range: the same numbers (False: test the distance of every one).
    """

    def __init__(self, parts: Parts, curve_grids: bool = True) -> None:
        self.parts = parts
        self.curve_grids = curve_grids
        s0, s1 = parts.seg_start, parts.seg_end
        self._s0 = np.ascontiguousarray(s0)
        self._edge = np.ascontiguousarray(s1 - s0)
        self._bb_lo = np.minimum(s0, s1)
        self._bb_hi = np.maximum(s0, s1)
        self._seg_tangent = np.arctan2(self._edge[:, 1], self._edge[:, 0])
        self._arc_full = parts.arc_sweep >= _TAU - 1e-12
        self._arc_r2 = parts.arc_radius ** 2
        ang = parts.ell_angle
        self._ell_u = np.column_stack([np.cos(ang), np.sin(ang)]) if len(ang) else np.zeros((0, 2))
        self._ell_bound = parts.ell_axes.max(axis=1) if len(ang) else np.zeros(0)
        # Complex form (a point is x + iy) of the starts and edges, for :class:`FanCaster`.
        self._z0 = self._s0[:, 0] + 1j * self._s0[:, 1]
        self._ze = self._edge[:, 0] + 1j * self._edge[:, 1]
        # A face whose line passes within _T_MIN of the origin is never hit (t <= _T_MIN).
        self._front_min = _T_MIN * np.abs(self._ze)

    @cached_property
    def grid(self) -> FaceGrid | None:
        """The faces' grid (:class:`sim.faceindex.FaceGrid`), built on first use; None: no faces.

        One per world, shared by every :class:`FanCaster` of it.
        """
        if self._s0.shape[0] == 0:
            return None
        return FaceGrid.build(self._s0, self._s0 + self._edge)

    @cached_property
    def arc_grid(self) -> BoxGrid | None:
        """The arcs' boxes by cell (:class:`sim.faceindex.BoxGrid`), built on first use.

        None up to ``_CULL_ABOVE`` arcs: then testing the distance of each costs less.
        """
        P = self.parts
        if not self.curve_grids or P.arc_radius.shape[0] <= _CULL_ABOVE:
            return None
        return BoxGrid.of_arcs(P)

    @cached_property
    def ellipse_grid(self) -> BoxGrid | None:
        """The ellipses' boxes (their bounding circles') by cell, as :attr:`arc_grid`."""
        P = self.parts
        if not self.curve_grids or P.ell_angle.shape[0] <= _CULL_ABOVE:
            return None
        return BoxGrid.of_ellipses(P)

    def fan(self, rel: np.ndarray, max_range: float, compiled: bool | None = None,
            indexed: bool | None = None) -> FanCaster:
        """Make a :class:`FanCaster` for a fixed fan of beams (a ladar's), with its buffers.

        ``compiled``, ``indexed``: as :class:`FanCaster` takes them.
        """
        return FanCaster(self, rel, max_range, compiled, indexed)

    # ------------------------------------------------------------------ public
    def cast(self, origin: np.ndarray, angles: np.ndarray, max_range: float = math.inf,
             detail: bool = True, rel: np.ndarray | None = None) -> RayHits:
        """Cast rays from ``origin`` at world-frame ``angles``.

        Parameters
        ----------
        origin : (2,) float array, metres
        angles : (B,) float array, radians
            Any order; a sorted fan (such as a ladar's) skips a sort.
        max_range : float, metres
            Primitives farther than this are culled; hits beyond it (by more than
            :data:`MAX_RANGE_SLACK`, relative) are reported as misses.
        detail : bool
            Also compute tangents, curvatures and owners (the oracle's data).
        rel : (B,) float array, radians, optional
            ``angles - angles[0]``, already known to be ascending in [0, 2 pi) (a ladar's
            fixed fan): saves the check on every scan.

        Returns
        -------
        RayHits
        """
        o = np.asarray(origin, dtype=float).reshape(2)
        ang = np.asarray(angles, dtype=float).reshape(-1)
        n = ang.shape[0]
        order = None
        if rel is None:
            rel = np.mod(ang - ang[0], _TAU) if n else ang
            ascending = n < 2 or bool((rel[1:] >= rel[:-1]).all())
        else:
            ascending = True    # the caller's promise (a ladar's fixed fan)
        if not ascending:
            order = np.argsort(rel, kind="stable")
            ang, rel = ang[order], rel[order]
        cos, sin = np.cos(ang), np.sin(ang)

        best = np.full(n, math.inf)
        kind = np.zeros(n, dtype=np.int8)   # 0 none, 1 segment, 2 arc, 3 ellipse
        which = np.full(n, -1, dtype=np.intp)

        self._segments(o, ang[0] if n else 0.0, rel, cos, sin, max_range, best, kind, which,
                       detail)
        if len(self.parts.arc_radius):
            self._arcs(o, cos, sin, max_range, best, kind, which)
        if len(self.parts.ell_angle):
            self._ellipses(o, cos, sin, max_range, best, kind, which)

        hit = np.isfinite(best) & (best <= max_range * (1.0 + MAX_RANGE_SLACK))
        ranges = np.where(hit, best, math.inf)
        tangents = curvatures = owner = None
        if detail:
            tangents, curvatures, owner = self._detail(o, cos, sin, ranges, hit, kind, which)
        if order is not None:
            inv = np.empty_like(order)
            inv[order] = np.arange(n)
            ranges, hit = ranges[inv], hit[inv]
            if tangents is not None and curvatures is not None and owner is not None:
                tangents, curvatures, owner = tangents[inv], curvatures[inv], owner[inv]
        return RayHits(ranges, hit, tangents, curvatures, owner)

    # ------------------------------------------------------------------ segments
    def _segments(self, o: np.ndarray, base: float, rel: np.ndarray, cos: np.ndarray,
                  sin: np.ndarray, max_range: float, best: np.ndarray, kind: np.ndarray,
                  which: np.ndarray, detail: bool) -> None:
        n_seg = self._s0.shape[0]
        if n_seg == 0 or rel.shape[0] == 0:
            return
        if math.isfinite(max_range) and n_seg > _CULL_ABOVE:
            lo_x, hi_x = o[0] - max_range, o[0] + max_range
            lo_y, hi_y = o[1] - max_range, o[1] + max_range
            near = self._bb_lo[:, 0] <= hi_x
            near &= self._bb_hi[:, 0] >= lo_x
            near &= self._bb_lo[:, 1] <= hi_y
            near &= self._bb_hi[:, 1] >= lo_y
            idx = np.flatnonzero(near)
            if idx.size == 0:
                return
            p = self._s0[idx] - o
            e = self._edge[idx]
        else:
            idx = None
            p = self._s0 - o
            e = self._edge
        px, py, ex, ey = p[:, 0], p[:, 1], e[:, 0], e[:, 1]
        num = px * ey
        num -= py * ex                              # cross(p, e) = cross(p, q), per segment
        # Back-face culling: with the solid on each segment's right, only segments whose
        # left (outer) side faces the origin can be hit first from outside (num > 0).
        front = np.flatnonzero(num > 0.0)
        if front.size < num.shape[0]:
            if front.size == 0:
                return
            idx = front if idx is None else idx[front]
            p, e, num = p[front], e[front], num[front]
            px, py, ex, ey = p[:, 0], p[:, 1], e[:, 0], e[:, 1]
        # The segment's bearing interval seen from the origin: from p, counter-clockwise
        # by the angle between p and q = p + e (in (0, pi) for a front face).
        dot = px * (px + ex)
        dot += py * (py + ey)
        sweep = np.arctan2(num, dot)
        lo = np.arctan2(py, px)
        lo -= base + math.pi
        np.mod(lo, _TAU, out=lo)
        lo -= math.pi + _EPS_ANGLE                 # relative to the first beam, [-pi, pi)
        hi = lo + sweep
        hi += 2 * _EPS_ANGLE
        m = px.shape[0]
        if rel[-1] >= math.pi - 1e-9:
            # A fan wider than a half turn can also meet the interval one turn up.
            lo = np.concatenate([lo, lo + _TAU])
            hi = np.concatenate([hi, hi + _TAU])
        k_lo = np.searchsorted(rel, lo, side="left")
        cnt = np.searchsorted(rel, hi, side="right")
        cnt -= k_lo
        np.maximum(cnt, 0, out=cnt)
        total = int(cnt.sum())
        if total == 0:
            return
        pseg = np.repeat(np.arange(cnt.shape[0]) % m if cnt.shape[0] > m else
                         np.arange(m), cnt)
        starts = np.cumsum(cnt)
        starts -= cnt
        k_lo -= starts
        pbeam = np.repeat(k_lo, cnt)
        pbeam += np.arange(total)
        den = cos[pbeam] * ey[pseg]
        den -= sin[pbeam] * ex[pseg]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.divide(num[pseg], den, out=den)
        t[t <= _T_MIN] = math.inf                   # grazing at an interval's edge: no hit
        np.minimum.at(best, pbeam, t)               # segments come first: best is all inf
        if detail:
            hitb = np.isfinite(best)
            kind[hitb] = 1
            win = t == best[pbeam]
            src = pseg[win] if idx is None else idx[pseg[win]]
            which[pbeam[win]] = src

    # ------------------------------------------------------------------ arcs
    def _arcs(self, o: np.ndarray, cos: np.ndarray, sin: np.ndarray, max_range: float,
              best: np.ndarray, kind: np.ndarray, which: np.ndarray) -> None:
        P = self.parts
        # Many arcs: first those of the cells in range (a superset of the arcs within
        # range, tested below exactly as all of them would be).
        near = _in_reach(self.arc_grid, float(o[0]), float(o[1]), max_range)
        if near is None:
            w = P.arc_center - o
            dist = np.hypot(w[:, 0], w[:, 1])
            keep = idx = np.flatnonzero(dist - P.arc_radius <= max_range)
        else:
            w = P.arc_center[near] - o
            dist = np.hypot(w[:, 0], w[:, 1])
            keep = np.flatnonzero(dist - P.arc_radius[near] <= max_range)
            idx = near[keep]
        if idx.size == 0:
            return
        wx, wy = w[keep, 0], w[keep, 1]
        tca = cos[:, None] * wx + sin[:, None] * wy              # (B, A)
        cr = cos[:, None] * wy - sin[:, None] * wx               # perpendicular offset
        disc = self._arc_r2[idx] - cr * cr
        with np.errstate(invalid="ignore"):
            h = np.sqrt(disc)
        t1 = tca - h
        t2 = tca + h
        full = self._arc_full[idx]
        start, sweep = P.arc_start[idx], P.arc_sweep[idx]

        def on_arc(t: np.ndarray) -> np.ndarray:
            if bool(full.all()):
                return np.ones(t.shape, dtype=bool)
            a = np.arctan2(t * sin[:, None] - wy, t * cos[:, None] - wx)
            return full | (np.mod(a - start, _TAU) <= sweep + 1e-12)

        ok1 = (disc >= 0) & (t1 > _T_MIN) & on_arc(t1)
        ok2 = (disc >= 0) & (t2 > _T_MIN) & on_arc(t2)
        t = np.where(ok1, t1, np.where(ok2, t2, math.inf))
        j = np.argmin(t, axis=1)
        tb = t[np.arange(t.shape[0]), j]
        better = tb < best
        best[better] = tb[better]
        kind[better] = 2
        which[better] = idx[j[better]]

    # ------------------------------------------------------------------ ellipses
    def _ellipses(self, o: np.ndarray, cos: np.ndarray, sin: np.ndarray, max_range: float,
                  best: np.ndarray, kind: np.ndarray, which: np.ndarray) -> None:
        P = self.parts
        near = _in_reach(self.ellipse_grid, float(o[0]), float(o[1]), max_range)  # as arcs
        if near is None:
            w = o - P.ell_center
            dist = np.hypot(w[:, 0], w[:, 1])
            keep = idx = np.flatnonzero(dist - self._ell_bound <= max_range)
        else:
            w = o - P.ell_center[near]
            dist = np.hypot(w[:, 0], w[:, 1])
            keep = np.flatnonzero(dist - self._ell_bound[near] <= max_range)
            idx = near[keep]
        if idx.size == 0:
            return
        u = self._ell_u[idx]
        a, b = P.ell_axes[idx, 0], P.ell_axes[idx, 1]
        # Origin and directions in the ellipse frame, scaled to the unit circle.
        ox = (w[keep, 0] * u[:, 0] + w[keep, 1] * u[:, 1]) / a
        oy = (-w[keep, 0] * u[:, 1] + w[keep, 1] * u[:, 0]) / b
        dx = (cos[:, None] * u[:, 0] + sin[:, None] * u[:, 1]) / a     # (B, E)
        dy = (-cos[:, None] * u[:, 1] + sin[:, None] * u[:, 0]) / b
        A = dx * dx + dy * dy
        Bh = dx * ox + dy * oy
        C = ox * ox + oy * oy - 1.0
        disc = Bh * Bh - A * C
        with np.errstate(invalid="ignore", divide="ignore"):
            s = np.sqrt(disc)
            # Outside (C > 0): nearer root C / (-B + s), free of cancellation.
            t_out = np.where(Bh < 0, C / (s - Bh), math.inf)
            t_in = (s - Bh) / A
        t = np.where(C > 0, t_out, t_in)
        t = np.where((disc >= 0) & (t > _T_MIN), t, math.inf)
        j = np.argmin(t, axis=1)
        rows = np.arange(t.shape[0])
        tb = t[rows, j]
        better = tb < best
        best[better] = tb[better]
        kind[better] = 3
        which[better] = idx[j[better]]

    # ------------------------------------------------------------------ oracle data
    def _detail(self, o: np.ndarray, cos: np.ndarray, sin: np.ndarray, ranges: np.ndarray,
                hit: np.ndarray, kind: np.ndarray, which: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        P = self.parts
        n = ranges.shape[0]
        tangents = np.full(n, math.nan)
        curv = np.full(n, math.nan)
        owner = np.full(n, -1, dtype=np.intp)
        r = np.where(hit, ranges, 0.0)
        hx, hy = o[0] + r * cos, o[1] + r * sin

        m = hit & (kind == 1)
        if m.any():
            s = which[m]
            tangents[m] = self._seg_tangent[s]
            curv[m] = P.seg_kappa[s]
            owner[m] = P.seg_owner[s]
        m = hit & (kind == 2)
        if m.any():
            s = which[m]
            c = P.arc_center[s]
            a = np.arctan2(hy[m] - c[:, 1], hx[m] - c[:, 0])
            side = P.arc_side[s]
            # Convex face (obstacle inside): clockwise, tangent = a - pi/2; concave: a + pi/2.
            tangents[m] = a + side * (math.pi / 2)
            curv[m] = side / P.arc_radius[s]
            owner[m] = P.arc_owner[s]
        m = hit & (kind == 3)
        if m.any():
            s = which[m]
            c = P.ell_center[s]
            u = self._ell_u[s]
            a, b = P.ell_axes[s, 0], P.ell_axes[s, 1]
            qx, qy = hx[m] - c[:, 0], hy[m] - c[:, 1]
            lx = qx * u[:, 0] + qy * u[:, 1]
            ly = -qx * u[:, 1] + qy * u[:, 0]
            tau = np.arctan2(ly / b, lx / a)
            st, ct = np.sin(tau), np.cos(tau)
            # Clockwise tangent (a sin t, -b cos t) in the ellipse frame, then rotated.
            tangents[m] = np.arctan2(-b * ct, a * st) + P.ell_angle[s]
            curv[m] = -(a * b) / (a * a * st * st + b * b * ct * ct) ** 1.5
            owner[m] = P.ell_owner[s]
        tangents = np.where(hit, np.mod(tangents + math.pi, _TAU) - math.pi, math.nan)
        return tangents, curv, owner


class FanCaster:
    """Casts one fixed fan of beams (a ladar's) again and again, with few numpy calls.

    The per-scan cost of a small world is the fixed cost of each numpy call, not the
    arithmetic, so this path works in the fan's own frame (its middle beam along +x),
    where the beam directions are constants: segments are rotated into it with complex
    numbers (a point is ``x + iy``), the faces the fan sees from behind are dropped, each
    remaining face's bearing interval comes from one ``arctan2`` call over all of them,
    and a (beam, face) pair needs one complex product for ``1/t`` (the nearest hit has the
    largest ``1/t``). Constants are 0-d arrays: a ufunc converts a Python float on every
    call, which costs more than the arithmetic on a few hundred numbers. Ellipses are
    mapped onto the unit circle with one complex matrix product for all beams; arcs use
    the caster's dense analytic code. Ranges agree with :meth:`RayCaster.cast` to rounding.
    The buffers are this object's own: make one per ladar.

    Parameters
    ----------
    caster : RayCaster
    rel : (B,) float array, radians
        Beam angles relative to the first beam, ascending, the last at most 2 pi.
    max_range : float, metres
        Finite and positive: hits beyond it are misses.
    compiled : bool, optional
        Cast the faces with the compiled loop (True), with numpy (False), or the compiled
        loop where this install has it (None, the default; see :data:`COMPILED`). Both
        give the same numbers.
    indexed : bool, optional
        With the compiled loop, in a world of more than 256 faces: walk each beam through
        the caster's :attr:`RayCaster.grid` (True, or None, the default) or cull the faces
        by bounding box and test every one within range (False). The same numbers where
        the faces met are the same; the walk reads only the faces along the beams.

    Raises
    ------
    ValueError
        A fan that is not ascending, wider than a turn, or an invalid range; or
        ``compiled=True`` on an install without the compiled loop.
    """

    def __init__(self, caster: RayCaster, rel: np.ndarray, max_range: float,
                 compiled: bool | None = None, indexed: bool | None = None) -> None:
        rel = np.asarray(rel, dtype=float).reshape(-1)
        if rel.shape[0] == 0 or rel[0] != 0.0 or bool((np.diff(rel) < 0).any()):
            raise ValueError("a fan's relative angles must start at 0 and ascend")
        if rel[-1] > _TAU:
            raise ValueError(f"a fan spans at most 2 pi radians, not {rel[-1]!r}")
        if not (math.isfinite(max_range) and max_range > 0):
            raise ValueError(f"a fan needs a finite, positive max_range, not {max_range!r}")
        if compiled and not COMPILED:
            raise ValueError("this install of mdle has no compiled fan cast (it was built "
                             "without a C compiler, or numpy rounds in a way it does not match)")
        self._kernel = _KERNEL if COMPILED and compiled is not False else None
        self.caster = caster
        self.max_range = float(max_range)
        n = rel.shape[0]
        self._half = 0.5 * float(rel[-1])
        self._rel_c = rel - self._half              # beams in [-half, half], fan frame
        self._dconj = np.exp(-1j * self._rel_c)     # conjugate beam directions, fan frame
        self._dirs = np.exp(1j * self._rel_c)
        # The nearest hit has the largest 1/t; a beam is a hit when its 1/t reaches
        # _inv_hit (t <= max_range within MAX_RANGE_SLACK, as in RayCaster.cast);
        # _inv_none marks "nothing yet", below that.
        self._t_hit = self.max_range * (1.0 + MAX_RANGE_SLACK)
        self._inv_hit = 1.0 / self._t_hit
        self._inv_none = 0.5 / self.max_range
        # The same numbers as 0-d arrays: a ufunc takes one far faster than a Python float.
        self._one = np.array(1.0)
        self._inv_hit_a = np.array(self._inv_hit)
        self._max_a = np.array(self.max_range)
        self._best = np.empty(n)
        m = caster._s0.shape[0]
        self._z = np.empty((4, m), dtype=complex)
        # Bearings of face starts are measured from the direction psi (fan frame), so
        # that arctan2's (-pi, pi] puts them in [half + eps - 2 pi, half + eps): then an
        # interval's copy one turn up holds no beam, two turns down neither (hi < lo + pi),
        # and one turn down only when hi reaches 3 pi - fov; hi (lo at most pi, the sweep
        # under pi) stays under 2 pi + 2 eps, so a fan narrower than pi never needs the
        # check (a ladar's half turn does: checked per scan).
        psi = self._half + _EPS_ANGLE - math.pi
        self._kappa = complex(math.cos(psi), -math.sin(psi))
        # World-frame rows (end, conj(start), kappa start, edge): a scan multiplies them by
        # (R, conj(R), R, R) and subtracts the origin's (c, conj(c), kappa c, 0), where R
        # turns the world into the fan frame and c = R o, giving (q, conj(p), kappa p, e).
        z0, ze = caster._z0, caster._ze
        self._zw = np.stack([z0 + ze, z0.conjugate(), self._kappa * z0, ze])
        self._rv = np.empty((4, 1), dtype=complex)
        self._off = np.zeros((4, 1), dtype=complex)
        self._rel_s = self._rel_c - psi             # the beams as seen from psi
        self._wrap_hi = 3.0 * math.pi - 2.0 * self._half - 3.0 * _EPS_ANGLE
        self._may_wrap = 2.0 * self._half + 5.0 * _EPS_ANGLE + 1e-9 >= math.pi
        self._pair_ids = np.arange(4 * n)            # grown on demand
        self._widen = np.array([[_EPS_ANGLE], [-_EPS_ANGLE]])   # rows: hi, lo
        self._kind = np.zeros(n, dtype=np.int8)
        self._which = np.zeros(n, dtype=np.intp)
        # Ellipses: x/a + i y/b = alpha z + beta conj(z) maps an ellipse's frame onto the
        # unit circle's, so a beam's direction there, for all beams and ellipses at once,
        # is [dirs, conj(dirs)] @ [[alpha conj(u) R], [beta u conj(R)]] (R: the fan's turn).
        P = caster.parts
        ia, ib = 1.0 / P.ell_axes[:, 0], 1.0 / P.ell_axes[:, 1]
        self._ell_alpha, self._ell_beta = 0.5 * (ia + ib), 0.5 * (ia - ib)
        self._ell_uconj = np.exp(-1j * P.ell_angle)
        self._ell_c = P.ell_center[:, 0] + 1j * P.ell_center[:, 1]
        self._ell_k = np.stack([self._ell_alpha * self._ell_uconj,
                                self._ell_beta * self._ell_uconj.conjugate()])
        self._ell_turn = np.empty((2, 1), dtype=complex)
        self._ell_coef = np.empty_like(self._ell_k)
        self._dd = np.column_stack([self._dirs, self._dirs.conjugate()])
        self._ell_kernel: _EllipseKernels | None = None
        self._ell_inplace = False
        if self._kernel is not None and _ELL is not None:
            inplace = self._ell_check(_ELL)
            if inplace is not None:
                self._ell_kernel, self._ell_inplace = _ELL, inplace
        # A world of ellipses only, compiled: a whole scan is one call.
        self._ellipses_only = self._ell_kernel is not None and not (
            caster._s0.shape[0] or len(caster.parts.arc_radius))
        self._t_none = 1.0 / self._inv_none     # a beam's t before anything is met
        # The grid walk (compiled only): the world's grid, and this fan's walker, which
        # holds the arrays above and its own per-face scratch.
        self._grid: FaceGrid | None = None
        self._walker: Any = None
        straight = not (len(caster.parts.arc_radius) or len(caster.parts.ell_angle))
        if (self._kernel is not None and _GRID_WALK is not None and indexed is not False
                and m > _CULL_ABOVE):
            self._grid = caster.grid
        if self._grid is not None and _GRID_WALK is not None:
            g = self._grid
            self._ranges, self._hit = np.empty(n), np.empty(n, dtype=bool)
            self._walker = _GRID_WALK(
                self._zw, caster._front_min, self._dconj, g.box, g.start, g.faces, self._best,
                self._ranges, self._hit, _EPS_ANGLE, bool(_FUSED), self._t_hit + _GRID_TOL,
                _GRID_TOL, self._inv_none, self._inv_hit, self.max_range)
        self._straight_walk = self._walker is not None and straight

    @property
    def compiled_ellipses(self) -> bool:
        """Whether this fan's ellipses go through the compiled cast (the same numbers)."""
        return self._ell_kernel is not None

    def _ell_check(self, kernels: _EllipseKernels) -> bool | None:
        """Check the compiled ellipse cast against numpy's for this fan and world.

        Returns how numpy rounds the in-place products of the ellipses' numbers (fused
        or not), or None where the compiled cast would not give numpy's numbers: then
        numpy casts. numpy's matmul hands ``(B, 2) @ (2, E)`` to BLAS, whose rounding
        depends on the library, the CPU and the shapes; the compiled cast follows
        OpenBLAS's for one ellipse (zgemv). That product is checked on this fan's beams
        with coefficients of every scale, and then whole casts from places round each
        ellipse (inside, on it, near and far), bit for bit. A world of many ellipses
        (their grid: products of varying width) keeps numpy's cast.
        """
        P = self.caster.parts
        e = P.ell_angle.shape[0]
        if e == 0 or _ABS_FUSED is None or self.caster.ellipse_grid is not None:
            return None
        rng = np.random.default_rng(e)
        for scale in (1e-6, 1e-2, 1.0, 1e2, 1e6):
            coef = (rng.standard_normal((2, e)) + 1j * rng.standard_normal((2, e))) * scale
            want = self._dd @ coef
            got = np.empty_like(want)
            kernels.product(self._dd, coef, got)
            if not np.array_equal(got.view(float), want.view(float)):
                return None
        inplace = _numpy_inplace_rounding(e)
        if inplace is None:
            return None
        axes, angle = P.ell_axes, P.ell_angle
        for k in range(12):
            j = k % e
            r, s = (0.3, 1.0, 1.0 + 1e-9, 1.5, 4.0, 30.0)[k % 6], 0.7 * k
            lx, ly = r * axes[j, 0] * math.cos(s), r * axes[j, 1] * math.sin(s)
            o = complex(self._ell_c[j] + complex(lx, ly) * complex(math.cos(angle[j]),
                                                                    math.sin(angle[j])))
            turn = complex(math.cos(1.3 * k), math.sin(1.3 * k))
            want = np.full(self._best.shape[0], self.max_range)
            self._ellipses_numpy(o, turn, want)
            got = np.full(self._best.shape[0], self.max_range)
            kernels.cast(got, self._dd, self._ell_k, self._ell_c, self._ell_uconj,
                         self._ell_alpha, self._ell_beta, o, turn, _T_MIN, bool(_FUSED),
                         bool(_ABS_FUSED), inplace)
            if got.tobytes() != want.tobytes():
                return None
        return inplace

    def cast(self, ox: float, oy: float, first: float) -> tuple[np.ndarray, np.ndarray]:
        """Cast the fan from ``(ox, oy)`` (m) with its first beam at world angle ``first``.

        Returns
        -------
        ranges : (B,) float array, metres (a new array)
            Distance to the first boundary; ``max_range`` where nothing is hit.
        hit : (B,) bool array (a new array)
            True where a boundary was hit closer than ``max_range``.
        """
        phi = first + self._half                    # world angle of the fan's middle
        rot = complex(math.cos(phi), -math.sin(phi))
        if self._straight_walk:
            # Straight faces only, through the grid: the whole scan in one compiled call.
            self._walker.scan(ox, oy, rot, complex(ox, oy) * rot)
            return self._ranges.copy(), self._hit.copy()
        if self._ellipses_only and self._ell_kernel is not None:
            # Ellipses only: the ranges' start, the ellipses and the finish in one call,
            # the steps below in their order.
            n = self._best.shape[0]
            t, hit = np.empty(n), np.empty(n, dtype=bool)
            self._ell_kernel.scan(t, hit, self._t_none, self._t_hit, self.max_range,
                                  self._dd, self._ell_k, self._ell_c, self._ell_uconj,
                                  self._ell_alpha, self._ell_beta, complex(ox, oy),
                                  rot.conjugate(), _T_MIN, bool(_FUSED), bool(_ABS_FUSED),
                                  self._ell_inplace)
            return t, hit
        caster = self.caster
        P = caster.parts
        best = self._best
        best.fill(self._inv_none)
        if caster._s0.shape[0]:
            self._segments(ox, oy, rot, best)
        t = np.divide(self._one, best)
        if len(P.arc_radius) or len(P.ell_angle):
            if len(P.arc_radius):
                d = self._dirs * rot.conjugate()    # world directions of the beams
                o = np.array((ox, oy))
                caster._arcs(o, d.real, d.imag, self.max_range, t, self._kind, self._which)
            if len(P.ell_angle):
                self._ellipses(complex(ox, oy), rot.conjugate(), t)
            hit = np.less_equal(t, self._t_hit)
        else:
            hit = np.greater_equal(best, self._inv_hit_a)
        np.minimum(t, self._max_a, out=t)
        return t, hit

    def batchable(self) -> bool:
        """Whether :meth:`cast_many` can cast this fan (segments only, no culling)."""
        P = self.caster.parts
        return not (len(P.arc_radius) or len(P.ell_angle)
                    or self.caster._s0.shape[0] > _CULL_ABOVE)

    def cast_many(self, ox: np.ndarray, oy: np.ndarray, first: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        """Cast the fan from ``S`` places at once: :meth:`cast` for each row, in one pass.

        For a team, whose robots' scans are all finished at the end of a tick: the
        fixed cost of the numpy calls is paid once for every robot. Only for a world
        :meth:`batchable` accepts (segments only, at most ``_CULL_ABOVE`` of them).
        The arithmetic is the same, element by element, as :meth:`cast`'s, so each row
        equals what :meth:`cast` returns from that place, bit for bit.

        Returns
        -------
        ranges, hit : (S, B) arrays (new)
        """
        caster = self.caster
        n_scan, n_beam = ox.shape[0], self._best.shape[0]
        m = caster._s0.shape[0]
        best = np.full(n_scan * n_beam, self._inv_none)
        if m:
            # A turn and an origin per place, in plain floats (a loop over robots, not
            # beams): math's cos and Python's complex products, as in :meth:`cast`.
            half, kappa = self._half, self._kappa
            rots = [complex(math.cos(p + half), -math.sin(p + half)) for p in first.tolist()]
            cs = [complex(x, y) * r for x, y, r in zip(ox.tolist(), oy.tolist(), rots,
                                                       strict=True)]
            if self._kernel is not None:    # every scan in one call
                self._compiled(self._zw, caster._front_min, best, np.array(rots),
                               np.array(cs), np.array([kappa * c for c in cs]))
            else:
                rv = np.array([rots, [r.conjugate() for r in rots], rots, rots])[:, :, None]
                off = np.array([cs, [c.conjugate() for c in cs], [kappa * c for c in cs],
                                [0j] * n_scan])[:, :, None]
                z = np.multiply(self._zw[:, None, :], rv)                     # (4, S, m)
                np.subtract(z, off, z)
                z = z.reshape(4, n_scan * m)
                self._faces(z, np.tile(caster._front_min, n_scan), best, m, n_beam)
        best = best.reshape(n_scan, n_beam)
        t = np.divide(self._one, best)
        hit = np.greater_equal(best, self._inv_hit_a)
        np.minimum(t, self._max_a, out=t)
        return t, hit

    def _segments(self, ox: float, oy: float, rot: complex, best: np.ndarray) -> None:
        caster = self.caster
        zw, front_min = self._zw, caster._front_min
        n_seg = front_min.shape[0]
        if self._walker is not None:     # best is the walker's own buffer
            self._walker.faces(ox, oy, rot, complex(ox, oy) * rot)
            return
        if n_seg > _CULL_ABOVE:
            # Large worlds: only the faces whose bounding box comes within range.
            r = self.max_range
            lo, hi = caster._bb_lo, caster._bb_hi
            near = lo[:, 0] <= ox + r
            near &= hi[:, 0] >= ox - r
            near &= lo[:, 1] <= oy + r
            near &= hi[:, 1] >= oy - r
            idx = near.nonzero()[0]
            if idx.shape[0] == 0:
                return
            if idx.shape[0] < n_seg:
                zw = zw.take(idx, axis=1)           # take: far faster than [:, idx] here
                front_min = front_min.take(idx)
        c = complex(ox, oy) * rot
        if self._kernel is not None:
            self._compiled(zw, front_min, best, rot, c, self._kappa * c)
            return
        rv, off = self._rv, self._off
        rv[0, 0] = rv[2, 0] = rv[3, 0] = rot
        rv[1, 0] = rot.conjugate()
        off[0, 0] = c
        off[1, 0] = c.conjugate()
        off[2, 0] = self._kappa * c
        z = np.multiply(zw, rv, out=self._z if zw is self._zw else None)
        np.subtract(z, off, z)                      # rows: q, conj(p), kappa p, e
        self._faces(z, front_min, best, 0, 0)

    def _compiled(self, zw: np.ndarray, front_min: np.ndarray, best: np.ndarray,
                  rot: complex | np.ndarray, c: complex | np.ndarray,
                  kc: complex | np.ndarray) -> None:
        """:meth:`_faces` of the world rows ``zw`` turned by ``rot`` less ``c``, in C.

        ``kc`` is ``kappa c`` as Python's complex product rounds it. One scan (complex
        numbers, ``best`` (B,)) or ``S`` (arrays of them, ``best`` (S * B,)).
        """
        assert self._kernel is not None
        self._kernel(zw, front_min, best, self._rel_s, self._dconj, rot, c, kc, _EPS_ANGLE,
                     self._wrap_hi, self._may_wrap, _FUSED)

    def _faces(self, z: np.ndarray, front_min: np.ndarray, best: np.ndarray, m: int,
               n_beam: int) -> None:
        """Raise ``best`` (1/t per beam) to the faces' hits; ``z`` rows from :meth:`_segments`.

        ``z`` is overwritten. For a batch (:meth:`cast_many`), face ``j`` belongs to scan
        ``j // m``, whose beams are ``n_beam`` apart in ``best`` (``m`` = 0: one scan).
        """
        # conj(p) q = (p . q) + i cross(p, e). numpy multiplies a single number in place in
        # its plain scalar loop, and everything else (a single number into a new array too)
        # in its SIMD loop, with the fused multiply-add the compiled loops follow.
        if z.shape[1] == 1:
            z[1] = np.multiply(z[1], z[0])
        else:
            np.multiply(z[1], z[0], z[1])
        # Only front faces (the solid on the far side, the origin off the face's line) can
        # be hit first: the rest is dropped here.
        ids = np.greater(z[1].imag, front_min).nonzero()[0]
        if ids.shape[0] == 0:
            return
        zf = z[1:].take(ids, axis=1)                # rows: conj(p) q, kappa p, e
        # Both angles in one flat call (a flat strided input skips numpy's buffered
        # iterator): sweep (p to q) then p from psi, face by face; then hi, lo.
        zr = zf[:2].reshape(-1)
        a = np.arctan2(zr.imag, zr.real).reshape(2, -1)
        hi = a[0]
        np.add(hi, a[1], hi)
        a += self._widen
        # 1/t = cross(d, e) / cross(p, e), with the edge e in the fan frame.
        f = np.divide(zf[2], zf[0].imag)
        if self._may_wrap and float(np.maximum.reduce(hi)) >= self._wrap_hi:
            a = np.concatenate([a, a - _TAU], axis=1)
            ids = np.concatenate([ids, ids])
            f = np.concatenate([f, f])
        k = self._rel_s.searchsorted(a)             # rows: first beam >= hi, first >= lo
        cnt = np.subtract(k[0], k[1])
        ends = cnt.cumsum()
        total = int(ends[-1])
        if total == 0:
            return
        # Pairs (beam, face), grouped by face: the face's beams k_lo .. k_hi - 1.
        np.subtract(k[0], ends, ends)               # k_lo less the pairs before the face
        if m:
            ends += ids // m * n_beam               # the scan's beams in `best`
            dconj = np.tile(self._dconj, best.shape[0] // n_beam)
        else:
            dconj = self._dconj
        pbeam = ends.repeat(cnt)
        if self._pair_ids.shape[0] < total:
            self._pair_ids = np.arange(2 * total)
        pbeam += self._pair_ids[:total]
        inv = np.multiply(dconj.take(pbeam), f.repeat(cnt)).imag
        np.maximum.at(best, pbeam, inv)

    def _ellipses(self, o: complex, turn: complex, t: np.ndarray) -> None:
        """Lower ``t`` (B,) to the nearest ellipse hit of each beam (exact, analytic).

        Compiled where :attr:`compiled_ellipses` (one call, the same numbers); the numpy
        code below is its reference.
        """
        if self._ell_kernel is not None:
            self._ell_kernel.cast(t, self._dd, self._ell_k, self._ell_c, self._ell_uconj,
                                  self._ell_alpha, self._ell_beta, o, turn, _T_MIN,
                                  bool(_FUSED), bool(_ABS_FUSED), self._ell_inplace)
        else:
            self._ellipses_numpy(o, turn, t)

    def _ellipses_numpy(self, o: complex, turn: complex, t: np.ndarray) -> None:
        """:meth:`_ellipses` in numpy: the compiled cast's reference."""
        centre, uconj, alpha, beta, rows = (self._ell_c, self._ell_uconj, self._ell_alpha,
                                            self._ell_beta, self._ell_k)
        # Many ellipses: only those of the cells in range. One farther away could only
        # lower a beam's t to beyond the range, which the scan then reads as a miss. The
        # product below then has fewer columns, which BLAS may round otherwise: ranges
        # within rounding of those cast with every ellipse.
        near = _in_reach(self.caster.ellipse_grid, o.real, o.imag, self.max_range)
        if near is not None:
            if near.shape[0] == 0:
                return
            centre, uconj, alpha, beta, rows = (centre[near], uconj[near], alpha[near],
                                                beta[near], rows[:, near])
        # The origin in each ellipse's frame, scaled to the unit circle (conjugated).
        v = o - centre
        v *= uconj
        oc = v.conjugate()
        oc *= alpha
        v *= beta
        oc += v                                     # conj(alpha v + beta conj(v))
        c = np.abs(oc)
        c *= c
        c -= 1.0                                    # > 0: the origin is outside
        sign = np.sign(c)
        k = self._ell_turn
        k[0, 0], k[1, 0] = turn, turn.conjugate()
        m = self._dd @ np.multiply(rows, k, out=self._ell_coef if near is None else None)
        a = np.abs(m)
        a *= a                                      # |m|^2
        q = m * oc                                  # real: m . o, imaginary: cross(o, m)
        disc = np.square(q.imag)
        np.subtract(a, disc, out=disc)              # (m . o)^2 - |m|^2 (|o|^2 - 1)
        with np.errstate(invalid="ignore", divide="ignore"):
            root = np.sqrt(disc)                    # NaN for a miss
            root *= sign
            root -= q.real
            # The entry point from outside, the exit from inside; free of cancellation.
            hit = np.divide(c, root, out=root)
        hit[~(hit > _T_MIN)] = math.inf              # behind, grazing at the origin, missed
        np.minimum(t, hit.min(axis=1), out=t)
