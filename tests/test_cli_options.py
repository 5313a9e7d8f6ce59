"""The options `mdle run` and `mdle repl` share (mdle/cli/options.py)."""

from __future__ import annotations

import argparse
import math

import pytest

from mdle.cli import build_parser
from mdle.cli.options import positive_seconds, seconds


@pytest.mark.parametrize("text, value", [("0", 0.0), ("2.5", 2.5), ("1e3", 1000.0),
                                         ("inf", math.inf)])
def test_seconds_reads_zero_or_more(text: str, value: float) -> None:
    assert seconds(text) == value


@pytest.mark.parametrize("text, message", [
    ("-1", "must be zero or more seconds, got '-1'"),
    ("nan", "must be zero or more seconds, got 'nan'"),
    ("10s", "expected a number of seconds, got '10s'"),
])
def test_seconds_rejects_with_the_reason(text: str, message: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=f"^{message}$"):
        seconds(text)


@pytest.mark.parametrize("text, message", [
    ("0", "must be more than zero seconds, got '0'"),
    ("-0.5", "must be more than zero seconds, got '-0.5'"),
    ("nan", "must be more than zero seconds, got 'nan'"),
    ("soon", "expected a number of seconds, got 'soon'"),
])
def test_positive_seconds_rejects_zero_and_below(text: str, message: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=f"^{message}$"):
        positive_seconds(text)
    assert positive_seconds("0.1") == 0.1


@pytest.mark.parametrize("command", ["run", "repl"])
def test_run_and_repl_take_the_same_simulation_options(command: str) -> None:
    argv = [command, "plan.mdle"] if command == "run" else [command]
    args = build_parser().parse_args([*argv, "--seed", "3", "--robot", "ideal",
                                      "--sensing", "exact"])
    assert (args.seed, args.robot, args.sensing) == (3, "ideal", "exact")
    defaults = build_parser().parse_args(argv)
    assert (defaults.seed, defaults.robot, defaults.sensing) == (None, None, "scan")


def test_until_bounds_differ_between_run_and_repl(capsys: pytest.CaptureFixture[str]) -> None:
    # `mdle run --until 0` stops the run at its first tick (t = 0); in the REPL a limit of 0
    # would stop every run, so it asks for more than zero
    assert build_parser().parse_args(["run", "p.mdle", "--until", "0"]).until == 0.0
    with pytest.raises(SystemExit) as exit_:
        build_parser().parse_args(["repl", "--until", "0"])
    assert exit_.value.code == 2
    assert "must be more than zero seconds" in capsys.readouterr().err
