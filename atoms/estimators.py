"""Boundary estimators: points, connected surfaces, tangents and curvatures from one scan.

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

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = [
    "Surfaces",
    "Estimate",
    "scan_points",
    "surfaces",
    "smooth_positions",
    "menger",
    "classical_curvature",
    "geometric_curvature",
    "averaged_curvature",
    "estimate_scan",
    "principal_direction",
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


def scan_points(ranges: np.ndarray, bearings: np.ndarray,
                valid: np.ndarray | None = None) -> np.ndarray:
    """Robot-frame points of a scan.

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
    a = np.asarray(bearings, dtype=float)
    ok = np.isfinite(r) & (r > 0)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    r = np.where(ok, r, np.nan)
    pts = np.empty(r.shape + (2,))
    np.multiply(r, np.cos(a), out=pts[..., 0])
    np.multiply(r, np.sin(a), out=pts[..., 1])
    return pts


def _segment_bounds(link: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """First and last index of each beam's run of linked neighbours."""
    idx = np.arange(n)
    brk = np.empty(n, dtype=np.intp)
    brk[0] = 0
    brk[1:] = np.where(link, 0, idx[1:])
    start = np.maximum.accumulate(brk)
    brk[-1] = n - 1
    brk[:-1] = np.where(link, n - 1, idx[:-1])
    end = np.minimum.accumulate(brk[::-1])[::-1]
    return start, end


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
    pts = scan_points(ranges, bearings, valid)
    x = pts[:, 0]
    y = pts[:, 1]
    ok = x == x  # not NaN
    n = ok.size
    if n < 2:
        e = np.arange(n)
        return Surfaces(pts, ok, e, e, np.zeros(n, dtype=np.intp))
    dx = x[1:] - x[:-1]
    dy = y[1:] - y[:-1]
    r = np.asarray(ranges, dtype=float)[:-1]
    da = np.asarray(bearings, dtype=float)
    lim = np.maximum(gap_factor * np.abs(da[1:] - da[:-1]) * r, gap)
    link = dx * dx + dy * dy < lim * lim  # NaN (an invalid end) compares False
    start, end = _segment_bounds(link, n)
    idx = np.arange(n)
    return Surfaces(pts, ok, start, end, np.minimum(idx - start, end - idx))


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


def menger(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Signed curvature of the circle through three points (Heron/Menger, equation 10).

    ``4 * area / (a b c)``, with the area from the cross product (exactly Heron's value, but
    without its cancellation for thin triangles) and the sign of the turn ``p0 -> p1 -> p2``
    (left turn positive). Collinear points give 0; coincident points NaN.

    Parameters
    ----------
    p0, p1, p2 : (..., 2) float arrays, metres

    Returns
    -------
    (...,) float array, 1/m

    >>> float(menger(np.array([1.0, 0]), np.array([0.0, 1]), np.array([-1.0, 0])).round(9))
    1.0
    """
    ux, uy = p1[..., 0] - p0[..., 0], p1[..., 1] - p0[..., 1]
    vx, vy = p2[..., 0] - p1[..., 0], p2[..., 1] - p1[..., 1]
    cx, cy = p2[..., 0] - p0[..., 0], p2[..., 1] - p0[..., 1]
    den = np.sqrt((ux * ux + uy * uy) * (vx * vx + vy * vy) * (cx * cx + cy * cy))
    good = den > 0
    out = np.full(np.shape(den), np.nan)
    np.divide(2.0 * (ux * vy - uy * vx), den, out=out, where=good)
    return out


@lru_cache(maxsize=64)
def _window_index(n: int, windows: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Index arrays of every window for an N-beam scan (a pure function, memoised: scans of
    one sensor always have the same N). Returned read-only."""
    w = np.asarray(windows, dtype=np.intp).reshape(-1, 1)
    idx = np.arange(n)
    lo = np.maximum(idx - w, 0)
    hi = np.minimum(idx + w, max(n - 1, 0))
    for a in (w, lo, hi):
        a.setflags(write=False)
    return w, lo, hi


def _windows(s: Surfaces, windows: Sequence[int] | int
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every window at once, as complex numbers ``x + iy``.

    Returns the chords u = P[n]-P[n-w] and v = P[n+w]-P[n], each (W, N), and the (W, N) mask
    of windows that fit on one surface.
    """
    key = (int(windows),) if isinstance(windows, (int, np.integer)) else tuple(map(int, windows))
    n = s.valid.size
    w, lo, hi = _window_index(n, key)
    ok = s.reach >= w
    z = np.ascontiguousarray(s.points).view(np.complex128).reshape(n)
    return z - z[lo], z[hi] - z, ok


def _finish(k: np.ndarray, u: np.ndarray, au: np.ndarray, ok: np.ndarray) -> Estimate:
    """Average the windows that fit (``k`` is 0 elsewhere) and give the tangent at ``P[n]``.

    The tangent of the circle through the window's points, at its middle point, is the chord
    ``u = P[n] - P[n-w]`` turned by half the arc it spans, ``asin(|u| k / 2)``: exact on a
    circle even when the beams sample it unevenly (the chord ``P[n+w] - P[n-w]`` is not).
    """
    s = 0.5 * au * k  # |s| <= 1: a chord is never longer than the diameter (up to rounding)
    s2 = s * s
    np.minimum(s2, 1.0, out=s2)
    t = u * (np.sqrt(1.0 - s2) + 1j * s)  # |t| = |u|: longer windows weigh more
    if k.shape[0] == 1:
        valid = ok[0]
        kappa = k[0]
        t = t[0]
    else:
        cnt = ok.sum(0)
        valid = cnt > 0
        kappa = k.sum(0) / np.maximum(cnt, 1)
        t = np.where(ok, t, 0.0).sum(0)
    invalid = ~valid
    kappa[invalid] = np.nan
    tangent = np.angle(t)
    tangent[invalid] = np.nan
    return Estimate(kappa, tangent, valid)


def classical_curvature(s: Surfaces, w: int | Sequence[int] = 1) -> Estimate:
    """Classical estimate: turning angle over arc length (equations 7-9), window ``w``.

    ``delta_theta`` is the signed angle from the chord ``P[n]-P[n-w]`` to ``P[n+w]-P[n]``
    (equation 8 gives its magnitude, the sign is the turn's). The turn is spread over the arc
    between the two chords' midpoints, i.e. half of equation 9's ``|P[n+w] - P[n-w]|``: taken
    literally, equation 9 returns half the curvature of a circle (for three points a central
    angle ``psi`` apart the chords turn by ``psi`` while ``|P[n+w]-P[n-w]| ~ 2 R psi``). With a
    sequence of windows, the estimates are averaged (as equation 11 does for the geometric one).

    Parameters
    ----------
    s : Surfaces
    w : int or sequence of int, beams

    Returns
    -------
    Estimate with (N,) arrays; beams whose window leaves the surface are NaN / invalid.
    """
    u, v, ok = _windows(s, w)
    cl = np.abs(u + v)
    turn = v * u.conjugate()  # its argument is the signed turn from u to v
    ok &= (cl > 0) & (turn != 0)
    k = np.divide(2.0 * np.angle(turn), cl, out=np.zeros_like(cl), where=ok)
    return _finish(k, u, np.abs(u), ok)


def geometric_curvature(s: Surfaces, w: int | Sequence[int] = 1) -> Estimate:
    """Geometric estimate: the circle through ``P[n-w], P[n], P[n+w]`` (equation 10).

    ``kappa = 4 * area / (a b c)`` (Heron's formula, with the area from the cross product,
    which is the same number without Heron's cancellation on thin triangles), signed by the
    turning direction of the three points. With a sequence of windows the estimates are
    averaged (equation 11).

    Parameters
    ----------
    s : Surfaces
    w : int or sequence of int, beams

    Returns
    -------
    Estimate with (N,) arrays.
    """
    u, v, ok = _windows(s, w)
    au = np.abs(u)
    den = au * np.abs(v) * np.abs(u + v)
    ok &= den > 0
    k = np.divide(2.0 * (v * u.conjugate()).imag, den, out=np.zeros_like(den), where=ok)
    return _finish(k, u, au, ok)


def averaged_curvature(s: Surfaces, windows: Sequence[int] = DEFAULT_WINDOWS) -> Estimate:
    """Averaged geometric estimate over ``windows`` (equation 11; the paper's choice 7-9).

    A beam is valid when at least one window fits on its surface; the mean is over those that
    fit (near a surface's end the larger windows drop out first).

    Parameters
    ----------
    s : Surfaces
    windows : sequence of int, beams

    Returns
    -------
    Estimate with (N,) arrays.
    """
    return geometric_curvature(s, windows)


_METHODS = {"classical": classical_curvature, "geometric": geometric_curvature,
            "averaged": averaged_curvature}


def estimate_scan(ranges: np.ndarray, bearings: np.ndarray, valid: np.ndarray | None = None, *,
                  method: str = "averaged", windows: int | Sequence[int] = DEFAULT_WINDOWS,
                  sigma: float = 0.0) -> Estimate:
    """One call from a scan's arrays to per-beam curvature and tangent.

    Parameters
    ----------
    ranges, bearings : (N,) float arrays, metres and radians
    valid : (N,) bool array, optional
    method : {"averaged", "geometric", "classical"}
    windows : int or sequence of int, beams
    sigma : float, beams
        Gaussian smoothing of the positions first (0: none).

    Returns
    -------
    Estimate

    Raises
    ------
    ValueError
        For an unknown ``method`` (a programming error, not a tick-path condition).
    """
    try:
        fn = _METHODS[method]
    except KeyError:
        raise ValueError(f"unknown curvature method {method!r}; "
                         f"choose one of {', '.join(_METHODS)}") from None
    s = surfaces(ranges, bearings, valid)
    if sigma > 0:
        s = smooth_positions(s, sigma)
    return fn(s, windows)  # type: ignore[operator,arg-type]


def principal_direction(points: np.ndarray) -> float:
    """Direction of the total-least-squares line through points, oriented first -> last.

    The points are centred (and the fit is scale-free), so the answer does not depend on how
    far they are from the origin. NaN for fewer than two distinct points.

    Parameters
    ----------
    points : (M, 2) float array, metres, in traversal order

    Returns
    -------
    float, radians

    >>> round(float(np.degrees(principal_direction(np.array([[0.0, 0], [1, 1], [2, 2.0]])))), 6)
    45.0
    """
    p = np.asarray(points, dtype=float)
    if p.shape[0] < 2 or not np.all(np.isfinite(p)):
        return float("nan")
    q = p - p.mean(0)
    sxx, syy, sxy = (q[:, 0] ** 2).sum(), (q[:, 1] ** 2).sum(), (q[:, 0] * q[:, 1]).sum()
    if sxx + syy <= 0:
        return float("nan")
    ang = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    d = p[-1] - p[0]
    if np.cos(ang) * d[0] + np.sin(ang) * d[1] < 0:
        ang += np.pi
    return float(np.arctan2(np.sin(ang), np.cos(ang)))
