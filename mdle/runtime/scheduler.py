"""The tick loop: executes a checked element on a backend, exactly as language.md says.

Over 500 lines: one class, the tick loop, whose rules (below) all act on one stack of
active elements; the slots and frames it makes are its private data.

Each tick (rule 4): observe; test timers and interrupts from the outermost active element
inwards, the outermost that fires ends with everything inside it (rule 3, innermost
first, each with its END event); the element after it starts at once and is tested in the
same tick (rule 5: zero-time elements get no control); then the innermost running atom
computes its control, alpha-scaled, and the command is sent; then the backend advances.
The robot is stopped whenever the run ends, whatever the cause (rule 7).

Time is the backend's observation time only; the optional wall-clock pacing lives in
:mod:`mdle.runtime.pacing`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, NamedTuple

from mdle.atoms.registry import Context
from mdle.core.backend import STOP, Backend, ClockMode, Command, Observation, clearance_floor
from mdle.core.errors import Diagnostic, MdleError, MdleRuntimeError, Span
from mdle.core.pose import Pose
from mdle.lang import AtomNode, Element, LiveArgs, Quantity, Send, StringNode, show_value
from mdle.runtime.events import (
    Cause,
    Collision,
    Event,
    EventKind,
    Observer,
    RunResult,
    Sample,
    Termination,
)
from mdle.runtime.pacing import Pacer

__all__ = ["Scheduler", "ActiveElement", "TIME_EPS", "DEFAULT_STALL_TIMEOUT"]

#: Timers are compared with this tolerance (s), so that a 1 s timer at 10 Hz ends at the
#: tick stamped 1.0 even when ten additions of 0.1 give 0.9999999999999999.
TIME_EPS = 1e-9

#: How long (s) the robot may stay stalled, or refuse to move, before the run is aborted.
DEFAULT_STALL_TIMEOUT = 5.0

_log = logging.getLogger(__name__)

_EMPTY: MappingProxyType[str, float] = MappingProxyType({})
_NO_MEMORY: MappingProxyType[Any, Any] = MappingProxyType({})


@dataclass(frozen=True)
class ActiveElement:
    """One level of the running path, for live views and the REPL.

    ``elapsed`` is the element's local time (s); ``remaining`` what is left of its own
    timer (s, ``inf`` for none).
    """

    path: str
    label: str
    level: int
    element: str
    elapsed: float
    remaining: float


class _Slot:
    """An element at one place in the tree, with everything a tick needs precomputed.

    A string's child slots are made when it first starts and dropped when it ends
    (:meth:`release`): a shared definition is one node of the program however many
    places use it, and instantiating every place up front would cost 2**N slots for a
    chain of N behaviors each holding the previous one twice.
    """

    __slots__ = ("node", "path", "label", "level", "kind", "is_atom", "timer", "limit",
                 "test", "source", "_children", "repeat", "step", "start", "args", "alpha_v",
                 "alpha_w", "law", "span", "tested", "sends", "remember", "track", "live")

    def __init__(self, node: Element, path: str, label: str, level: int) -> None:
        self.node = node
        self.path = path
        self.label = label
        self.level = level
        self.timer = float(node.timer)
        # the timer fires once the local time reaches `limit`; inf (or nan) never does
        self.limit = self.timer - TIME_EPS
        self.test: Callable[[Context], bool] | None = (
            None if node.interrupt.never else node.interrupt.test)
        # whether a tick has anything to test at this level (a `never` interrupt and no
        # timer have not: such levels are left out of the per-tick scan)
        self.tested = self.test is not None or self.limit < math.inf
        self.source = node.interrupt.source
        # the values the interrupt reads as they were at the start (at_start): evaluated
        # once when the element starts, kept in its frame
        self.remember = () if self.test is None else node.interrupt.remember
        # the running memories (lowest, highest, ever): folded before each test, by the
        # test itself (the levels without any pay nothing)
        self.track = () if self.test is None else node.interrupt.track
        if self.track and self.test is not None:
            self.test = _folding(self.track, self.test)
        self.span: Span | None = node.span
        self._children: tuple[_Slot, ...] | None = ()
        self.repeat = False
        self.step: Any = None
        self.start: Any = None
        self.args: Any = None
        self.alpha_v = 1.0
        self.alpha_w = 1.0
        self.law = ""
        self.sends: tuple[Send, ...] = ()
        # the law's arguments read while the atom runs (None: all fixed)
        self.live: LiveArgs | None = None
        if isinstance(node, AtomNode):
            self.sends = node.sends
            self.live = node.live
            self.is_atom = True
            self.kind = "atom"
            self.step = node.law.step
            self.start = node.law.start
            self.args = node.args
            self.law = node.law.name
            self.alpha_v, self.alpha_w = (float(a) for a in node.scale)
        else:
            self.is_atom = False
            self.kind = node.kind.value
            self.repeat = node.repeat
            self._children = None if node.elements else ()

    @property
    def children(self) -> tuple[_Slot, ...]:
        """The slots of a string's elements, made on first use."""
        kids = self._children
        if kids is None:
            assert isinstance(self.node, StringNode)
            kids = self._children = tuple(_child_slots(self.node, self.path, self.level + 1))
        return kids

    def release(self) -> None:
        """Drop the child slots of a string that has ended (made again if it restarts)."""
        if not self.is_atom and self._children:
            self._children = None


