"""The safety layer's arcs on a robot that ramps its turn rate (issue 23, the Pioneer's left).

Checked as if a command took at once, a turn back towards the boundary looked, to the safety
layer, like a swing into the face the robot was still turning away from: the layer asked for
more turn away, one tick of ramp at a time, and in a notch the robot wound up to 2 rad/s,
took over a second to unwind and swung out to 0.9-1.0 m at rc 0.55.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
import pytest

from mdle.atoms import safety
from mdle.atoms.fillet import turn_margin
from mdle.atoms.ramped_arcs import (
    SUBSTEPS,
    Ramp,
    heading_at,
    ramped_arc,
    ramped_turn_margin,
)
from tests.atoms.conftest import p3dx_lab_run

ACCEL = 1.74  # rad/s^2, the P3-DX profile's turn acceleration


def _integrated(speed: float, rate0: float, rate: float, accel: float, t: float,
                steps: int = 20000) -> complex:
    """The ramped path's end by brute force: the rate stepped towards the command each step."""
    h = t / steps
    w, th, p = rate0, 0.0, 0j
    for _ in range(steps):
        w_next = w + max(-accel * h, min(accel * h, rate - w))
        th_mid = th + 0.5 * (w + w_next) * h * 0.5
        p += speed * h * cmath.exp(1j * th_mid)
        th += 0.5 * (w + w_next) * h
        w = w_next
    return p


def test_the_heading_is_the_integral_of_the_ramped_rate() -> None:
    # from 1.0 rad/s commanded -1.0: the ramp lasts 2 / 1.74 s, then the rate holds
    ramp = 2.0 / ACCEL
    assert heading_at(0.5, 1.0, -1.0, ACCEL) == pytest.approx(0.5 - 0.5 * ACCEL * 0.25)
    at_end = 1.0 * ramp - 0.5 * ACCEL * ramp * ramp
    assert at_end == pytest.approx(0.0)  # up and back down to where it started turning
    assert heading_at(ramp + 0.3, 1.0, -1.0, ACCEL) == pytest.approx(-0.3)
    assert heading_at(0.7, 0.4, 0.4, ACCEL) == pytest.approx(0.28)  # at the command already
    assert heading_at(0.7, 0.0, 2.0, math.inf) == pytest.approx(1.4)  # no limit


@pytest.mark.parametrize(("rate0", "rate"), [(1.5, -1.5), (-0.5, 2.0), (0.3, 0.3)])
def test_the_ramped_arc_follows_the_path_driven(rate0: float, rate: float) -> None:
    points, headings = ramped_arc(0.3, rate0, rate, ACCEL, 0.8, 8)
    assert len(points) == len(headings) == 8
    assert points[-1] == pytest.approx(_integrated(0.3, rate0, rate, ACCEL, 0.8), abs=2e-4)
    assert points[3] == pytest.approx(_integrated(0.3, rate0, rate, ACCEL, 0.4), abs=2e-4)
    assert headings[-1] == pytest.approx(heading_at(0.8, rate0, rate, ACCEL))


def test_without_a_limit_the_ramped_arc_is_the_safety_layers_plain_arc() -> None:
    plain = safety._arc(0.3, -1.2, 0.8, 8)
    points, _ = ramped_arc(0.3, 0.7, -1.2, math.inf, 0.8, 8)
    assert np.allclose(points, plain, atol=1e-4)


def _wall_on_the_right(y: float = -0.45) -> np.ndarray:
    """Scan points of a wall parallel to the heading on the right (law frame), 1 cm apart."""
    x = np.arange(-0.2, 1.5, 0.01)
    return x + 1j * y


def test_a_turn_back_while_the_robot_still_turns_away_is_let_through() -> None:
    """The robot turns away at 1.5 rad/s and is asked to turn back at 1.5: checked at once,
    the arc bends into the wall (0.32 m from the centre, the body 0.25 and the margin 0.15);
    the robot's own path still turns away for 0.8 s, and stays clear."""
    z = _wall_on_the_right()
    v, u = safety.filter_complex(z, 0.3, -1.5, 8.7, 0.25, 0.15, 0.8)[:2]
    assert u > -1.5  # at once: refused, a turn away picked instead
    v, u = safety.filter_complex(z, 0.3, -1.5, 8.7, 0.25, 0.15, 0.8, ramp=Ramp(1.5, ACCEL))[:2]
    assert (v, u) == (0.3, -1.5)


def test_a_turn_into_the_face_is_still_refused_when_the_ramp_cannot_avoid_it() -> None:
    """Already turning towards the wall: the ramped arc bends in as well and is refused."""
    z = _wall_on_the_right()
    v, u, _ = safety.filter_complex(z, 0.3, -1.5, 8.7, 0.25, 0.15, 0.8, ramp=Ramp(-1.5, ACCEL))
    assert u > -1.5


