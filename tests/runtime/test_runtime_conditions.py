"""Interrupts compiled from MDLe conditions into one flat function.

The generated function must do what the conditions say, operator by operator: the same
sensor calls in the same order (``and``/``or`` short-circuit), division by zero giving
inf or nan, and a Python bool whatever the sensors return (numpy scalars, NaN).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pytest

from mdle.atoms.registry import BOOL, Context, SensorSpec
from mdle.core.units import LENGTH
from mdle.lang import conditions as cond


def _reader(name: str, values: list[Any], calls: list[str], kind: Any = LENGTH) -> cond.Typed:
    """Return a sensor reading that yields ``values`` in turn and logs its calls."""
    it = iter(values)

    def fn(args: Mapping[str, Any], ctx: Context) -> Any:
        calls.append(name)
        return next(it)

    return cond.sensor_reading(SensorSpec(name, (), kind, fn), {})


def _test(t: cond.Typed) -> Any:
    """Return the compiled interrupt's value (sensors here ignore the context)."""
    ctx: Any = None
    return cond.to_interrupt(t, "test").test(ctx)


@pytest.mark.parametrize("value, expected", [
    (0.5, True), (np.float64(0.5), True), (np.float64(2.0), False), (math.nan, False)])
def test_comparison_calls_the_sensor_and_returns_a_python_bool(value: Any,
                                                               expected: bool) -> None:
    calls: list[str] = []
    t = cond.compare("<", _reader("r", [value], calls), cond.constant(LENGTH, 1.0))
    result = _test(t)
    assert result is expected and calls == ["r"]


def test_and_or_short_circuit_left_to_right() -> None:
    calls: list[str] = []
    one = cond.constant(LENGTH, 1.0)
    left = cond.compare(">", _reader("a", [2.0, 0.0], calls), one)
    right = cond.compare(">", _reader("b", [2.0], calls), one)
    assert _test(cond.logic("or", left, right)) is True and calls == ["a"]
    calls.clear()
    assert _test(cond.logic("or", left, right)) is True and calls == ["a", "b"]
    calls.clear()
    left = cond.compare(">", _reader("c", [0.0], calls), one)
    assert _test(cond.logic("and", left, right)) is False and calls == ["c"]


def test_xor_not_and_arithmetic_with_division_by_zero() -> None:
    calls: list[str] = []
    x = _reader("x", [3.0, 3.0, 0.0], calls)
    zero = cond.constant(LENGTH, 0.0)
    # -x / 0 = -inf < 0 for x = 3; 0 / 0 is nan, and nan < 0 is false
    below = cond.compare("<", cond.arith("/", cond.negate("-", x), zero, LENGTH), zero)
    assert _test(below) is True
    assert _test(cond.negate("not", below)) is False
    assert _test(below) is False
    flag = _reader("f", [np.bool_(True)] * 2, calls, BOOL)
    assert _test(cond.logic("xor", flag, cond.negate("not", flag))) is True
    # `flag` is one node used twice: a test reads it once and reuses the value
    assert calls == ["x", "x", "x", "f"]


def test_a_shared_node_is_read_once_per_test_and_again_at_the_next() -> None:
    calls: list[str] = []
    one = cond.constant(LENGTH, 1.0)
    low = cond.compare("<", _reader("r", [2.0, 0.5], calls), one)
    both = cond.logic("or", cond.logic("and", low, low), cond.negate("not", low))
    test = cond.to_interrupt(both, "test").test
    ctx: Any = None
    assert test(ctx) is True and calls == ["r"]  # r = 2: low false, `not low` true
    assert test(ctx) is True and calls == ["r", "r"]  # a new test reads again


def test_constants_are_folded_at_check_time() -> None:
    one, two = cond.constant(LENGTH, 1.0), cond.constant(LENGTH, 2.0)
    assert cond.compare("<", one, two) == cond.constant(BOOL, True)
    assert cond.to_interrupt(cond.compare(">", one, two), "1 m > 2 m").never
