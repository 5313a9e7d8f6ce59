"""Engagement metrics on constructed true traces (a robot beside the wall y = 0)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.sweep.engagement import ENGAGE_BAND, ENGAGE_PATH, FollowMetrics, follow_metrics


def _along_wall(y: np.ndarray, heading: float = 0.0, dt: float = 0.1, speed: float = 1.0,
                side: str = "right", rc: float = 0.5) -> FollowMetrics:
    """A robot moving along x at ``speed`` with offsets ``y`` above the wall y = 0."""
    n = len(y)
    t = np.arange(n) * dt
    x = t * speed * math.cos(heading)
    d = np.abs(y)
    nearest = np.column_stack([x, np.zeros(n)])
    return follow_metrics(t, x, y, np.full(n, heading), d, nearest, d, collided=False,
                          side=side, rc=rc)


def test_following_from_the_start_engages_at_once_with_no_error() -> None:
    m = _along_wall(np.full(101, 0.5))
    assert m.engaged and m.t_engage == 0.0 and m.s_engage == 0.0
    assert m.mean_err == 0.0 and m.max_err == 0.0
    assert m.window_start == pytest.approx(5.0) and m.path_length == pytest.approx(10.0)
    assert m.min_clearance == 0.5 and m.final_d == 0.5 and m.blind_path == 0.0


def test_the_wall_on_the_wrong_side_never_engages_and_counts_as_blind_path() -> None:
    # heading west above the wall: the wall is on the robot's left
    m = _along_wall(np.full(101, 0.5), heading=math.pi)
    assert not m.engaged and math.isnan(m.t_engage) and math.isnan(m.mean_err)
    assert m.blind_path == pytest.approx(10.0)
    assert _along_wall(np.full(101, 0.5), heading=math.pi, side="left").engaged


def test_engagement_starts_where_the_band_is_entered_on_an_approach() -> None:
    y = np.concatenate([np.linspace(5.0, 0.5, 51), np.full(100, 0.5)])  # 5 s approach
    m = _along_wall(y)
    inside = np.flatnonzero(np.abs(y - 0.5) <= ENGAGE_BAND)[0]
    assert m.engaged and m.t_engage == pytest.approx(inside * 0.1)
    path = np.concatenate([[0.0], np.cumsum(np.hypot(0.1, np.diff(y)))])  # x moves 0.1 a tick
    assert m.s_engage == pytest.approx(path[inside])


def test_a_break_restarts_the_stretch_and_a_short_stretch_does_not_count() -> None:
    y = np.full(151, 0.5)
    y[30] = 0.9                       # 3 m in, a blip outside the band
    m = _along_wall(y)
    assert m.engaged and m.t_engage == pytest.approx(3.1)
    short = np.full(80, 2.0)
    short[20:20 + int(10 * ENGAGE_PATH) - 1] = 0.5   # just under 4 m inside the band
    assert not _along_wall(short).engaged
    short[20:20 + int(10 * ENGAGE_PATH) + 1] = 0.5   # 4 m
    assert _along_wall(short).engaged


def test_accuracy_is_measured_over_the_second_half_after_engagement() -> None:
    y = np.full(201, 0.5)            # engaged at 0 s, run ends at 20 s: window 10-20 s
    y[50:90] = 0.65                  # error 0.15 before the window: ignored
    y[150:160] = 0.6                 # error 0.1 for 10 of the window's 101 ticks
    m = _along_wall(y)
    assert m.engaged and m.t_engage == 0.0 and m.window_start == pytest.approx(10.0)
    assert m.mean_err == pytest.approx(0.1 * 10 / 101)
    assert m.max_err == pytest.approx(0.1)
    late = np.concatenate([np.full(40, 3.0), np.full(161, 0.5)])
    late[-20:] = 0.55                  # engaged at 4 s, end 20 s: window from 12 s
    m2 = _along_wall(late)
    assert m2.t_engage == pytest.approx(4.0) and m2.window_start == pytest.approx(12.0)
    assert m2.mean_err == pytest.approx(0.05 * 20 / 81)


def test_a_collision_and_the_clearance_are_reported_as_given() -> None:
    t = np.arange(5) * 0.1
    m = follow_metrics(t, t, np.full(5, 0.3), np.zeros(5), np.full(5, 0.3),
                       np.column_stack([t, np.zeros(5)]), np.array([0.1, 0.05, 0.0, 0.0, 0.0]),
                       collided=True, side="right", rc=0.5)
    assert m.collided and m.min_clearance == 0.0 and not m.engaged


def test_a_bad_side_is_refused() -> None:
    with pytest.raises(ValueError, match="side must be"):
        _along_wall(np.full(5, 0.5), side="up")
