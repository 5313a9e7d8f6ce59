"""The ranges numbers from users must lie in, and the one message for each.

A control rate comes from ``--rate``, a team file, a study's ``rates`` and the
experiments; a start pose from ``--start``, the REPL's ``:reset`` and a world file. Each
kind of number is checked here, so every input says the same thing about it
(docs/limits.md lists the ranges). A start pose's heading must be within one turn
either way: any heading can be written so, and 1e308 degrees is a typo. The callers
put the place in front: the option, or the file, line and key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["NumberRange", "RATE", "COORDINATE", "HEADING", "MAX_SEED"]


@dataclass(frozen=True)
class NumberRange:
    """Closed range ``[low, high]`` of a kind of number, in SI.

    Messages show the range in ``unit``, of which one is ``per_unit`` SI units (an
    angle is kept in radians and shown in degrees).
    """

    what: str
    low: float
    high: float
    unit: str
    per_unit: float = 1.0

    def problem(self, value: float, shown: str | None = None) -> str | None:
        """Return what is wrong with ``value`` in words, or None when it is in range."""
        text = shown if shown is not None else f"{value:g}"
        if not math.isfinite(value) or not self.low <= value <= self.high:
            low, high = self.low / self.per_unit, self.high / self.per_unit
            return (f"{self.what} must be from {_plain(low)} to {_plain(high)} "
                    f"{self.unit}, got {text}")
        return None


#: Control rates (Hz). Below a thousandth of a hertz a tick is longer than 16 minutes
#: and the clock's steps stop being exact; above 1000 Hz no robot or ladar keeps up.
RATE = NumberRange("the rate", 0.001, 1000.0, "Hz")
#: Coordinates of poses (m): farther from the origin than this is a typo, not a place
#: (the same bound as a world file's coordinates).
COORDINATE = NumberRange("a coordinate", -1e6, 1e6, "m")
#: Headings of start poses (rad, shown in degrees): one turn either way.
HEADING = NumberRange("a heading", -2.0 * math.pi, 2.0 * math.pi, "deg", math.pi / 180.0)
#: Largest simulation seed (numpy's legacy seeding takes 32 bits).
MAX_SEED = 2**32 - 1


def _plain(x: float) -> str:
    """Return ``1,000,000`` for 1e6 and ``0.001`` for 1e-3 (no exponents in a range)."""
    x = round(x, 9)  # 360 deg, not 359.99999999999994, after a division by pi / 180
    return f"{int(x):,}" if x == int(x) else f"{x:g}"
