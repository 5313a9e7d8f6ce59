"""Physical dimensions and the unit table of MDLe source text.

Values inside mdle are SI (metres, seconds, radians). A :class:`Dim` records the
exponents of length, time and angle so the checker can refuse a length where a time
is expected. Angle is tracked as its own dimension (though SI calls it dimensionless)
because confusing ``30`` with ``30 deg`` is the commonest unit slip in robot plans.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = [
    "Dim",
    "NONE",
    "LENGTH",
    "TIME",
    "ANGLE",
    "SPEED",
    "TURN_RATE",
    "CURVATURE",
    "UNITS",
    "unit_value",
]


@dataclass(frozen=True)
class Dim:
    """Exponents of (length, time, angle); ``Dim(0, 0, 0)`` is a plain number."""

    length: int = 0
    time: int = 0
    angle: int = 0

    def __mul__(self, other: "Dim") -> "Dim":
        return Dim(self.length + other.length, self.time + other.time, self.angle + other.angle)

    def __truediv__(self, other: "Dim") -> "Dim":
        return Dim(self.length - other.length, self.time - other.time, self.angle - other.angle)

    def __str__(self) -> str:
        return _NAMES.get(self, self.symbol())

    def symbol(self) -> str:
        """Return the dimension as a unit expression in SI base units, such as ``m/s``."""
        num = [u for u, e in (("m", self.length), ("s", self.time), ("rad", self.angle)) if e > 0
               for _ in range(e)]
        den = [u for u, e in (("m", self.length), ("s", self.time), ("rad", self.angle)) if e < 0
               for _ in range(-e)]
        top = "*".join(num) or "1"
        return top if not den else f"{top}/{'*'.join(den)}"


NONE = Dim()
LENGTH = Dim(length=1)
TIME = Dim(time=1)
ANGLE = Dim(angle=1)
SPEED = LENGTH / TIME
TURN_RATE = ANGLE / TIME
CURVATURE = ANGLE / LENGTH  # rad/m: the heading turns this much per metre of arc

_NAMES = {
    NONE: "a plain number",
    LENGTH: "a length",
    TIME: "a time",
    ANGLE: "an angle",
    SPEED: "a speed",
    TURN_RATE: "a turn rate",
    CURVATURE: "a curvature",
    Dim(length=-1): "a curvature",
}

#: Unit symbols accepted in source text: (factor to SI, dimension).
UNITS: dict[str, tuple[float, Dim]] = {
    "m": (1.0, LENGTH),
    "cm": (0.01, LENGTH),
    "mm": (0.001, LENGTH),
    "s": (1.0, TIME),
    "ms": (0.001, TIME),
    "min": (60.0, TIME),
    "deg": (math.pi / 180.0, ANGLE),
    "rad": (1.0, ANGLE),
}


def unit_value(expr: str) -> tuple[float, Dim]:
    """Factor to SI and dimension of a unit expression such as ``m``, ``deg/s`` or ``m/s``.

    Raises ``KeyError`` naming the unknown symbol.

    >>> unit_value("deg/s")[1] == TURN_RATE
    True
    >>> round(unit_value("cm")[0], 3)
    0.01
    """
    parts = expr.replace(" ", "").split("/")
    factor, dim = UNITS[parts[0]]
    for p in parts[1:]:
        f, d = UNITS[p]
        factor, dim = factor / f, dim / d
    return factor, dim
