"""A scripted backend for tests: replays given observations and records the commands.

It behaves like the backends the runtime meets in the field, on demand: data that
arrives at its own rate (a scan every ``scan_period`` s), a scan older than the tick
(``scan_delay``), a command watchdog that stops the robot when no command came for
``watchdog`` s, a robot that refuses to move (``motors_enabled=False``), late ticks
(``lateness``) and a connection that drops (``drop_at``: every call from then on raises
:class:`~mdle.core.errors.BackendError`). Between those, it is an ideal unicycle: the held
command is integrated exactly (arcs) over each ``advance``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any, Union

from mdle.core.backend import STOP, ClockMode, Command, Observation, RobotLimits, Scan, TickClock
from mdle.core.errors import BackendError
from mdle.core.pose import Pose

__all__ = ["ScriptedBackend", "Script", "IDEAL_LIMITS"]

#: Limits of an ideal robot: nothing is clamped.
IDEAL_LIMITS = RobotLimits(max_speed=math.inf, max_reverse_speed=math.inf,
                           max_turn_rate=math.inf)

_ORIGIN = Pose()

#: Per-tick overrides of Observation fields: a sequence indexed by tick (ticks past its end
#: get no override), or a function ``(time, tick) -> mapping``. Keys are Observation field
#: names (``stalled``, ``truth``, ``pose``, ``scan``, ...).
Script = Union[Sequence[Mapping[str, Any]], Callable[[float, int], Mapping[str, Any]]]


class ScriptedBackend:
    """A backend whose observations are scripted and whose commands are recorded.

    Parameters
    ----------
    script : Script
        Overrides applied to each observation (see :data:`Script`).
    start_time : float
        Clock value at the first observation, s.
    pose : Pose
        Starting odometry pose.
    limits : RobotLimits
        Reported limits; commands are clamped to them.
    scan : callable or None
        ``scan(stamp) -> Scan``: makes the scan taken at time ``stamp``.
    scan_period : float or None
        A new scan arrives every ``scan_period`` s (None: one per tick).
    scan_delay : float
        Age of each scan when it arrives, s (its stamp is that much older).
    watchdog : float or None
        Stop the robot when no command came for this many seconds.
    motors_enabled : bool
        False emulates a robot that refuses to move: commands are recorded, nothing moves.
    drop_at : float or None
        From this time on, ``observe``, ``command`` and ``advance`` raise BackendError.
    lateness : callable or None
        ``lateness(tick) -> seconds`` returned by ``advance``.
    clock : ClockMode
        Reported clock mode.

    Attributes
    ----------
    commands : list of (float, Command)
        Every command received, with the time it was sent (clamped value).
    stops : list of float
        Times at which :meth:`stop` was called.
    observations : list of Observation
        Everything :meth:`observe` returned.
    """

    def __init__(self, script: Script = (), *, start_time: float = 0.0, pose: Pose = _ORIGIN,
                 limits: RobotLimits = IDEAL_LIMITS,
                 scan: Callable[[float], Scan] | None = None,
                 scan_period: float | None = None, scan_delay: float = 0.0,
                 watchdog: float | None = None, motors_enabled: bool = True,
                 drop_at: float | None = None,
                 lateness: Callable[[int], float] | None = None,
                 clock: ClockMode = ClockMode.SIMULATED) -> None:
        self.clock = clock
        self.limits = limits
        self.time = float(start_time)
        self._clock = TickClock(base=self.time)
        self.pose = pose
        self.motors_enabled = motors_enabled
        self._script = script
        self._scan_fn = scan
        self._scan_period = scan_period
        self._scan_delay = scan_delay
        self._scan: Scan | None = None
        self._next_scan = self.time
        self._watchdog = watchdog
        self._drop_at = drop_at
        self._lateness = lateness
        self._held = STOP
        self._last_command_time = self.time
        self._ticks = 0
        self.commands: list[tuple[float, Command]] = []
        self.stops: list[float] = []
        self.observations: list[Observation] = []
        self.closed = False

    # ------------------------------------------------------------------ Backend protocol

    def observe(self) -> Observation:
        """Return the scripted observation for the current tick."""
        self._check_link("observe")
        if self._scan_fn is not None and self.time >= self._next_scan - 1e-12:
            self._scan = self._scan_fn(self.time - self._scan_delay)
            period = self._scan_period
            self._next_scan = self.time + period if period else self.time
        moving = self.motors_enabled
        obs = Observation(time=self.time, pose=self.pose,
                          v=self._held.v if moving else 0.0,
                          omega=self._held.omega if moving else 0.0,
                          scan=self._scan, motors_enabled=self.motors_enabled)
        override = self._override()
        if override:
            obs = replace(obs, **override)
        self.observations.append(obs)
        return obs

    def command(self, cmd: Command) -> None:
        """Record and hold ``cmd`` (clamped to the limits)."""
        self._check_link("command")
        lim = self.limits
        cmd = Command(min(max(cmd.v, -lim.max_reverse_speed), lim.max_speed),
                      min(max(cmd.omega, -lim.max_turn_rate), lim.max_turn_rate))
        self.commands.append((self.time, cmd))
        self._held = cmd
        self._last_command_time = self.time

    def advance(self, dt: float) -> float:
        """Integrate the held command over ``dt`` seconds; return the scripted lateness."""
        self._check_link("advance")
        if self._watchdog is not None and self.time + dt - self._last_command_time > \
                self._watchdog:
            self._held = STOP
        if self.motors_enabled:
            self.pose = _integrate(self.pose, self._held, dt)
        self.time = self._clock.advance(dt)
        tick = self._ticks
        self._ticks += 1
        return self._lateness(tick) if self._lateness is not None else 0.0

    def stop(self) -> None:
        """Hold zero velocity; never raises (a dropped link just records the attempt)."""
        self.stops.append(self.time)
        self._held = STOP

    def close(self) -> None:
        """Stop and mark closed."""
        self.stop()
        self.closed = True

    # ------------------------------------------------------------------ helpers for tests

    @property
    def held(self) -> Command:
        """The command the robot is holding now."""
        return self._held

    def commanded(self) -> list[Command]:
        """Return the commands received, in order, without their times."""
        return [c for _, c in self.commands]

    def _override(self) -> Mapping[str, Any]:
        script = self._script
        tick = len(self.observations)
        if callable(script):
            return script(self.time, tick)
        return script[tick] if tick < len(script) else {}

    def _check_link(self, what: str) -> None:
        if self._drop_at is not None and self.time >= self._drop_at - 1e-12:
            raise BackendError(f"connection to the robot lost ({what} at t = {self.time:.2f} s)")


def _integrate(pose: Pose, cmd: Command, dt: float) -> Pose:
    """Exact unicycle motion over ``dt`` under a constant (v, omega): a line or an arc."""
    v, w, th = cmd.v, cmd.omega, pose.theta
    if abs(w) < 1e-12:
        return Pose(pose.x + v * dt * math.cos(th), pose.y + v * dt * math.sin(th), th)
    th2 = th + w * dt
    r = v / w
    return Pose(pose.x + r * (math.sin(th2) - math.sin(th)),
                pose.y - r * (math.cos(th2) - math.cos(th)),
                math.atan2(math.sin(th2), math.cos(th2)))
