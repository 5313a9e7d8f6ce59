"""Every number a user gives is checked against one range with one message (mdle/core/ranges.py).

``--rate 1e-308`` was an internal error (exit 70), ``--rate 5e-324`` a message that did
not name the option, and ``--start 1e308,0,0`` a run where the robot "moved" 0 m.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mdle.cli import main
from mdle.core.ranges import COORDINATE, HEADING, RATE


@pytest.mark.parametrize("value", [0.001, 1.0, 1000.0])
def test_rates_in_range_pass(value: float) -> None:
    assert RATE.problem(value) is None


@pytest.mark.parametrize("value", [0.0, -1.0, 1e-308, 5e-324, 1000.5, float("inf"),
                                   float("nan")])
def test_rates_out_of_range_say_the_range(value: float) -> None:
    assert RATE.problem(value, "X") == "the rate must be from 0.001 to 1,000 Hz, got X"


@pytest.mark.parametrize("degrees", [-360.0, -90.0, 0.0, 359.5, 360.0])
def test_headings_within_one_turn_pass(degrees: float) -> None:
    assert HEADING.problem(math.radians(degrees)) is None


def test_coordinates_share_the_world_files_bound() -> None:
    from mdle.sim.yaml_values import MAX_COORDINATE

    assert COORDINATE.high == MAX_COORDINATE and COORDINATE.low == -MAX_COORDINATE


@pytest.fixture
def plan(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    p = tmp_path / "p.mdle"
    p.write_text("atom a = (go(0.3 m/s), never, 1 s)\nrun a\n")
    return p


@pytest.mark.parametrize(("argv", "message"), [
    (["--rate", "1e-308"], "argument --rate: the rate must be from 0.001 to 1,000 Hz, "
                           "got 1e-308"),
    (["--rate", "5e-324"], "argument --rate: the rate must be from 0.001 to 1,000 Hz"),
    (["--rate", "1e6"], "argument --rate: the rate must be from 0.001 to 1,000 Hz, got 1e6"),
    (["--start", "1e308,0,0"], "X of --start: a coordinate must be from -1,000,000 to "
                               "1,000,000 m, got 1e308"),
    (["--start", "0,-2000km,0"], "Y of --start: unknown unit"),
    (["--start", "0,-2e8cm,0"], "Y of --start: a coordinate must be from"),
    (["--start", "0,0,1e308"], "THETA of --start: a heading must be from -360 to 360 deg, "
                               "got 1e308"),
    (["--start", "0,0,1e400"], "THETA of --start: a heading must be from -360 to 360 deg, "
                               "got 1e400"),
    (["--start", "0,0,-361"], "THETA of --start: a heading must be from -360 to 360 deg, "
                              "got -361"),
    (["--start", "0,0,7 rad"], "THETA of --start: a heading must be from -360 to 360 deg, "
                               "got 7 rad"),
    (["--start", "1e400,0,0"], "X of --start: a coordinate must be from -1,000,000 to "
                               "1,000,000 m, got 1e400"),
])
def test_run_options_out_of_range_are_usage_errors(
        plan: Path, argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "p.mdle", "-q", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and "internal error" not in err


def test_experiment_rate_is_checked_the_same_way(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiment", "random-starts", "--rate", "1e-308"]) == 2
    assert "argument --rate: the rate must be from 0.001 to 1,000 Hz" in capsys.readouterr().err


def test_a_start_heading_of_a_whole_turn_runs(plan: Path) -> None:
    assert main(["run", "p.mdle", "-q", "--world", "empty", "--start", "0,0,-360"]) == 0
