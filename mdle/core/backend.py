"""The seam between the runtime and a robot: Observation, Command, Backend.

A backend is anything that can be observed and commanded: the embedded simulator
(:mod:`sim`), a hardware driver (:mod:`mdle.drivers`), or a scripted replay in tests.
The runtime knows nothing else about it. Everything here is SI: metres, seconds,
radians, counter-clockwise positive, x forward and y left in the robot frame (REP-103).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from mdle.core.messages import Inbox
from mdle.core.pose import Pose

if TYPE_CHECKING:  # numpy is only needed by those who build scans
    import numpy as np

__all__ = [
    "Scan",
    "Observation",
    "LazyTruth",
    "clearance_floor",
    "observation",
    "plain_scan",
    "Command",
    "STOP",
    "RobotLimits",
    "ClockMode",
    "TickClock",
    "Backend",
]


@dataclass(frozen=True, eq=False)
class Scan:
    """One ladar scan in the robot frame.

    Attributes
    ----------
    ranges : (N,) float array, metres
        Range of each beam; beams with no return hold the sensor's ``max_range``.
    bearings : (N,) float array, radians
        Bearing of each beam from the robot's heading, increasing counter-clockwise;
        index 0 is the robot's right (-pi/2 on an LMS-200), as the sensor delivers it.
    valid : (N,) bool array
        True where the beam saw a surface within range.
    stamp : float, seconds
        When the scan was taken, on the backend's clock.
    max_range : float, metres
        The sensor's maximum range.
    tangents, curvatures : (N,) float arrays or None
        Only from an *ideal* (oracle) ladar in simulation: the exact boundary tangent
        direction at each hit, in the robot frame (radians, the boundary oriented with
        the obstacle on its right, i.e. clockwise around an obstacle), and the signed
        curvature there (1/m, negative on convex obstacles, control-law.md's
        convention); NaN where the beam hit nothing. Real sensors leave them None and
        the estimators in :mod:`atoms` compute both from the ranges.

    The arrays must not be written to: a scan is shared by everything that reads it
    during a tick.
    """

    ranges: "np.ndarray"
    bearings: "np.ndarray"
    valid: "np.ndarray"
    stamp: float
    max_range: float
    tangents: "np.ndarray | None" = None
    curvatures: "np.ndarray | None" = None


@dataclass(frozen=True)
class Observation:
    """What the robot knows at one tick. Immutable.

    ``pose`` is odometry (it drifts on a real robot); ``v`` and ``omega`` the measured
    speed (m/s) and turn rate (rad/s); ``scan`` the newest scan, which may be older than
    ``time`` (compare ``scan.stamp``), or None when the robot has no ladar or none has
    arrived yet. ``truth`` carries simulator ground truth (``clearance``, ``collided``,
    true pose) for traces and tests; control laws must not read it. ``inbox`` holds the
    messages a team member's radio has received (None for a robot alone).
    """

    time: float
    pose: Pose
    v: float = 0.0
    omega: float = 0.0
    scan: Scan | None = None
    stalled: bool = False
    motors_enabled: bool = True
    battery: float | None = None
    truth: Mapping[str, Any] = field(default_factory=dict)
    inbox: Inbox | None = None


class LazyTruth(Mapping[str, Any]):
    """Ground truth whose ``clearance`` is measured only when someone reads it.

    A simulator knows a lower bound of the clearance for free at every tick (where it was
    last measured, less how far the robot can have moved since) and the exact value for a
    distance query; most ticks nobody needs the exact value (the runtime keeps only the
    smallest clearance of a run, which a bound above it cannot change). ``fields`` are the
    other entries; ``measure`` returns the exact clearance, called at most once;
    :attr:`clearance_floor` is the bound (see :func:`clearance_floor`). Reading it as a
    mapping (``[]``, ``get``, iteration, ``dict(...)``, equality) gives what a dict holding
    the exact value would; it pickles as that dict.
    """

    __slots__ = ("_fields", "_measure", "clearance_floor")

    def __init__(self, fields: dict[str, Any], measure: Callable[[], float],
                 clearance_floor: float) -> None:
        self._fields = fields
        self._measure: Callable[[], float] | None = measure
        #: A lower bound of ``self["clearance"]``, known without measuring.
        self.clearance_floor = clearance_floor

    def _measured(self) -> dict[str, Any]:
        if self._measure is not None:
            self._fields["clearance"] = self._measure()
            self._measure = None
        return self._fields

    def __getitem__(self, key: str) -> Any:
        if key == "clearance":
            return self._measured()[key]
        return self._fields[key]

    def get(self, key: str, default: Any = None) -> Any:
        """Return ``self[key]``, or ``default`` when there is no such entry."""
        if key == "clearance":
            return self._measured()[key]
        return self._fields.get(key, default)

    def __contains__(self, key: object) -> bool:
        return key == "clearance" or key in self._fields

    def __iter__(self) -> Iterator[str]:
        return iter(self._measured())

    def __len__(self) -> int:
        return len(self._fields) + (self._measure is not None)

    def __repr__(self) -> str:
        return repr(self._measured())

    def __reduce__(self) -> tuple[Any, ...]:
        return dict, (dict(self._measured()),)


def clearance_floor(truth: Mapping[str, Any]) -> float:
    """Return a lower bound of ``truth["clearance"]`` known without measuring it.

    :attr:`LazyTruth.clearance_floor` of a :class:`LazyTruth`, the exact value of any other
    mapping; ``-inf`` when there is no clearance.
    """
    if isinstance(truth, LazyTruth):
        return truth.clearance_floor
    value = truth.get("clearance")
    return -math.inf if value is None else float(value)


def observation(time: float, pose: Pose, v: float, omega: float, scan: Scan | None,
                stalled: bool, truth: Mapping[str, Any], inbox: Inbox | None = None
                ) -> Observation:
    """Return ``Observation(time, pose, v, omega, scan, stalled, truth=truth, inbox=inbox)``.

    A backend's observation at every tick: motors enabled, no battery reading.
    """
    return Observation(time, pose, v, omega, scan, stalled, truth=truth, inbox=inbox)


def plain_scan(ranges: np.ndarray, bearings: np.ndarray, valid: np.ndarray, stamp: float,
               max_range: float) -> Scan:
    """Return ``Scan(ranges, bearings, valid, stamp, max_range)``: no oracle data.

    A simulated ladar's or a driver's scan at every tick.
    """
    return Scan(ranges, bearings, valid, stamp, max_range)


@dataclass(frozen=True)
class Command:
    """A velocity command: forward speed ``v`` (m/s), turn rate ``omega`` (rad/s, CCW +)."""

    v: float = 0.0
    omega: float = 0.0


STOP = Command(0.0, 0.0)


@dataclass(frozen=True)
class RobotLimits:
    """What a robot can do; backends clamp commands to it, control laws may read it.

    Accelerations of ``inf`` mean an ideal robot that reaches any command at once.
    """

    max_speed: float
    max_reverse_speed: float
    max_turn_rate: float
    max_accel: float = float("inf")
    max_decel: float = float("inf")
    max_turn_accel: float = float("inf")
    radius: float = 0.0
    """Radius of the disc that bounds the robot's body, metres (0 for a point robot)."""
    command_latency: float = 0.0
    """Seconds from a command leaving the controller until the wheels start to follow it
    (transport, firmware cycle, status-packet delay; the ramp is not included). 0: ideal."""
    scan_latency: float = 0.0
    """Typical age of a scan when a tick reads it, seconds (0: the scan is taken at the tick)."""


