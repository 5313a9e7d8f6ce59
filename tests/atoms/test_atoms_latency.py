"""Latency prediction: odometry since the scan, commands in flight, rays moved into the
predicted frame."""

from __future__ import annotations

import math

import pytest

from mdle.atoms.latency import Predictor, compose, shift_front, shift_side
from mdle.atoms.steering import MISS, Ray


def test_motion_since_the_scan_comes_from_the_odometry_history() -> None:
    p = Predictor()
    for k in range(11):  # 1 m/s straight ahead, 10 Hz
        p.record_pose(0.1 * k, (0.1 * k, 0.0, 0.0))
    ahead = p.predict(1.0, 0.75, (1.0, 0.0, 0.0), 1.0, 0.0, 0.0, math.inf, math.inf)
    moved, pose = ahead.moved, ahead.pose
    assert moved == pytest.approx((0.25, 0.0, 0.0))
    assert pose == (1.0, 0.0, 0.0)


def test_a_scan_stamped_now_to_the_clocks_rounding_means_no_motion() -> None:
    # a stamp and a tick time summed from the same ticks differ in the last bits (46.5 and
    # 46.50000000000039): the scan was taken here, so the rays and points stay as they are
    p = Predictor()
    now = sum([0.1] * 465)
    assert now != 46.5 and abs(now - 46.5) < 1e-9
    p.record_pose(46.4, (13.9, 4.6, 9.2))
    p.record_pose(now, (13.93, 4.61, 9.22))
    ahead = p.predict(now, 46.5, p.poses[-1].pose, 0.3, 0.2, 0.0, math.inf, math.inf)
    moved, pose = ahead.moved, ahead.pose
    assert moved == (0.0, 0.0, 0.0)
    assert pose == p.poses[-1].pose


def test_commands_in_flight_act_after_the_latency_with_the_ramp() -> None:
    p = Predictor()
    p.record_pose(0.0, (0.0, 0.0, 0.0))
    p.record_command(-0.3, 0.0, 1.0)  # a 1 rad/s turn sent 0.3 s ago, latency 0.4 s
    # the next 0.1 s still carry the old turn rate (0), then 1 rad/s ramps in at 2 rad/s^2
    (_, _, dth) = p.predict(0.0, 0.0, (0.0, 0.0, 0.0), 0.0, 0.0, 0.4, math.inf, 2.0).moved
    # 0.1 s at 0, then 0.3 s ramping 0 -> 0.6 rad/s: 0.09 rad
    assert dth == pytest.approx(0.09, abs=0.01)
    (_, _, dth) = p.predict(0.0, 0.0, (0.0, 0.0, 0.0), 0.0, 0.0, 0.4, math.inf, math.inf).moved
    assert dth == pytest.approx(0.3, abs=0.02)


def test_rays_move_with_the_robot() -> None:
    # a wall 0.5 m to the right; after 0.1 m ahead and a 0.1 rad left turn the side ray is
    # longer and the wall's tangent turns right relative to the heading
    side = shift_side(Ray(True, 0.5, 0.0, 0.0), (0.1, 0.0, 0.1))
    assert side.r == pytest.approx(0.5 / math.cos(0.1))
    assert side.beta == pytest.approx(-0.1)
    # a wall 1 m straight ahead, 0.1 m closer
    front = shift_front(Ray(True, 1.0, math.pi / 2, 0.0), (0.1, 0.0, 0.0))
    assert front.r == pytest.approx(0.9) and front.beta == pytest.approx(math.pi / 2)
    # no motion, no change; a miss stays a miss
    ray = Ray(True, 1.0, 1.0, -0.5)
    assert shift_front(ray, (0.0, 0.0, 0.0)) is ray
    assert shift_side(MISS, (0.3, 0.0, 0.0)) is MISS


def test_a_hit_that_would_leave_the_local_model_is_dropped() -> None:
    # the front wall passes behind the robot: nothing ahead any more
    assert not shift_front(Ray(True, 0.2, math.pi / 2, 0.0), (0.5, 0.0, 0.0)).hit


def test_compose_is_the_frame_product() -> None:
    assert compose((1.0, 0.0, math.pi / 2), (1.0, 0.0, 0.0)) == pytest.approx(
        (1.0, 1.0, math.pi / 2))
