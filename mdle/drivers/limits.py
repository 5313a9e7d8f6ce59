"""What the numbers in ``--connect`` and ``--laser`` URLs may be, and their checks.

Every query option that reaches a driver is a number with a unit and a range it must lie
in: a conversion factor of zero or a negative speed limit would turn a command into
nonsense on the wire (``?max_speed=-1`` once sent VEL -1000 mm/s, driving backwards for a
forward command). Values outside their range, not numbers, NaN or infinite are refused
before anything is connected, with a message naming the option, the allowed range and
what was given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from mdle.core.backend import RobotLimits
from mdle.core.errors import BackendError
from mdle.drivers.arcos import RobotParams

__all__ = [
    "LASER_MAX_RANGE",
    "ROBOT_PARAM_RANGES",
    "Range",
    "check_limits",
    "check_robot_params",
    "read_number",
]


@dataclass(frozen=True)
class Range:
    """An interval of allowed values with its unit; ``open_low`` excludes ``low``."""

    low: float
    high: float
    unit: str
    open_low: bool = True

    def __contains__(self, value: object) -> bool:
        if not isinstance(value, (int, float)) or not math.isfinite(value):
            return False
        above = value > self.low if self.open_low else value >= self.low
        return above and value <= self.high

    def describe(self) -> str:
        """Say what the range allows: ``a number of m/s in (0, 2]``."""
        left = "(" if self.open_low else "["
        unit = f" of {self.unit}" if self.unit else ""
        return f"a number{unit} in {left}{self.low:g}, {self.high:g}]"


#: Ranges of the :class:`~mdle.drivers.arcos.RobotParams` fields a URL may override. The
#: limits keep commands inside what a Pioneer's firmware takes (VEL and RVEL are 16-bit
#: integers; the fastest Pioneers do about 2 m/s and 300 deg/s).
ROBOT_PARAM_RANGES: dict[str, Range] = {
    "dist_conv": Range(0.0, 10.0, "mm per position unit"),
    "angle_conv": Range(0.0, 0.1, "rad per heading unit"),
    "vel_conv": Range(0.0, 10.0, "mm/s per velocity unit"),
    "diff_conv": Range(0.0, 1.0, "rad/s per mm/s"),
    "range_conv": Range(0.0, 10.0, "mm per range unit"),
    "max_speed": Range(0.0, 2.0, "m/s"),
    "max_reverse_speed": Range(0.0, 2.0, "m/s", open_low=False),
    "max_turn_rate": Range(0.0, 2 * math.pi, "rad/s"),
    "max_accel": Range(0.0, 5.0, "m/s^2"),
    "max_decel": Range(0.0, 5.0, "m/s^2"),
    "max_turn_accel": Range(0.0, 4 * math.pi, "rad/s^2"),
    "radius": Range(0.0, 2.0, "m"),
}
assert set(ROBOT_PARAM_RANGES) == {f.name for f in fields(RobotParams)}, \
    "every robot parameter needs a range"

#: The simulator laser's no-return value travels as a 16-bit count of millimetres.
LASER_MAX_RANGE = Range(0.1, 65.535, "m", open_low=False)


def read_number(flag: str, url: str, key: str, raw: str, allowed: Range) -> float:
    """Return option ``key`` of ``url`` as a number inside ``allowed``.

    Raises
    ------
    BackendError
        Not a number, NaN, infinite or out of range: the message names the flag, the
        URL, the option, the allowed range and the value given.
    """
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if value not in allowed:
        raise BackendError(f"{flag} `{url}`: `{key}` must be {allowed.describe()}, "
                           f"got `{raw}`")
    return value


def check_robot_params(params: RobotParams) -> str | None:
    """Return what is wrong with a model's parameters (every field in its range), or None."""
    for f in fields(params):
        value = getattr(params, f.name)
        allowed = ROBOT_PARAM_RANGES[f.name]
        if value not in allowed:
            return f"robot parameter `{f.name}` must be {allowed.describe()}, got {value!r}"
    return None


def check_limits(limits: RobotLimits) -> str | None:
    """Return what is wrong with command limits (each finite, in its range), or None."""
    for name in ("max_speed", "max_reverse_speed", "max_turn_rate"):
        value = getattr(limits, name)
        allowed = ROBOT_PARAM_RANGES[name]
        if value not in allowed:
            return f"the limit `{name}` must be {allowed.describe()}, got {value!r}"
    return None
