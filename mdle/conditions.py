"""Interrupt expressions compiled once into closures.

The checker types each sub-expression (:class:`Typed`: a condition, or a number of
some dimension) and combines closures bottom-up; constant parts are folded at check
time, so ``range(0 deg) < 2 * 0.5 m`` becomes one call of the sensor function and one
comparison per tick. The runtime calls ``Interrupt.test(ctx)`` and nothing else.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from atoms.registry import BOOL, Context, SensorSpec
from mdle.program import NEVER, Interrupt
from mdle.units import Dim

__all__ = ["Typed", "constant", "sensor_reading", "negate", "logic", "compare", "arith",
           "to_interrupt"]

Kind = Any  # Dim (a number), None (a number of unknown dimension) or BOOL (a condition)
Fn = Callable[[Context], Any]


@dataclass(frozen=True)
class Typed:
    """A typed expression: its kind, and either a constant or a closure ``fn(ctx)``."""

    kind: Kind
    fn: Fn | None = None
    const: Any = None

    @property
    def is_bool(self) -> bool:
        """True for a condition."""
        return self.kind is BOOL

    @property
    def is_const(self) -> bool:
        """True when the value is known at check time."""
        return self.fn is None

    @property
    def dim(self) -> Dim | None:
        """The dimension of a number (None when unknown)."""
        return None if self.kind is BOOL else self.kind

    def call(self) -> Fn:
        """Return a closure for this expression (constants become a function returning them)."""
        if self.fn is not None:
            return self.fn
        value = self.const
        return lambda ctx: value


def constant(kind: Kind, value: Any) -> Typed:
    """Return a value known at check time."""
    return Typed(kind, None, value)


def sensor_reading(spec: SensorSpec, args: Mapping[str, Any]) -> Typed:
    """Return a sensor function read each time the interrupt is tested."""
    fn = spec.fn

    def read(ctx: Context) -> Any:
        return fn(args, ctx)

    return Typed(spec.result, read)


def negate(op: str, a: Typed) -> Typed:
    """``not a``, ``-a`` or ``+a`` (already type-checked)."""
    if op == "not":
        if a.is_const:
            return constant(BOOL, not a.const)
        f = a.fn
        return Typed(BOOL, lambda ctx: not f(ctx))  # type: ignore[misc]
    if op == "+":
        return a
    if a.is_const:
        return constant(a.kind, -a.const)
    g = a.fn
    return Typed(a.kind, lambda ctx: -g(ctx))  # type: ignore[misc]


def logic(op: str, a: Typed, b: Typed) -> Typed:
    """Combine conditions with ``and``, ``or``, ``xor``, short-circuiting where it can."""
    if a.is_const and b.is_const:
        value = {"and": a.const and b.const, "or": a.const or b.const,
                 "xor": bool(a.const) != bool(b.const)}[op]
        return constant(BOOL, bool(value))
    for fixed, other in ((a, b), (b, a)):
        if fixed.is_const:
            if op == "and":
                return other if fixed.const else constant(BOOL, False)
            if op == "or":
                return constant(BOOL, True) if fixed.const else other
            return negate("not", other) if fixed.const else other
    f, g = a.call(), b.call()
    if op == "and":
        return Typed(BOOL, lambda ctx: bool(f(ctx)) and bool(g(ctx)))
    if op == "or":
        return Typed(BOOL, lambda ctx: bool(f(ctx)) or bool(g(ctx)))
    return Typed(BOOL, lambda ctx: bool(f(ctx)) != bool(g(ctx)))


_COMPARE: dict[str, Callable[[Any, Any], bool]] = {
    "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge,
    "==": operator.eq, "!=": operator.ne,
}
_ARITH: dict[str, Callable[[Any, Any], Any]] = {
    "+": operator.add, "-": operator.sub, "*": operator.mul,
}


def _divide(x: float, y: float) -> float:
    if y == 0:
        return math.copysign(math.inf, x) if x else math.nan
    return x / y


def compare(op: str, a: Typed, b: Typed) -> Typed:
    """Return a comparison of two numbers of the same dimension."""
    cmp = _COMPARE[op]
    if a.is_const and b.is_const:
        return constant(BOOL, bool(cmp(a.const, b.const)))
    if b.is_const:
        f, k = a.call(), b.const
        return Typed(BOOL, lambda ctx: bool(cmp(f(ctx), k)))
    if a.is_const:
        k, g = a.const, b.call()
        return Typed(BOOL, lambda ctx: bool(cmp(k, g(ctx))))
    f, g = a.call(), b.call()
    return Typed(BOOL, lambda ctx: bool(cmp(f(ctx), g(ctx))))


def arith(op: str, a: Typed, b: Typed, kind: Kind) -> Typed:
    """Apply ``a + b`` and friends; division by zero gives inf (or nan), never an exception."""
    fn = _divide if op == "/" else _ARITH[op]
    if a.is_const and b.is_const:
        return constant(kind, fn(a.const, b.const))
    f, g = a.call(), b.call()
    return Typed(kind, lambda ctx: fn(f(ctx), g(ctx)))


def to_interrupt(t: Typed, source: str) -> Interrupt:
    """Return the runtime's :class:`~mdle.program.Interrupt` for a checked condition."""
    if t.is_const:
        if not t.const:
            return NEVER if source == "never" else Interrupt(NEVER.test, source, never=True)
        return Interrupt(lambda ctx: True, source)
    fn = t.fn
    return Interrupt(lambda ctx: bool(fn(ctx)), source)  # type: ignore[misc]
