"""SimBackend: kinematics, limits, collisions (no tunnelling), ladar model, determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle import sim
from mdle.core.backend import Backend, ClockMode, Command
from mdle.core.errors import BackendError, WorldError
from mdle.core.pose import Pose
from mdle.sim.backend import SimBackend
from mdle.sim.ladar import Ladar, LadarProfile
from mdle.sim.profiles import robot_profile
from mdle.sim.robot import OdometryNoise, Phase, RobotProfile, integrate, plan_phases
from mdle.sim.shapes import Circle, Rectangle, Wall
from mdle.sim.world import World

IDEAL = robot_profile("ideal")
PIONEER2DX = robot_profile("pioneer2dx")


def wall_world(robot: RobotProfile = PIONEER2DX) -> World:
    """A thin (1 mm) wall across the x axis at x = 5."""
    return World("thin", obstacles=(Rectangle((5.0, 0.0), (0.001, 20.0)),), robot=robot)


def test_implements_the_backend_protocol() -> None:
    b = SimBackend(sim.load_world("default"))
    assert isinstance(b, Backend)
    assert b.clock is ClockMode.SIMULATED
    assert b.limits.radius == 0.25
    obs = b.observe()
    assert set(obs.truth) == {"x", "y", "theta", "clearance", "collided"}
    # Plans see odometry from the run's start (REP-105 odom); the world pose is ground truth.
    s = b.world.start_pose
    assert obs.time == 0.0 and obs.pose == Pose(0.0, 0.0, 0.0)
    assert (obs.truth["x"], obs.truth["y"], obs.truth["theta"]) == (s.x, s.y, s.theta)


def test_commands_are_clamped_to_limits() -> None:
    b = SimBackend(wall_world(), robot="ideal")
    b.command(Command(5.0, -9.0))
    b.advance(0.1)
    obs = b.observe()
    assert (obs.v, obs.omega) == (1.0, -3.0)
    with pytest.raises(BackendError, match="not finite"):
        b.command(Command(math.nan, 0.0))
    with pytest.raises(BackendError, match="dt >= 0"):
        b.advance(-1.0)


def test_arc_integration_is_exact_at_any_tick_length() -> None:
    world = World("open")
    ends = []
    for steps in (1, 7, 100):
        b = SimBackend(world, robot="ideal", ladar="lms200-ideal")
        b.command(Command(1.0, 0.5))
        for _ in range(steps):
            b.advance(2.0 / steps)
        ends.append(b.true_pose)
    # Circle of radius 2 about (0, 2): after 2 s, angle 1 rad.
    for p in ends:
        assert math.isclose(p.x, 2 * math.sin(1.0), abs_tol=1e-12)
        assert math.isclose(p.y, 2 - 2 * math.cos(1.0), abs_tol=1e-12)
        assert math.isclose(p.theta, 1.0, abs_tol=1e-12)


def test_ramps_match_a_fine_reference() -> None:
    # Pioneer limits: 0.3 m/s^2 and 100 deg/s^2. One long step against RK4 at 1e-4 s.
    phases, v_end, w_end = plan_phases(0.0, 0.0, 0.6, 1.2, 3.0, PIONEER2DX)
    x = y = th = 0.0
    for ph in phases:
        x, y, th = integrate(x, y, th, ph, ph.duration)
    assert math.isclose(v_end, 0.6) and math.isclose(w_end, 1.2)

    def vel(t: float) -> tuple[float, float]:
        return min(0.6, 0.3 * t), min(1.2, math.radians(100) * t)

    h, rx, ry, rth, t = 1e-4, 0.0, 0.0, 0.0, 0.0

    def f(t: float, th: float) -> tuple[float, float, float]:
        v, w = vel(t)
        return v * math.cos(th), v * math.sin(th), w

    for _ in range(30000):
        k1 = f(t, rth)
        k2 = f(t + h / 2, rth + h / 2 * k1[2])
        k3 = f(t + h / 2, rth + h / 2 * k2[2])
        k4 = f(t + h, rth + h * k3[2])
        rx += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        ry += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        rth += h / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
        t += h
    assert abs(x - rx) < 1e-7 and abs(y - ry) < 1e-7 and abs(th - rth) < 1e-9


def test_a_turn_ramp_at_constant_speed_matches_simpson() -> None:
    # The constant-speed branch of the quadrature (the usual tick of a following robot),
    # over several pieces, against composite Simpson on theta(t) in closed form.
    ph = Phase(duration=0.9, v0=0.5, a_v=0.0, w0=0.2, a_w=1.7)
    x, y, th = integrate(1.0, -2.0, 0.3, ph, 0.9)
    t = np.linspace(0.0, 0.9, 200001)
    a = 0.3 + 0.2 * t + 0.85 * t * t
    wts = np.ones_like(t)
    wts[1:-1:2], wts[2:-1:2] = 4.0, 2.0
    h = t[1] - t[0]
    assert math.isclose(x, 1.0 + h / 3 * float(wts @ (0.5 * np.cos(a))), abs_tol=1e-12)
    assert math.isclose(y, -2.0 + h / 3 * float(wts @ (0.5 * np.sin(a))), abs_tol=1e-12)
    assert th == 0.3 + 0.2 * 0.9 + 0.85 * 0.9 * 0.9


def test_the_written_out_gauss_legendre_nodes_are_numpys() -> None:
    from mdle.sim.robot import GAUSS_LEGENDRE_8

    nodes, weights = np.polynomial.legendre.leggauss(8)
    assert GAUSS_LEGENDRE_8 == tuple(zip(nodes.tolist(), weights.tolist(), strict=True))


def test_acceleration_limit_of_the_pioneer() -> None:
    b = SimBackend(World("open"), robot="pioneer2dx")
    b.command(Command(0.3, 0.0))
    b.advance(0.5)
    assert math.isclose(b.observe().v, 0.15)
    b.advance(0.5)
    obs = b.observe()
    assert math.isclose(obs.v, 0.3)
    assert math.isclose(obs.truth["x"], 0.5 * 0.3 * 1.0 ** 2)   # area under the ramp


@pytest.mark.parametrize("speed", [1.0, 50.0, 1000.0])
@pytest.mark.parametrize("dt", [0.01, 0.1, 1.0])
def test_no_tunnelling_through_a_thin_wall(speed: float, dt: float) -> None:
    fast = IDEAL.with_overrides(max_speed=speed, radius=0.2)
    world = wall_world(robot=fast)
    b = SimBackend(world, ladar="lms200-ideal")
    b.command(Command(speed, 0.0))
    for _ in range(round(20.0 / (speed * dt)) + 5):
        b.advance(dt)
        obs = b.observe()
        assert obs.truth["x"] < 5.0 - 0.0005 - 0.2 + 1e-9          # never into the wall
        assert obs.truth["clearance"] >= 0.0
    obs = b.observe()
    assert obs.stalled and obs.truth["collided"]
    assert obs.truth["clearance"] < 1e-4                         # stopped at contact
    assert [e.kind for e in b.events] == ["collision"]           # recorded once


def test_diagonal_dash_into_a_corner_and_grazing() -> None:
    room = World("room", obstacles=(Wall(((-2, -2), (2, -2), (2, 2), (-2, 2)), 0.01, True),),
                 robot=IDEAL.with_overrides(max_speed=100.0, radius=0.3))
    b = SimBackend(room, ladar="lms200-ideal")
    b.command(Command(100.0, 0.0))
    b.reset(Pose(0.0, 0.0, math.radians(44.9)))
    b.command(Command(100.0, 0.0))
    b.advance(1.0)
    t = b.observe().truth
    assert t["collided"] and t["clearance"] >= 0
    assert abs(t["x"]) < 2 and abs(t["y"]) < 2
    # Grazing along a wall at a tiny angle: stops before touching, never goes through.
    b.reset(Pose(-1.5, -1.69, math.radians(0.5)))
    b.command(Command(100.0, 0.0))
    b.advance(1.0)
    t = b.observe().truth
    assert t["clearance"] >= 0 and -1.695 <= t["y"] and t["x"] < 1.7


def test_stalled_robot_can_turn_and_back_away() -> None:
    world = wall_world(robot=IDEAL.with_overrides(radius=0.2))
    b = SimBackend(world, ladar="lms200-ideal")
    b.command(Command(1.0, 0.0))
    for _ in range(60):
        b.advance(0.1)
    assert b.observe().stalled
    b.command(Command(1.0, 0.0))          # pushing on: still stalled, not moving
    x = b.observe().truth["x"]
    b.advance(0.1)
    assert b.observe().stalled and b.observe().truth["x"] == x
    b.command(Command(0.0, 1.0))          # turning in place is fine
    b.advance(0.1)
    assert not b.observe().stalled
    b.command(Command(-1.0, 0.0))         # backing away is fine
    b.advance(0.5)
    obs = b.observe()
    assert not obs.stalled and obs.truth["clearance"] > 0.4
    assert obs.truth["collided"]          # sticky until reset
    b.reset()
    assert not b.observe().truth["collided"] and b.events == []


def test_start_overlapping_an_obstacle_is_refused() -> None:
    world = World("tight", obstacles=(Circle((0.5, 0.0), 0.3),), robot=IDEAL)
    SimBackend(world)                                            # a point robot fits
    with pytest.raises(WorldError, match=r"overlaps obstacles\[0\]"):
        SimBackend(world, robot="pioneer2dx")


def test_scan_geometry_and_invalid_beams() -> None:
    # One wall 3 m ahead, 2 m wide: beams that miss it are invalid at max range.
    world = World("one", obstacles=(Rectangle((3.5, 0.0), (1.0, 2.0)),), robot=IDEAL)
    scan = SimBackend(world, ladar="lms200-ideal").observe().scan
    assert scan is not None
    assert scan.ranges.shape == scan.bearings.shape == scan.valid.shape == (181,)
    assert math.isclose(scan.bearings[0], -math.pi / 2) and math.isclose(scan.bearings[90], 0.0)
    assert math.isclose(scan.ranges[90], 3.0, abs_tol=1e-12)
    assert scan.valid[90] and not scan.valid[0] and not scan.valid[180]
    assert np.all(scan.ranges[~scan.valid] == 10.0)
    assert not scan.ranges.flags.writeable
    assert scan.tangents is None and scan.curvatures is None


def test_ladar_mount_offset_of_the_pioneer() -> None:
    world = World("one", obstacles=(Rectangle((3.5, 0.0), (1.0, 20.0)),))
    scan = SimBackend(world, ladar="lms200-ideal").observe().scan
    assert scan is not None
    assert math.isclose(scan.ranges[90], 3.0 - 0.017, abs_tol=1e-12)


def test_oracle_fills_tangents_and_curvatures() -> None:
    world = sim.load_world("trashcan")
    scan = SimBackend(world, sensing="exact").observe().scan
    assert scan is not None and scan.tangents is not None and scan.curvatures is not None
    v = scan.valid
    assert v.sum() > 10
    np.testing.assert_allclose(scan.curvatures[v], -5.0, atol=1e-12)
    assert np.isnan(scan.curvatures[~v]).all() and np.isnan(scan.tangents[~v]).all()
    # The can is ahead; clockwise around it (can on the right) its near face runs to the
    # robot's left: the central beam's tangent is about +pi/2 in the robot frame.
    assert abs(scan.tangents[90] - math.pi / 2) < 0.05
    with pytest.raises(BackendError, match="unknown sensing mode"):
        SimBackend(world, sensing="psychic")


def _noise_samples(model: str, sigma: float, n_scans: int = 300) -> tuple[np.ndarray, np.ndarray]:
    world = World("room", obstacles=(Wall(((-4, -3), (4, -3), (4, 3), (-4, 3)), 0.2, True),),
                  robot=IDEAL)
    truth = world.cast((0.0, 0.0), np.linspace(-math.pi / 2, math.pi / 2, 181)).ranges
    prof = LadarProfile("test", noise=model, sigma=sigma, resolution=0.0, rate=0.0)
    ladar = Ladar(prof, np.random.default_rng(42))
    hits = world.caster.cast(np.zeros(2), ladar.world_angles(0.0), 10.0, detail=False)
    scans = np.array([ladar.measure(hits, 0.0, 0.0).ranges for _ in range(n_scans)])
    return scans, truth


def test_relative_noise_statistics_match_the_model() -> None:
    scans, truth = _noise_samples("relative", 0.008)
    z = (scans / truth - 1.0) / 0.008          # standardised errors, should be N(0, 1)
    n = z.size
    assert abs(z.mean()) < 4 / math.sqrt(n)
    assert abs(z.std() - 1.0) < 0.02
    assert abs(np.mean(np.abs(z) < 1.0) - 0.6827) < 0.01
    assert abs(np.mean(np.abs(z) < 2.0) - 0.9545) < 0.006
    # Beams are independent: neighbouring errors uncorrelated.
    r = np.corrcoef(z[:, :-1].ravel(), z[:, 1:].ravel())[0, 1]
    assert abs(r) < 0.02


def test_absolute_noise_statistics_match_the_model() -> None:
    scans, truth = _noise_samples("absolute", 0.005)
    e = scans - truth
    assert abs(e.std() - 0.005) < 0.0002
    # Independent of range: near and far beams have the same spread.
    near, far = truth < np.median(truth), truth >= np.median(truth)
    assert abs(e[:, near].std() - e[:, far].std()) < 0.0004


def test_range_resolution() -> None:
    scan = SimBackend(sim.load_world("corridor")).observe().scan
    assert scan is not None
    mm = scan.ranges[scan.valid] * 1000.0
    np.testing.assert_allclose(mm, np.round(mm), atol=1e-6)


def test_scan_rate_and_stamps() -> None:
    b = SimBackend(sim.load_world("corridor"))          # lms200: 10 Hz
    b.command(Command(0.3, 0.0))
    stamps = []
    for _ in range(50):
        b.advance(0.02)
        scan = b.observe().scan
        assert scan is not None                         # the corridor's robot has a ladar
        stamps.append(scan.stamp)
    distinct = sorted(set(stamps))
    np.testing.assert_allclose(distinct, [0.1 * k for k in range(11)], atol=1e-12)
    # A scan taken mid-step sees the robot where it was at the scan instant.
    b2 = SimBackend(sim.load_world("corridor"))
    b2.command(Command(0.3, 0.0))
    b2.advance(0.15)                                    # scan at 0.1, robot at 0.15
    scan = b2.observe().scan
    assert scan is not None
    assert scan.stamp == pytest.approx(0.1)


def _run(seed: int, drift: bool) -> list[tuple[float, ...]]:
    world = sim.load_world("office")
    if drift:
        noisy = world.robot.with_overrides(odometry=OdometryNoise(0.02, 0.02, 0.01))
        world = World(world.name, world.obstacles, world.start_pose, world.seed, noisy,
                      world.ladar)
    b = SimBackend(world, seed=seed)
    out: list[tuple[float, ...]] = []
    for k in range(40):
        b.command(Command(0.4, 0.3 * math.sin(0.2 * k)))
        b.advance(0.1)
        o = b.observe()
        assert o.scan is not None
        out.append((o.pose.x, o.pose.y, o.pose.theta, o.truth["x"], float(o.scan.ranges.sum()),
                    o.truth["y"]))
    return out


def _start_frame(x: float, y: float) -> tuple[float, float]:
    """Return a world point in the odometry frame of the office world's start pose."""
    s = sim.load_world("office").start_pose
    c, sn = math.cos(s.theta), math.sin(s.theta)
    return c * (x - s.x) + sn * (y - s.y), c * (y - s.y) - sn * (x - s.x)


