"""The steering law: sign conventions, target-set behaviour, safeguards, closed loops."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pytest

from mdle.atoms import safety
from mdle.atoms import steering as S

if TYPE_CHECKING:
    from tests.atoms.conftest import LoopResult, World2D

G = S.Gains()


def _law(front: S.Ray, side: S.Ray, v: float, rc: float, g: S.Gains,
         umax: float | None = None) -> float:
    """The two-ray law's turn rate for one tick from a fresh start (no memory yet)."""
    return S.step(front, side, (0.0, 0.0, 0.0), 0.0, 0.01, S.Memory(), v, rc, g, umax)


def _z(points: np.ndarray) -> np.ndarray:
    """Robot-frame points (M, 2) as complex numbers (M,), as the safety layer reads them."""
    return points[:, 0] + 1j * points[:, 1]
ARGS = dict(side="right", rc=0.5, v=1.0, zeta=1.0, kf=0.5, umax=math.inf, tau=0.2, margin=0.15,
            lookahead=0.8, latency=math.inf)


@pytest.mark.parametrize("kappa", [-2.0, -1.0, -0.25, 0.0, 0.3, 0.7])
@pytest.mark.parametrize("rc", [0.5, 1.0])
def test_on_the_target_set_u_is_the_offset_curve_rate(kappa: float, rc: float) -> None:
    side = S.Ray(True, rc, 0.0, kappa)
    u = _law(S.MISS, side, 1.0, rc, G, umax=100.0)
    assert u == pytest.approx(kappa / (1.0 - kappa * rc), rel=1e-12, abs=1e-12)


def test_concave_side_curvature_is_clamped() -> None:
    # kappa rs >= 1: the offset curve does not exist; the clamp keeps 1 - k rs >= 0.2
    u = _law(S.MISS, S.Ray(True, 0.5, 0.0, 5.0), 1.0, 0.5, G, umax=100.0)
    kc = 0.8 / 0.5
    assert u == pytest.approx(kc / (1 - kc * 0.5))


def test_clf_decreases_along_the_law_when_the_front_misses() -> None:
    """dV/dt = A u + B <= 0 (control-law.md section 2) over random side states."""
    rng = np.random.default_rng(3)
    v, rc = 1.0, 0.5
    for _ in range(2000):
        bs = rng.uniform(-1.4, 1.4)
        rs = rng.uniform(0.1, 2.0)
        ks = rng.uniform(-3.0, 1.0)
        u = S.clf_law(S.MISS, S.Ray(True, rs, bs, ks), v, rc, G, 1e9)
        ks_c = min(ks, 0.8 * math.cos(bs) / rs)
        # on a convex boundary V's distance gain is kf (1 - ks rc)^2 (at most 4 kf): a
        # constant along a boundary of constant curvature
        f = S.f_gain(rs, rc, G) * (min(1 - ks_c * rc, 2.0) ** 2 if ks_c < 0 else 1.0)
        as_ = 1 - ks_c * rs / math.cos(bs)
        s2 = math.sin(-bs / 2)
        a = s2 * as_ - f * rs * math.tan(bs)
        b = -v * (s2 * ks_c / math.cos(bs) + f * math.tan(bs))
        d = math.cos(bs) - ks_c * rs + 2 * f * rs * math.cos(bs / 2)
        if d < G.d_min:
            continue  # the D clamp changes the feedforward there by design
        assert a * u + b <= 1e-9


@pytest.mark.parametrize("b0", [0.3, 1.0, math.pi / 2, 2.5])
def test_an_obstacle_ahead_turns_the_robot_left(b0: float) -> None:
    front = S.Ray(True, 1.0, b0, 0.0)
    assert _law(front, S.MISS, 1.0, 0.5, G) > 0


def test_front_floor_turns_fully_left_close_to_a_wall() -> None:
    front = S.Ray(True, 0.3, math.pi / 2, 0.0)   # wall 0.3 m ahead, square on
    side = S.Ray(True, 0.5, 0.0, -1.0)           # even with the side asking for a right turn
    assert _law(front, side, 1.0, 0.5, G) == pytest.approx(G.umax)


def test_grazing_and_far_front_hits_count_as_misses() -> None:
    side = S.Ray(True, 0.6, 0.1, 0.0)
    base = _law(S.MISS, side, 1.0, 0.5, G)
    assert _law(S.Ray(True, 1.0, 0.01, 0.0), side, 1.0, 0.5, G) == base   # grazing
    assert _law(S.Ray(True, 5.0, 1.5, 0.0), side, 1.0, 0.5, G) == base    # beyond 3 rc
    assert _law(S.MISS, S.Ray(True, 0.5, 1.55, 0.0), 1.0, 0.5, G) == 0.0  # side grazing