def _fold(track: tuple[tuple[Any, Callable[[Context], Any], Callable[[Any, Any], Any]], ...],
          ctx: Context, memory: Any) -> None:
    """Join this tick's readings to the running memories, inner before outer.

    Every tick the element runs, whatever its condition would skip; a second test in
    the same tick (after an element ended) folds the same readings again, which
    changes nothing.
    """
    for key, read, fold in track:
        memory[key] = fold(memory[key], read(ctx))


def _folding(track: tuple[tuple[Any, Callable[[Context], Any], Callable[[Any, Any], Any]], ...],
             test: Callable[[Context], bool]) -> Callable[[Context], bool]:
    """Return ``test`` that first folds this tick's readings into ``ctx.memory``."""
    def folded(ctx: Context) -> bool:
        _fold(track, ctx, ctx.memory)
        return test(ctx)
    return folded


def _child_slots(node: StringNode, path: str, level: int) -> list[_Slot]:
    seen: dict[str, int] = {}
    out = []
    for child in node.elements:
        n = seen[child.label] = seen.get(child.label, 0) + 1
        label = child.label if n == 1 else f"{child.label}#{n}"
        out.append(_Slot(child, f"{path}/{label}", label, level))
    return out


class _Frame:
    """A running element: its slot, start time, position in its string, atom state."""

    __slots__ = ("slot", "start", "index", "state", "pass_tick", "memory", "arg_memory")

    def __init__(self, slot: _Slot, start: float, tick: int) -> None:
        self.slot = slot
        self.start = start
        self.index = 0
        self.state: Any = None
        self.pass_tick = tick
        #: what the element's interrupt remembered when it started (at_start)
        self.memory: Mapping[Any, Any] = _NO_MEMORY
        #: what the atom's live law arguments remember (at_start, lowest...)
        self.arg_memory: dict[Any, Any] = {}


class _Check(NamedTuple):
    """What a tick tests of an active level that can fire: its timer and its interrupt.

    Copied out of the frame and its slot once per change of the stack, so that the tick
    reads one tuple per level.
    """

    level: int
    start: float
    limit: float
    test: Any
    slot: _Slot
    memory: Mapping[Any, Any]


def _remembered(pairs: Iterable[tuple[Any, Callable[[Context], Any]]], ctx: Context,
                span: Span | None, failing: str) -> dict[Any, Any]:
    """Evaluate each ``(key, fn)`` of ``pairs`` into a fresh memory, which ``ctx`` then reads.

    A plan's own error passes through; any other is reported as ``failing``, at ``span``.
    """
    memory: dict[Any, Any] = {}
    ctx.memory = memory
    for key, fn in pairs:
        try:
            memory[key] = fn(ctx)
        except MdleError:
            raise
        except Exception as exc:
            raise _failure(failing, span, exc) from exc
    return memory


