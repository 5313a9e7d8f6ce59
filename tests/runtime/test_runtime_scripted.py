"""The scripted backend emulates what hardware does.

Its own data rates, stale scans, a command watchdog, refusal, dropped links; and it
integrates the held command exactly.
"""

from __future__ import annotations

import math

import pytest

from mdle.core.backend import Backend, ClockMode, Command, RobotLimits
from mdle.core.errors import BackendError
from mdle.core.pose import Pose
from mdle.runtime.scripted import ScriptedBackend


def test_it_is_a_backend() -> None:
    assert isinstance(ScriptedBackend(), Backend)


def test_arc_is_integrated_exactly() -> None:
    b = ScriptedBackend()
    b.command(Command(1.0, math.pi / 2))  # quarter circle of radius 2/pi in 1 s
    for _ in range(10):
        b.advance(0.1)
    r = 2 / math.pi
    assert (b.pose.x, b.pose.y, b.pose.theta) == pytest.approx((r, r, math.pi / 2))
    assert b.time == pytest.approx(1.0)


def test_commands_are_clamped_and_recorded() -> None:
    b = ScriptedBackend(limits=RobotLimits(0.5, 0.2, 1.0))
    b.command(Command(2.0, -3.0))
    b.advance(0.1)
    b.command(Command(-1.0, 0.5))
    assert b.commands == [(0.0, Command(0.5, -1.0)), (pytest.approx(0.1), Command(-0.2, 0.5))]


def test_watchdog_stops_a_robot_left_without_commands() -> None:
    b = ScriptedBackend(watchdog=0.25)
    b.command(Command(1.0, 0.0))
    for _ in range(5):
        b.advance(0.1)
    assert b.held == Command() and b.pose.x == pytest.approx(0.2)


def test_refusing_robot_records_but_does_not_move() -> None:
    b = ScriptedBackend(motors_enabled=False)
    b.command(Command(1.0, 0.0))
    b.advance(1.0)
    obs = b.observe()
    assert b.pose == Pose() and obs.v == 0.0 and not obs.motors_enabled


def test_dropped_link_raises_backend_error_but_stop_never_raises() -> None:
    b = ScriptedBackend(drop_at=0.2)
    b.observe()
    b.advance(0.1)
    b.advance(0.1)
    with pytest.raises(BackendError, match=r"lost \(observe at t = 0.20 s\)"):
        b.observe()
    with pytest.raises(BackendError):
        b.command(Command())
    b.stop()
    b.close()
    assert b.closed and len(b.stops) == 2


def test_script_overrides_and_clock_mode() -> None:
    b = ScriptedBackend([{"stalled": True}, {"battery": 12.5}], clock=ClockMode.WALL,
                        start_time=100.0)
    assert b.clock is ClockMode.WALL
    first = b.observe()
    b.advance(0.1)
    second = b.observe()
    b.advance(0.1)
    third = b.observe()
    assert first.stalled and first.time == 100.0
    assert second.battery == 12.5 and not second.stalled
    assert third.battery is None and third.time == pytest.approx(100.2)