def test_front_blend_is_continuous_at_the_gate() -> None:
    side = S.Ray(True, 0.6, 0.1, -0.5)
    gate = G.front_gate * 0.5
    inside = _law(S.Ray(True, gate - 1e-9, 1.2, 0.0), side, 1.0, 0.5, G)
    outside = _law(S.Ray(True, gate + 1e-9, 1.2, 0.0), side, 1.0, 0.5, G)
    assert inside == pytest.approx(outside, abs=1e-6)


def test_saturation_at_the_given_limit() -> None:
    u = _law(S.MISS, S.Ray(True, 5.0, 1.2, -3.0), 1.0, 0.5, G, umax=0.7)
    assert abs(u) <= 0.7


def test_corner_mode_starts_when_the_side_ray_is_lost_and_circles_the_vertex() -> None:
    mem = S.Memory()
    side = S.Ray(True, 0.5, 0.0, 0.0)
    S.step(S.MISS, side, (0.0, 0.0, 0.0), 0.0, 0.01, mem, 1.0, 0.5, G)
    assert mem.mode == S.FOLLOW and mem.last_side is not None
    u = S.step(S.MISS, S.MISS, (0.01, 0.0, 0.0), 0.01, 0.01, mem, 1.0, 0.5, G)
    assert mem.mode == S.CORNER
    assert mem.corner == pytest.approx((0.0, -0.5))
    assert u < 0  # circling a vertex on the right turns right
    # a front hit ends the corner mode
    S.step(S.Ray(True, 1.0, 1.2, 0.0), S.MISS, (0.02, 0.0, 0.0), 0.02, 0.01, mem, 1.0, 0.5, G)
    assert mem.mode == S.FOLLOW


def test_corner_law_on_the_circle_is_the_circling_rate() -> None:
    assert S.corner_law(0.5, 0.0, 1.0, 0.5, G, 10.0) == pytest.approx(-2.0)


def test_safety_layer_keeps_a_clear_arc_and_replaces_a_blocked_one() -> None:
    far = np.array([[5.0, 5.0]])
    assert safety.filter_complex(_z(far), 1.0, 0.2, 3.0, 0.0, 0.05, 0.5) == (1.0, 0.2, math.inf)
    post = np.array([[0.35, 0.02]])  # a thin post just left of straight ahead, followed side
    v, u, own = safety.filter_complex(_z(post), 1.0, 0.0, 3.0, 0.0, 0.05, 0.5, side=1)
    assert own < 0.05
    assert v == 1.0 and u != 0.0
    # the chosen arc really clears the post
    th = u * np.linspace(0.0, 0.5, 200)
    path = np.stack((np.sin(th) / u, (1 - np.cos(th)) / u), axis=1)
    assert np.min(np.hypot(*(path - post[0]).T)) >= 0.05


def test_safety_layer_slows_down_in_a_dead_end() -> None:
    # a narrow wedge ahead, opening towards the robot: no arc at full speed escapes it
    t = np.linspace(0.0, 2.0, 200)[:, None]
    walls = np.vstack((np.hstack((t, 0.2 - 0.1 * t)), np.hstack((t, -0.2 + 0.1 * t))))
    v, u, own = safety.filter_complex(_z(walls[walls[:, 0] > 0.1]), 1.0, 0.0, 3.0, 0.0, 0.15, 0.8)
    assert own < 0.15
    assert v < 1.0  # slowed (or stopped to turn on the spot) rather than driving on


# ---- closed loops on exact shapes (tests/atoms/conftest.py), real atom, no simulator --------

def _steady(res: LoopResult, rc: float, t0: float) -> tuple[float, float]:
    half = res.t >= t0
    return float(res.clearance.min()), float(np.mean(np.abs(res.clearance[half] - rc)))


