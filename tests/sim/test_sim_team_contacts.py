"""Robots of a team meet when and where they would: not late, and never through each other.

Robots moved one after the other, each for a whole tick with the others standing, met
late and lopsided (the first to move covered more ground), and two robots crossing paths
within one long tick never met at all. The team now cuts a tick where two robots could
first meet; these tests drive two bodies into each other at speed and compare with the
closed form, at rates from 100 Hz to 0.5 Hz.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from mdle.core.backend import Command
from mdle.core.pose import Pose
from mdle.sim.ladar import ladar_profile
from mdle.sim.profiles import robot_profile
from mdle.sim.shapes import Rectangle
from mdle.sim.team import TOUCHING, TeamSim
from mdle.sim.world import RobotPlace, World

RADIUS = 0.25
#: The paper's unicycle (reaches any command at once, no delays) with a body.
BODY = dataclasses.replace(robot_profile("ideal"), radius=RADIUS)
RATES = [100.0, 10.0, 1.0, 0.5]


def _team(*starts: Pose) -> TeamSim:
    world = World("open", obstacles=(Rectangle((30.0, 0.0), (0.2, 8.0)),))
    places = [RobotPlace(name, BODY, ladar_profile("lms200"), p)
              for name, p in zip("ab", starts, strict=False)]
    return TeamSim(world, places, seed=4)


def _drive(team: TeamSim, rate: float, seconds: float) -> None:
    dt = 1.0 / rate
    for _ in range(round(seconds * rate)):
        for m in team.members:
            m.command(Command(1.0, 0.0))
        team.step(dt)


@pytest.mark.parametrize("rate", RATES)
def test_head_on_at_full_speed_meet_halfway_at_the_closed_form_time(rate: float) -> None:
    # 3 m apart, 0.5 m of bodies, closing at 2 m/s: they touch at 1.25 s, x 1.25 and 1.75
    team = _team(Pose(0.0, 0.0, 0.0), Pose(3.0, 0.0, math.pi))
    _drive(team, rate, 4.0)
    a, b = team.members
    assert len(a.events) == 1 and len(b.events) == 1
    (ea,), (eb,) = a.events, b.events
    assert (ea.label, eb.label) == ("b", "a")
    tol = TOUCHING / 2.0 + 1e-9   # found within TOUCHING of the contact, closing at 2 m/s
    assert ea.time == pytest.approx(1.25, abs=tol) and eb.time == pytest.approx(1.25, abs=tol)
    assert ea.x == pytest.approx(1.25, abs=TOUCHING) and eb.x == pytest.approx(1.75, abs=TOUCHING)
    gap = math.hypot(a.true_pose.x - b.true_pose.x, a.true_pose.y - b.true_pose.y)
    assert 2 * RADIUS - 1e-9 <= gap <= 2 * RADIUS + TOUCHING


@pytest.mark.parametrize("rate", RATES)
def test_robots_crossing_paths_meet_at_the_crossing_at_any_rate(rate: float) -> None:
    # a along y = 0, b along x = 0, both 2 m from the crossing: they touch when
    # sqrt(2) (2 - t) = 0.5, each 0.5 / sqrt(2) m short of it.
    team = _team(Pose(-2.0, 0.0, 0.0), Pose(0.0, -2.0, math.pi / 2))
    _drive(team, rate, 4.0)
    a, b = team.members
    assert [e.label for e in a.events] == ["b"] and [e.label for e in b.events] == ["a"]
    short = 2 * RADIUS / math.sqrt(2.0)
    contact = 2.0 - short
    tol = TOUCHING / math.sqrt(2.0) + 1e-9   # closing at sqrt(2) m/s
    assert a.events[0].time == pytest.approx(contact, abs=tol)
    assert b.events[0].time == pytest.approx(contact, abs=tol)
    assert a.events[0].x == pytest.approx(-short, abs=TOUCHING)
    assert b.events[0].y == pytest.approx(-short, abs=TOUCHING)
    # stalled where they met: neither has passed the crossing
    assert a.true_pose.x < 0.0 and b.true_pose.y < 0.0


def test_robots_far_apart_move_in_one_piece_per_tick() -> None:
    # no two can meet within the tick: the step is not cut (the horizon covers it)
    team = _team(Pose(0.0, 0.0, 0.0), Pose(0.0, 5.0, 0.0))
    for m in team.members:
        m.command(Command(1.0, 0.0))
    assert team._horizon() > 1.0
    team.step(1.0)
    assert [m.true_pose.x for m in team.members] == pytest.approx([1.0, 1.0])
    assert not any(m.events for m in team.members)
