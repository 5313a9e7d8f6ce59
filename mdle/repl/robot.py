"""The REPL on a real robot: the session of :mod:`mdle.repl.session` driving a hardware backend.

A :class:`RobotSession` runs the same inputs as in simulation against a robot reached with
:func:`mdle.drivers.open_backend` (a Pioneer, or MobileSim/AMRISim). What differs:

* **Confirmation before the first motion.** The first run or ``:step`` asks
  :attr:`RobotSession.confirm` whether the robot may move (the front end puts the
  question to the user); without a way to ask and without ``armed`` (``--yes``), motion
  is refused with a message.
* **Stops.** Ctrl-C during a run stops the robot (the scheduler's stop), a paused
  ``:step`` leaves it stopped, and :meth:`RobotSession.close` (``:quit``, Ctrl-D, the end
  of piped input, a signal) stops it, waits for the wheels and closes the connection.
* **Idle.** The backend's reader thread sends a keep-alive whenever nothing else was
  sent, so the firmware's watchdog never trips while the prompt waits.
* **A lost link** ends the run it happens in; the session goes on without a robot
  (definitions can still be edited, shown and saved) and says so before each input
  until ``:quit``.
* Simulator-only commands (``:world``, ``:where``, ``:set seed``, ``:reset X Y``) refuse
  with a message; there is no ground truth, so reports show odometry only.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from mdle.atoms.registry import Registry
from mdle.core.backend import Backend
from mdle.core.errors import Diagnostic, MdleError
from mdle.core.motion_limits import KnownRobot
from mdle.core.pose import Pose
from mdle.repl.reports import RunReport, StepOutcome, _side_stats
from mdle.repl.runs import _Run
from mdle.repl.session import DEFAULT_UNTIL, ReplError, Session
from mdle.runtime import Cause, Observer

__all__ = ["HardwareBackend", "RobotSession"]


class HardwareBackend(Backend, Protocol):
    """A robot's backend as the REPL needs it: a Backend that can tell a lost link."""

    @property
    def failure(self) -> str | None:
        """Why the link was lost (None while it is up)."""
        ...

    @property
    def description(self) -> str:
        """Where the robot is (its connection)."""
        ...


