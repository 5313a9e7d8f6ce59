"""The fast paths against plain reference computations written the slow, obvious way.

The estimators stack every window into one computation and the boundary view reads only the
beams its two rays need, with closed-form fits; here each is checked against a per-window
loop, an eigenvector line fit and ``np.polyfit`` on noisy scans, and on degenerate scans
(coincident points, a side fit with only two distinct abscissae).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pytest

from mdle.atoms import estimators as E
from mdle.atoms.boundary import boundary_view
from mdle.core.backend import Scan

if TYPE_CHECKING:
    from tests.atoms.conftest import Raycast


def _noisy_scene(raycast: Raycast, seed: int, centre: tuple[float, float] = (1.5, 0.0),
                 radius: float = 0.5) -> Scan:
    """A wall 0.6 m to the right and a cylinder ahead, 0.8 % range noise."""
    rng = np.random.default_rng(seed)
    r = np.minimum(raycast.line((0.0, -0.6), (0.0, -1.0)), raycast.circle(centre, radius))
    return raycast.scan(r * (1.0 + rng.normal(0.0, 0.008, r.shape)))


def _menger(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Signed curvature of the circle through three points: 4 area / (a b c), left turn +.

    Collinear points give 0, coincident points NaN (the estimators mark those invalid).
    """
    ux, uy = p1[..., 0] - p0[..., 0], p1[..., 1] - p0[..., 1]
    vx, vy = p2[..., 0] - p1[..., 0], p2[..., 1] - p1[..., 1]
    cx, cy = p2[..., 0] - p0[..., 0], p2[..., 1] - p0[..., 1]
    den = np.sqrt((ux * ux + uy * uy) * (vx * vx + vy * vy) * (cx * cx + cy * cy))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, 2.0 * (ux * vy - uy * vx) / den, np.nan)


def test_menger_reference_on_a_unit_circle() -> None:
    k = _menger(np.array([1.0, 0.0]), np.array([0.0, 1.0]), np.array([-1.0, 0.0]))
    assert float(k) == pytest.approx(1.0, abs=1e-12)
    assert np.isnan(_menger(np.zeros(2), np.zeros(2), np.ones(2)))