class Scheduler:
    """Runs one element on a backend, tick by tick.

    Parameters
    ----------
    element : Element
        The checked element to run (a plan, behavior, group or atom).
    backend : Backend
        The robot; the scheduler observes, commands, advances and finally stops it, but
        never closes it (a supervisor may run the next element on it).
    rate : float
        Control rate, Hz (10 Hz is the Pioneer's 100 ms cycle).
    observers : sequence of Observer
        Told of the start, every event, every tick and the end.
    until : float or None
        Stop the run (cause STOPPED) once this many seconds have passed on the backend's
        clock since the first tick.
    realtime : bool
        Pace a simulated backend to the wall clock (hardware backends pace themselves).
    stall_timeout : float or None
        Abort (cause ERROR) when the robot reports ``stalled``, or refuses a non-zero
        command because its motors are disabled, for this many seconds in a row.

    Use :meth:`tick` until it returns False, then read :attr:`result`; or call
    :func:`mdle.runtime.run`. Only the scheduler starts and ends elements.
    """

    def __init__(self, element: Element, backend: Backend, rate: float = 10.0,
                 observers: Sequence[Observer] = (), *, until: float | None = None,
                 realtime: bool = False,
                 stall_timeout: float | None = DEFAULT_STALL_TIMEOUT) -> None:
        if not rate > 0.0 or not math.isfinite(rate):
            raise ValueError(f"rate must be a positive number of Hz, got {rate!r}")
        if until is not None and not until >= 0.0:
            raise ValueError(f"until must be a non-negative number of seconds, got {until!r}")
        self.element = element
        self.backend = backend
        self.rate = float(rate)
        self.dt = 1.0 / self.rate
        self.until = until
        self.stall_timeout = stall_timeout
        self.observers: tuple[Observer, ...] = tuple(observers)
        self._root = _Slot(element, element.label, element.label, 0)
        self._pacer = Pacer() if realtime and backend.clock is ClockMode.SIMULATED else None
        self._stack: list[_Frame] = []
        # each active level that can fire, outermost first; rebuilt after the stack
        # changes (None: stale)
        self._checks: tuple[_Check, ...] | None = ()
        self._events: list[Event] = []
        self._terminations: list[Termination] = []
        self._ticks = 0
        self._started = False
        self._stop_requested = False
        self._stop_reason: str | None = None
        self._ending = False
        self._aborting = False  # ending by an error or a stop: observers cannot undo it
        self._t0: float | None = None
        self._obs: Observation | None = None
        self._pose: Pose = Pose()
        self._distance = 0.0
        self._min_clearance: float | None = None
        self._collided = False
        self._collision: Collision | None = None  # the first contact
        self._ran = ""  # the path that ran during the last advance
        self._max_lateness = 0.0
        self._stall_since: float | None = None
        self._last_cmd = STOP
        # where an atom's `send` goes: a team member's transmitter (alone: nowhere)
        self._radio: Any = getattr(backend, "radio", None)
        self.result: RunResult | None = None

    # ------------------------------------------------------------------ lifecycle API

    def start(self) -> None:
        """Tell the observers the run begins. The first :meth:`tick` starts the element.

        Calling it is optional: the first tick does it.
        """
        if self._started:
            return
        self._started = True
        for o in self.observers:
            o.on_start(self)

    def tick(self) -> bool:
        """Run one tick; True while the program is still running afterwards.

        Raises whatever aborted the run (MdleRuntimeError from a failing law or
        interrupt, BackendError, KeyboardInterrupt...) after ending every element,
        stopping the robot and telling the observers.
        """
        if self.result is not None:
            return False
        if not self._started:
            self.start()
        try:
            return self._tick()
        except BaseException as exc:
            if self.result is None:
                cause = Cause.STOPPED if isinstance(exc, KeyboardInterrupt) else Cause.ERROR
                fault = None if cause is Cause.STOPPED else _describe(exc)
                if cause is Cause.STOPPED and self._stop_reason is None:
                    self._stop_reason = getattr(exc, "reason", None) or "KeyboardInterrupt"
                try:
                    self._finish(cause, fault)
                except Exception:  # keep the original error; the stop failure is logged
                    _log.exception("could not stop the robot cleanly after: %s", fault)
            raise

    def stop(self, cause: Cause = Cause.STOPPED, fault: str | None = None) -> RunResult:
        """End the run now: every active element ends with ``cause``, the robot stops."""
        if self.result is None:
            if not self._started:
                self.start()
            self._finish(cause, fault)
        assert self.result is not None
        return self.result

    def request_stop(self, reason: str | None = None) -> None:
        """Ask the run to stop at the next tick (safe from a signal handler).

        That tick observes, ends every active element with cause ``stopped`` and sends
        the stop command, which its sample records. ``reason`` (a signal's name, "standard
        output closed") goes to :attr:`RunResult.reason`; the first one given is kept.
        """
        if self._stop_reason is None:
            self._stop_reason = reason or "stop requested"
        self._stop_requested = True

    @property
    def ending(self) -> bool:
        """True once the run has begun to end (and after it ended)."""
        return self._ending or self.result is not None

    # ------------------------------------------------------------------ introspection API

    @property
    def running(self) -> bool:
        """True until the run has ended."""
        return self.result is None

    @property
    def ticks(self) -> int:
        """Ticks run so far."""
        return self._ticks

    @property
    def time(self) -> float | None:
        """Backend time of the latest observation (s), None before the first tick."""
        return None if self._obs is None else self._obs.time

    @property
    def elapsed(self) -> float:
        """Seconds since the first tick, on the backend's clock."""
        if self._obs is None or self._t0 is None:
            return 0.0
        return self._obs.time - self._t0

    @property
    def path(self) -> tuple[str, ...]:
        """Labels of the active elements, outermost first (empty before and after the run)."""
        return tuple(f.slot.label for f in self._stack)

    @property
    def path_str(self) -> str:
        """The active path joined with ``/`` (``main/patrol/cruise``), '' when idle."""
        return self._stack[-1].slot.path if self._stack else ""

    @property
    def active(self) -> tuple[ActiveElement, ...]:
        """Each active level with its elapsed time and remaining timer."""
        now = self.time or 0.0
        return tuple(ActiveElement(f.slot.path, f.slot.label, f.slot.level, f.slot.kind,
                                   now - f.start, f.slot.timer - (now - f.start))
                     for f in self._stack)

    @property
    def events(self) -> tuple[Event, ...]:
        """Every event so far."""
        return tuple(self._events)

    @property
    def pose(self) -> Pose:
        """Odometry pose at the latest observation."""
        return self._pose

    # ------------------------------------------------------------------ the tick

    def _tick(self) -> bool:
        obs = self.backend.observe()
        now = obs.time
        contact = self._absorb(obs)
        pose = obs.pose
        truth = obs.truth

        tick = self._ticks
        self._ticks = tick + 1
        ctx = Context(obs, 0.0, self.dt, self.backend.limits, {})
        if self._t0 is None:
            self._t0 = now
            if not self._stop_requested:  # asked to stop before it began: never start
                self._descend(self._root, now, ctx)
        fault = None
        if self._stop_requested:
            self._end_from(0, Cause.STOPPED, now, all_levels=True)
        elif self.until is not None and now - self._t0 >= self.until - TIME_EPS:
            if self._stop_reason is None:
                self._stop_reason = f"the time limit (until = {self.until:g} s)"
            self._end_from(0, Cause.STOPPED, now, all_levels=True)
        elif self.stall_timeout is not None and (obs.stalled or not obs.motors_enabled
                                                 or self._stall_since is not None):
            fault = self._stall_check(obs, now)
            if fault is not None:
                self._end_from(0, Cause.ERROR, now, all_levels=True)
        if self._stack:
            self._settle(ctx, now, tick)

        stack = self._stack
        if stack and stack[-1].slot.is_atom:
            frame = stack[-1]
            slot = frame.slot
            ctx.t = now - frame.start
            args = slot.args if slot.live is None else self._read_args(frame, ctx, fold=True)
            try:
                cmd = slot.step(args, ctx, frame.state)
            except MdleError:
                raise
            except Exception as exc:
                raise _failure(f"control law `{slot.law}` of `{slot.path}` failed at "
                               f"t = {ctx.t:.3f} s", slot.span, exc) from exc
            if slot.alpha_v != 1.0 or slot.alpha_w != 1.0:
                cmd = Command(cmd.v * slot.alpha_v, cmd.omega * slot.alpha_w)
            if slot.sends and self._radio is not None:
                ctx.memory = frame.arg_memory  # what the values sent remember
                self._send(slot, ctx, now)
        else:
            cmd = STOP
        self.backend.command(cmd)
        self._last_cmd = cmd
        self._ran = stack[-1].slot.path if stack else ""

        running = bool(stack)
        lateness = 0.0
        if running:
            lateness = self.backend.advance(self.dt)
            if self._pacer is not None:
                lateness = max(lateness, self._pacer.wait(now + self.dt - self._t0))
            if lateness > self._max_lateness:
                self._max_lateness = lateness
        if self.observers:
            trace = ctx.cache.get("trace")
            scan = obs.scan
            clearance, collided, true_x, true_y, true_theta = (
                _truth_fields(truth) if truth else _NO_TRUTH)
            sample = Sample(
                now, pose.x, pose.y, pose.theta, obs.v, obs.omega, cmd.v, cmd.omega,
                stack[-1].slot.path if stack else "", lateness,
                None if scan is None else now - scan.stamp, obs.stalled,
                MappingProxyType(dict(trace)) if trace else _EMPTY,
                clearance, collided, true_x, true_y, true_theta, scan, contact)
            for o in self.observers:
                o.on_tick(sample)
        if not running:
            self._finish(None, fault)
        return running

    def _send(self, slot: _Slot, ctx: Context, now: float) -> None:
        """Send what the running atom sends at each of its ticks (language.md, messages)."""
        for s in slot.sends:
            try:
                value = None if s.value is None else float(s.value(ctx))
            except MdleError:
                raise
            except Exception as exc:
                raise _failure(f"`{s.source}` of `{slot.path}` failed at t = {ctx.t:.3f} s",
                               s.span, exc) from exc
            self._radio.send(s.channel, value, now)

    def _absorb(self, obs: Observation) -> Collision | None:
        """Make ``obs`` the latest observation: pose, distance, clearance, collision.

        Returns the contact the backend reported at this observation (None: none).
        """
        prev = self._obs
        self._obs = obs
        pose = obs.pose
        if prev is not None:
            self._distance += math.hypot(pose.x - self._pose.x, pose.y - self._pose.y)
        self._pose = pose
        truth = obs.truth
        if truth:
            # a backend's bound of the clearance that is no lower than the least so far
            # cannot make a new least: then the exact value need not be measured
            least = self._min_clearance
            if least is None or clearance_floor(truth) < least:
                clearance = truth.get("clearance")
                if clearance is not None and (least is None or clearance < least):
                    self._min_clearance = float(clearance)
            if truth.get("collided"):
                self._collided = True
            reported = truth.get("contact")
            if reported is not None:
                contact = _collision(reported, self._ran)
                if self._collision is None:
                    self._collision = contact
                return contact
        return None

    def _settle(self, ctx: Context, now: float, tick: int) -> None:
        """Test the active elements outermost first until none fires (rules 3-6)."""
        # `checked` names the level under test for the error message
        stack = self._stack
        level = 0
        while True:
            ctx.atom = stack[-1].state if stack else None  # for sensors reading the law's state
            checks = self._checks
            if checks is None:
                checks = self._checks = tuple(
                    _Check(f.slot.level, f.start, f.slot.limit, f.slot.test, f.slot, f.memory)
                    for f in stack if f.slot.tested)
            fired = -1
            cause = Cause.TIMER
            checked: _Slot | None = None
            t = 0.0
            try:
                for check in checks:
                    if check.level < level:
                        continue
                    checked = check.slot
                    t = now - check.start
                    if t >= check.limit:  # the timer wins when both hold
                        fired = check.level
                        break
                    if check.test is not None:
                        ctx.t = t
                        ctx.memory = check.memory
                        if check.test(ctx):
                            fired = check.level
                            cause = Cause.INTERRUPT
                            break
            except MdleError:
                raise
            except Exception as exc:
                assert checked is not None
                raise _failure(f"interrupt `{checked.source}` of `{checked.path}` failed at "
                               f"t = {t:.3f} s", checked.span, exc) from exc
            if fired >= 0:
                why = self._which(checked, ctx) if cause is Cause.INTERRUPT else None
                self._end_from(fired, cause, now, fired_by=why)
                level = self._next_child(now, ctx)
                continue
            # Every active element has been tested and none fired.
            if not stack:
                return
            top = stack[-1]
            slot = top.slot
            if slot.is_atom:
                return
            # A string whose last element has ended (or an empty string).
            if not slot.repeat:
                self._end_from(len(stack) - 1, Cause.COMPLETED, now)
                level = self._next_child(now, ctx)
            elif slot.children and top.pass_tick != tick:
                # Repeat; a pass that took no time waits for the next tick (rule 5).
                top.index = 0
                top.pass_tick = tick
                level = len(stack)
                self._descend(slot.children[0], now, ctx)
            else:
                return

    def _next_child(self, now: float, ctx: Context) -> int:
        """After the top of the stack was popped: start the next element of the parent.

        Returns the level from which testing goes on.
        """
        stack = self._stack
        if not stack:
            return 0
        parent = stack[-1]
        parent.index += 1
        children = parent.slot.children
        level = len(stack)
        if parent.index < len(children):
            self._descend(children[parent.index], now, ctx)
        return level

    def _descend(self, slot: _Slot, now: float, ctx: Context) -> None:
        """Start ``slot`` and, for a string, its first element, down to an atom."""
        while True:
            frame = _Frame(slot, now, self._ticks - 1)
            self._stack.append(frame)
            self._checks = None
            self._emit(Event(now, EventKind.START, slot.path, slot.level, slot.kind,
                             self._pose))
            if slot.remember:
                frame.memory = self._remember(slot, ctx)
            if slot.is_atom:
                args = slot.args
                if slot.live is not None:
                    ctx.t = 0.0
                    frame.arg_memory = self._remember_args(slot, ctx)
                    args = self._read_args(frame, ctx, fold=False)
                if slot.start is not None:
                    ctx.t = 0.0
                    try:
                        frame.state = slot.start(args, ctx)
                    except MdleError:
                        raise
                    except Exception as exc:
                        raise _failure(f"control law `{slot.law}` of `{slot.path}` failed "
                                       "to start", slot.span, exc) from exc
                return
            if not slot.children:
                return
            slot = slot.children[0]

    @staticmethod
    def _remember(slot: _Slot, ctx: Context) -> dict[Any, Any]:
        """Evaluate what ``slot``'s interrupt remembers, at its start (local time 0)."""
        ctx.t = 0.0
        return _remembered(slot.remember, ctx, slot.span,
                           f"interrupt `{slot.source}` of `{slot.path}` failed to remember its "
                           "start values")

    @staticmethod
    def _remember_args(slot: _Slot, ctx: Context) -> dict[Any, Any]:
        """Evaluate what the live arguments of ``slot``'s law remember, at its start."""
        assert slot.live is not None
        return _remembered(slot.live.remember, ctx, slot.span,
                           f"the arguments of `{slot.law}` in `{slot.path}` failed to "
                           "remember their start values")

    @staticmethod
    def _read_args(frame: _Frame, ctx: Context, fold: bool) -> dict[str, Any]:
        """Return the law's arguments with those read each tick read now (at ``ctx.t``).

        ``fold`` joins this tick's readings to the running memories first (not at the
        start, whose readings are their first values). A value outside the parameter's
        declared range ends the run with an error naming it.
        """
        slot = frame.slot
        live = slot.live
        assert live is not None
        ctx.memory = frame.arg_memory
        args = dict(slot.args)
        name = ""
        try:
            if fold and live.track:
                _fold(live.track, ctx, frame.arg_memory)
            for arg in live.args:
                name = arg.text
                args[arg.name] = arg.read(ctx)
        except MdleError:
            raise
        except Exception as exc:
            raise _failure(f"`{name}`, an argument of `{slot.law}` in `{slot.path}`, failed "
                           f"at t = {ctx.t:.3f} s", slot.span, exc) from exc
        for arg in live.args:
            value = args[arg.name]
            if arg.param is not None and not arg.param.accepts(float(value)):
                raise MdleRuntimeError(Diagnostic(
                    slot.span, f"`{arg.name}` of `{slot.law}` in `{slot.path}` is "
                    f"{show_value(Quantity(float(value), arg.param.dim))} at t = {ctx.t:.3f} s "
                    f"(`{arg.text}`): it must be {arg.param.range_words()} (SI units)"))
        return args

    @staticmethod
    def _which(slot: _Slot | None, ctx: Context) -> str | None:
        """Say which conditions of ``slot``'s interrupt hold (it has just fired)."""
        if slot is None:
            return None
        interrupt = slot.node.interrupt
        try:
            held = [text for text, test in interrupt.parts if test(ctx)]
        except Exception:  # the interrupt itself evaluated: its parts will; never fail here
            held = []
        return " and ".join(held) if held else interrupt.source

    def _end_from(self, level: int, cause: Cause, now: float, all_levels: bool = False,
                  fired_by: str | None = None) -> None:
        """End the frames at ``level`` and below, innermost first (rule 3).

        The frame at ``level`` ends with ``cause``, those inside it are ended by their
        parent; with ``all_levels`` (an abort) every one of them ends with ``cause``.
        """
        stack = self._stack
        while len(stack) > level:
            frame = stack.pop()
            self._checks = None
            slot = frame.slot
            c = cause if all_levels or len(stack) == level else Cause.ENDED_BY_PARENT
            frame.state = None  # per-atom state is dropped with the atom
            slot.release()
            why = fired_by if c is cause and len(stack) == level else None
            self._terminations.append(Termination(slot.path, slot.level, c, now, why))
            self._emit(Event(now, EventKind.END, slot.path, slot.level, slot.kind,
                             self._pose, c, why))

    def _emit(self, event: Event) -> None:
        self._events.append(event)
        if self._aborting:
            self._tell_all("on_event", event)
            return
        for o in self.observers:
            o.on_event(event)

    def _tell_all(self, hook: str, arg: Any) -> None:
        """Call ``hook`` of every observer while a run is aborted, whatever one of them does.

        The run already ends with its own error; an observer failing now (a trace on the
        disk that just filled) must not keep the others from hearing of the end, nor hide
        that error behind its own. Its failure stays where it keeps it (a trace writer's
        ``error``).
        """
        for o in self.observers:
            try:
                getattr(o, hook)(arg)
            except Exception as exc:  # noqa: BLE001 - see the docstring
                _log.debug("observer %r failed while the run ended: %s", o, exc)

    def _stall_check(self, obs: Observation, now: float) -> str | None:
        """Return the fault when the robot has been stalled or refusing to move too long."""
        assert self.stall_timeout is not None
        refusing = not obs.motors_enabled and (self._last_cmd.v != 0.0
                                               or self._last_cmd.omega != 0.0)
        if not (obs.stalled or refusing):
            self._stall_since = None
            return None
        if self._stall_since is None:
            self._stall_since = now
            return None
        if now - self._stall_since < self.stall_timeout - TIME_EPS:
            return None
        what = "stalled" if obs.stalled else "refused to move (motors disabled)"
        t0 = self._t0 if self._t0 is not None else now
        return (f"the robot {what} for {now - self._stall_since:.1f} s "
                f"(since t = {self._stall_since - t0:.1f} s)")

    def _finish(self, cause: Cause | None, fault: str | None) -> None:
        """End every active element with ``cause``, stop the robot, build the result.

        ``cause`` None means the program ended by itself, or at a tick that already sent
        the stop command (the stack is empty). Otherwise (an abort between or inside
        ticks) the robot is observed once more where it is stopped, the elements end at
        that time, and after the stop command a last sample records it (``cmd_v`` and
        ``cmd_omega`` zero), so a trace always ends with the command actually sent.
        """
        self._ending = True
        self._aborting = cause is not None
        stopped: Observation | None = None
        if cause is not None:
            stopped = self._last_look()
        now = self._obs.time if self._obs is not None else 0.0
        stack = self._stack
        try:
            if cause is not None:
                while stack:
                    frame = stack.pop()
                    self._checks = None
                    slot = frame.slot
                    frame.state = None
                    slot.release()
                    self._terminations.append(Termination(slot.path, slot.level, cause, now))
                    self._emit(Event(now, EventKind.END, slot.path, slot.level, slot.kind,
                                     self._pose, cause))
        finally:
            stack.clear()
            self._checks = None
            try:
                self.backend.stop()
                self._last_cmd = STOP
                if stopped is not None and self.observers:
                    self._tell_all("on_tick", _stop_sample(stopped))
            finally:
                root = next((t for t in reversed(self._terminations) if t.level == 0),
                            Termination(self._root.path, 0, cause or Cause.STOPPED, now))
                self.result = RunResult(
                    termination=root,
                    terminations=tuple(self._terminations),
                    events=tuple(self._events),
                    ticks=self._ticks,
                    duration=now - self._t0 if self._t0 is not None else 0.0,
                    distance=self._distance,
                    min_clearance=self._min_clearance,
                    collided=self._collided,
                    collision=self._collision,
                    fault=fault,
                    max_lateness=self._max_lateness,
                    reason=self._stop_reason if root.cause is Cause.STOPPED else None,
                )
                if self._aborting:
                    self._tell_all("on_end", self.result)
                else:
                    for o in self.observers:
                        o.on_end(self.result)

    def _last_look(self) -> Observation | None:
        """Observe the robot as the run is aborted; the latest observation if that fails.

        None before the first tick when the backend cannot be observed either.
        """
        try:
            obs = self.backend.observe()
        except (Exception, KeyboardInterrupt):  # a lost robot, a second Ctrl-C: end anyway
            return self._obs
        self._absorb(obs)
        return obs


