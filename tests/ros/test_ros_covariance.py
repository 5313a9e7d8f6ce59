"""``/odom``'s covariances: from the simulator's noise model, checked against its spread."""

from __future__ import annotations

import math

import numpy as np

from mdle import sim
from mdle.core.pose import Pose
from mdle.lang import load_text
from mdle.rosmsg.covariance import UNKNOWN, OdometryCovariance
from mdle.runtime import Recorder, run
from mdle.sim.profiles import robot_profile
from mdle.sim.robot import OdometryNoise

PLAN = "atom drive = (arc(0.5 m/s, 10 deg/s), never, 4 s)\nrun drive\n"
NOISE = OdometryNoise(distance=0.02, turn=0.05, drift=0.03)


def _path(k: int) -> np.ndarray:
    t = np.linspace(0.0, 6.0, k)
    return np.column_stack((np.cos(t) * t, np.sin(t) * t, np.remainder(t * 1.3, 2 * np.pi)
                            - np.pi))


def test_batches_give_the_same_numbers_as_one_pass() -> None:
    pose = _path(200)
    whole = OdometryCovariance(vars(NOISE)).batch(pose)
    assert whole is not None
    cov = OdometryCovariance(vars(NOISE))
    parts = [cov.batch(pose[i:i + 7]) for i in range(0, 200, 7)]
    assert all(p is not None for p in parts)
    pose_cov = np.concatenate([p[0] for p in parts if p is not None])
    assert np.array_equal(pose_cov, whole[0])  # bit for bit: recording and export agree
    # it only grows, on x, y and yaw alone
    assert np.all(np.diff(whole[0][:, 0]) >= 0) and np.all(np.diff(whole[0][:, 35]) >= 0)
    assert not np.any(np.delete(whole[0], [0, 7, 35], axis=1))
    assert not np.any(whole[1])


def test_exact_and_unknown_odometry() -> None:
    exact = OdometryCovariance({"distance": 0.0, "turn": 0.0, "drift": 0.0})
    assert exact.batch(_path(10)) is None and not np.any(exact.constant[0])
    unknown = OdometryCovariance(None)
    assert unknown.batch(_path(10)) is None
    assert unknown.constant[0][0] == -1.0 and np.array_equal(unknown.constant[1], UNKNOWN)


def test_the_predicted_spread_matches_the_simulated_one() -> None:
    world = sim.load_world("default")
    profile = robot_profile("pioneer2dx").with_overrides(odometry=NOISE)
    element = load_text(PLAN, "<test>").elements["drive"]
    start = Pose(-3.0, -2.0, 0.0)
    errors = []
    predicted = None
    for seed in range(160):
        backend = sim.SimBackend(world, seed=seed, robot=profile, sensing="exact",
                                 start=start)
        rec = Recorder()
        run(element, backend, rate=10.0, observers=[rec])
        s = rec.samples[-1]
        assert s.true_x is not None and s.true_y is not None and s.true_theta is not None
        # the true pose in the frame odometry counts in (the start pose)
        dx, dy = s.true_x - start.x, s.true_y - start.y
        errors.append((s.x - dx, s.y - dy, math.remainder(s.theta - s.true_theta, math.tau)))
        if predicted is None:
            pose = np.array([(r.x, r.y, r.theta) for r in rec.samples])
            got = OdometryCovariance(vars(NOISE)).batch(pose)
            assert got is not None
            predicted = got[0][-1]
    err = np.array(errors)
    var_x, var_y, var_yaw = err.var(axis=0)
    assert predicted is not None
    # the heading's variance is exact: within the sampling error of 160 runs
    assert 0.7 < var_yaw / predicted[35] < 1.3
    # x and y each carry the bound on the larger direction: their sum is near it
    assert var_x < 1.3 * predicted[0] and var_y < 1.3 * predicted[7]
    assert 0.6 < (var_x + var_y) / predicted[0] < 1.4