def test_the_p3dx_on_the_left_leaves_a_pole_row_notch_without_winding_up() -> None:
    """Lab suite, seed 0, shape 19 (a pole row), collision start 6: 0.100 m before (the safety
    layer wound a turn away up to 2.2 rad/s in the notch between two poles, and the robot swung
    out to 1.02 m while it unwound); 0.050 m with the ramped arcs."""
    spec, omega, engaged, err = p3dx_lab_run("left", 19, 6)
    assert spec.family == "pole-row"
    assert engaged and err <= 0.07, err
    assert omega.min() > -2.0  # turns away (negative on the left) no longer wind up


def test_the_p3dx_on_the_left_engages_the_wide_star_it_never_engaged() -> None:
    """Lab suite, seed 0, shape 26 (tips 1.7 m apart, deep notches), collision start 2: it
    never engaged (each notch's wound-up turn away broke every 4 m stretch within 0.2 m of
    rc); 0.052 m with the ramped arcs."""
    spec, _, engaged, err = p3dx_lab_run("left", 26, 2)
    assert spec.family == "spike-star"
    assert engaged and err <= 0.08, err


def test_a_ramp_without_limit_turns_on_the_circle_of_the_full_rate() -> None:
    v, umax, rc = 0.3, 1.5, 0.55
    for p in (complex(0.6, 0.5), complex(0.3, 0.9), complex(1.2, -0.2)):
        circle = turn_margin(p, rc, v / umax)
        assert ramped_turn_margin(p, rc, v, Ramp(0.0, 1e9), umax, samples=400) == \
            pytest.approx(circle, abs=2e-3)


def test_a_ramped_turn_passes_a_face_ahead_closer_than_the_turning_circle() -> None:
    """The Pioneer (8.7 rad/s at 1.74 rad/s^2) turning towards its boundary at 0.5 rad/s: the
    circle of its full rate (3 cm) passes the next leg 0.7 m ahead and 0.3 m left 0.16 m
    outside rc; the turn it can make, the rate ramping through zero, comes 0.24 m inside."""
    p, v, rc, umax = complex(0.7, 0.3), 0.3, 0.55, 8.7
    circle = turn_margin(p, rc, v / umax)
    ramped = ramped_turn_margin(p, rc, v, Ramp(-0.5, ACCEL), umax)
    assert circle == pytest.approx(0.164, abs=0.005)
    assert ramped == pytest.approx(-0.239, abs=0.01)
    # already turning left fast, the ramped turn is nearly the circle again
    assert ramped_turn_margin(p, rc, v, Ramp(6.0, ACCEL), umax) > ramped


def test_the_p3dx_on_the_right_rounds_a_tight_stars_kinks_without_cutting_in() -> None:
    """Lab suite, seed 0, shape 2 (tips 0.6-0.8 m apart), collision start 3, on the right:
    0.087 m before, the robot 0.08 m inside rc on average (its turn away from the boundary
    at each kink ramps, and came late); 0.040 m with the ramped corner floor."""
    spec, _, engaged, err = p3dx_lab_run("right", 2, 3)
    assert spec.family == "spike-star"
    assert engaged and err <= 0.06, err


def test_the_p3dx_on_the_left_follows_a_disc_chain_it_followed_0_085_m_off() -> None:
    """Lab suite, seed 0, shape 27 (a chain of discs), collision start 2, on the left:
    0.085 m before (a late turn at a cusp, then the robot's first jump to a turn away,
    1.8 rad/s, unwound over a second: out to 1.07 m); 0.039 m with the ramped corner floor."""
    spec, _, engaged, err = p3dx_lab_run("left", 27, 2)
    assert spec.family == "disc-chain"
    assert engaged and err <= 0.06, err


def _loop_arc(speed: float, rate0: float, rate: float, accel: float, lookahead: float,
              samples: int) -> list[complex]:
    """The ramped arc's reference: the midpoint rule one step at a time, in plain Python."""
    h = lookahead / (samples * SUBSTEPS)
    p, points = 0j, []
    for k in range(samples):
        for j in range(SUBSTEPS):
            p += speed * h * cmath.exp(1j * heading_at((k * SUBSTEPS + j + 0.5) * h, rate0,
                                                        rate, accel))
        points.append(p)
    return points


def test_the_vectorised_ramped_arc_gives_the_step_by_step_sums_to_the_bit() -> None:
    rng = np.random.default_rng(5)
    for _ in range(500):
        speed, rate0, rate = rng.uniform(0.0, 1.5), rng.uniform(-3, 3), rng.uniform(-9, 9)
        accel = float(rng.choice([rng.uniform(0.5, 5.0), math.inf]))
        lookahead, samples = rng.uniform(0.1, 3.0), int(rng.integers(1, 25))
        points, headings = ramped_arc(speed, rate0, rate, accel, lookahead, samples)
        assert points.tolist() == _loop_arc(speed, rate0, rate, accel, lookahead, samples)
        h = lookahead / (samples * SUBSTEPS)
        ends = [heading_at((k + 1) * SUBSTEPS * h, rate0, rate, accel) for k in range(samples)]
        assert headings.tolist() == ends
