"""The scheduler beyond the ordering rules.

Per-atom state, the tick's Context, faults, aborts, the robot stopped on every path out,
observers and the supervisor API.
"""

from __future__ import annotations

import types
from types import SimpleNamespace
from typing import Any

import pytest

from mdle.atoms.registry import Context
from mdle.core.backend import ClockMode, Command, Scan
from mdle.core.errors import BackendError, MdleRuntimeError
from mdle.core.pose import Pose
from mdle.lang import Program
from mdle.runtime import (
    BaseObserver,
    Cause,
    Event,
    Recorder,
    RunResult,
    Sample,
    Scheduler,
    element_of,
    run,
    run_named,
)
from mdle.runtime.scripted import ScriptedBackend


def test_per_atom_state_is_made_at_start_and_dropped_at_end(ir: SimpleNamespace) -> None:
    made = []

    def start(args: Any, ctx: Context) -> types.SimpleNamespace:
        state = types.SimpleNamespace(n=0, t_start=ctx.t, at=ctx.obs.time)
        made.append(state)
        return state

    def step(args: Any, ctx: Context, state: Any) -> Command:
        state.n += 1
        return Command(float(state.n), 0.0)

    law = ir.const_law("count", start=start, step=step)
    a = ir.atom("a", law=law, timer=0.3)
    r = ir.string("r", a, repeat=True, timer=0.6)
    backend = ScriptedBackend()
    sch = Scheduler(ir.string("main", r), backend)
    while sch.tick():
        pass
    # two runs of `a`, each with its own fresh state counting its own ticks
    assert [(s.n, s.t_start, round(s.at, 9)) for s in made] == [(3, 0.0, 0.0), (3, 0.0, 0.3)]
    assert [c.v for c in backend.commanded()] == [1, 2, 3, 1, 2, 3, 0]


def test_context_is_fresh_each_tick_with_local_time_per_element(ir: SimpleNamespace) -> None:
    seen = []

    def probe(ctx: Context) -> bool:
        seen.append(("xi", round(ctx.obs.time, 9), round(ctx.t, 9), dict(ctx.cache)))
        ctx.cache["probe"] = ctx.obs.time
        return False

    def step(args: Any, ctx: Context, state: Any) -> Command:
        seen.append(("U", round(ctx.obs.time, 9), round(ctx.t, 9), dict(ctx.cache)))
        return Command()

    from mdle.lang import Interrupt

    a = ir.atom("a", law=ir.const_law("a", step=step), when=Interrupt(probe, "probe"))
    main = ir.string("main", ir.atom("w", timer=0.1), a, timer=0.25)
    run(main, ScriptedBackend())
    assert seen == [
        ("xi", 0.1, 0.0, {}), ("U", 0.1, 0.0, {"probe": 0.1}),
        ("xi", 0.2, 0.1, {}), ("U", 0.2, 0.1, {"probe": 0.2}),
    ]


def test_failing_control_law_stops_robot_and_names_the_element(ir: SimpleNamespace) -> None:
    def bad(args: Any, ctx: Context, state: Any) -> Command:
        if ctx.t > 0.15:
            raise ZeroDivisionError("division by zero")
        return Command(1.0, 0.0)

    main = ir.string("main", ir.string("p", ir.atom("a", law=ir.const_law("law_x", step=bad))))
    backend = ScriptedBackend()
    rec = Recorder()
    with pytest.raises(MdleRuntimeError, match=r"control law `law_x` of `main/p/a` failed"):
        run(main, backend, observers=[rec])
    assert backend.stops and backend.held == Command()
    assert rec.result is not None and rec.result.cause is Cause.ERROR
    assert rec.result.fault is not None and "ZeroDivisionError" in rec.result.fault
    assert [t.cause for t in rec.result.terminations] == [Cause.ERROR] * 3


def test_failing_interrupt_names_its_source(ir: SimpleNamespace) -> None:
    from mdle.lang import Interrupt

    def broken(ctx: Context) -> bool:
        raise KeyError("beam")

    main = ir.string("main", ir.atom("a", 1.0, when=Interrupt(broken, "range(0 deg) < 1 m")))
    backend = ScriptedBackend()
    with pytest.raises(MdleRuntimeError, match=r"interrupt `range\(0 deg\) < 1 m` of `main/a`"):
        run(main, backend)
    assert backend.stops


