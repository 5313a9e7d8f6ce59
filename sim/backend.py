"""SimBackend: the embedded simulator behind :class:`mdle.core.backend.Backend`.

Over 500 lines: one class, the simulated robot's observe/command/advance cycle, whose
clock, kinematics, contact, scans and odometry share one state.

Time advances only in :meth:`SimBackend.advance`, which integrates the held command
exactly (arcs, with the profile's acceleration limits), sweeps the body so it never
passes through an obstacle (on contact it stops and raises ``stalled``, as a Pioneer
does, and records a :class:`SimEvent`), takes ladar scans at the ladar's own instants
(``k / rate``), and updates odometry (with the profile's seeded drift, if any).

Observations report odometry as a robot does (REP-105 ``odom`` frame): the pose relative
to where the robot was at :meth:`SimBackend.reset` (the run's start), which is
(0, 0, 0). World coordinates are ground truth: ``Observation.truth`` and
:attr:`SimBackend.true_pose`. The truth's exact clearance is a distance query over every
segment, so a step that touched nothing keeps a lower bound instead, and the observation's
truth (a :class:`mdle.core.backend.LazyTruth`) measures it only when read.

>>> import math
>>> from mdle.sim.world import World
>>> from mdle.sim.shapes import Rectangle
>>> from mdle.core.backend import Command
>>> from mdle.core.pose import Pose
>>> world = World("wall", obstacles=(Rectangle((3.0, 0.0), (0.1, 4.0)),))
>>> sim = SimBackend(world, robot="ideal", ladar="lms200-ideal")
>>> sim.command(Command(1.0, 0.0))
>>> for _ in range(40):
...     _ = sim.advance(0.1)
>>> obs = sim.observe()
>>> obs.stalled, obs.truth["collided"], round(obs.pose.x, 3)
(True, True, 2.95)
>>> [e.kind for e in sim.events]
['collision']
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from functools import partial
from typing import Any, NamedTuple

import numpy as np

from mdle.core.backend import (
    STOP,
    ClockMode,
    Command,
    LazyTruth,
    Observation,
    RobotLimits,
    Scan,
    TickClock,
    observation,
)
from mdle.core.errors import BackendError, WorldError
from mdle.core.messages import Inbox
from mdle.core.pose import Pose
from mdle.sim.collision import CONTACT, Clearance, Collider
from mdle.sim.ladar import Ladar, LadarProfile, ladar_profile
from mdle.sim.profiles import robot_profile
from mdle.sim.robot import (
    Phase,
    RobotProfile,
    RunClock,
    integrate,
    plan_phases,
    ramp_step,
)
from mdle.sim.world import World

__all__ = ["SENSING_MODES", "SimBackend", "SimEvent"]

SENSING_MODES = ("scan", "exact")
_TAU = 2.0 * math.pi
_EPS = 1e-9  # s: instants closer than this are the same instant


_PI = math.pi


def _wrap(a: float) -> float:
    return (a + math.pi) % _TAU - math.pi


class _Report(NamedTuple):
    """What the server last reported: odometry pose (m, m, rad) and speeds (m/s, rad/s)."""

    x: float
    y: float
    theta: float
    v: float
    omega: float


class _Origin(NamedTuple):
    """The true pose the odometry frame starts at, with its heading's cosine and sine."""

    x: float
    y: float
    cos: float
    sin: float
    theta: float


class _Queued(NamedTuple):
    """A command on its way to the robot, and the simulated time it arrives (s)."""

    at: float
    command: Command


class _Held(NamedTuple):
    """A server loop's pieces for one step, the speeds at its end, and its report's piece.

    ``mark`` is the index of the piece at whose start the server reported (-1: none).
    """

    phases: list[Phase]
    v_end: float
    w_end: float
    mark: int


@dataclass(frozen=True)
class SimEvent:
    """Something the simulator noticed, with where and when.

    ``kind`` is ``"collision"`` (the body touched an obstacle and stalled), at sim
    ``time`` (s), true position ``x``, ``y`` (m), obstacle index and label.
    """

    kind: str
    time: float
    x: float
    y: float
    obstacle: int
    label: str


