"""A signal that Python wraps (an exception in ``__set_name__`` while a class is made, as
dataclasses do at import) is still the interruption it is, never an internal error."""

from __future__ import annotations

import argparse
from typing import Any

import pytest

from mdle.console import output
from mdle.console.signals import Interrupted, SignalGuard, interruption_of


class _Raises:
    def __set_name__(self, owner: type, name: str) -> None:
        raise Interrupted(2)


def _make_class() -> None:
    type("C", (), {"f": _Raises()})  # Python <= 3.11 wraps this in a RuntimeError


def test_the_interruption_behind_a_wrapped_error_is_found() -> None:
    try:
        _make_class()
    except BaseException as exc:  # RuntimeError on 3.11, the Interrupted itself later
        found = interruption_of(exc)
        assert isinstance(found, Interrupted) and found.signum == 2
    else:
        raise AssertionError("the class was made")
    assert interruption_of(ValueError("plain")) is None


def test_guarded_reports_it_as_an_interruption_not_an_internal_error(capsys: Any) -> None:
    def handler(args: argparse.Namespace) -> int:
        _make_class()
        return 0

    args = argparse.Namespace(signals=SignalGuard(), debug=False)
    assert output.guarded(handler, args) == 130
    err = capsys.readouterr().err
    assert "internal error" not in err and "interrupted by SIGINT" in err


class _Target:
    def __init__(self) -> None:
        self.asked: list[str | None] = []
        self.ending = False

    def request_stop(self, reason: str | None = None) -> None:
        self.asked.append(reason)


class _RaisesOnCollect:
    """Runs the guard's handler where Python cannot raise (as a signal landing in the
    import system's module-lock weakref callback does): the exception is 'ignored'."""

    def __init__(self, guard: SignalGuard) -> None:
        self.guard = guard

    def __del__(self) -> None:
        self.guard._handle(2, None)


def test_an_interruption_python_could_not_raise_is_kept_and_stops_the_run(
        capsys: Any) -> None:
    guard = SignalGuard().install(deferred=False)
    try:
        _RaisesOnCollect(guard)  # collected at once: the raise in __del__ is swallowed
        assert guard.pending and guard.received == 2
        target = _Target()
        with guard.stopping(target):  # the next checkpoint acts on it
            pass
        assert target.asked == ["SIGINT (Ctrl-C)"] and not guard.pending
    finally:
        guard.restore()
    assert "Exception ignored" not in capsys.readouterr().err  # no traceback either


def test_other_unraisable_errors_still_reach_the_previous_hook(capsys: Any) -> None:
    class _Fails:
        def __del__(self) -> None:
            raise ValueError("from __del__")

    seen: list[BaseException | None] = []
    import sys

    old = sys.unraisablehook
    sys.unraisablehook = lambda u: seen.append(u.exc_value)
    guard = SignalGuard().install(deferred=False)
    try:
        _Fails()
        assert not guard.pending
        assert len(seen) == 1 and isinstance(seen[0], ValueError)
    finally:
        guard.restore()
        sys.unraisablehook = old
    assert sys.unraisablehook is old


def test_a_signal_raised_and_swallowed_on_the_way_still_stops_the_run() -> None:
    # A library that catches BaseException (not Python's "Exception ignored": no hook
    # sees it) swallows the Interrupted; the run that follows must stop at once all the same.
    guard = SignalGuard()
    guard.arm()
    with pytest.raises(Interrupted):  # raised, then swallowed on the way
        guard._handle(15, None)
    assert guard.received == 15 and not guard.pending
    target = _Target()
    with guard.stopping(target):
        pass
    assert target.asked == ["SIGTERM"]


def test_a_signal_as_mdle_exits_never_kills_it_without_a_word(tmp_path: Any,
                                                              mdle_command: list[str]) -> None:
    # Python put the default handlers back while it shut down (60-260 ms): a SIGTERM then
    # killed mdle with no message in 3 to 29 of 40 tries
    import signal
    import subprocess

    plan = tmp_path / "p.mdle"
    plan.write_text("atom a = (go(0.3 m/s), never, 1 s)\nrun a\n")
    killed = []
    for _ in range(12):
        proc = subprocess.Popen([*mdle_command, "check", str(plan)], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        assert proc.stdout is not None
        proc.stdout.readline()  # the command's last line: it is ending now
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        if proc.returncode == -signal.SIGTERM:
            killed.append(err)
        else:  # done (0), or interrupted with mdle's own message (143)
            assert proc.returncode == 0 or (proc.returncode == 143 and "interrupted" in err)
    assert killed == []