def _reference_geometric(pts: np.ndarray, start: np.ndarray, end: np.ndarray,
                         windows: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Equation 11 one window at a time: circle through three points, tangent at the middle."""
    n = pts.shape[0]
    ks = np.zeros((len(windows), n))
    ts = np.zeros((len(windows), n), dtype=complex)
    fit = np.zeros((len(windows), n), dtype=bool)
    idx = np.arange(n)
    for i, w in enumerate(windows):
        ok = (idx - w >= start) & (idx + w <= end)
        lo, hi = np.clip(idx - w, 0, n - 1), np.clip(idx + w, 0, n - 1)
        p0, p1, p2 = pts[lo], pts[idx], pts[hi]
        k = _menger(p0, p1, p2)
        ok &= np.isfinite(k)
        u = p1 - p0
        half = np.arcsin(np.clip(0.5 * np.hypot(u[:, 0], u[:, 1]) * np.where(ok, k, 0), -1, 1))
        ts[i] = np.where(ok, (u[:, 0] + 1j * u[:, 1]) * np.exp(1j * half), 0)
        ks[i] = np.where(ok, k, 0.0)
        fit[i] = ok
    cnt = fit.sum(0)
    with np.errstate(invalid="ignore"):
        kappa = ks.sum(0) / cnt
    tangent = np.where(cnt > 0, np.angle(ts.sum(0)), np.nan)
    return kappa, tangent


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("windows", [(7, 8, 9), (1,), (2, 5)])
def test_averaged_estimate_matches_a_per_window_loop(raycast: Raycast, seed: int,
                                                     windows: tuple[int, ...]) -> None:
    scan = _noisy_scene(raycast, seed, centre=(2.0, 0.5))
    s = E.surfaces(scan.ranges, scan.bearings, scan.valid)
    est = E.geometric_curvature(s, windows)
    kappa, tangent = _reference_geometric(s.points, s.start, s.end, windows)
    assert np.array_equal(est.valid, np.isfinite(kappa))
    assert est.valid.sum() > 60
    np.testing.assert_allclose(est.curvature, kappa, rtol=1e-9, atol=1e-9)
    diff = np.angle(np.exp(1j * (est.tangent[est.valid] - tangent[est.valid])))
    assert np.abs(diff).max() < 1e-9
    assert np.isnan(est.tangent[~est.valid]).all() and np.isnan(est.curvature[~est.valid]).all()


def test_bearing_memo_follows_the_bearings(raycast: Raycast) -> None:
    # two layouts of the same size, one after the other: each gets its own directions
    r = np.full(181, 2.0)
    for b in (raycast.bearings, raycast.bearings[::-1].copy(),
              np.radians(np.linspace(-60, 60, 181))):
        pts = E.scan_points(r, b)
        np.testing.assert_allclose(pts, np.stack((2 * np.cos(b), 2 * np.sin(b)), 1), atol=1e-15)
        s = E.surfaces(r, b)
        np.testing.assert_allclose(s.points, pts, atol=1e-15)


def _reference_side_fit(pts: np.ndarray) -> tuple[float, float]:
    """Tangent angle and curvature at pts[0]: eigenvector line, then np.polyfit quadratic."""
    q = pts - pts.mean(0)
    evals, evecs = np.linalg.eigh(q.T @ q)
    d = evecs[:, np.argmax(evals)]
    if d @ (pts[-1] - pts[0]) < 0:
        d = -d
    nrm = np.array([-d[1], d[0]])
    s, h = q @ d, q @ nrm
    c2, c1, _ = np.polyfit(s, h, 2)
    slope = c1 + 2 * c2 * s[0]
    return math.atan2(d[1], d[0]) + math.atan(slope), 2 * c2 / (1 + slope * slope) ** 1.5


@pytest.mark.parametrize("seed", range(6))
def test_view_matches_the_full_scan_estimates(raycast: Raycast, seed: int) -> None:
    scan = _noisy_scene(raycast, seed)
    view = boundary_view(scan, "right")
    assert view.front.hit and view.side.hit
    # front ray: the averaged estimate of the whole scan at the 0-degree beam
    est = E.averaged_curvature(E.surfaces(scan.ranges, scan.bearings, scan.valid))
    assert view.front.kappa == pytest.approx(est.curvature[90], rel=1e-9)
    assert view.front.beta == pytest.approx(est.tangent[90], abs=1e-9)
    # side ray: the quadratic fit over the 31 beams from -90 degrees
    s = E.surfaces(scan.ranges, scan.bearings, scan.valid)
    assert s.end[0] >= 30
    beta, kappa = _reference_side_fit(s.points[:31])
    assert math.remainder(view.side.beta - beta, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert view.side.kappa == pytest.approx(kappa, rel=1e-7, abs=1e-9)
    assert view.side.r == scan.ranges[0]


@pytest.mark.parametrize("last", [140, 94])
def test_all_window_points_equal_gives_the_longer_sides_chord(raycast: Raycast, last: int) -> None:
    # 41 beams on one bearing and range: every window at the front beam (70) is degenerate,
    # so the view falls back to the one-sided chord towards the longer side of the surface,
    # which reaches beyond every window on both sides (the view must look further to know)
    b = raycast.bearings.copy()
    b[70:111] = 0.0
    r = np.full(181, 10.0)
    r[40:last + 1] = 1.0 / np.maximum(np.cos(b[40:last + 1]), 0.2)
    scan = raycast.scan(r, b)
    s = E.surfaces(scan.ranges, b, scan.valid)
    c = int(np.argmin(np.abs(b)))
    right, left = c - int(s.start[c]), int(s.end[c]) - c
    assert min(right, left) > 9 and (left >= right) == (last == 140)
    m = 9
    chord = s.points[c + m] - s.points[c] if left >= right else s.points[c] - s.points[c - m]
    for side, sc in (("right", scan), ("left", _mirror(scan))):
        view = boundary_view(sc, side)
        assert view.front.hit and view.front.kappa == 0.0 and view.front.r == 1.0
        assert view.front.beta == pytest.approx(math.atan2(chord[1], chord[0]), abs=1e-12)


def _mirror(scan: Scan) -> Scan:
    """The same scene reflected left-right (y -> -y)."""
    return Scan(scan.ranges[::-1].copy(), -scan.bearings[::-1], scan.valid[::-1].copy(),
                scan.stamp, scan.max_range)


def test_side_fit_with_two_distinct_abscissae_uses_the_minimum_norm_solution(
        raycast: Raycast) -> None:
    b = raycast.bearings.copy()
    b[1:40] = math.radians(-89.0)   # beam 0 and then one point repeated
    r = np.full(181, 10.0)
    r[:40] = 0.5
    view = boundary_view(raycast.scan(r, b), "right")
    p0 = 0.5 * np.array([math.cos(b[0]), math.sin(b[0])])
    p1 = 0.5 * np.array([math.cos(b[1]), math.sin(b[1])])
    assert view.side.hit and abs(view.side.kappa) < 1e-9
    assert view.side.beta == pytest.approx(math.atan2(*(p1 - p0)[::-1]), abs=1e-9)


def _next_nearest_reference(z: np.ndarray, fitted: np.ndarray) -> tuple[float, float] | None:
    """The next face one point at a time: range and bearing of the nearest qualifying point.

    A point qualifies when it is not fitted, lies less than 45 deg left of the heading, and
    is the nearest of the 10 points on either side of it or lies on another surface than the
    first fitted point (surfaces: runs of points less than ``JUMP`` apart).
    """
    from mdle.atoms import closest as C

    m = z.size
    d = np.abs(z)
    surface = [0] * m
    for i in range(1, m):
        surface[i] = surface[i - 1] + (abs(z[i] - z[i - 1]) > C.JUMP)
    own = surface[int(np.flatnonzero(fitted)[0])]
    best = None
    for k in range(m):
        window = d[max(0, k - C.WINDOW):k + C.WINDOW + 1]
        qualifies = (d[k] <= window.min() or surface[k] != own) and not fitted[k] \
            and z[k].imag < z[k].real and d[k] > 0
        if qualifies and (best is None or d[k] < d[best]):
            best = k
    return None if best is None else (float(d[best]), float(np.angle(z[best])))


@pytest.mark.parametrize("seed", range(40))
def test_next_face_matches_the_one_point_at_a_time_reference(seed: int) -> None:
    from mdle.atoms import closest as C

    rng = np.random.default_rng(seed)
    bearings = np.radians(np.arange(-90.0, 90.5, 1.0))
    # poles and walls at random, some beams missing: several surfaces, gaps in the list
    r = np.full(bearings.size, np.inf)
    for _ in range(int(rng.integers(1, 5))):
        c = complex(rng.uniform(-1.0, 3.0), rng.uniform(-2.5, 2.5))
        rho = rng.uniform(0.05, 0.6)
        u = np.exp(1j * bearings)
        b = (u.conjugate() * c).real
        disc = b * b - abs(c) ** 2 + rho * rho
        hit = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        r = np.minimum(r, np.where(hit > 0, hit, np.inf))
    r *= 1.0 + rng.normal(0.0, 0.008, r.shape)
    r[rng.random(r.size) < 0.05] = np.inf
    ok = np.isfinite(r)
    if ok.sum() < 3:
        return
    z = r[ok] * np.exp(1j * bearings[ok])
    z = np.round(z, 3)  # millimetre points: ties between equal ranges are common
    d2 = (z * z.conjugate()).real
    fitted = np.zeros(z.size, dtype=bool)
    first = int(rng.integers(0, z.size))
    fitted[first:first + int(rng.integers(1, 12))] = True
    ray = C.next_nearest(z, d2, fitted)
    want = _next_nearest_reference(z, fitted)
    if want is None:
        assert not ray.hit
    else:
        assert ray.hit and ray.r == pytest.approx(want[0], abs=1e-12)
        # the ray's tangent is perpendicular to the line of sight: beta = bearing + pi/2
        assert math.remainder(ray.beta - want[1] - math.pi / 2, 2 * math.pi) \
            == pytest.approx(0.0, abs=1e-12)

