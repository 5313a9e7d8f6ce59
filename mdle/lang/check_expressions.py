"""The checker's expressions read each tick, and comparisons that can never hold.

Sensor functions of sensor functions, ``abs``, ``min``, ``max``, ``at_start``, sensor
overloads: the base of :class:`~mdle.lang.check_dimensions.DimensionChecks`, which calls
these methods while it types conditions.
"""

from __future__ import annotations

import math
from abc import abstractmethod
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

from mdle.atoms.registry import REQUIRED, SensorSpec
from mdle.lang import conditions as cond
from mdle.lang import syntax as st
from mdle.lang.check_state import CheckerState, Env, _Abort, _short, _Slot
from mdle.lang.dimensions import Quantity, Value, dim_example, dim_words, same_kind, show_value

__all__ = ["ExpressionChecks", "overload", "disjuncts"]

#: The functions of numbers a condition may call (besides ``at_start``)
_NUMBER_FUNCTIONS: Mapping[str, Callable[..., Any]] = MappingProxyType(
    {"abs": abs, "min": min, "max": max})

class ExpressionChecks(CheckerState):
    """Expressions read each tick, and bounded readings."""

    @abstractmethod
    def condition(self, expr: st.Expr, env: Env) -> cond.Typed:
        """Type and compile a condition (:mod:`~mdle.lang.check_dimensions`)."""

    def _is_live(self, expr: st.Expr, env: Env) -> bool:
        """Tell whether ``expr`` reads a sensor function (or a start value): not fixed."""
        if isinstance(expr, st.Name):
            return expr.name not in env and isinstance(self._lookup(expr.name), SensorSpec)
        if isinstance(expr, st.Call):
            if expr.name in cond.BUILTINS and expr.name not in env:
                # at_start, lowest, highest, ever: kept by the element, never fixed
                remembers = expr.name == "at_start" or expr.name in cond.FOLDS
                return remembers or any(self._is_live(a.value, env) for a in expr.args)
            return isinstance(self._lookup(expr.name), SensorSpec)
        if isinstance(expr, st.Binary):
            return self._is_live(expr.left, env) or self._is_live(expr.right, env)
        if isinstance(expr, st.Unary):
            return self._is_live(expr.operand, env)
        if isinstance(expr, st.Group):
            return any(self._is_live(e, env) for e in expr.items)
        return False

    def live_argument(self, callee: str, slot: _Slot, expr: st.Expr, env: Env) -> Value | None:
        """Type an argument of a sensor function read each tick (``range(-theta)``).

        Returns a placeholder value for the binder (the expression is kept aside), or
        None when the argument is fixed and is bound as usual.
        """
        read = self._live_args
        if read is None or slot.symbol or not self._is_live(expr, env):
            return None
        p = slot.param
        if p is not None and p.fixed:
            self.error(expr.span, f"`{slot.name}` of `{callee}` is a fixed value, but this "
                       "reads a sensor function", hint="give it a number with its unit, or a "
                       "parameter; sensor readings are not taken here")
            raise _Abort
        t = self.condition(expr, env)
        if t.is_bool:
            self.error(expr.span, f"`{slot.name}` of `{callee}` is {dim_example(slot.dim)}, "
                       "found a condition")
            raise _Abort
        if t.dim is not None and slot.dim is not None and not same_kind(t.dim, slot.dim):
            self.error(expr.span, f"`{slot.name}` of `{callee}` is {dim_example(slot.dim)}, "
                       f"found {dim_words(t.dim)} (`{_short(expr)}`)")
            raise _Abort
        read[slot.name] = t
        return Quantity(math.nan, slot.dim)

    def _builtin(self, expr: st.Call, env: Env) -> cond.Typed:
        """``abs``, ``min``, ``max``, ``at_start``, ``lowest``, ``highest`` and ``ever``."""
        name = expr.name
        low, high = cond.BUILTINS[name]
        named = [a for a in expr.args if a.name is not None]
        if named:
            self.error(named[0].span, f"`{name}` takes no keyword arguments")
            raise _Abort
        n = len(expr.args)
        if not low <= n <= high:
            takes = ("one value" if high == 1 else "two values or more")
            self.error(expr.span, f"`{name}` takes {takes}, found {n}")
            raise _Abort
        if name == "at_start":
            if self._remembering:
                self.error(expr.span, "`at_start` inside `at_start`: the inner one adds "
                           "nothing", hint=f"write `{_short(expr.args[0].value)}`")
                raise _Abort
            self._remembering = True
            try:
                t = self.condition(expr.args[0].value, env)
            finally:
                self._remembering = False
            return cond.remembered(t)
        if name in cond.FOLDS:  # a running memory: lowest(e), highest(e), ever(c)
            t = self.condition(expr.args[0].value, env)
            if (name == "ever") != t.is_bool:
                needs = "a condition" if name == "ever" else "a number"
                found = "a condition" if t.is_bool else dim_words(t.dim)
                self.error(expr.args[0].span, f"`{name}` needs {needs}, found {found}",
                           hint="`ever(c)`: c has held at some tick; `lowest(e)`, "
                                "`highest(e)`: the least or greatest e so far")
                raise _Abort
            return cond.tracked(name, t)
        parts = [self.condition(a.value, env) for a in expr.args]
        for a, t in zip(expr.args, parts, strict=True):
            if t.is_bool:
                self.error(a.span, f"`{name}` needs numbers, found a condition")
                raise _Abort
        dim = next((t.dim for t in parts if t.dim is not None), None)
        for a, t in zip(expr.args, parts, strict=True):
            if not _same_dim(t, parts[0]) or (dim is not None and t.dim is not None
                                               and not same_kind(t.dim, dim)):
                self.error(a.span, f"`{name}` needs values of one kind: found "
                           f"{dim_words(t.dim)} beside {dim_words(dim)}")
                raise _Abort
        return cond.apply(_NUMBER_FUNCTIONS[name], parts, dim)

    def _never_holds(self, expr: st.Binary, a: cond.Typed, b: cond.Typed) -> None:
        """Warn about a comparison of a bounded reading that can never hold (`theta > 200 deg`)."""
        for reading, other, left in ((a, b, True), (b, a, False)):
            hit = self._bounded.get(id(reading.node)) if reading.node is not None else None
            if hit is None or not other.is_const or not isinstance(other.const, (int, float)):
                continue
            bounds, name = hit
            if bounds.holds_somewhere(expr.op, float(other.const), left):
                continue
            self.warn(expr.span, f"`{_short(expr)}` can never hold: `{name}` lies in "
                      f"{_interval(bounds, reading.dim)}",
                      hint="this comparison is always false",
                      in_use=True)