def test_failing_interrupt_deep_below_untested_levels_names_its_element_and_time(
        ir: SimpleNamespace) -> None:
    # levels without anything to test (never, no timer) are skipped by the tick; the
    # error still names the level whose interrupt failed and its own local time
    from mdle.lang import Interrupt

    def broken(ctx: Context) -> bool:
        if ctx.obs.time > 0.25:
            raise ValueError("bad beam")
        return False

    inner = ir.atom("a", 1.0, when=Interrupt(broken, "range(0 deg) < 1 m"))
    main = ir.string("main", ir.string("p", ir.string("q", inner), timer=10.0),
                     ir.atom("b", 0.0))
    rec = Recorder()
    with pytest.raises(MdleRuntimeError,
                       match=r"interrupt `range\(0 deg\) < 1 m` of `main/p/q/a` failed at "
                             r"t = 0\.300 s: ValueError: bad beam"):
        run(main, ScriptedBackend(), observers=[rec])
    assert rec.result is not None and rec.result.cause is Cause.ERROR
    assert [t.path for t in rec.result.terminations] == ["main/p/q/a", "main/p/q", "main/p",
                                                         "main"]


def test_dropped_connection_aborts_with_error_and_stops(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend(drop_at=0.35)
    rec = Recorder()
    with pytest.raises(BackendError, match="connection to the robot lost"):
        run(ir.string("main", ir.atom("a", 1.0)), backend, observers=[rec])
    assert rec.result is not None
    assert rec.result.cause is Cause.ERROR and rec.result.ticks == 4
    assert backend.stops == [pytest.approx(0.4)]


def test_keyboard_interrupt_inside_a_tick_stops_robot(ir: SimpleNamespace) -> None:
    def ctrl_c(args: Any, ctx: Context, state: Any) -> Command:
        if ctx.t >= 0.2:
            raise KeyboardInterrupt
        return Command(1.0, 0.0)

    backend = ScriptedBackend()
    rec = Recorder()
    with pytest.raises(KeyboardInterrupt):
        run(ir.string("main", ir.atom("a", law=ir.const_law("a", step=ctrl_c))), backend,
            observers=[rec])
    assert rec.result is not None
    assert backend.stops and rec.result.cause is Cause.STOPPED and rec.result.fault is None


def test_request_stop_ends_the_run_at_the_next_tick(ir: SimpleNamespace) -> None:
    # the next tick observes, ends every element and sends the stop command, which its
    # sample records; the reason reaches the result
    backend = ScriptedBackend()
    rec = Recorder()
    sch = Scheduler(ir.string("main", ir.atom("a", 1.0, law=ir.const_law("a", 0.5))),
                    backend, observers=[rec])
    sch.tick()
    sch.tick()
    sch.request_stop("SIGTERM")
    assert not sch.tick()
    assert sch.result is not None
    assert sch.result.cause is Cause.STOPPED and sch.result.ticks == 3
    assert sch.result.reason == "SIGTERM"
    assert [s.cmd_v for s in rec.samples] == [0.5, 0.5, 0.0]
    assert rec.samples[-1].path == "" and backend.commands[-1][1] == Command(0.0, 0.0)
    assert len(backend.stops) == 1


def test_an_abort_between_ticks_records_the_stop_command(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend()
    rec = Recorder()
    sch = Scheduler(ir.atom("a", 1.0, law=ir.const_law("a", 0.5)), backend,
                    observers=[rec])
    sch.tick()
    sch.tick()
    assert rec.samples[-1].cmd_v == 0.5
    sch.stop()
    assert sch.ending and sch.result is not None
    last = rec.samples[-1]
    assert (last.cmd_v, last.cmd_omega, last.path) == (0.0, 0.0, "")
    # observed where the robot was stopped: after the last tick's advance
    assert last.time > rec.samples[-2].time
    assert rec.events[-1].time == last.time and len(backend.stops) == 1


def test_a_stop_requested_before_the_first_tick_starts_nothing(ir: SimpleNamespace) -> None:
    rec = Recorder()
    sch = Scheduler(ir.atom("a", 1.0, law=ir.const_law("a", 0.5)), ScriptedBackend(),
                    observers=[rec])
    sch.request_stop("SIGINT (Ctrl-C)")
    assert not sch.tick()
    assert rec.events == [] and [s.cmd_v for s in rec.samples] == [0.0]
    assert rec.result is not None and rec.result.cause is Cause.STOPPED


def test_stop_is_idempotent_and_works_before_any_tick(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend()
    sch = Scheduler(ir.atom("a", 1.0), backend)
    first = sch.stop()
    assert sch.stop() is first and first.ticks == 0 and first.cause is Cause.STOPPED
    assert len(backend.stops) == 1


def test_stalled_robot_aborts_after_the_stall_timeout(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend(lambda t, k: {"stalled": t > 0.25})
    result = run(ir.atom("push", 1.0), backend, stall_timeout=1.0)
    assert result.cause is Cause.ERROR
    assert result.fault == "the robot stalled for 1.0 s (since t = 0.3 s)"
    assert result.duration == pytest.approx(1.3)
    assert backend.stops


def test_a_stall_the_plan_handles_is_not_fatal(ir: SimpleNamespace) -> None:
    # the plan backs away when stalled: the stall lasts one tick
    backend = ScriptedBackend(lambda t, k: {"stalled": 0.25 < t < 0.35})
    main = ir.string("main", ir.atom("push", 1.0, when="__never__", timer=0.3),
                     ir.atom("back", -1.0, timer=0.5))
    result = run(main, backend, stall_timeout=0.2)
    assert result.cause is Cause.COMPLETED and result.fault is None


def test_robot_refusing_to_move_is_a_fault(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend(motors_enabled=False)
    result = run(ir.atom("go", 0.5), backend, stall_timeout=0.5)
    assert result.cause is Cause.ERROR
    assert result.fault is not None and "motors disabled" in result.fault
    assert backend.pose == Pose()


def test_idle_robot_with_motors_disabled_is_not_a_fault(ir: SimpleNamespace) -> None:
    result = run(ir.atom("wait", 0.0, timer=1.0), ScriptedBackend(motors_enabled=False),
                 stall_timeout=0.5)
    assert result.cause is Cause.TIMER and result.fault is None


def test_result_measures_distance_clearance_collision_and_lateness(ir: SimpleNamespace) -> None:
    script = lambda t, k: {"truth": {"clearance": 1.0 - t, "collided": k == 3}}  # noqa: E731
    backend = ScriptedBackend(script, lateness=lambda k: 0.01 * k, clock=ClockMode.WALL)
    rec = Recorder()
    result = run(ir.atom("a", 2.0, timer=0.5), backend, observers=[rec])
    assert result.distance == pytest.approx(1.0)
    assert result.min_clearance == pytest.approx(0.5)
    assert result.collided and not result.ok
    assert result.max_lateness == pytest.approx(0.04)
    assert [s.lateness for s in rec.samples] == pytest.approx([0, 0.01, 0.02, 0.03, 0.04, 0])
    assert [s.collided for s in rec.samples] == [False, False, False, True, False, False]


def test_samples_carry_pose_command_path_and_law_diagnostics(ir: SimpleNamespace) -> None:
    def step(args: Any, ctx: Context, state: Any) -> Command:
        ctx.cache["trace"] = {"front": 2.0 - ctx.t, "curvature": -1.0}
        return Command(1.0, 0.5)

    a = ir.atom("f", law=ir.const_law("f", step=step), timer=0.2, scale=(0.5, 1.0))
    rec = Recorder()
    run(ir.string("main", a), ScriptedBackend(), observers=[rec])
    s0, s1, s2 = rec.samples
    assert (s0.path, s0.cmd_v, s0.cmd_omega) == ("main/f", 0.5, 0.5)
    assert dict(s1.diag) == {"front": pytest.approx(1.9), "curvature": -1.0}
    assert s1.x > 0 and s1.theta == pytest.approx(0.05)
    assert (s2.path, s2.cmd_v, dict(s2.diag)) == ("", 0.0, {})
    assert s0.clearance is None and s0.collided is None and s0.scan_age is None


def test_scan_older_than_the_tick_is_reported(ir: SimpleNamespace) -> None:
    import numpy as np

    def scan(stamp: float) -> Scan:
        b = np.linspace(-np.pi / 2, np.pi / 2, 5)
        return Scan(np.full(5, 3.0), b, np.ones(5, bool), stamp, 8.0)

    backend = ScriptedBackend(scan=scan, scan_period=0.2, scan_delay=0.05)
    rec = Recorder()
    run(ir.atom("a", timer=0.5), backend, observers=[rec])

    def age(s: Sample) -> float:
        assert s.scan_age is not None
        return round(s.scan_age, 9)

    assert [age(s) for s in rec.samples] == [0.05, 0.15, 0.05, 0.15, 0.05, 0.15]


def test_observer_hooks_are_called_in_order(ir: SimpleNamespace) -> None:
    calls: list[tuple[str, object]] = []

    class Log(BaseObserver):
        def on_start(self, scheduler: Scheduler) -> None:
            calls.append(("start", scheduler.path))

        def on_event(self, event: Event) -> None:
            calls.append(("event", event.path))

        def on_tick(self, sample: Sample) -> None:
            calls.append(("tick", sample.path))

        def on_end(self, result: RunResult) -> None:
            calls.append(("end", result.cause.value))

    run(ir.atom("a", timer=0.1), ScriptedBackend(), observers=[Log()])
    assert calls == [("start", ()), ("event", "a"), ("tick", "a"), ("event", "a"),
                     ("tick", ""), ("end", "timer")]


def test_supervisor_runs_named_elements_one_after_another(ir: SimpleNamespace) -> None:
    program = Program({"explore": ir.atom("explore", 1.0, when="wall"),
                       "home": ir.atom("home", -1.0, timer=0.2)}, entry="explore")
    backend = ScriptedBackend(lambda t, k: {"truth": {"wall": t > 0.45}})
    first = run_named(program, None, backend)
    assert first.termination == first.terminations[-1]
    assert first.cause is Cause.INTERRUPT and backend.pose.x == pytest.approx(0.5)
    second = run_named(program, "home", backend)
    assert second.cause is Cause.TIMER
    assert second.events[0].time == pytest.approx(0.5)
    assert backend.pose.x == pytest.approx(0.3) and not backend.closed


def test_element_of_explains_unknown_names(ir: SimpleNamespace) -> None:
    program = Program({"patrol": ir.atom("patrol")}, entry=None)
    with pytest.raises(MdleRuntimeError, match="no runnable element named `patrl`") as err:
        element_of(program, "patrl")
    assert err.value.diagnostics[0].hint == "did you mean `patrol`?"
    with pytest.raises(MdleRuntimeError, match="has no entry"):
        element_of(program)


def test_bad_rate_is_refused(ir: SimpleNamespace) -> None:
    with pytest.raises(ValueError, match="rate"):
        Scheduler(ir.atom("a"), ScriptedBackend(), rate=0)


def test_realtime_pacing_uses_an_injected_clock() -> None:
    from mdle.runtime.pacing import Pacer

    now = [100.0]
    slept: list[float] = []
    pacer = Pacer(clock=lambda: now[0], sleep=slept.append)
    assert pacer.wait(0.0) == 0.0
    now[0] = 100.05
    assert pacer.wait(0.1) == 0.0 and slept == [pytest.approx(0.05)]
    now[0] = 100.3
    assert pacer.wait(0.2) == pytest.approx(0.1)


def test_scheduler_logic_never_reads_the_wall_clock() -> None:
    import pathlib

    import mdle.runtime as rt

    pkg = pathlib.Path(rt.__file__).parent
    for path in pkg.glob("*.py"):
        text = path.read_text()
        if path.name == "pacing.py":
            continue
        assert "time.time(" not in text and "monotonic" not in text and "import time" \
            not in text, path.name
