"""A signal that Python wraps (an exception in ``__set_name__`` while a class is made, as
dataclasses do at import) is still the interruption it is, never an internal error."""

from __future__ import annotations

import argparse
from typing import Any

from mdle.cli import output
from mdle.cli.signals import Interrupted, SignalGuard, interruption_of


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