def _stop_sample(obs: Observation) -> Sample:
    """Return the sample of the stop command sent at ``obs`` (no element running)."""
    scan = obs.scan
    clearance, collided, true_x, true_y, true_theta = (
        _truth_fields(obs.truth) if obs.truth else _NO_TRUTH)
    return Sample(obs.time, obs.pose.x, obs.pose.y, obs.pose.theta, obs.v, obs.omega,
                  STOP.v, STOP.omega, "", 0.0,
                  None if scan is None else obs.time - scan.stamp, obs.stalled, _EMPTY,
                  clearance, collided, true_x, true_y, true_theta, scan)


_NO_TRUTH = (None, None, None, None, None)


def _collision(contact: Mapping[str, Any], path: str) -> Collision:
    """Return the record of a contact the backend reported in its ground truth."""
    return Collision(float(contact.get("t", 0.0)), float(contact.get("x", math.nan)),
                     float(contact.get("y", math.nan)), str(contact.get("obstacle", "")),
                     str(contact.get("kind", "")), int(contact.get("index", -1)), path)


def _truth_fields(truth: Mapping[str, Any]) -> tuple[Any, Any, Any, Any, Any]:
    """(clearance, collided, x, y, theta) from an observation's ground truth."""
    return (truth.get("clearance"), truth.get("collided"), truth.get("x"), truth.get("y"),
            truth.get("theta"))


def _describe(exc: BaseException) -> str:
    if isinstance(exc, MdleError):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def _failure(what: str, span: Span | None, exc: Exception) -> MdleRuntimeError:
    return MdleRuntimeError(Diagnostic(span, f"{what}: {type(exc).__name__}: {exc}"))
