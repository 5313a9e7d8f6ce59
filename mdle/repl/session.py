"""The REPL's state and what it can do, with no terminal in sight.

Over 500 lines: one class, whose world, definitions, running, stepping, loading and trace
share one state (the backend, the runs since the reset, the element being stepped); its
records are in reports.py and its run recorder in runs.py.

A :class:`Session` holds the definitions typed so far (a :class:`~mdle.lang.Workspace`),
a simulated robot in a world (a :class:`sim.SimBackend` that is never reset between runs, so
each run starts where the last one left the robot), the path and the per-tick samples since
the last reset (the session trace), and the element last run (for ``:step``). Its methods
return plain records (:mod:`mdle.repl.reports`; each run is recorded as in
:mod:`mdle.repl.runs`); :mod:`mdle.repl.commands` turns them into text.

>>> s = Session("ellipse")
>>> _ = s.define("atom creep = (go(0.5 m/s), never, 2 s)")
>>> report = s.run("creep")
>>> report.decisive.cause.value, round(report.pose.x, 2), round(report.result.distance, 2)
('timer', 1.0, 1.0)
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from mdle.atoms.registry import Registry
from mdle.console.signals import ends_session
from mdle.core.backend import Backend, Observation, RobotLimits
from mdle.core.errors import Diagnostic, MdleError
from mdle.core.motion_limits import KnownRobot
from mdle.core.pose import Pose
from mdle.lang import DefKind, Element, Workspace, format_statement
from mdle.repl.reports import (
    LoadedRun,
    RunReport,
    StepOutcome,
    StepRow,
    _closest,
    _row,
    _side_stats,
)
from mdle.repl.runs import _Recorded, _Run, _write_runs
from mdle.runtime import (
    Cause,
    Observer,
    Sample,
    Scheduler,
)

if TYPE_CHECKING:
    import numpy as np

    from mdle.sim import SimBackend, World

__all__ = ["DEFAULT_UNTIL", "ReplError", "Session"]

#: Longest a single run may go on, in simulated seconds, before the REPL stops it: an
#: element with ``never`` and ``inf`` would otherwise never give the prompt back when no
#: one is there to press Ctrl-C (a piped session). ``:set until`` changes it.
DEFAULT_UNTIL = 600.0


class ReplError(MdleError):
    """A REPL command cannot be done (nothing to step, nothing to save, a bad argument)."""



class Session:
    """A simulated robot, the definitions typed so far and the runs since the last reset.

    Parameters
    ----------
    world : str or path-like, optional
        A reference world name or a YAML file (default: ``sim.DEFAULT_WORLD``).
    seed : int, optional
        Seed of the simulation (default: the world's).
    registry : Registry, optional
        Control laws and sensor functions (default: ``atoms.default_registry()``).
    rate : float
        Control rate, Hz.
    until : float or None
        Longest run, simulated seconds (None: no limit); see :data:`DEFAULT_UNTIL`.
    robot, sensing : str, optional
        Robot profile and ladar mode, as for :class:`sim.SimBackend`.
    realtime : bool
        Pace runs to the wall clock (default: as fast as the simulator goes).

    Raises
    ------
    WorldError
        The world cannot be loaded.

    Notes
    -----
    :class:`mdle.repl.robot.RobotSession` is the same session on a real robot; the
    methods that only make sense in simulation (worlds, seeds, putting the robot
    somewhere) refuse there with a message, and :attr:`simulated` tells them apart.
    """

    #: True for the simulator; a session on a real robot says False.
    simulated: bool = True

    def __init__(self, world: str | os.PathLike[str] | None = None, *, seed: int | None = None,
                 registry: Registry | None = None, rate: float = 10.0,
                 until: float | None = DEFAULT_UNTIL, robot: str | None = None,
                 sensing: str = "scan", realtime: bool = False) -> None:
        if not (rate > 0 and math.isfinite(rate)):
            raise ReplError(f"the control rate must be a positive number of Hz, got {rate!r}")
        self.workspace = Workspace(registry)
        self.rate = float(rate)
        self.until = until
        #: Pace runs to the wall clock (to watch them); otherwise as fast as possible.
        self.realtime = realtime
        self._seed = seed
        self._robot = robot
        self._sensing = sensing
        self._runs: list[_Run] = []
        self._stepping: _Run | None = None
        self._last: tuple[str, Element] | None = None
        self.world: World
        self.world_spec: str
        self.backend: SimBackend
        self._open_world(world)

    # ------------------------------------------------------------------ the robot

    @property
    def target(self) -> Backend:
        """The backend runs drive (the simulator here, the robot in a RobotSession)."""
        return self.backend

    @property
    def limits(self) -> RobotLimits:
        """The robot's speed and turn limits."""
        return self.target.limits

    @property
    def true_pose(self) -> Pose | None:
        """The simulator's ground-truth pose (None where there is no ground truth)."""
        return self.backend.true_pose

    def describe(self) -> str:
        """Say in one line what the session drives: world and seed."""
        return f"world `{self.world.name}`, seed {self.seed}"

    def notices(self) -> list[str]:
        """Return news to tell the user before the next input (none in simulation)."""
        return []

    def close(self) -> None:
        """Release the robot (nothing to do for the simulator)."""

    # ------------------------------------------------------------------ the world

    def _open_world(self, spec: str | os.PathLike[str] | None,
                    pose: Pose | None = None) -> None:
        from mdle import sim

        text = sim.DEFAULT_WORLD if spec is None else os.fspath(spec)
        world = sim.load_world(text)
        kwargs: dict[str, Any] = {"seed": self._seed, "sensing": self._sensing}
        if self._robot:
            kwargs["robot"] = self._robot
        backend = sim.SimBackend(world, **kwargs)
        if pose is not None:
            backend.reset(pose)
        self._stop_stepping()
        self.world, self.backend = world, backend

        self.workspace.robot = KnownRobot.of(
            backend.profile, "--robot" if self._robot else f"the robot of world `{world.name}`")
        self.world_spec = os.path.abspath(text) if os.path.exists(text) else text
        self._runs = []

    def set_world(self, spec: str | os.PathLike[str]) -> None:
        """Load another world; the robot starts at its start pose, the path is cleared.

        Raises
        ------
        WorldError
            The world cannot be loaded (the session keeps the old one).
        """
        self._open_world(spec)

    @property
    def seed(self) -> int:
        """The seed the simulation uses now."""
        return int(self.backend.seed)

    def set_seed(self, seed: int) -> None:
        """Reseed the simulation.

        The robot stays where it is; the simulated clock, the path and the trace start
        afresh (the random streams restart from the new seed).
        """
        here = self.backend.true_pose
        old = self._seed
        self._seed = int(seed)
        try:
            self._open_world(self.world_spec, here)
        except MdleError:
            self._seed = old
            raise

    def reset(self, pose: Pose | None = None) -> Pose:
        """Put the robot at ``pose`` (default: the world's start), stopped, at time 0.

        The path and trace are cleared. Returns the pose.

        Raises
        ------
        WorldError
            The robot would overlap an obstacle there (nothing changes).
        """
        self.backend.reset(pose)
        self._stop_stepping()
        self._runs = []
        return self.backend.true_pose

    # ------------------------------------------------------------------ definitions

    def define(self, text: str) -> tuple[tuple[str, ...], tuple[str, ...], tuple[Diagnostic, ...]]:
        """Add the definitions in ``text``.

        Returns
        -------
        (added, replaced, warnings)
            Names defined for the first time, names whose definition changed (a definition
            typed again unchanged is in neither), new warnings.

        Raises
        ------
        MdleError
            The text does not parse or check; nothing changes.
        """
        before = self._forms()
        warnings = self.workspace.define(text)
        after = self._forms()
        added = tuple(n for n in after if n not in before)
        replaced = tuple(n for n in after if n in before and before[n] != after[n])
        return added, replaced, warnings

    def _forms(self) -> dict[str, str]:
        """Each definition's canonical text, to tell a changed definition from a retyped one."""
        out = {}
        for name in self.workspace.names():
            d = self.workspace.definition(name)
            if d is not None:
                out[name] = format_statement(d)
        return out

    def load(self, path: str | os.PathLike[str]) -> tuple[tuple[str, ...], tuple[Diagnostic, ...]]:
        """Add the definitions of a file (and its imports); returns (names, warnings).

        Raises
        ------
        MdleError
            The file cannot be read, parsed or checked; nothing changes.
        """
        before = self._forms()
        warnings = self.workspace.load(path)
        after = self._forms()
        return tuple(n for n in after if before.get(n) != after[n]), warnings

    def load_run(self, path: str | os.PathLike[str]) -> LoadedRun:
        """Bring a recorded run (a trace or an MCAP recording) into the session.

        The session switches to the run's world (with its seed, robot and sensing) when it
        was simulated and that world loads, and puts the robot where the run ended; the
        run becomes the path since the last reset (``:where``, ``:plot``, ``:trace``).

        Raises
        ------
        TraceError
            The file cannot be read.
        ReplError
            The recording has no ticks.
        """
        from mdle.record.load import read_trace
        from mdle.repl.recorded import recorded_run

        trace = read_trace(path)
        run = recorded_run(trace)
        if not run.samples:
            raise ReplError(f"`{os.fspath(path)}` holds no recorded ticks")
        header = trace.header
        note = None
        world = header.get("world") if isinstance(header.get("world"), dict) else None
        last = run.samples[-1]
        if world and world.get("spec"):
            pose = (Pose(last.true_x, last.true_y, last.true_theta)
                    if last.true_x is not None and last.true_y is not None
                    and last.true_theta is not None else None)
            old = (self._seed, self._robot, self._sensing)
            seed = header.get("seed")
            self._seed = seed if isinstance(seed, int) and not isinstance(seed, bool) else None
            self._robot = header.get("robot") if isinstance(header.get("robot"), str) else None
            sensing = header.get("sensing")
            self._sensing = sensing if sensing in ("scan", "exact") else "scan"
            try:
                try:
                    self._open_world(str(world["spec"]), pose)
                except MdleError:
                    if pose is None:
                        raise
                    self._open_world(str(world["spec"]))
                    note = ("the robot cannot stand where the run ended (it touches an "
                            "obstacle): it is at the world's start")
            except MdleError as exc:
                self._seed, self._robot, self._sensing = old
                note = f"the run's world does not load ({exc}); the session keeps its own"
        else:
            note = "recorded on a robot: the path is in odometry; the simulated robot stays"
        self._stop_stepping()
        record = _Run(run.label, f"<{os.path.basename(os.fspath(path))}>")
        record.samples = list(run.samples)
        record.events = list(run.events)
        record.result = run.result
        rate = header.get("rate")
        record.started = _Recorded(run.label, float(rate) if isinstance(rate, (int, float))
                                   and rate > 0 else self.rate, self.backend)
        self._runs = [record]
        return LoadedRun(run.label, run.result, len(run.samples),
                         self.world.name, trace.truncated or trace.end is None, note)

    def save_entry(self) -> str | None:
        """Return what ``:save`` writes as ``run NAME``, so that ``mdle run`` runs the file.

        The entry a ``run`` input gave (or a plan ``main``); else the definition last run
        (``creep`` after ``creep`` or ``creep(1 m/s)``), when it runs as it stands; else the
        plan defined last; else whatever runnable element was defined last. None when
        nothing runs without arguments.
        """
        program = self.workspace.program()
        if program.entry is not None:
            return program.entry
        called = re.fullmatch(r"([A-Za-z_][A-Za-z0-9_]*)\s*(?:\(.*\))?", self.last_element or "",
                              re.S)
        if called is not None and called.group(1) in program.elements:
            return called.group(1)
        defs = [d for d in reversed(self.workspace.definitions()) if d.name in program.elements]
        plans = [d for d in defs if d.kind is DefKind.PLAN]
        return (plans or defs)[0].name if defs else None

    def save_text(self) -> str:
        """Return what ``:save`` writes (and ``:defs`` shows): definitions, then ``run``."""
        return self.workspace.format(self.save_entry())

    def save(self, path: str | os.PathLike[str]) -> str:
        """Write every definition, formatted as ``mdle fmt`` does, then a ``run`` line.

        The ``run`` line names :meth:`save_entry` (none when nothing runs as it stands).
        In simulation the session's world (obstacles, start, robot, ladar, seed) is
        written beside it (:meth:`world_path`), where ``mdle run FILE`` looks for it, so
        that the file runs as it ran here. Returns the text.

        Raises
        ------
        ReplError
            Nothing is defined yet, or a file cannot be written.
        """
        text = self.save_text()
        if not text.strip():
            raise ReplError("nothing to save: no definitions yet")
        files = [(path, text)]
        if self.simulated:
            from mdle.sim.world_dump import world_to_yaml

            files.append((self.world_path(path), world_to_yaml(self.world)))
        for where, content in files:
            try:
                with open(where, "w", encoding="utf-8") as f:
                    f.write(content)
            except OSError as exc:
                raise ReplError(f"cannot write `{os.fspath(where)}`: {exc.strerror}") from None
        return text

    @staticmethod
    def world_path(path: str | os.PathLike[str]) -> str:
        """Return where :meth:`save` writes the world of a plan saved to ``path``."""
        base = os.fspath(path)
        stem = base[:-len(".mdle")] if base.endswith(".mdle") else base
        return stem + ".world.yaml"

    @property
    def sources(self) -> dict[str, str]:
        """Texts of everything defined so far by file name, to show source lines under warnings.

        (The workspace keeps them privately; read here, without changing it.)
        """
        return dict(getattr(self.workspace, "_sources", {}))

    # ------------------------------------------------------------------ running

    @property
    def last_element(self) -> str | None:
        """The text of the element last run or stepped (what ``:step`` advances)."""
        return None if self._last is None else self._last[0]

    @property
    def stepping(self) -> bool:
        """True while a stepped run is paused between ``:step`` commands."""
        return self._stepping is not None

    def compile(self, text: str) -> Element:
        """Return the element ``text`` denotes, checked against the definitions.

        Raises
        ------
        MdleError
        """
        return self.workspace.element(text.strip())

    def run(self, text: str, observers: Sequence[Observer] = ()) -> RunReport:
        """Run the element ``text`` from the robot's current state to its end.

        Ctrl-C (KeyboardInterrupt) stops the run: the robot is stopped and the report
        says so. A paused stepped run is ended first. ``observers`` also watch this run
        (a progress line, say).

        Raises
        ------
        MdleError
            The text is not an element (nothing ran).
        """
        element = self.compile(text)
        self._stop_stepping()
        self._last = (text.strip(), element)
        record, scheduler = self._start(element, text.strip(), observers)
        interrupted = False
        error: MdleError | None = None
        try:
            scheduler.start()
            while scheduler.tick():
                pass
        except KeyboardInterrupt as exc:
            interrupted = True
            if ends_session(exc):  # SIGTERM: stop the robot (below), then end the session
                scheduler.request_stop(getattr(exc, "reason", None))
                scheduler.stop()
                raise
        except MdleError as exc:  # a failing law or interrupt, a backend fault
            error = exc
        finally:
            if scheduler.result is None:  # interrupted between ticks
                scheduler.stop()
        return self._report(record, interrupted, error)

    def step(self, n: int) -> StepOutcome:
        """Advance the last element by ``n`` ticks.

        A new run of it starts from the robot's current state when none is paused.

        Raises
        ------
        ReplError
            No element has been run yet, or ``n`` is not positive.
        """
        if n < 1:
            raise ReplError(f":step needs a positive number of ticks, got {n}")
        started = False
        if self._stepping is None:
            if self._last is None:
                raise ReplError("nothing to step: run an element first (type its name or "
                                "an element such as `(go(0.3 m/s), never, 5 s)`)")
            text = self._last[0]
            element = self.compile(text)  # the definitions may have changed since
            self._last = (text, element)
            record, _ = self._start(element, text)
            self._stepping = record
            started = True
        record = self._stepping
        scheduler = record.scheduler
        assert scheduler is not None
        rows: list[StepRow] = []
        report = None
        interrupted = False
        error: MdleError | None = None
        try:
            for _ in range(n):
                scan = self.observe().scan  # what this tick will see
                running = scheduler.tick()
                rows.append(_row(scheduler.ticks, record.samples[-1], scan))
                if not running:
                    break
        except KeyboardInterrupt as exc:
            interrupted = True
            if ends_session(exc):
                scheduler.stop()
                self._stepping = None
                raise
        except MdleError as exc:
            error = exc
        if scheduler.result is None and interrupted:
            scheduler.stop()
        if scheduler.result is not None:
            self._stepping = None
            report = self._report(record, interrupted, error)
        return StepOutcome(tuple(rows), report, started, record.label, record.t0)

    def _start(self, element: Element, text: str, observers: Sequence[Observer] = ()
               ) -> tuple[_Run, Scheduler]:
        record = _Run(element.label, text)
        scheduler = Scheduler(element, self.target, self.rate, (record, *observers),
                              until=self.until, realtime=self.realtime)
        scheduler.start()
        self._runs.append(record)
        return record, scheduler

    def _stop_stepping(self) -> None:
        if self._stepping is not None and self._stepping.scheduler is not None:
            self._stepping.scheduler.stop()
        self._stepping = None

    def _report(self, record: _Run, interrupted: bool, error: MdleError | None) -> RunReport:
        result = record.result
        assert result is not None
        t0 = record.t0
        collision = next((e for e in self.backend.events if e.time >= t0 - 1e-9), None)
        limit = None
        if (not interrupted and result.cause is Cause.STOPPED and self.until is not None
                and result.duration >= self.until - 1e-6):
            limit = self.until
        obs = self.backend.observe()
        return RunReport(record.label, result, t0, obs.pose, self.backend.true_pose,
                         interrupted, limit, collision, error, _closest(record.samples, t0),
                         _side_stats(record.samples))

    # ------------------------------------------------------------------ looking around

    def observe(self) -> Observation:
        """Return what the robot senses now (pose, velocities, newest scan, truth)."""
        return self.target.observe()

    @property
    def samples(self) -> list[Sample]:
        """Every tick since the last reset, in order."""
        return [s for r in self._runs for s in r.samples]

    def path_xy(self) -> np.ndarray:
        """Return the robot's true positions since the last reset.

        Shape (N, 2), metres, starting at the pose of the reset and ending at the current
        pose.
        """
        import numpy as np

        pts = [(s.true_x, s.true_y) if s.true_x is not None else (s.x, s.y)
               for s in self.samples]
        here = self.backend.true_pose
        pts.append((here.x, here.y))
        return np.asarray(pts, dtype=float)

    # ------------------------------------------------------------------ trace and plot

    def trace_header(self) -> dict[str, Any]:
        """Return the header of the session trace: world, seed, rate and what ran."""
        return {"program": {"file": "<repl>", "element": self._runs[-1].label if self._runs
                            else None, "runs": [r.text for r in self._runs]},
                "world": {"name": self.world.name, "spec": self.world_spec},
                "seed": self.seed, "rate": self.rate, "backend": "sim", "repl": True}

    def write_trace(self, path: str | os.PathLike[str]) -> int:
        """Write the runs since the last reset as one JSON lines trace (``docs/trace.md``).

        A ``start`` record per run, their events and samples, and one ``end`` record that
        sums them up. Returns the number of samples written.

        Raises
        ------
        ReplError
            Nothing has run since the last reset, or the file cannot be written.
        """
        from mdle.record.trace import TraceWriter

        runs = [r for r in self._runs if r.scheduler is not None]
        if not any(r.samples for r in runs):
            raise ReplError("nothing to write: no element has run since the last reset")
        try:
            writer = TraceWriter(path, self.trace_header())
        except OSError as exc:
            raise ReplError(f"cannot write `{os.fspath(path)}`: {exc.strerror}") from None
        try:
            return _write_runs(writer, runs)
        finally:
            writer.close()

    def plot(self, out: str | os.PathLike[str]) -> str:
        """Draw the path since the last reset as ``mdle plot`` does; returns ``out``.

        Raises
        ------
        ReplError, PlotError
        """
        from mdle.view.plot import plot_trace

        with tempfile.TemporaryDirectory(prefix="mdle-repl-") as tmp:
            trace = os.path.join(tmp, "session.jsonl")
            self.write_trace(trace)
            return plot_trace(trace, out, world=self.world)
