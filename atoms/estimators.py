"""Boundary estimators: points, connected surfaces, tangents and curvatures from one scan.

Over 500 lines: one vectorised pipeline (points, connected surfaces, then tangents and
curvatures over shared window indexes), used as one namespace (``estimators as E``) by
the laws, the experiments, the benchmark and ``docs/curvature.md``.

Everything here is numpy, vectorised over the whole scan (no Python loop over beams), and
never raises on well-formed arrays: where an estimate is undefined (an invalid beam, a window
that does not fit inside one connected surface) the result is NaN and ``valid`` is False.

Conventions (control-law.md section 2): points are in the robot frame (x forward, y left);
beams are in order of increasing bearing, index 0 on the robot's right. Walking the points in
that order traverses a visible surface with the obstacle on the right, so

* a tangent is the direction of travel along the surface in beam order (radians, robot frame);
* the signed curvature is ``dphi/ds`` along that direction: **convex obstacles are negative**,
  concave (inward) parts positive, a straight wall 0.

Three estimators of the paper (equations 7-11), all computing every window at once:

* :func:`classical_curvature`: the turning angle between the chords ``P[n]-P[n-w]`` and
  ``P[n+w]-P[n]`` divided by the arc length it is spread over (eqs. 7-9, see the note there);
* :func:`geometric_curvature`: the circle through ``P[n-w], P[n], P[n+w]`` (Heron/Menger, eq. 10);
* :func:`averaged_curvature`: the mean of the geometric estimate over windows (eq. 11, 7-9).

Each takes a :class:`Surfaces` (from :func:`surfaces`), optionally smoothed first with
:func:`smooth_positions` (Gaussian filter along each surface).

Example: five beams on a wall 1 m ahead (x = 1), seen from -20 to +20 degrees.

>>> import numpy as np
>>> b = np.radians([-20.0, -10.0, 0.0, 10.0, 20.0])
>>> r = 1.0 / np.cos(b)
>>> s = surfaces(r, b)
>>> s.labels.tolist()
[0, 0, 0, 0, 0]
>>> est = geometric_curvature(s, 1)
>>> est.valid.tolist()
[False, True, True, True, False]
>>> np.round(est.curvature[1:4], 6).tolist()
[0.0, 0.0, 0.0]
>>> float(np.degrees(est.tangent[2]).round(3))   # travelling left (+y) along the wall
90.0
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from mdle.atoms.memo import ByIdentity

__all__ = [
    "Surfaces",
    "Estimate",
    "scan_points",
    "valid_points",
    "beam_points",
    "points_of",
    "surfaces",
    "smooth_positions",
    "classical_curvature",
    "geometric_curvature",
    "averaged_curvature",
    "DEFAULT_WINDOWS",
]

#: Windows of the paper's averaged estimate (equation 11).
DEFAULT_WINDOWS: tuple[int, ...] = (7, 8, 9)
#: Smallest depth gap (metres) always accepted between neighbouring points of one surface.
DEFAULT_GAP = 0.10
#: Neighbours further apart than this many beam-spacing arcs (``r * dalpha``) are disconnected.
DEFAULT_GAP_FACTOR = 8.0


@dataclass(frozen=True, eq=False)
class Surfaces:
    """A scan as points split into connected surfaces.

    Attributes
    ----------
    points : (N, 2) float array, metres
        Robot-frame points, NaN for invalid beams.
    valid : (N,) bool array
        Beam saw a surface.
    start, end : (N,) int arrays
        Index of the first and last beam of the connected surface each beam lies on
        (an invalid beam is its own surface: ``start == end == index``).
    reach : (N,) int array
        The largest centred window that fits: ``min(n - start, end - n)`` (0 when invalid).
    """

    points: np.ndarray
    valid: np.ndarray
    start: np.ndarray
    end: np.ndarray
    reach: np.ndarray

    @property
    def labels(self) -> np.ndarray:
        """(N,) int array: surface number per beam (0, 1, ...), -1 for invalid beams."""
        first = self.start == np.arange(self.valid.size)
        return np.where(self.valid, np.cumsum(first & self.valid) - 1, -1)

    def fits(self, w: np.ndarray | int) -> np.ndarray:
        """Mask of beams whose centred window ``(n-w, n, n+w)`` lies on one surface.

        ``w`` scalar gives an (N,) mask, a (W,) array a (W, N) mask.
        """
        w = np.asarray(w)[..., None] if np.ndim(w) else np.asarray(w)
        return self.reach >= w


@dataclass(frozen=True, eq=False)
class Estimate:
    """Per-beam curvature and tangent from one estimator.

    Attributes
    ----------
    curvature : (N,) float array, 1/m
        Signed curvature (convex obstacle negative); NaN where not ``valid``.
    tangent : (N,) float array, radians
        Robot-frame direction of the surface in beam order; NaN where not ``valid``.
    valid : (N,) bool array
        Where the estimate is defined (the beam and its window lie on one surface).
    """

    curvature: np.ndarray
    tangent: np.ndarray
    valid: np.ndarray


@lru_cache(maxsize=16)
def _bearing_terms(key: bytes, gap_factor: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Compute the per-bearing constants of a scan layout, memoised and read-only.

    The unit directions ``cos a + i sin a``, the link limit per unit range of each beam
    spacing, ``gap_factor * |a[j+1] - a[j]|``, and a zero and a NaN per beam (numpy compares
    and selects against an array of the same shape for less than against a Python scalar):
    a pure function of the bearings, and one sensor always sends the same bearings.
    """
    a = np.frombuffer(key, dtype=np.float64)
    unit = np.empty(a.size, dtype=np.complex128)
    np.cos(a, out=unit.real)
    np.sin(a, out=unit.imag)
    spacing = gap_factor * np.abs(a[1:] - a[:-1])
    zero = np.zeros(a.size)
    nan = np.full(a.size, np.nan)
    for arr in (unit, spacing, zero, nan):
        arr.setflags(write=False)
    return unit, spacing, zero, nan