@pytest.mark.parametrize("side", ["right", "left"])
def test_closed_loop_circle_exact_rays(world2d: World2D, side: str) -> None:
    shape = world2d.Shape("circle", center=(0.0, 0.0), radius=2.0)
    y0 = 0.3 if side == "right" else -0.3
    res = world2d.run(shape, {**ARGS, "side": side, "rc": 1.0}, (-8.0, y0, 0.0),
                      duration=50.0, dt=0.01)
    worst, err = _steady(res, 1.0, 25.0)
    assert worst > 0.4
    assert err < 0.02
    # it goes round the obstacle the right way: clockwise for right, counter-clockwise for left
    ang = np.unwrap(np.arctan2(res.xy[:, 1], res.xy[:, 0]))
    assert (ang[-1] - ang[len(ang) // 2]) * (1 if side == "left" else -1) > 2.0


def test_closed_loop_square_noisy_scan_uses_corner_mode(world2d: World2D) -> None:
    shape = world2d.Shape("poly", vertices=[(-2, -2), (2, -2), (2, 2), (-2, 2)])
    res = world2d.run(shape, ARGS, (-8.0, 0.3, 0.0), duration=50.0, dt=0.02, exact=False,
                      noise=0.008, seed=1)
    worst, err = _steady(res, 0.5, 25.0)
    assert worst > 0.2
    assert err < 0.08
    assert 0.02 < np.mean(res.modes) < 0.4


def _arcs_brute(pts: np.ndarray, v: float, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clearance and nearest-point side of each arc (0.8 s, 8 samples), one arc at a time."""
    clear, cross = [], []
    for u in rates:
        s = v * 0.8 * np.arange(1, 9) / 8
        th = u / v * s
        ax = s if u == 0 else np.sin(th) / (u / v)
        ay = 0 * s if u == 0 else (1 - np.cos(th)) / (u / v)
        d = np.hypot(pts[None, :, 0] - ax[:, None], pts[None, :, 1] - ay[:, None])
        i, j = np.unravel_index(np.argmin(d), d.shape)
        clear.append(d[i, j])
        cross.append(math.cos(th[i]) * (pts[j, 1] - ay[i]) - math.sin(th[i]) * (pts[j, 0] - ax[i]))
    return np.array(clear), np.array(cross)


def test_own_arc_clearance_equals_the_candidate_computation_and_one_arc_at_a_time() -> None:
    rng = np.random.default_rng(0)
    for _ in range(300):
        pts = rng.uniform(-2.0, 2.0, (int(rng.integers(1, 80)), 2))
        v = float(rng.uniform(0.1, 1.0))
        u = 0.0 if rng.random() < 0.2 else float(rng.uniform(-3.0, 3.0))
        z = _z(pts)
        own = safety._own_clearance(z, v, u, 0.8, 8)
        assert own == pytest.approx(safety._arc_clearance(z, v, np.array([u]), 0.8, 8)[0][0],
                                    abs=1e-12)
        assert own == pytest.approx(_arcs_brute(pts, v, np.array([u]))[0][0], abs=1e-12)


def test_candidate_arcs_clearance_and_side_match_one_arc_at_a_time() -> None:
    rng = np.random.default_rng(1)
    rates = np.linspace(-3.0, 3.0, 25)  # the straight arc (rate 0) among them
    for _ in range(50):
        pts = rng.uniform(-1.5, 1.5, (int(rng.integers(1, 60)), 2))
        v = float(rng.uniform(0.1, 1.0))
        clear, cross = safety._arc_clearance(_z(pts), v, rates, 0.8, 8)
        want_clear, want_cross = _arcs_brute(pts, v, rates)
        assert clear == pytest.approx(want_clear, abs=1e-12)
        assert cross == pytest.approx(want_cross, abs=1e-12)


def test_admissible_rate_tried_nearest_first_is_the_nearest_admissible() -> None:
    # the staged search (a few rates nearest to u, then the rest) picks what a sweep of all
    # candidates picks: the admissible rate nearest to u, the lower one on a tie
    rng = np.random.default_rng(2)
    rates = np.linspace(-3.0, 3.0, 25)
    found = 0
    for n in range(400):
        pts = rng.uniform(-1.2, 1.2, (int(rng.integers(1, 40)), 2))
        v = float(rng.uniform(0.1, 1.0))
        u = float(rates[n % 25]) if n % 3 == 0 else float(rng.uniform(-3.0, 3.0))
        side, need = (-1, 1)[n % 2], float(rng.uniform(0.0, 0.3))
        clear, cross = _arcs_brute(pts, v, rates)
        ok = (clear - 0.1 >= need) & (cross * side > 0)
        want = float(rates[np.flatnonzero(ok)[np.argmin(np.abs(rates[ok] - u))]]) \
            if ok.any() else None
        got = safety._admissible(_z(pts), v, rates, u, 0.8, 8, 0.1, need, side)
        assert got == want
        found += want is not None and abs(want - u) > 0.5
    assert found > 20  # the rest, not only the few nearest, were needed and searched
