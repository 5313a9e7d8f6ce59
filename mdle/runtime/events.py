"""What a run produces (events, terminations, per-tick samples, the result) and who hears it.

These are plain frozen records. The scheduler makes them and hands them to observers
(the trace writer, the live view) through the :class:`Observer` hooks declared here, so
the scheduler and the observers both depend on this module and not on each other.
Nothing here knows about JSON, rich or matplotlib. Times are seconds on the backend's
clock (the observation time), poses are odometry.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, NamedTuple, Protocol, runtime_checkable

from mdle.core.backend import Scan
from mdle.core.pose import Pose

__all__ = ["Cause", "EventKind", "Event", "Termination", "Collision", "Sample", "RunResult",
           "ended_how", "Observer"]

_NO_DIAG: Mapping[str, float] = MappingProxyType({})


class Cause(enum.Enum):
    """Why an element ended."""

    INTERRUPT = "interrupt"
    """Its own interrupt xi was true at a tick (possibly the tick it started: zero time)."""
    TIMER = "timer"
    """Its own timer T (beta-scaled, measured from its start) elapsed. When the timer and
    the interrupt of one element both hold at the same tick, the timer is reported."""
    COMPLETED = "completed"
    """A string ended normally: its last element ended (never an atom's cause)."""
    ENDED_BY_PARENT = "ended-by-parent"
    """An enclosing element ended (interrupt, timer or abort) while this one was running."""
    STOPPED = "stopped"
    """The run was stopped from outside: Ctrl-C, ``--until``, :meth:`Scheduler.stop`."""
    ERROR = "error"
    """The run was aborted by an error: a failing control law or interrupt, a backend
    fault (dropped connection), or the robot stalled or refusing to move for too long."""


#: How an element ended, as words after its name ("main ran to its end at 60.0 s").
_HOW = {
    Cause.INTERRUPT: "ended by interrupt",
    Cause.TIMER: "ended by timer",
    Cause.COMPLETED: "ran to its end",
    Cause.ENDED_BY_PARENT: "ended with its parent",
    Cause.STOPPED: "was stopped from outside",
    Cause.ERROR: "was aborted by an error",
}


def ended_how(cause: Cause) -> str:
    """Say how an element ended, to follow its name.

    >>> ended_how(Cause.COMPLETED), ended_how(Cause.STOPPED)
    ('ran to its end', 'was stopped from outside')
    """
    return _HOW[cause]


class EventKind(enum.Enum):
    """Whether an event is an element starting or ending."""

    START = "start"
    """The element started; its local clock is 0 at :attr:`Event.time`."""
    END = "end"
    """The element ended; :attr:`Event.cause` says why."""


@dataclass(frozen=True)
class Event:
    """An element started or ended (language.md rule 8).

    ``path`` joins the labels from the entry down (``main/patrol/cruise``), ``level`` is
    its depth (0 for the element the run started with), ``element`` its kind (``atom``,
    ``plan``, ``behavior``, ``group``); ``cause`` is None for a start. ``pose`` is the
    odometry pose at that tick.
    """

    time: float
    kind: EventKind
    path: str
    level: int
    element: str
    pose: Pose
    cause: Cause | None = None
    #: For an end by interrupt: which of its conditions held (``stalled``, or
    #: ``at_goal and stalled`` when both did); None otherwise
    fired: str | None = None

    @property
    def label(self) -> str:
        """The last label of the path (the element's own name)."""
        return self.path.rpartition("/")[2]


@dataclass(frozen=True)
class Termination:
    """How one element ended: which one (``path``, ``level``), ``cause`` and ``time`` (s).

    ``fired`` says, for an end by interrupt, which of the interrupt's conditions held
    (the parts of a top-level ``or``; the whole interrupt when it has none).
    """

    path: str
    level: int
    cause: Cause
    time: float
    fired: str | None = None


@dataclass(frozen=True)
class Collision:
    """The robot's body touched an obstacle (simulator ground truth).

    ``obstacle`` is its name in the world (else its kind), ``kind`` its shape
    (``rectangle``, ``circle``, ``wall``...), ``index`` its place in the world's list (-1
    unknown); ``time`` (s, backend clock), ``x``, ``y`` the robot's true position (m, world
    frame); ``path`` the element that was running.
    """

    time: float
    x: float
    y: float
    obstacle: str
    kind: str
    index: int
    path: str

    def describe(self, t0: float = 0.0) -> str:
        """Return where, when and what was hit, in words (``hit `box` (rectangle) at ...``)."""
        what = f"`{self.obstacle}`" if self.obstacle else "an obstacle"
        kind = f" ({self.kind})" if self.kind and self.kind != self.obstacle else ""
        where = f", while `{self.path}` ran" if self.path else ""
        return (f"hit {what}{kind} at x {self.x:.2f} m, y {self.y:.2f} m, "
                f"t = {self.time - t0:.1f} s{where}")


class Sample(NamedTuple):
    """One tick as the robot saw it, after the control was computed and sent.

    ``x, y, theta`` odometry (m, rad), ``v, omega`` measured velocities (m/s, rad/s),
    ``cmd_v, cmd_omega`` the command sent (after alpha scaling; zero when no atom runs),
    ``path`` the active path ('' once the program has ended), ``lateness`` how late the
    tick finished (s; 0 in simulation), ``scan_age`` how old the newest scan was (s, None
    without a scan), ``stalled`` the robot's flag. ``diag`` holds the control law's
    diagnostics (front and side range, tangent, curvature: whatever it put in
    ``ctx.cache["trace"]``). ``clearance``, ``collided`` and the true pose
    ``true_x, true_y, true_theta`` are simulator truth, None when unknown. ``scan`` is
    the newest scan the tick saw (the same object from tick to tick until a new one
    arrives; None without a ladar), for recorders.

    A named tuple rather than a frozen dataclass: one is made every tick, and a frozen
    dataclass's ``__init__`` costs five times as much.
    """

    time: float
    x: float
    y: float
    theta: float
    v: float
    omega: float
    cmd_v: float
    cmd_omega: float
    path: str
    lateness: float = 0.0
    scan_age: float | None = None
    stalled: bool = False
    diag: Mapping[str, float] = _NO_DIAG
    clearance: float | None = None
    collided: bool | None = None
    true_x: float | None = None
    true_y: float | None = None
    true_theta: float | None = None
    scan: Scan | None = None
    contact: Collision | None = None


@dataclass(frozen=True)
class RunResult:
    """How a run ended.

    ``termination`` is the record of the element the run started with; ``terminations``
    holds one record per element that ran, in the order they ended. ``distance`` is the
    odometry path length (m), ``duration`` the time from the first tick to the end (s),
    ``min_clearance`` the smallest true clearance seen (m, None without ground truth),
    ``collided`` whether the simulator reported a collision, ``fault`` the message of the
    error or fault that aborted the run (None otherwise), ``max_lateness`` the worst tick
    lateness (s), ``reason`` why a run that was stopped from outside (cause ``stopped``)
    was stopped: the signal (``SIGTERM``), ``standard output closed``, the time limit.
    """

    termination: Termination
    terminations: tuple[Termination, ...]
    events: tuple[Event, ...]
    ticks: int
    duration: float
    distance: float
    min_clearance: float | None = None
    collided: bool = False
    fault: str | None = None
    max_lateness: float = 0.0
    collision: Collision | None = None
    reason: str | None = None

    @property
    def cause(self) -> Cause:
        """Why the run's element ended."""
        return self.termination.cause

    @property
    def ok(self) -> bool:
        """True when the program ended by itself and the robot did not collide.

        Ending by itself means completion, or its own interrupt or timer.
        """
        return (self.termination.cause in (Cause.COMPLETED, Cause.INTERRUPT, Cause.TIMER)
                and not self.collided and self.fault is None)


@runtime_checkable
class Observer(Protocol):
    """Anything with the four observer hooks.

    The scheduler calls them in this order: ``on_start`` once before the first tick,
    ``on_event`` for every element start and end, ``on_tick`` once per tick with its
    :class:`Sample`, ``on_end`` once with the :class:`RunResult` (also after an error or
    Ctrl-C). Hooks must be quick: they run on the control loop.
    """

    # The running mdle.runtime.Scheduler: typed Any so that this module, which the
    # scheduler imports, does not import it back; an observer types it as it needs.
    def on_start(self, scheduler: Any) -> None:
        """Handle the start of the run, just before its first tick."""

    def on_event(self, event: Event) -> None:
        """Handle an element starting or ending."""

    def on_tick(self, sample: Sample) -> None:
        """Handle a completed tick (its command has been sent)."""

    def on_end(self, result: RunResult) -> None:
        """Handle the end of the run (whatever the cause), after the robot was stopped."""