class SimBackend:
    """A simulated robot in a :class:`sim.world.World` (``clock = ClockMode.SIMULATED``).

    Parameters
    ----------
    world : World
    seed : int, optional
        Seed of every random draw (ladar noise, odometry drift); default the world's.
    robot : str or RobotProfile, optional
        A robot profile: a shipped name (``pioneer-p3dx``, ``pioneer2dx``, ``ideal``), a
        profile file, or a :class:`sim.robot.RobotProfile`; default the world's.
    ladar : str or LadarProfile, optional
        A ladar profile or its name (``lms200``, ``lms200-ideal``); default the world's.
    sensing : {"scan", "exact"}
        ``exact`` makes the ladar an oracle: noise-free ranges plus ``Scan.tangents``
        and ``Scan.curvatures``, and a fresh scan at every observation.
    start : Pose, optional
        Where :meth:`reset` puts the robot (world frame); default the world's start.
    clock : RunClock, optional
        For a profile with a ``control_cycle``: the run's motion-cycle phase and report
        instants (default: drawn from the seed). Replays of recorded runs set them.
    compiled : bool, optional
        Cast the ladar's scans with the compiled face loop (True) or with numpy (False);
        default: compiled where this install has it (:data:`sim.raycast.COMPILED`). The
        numbers are the same; False is for comparing the two.

    Raises
    ------
    WorldError
        Unknown profile, or the robot's body overlaps an obstacle at the start pose.
    BackendError
        Unknown sensing mode.
    """

    clock: ClockMode = ClockMode.SIMULATED
    #: What the robot's radio has received (a team member's; None: a robot alone).
    inbox: Inbox | None = None
    #: A step that touched nothing leaves a lower bound of the clearance; the exact value
    #: is measured when an observation's truth is read, or when a step needs it.
    _lazy_clearance = True

    def __init__(self, world: World, *, seed: int | None = None,
                 robot: str | RobotProfile | None = None,
                 ladar: str | LadarProfile | None = None, sensing: str = "scan",
                 start: Pose | None = None, clock: RunClock | None = None,
                 compiled: bool | None = None) -> None:
        if sensing not in SENSING_MODES:
            raise BackendError(f"unknown sensing mode `{sensing}` (one of: "
                               f"{', '.join(SENSING_MODES)})")
        self.world = world
        self.seed = world.seed if seed is None else int(seed)
        self.profile: RobotProfile = (world.robot if robot is None else robot
                                      if isinstance(robot, RobotProfile) else robot_profile(robot))
        self.ladar_profile: LadarProfile = (world.ladar if ladar is None
                                            else ladar_profile(ladar) if isinstance(ladar, str)
                                            else ladar)
        self.sensing = sensing
        self._collider = self._make_collider()
        self._oracle = sensing == "exact"
        self._clock = clock or RunClock()
        self.events: list[SimEvent] = []
        self._start = start
        self._compiled = compiled
        self.reset()

    # ------------------------------------------------------------------ lifecycle
    def reset(self, pose: Pose | None = None) -> None:
        """Put the robot at ``pose`` (default the world's start), time 0, fresh seed.

        Odometry restarts there at (0, 0, 0); ``pose`` is in world coordinates.
        """
        if pose is None:
            pose = self.world.start_pose if self._start is None else self._start
        clear, owner = self._collider.clearance(pose.x, pose.y)
        if clear < 0 or self.world.inside((pose.x, pose.y)):
            raise WorldError(f"world `{self.world.name}`: the robot ({self.profile.name}, "
                             f"radius {self.profile.radius} m) at ({pose.x:g}, {pose.y:g}) "
                             f"overlaps obstacles[{owner}]")
        ss = np.random.SeedSequence(self.seed)
        # each new stream is spawned last: the earlier ones keep their numbers
        ladar_seq, odo_seq, timing_seq, slip_seq, half_seq = ss.spawn(5)
        self._odo_rng = np.random.default_rng(odo_seq)
        self._timing_rng = np.random.default_rng(timing_seq)
        self._slip_rng = np.random.default_rng(slip_seq)
        self._ladar = Ladar(self.ladar_profile, np.random.default_rng(ladar_seq),
                            mount=self.profile.ladar_mount, oracle=self._oracle)
        self._fan = (self._ladar.fan(self.world.caster, self._compiled)
                     if not self._oracle and math.isfinite(self._ladar.profile.max_range)
                     else None)
        self._t = 0.0
        self._ticks = TickClock()
        self._x, self._y, self._th = pose.x, pose.y, pose.theta
        # Odometry starts at (0, 0, 0) where the robot is now, as on a robot (REP-105 odom).
        self._ox = self._oy = self._oth = 0.0
        self._origin = _Origin(pose.x, pose.y, math.cos(pose.theta), math.sin(pose.theta),
                               pose.theta)
        self._v = self._w = 0.0
        self._cmd = STOP
        self._stalled = False
        self._collided = False
        # the clearance, exact or a lower bound (_clear_bound): sim/team.py writes it too
        self._clear = Clearance(clear, owner)
        self._clear_bound = False
        self.events = []
        self._reported = 0  # events already handed out in an observation's truth
        prof = self.profile
        rate = self._ladar.profile.rate
        if self._oracle:
            self._period = 0.0
        elif prof.scan_period is not None:
            self._period = prof.scan_period
        else:
            self._period = 1.0 / rate if rate > 0 else 0.0
        self.limits: RobotLimits = prof.limits_with(self._period)
        # The timing model: commands wait `command_latency` in a queue of simulated time,
        # pose and velocities are reported every `sip_cycle`, scans are taken at a seeded
        # phase of their period (the ladar does not run on the controller's clock) and
        # become readable `scan_latency` later.
        self._timed = prof.timed
        self._pending: deque[_Queued] = deque()
        self._sip_j = 1
        self._report = _Report(self._ox, self._oy, self._oth, 0.0, 0.0)
        self._scan_delay = (prof.scan_latency if prof.scan_latency.enabled and not self._oracle
                            else None)
        self._scan_queue: list[tuple[float, Scan]] = []   # (readable at, scan)
        self._scan_phase = (float(self._timing_rng.uniform(0.0, self._period))
                            if self._timed and self._period > 0 else 0.0)
        self._scan_k = 0 if self._scan_phase == 0.0 else -1
        # Stretches at half the scan rate (scan_half_rate): where the first one ends and
        # whether the run begins in one, drawn from their own stream.
        half = prof.scan_half_rate
        self._half_rng = np.random.default_rng(half_seq)
        self._halved = False
        self._rate_switch = math.inf
        if half.enabled and self._period > 0:
            self._halved = bool(self._half_rng.random() < half.share)
            self._rate_switch = float(self._half_rng.exponential(
                half.length if self._halved else half.full_length))
        self._scan: Scan = self._take_scan(self._x, self._y, self._th, 0.0)
        # The server loop (control_cycle): speeds step at the motion instants, reports
        # come on their own clock, commands are read between them (see _advance_cycled).
        self._cycled = prof.control_cycle > 0
        self._queued = prof.command_latency > 0 or self._cycled   # commands wait (_send)
        self._reports_on = prof.sip_cycle > 0
        if self._cycled:
            clock = self._clock
            self._desired = STOP
            self._next_control = (clock.control_phase if clock.control_phase is not None
                                  else float(self._timing_rng.uniform(0.0, prof.control_cycle)))
            self._report_times = clock.report_times or ()
            self._report_i = 0
            if self._report_times:
                self._reports_on = True
                self._next_report = self._report_times[0]
            elif prof.sip_cycle > 0:
                self._next_report = float(self._timing_rng.uniform(0.0, prof.sip_cycle))
            else:
                self._next_report = math.inf

    def close(self) -> None:
        """Stop the robot (nothing to release)."""
        self.stop()

    def stop(self) -> None:
        """Command zero velocity (after the command latency; the robot decelerates)."""
        self._send(STOP)

    @property
    def laser_mount(self) -> tuple[float, float, float]:
        """Ladar pose in the robot frame (x, y, theta: m, m, rad), for recorders' frames."""
        x, y, th = self.profile.ladar_mount
        return float(x), float(y), float(th)

    @property
    def laser_timing(self) -> tuple[float, float]:
        """(period, time_increment) of the ladar's scans, s, for recorders.

        The period is 0 when a scan is taken at every tick; the beams of a simulated
        scan are all taken at one instant (time increment 0).
        """
        return self._period, 0.0

    # ------------------------------------------------------------------ protocol
    def observe(self) -> Observation:
        """Report odometry pose, measured velocities, newest scan, flags and ground truth."""
        if self._reports_on:
            ox, oy, oth, v, w = self._report
        else:
            ox, oy, oth, v, w = self._ox, self._oy, self._oth, self._v, self._w
        pose = Pose(ox, oy, (oth + _PI) % _TAU - _PI)      # theta wrapped to [-pi, pi)
        theta = (self._th + _PI) % _TAU - _PI
        # The step left a bound of the clearance: measured only if read (LazyTruth).
        lazy = self._clear_bound
        clearance, _ = self._clear          # the exact value, or a bound when lazy
        truth: dict[str, Any] = {"x": self._x, "y": self._y, "theta": theta,
                                 "collided": self._collided}
        if not lazy:
            truth["clearance"] = clearance
        # a collision since the previous observation: truth["contact"] names it
        if len(self.events) > self._reported:
            e = self.events[self._reported]
            self._reported = len(self.events)
            kind = self._obstacle(e.obstacle)[1]
            truth["contact"] = {"obstacle": e.label, "kind": kind, "index": e.obstacle,
                                "t": e.time, "x": e.x, "y": e.y}
        if lazy:
            return observation(self._t, pose, v, w, self._scan, self._stalled,
                               LazyTruth(truth, partial(self._measure_clearance, self._x,
                                                        self._y), clearance),
                               self.inbox)
        return observation(self._t, pose, v, w, self._scan, self._stalled, truth, self.inbox)

    def _measure_clearance(self, x: float, y: float) -> float:
        """Return the exact clearance at ``(x, y)``, where the robot was when observed.

        If the robot is still there (a clearance depends on the place only), its next step
        starts from the exact value.
        """
        clear = self._collider.clearance(x, y)
        if self._clear_bound and self._x == x and self._y == y:
            self._clear, self._clear_bound = clear, False
        distance, _ = clear
        return distance

    def command(self, cmd: Command) -> None:
        """Hold ``cmd`` (clamped to the limits) until the next command."""
        lim = self.limits
        v, w = float(cmd.v), float(cmd.omega)
        # min(max(.)) written out (a NaN stays NaN, and is refused below)
        if v > lim.max_speed:
            v = lim.max_speed
        elif v < -lim.max_reverse_speed:
            v = -lim.max_reverse_speed
        if w > lim.max_turn_rate:
            w = lim.max_turn_rate
        elif w < -lim.max_turn_rate:
            w = -lim.max_turn_rate
        if not (math.isfinite(v) and math.isfinite(w)):
            raise BackendError(f"command is not finite: v={cmd.v}, omega={cmd.omega}")
        if self._queued:
            self._send(Command(v, w))
        else:
            self._cmd = Command(v, w)

    def _send(self, cmd: Command) -> None:
        if self._queued:
            self._pending.append(_Queued(self._t + self.profile.command_latency, cmd))
        else:
            self._cmd = cmd

    def advance(self, dt: float) -> float:
        """Let ``dt`` seconds of simulated time pass; return 0 (never late)."""
        if not (dt >= 0.0 and math.isfinite(dt)):
            raise BackendError(f"advance(dt) needs a finite dt >= 0, got {dt}")
        if dt == 0.0:
            return 0.0
        t1 = self._ticks.advance(dt)   # whole ticks: no drift over long runs
        self._advance_to(t1, True)
        return 0.0

    def _advance_to(self, t1: float, last: bool) -> None:
        """Move to time ``t1``: the tick's end (``last``) or an instant inside it.

        A team cuts a tick where two robots could meet (:class:`sim.team.TeamSim`); only
        the ``last`` piece takes an oracle scan and measures the exact clearance.
        """
        if not self._timed:
            self._step(t1, last)
        elif self._cycled:
            self._advance_cycled(t1, last)
        else:
            self._advance_timed(t1, last)

    def _advance_cycled(self, t1: float, last: bool = True) -> None:
        """Move to ``t1`` through the server loop's instants (``control_cycle`` profiles).

        At a motion instant the speeds take one ramp step towards the command the server
        holds, and hold until the next; at a report instant the pose and speeds are
        reported. After either, the server reads the commands that have arrived (sent
        ``command_latency`` earlier), unless its next instant is within ``input_window``:
        so a command waits for a read and then for a motion instant, as on AMRISim.
        """
        prof = self.profile
        if prof.odometry.enabled:
            self._advance_cycled_pieces(t1, last)
            return
        cycle, window, pending = prof.control_cycle, prof.input_window, self._pending
        t = self._t
        v, w = self._v, self._w
        phases: list[Phase] = []
        mark = -1
        while True:
            nc, nr = self._next_control, self._next_report
            at = nc if nc <= nr else nr
            if at > t1 - _EPS:
                break
            if at > t + _EPS:
                phases.append(Phase(at - t, v, 0.0, w, 0.0))
                t = at
            if nc <= nr:
                d = self._desired
                v = ramp_step(v, d.v, prof.max_accel, prof.max_decel, prof.ramp, cycle)
                w = ramp_step(w, d.omega, prof.max_turn_accel, prof.max_turn_decel, prof.ramp,
                              cycle)
                nc = self._next_control = nc + cycle
            else:
                mark = len(phases)       # the report: the pose there, these speeds
                self._report = _Report(0.0, 0.0, 0.0, v, w)
                nr = self._next_report = self._following_report(nr)
            if (nc if nc <= nr else nr) - at > window:
                while pending and pending[0].at <= at + _EPS:
                    self._desired = pending.popleft().command
        if t1 > t:
            phases.append(Phase(t1 - t, v, 0.0, w, 0.0))
        if phases:
            self._step(t1, last, held=_Held(phases, v, w, mark))
        else:
            self._v, self._w = v, w
        self._release_scans(t1)

    def _advance_cycled_pieces(self, t1: float, last: bool = True) -> None:
        """:meth:`_advance_cycled` a piece at a time (odometry noise draws per piece)."""
        prof = self.profile
        cycle, window, pending = prof.control_cycle, prof.input_window, self._pending
        while True:
            t = self._t
            nc, nr = self._next_control, self._next_report
            at = nc if nc <= nr else nr
            if at <= t + _EPS:
                if nc <= nr:
                    d = self._desired
                    self._v = ramp_step(self._v, d.v, prof.max_accel, prof.max_decel,
                                        prof.ramp, cycle)
                    self._w = ramp_step(self._w, d.omega, prof.max_turn_accel,
                                        prof.max_turn_decel, prof.ramp, cycle)
                    nc = self._next_control = nc + cycle
                else:
                    self._report = _Report(self._ox, self._oy, self._oth, self._v, self._w)
                    nr = self._next_report = self._following_report(nr)
                if (nc if nc <= nr else nr) - at > window:
                    while pending and pending[0].at <= at + _EPS:
                        self._desired = pending.popleft().command
                continue
            if t >= t1 - _EPS:
                break
            ends = at >= t1 - _EPS
            self._cmd = Command(self._v, self._w)   # held: constant speeds until `at`
            self._step(t1 if ends else at, ends and last)
        self._release_scans(t1)

    def _following_report(self, now: float) -> float:
        """Return the report instant after ``now`` (recorded instants, then every cycle)."""
        times = self._report_times
        self._report_i += 1
        if self._report_i < len(times):
            return times[self._report_i]
        prof = self.profile
        if prof.sip_cycle <= 0:
            return math.inf
        nxt = now + prof.sip_cycle
        if prof.report_slip_rate > 0 and self._slip_rng.random() < prof.report_slip_rate:
            nxt += prof.report_slip.draw(self._slip_rng)
        return nxt

    def _advance_timed(self, t1: float, last: bool = True) -> None:
        """Move to ``t1`` in pieces cut where a report is due; queued commands switch inside."""
        pending = self._pending
        cycle = self.profile.sip_cycle
        while True:
            t = self._t
            while pending and pending[0].at <= t + _EPS:
                self._cmd = pending.popleft().command
            if cycle > 0:
                while self._sip_j * cycle <= t + _EPS:
                    self._report = _Report(self._ox, self._oy, self._oth, self._v, self._w)
                    self._sip_j += 1
            if t >= t1 - _EPS:
                break
            end = t1
            if cycle > 0 and self._sip_j * cycle < end:
                end = self._sip_j * cycle
            final = end >= t1 - _EPS
            if final:
                end = t1
            switches = []
            while pending and pending[0].at < end - _EPS:
                switches.append(pending.popleft())
            self._step(end, final and last, switches)
        self._release_scans(t1)

    def _release_scans(self, t1: float) -> None:
        """Make the newest scan whose latency has passed by ``t1`` the readable one."""
        if self._scan_queue:
            kept = []
            for due, scan in self._scan_queue:
                if due > t1 + _EPS:
                    kept.append((due, scan))
                elif scan.stamp >= self._scan.stamp:
                    self._scan = scan
            self._scan_queue = kept

    def _step(self, t1: float, final: bool,
              switches: list[_Queued] | None = None,
              held: _Held | None = None) -> None:
        """Integrate from the current time to ``t1`` (collisions, scans).

        The held command changes at each :class:`_Queued` command of ``switches`` (queued
        commands taking effect inside the step). Only the ``final`` piece of a tick takes
        an oracle scan. A piece that touched nothing leaves a lower bound of the clearance
        (the centre moved at most its reach), measured exactly when it no longer covers a
        step or someone reads it (:meth:`observe`, ``_lazy_clearance``).
        """
        t0 = self._t
        # The last ladar instant inside (t0, t1], if any.
        scan_at = math.inf          # none this step
        if self._period == 0.0:
            if final:
                scan_at = t1
        else:
            k = math.floor((t1 - self._scan_phase) / self._period + 1e-9)
            if k > self._scan_k:
                scan_at = min(t1, max(t0, self._scan_phase + k * self._period))
                self._scan_k = k
                if self._scan_lost(k, scan_at):
                    scan_at = math.inf  # not taken: the controller never sees it
        x0, y0, th0 = self._x, self._y, self._th
        mark, marked = -1, Pose(0.0, 0.0, 0.0)   # the true pose at the report
        if held is not None:        # the server loop's pieces, and where to note the pose
            phases, v_end, w_end, mark = held.phases, held.v_end, held.w_end, held.mark
        elif switches:
            phases = []
            v, w, cmd, t = self._v, self._w, self._cmd, t0
            for ta, nxt in switches:    # (arrival time, command)
                if ta > t:
                    more, v, w = plan_phases(v, w, cmd.v, cmd.omega, ta - t, self.profile)
                    phases += more
                    t = ta
                cmd = nxt
            more, v_end, w_end = plan_phases(v, w, cmd.v, cmd.omega, t1 - t, self.profile)
            phases += more
            self._cmd = cmd
        else:
            phases, v_end, w_end = plan_phases(self._v, self._w, self._cmd.v, self._cmd.omega,
                                               t1 - t0, self.profile)
        x, y, th = x0, y0, th0
        clear = self._clear
        t = t0
        contact = False
        scanned = math.isinf(scan_at)
        if not scanned and scan_at <= t0 + 1e-12:
            self._scanned(self._take_scan(x, y, th, scan_at))
            scanned = True
        if mark == 0:
            marked = Pose(x, y, th)
        # The centre moves at most sum(|v|max * duration): if the clearance covers that,
        # nothing can be touched this step and one distance query (at the end) suffices.
        reach = 0.0
        for ph in phases:
            reach += ph.max_abs_v * ph.duration
        distance, _ = clear
        safe = distance - CONTACT >= reach
        if not safe and self._clear_bound:
            clear = self._collider.clearance(x, y)   # the sweep needs the exact clearance
            distance, _ = clear
            safe = distance - CONTACT >= reach
        self._clear_bound = False
        for i, ph in enumerate(phases):
            pieces = [ph]
            if not scanned and t < scan_at < t + ph.duration:
                cut = scan_at - t
                pieces = [ph._replace(duration=cut),
                          Phase(ph.duration - cut, ph.v_at(cut), ph.a_v, ph.w_at(cut), ph.a_w)]
            for piece in pieces:
                if safe:
                    x, y, th = integrate(x, y, th, piece, piece.duration)
                else:
                    r = self._collider.sweep(x, y, th, piece, clear)
                    x, y, th, clear = r.x, r.y, r.theta, Clearance(r.clearance, r.obstacle)
                    if r.contact:  # the event's time is the contact's, inside the piece
                        contact = True
                        t += r.tau
                        break
                t += piece.duration
                if not scanned and t >= scan_at - 1e-12:
                    self._scanned(self._take_scan(x, y, th, scan_at))
                    scanned = True
            if contact:
                break
            if mark == i + 1:
                marked = Pose(x, y, th)
        if safe:
            if final and not self._lazy_clearance:
                clear = self._settled_clearance(x, y)
            else:       # a lower bound: the centre moved at most `reach`
                clear = Clearance(clear.distance - reach, clear.obstacle)
                self._clear_bound = True
        if contact:
            self._v = self._w = 0.0
            if not self._stalled:
                obs_i = clear.obstacle
                self.events.append(SimEvent("collision", t, x, y, obs_i,
                                            self._obstacle(obs_i)[0]))
            self._stalled = self._collided = True
            if not scanned:  # the robot rests at the contact point until the scan instant
                self._scanned(self._take_scan(x, y, th, scan_at))
        else:
            self._v, self._w = v_end, w_end
            self._stalled = False
        self._x, self._y, self._th, self._clear = x, y, th, clear
        self._t = t1
        self._update_odometry(x0, y0, th0)
        if mark >= 0:
            if contact:     # the robot rests at the contact, stopped
                self._report = _Report(self._ox, self._oy, self._oth, 0.0, 0.0)
            else:
                o = self._origin
                dx, dy = marked.x - o.x, marked.y - o.y
                self._report = self._report._replace(
                    x=o.cos * dx + o.sin * dy, y=o.cos * dy - o.sin * dx,
                    theta=marked.theta - o.theta)

    # ------------------------------------------------------------------ extras
    @property
    def time(self) -> float:
        """Simulated time, seconds."""
        return self._t

    @property
    def true_pose(self) -> Pose:
        """The robot's true pose (theta wrapped to [-pi, pi))."""
        return Pose(self._x, self._y, _wrap(self._th))

    # ------------------------------------------------------------------ internals
    def _settled_clearance(self, x: float, y: float) -> Clearance:
        """Return the exact clearance where a step that touched nothing ended."""
        return self._collider.clearance(x, y)

    def _make_collider(self) -> Collider:
        """Return the collider of the robot's body in the world (made once)."""
        return Collider(self.world.parts, self.profile.radius)

    def _obstacle(self, index: int) -> tuple[str, str]:
        """Return the label and kind of obstacle ``index`` ("", "" when none)."""
        if 0 <= index < len(self.world.obstacles):
            o = self.world.obstacles[index]
            return o.name or o.kind, o.kind
        return "", ""

    def _scan_lost(self, k: int, t: float) -> bool:
        """Return True when scan ``k`` (taken at ``t``) is lost in a half-rate stretch.

        The stretches (``scan_half_rate``) alternate with stretches at the full rate, each
        of an exponential length; inside one, every odd-numbered scan is lost.
        """
        if self._rate_switch > t:
            return self._halved and k % 2 == 1
        half = self.profile.scan_half_rate
        while self._rate_switch <= t:
            self._halved = not self._halved
            self._rate_switch += float(self._half_rng.exponential(
                half.length if self._halved else half.full_length))
        return self._halved and k % 2 == 1

    def _scanned(self, scan: Scan) -> None:
        """Make a new scan readable now, or after its seeded latency."""
        if self._scan_delay is None:
            self._scan = scan
        else:
            due = scan.stamp + self._scan_delay.draw(self._timing_rng)
            self._scan_queue.append((due, scan))

    def _take_scan(self, x: float, y: float, th: float, stamp: float) -> Scan:
        lad = self._ladar
        if self._fan is not None:
            return lad.scan(self._fan, x, y, th, stamp)
        ox, oy = lad.origin(x, y, th)
        angles = lad.world_angles(th)
        hits = self.world.caster.cast(np.array((ox, oy)), angles, lad.profile.max_range,
                                      detail=self._oracle, rel=lad.rel)
        return lad.measure(hits, th, stamp)

    def _update_odometry(self, x0: float, y0: float, th0: float) -> None:
        noise = self.profile.odometry
        if not noise.enabled:
            o = self._origin
            dx0, dy0 = self._x - o.x, self._y - o.y
            self._ox, self._oy = o.cos * dx0 + o.sin * dy0, o.cos * dy0 - o.sin * dx0
            self._oth = self._th - o.theta
            return
        c, s = math.cos(th0), math.sin(th0)
        dx, dy = self._x - x0, self._y - y0
        fx, fy = c * dx + s * dy, -s * dx + c * dy      # motion in the old robot frame
        dth = self._th - th0
        ds = math.hypot(fx, fy)
        e_d, e_t, e_k = self._odo_rng.standard_normal(3)
        if ds > 0:
            scale = (ds + noise.distance * math.sqrt(ds) * e_d) / ds
            fx, fy = fx * scale, fy * scale
        dth += noise.turn * math.sqrt(abs(dth)) * e_t + noise.drift * math.sqrt(ds) * e_k
        oc, os_ = math.cos(self._oth), math.sin(self._oth)
        self._ox += oc * fx - os_ * fy
        self._oy += os_ * fx + oc * fy
        self._oth += dth
