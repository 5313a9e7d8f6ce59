"""The other robots of a team: discs the ladar sees and the body stops at."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.core.backend import Command
from mdle.core.errors import WorldError
from mdle.core.pose import Pose
from mdle.sim.crowd import CrowdCollider, Discs, cast_discs
from mdle.sim.ladar import ladar_profile
from mdle.sim.profiles import robot_profile
from mdle.sim.robot import Latency
from mdle.sim.shapes import Parts, Rectangle
from mdle.sim.team import TeamSim
from mdle.sim.world import RobotPlace, World


def _place(name: str, x: float, y: float, th: float = 0.0, robot: str = "pioneer2dx",
           ladar: str = "lms200") -> RobotPlace:
    return RobotPlace(name, robot_profile(robot), ladar_profile(ladar), Pose(x, y, th))


def test_cast_discs_agrees_with_sampling_along_each_ray() -> None:
    rng = np.random.default_rng(5)
    d = Discs(rng.uniform(-4, 4, 6), rng.uniform(-4, 4, 6), rng.uniform(0.2, 0.6, 6),
              np.arange(6))
    angles = np.linspace(-math.pi, math.pi, 721)
    t, which = cast_discs(0.0, 0.0, angles, d, which=True)
    assert which is not None
    for a, ti, w in zip(angles, t, which, strict=True):
        s = np.linspace(0.0, 12.0, 24001)
        px, py = s * math.cos(a), s * math.sin(a)
        inside = ((px[:, None] - d.cx) ** 2 + (py[:, None] - d.cy) ** 2) <= d.r ** 2
        hits = np.flatnonzero(inside.any(axis=1))
        if hits.size == 0:
            assert math.isinf(ti) and w == -1
        else:
            assert ti == pytest.approx(s[hits[0]], abs=1e-3)
            assert inside[hits[0], w]


def test_a_ray_from_inside_a_disc_does_not_see_it() -> None:
    d = Discs(np.array([0.0]), np.array([0.0]), np.array([1.0]), np.array([0]))
    t, which = cast_discs(0.1, 0.0, np.array([0.0]), d, which=True)
    assert which is not None
    assert math.isinf(t[0]) and which[0] == -1


def test_the_collider_stops_at_another_robot_and_names_it() -> None:
    from mdle.sim.robot import Phase

    c = CrowdCollider(Parts.concat([Rectangle((20.0, 0.0), (0.1, 4.0)).parts()]), 0.25, 1)
    c.join(Discs(np.array([3.0]), np.array([0.0]), np.array([0.25]), np.array([4])), -1)
    r = c.sweep(0.0, 0.0, 0.0, Phase(10.0, 1.0, 0.0, 0.0, 0.0))
    assert r.contact and r.x == pytest.approx(2.5, abs=1e-3) and r.obstacle == 5


def _world() -> World:
    return World("open", obstacles=(Rectangle((9.0, 0.0), (0.2, 8.0)),))


def test_each_robot_s_ladar_sees_the_others() -> None:
    team = TeamSim(_world(), [_place("a", 0, 0), _place("b", 3, 0, math.pi)], seed=2,
                   sensing="exact")
    for m in team.members:
        scan = m.observe().scan
        assert scan is not None and scan.curvatures is not None
        i = int(np.argmin(np.abs(scan.bearings)))
        assert scan.valid[i]   # the other's disc: 3 m between centres, radius 0.25 m
        assert scan.ranges[i] == pytest.approx(2.75 - m.profile.ladar_mount[0], abs=2e-3)
        assert scan.curvatures[i] == pytest.approx(-1 / 0.25)  # a robot is a convex disc
    # with a noisy scan too, and the wall behind the other robot is hidden
    team = TeamSim(_world(), [_place("a", 0, 0), _place("b", 3, 0, math.pi)], seed=2)
    scan = team.members[0].observe().scan
    assert scan is not None
    i = int(np.argmin(np.abs(scan.bearings)))
    assert scan.ranges[i] < 3.0


def test_robots_that_meet_stall_and_both_records_name_the_other() -> None:
    team = TeamSim(_world(), [_place("a", 0, 0), _place("b", 2, 0, math.pi)], seed=1)
    a, b = team.members
    for _ in range(40):
        a.command(Command(0.4, 0.0))
        b.command(Command(0.3, 0.0))
        team.step(0.1)
    oa, ob = a.observe(), b.observe()
    assert oa.truth["contact"]["obstacle"] == "b" and oa.truth["contact"]["kind"] == "robot"
    assert ob.truth["contact"]["obstacle"] == "a"
    gap = math.hypot(a.true_pose.x - b.true_pose.x, a.true_pose.y - b.true_pose.y)
    assert gap >= 0.5 - 1e-6  # touching, never overlapping
    assert oa.stalled and len(a.events) == 1 and len(b.events) == 1


def test_robots_starting_overlapped_are_refused_with_both_names() -> None:
    with pytest.raises(WorldError, match="robots `a` and `b` overlap"):
        TeamSim(_world(), [_place("a", 0, 0), _place("b", 0.3, 0)])
    with pytest.raises(WorldError, match="robot `b`"):
        TeamSim(_world(), [_place("a", 0, 0), _place("b", 9.0, 0)])


def test_the_world_file_lists_robots_and_refuses_overlaps() -> None:
    from mdle.sim.world_yaml import parse_world

    w = parse_world("robots:\n  - {name: a, start: [0, 0, 90]}\n"
                    "  - {name: b, start: [2, 0, 0], robot: ideal}\n")
    assert [r.name for r in w.robots] == ["a", "b"]
    assert w.robots[0].start.theta == pytest.approx(math.pi / 2)
    assert w.robots[1].profile.name == "ideal"
    with pytest.raises(WorldError, match=r"robots\[1\]\.start: robot `b` .* overlaps robot `a`"):
        parse_world("robots:\n  - {name: a, start: [0, 0, 0]}\n  - {name: b, start: [0.1, 0, 0]}\n")
    with pytest.raises(WorldError, match="listed twice"):
        parse_world("robots:\n  - {name: a, start: [0, 0, 0]}\n  - {name: a, start: [3, 0, 0]}\n")
    with pytest.raises(WorldError, match="a plan name"):
        parse_world("robots:\n  - {name: 2a, start: [0, 0, 0]}\n")
    with pytest.raises(WorldError, match=r"robots\[0\]\.start: robot `a` .* overlaps"):
        parse_world("robots:\n  - {name: a, start: [3, 0, 0]}\n"
                    "obstacles:\n  - {type: circle, center: [3, 0], radius: 1}\n")


def test_messages_arrive_at_the_next_tick_within_range_and_lossy_by_seed() -> None:
    from mdle.core.messages import DeliveryRules

    places = [_place("a", 0, 0), _place("b", 2, 0), _place("c", 6, 0)]
    team = TeamSim(_world(), places, rules=DeliveryRules(range=3.0))
    a, b, c = team.members
    a.send("go", 1.0, 0.0)
    assert not b.box.since("go", 0.0)          # not at once
    team.step(0.1)
    assert b.box.since("go", 0.0) and b.box.value("go") == 1.0
    assert not c.box.since("go", 0.0)          # 6 m away: out of range
    assert not a.box.since("go", 0.0)          # never one's own
    got = []
    for seed in (1, 1, 2):
        team = TeamSim(_world(), places, rules=DeliveryRules(loss=0.5, seed=seed))
        heard = 0
        for _ in range(200):
            team.members[0].send("n", 1.0, team.time)
            team.step(0.1)
            heard += team.members[1].box.since("n", team.time - 0.05)  # this tick's
        got.append(heard)
    assert got[0] == got[1] != got[2] and 60 < got[0] < 140


def test_scans_taken_during_a_step_see_the_others_where_they_ended_it() -> None:
    # a noise-free ladar: the batched occlusion must equal a direct cast at the new poses
    places = [_place(n, x, y, th, ladar="lms200-ideal") for n, x, y, th in
              (("a", 0, 0, 0), ("b", 2.5, 0.4, 2.0), ("c", 1.5, -1.8, 1.0), ("d", -2, 0, 0))]
    team = TeamSim(_world(), places, seed=3)
    for k in range(15):
        for i, m in enumerate(team.members):
            m.command(Command(0.2 + 0.05 * i, 0.3 * math.sin(k + i)))
        team.step(0.1)
    for m in team.members:
        scan = m.observe().scan
        assert scan is not None and not scan.ranges.flags.writeable
        lad = m._ladar
        x, y, th = m.true_pose.x, m.true_pose.y, m.true_pose.theta
        ox, oy = lad.origin(x, y, th)
        angles = th + lad.bearings
        hits = team.world.caster.cast(np.array((ox, oy)), angles, lad.profile.max_range,
                                      detail=False)
        t, _ = cast_discs(ox, oy, angles, team.discs, m.index)
        want = np.minimum(np.where(hits.hit, hits.ranges, lad.profile.max_range), t)
        want = np.minimum(want, lad.profile.max_range)
        seen = np.isfinite(t) & (t < np.where(hits.hit, hits.ranges, np.inf))
        assert seen.any(), f"{m.name} sees no other robot"
        assert np.allclose(scan.ranges, want, atol=1e-9)
        assert (scan.valid == (hits.hit | (t <= lad.profile.max_range))).all()


def _mixed_team(cast_later: bool, ladars: tuple[str, ...] = ("lms200",),
                robot: str = "pioneer2dx") -> TeamSim:
    profile = robot_profile(robot)
    if robot == "pioneer-p3dx":   # scans older than a tick: they wait in the queue
        profile = profile.with_overrides(scan_latency=Latency("uniform", 0.12, 0.25))
    places = [RobotPlace(n, profile, ladar_profile(ladars[i % len(ladars)]), Pose(x, y, th))
              for i, (n, x, y, th) in
              enumerate((("a", 0, 0, 0), ("b", 2.5, 0.4, 2.0), ("c", 1.5, -1.8, 1.0),
                         ("d", -2, 0, 0), ("e", 4.0, 2.0, -2.0)))]
    team = TeamSim(_world(), places, seed=5)
    for m in team.members:
        m._cast_later = m._cast_later and cast_later
    return team


@pytest.mark.parametrize(("ladars", "robot"), [
    (("lms200",), "pioneer2dx"), (("lms200", "lms200-ideal"), "pioneer2dx"),
    (("lms200",), "pioneer-p3dx")])   # the last: scans wait out their latency in a queue
def test_the_team_s_one_pass_scans_equal_each_robot_s_own_bit_for_bit(
        ladars: tuple[str, ...], robot: str) -> None:
    # the same seeded team, its scans cast at the end of each step in one pass per kind of
    # ladar, or by each robot as it moves: every range, flag and pose the same
    batched, alone = _mixed_team(True, ladars, robot), _mixed_team(False, ladars, robot)
    assert all(m._cast_later for m in batched.members)
    for k in range(20):
        for team in (batched, alone):
            for i, m in enumerate(team.members):
                m.command(Command(0.3 + 0.05 * i, 0.4 * math.sin(k + i)))
            team.step(0.1)
        for mb, ma in zip(batched.members, alone.members, strict=True):
            sb, sa = mb.observe().scan, ma.observe().scan
            assert sb is not None and sa is not None
            assert sb.stamp == sa.stamp and not sb.ranges.flags.writeable
            assert np.array_equal(sb.ranges, sa.ranges)
            assert np.array_equal(sb.valid, sa.valid)
            assert mb.true_pose == ma.true_pose
