"""The sensor functions and the law that read a robot's inbox, on hand-made inboxes."""

from __future__ import annotations

import math
from collections import deque
from typing import Any

import pytest

from mdle.atoms.registry import Context
from mdle.atoms.team import bearing_to, message, pursue, range_to, received
from mdle.core.backend import Observation, RobotLimits
from mdle.core.messages import Inbox, Message, compose, relative
from mdle.core.pose import Pose

LIMITS = RobotLimits(1.0, 1.0, 2.0)
ORIGIN = Pose()


def _ctx(box: Inbox | None, pose: Pose = ORIGIN, time: float = 10.0, t: float = 0.0
         ) -> Context:
    return Context(Observation(time, pose, inbox=box), t, 0.1, LIMITS)


def test_compose_and_relative_follow_the_conventions() -> None:
    # odometry (1, 0) from a start at (2, 3) facing +y is (2, 4) in the team frame
    p = compose(Pose(2.0, 3.0, math.pi / 2), Pose(1.0, 0.0, 0.5))
    assert (p.x, p.y, p.theta) == pytest.approx((2.0, 4.0, math.pi / 2 + 0.5))
    d, b = relative(Pose(0.0, 0.0, math.pi / 2), Pose(-1.0, 1.0, 0.0))
    assert d == pytest.approx(math.sqrt(2)) and b == pytest.approx(math.pi / 4)  # to the left


def test_received_counts_only_since_the_element_started() -> None:
    box = Inbox(Pose())
    box.put(Message("go", 1.0, "a", 4.9, 5.0))
    assert received({"channel": "go"}, _ctx(box, time=10.0, t=5.1))      # started at 4.9
    assert not received({"channel": "go"}, _ctx(box, time=10.0, t=5.0))  # started at 5.0:
    # the message was in the observation of the tick the element started in, so older
    assert not received({"channel": "go"}, _ctx(box, time=10.0, t=4.9))  # started at 5.1
    assert not received({"channel": "stop"}, _ctx(box))
    assert not received({"channel": "go"}, _ctx(None))                    # a robot alone


def test_message_is_the_last_number_and_nan_before_any() -> None:
    box = Inbox(Pose())
    assert math.isnan(message({"channel": "gap"}, _ctx(box)))
    box.put(Message("gap", 1.5, "a", 1.0, 1.1))
    box.put(Message("gap", 2.5, "b", 2.0, 2.1))
    assert message({"channel": "gap"}, _ctx(box)) == 2.5
    assert math.isnan(message({"channel": "gap"}, _ctx(None)))


def test_range_and_bearing_to_a_robot_from_its_last_pose() -> None:
    box = Inbox(Pose(1.0, 1.0, 0.0))  # this robot started at (1, 1) facing +x
    args = {"robot": "lead"}
    assert range_to(args, _ctx(box)) == math.inf and math.isnan(bearing_to(args, _ctx(box)))
    box.put(Message("pose", Pose(4.0, 5.0, 0.0), "lead", 1.0, 1.1))
    # odometry: 0 m moved, turned 90 deg left: the leader at (3, 4) relative, bearing -36.87
    ctx = _ctx(box, pose=Pose(0.0, 0.0, math.pi / 2))
    assert range_to(args, ctx) == pytest.approx(5.0)
    assert bearing_to(args, ctx) == pytest.approx(math.atan2(4, 3) - math.pi / 2)
    assert range_to({"robot": "other"}, ctx) == math.inf


def test_pursue_waits_for_a_pose_then_follows_the_trail_and_keeps_its_gap() -> None:
    args: dict[str, float | str | bool] = {"robot": "lead", "gap": 1.0, "v": 0.4, "reach": 0.3}
    box = Inbox(Pose())
    state: dict[str, Any] = {"trail": deque(), "last": None}
    cmd = pursue(args, _ctx(box), state)
    assert (cmd.v, cmd.omega) == (0.0, 0.0)
    # the leader went ahead then turned left: the follower steers to the trail's first
    # point (straight ahead), not at the leader (to its left)
    for p in (Pose(1.0, 0.0, 0.0), Pose(2.0, 0.0, 0.0), Pose(2.5, 1.5, 1.5)):
        box.put(Message("pose", p, "lead", 0.0, 0.1))
        cmd = pursue(args, _ctx(box), state)
    assert cmd.omega == pytest.approx(0.0, abs=1e-12) and cmd.v == pytest.approx(0.4)
    # within the gap of the leader: it stops
    box.put(Message("pose", Pose(0.5, 0.0, 0.0), "lead", 0.0, 0.2))
    cmd = pursue(args, _ctx(box, pose=Pose(0.0, 0.0, 0.0)), state)
    assert cmd.v == 0.0
