"""mdle.core.exit_hooks: what a robot backend registers so the robot stops however mdle ends."""

from __future__ import annotations

import signal

import pytest

from mdle.core.exit_hooks import register_exit_hooks


class _Robot:
    def __init__(self) -> None:
        self.closes = 0

    @property
    def closed(self) -> bool:
        return self.closes > 0

    def close(self) -> None:
        self.closes += 1


def test_an_unhandled_sigterm_becomes_system_exit_until_the_robot_is_closed() -> None:
    old = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        robot = _Robot()
        hooks = register_exit_hooks(robot, handle_sigterm=True)
        handler = signal.getsignal(signal.SIGTERM)
        assert callable(handler)
        with pytest.raises(SystemExit) as exc:
            handler(signal.SIGTERM, None)
        assert exc.value.code == 143
        robot.close()
        handler(signal.SIGTERM, None)  # closed: a second SIGTERM must not cut the goodbye
        assert hooks.at_exit is not None
        hooks.at_exit()
        assert robot.closes == 2  # the exit hook closes the robot
        hooks.release()
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
        assert hooks.at_exit is None and hooks.old_sigterm is None
        hooks.release()  # twice is harmless
    finally:
        signal.signal(signal.SIGTERM, old)


def test_a_handler_already_there_keeps_sigterm() -> None:
    def mine(signum: int, frame: object) -> None:
        pass

    old = signal.signal(signal.SIGTERM, mine)
    try:
        hooks = register_exit_hooks(_Robot(), handle_sigterm=True)
        assert signal.getsignal(signal.SIGTERM) is mine
        hooks.release()
        assert signal.getsignal(signal.SIGTERM) is mine
    finally:
        signal.signal(signal.SIGTERM, old)


def test_the_hooks_do_not_keep_a_dropped_backend_alive() -> None:
    robot = _Robot()
    hooks = register_exit_hooks(robot, handle_sigterm=False)
    del robot
    assert hooks.at_exit is not None
    hooks.at_exit()  # nothing left to close, and no error
    hooks.release()