def _terms_of(a: np.ndarray, gap_factor: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return _bearing_terms(np.ascontiguousarray(a, dtype=float).tobytes(), float(gap_factor))


#: :func:`_bearing_terms` by the bearing array itself (a sensor's fixed bearings).
_terms_by_array = ByIdentity(_terms_of)


def _unit_directions(a: np.ndarray, gap_factor: float = DEFAULT_GAP_FACTOR
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return :func:`_bearing_terms` of a 1-D bearing array."""
    return _terms_by_array(a, gap_factor)


def _compiled_points() -> Callable[..., None] | None:
    """Return :func:`beam_points` in C (atoms/_points.c), or None where it was not built."""
    try:
        from mdle.atoms._points import beam_points as compiled
    except ImportError:
        return None
    return compiled


@dataclass(frozen=True)
class _CompiledPoints:
    """The compiled :func:`beam_points`, and how numpy's complex product rounds here."""

    kernel: Callable[..., None]
    fused: bool


def _checked_points() -> _CompiledPoints | None:
    """Return the compiled :func:`beam_points` where it gives numpy's numbers, else None.

    A point is a range times a unit direction, which numpy multiplies as complex numbers
    (with a fused multiply-add in its SIMD loop, or plainly): the rounding that matches
    numpy on awkward ranges (signed zeros, subnormals whose products underflow, NaN,
    infinities, negatives), in every quadrant, with and without a valid mask, is kept;
    with none, numpy finds the points.
    """
    kernel = _compiled_points()
    if kernel is None:
        return None
    ranges, bearings, valid = _probe_scan()
    unit = _terms_of(bearings, DEFAULT_GAP_FACTOR)[0]
    for fused in (True, False):
        if all(_same_points(_points_numpy(ranges, bearings, mask),
                            _points_compiled(kernel, fused, ranges, unit, mask))
               for mask in (None, valid)):
            return _CompiledPoints(kernel, fused)
    return None


def _probe_scan() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the ranges, bearings and valid mask :func:`_checked_points` compares on.

    The roundings differ only in the sign of a product that underflows to zero: the
    smallest subnormal range in every direction shows it.
    """
    odd = [0.0, -0.0, 5e-324, 1e-320, 2.2e-308, 1e-300, math.nan, math.inf, -math.inf, -1.0,
           1.0, 3.7, 9.999, 1e300]
    ranges = np.array(odd * 4 + [5e-324] * 72)
    bearings = np.linspace(-3.1, 3.1, ranges.shape[0])
    return ranges, bearings, np.arange(ranges.shape[0]) % 3 != 1


def _same_points(a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...]) -> bool:
    return all(x.tobytes() == y.tobytes() for x, y in zip(a, b, strict=True))


def _points_compiled(kernel: Callable[..., None], fused: bool, r: np.ndarray,
                     unit: np.ndarray, valid: np.ndarray | None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n = r.shape[0]
    z, ok, rr = np.empty(n, dtype=complex), np.empty(n, dtype=bool), np.empty(n)
    kernel(r, unit, valid, z, ok, rr, fused)
    return z, ok, rr


def beam_points(ranges: np.ndarray, bearings: np.ndarray, valid: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the points of a 1-D scan as complex ``x + iy``, NaN where a beam saw no surface.

    Also returns the mask of beams that saw one (``valid``, finite and positive range) and
    the ranges, NaN where not. What the boundary view and the safety layer's point list
    (:func:`points_of`) share in one tick.

    >>> z, ok, r = beam_points(np.array([1.0, np.inf, 2.0]), np.array([0.0, 0.1, np.pi / 2]))
    >>> ok.tolist(), r.tolist()
    ([True, False, True], [1.0, nan, 2.0])
    """
    # np.asarray costs as much as a small ufunc: skipped for the arrays a scan holds
    r = ranges if type(ranges) is np.ndarray and ranges.dtype.char == "d" \
        else np.asarray(ranges, dtype=float)
    compiled = _POINTS
    if compiled is not None and r.ndim == 1 and r.flags.c_contiguous and (
            valid is None or (type(valid) is np.ndarray and valid.dtype.char == "?"
                              and valid.shape == r.shape and valid.flags.c_contiguous)):
        unit = _unit_directions(bearings)[0]
        if unit.shape == r.shape:    # (else numpy says what does not fit)
            return _points_compiled(compiled.kernel, compiled.fused, r, unit, valid)
    return _points_numpy(r, bearings, valid)


def _points_numpy(r: np.ndarray, bearings: np.ndarray, valid: np.ndarray | None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`beam_points` in numpy (``r`` a float array): the compiled loop's reference."""
    unit, _, zero, nan = _unit_directions(bearings)
    ok = np.isfinite(r)
    ok &= r > zero
    if valid is not None:
        ok &= valid if type(valid) is np.ndarray and valid.dtype.char == "?" \
            else np.asarray(valid, dtype=bool)
    r = np.where(ok, r, nan)
    return r * unit, ok, r


#: The compiled :func:`beam_points`, checked against numpy (None: numpy's).
_POINTS = _checked_points()

#: A complex array viewed as rows of (x, y) floats in one call.
_XY = np.dtype((np.float64, (2,)))


def points_of(z: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Return the rows (M, 2) of the complex points ``z`` where ``ok``, as floats (x, y)."""
    return z[ok].view(_XY)


def _complex_points(ranges: np.ndarray, bearings: np.ndarray, valid: np.ndarray | None,
                    gap_factor: float = DEFAULT_GAP_FACTOR
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return :func:`beam_points` and the link limits per unit range of :func:`_bearing_terms`."""
    z, ok, r = beam_points(ranges, bearings, valid)
    return z, ok, r, _unit_directions(bearings, gap_factor)[1]


def valid_points(ranges: np.ndarray, bearings: np.ndarray,
                 valid: np.ndarray | None = None) -> np.ndarray:
    """Compute the robot-frame points (M, 2) of the beams of a 1-D scan that saw a surface.

    The finite rows of :func:`scan_points`, in beam order.

    >>> p = valid_points(np.array([1.0, np.inf, 2.0]), np.array([0.0, 0.1, np.pi / 2]))
    >>> p.round(6).tolist()
    [[1.0, 0.0], [0.0, 2.0]]
    """
    z, ok, _ = beam_points(ranges, bearings, valid)
    return points_of(z, ok)


def scan_points(ranges: np.ndarray, bearings: np.ndarray,
                valid: np.ndarray | None = None) -> np.ndarray:
    """Compute the robot-frame points of a scan.

    Parameters
    ----------
    ranges : (N,) float array, metres
    bearings : (N,) float array, radians, counter-clockwise from the heading
    valid : (N,) bool array, optional
        Beams that saw a surface; default: finite, positive ranges.

    Returns
    -------
    (N, 2) float array, metres; rows of invalid beams are NaN.

    >>> scan_points(np.array([1.0, 2.0]), np.array([0.0, np.pi / 2])).round(6).tolist()
    [[1.0, 0.0], [0.0, 2.0]]
    """
    r = np.asarray(ranges, dtype=float)
    if r.ndim == 1 and np.shape(bearings) == r.shape:
        z = _complex_points(r, bearings, valid)[0]
        return z.view(np.float64).reshape(r.shape + (2,))
    a = np.asarray(bearings, dtype=float)
    ok = np.isfinite(r) & (r > 0)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    r = np.where(ok, r, np.nan)
    pts = np.empty(r.shape + (2,))
    np.multiply(r, np.cos(a), out=pts[..., 0])
    np.multiply(r, np.sin(a), out=pts[..., 1])
    return pts


@lru_cache(maxsize=16)
def _beam_index(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return ``arange(n)``, its tail ``1..n-1`` and its head ``0..n-2`` (memoised, read-only)."""
    idx = np.arange(n)
    idx.setflags(write=False)
    return idx, idx[1:], idx[:-1]


def _segment_bounds(link: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Find the first and last index of each beam's run of linked neighbours, and the reach."""
    idx, tail, head = _beam_index(n)
    start = np.empty(n, dtype=np.intp)
    start[0] = 0  # a run starts where a beam is not linked to the one before it
    np.maximum.accumulate(tail * ~link, out=start[1:])
    end = np.empty(n, dtype=np.intp)
    end[-1] = n - 1  # ... and ends where it is not linked to the next one
    np.minimum.accumulate(np.where(link, n - 1, head)[::-1], out=end[-2::-1])
    return start, end, np.minimum(idx - start, end - idx)


def surfaces(ranges: np.ndarray, bearings: np.ndarray, valid: np.ndarray | None = None, *,
             gap: float = DEFAULT_GAP, gap_factor: float = DEFAULT_GAP_FACTOR) -> Surfaces:
    """Split a scan into connected surfaces, so that no window straddles a depth jump.

    Neighbouring beams ``j, j+1`` are connected when both saw a surface and their points are
    closer than ``max(gap, gap_factor * r_j * dalpha)``: a jump in depth, or a surface seen
    so obliquely that its samples are far apart, starts a new surface.

    Parameters
    ----------
    ranges, bearings : (N,) float arrays, metres and radians (increasing)
    valid : (N,) bool array, optional (default: finite positive ranges)
    gap : float, metres
    gap_factor : float

    Returns
    -------
    Surfaces

    >>> s = surfaces(np.array([1.0, 1.0, 3.0, 3.0, np.nan]), np.radians([-2.0, -1, 0, 1, 2]))
    >>> s.labels.tolist(), s.start.tolist(), s.end.tolist()
    ([0, 0, 1, 1, -1], [0, 0, 2, 2, 4], [1, 1, 3, 3, 4])
    """
    z, ok, r, spacing = _complex_points(ranges, bearings, valid, gap_factor)
    n = ok.size
    pts = z.view(np.float64).reshape(n, 2)
    if n < 2:
        e = np.arange(n)
        return Surfaces(pts, ok, e, e, np.zeros(n, dtype=np.intp))
    lim = spacing * r[:-1]
    np.maximum(lim, gap, out=lim)
    link = np.abs(z[1:] - z[:-1]) < lim  # NaN (an invalid end) compares False
    start, end, reach = _segment_bounds(link, n)
    return Surfaces(pts, ok, start, end, reach)


def smooth_positions(s: Surfaces, sigma: float = 1.0, truncate: float = 3.0) -> Surfaces:
    """Gaussian-smooth the points along each connected surface (never across a jump).

    Parameters
    ----------
    s : Surfaces
    sigma : float, beams
        Standard deviation of the kernel, in beam steps; 0 returns ``s`` unchanged.
    truncate : float
        Kernel half-width in sigmas. Near a surface's ends the kernel is cut and renormalised.

    Returns
    -------
    Surfaces with the same topology and smoothed ``points``.

    >>> b = np.radians(np.arange(-4.0, 5.0))
    >>> s = surfaces(1.0 / np.cos(b), b)
    >>> bool(np.allclose(smooth_positions(s, 1.5).points[:, 0], 1.0))   # a line stays put
    True
    """
    if sigma <= 0 or s.valid.size == 0:
        return s
    half = max(1, int(truncate * sigma + 0.5))
    k = np.arange(-half, half + 1)
    w = np.exp(-0.5 * (k / sigma) ** 2)
    n = np.arange(s.valid.size)
    idx = n[None, :] + k[:, None]                          # (K, N)
    inside = (idx >= s.start) & (idx <= s.end)
    wk = np.where(inside, w[:, None], 0.0)
    p = s.points[np.clip(idx, 0, n.size - 1)]              # (K, N, 2)
    p = np.where(inside[..., None], p, 0.0)
    sm = (wk[..., None] * p).sum(0) / wk.sum(0)[:, None]
    sm[~s.valid] = np.nan
    return Surfaces(sm, s.valid, s.start, s.end, s.reach)


@lru_cache(maxsize=64)
def _window_index(n: int, windows: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Build the index arrays of every window for an N-beam scan, memoised and read-only.

    A pure function (scans of one sensor always have the same N).

    Returns the (W, 1) windows and the (4, W, N) indices ``(n+w, n, n-w, n+w)`` (clipped to
    the scan), so one gather and one subtraction of neighbouring rows give all three sides
    of every window's triangle.
    """
    w = np.asarray(windows, dtype=np.intp).reshape(-1, 1)
    idx = np.arange(n)
    lo = np.maximum(idx - w, 0)
    hi = np.minimum(idx + w, max(n - 1, 0))
    ring = np.stack((hi, np.broadcast_to(idx, hi.shape), lo, hi))
    for a in (w, ring):
        a.setflags(write=False)
    return w, ring


def _window_key(windows: Sequence[int] | int) -> tuple[int, ...]:
    if isinstance(windows, (int, np.integer)):
        return (int(windows),)
    return tuple(map(int, windows))


def _sides(s: Surfaces, windows: Sequence[int] | int
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the sides of every window's triangle at once, as complex numbers ``x + iy``.

    Returns ``d`` (3, W, N): ``v = P[n+w]-P[n]``, ``u = P[n]-P[n-w]`` and ``-(u+v)``; their
    lengths (3, W, N); and the (W, N) mask of windows that fit on one surface. Invalid points
    are zeroed first so that windows that do not fit carry no NaN into the masked sums.
    """
    n = s.valid.size
    w, ring = _window_index(n, _window_key(windows))
    pts = s.points
    if not (pts.dtype == np.float64 and pts.flags.c_contiguous):
        pts = np.ascontiguousarray(pts, dtype=np.float64)
    z = np.where(s.valid, pts.view(np.complex128).reshape(n), 0.0)
    g = z[ring]
    d = g[:-1] - g[1:]
    return d, np.abs(d), s.reach >= w


def _average(kt: np.ndarray, ok: np.ndarray) -> Estimate:
    """Average over the windows that fit, NaN where none does.

    ``kt`` (2, W, N) complex holds half the curvature of each window in ``kt[0].real`` and
    its tangent, weighted by ``|u|`` (longer windows weigh more), in ``kt[1]``; both are 0
    where the window does not fit. ``kt[0].imag`` is scratch: it receives the mask, so one
    sum over the windows gives the curvature, the tangent and the count together.
    """
    np.copyto(kt[0].imag, ok)
    sums = kt[:, 0] if ok.shape[0] == 1 else np.add.reduce(kt, axis=1)  # (2, N)
    cnt = sums[0].imag
    with np.errstate(divide="ignore", invalid="ignore"):
        share = 2.0 / cnt  # inf where no window fits: 0 * inf = NaN marks "no estimate"
        kappa = sums[0].real * share
        hole = share * 0.0  # 0, or NaN where no window fits
    kappa += 0.0  # an exact straight line reads 0.0, not -0.0
    t = sums[1]  # the angle of the sum is the angle of the mean
    return Estimate(kappa, np.arctan2(t.imag + hole, t.real), cnt > 0)


def _masked_inverse(den: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Return ``1 / den`` where ``ok``, 0 elsewhere (``den`` finite and > 0 where ``ok``)."""
    inv = np.zeros(den.shape)
    np.divide(1.0, den, out=inv, where=ok)
    return inv


def classical_curvature(s: Surfaces, w: int | Sequence[int] = 1) -> Estimate:
    """Estimate classically: turning angle over arc length (equations 7-9), window ``w``.

    ``delta_theta`` is the signed angle from the chord ``P[n]-P[n-w]`` to ``P[n+w]-P[n]``
    (equation 8 gives its magnitude, the sign is the turn's). The turn is spread over the arc
    between the two chords' midpoints, i.e. half of equation 9's ``|P[n+w] - P[n-w]|``: taken
    literally, equation 9 returns half the curvature of a circle (for three points a central
    angle ``psi`` apart the chords turn by ``psi`` while ``|P[n+w]-P[n-w]| ~ 2 R psi``). With a
    sequence of windows, the estimates are averaged (as equation 11 does for the geometric one).

    The tangent at ``P[n]`` is the chord ``u = P[n] - P[n-w]`` turned by ``asin(|u| k / 2)``
    (as for the geometric estimate, with this estimate's ``k``).

    Parameters
    ----------
    s : Surfaces
    w : int or sequence of int, beams

    Returns
    -------
    Estimate with (N,) arrays; beams whose window leaves the surface are NaN / invalid.
    """
    d, a, ok = _sides(s, w)
    v, u = d[0], d[1]
    turn = v * u.conjugate()  # its argument is the signed turn from u to v
    ok &= a[2] > 0
    ok &= turn != 0
    kt = np.empty((2,) + ok.shape, dtype=np.complex128)
    half = kt[0].real
    np.arctan2(turn.imag, turn.real, out=half)
    half *= _masked_inverse(a[2], ok)  # k / 2
    sn = a[1] * half  # |sn| <= 1 up to rounding for a circle; clamp the cosine's argument
    c2 = sn * sn
    np.minimum(c2, 1.0, out=c2)
    np.subtract(1.0, c2, out=c2)
    rot = kt[1]
    np.sqrt(c2, out=rot.real)
    rot.imag[...] = sn
    rot *= u
    rot *= ok
    return _average(kt, ok)


def geometric_curvature(s: Surfaces, w: int | Sequence[int] = 1) -> Estimate:
    """Estimate geometrically: the circle through ``P[n-w], P[n], P[n+w]`` (equation 10).

    ``kappa = 4 * area / (a b c)`` (Heron's formula, with the area from the cross product,
    which is the same number without Heron's cancellation on thin triangles), signed by the
    turning direction of the three points. With a sequence of windows the estimates are
    averaged (equation 11).

    The tangent of that circle at its middle point ``P[n]`` is the chord
    ``u = P[n] - P[n-w]`` turned by half the arc it spans, ``asin(|u| k / 2)``: exact on a
    circle even when the beams sample it unevenly (the chord ``P[n+w] - P[n-w]`` is not). That
    rotation is computed without trigonometry, as the unit complex number
    ``(|(u+v).v| + i u x v) / (|v| |u+v|)`` (sine and cosine of the triangle's angle at
    ``P[n+w]``, the cosine taken non-negative as ``asin`` does).

    Parameters
    ----------
    s : Surfaces
    w : int or sequence of int, beams

    Returns
    -------
    Estimate with (N,) arrays.
    """
    d, a, fit = _sides(s, w)
    den = a[0] * a[1]
    den *= a[2]
    ok = den > 0
    ok &= fit
    inv = _masked_inverse(den, ok)
    m = d[0].conjugate()
    m *= d[2]  # -(u+v).v + i u x v
    np.abs(m.real, out=m.real)
    kt = np.empty((2,) + den.shape, dtype=np.complex128)
    np.multiply(m.imag, inv, out=kt[0].real)  # k / 2
    t = np.multiply(m, d[1], out=kt[1])
    t *= inv * a[1]  # / (|v| |u+v|): u turned by the unit rotation, weighted by |u|
    return _average(kt, ok)


def averaged_curvature(s: Surfaces, windows: int | Sequence[int] = DEFAULT_WINDOWS
                       ) -> Estimate:
    """Average the geometric estimate over ``windows`` (equation 11; the paper's choice 7-9).

    A beam is valid when at least one window fits on its surface; the mean is over those that
    fit (near a surface's end the larger windows drop out first).

    Parameters
    ----------
    s : Surfaces
    windows : int or sequence of int, beams
        One window is :func:`geometric_curvature` with that window.

    Returns
    -------
    Estimate with (N,) arrays.
    """
    return geometric_curvature(s, windows)
