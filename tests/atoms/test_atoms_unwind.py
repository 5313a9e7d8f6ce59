"""Unwind look-ahead (issue 23): on a robot that ramps back from turns away, look past the ramp.

The Pioneer 3-DX profile's ``ramp: stage`` jumps to a turn away from the boundary on the
left and ramps the turn back at 1.74 rad/s^2. Without the look-ahead the law asked to turn
back only once its heading was right, and the robot swung out to 0.8-0.9 m round the next
tip while its turn away wound down.
"""

from __future__ import annotations

import math

import pytest

from mdle.atoms.unwind import SHARE, unwind_motion
from tests.atoms.conftest import p3dx_lab_run

ACCEL = 1.74  # rad/s^2, the P3-DX profile's turn acceleration


def test_the_unwind_turns_as_far_as_a_linear_ramp_down_over_its_share() -> None:
    rate, v = 1.2, 0.3
    dx, dy, dth = unwind_motion(rate, v, ACCEL)
    t = SHARE * rate / ACCEL  # the share of the unwind's time
    assert dth == pytest.approx(rate * t - 0.5 * ACCEL * t * t)
    assert math.hypot(dx, dy) == pytest.approx(v * t, rel=0.05)  # a chord of a gentle arc
    assert dy > 0.0  # the turn away (positive) carries the robot on to its left


def test_nothing_is_looked_past_for_a_turn_towards_or_a_robot_that_turns_at_once() -> None:
    assert unwind_motion(-1.0, 0.3, ACCEL) == (0.0, 0.0, 0.0)
    assert unwind_motion(0.0, 0.3, ACCEL) == (0.0, 0.0, 0.0)
    assert unwind_motion(1.0, 0.3, math.inf) == (0.0, 0.0, 0.0)


def test_the_p3dx_on_the_left_turns_back_round_the_tips_of_a_wide_star_in_time() -> None:
    """Lab suite, seed 0, shape 26: tips 1.7 m apart, deep notches. Without the look-ahead the
    robot swung out of each notch and never engaged from this start."""
    spec, _, engaged, err = p3dx_lab_run("left", 26, 3)
    assert spec.family == "spike-star"
    assert engaged and err <= 0.10, err


def test_the_p3dx_on_the_left_follows_a_star_it_followed_0_107_m_off() -> None:
    """Lab suite, seed 0, shape 32, start 3: 0.107 m without the look-ahead (0.051 with it)."""
    spec, _, engaged, err = p3dx_lab_run("left", 32, 3)
    assert spec.family == "spike-star"
    assert engaged and err <= 0.08, err
