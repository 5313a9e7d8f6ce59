"""`/` after a number with a unit: a compound unit, or a division by a name."""

from __future__ import annotations

import math

import pytest

from mdle.core.errors import MdleSyntaxError
from mdle.core.units import LENGTH, NONE, SPEED, TIME, TURN_RATE
from mdle.lang import format_source, load_text
from mdle.lang import syntax as st
from mdle.lang.parser import parse_expression, parse_module


@pytest.mark.parametrize("text, value, dim", [
    ("0.3 m/s", 0.3, SPEED),
    ("0.3 m / s", 0.3, SPEED),       # a unit of the table after a spaced `/`: still a unit
    ("30 deg/s", math.radians(30), TURN_RATE),
    ("30 deg / s", math.radians(30), TURN_RATE),
    ("2 min", 120.0, TIME),
])
def test_compound_units_stay_units(text: str, value: float, dim: object) -> None:
    node = parse_expression(text)
    assert isinstance(node, st.Number)
    assert node.value == pytest.approx(value) and node.dim == dim


@pytest.mark.parametrize("text, left, right", [
    ("0.4 m / v", "0.4 m", "v"),
    ("1 m / x", "1 m", "x"),
    ("1 m /speed", "1 m", "speed"),    # `speed` is not the unit `s`
    ("10 s / t", "10 s", "t"),
])
def test_a_name_after_a_spaced_slash_is_divided_by(text: str, left: str, right: str) -> None:
    node = parse_expression(text)
    assert isinstance(node, st.Binary) and node.op == "/"
    assert isinstance(node.left, st.Number) and f"{node.left.text} {node.left.unit}" == left
    assert isinstance(node.right, st.Name) and node.right.name == right


def test_division_by_a_parameter_checks_and_evaluates() -> None:
    program = load_text("atom a(v = 0.2 m/s) = (go(v), t > 0.4 m / v or x > 1 m / 2, 1 min)\n"
                        "interrupt far = 1 m / x < 0.5\nrun a\n")
    assert not [w for w in program.warnings if "error" in w.message]
    assert program.entry is not None


def test_fmt_round_trips_divisions() -> None:
    text = "atom a(v = 0.2 m/s) = (go(v), t > 0.4 m / v and x < 3 m / 2, 0.3 m / s * 1 s / v)\n"
    statements = parse_module(text, "f.mdle").statements
    formatted = format_source(text)
    assert "0.4 m / v" in formatted and "0.3 m/s * 1 s / v" in formatted
    assert format_source(formatted) == formatted
    assert parse_module(formatted, "f.mdle").statements == statements


def test_a_tight_slash_with_an_unknown_word_says_how_to_divide() -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_module("atom a(v = 0.2 m/s) = (go(v), t > 0.4 m/v, 1 min)")
    (d,) = err.value.diagnostics
    assert d.message == "unknown unit `v`"
    assert "to divide by `v`, put spaces around `/`: `0.4 m / v`" in (d.hint or "")
    assert "multiply" not in (d.hint or "")


def test_bare_and_unit_numbers_divide_as_before() -> None:
    node = parse_expression("x / 2")
    assert isinstance(node, st.Binary) and node.op == "/"
    number = parse_expression("1 / 2")
    assert isinstance(number, st.Binary) and isinstance(number.left, st.Number)
    assert number.left.dim == NONE
    assert parse_expression("3 m").dim == LENGTH  # type: ignore[union-attr]