class RobotSession(Session):
    """A REPL session driving a real robot.

    Parameters
    ----------
    backend : HardwareBackend
        The connected robot (owned from now on: :meth:`close` closes it).
    connect, laser : str
        The URLs it was opened with (for the trace header and messages).
    registry : Registry, optional
    rate : float
        Control rate, Hz.
    until : float or None
        Longest run, wall-clock seconds (None: no limit).
    armed : bool
        The robot may move without asking (``--yes``).
    confirm : callable, optional
        ``confirm(question) -> bool``: asks the user before the first motion.
    """

    simulated = False

    def __init__(self, backend: HardwareBackend, *, connect: str, laser: str | None = None,
                 registry: Registry | None = None, rate: float = 10.0,
                 until: float | None = DEFAULT_UNTIL, armed: bool = False,
                 confirm: Callable[[str], bool] | None = None,
                 name: str = "robot") -> None:
        self.hardware = backend
        self.connect = connect
        self.laser = laser
        self.name = name
        self.armed = armed
        self.confirm = confirm
        self._told_lost = False
        self._closed = False
        super().__init__(None, registry=registry, rate=rate, until=until, realtime=False)

        limits = backend.limits
        self.workspace.robot = KnownRobot(name, limits.max_speed, limits.max_reverse_speed,
                                          limits.max_turn_rate, "the connected robot")

    # ------------------------------------------------------------------ the robot

    def _open_world(self, spec: str | os.PathLike[str] | None,
                    pose: Pose | None = None) -> None:
        """Start with no runs: the robot is where it is (there is no world to open)."""
        if spec is not None or pose is not None:
            raise ReplError("a session on a real robot has no simulated world")
        self._stop_stepping()
        self._runs = []

    @property
    def target(self) -> Backend:
        """The robot."""
        return self.hardware

    @property
    def true_pose(self) -> Pose | None:
        """None: a real robot has no ground truth."""
        return None

    @property
    def seed(self) -> int:
        """No seed on a robot: refuse."""
        raise ReplError("a real robot has no random seed")

    @property
    def lost(self) -> str | None:
        """Why the link to the robot is gone, or None while it is up."""
        return self.hardware.failure

    def describe(self) -> str:
        """Say in one line what the session drives: the robot, its connection, its laser."""
        laser = f", laser {self.laser}" if self.laser else ", no laser"
        state = "" if self.lost is None else " (link lost)"
        return f"{self.name} on {self.hardware.description}{laser}{state}"

    def notices(self) -> list[str]:
        """Tell once that the link is gone (found by the backend while the prompt waited)."""
        why = self.lost
        if why is None or self._told_lost:
            return []
        self._told_lost = True
        return [f"lost the robot on {self.hardware.description}: {why}; the session goes "
                f"on without it (`:defs`, `:save FILE` keep your definitions; `:quit` "
                f"leaves)"]

    def close(self) -> None:
        """Stop the robot, wait for its wheels, close the connection (idempotent)."""
        if self._closed:
            return
        self._closed = True
        self._stop_stepping()
        self.hardware.close()

    # ------------------------------------------------------------------ running

    def run(self, text: str, observers: Sequence[Observer] = ()) -> RunReport:
        """Run an element on the robot (after the first-motion confirmation)."""
        self.compile(text)  # a typo is reported before any question about moving
        self._may_move()
        report = super().run(text, observers)
        if report.error is not None and self.lost is not None:
            self._told_lost = False  # say it once more, with what to do now
        return report

    def step(self, n: int) -> StepOutcome:
        """Advance the last element ``n`` ticks; between ``:step`` commands the robot waits stopped.

        The run's clock is the wall clock, so the element's timer runs on meanwhile.
        """
        if self._stepping is None and self._last is not None:
            self.compile(self._last[0])
        self._may_move()
        outcome = super().step(n)
        if self._stepping is not None:
            self.hardware.stop()
        return outcome

    def _may_move(self) -> None:
        """Refuse motion without a robot or without the user's go-ahead."""
        if self._closed:
            raise ReplError("the connection to the robot is closed")
        why = self.lost
        if why is not None:
            self._told_lost = True
            raise ReplError(Diagnostic(
                None, f"no robot: the link to {self.hardware.description} was lost ({why})",
                hint="`:save FILE` keeps your definitions; `:quit` leaves"))
        if self.armed:
            return
        question = (f"The robot on {self.hardware.description} will move. Is the space "
                    f"around it clear and the stop button at hand?")
        if self.confirm is None:
            raise ReplError(Diagnostic(None, "the robot may not move: nobody confirmed it",
                                       hint="start the session with --yes to let a script "
                                            "drive the robot"))
        if not self.confirm(question):
            raise ReplError("not confirmed: the robot did not move")
        self.armed = True

    def reset(self, pose: Pose | None = None) -> Pose:
        """Clear the path and the trace; a real robot stays where it is.

        Raises
        ------
        ReplError
            A pose was given (a command cannot put a real robot somewhere).
        """
        if pose is not None:
            raise ReplError(Diagnostic(None, ":reset X Y works in simulation only",
                                       hint="put the robot in place by hand; `:reset` "
                                            "alone clears the path and the trace"))
        self._stop_stepping()
        self._runs = []
        return self.observe().pose

    def set_world(self, spec: str | os.PathLike[str]) -> None:
        """Refuse: a real robot has no simulated world."""
        raise ReplError("a session on a real robot has no simulated world")

    def load_run(self, path: str | os.PathLike[str]) -> Any:
        """Refuse: a recorded run is replayed into a simulated world."""
        raise ReplError("a recorded run can be loaded in simulation only")

    def set_seed(self, seed: int) -> None:
        """Refuse: a real robot has no seed."""
        raise ReplError("a real robot has no random seed")

    def _report(self, record: _Run, interrupted: bool, error: MdleError | None) -> RunReport:
        result = record.result
        assert result is not None
        pose = Pose(0.0, 0.0, 0.0)
        if record.samples:
            last = record.samples[-1]
            pose = Pose(last.x, last.y, last.theta)
        if self.lost is None:
            try:
                pose = self.hardware.observe().pose
            except MdleError:  # the link went while reporting: the last sample will do
                pass
        limit = None
        if (not interrupted and result.cause is Cause.STOPPED and self.until is not None
                and result.duration >= self.until - 1e-6):
            limit = self.until
        return RunReport(record.label, result, record.t0, pose, None, interrupted, limit,
                         None, error, None, _side_stats(record.samples))

    # ------------------------------------------------------------------ looking around

    def path_xy(self) -> Any:
        """Return the odometry positions since the last reset, shape (N, 2), metres."""
        import numpy as np

        pts = [(s.x, s.y) for s in self.samples]
        return np.asarray(pts, dtype=float).reshape(-1, 2)

    def trace_header(self) -> dict[str, Any]:
        """Return the header of the session trace: the robot, its connection, what ran."""
        return {"program": {"file": "<repl>", "element": self._runs[-1].label if self._runs
                            else None, "runs": [r.text for r in self._runs]},
                "backend": "pioneer", "connect": self.connect, "laser": self.laser,
                "rate": self.rate, "repl": True}

    def plot(self, out: str | os.PathLike[str]) -> str:
        """Draw the odometry path since the last reset (no world: there is none)."""
        from mdle.view.plot import plot_trace

        with tempfile.TemporaryDirectory(prefix="mdle-repl-") as tmp:
            trace = os.path.join(tmp, "session.jsonl")
            self.write_trace(trace)
            return plot_trace(trace, out)
