"""Values the checker computes with, and the dimension rules of MDLe.

A fixed value in a plan is a :class:`Quantity` (an SI number with its dimension) or a
:class:`Symbol` (``right``). The rules for bare numbers (documented in
docs/language.md):

* a bare number is a plain, dimensionless number;
* as a timer it means seconds (``10`` is ``10 s``);
* a bare ``0`` fits any dimension (zero metres, seconds and radians are all zero);
* anywhere else a bare number where a length, time, angle, speed... is expected is
  an error, with a hint naming the unit to add (``30`` is never silently degrees or
  radians).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mdle.core.units import ANGLE, CURVATURE, LENGTH, NONE, SPEED, TIME, TURN_RATE, Dim

__all__ = [
    "Quantity",
    "Symbol",
    "Value",
    "dim_words",
    "dim_example",
    "fits",
    "same_kind",
    "show_value",
]


@dataclass(frozen=True)
class Quantity:
    """A number in SI units with its dimension.

    ``dim`` is None when the dimension is not known yet (a required parameter while a
    definition is checked on its own); ``bare`` marks a number written without a unit.
    """

    value: float
    dim: Dim | None
    bare: bool = False

    @property
    def zero(self) -> bool:
        """A bare 0, which fits any dimension."""
        return self.bare and self.value == 0.0


@dataclass(frozen=True)
class Symbol:
    """A symbol a control law or sensor function declares, such as ``right``."""

    name: str


Value = Quantity | Symbol

_EXAMPLES: dict[Dim, str] = {
    NONE: "`2`",
    LENGTH: "`1 m`",
    TIME: "`10 s`",
    ANGLE: "`30 deg`",
    SPEED: "`0.3 m/s`",
    TURN_RATE: "`30 deg/s`",
    CURVATURE: "`2 rad/m`",
}

_UNIT_OF: dict[Dim, str] = {LENGTH: "m", TIME: "s", ANGLE: "deg", SPEED: "m/s",
                            TURN_RATE: "deg/s", CURVATURE: "rad/m"}


def dim_words(dim: Dim | None) -> str:
    """Return a dimension in words: ``a speed``, ``a plain number``, ``any value``."""
    return "any value" if dim is None else str(dim)


def dim_example(dim: Dim | None) -> str:
    """Return a dimension with an example: ``a speed such as `0.3 m/s```."""
    if dim is None:
        return "a value"
    example = _EXAMPLES.get(dim)
    return f"{dim} such as {example}" if example else f"{dim} ({dim.symbol()})"


def unit_for(dim: Dim) -> str | None:
    """Return the unit suggested for a bare number where ``dim`` is expected."""
    return _UNIT_OF.get(dim)


def same_kind(a: Dim, b: Dim) -> bool:
    """Whether two dimensions measure the same thing.

    Radians are a ratio of lengths, so a rate per metre or per second is the same quantity
    with or without them: a curvature in rad/m compares with ``1 / 2 m``, a turn rate in
    rad/s with ``1 / 1 s``. A bare angle stays apart from a plain number, so that
    ``heading > 30`` still asks for a unit.
    """
    if a is b or a == b:  # dimensions are mostly the shared constants of mdle.core.units
        return True
    if (a.length or a.time) and (b.length or b.time):
        return (a.length, a.time) == (b.length, b.time)
    return False


def fits(value: Quantity, dim: Dim | None) -> bool:
    """Whether ``value`` may stand where ``dim`` is expected (unknowns and bare 0 fit)."""
    return dim is None or value.dim is None or value.zero or same_kind(value.dim, dim)


def show_value(value: Value) -> str:
    """Return a value as a person reads it, in SI units: ``0.3 m/s``, ``right``."""
    if isinstance(value, Symbol):
        return value.name
    if math.isnan(value.value):
        return "?"
    if value.dim is None or value.dim == NONE:
        return f"{value.value:g}"
    if value.dim in (ANGLE, TURN_RATE):  # angles read better in degrees
        return f"{math.degrees(value.value):.6g} deg" + ("/s" if value.dim == TURN_RATE else "")
    return f"{value.value:.6g} {value.dim.symbol()}"