def _same_dim(a: cond.Typed, b: cond.Typed) -> bool:
    x, y = a.dim, b.dim
    return x is None or y is None or x is y or same_kind(x, y)


def _interval(b: Any, dim: Any) -> str:
    """``(-180 deg, 180 deg]``: bounds in the unit a plan writes them in."""
    def show(v: float) -> str:
        return "inf" if math.isinf(v) else show_value(Quantity(v, dim))
    return (f"{'(' if b.low_open else '['}{show(b.low)}, {show(b.high)}"
            f"{')' if b.high_open or math.isinf(b.high) else ']'}")


def overload(spec: SensorSpec, args: tuple[st.Argument, ...] | list[st.Argument]) -> SensorSpec:
    """Pick the sensor function of that name whose parameters the call's arguments fit."""
    if not spec.overloads:
        return spec
    names = {a.name for a in args if a.name is not None}
    for candidate in (spec, *spec.overloads):
        params = {p.name for p in candidate.params}
        needed = sum(1 for p in candidate.params if p.default is REQUIRED)
        if names <= params and needed <= len(args) <= len(candidate.params):
            return candidate
    return spec


def disjuncts(expr: st.Expr) -> list[st.Expr]:
    """Return the conditions a top-level ``or`` joins (``a or (b or c)``: a, b, c)."""
    while isinstance(expr, st.Group) and len(expr.items) == 1 and not expr.repeat:
        expr = expr.items[0]
    if isinstance(expr, st.Binary) and expr.op == "or":
        return disjuncts(expr.left) + disjuncts(expr.right)
    return [expr]