def test_determinism_same_seed_same_trajectory() -> None:
    assert _run(3, drift=True) == _run(3, drift=True)
    assert _run(3, drift=True) != _run(4, drift=True)


def test_odometry_drift_is_optional_and_seeded() -> None:
    exact = _run(1, drift=False)
    # perfect odometry = truth, seen from the start pose
    assert all(abs(r[0] - _start_frame(r[3], r[5])[0]) < 1e-9 for r in exact)
    assert all(abs(r[1] - _start_frame(r[3], r[5])[1]) < 1e-9 for r in exact)
    drifting = _run(1, drift=True)
    assert any(abs(r[0] - _start_frame(r[3], r[5])[0]) > 1e-4 for r in drifting)
    # The true trajectory does not depend on the odometry noise.
    assert [r[3] for r in exact] == [r[3] for r in drifting]


def test_reset_to_a_pose() -> None:
    b = SimBackend(sim.load_world("empty"), robot="ideal")
    b.command(Command(0.5, 0.0))
    b.advance(1.0)
    b.reset(Pose(1.0, 1.0, 0.5))
    o = b.observe()
    assert o.time == 0.0 and o.pose == Pose(0.0, 0.0, 0.0) and o.v == 0.0  # odometry restarts
    assert b.true_pose == Pose(1.0, 1.0, 0.5)
    b.command(Command(1.0, 0.0))
    b.advance(1.0)
    o = b.observe()
    assert o.pose.x == pytest.approx(1.0) and o.pose.y == pytest.approx(0.0, abs=1e-12)
    assert b.true_pose.x == pytest.approx(1.0 + math.cos(0.5), abs=0.02)


def test_phase_helpers() -> None:
    ph = Phase(2.0, 1.0, -0.5, 0.0, 0.0)
    assert ph.max_abs_v == 1.0 and ph.v_at(2.0) == 0.0
