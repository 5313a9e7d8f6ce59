"""Execution semantics (language.md rules 1-8), tick by tick, on hand-built IR.

Each test builds a small element tree, scripts which signals hold at which tick, runs
it at 10 Hz on the scripted backend and compares the events of every tick with a table
(``+path`` a start, ``-path:cause`` an end), and the commands sent, as py_trees' tests
compare node statuses per tick.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

from mdle.atoms.registry import Context
from mdle.core.backend import Command
from mdle.lang import StringKind
from mdle.runtime import Cause, Recorder, Scheduler, run
from mdle.runtime.scripted import ScriptedBackend


def vs(backend: ScriptedBackend) -> list[float]:
    return [round(c.v, 9) for c in backend.commanded()]


def test_string_runs_left_to_right_and_completes_upwards(ir: SimpleNamespace) -> None:
    # rules 1, 2: each element starts its own clock; the last one's end ends the string.
    main = ir.string("main", ir.atom("a", 1.0, timer=0.2), ir.atom("b", 2.0, timer=0.3),
                     kind=StringKind.PLAN)
    backend = ScriptedBackend()
    result = run(main, backend)
    assert ir.table(result.events) == {
        0: ["+main", "+main/a"],
        2: ["-main/a:timer", "+main/b"],
        5: ["-main/b:timer", "-main:completed"],
    }
    # tick:        0    1    2    3    4    5 (ended: stop)
    assert vs(backend) == [1.0, 1.0, 2.0, 2.0, 2.0, 0.0]
    assert result.ticks == 6
    assert result.termination.cause is Cause.COMPLETED
    assert result.termination.path == "main" and result.termination.level == 0
    assert result.duration == pytest.approx(0.5)
    assert backend.stops == [pytest.approx(0.5)]


def test_outermost_firing_element_wins(ir: SimpleNamespace) -> None:
    # rules 3, 4: parent and child fire at the same tick: the parent's record wins, the
    # child is ended by its parent, control passes to the parent's successor.
    inner = ir.string("p", ir.atom("c", 1.0, when="c"), ir.atom("c2", 5.0), when="p")
    main = ir.string("main", inner, ir.atom("d", 2.0, timer=0.1))
    backend = ScriptedBackend(ir.signals(6, p=[2], c=[2]))
    result = run(main, backend)
    assert ir.table(result.events) == {
        0: ["+main", "+main/p", "+main/p/c"],
        2: ["-main/p/c:ended-by-parent", "-main/p:interrupt", "+main/d"],
        3: ["-main/d:timer", "-main:completed"],
    }
    assert vs(backend) == [1.0, 1.0, 2.0, 0.0]
    ends = {t.path: (t.level, t.cause) for t in result.terminations}
    assert ends == {"main/p/c": (2, Cause.ENDED_BY_PARENT), "main/p": (1, Cause.INTERRUPT),
                    "main/d": (1, Cause.TIMER), "main": (0, Cause.COMPLETED)}


def test_outermost_of_three_firing_levels_wins(ir: SimpleNamespace) -> None:
    inner = ir.string("mid", ir.string("low", ir.atom("leaf", 1.0, when="x"), when="x"),
                      when="x")
    main = ir.string("top", inner, ir.atom("next", 3.0, timer=0.1))
    backend = ScriptedBackend(ir.signals(5, x=[1]))
    result = run(main, backend)
    assert ir.table(result.events)[1] == [
        "-top/mid/low/leaf:ended-by-parent", "-top/mid/low:ended-by-parent",
        "-top/mid:interrupt", "+top/next"]


def test_inner_element_ends_alone_when_only_it_fires(ir: SimpleNamespace) -> None:
    main = ir.string("main", ir.string("p", ir.atom("c", 1.0, when="c"), ir.atom("e", 4.0)),
                     when="stop")
    backend = ScriptedBackend(ir.signals(6, c=[1], stop=[3]))
    result = run(main, backend)
    assert ir.table(result.events) == {
        0: ["+main", "+main/p", "+main/p/c"],
        1: ["-main/p/c:interrupt", "+main/p/e"],
        3: ["-main/p/e:ended-by-parent", "-main/p:ended-by-parent", "-main:interrupt"],
    }
    assert vs(backend) == [1.0, 4.0, 4.0, 0.0]


def test_zero_time_element_gets_no_control(ir: SimpleNamespace) -> None:
    # rule 5: `a` starts with its interrupt true: it ends in zero time, `b` is tested and
    # runs in the same tick; a's law is never evaluated.
    steps = []

    def a_step(args: Any, ctx: Context, state: Any) -> Command:
        steps.append(ctx.obs.time)
        return Command(9.0, 0.0)

    a = ir.atom("a", when="z", law=ir.const_law("a", step=a_step))
    main = ir.string("main", a, ir.atom("b", 2.0, timer=0.2))
    backend = ScriptedBackend(ir.signals(4, z=[0]))
    result = run(main, backend)
    assert ir.table(result.events) == {
        0: ["+main", "+main/a", "-main/a:interrupt", "+main/b"],
        2: ["-main/b:timer", "-main:completed"],
    }
    assert steps == []
    assert vs(backend) == [2.0, 2.0, 0.0]


def test_zero_timer_is_zero_time(ir: SimpleNamespace) -> None:
    main = ir.string("main", ir.atom("a", 9.0, timer=0.0), ir.atom("b", 1.0, timer=0.1))
    backend = ScriptedBackend()
    result = run(main, backend)
    assert ir.table(result.events)[0] == ["+main", "+main/a", "-main/a:timer", "+main/b"]
    assert vs(backend) == [1.0, 0.0]


def test_string_of_zero_time_elements_completes_in_one_tick(ir: SimpleNamespace) -> None:
    s = ir.string("s", ir.atom("a", 9.0, when="z"), ir.atom("b", 9.0, when="z"))
    main = ir.string("main", s, ir.atom("c", 1.0, timer=0.1))
    backend = ScriptedBackend(ir.signals(3, z=[0]))
    result = run(main, backend)
    assert ir.table(result.events)[0] == [
        "+main", "+main/s", "+main/s/a", "-main/s/a:interrupt", "+main/s/b",
        "-main/s/b:interrupt", "-main/s:completed", "+main/c"]
    assert vs(backend) == [1.0, 0.0]


def test_repetition_of_zero_time_elements_does_not_spin_within_a_tick(ir: SimpleNamespace) -> None:
    # rule 5: a repeated string whose whole pass takes no time makes one pass per tick,
    # with the robot held still, until its elements can run or an interrupt ends it.
    r = ir.string("r", ir.atom("a", 1.0, when="z"), ir.atom("b", 9.0, when="z"), repeat=True,
                  when="q")
    main = ir.string("main", r)
    backend = ScriptedBackend(ir.signals(5, z=[0, 1], q=[3]))
    result = run(main, backend)
    one_pass = ["+main/r/a", "-main/r/a:interrupt", "+main/r/b", "-main/r/b:interrupt"]
    assert ir.table(result.events) == {
        0: ["+main", "+main/r", *one_pass],
        1: one_pass,
        2: ["+main/r/a"],
        3: ["-main/r/a:ended-by-parent", "-main/r:interrupt", "-main:completed"],
    }
    assert vs(backend) == [0.0, 0.0, 1.0, 0.0]


def test_child_timer_is_bounded_by_parent_timer(ir: SimpleNamespace) -> None:
    # rule 6: the parent's 0.3 s bounds its child's 5 s.
    p = ir.string("p", ir.atom("c", 1.0, timer=5.0), timer=0.3)
    main = ir.string("main", p, ir.atom("d", 2.0, timer=0.1))
    backend = ScriptedBackend()
    result = run(main, backend)
    assert ir.table(result.events) == {
        0: ["+main", "+main/p", "+main/p/c"],
        3: ["-main/p/c:ended-by-parent", "-main/p:timer", "+main/d"],
        4: ["-main/d:timer", "-main:completed"],
    }


def test_parent_and_child_timers_expiring_together_report_the_parent(ir: SimpleNamespace) -> None:
    p = ir.string("p", ir.atom("c", 1.0, timer=0.2), timer=0.2)
    result = run(ir.string("main", p), ScriptedBackend())
    assert ir.table(result.events)[2] == [
        "-main/p/c:ended-by-parent", "-main/p:timer", "-main:completed"]


def test_timer_is_reported_when_timer_and_interrupt_hold_together(ir: SimpleNamespace) -> None:
    result = run(ir.string("main", ir.atom("a", 1.0, when="x", timer=0.2)),
                 ScriptedBackend(ir.signals(4, x=[2])))
    assert ir.table(result.events)[2] == ["-main/a:timer", "-main:completed"]


def test_repetition_is_ended_by_an_outer_interrupt(ir: SimpleNamespace) -> None:
    r = ir.string("r", ir.atom("a", 1.0, timer=0.2), ir.atom("b", 2.0, timer=0.1),
                  repeat=True)
    g = ir.string("g", r, when="q", kind=StringKind.GROUP)
    main = ir.string("main", g, ir.atom("e", 3.0, timer=0.1))
    backend = ScriptedBackend(ir.signals(10, q=[7]))
    result = run(main, backend)
    assert ir.table(result.events) == {
        0: ["+main", "+main/g", "+main/g/r", "+main/g/r/a"],
        2: ["-main/g/r/a:timer", "+main/g/r/b"],
        3: ["-main/g/r/b:timer", "+main/g/r/a"],
        5: ["-main/g/r/a:timer", "+main/g/r/b"],
        6: ["-main/g/r/b:timer", "+main/g/r/a"],
        7: ["-main/g/r/a:ended-by-parent", "-main/g/r:ended-by-parent", "-main/g:interrupt",
            "+main/e"],
        8: ["-main/e:timer", "-main:completed"],
    }
    assert vs(backend) == [1.0, 1.0, 2.0, 1.0, 1.0, 2.0, 1.0, 3.0, 0.0]


def test_repetition_is_ended_by_its_own_timer(ir: SimpleNamespace) -> None:
    r = ir.string("r", ir.atom("a", 1.0, timer=0.2), repeat=True, timer=0.5)
    result = run(ir.string("main", r), ScriptedBackend())
    assert ir.table(result.events) == {
        0: ["+main", "+main/r", "+main/r/a"],
        2: ["-main/r/a:timer", "+main/r/a"],
        4: ["-main/r/a:timer", "+main/r/a"],
        5: ["-main/r/a:ended-by-parent", "-main/r:timer", "-main:completed"],
    }


def test_scaled_atom_scales_both_control_channels(ir: SimpleNamespace) -> None:
    # (alpha, beta, sigma): alpha scales v and omega; beta is already in the timer
    # (the checker writes beta * T), so a 0.2 s atom with beta 2 carries timer 0.4.
    a = ir.atom("a", 0.4, 0.3, timer=2 * 0.2, scale=(0.5, 2.0))
    backend = ScriptedBackend()
    result = run(ir.string("main", a), backend)
    assert backend.commanded()[:4] == [Command(0.2, 0.6)] * 4
    assert ir.table(result.events)[4] == ["-main/a:timer", "-main:completed"]


def test_element_labels_are_disambiguated_in_paths(ir: SimpleNamespace) -> None:
    a = ir.atom("a", 1.0, timer=0.1)
    result = run(ir.string("main", a, a, ir.atom("b", timer=0.1), a), ScriptedBackend())
    starts = [e for e in map(ir.fmt, result.events) if e.startswith("+")]
    assert starts == ["+main", "+main/a", "+main/a#2", "+main/b", "+main/a#3"]


def test_an_atom_can_be_run_alone(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend(ir.signals(5, hit=[3]))
    result = run(ir.atom("go", 0.5, when="hit"), backend)
    assert ir.table(result.events) == {0: ["+go"], 3: ["-go:interrupt"]}
    assert result.termination.cause is Cause.INTERRUPT
    assert vs(backend) == [0.5, 0.5, 0.5, 0.0]


def test_every_start_and_end_is_an_event_with_pose_and_level(ir: SimpleNamespace) -> None:
    # rule 8: events carry the odometry pose at their tick.
    main = ir.string("main", ir.atom("a", 1.0, timer=0.5), ir.atom("b", timer=0.1))
    rec = Recorder()
    result = run(main, ScriptedBackend(), observers=[rec])
    assert rec.events == list(result.events)
    end_a = next(e for e in result.events if e.path == "main/a" and e.cause)
    assert end_a.pose.x == pytest.approx(0.5) and end_a.level == 1
    assert end_a.element == "atom" and end_a.label == "a"
    assert [e.element for e in result.events[:1]] == ["behavior"]
    assert len(result.terminations) == 3


@pytest.mark.parametrize("ending", ["completed", "outer interrupt", "outer timer", "until"])
def test_robot_is_stopped_whatever_ends_the_program(ir: SimpleNamespace, ending: str) -> None:
    # rule 7
    main = ir.string("main", ir.atom("a", 1.0, timer=0.3 if ending == "completed" else 9.0),
                     when="q", timer=0.5 if ending == "outer timer" else float("inf"))
    backend = ScriptedBackend(ir.signals(20, q=[2] if ending == "outer interrupt" else []))
    result = run(main, backend, until=0.7 if ending == "until" else None)
    expected = {"completed": Cause.COMPLETED, "outer interrupt": Cause.INTERRUPT,
                "outer timer": Cause.TIMER, "until": Cause.STOPPED}[ending]
    assert result.termination.cause is expected
    assert len(backend.stops) == 1
    assert backend.held == Command(0.0, 0.0)
    assert backend.commanded()[-1] == Command(0.0, 0.0) or ending == "until"


def test_until_stops_every_active_element(ir: SimpleNamespace) -> None:
    main = ir.string("main", ir.string("p", ir.atom("a", 1.0)))
    result = run(main, ScriptedBackend(), until=0.3)
    assert ir.table(result.events)[3] == ["-main/p/a:stopped", "-main/p:stopped",
                                          "-main:stopped"]
    assert result.ticks == 4


def test_scheduler_steps_tick_by_tick(ir: SimpleNamespace) -> None:
    main = ir.string("main", ir.string("p", ir.atom("a", 1.0, timer=0.2), timer=5.0),
                     ir.atom("b", 2.0, timer=0.1))
    sch = Scheduler(main, ScriptedBackend())
    assert sch.path == () and sch.running
    assert sch.tick()
    assert sch.path == ("main", "p", "a") and sch.path_str == "main/p/a"
    sch.tick()
    [m, p, a] = sch.active
    assert (a.elapsed, p.remaining) == (pytest.approx(0.1), pytest.approx(4.9))
    assert a.remaining == pytest.approx(0.1) and m.remaining == float("inf")
    assert sch.tick()
    assert sch.path == ("main", "b")
    assert not sch.tick()
    assert sch.result is not None and sch.result.cause is Cause.COMPLETED
    assert not sch.tick() and sch.ticks == 4