class ClockMode(enum.Enum):
    """How a backend's time relates to the wall clock."""

    SIMULATED = "simulated"
    """Time advances only when the runtime calls :meth:`Backend.advance`; runs go as fast as
    the CPU allows (or are paced to the wall clock by the runtime on request)."""
    WALL = "wall"
    """Time is the wall clock; data arrives at its own rate and the runtime paces ticks."""


@dataclass
class TickClock:
    """A simulated clock counted in whole ticks: the time is ``base + ticks * step``.

    Adding ``dt`` to a float at every tick drifts (36 000 additions of 0.1 give
    3600.0999999978), and a timer compared with such a sum ends a tick late. Counting
    ticks keeps tick k at ``k * dt`` to the last bit, at any length. A change of ``dt``
    starts a new count from the time reached.
    """

    base: float = 0.0
    step: float = 0.0
    ticks: int = 0

    @property
    def now(self) -> float:
        """The current time, s."""
        return self.base + self.ticks * self.step

    def advance(self, dt: float) -> float:
        """Move on by one tick of ``dt`` seconds; return the new time."""
        if dt != self.step:
            self.base, self.step, self.ticks = self.now, dt, 0
        self.ticks += 1
        return self.now


@runtime_checkable
class Backend(Protocol):
    """A robot the runtime can drive: simulated or real.

    The runtime calls, each tick: :meth:`observe`, then :meth:`command`, then
    :meth:`advance` with the tick length. A simulated backend integrates its physics
    in ``advance``; a hardware backend waits there until the tick's wall-clock deadline
    (never longer) and returns the lateness. :meth:`stop` and :meth:`close` must be safe
    to call at any time, more than once, and from a ``finally`` block.

    A backend may also have a ``laser_mount`` attribute: the ladar's pose in the robot
    frame (x, y, theta: m, m, rad); recorders use it for the ``base_link -> laser``
    transform and read (0, 0, 0) when it is absent.
    """

    clock: ClockMode
    limits: RobotLimits

    def observe(self) -> Observation:
        """Return the newest observation; raises BackendError if the robot is lost."""
        ...

    def command(self, cmd: Command) -> None:
        """Set the velocity to hold until the next command (clamped to ``limits``)."""
        ...

    def advance(self, dt: float) -> float:
        """Let ``dt`` seconds pass; returns the tick's lateness in seconds (0 in simulation)."""
        ...

    def stop(self) -> None:
        """Command zero velocity now."""
        ...

    def close(self) -> None:
        """Stop the robot and release the connection."""
        ...
