"""Expressions read each tick: sensor functions of sensor functions, abs/min/max,
bearing_to(x, y), clear(...), and values remembered when an element starts (at_start)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdle.atoms import default_registry
from mdle.atoms.registry import Context
from mdle.atoms.sensors import bearing_to_point, clear
from mdle.core.backend import Observation, RobotLimits, Scan
from mdle.core.errors import CheckError
from mdle.core.pose import Pose
from mdle.lang import format_source, load_text
from mdle.runtime import run_named
from mdle.runtime.scripted import ScriptedBackend

LIMITS = RobotLimits(1.0, 1.0, 1.0, radius=0.25)


def error(text: str) -> tuple[str, str | None]:
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle")
    (d,) = err.value.diagnostics
    return d.message, d.hint


def ends(text: str, until: float = 10.0) -> list[tuple[str, str, float]]:
    program = load_text(text, "t.mdle")
    result = run_named(program, None, ScriptedBackend(), rate=10, until=until)
    return [(t.path, t.cause.value, round(t.time, 6)) for t in result.terminations]


# ------------------------------------------------------------------ checking


@pytest.mark.parametrize("condition", [
    "range(-theta) < 1 m",
    "range(bearing_to(8 m, 0 m)) < 1 m",
    "min_range(bearing_to(8 m, 0 m) - 10 deg, bearing_to(8 m, 0 m) + 10 deg) < 1 m",
    "abs(theta) > 30 deg and max(x, y, 0 m) < 2 m and min(speed, 1 m/s) > 0",
    "clear(bearing_to(8 m, 0 m), min(dist_to(8 m, 0 m), 3 m))",
    "dist_to(8 m, 0 m) < at_start(dist_to(8 m, 0 m)) - 0.5 m",
    "abs(theta - at_start(theta)) > 90 deg",
    "ever(x > 1 m) and dist_to(8 m, 0 m) < lowest(dist_to(8 m, 0 m)) + 0.1 m",
    "highest(dist_to(at_start(x), at_start(y))) > 1 m and lowest(range(0 deg)) < 0.5 m",
])
def test_expressions_read_each_tick_check_clean(condition: str) -> None:
    program = load_text(f"atom a = (go(0.3 m/s), {condition}, 20 s)\nrun a\n")
    assert not program.warnings
    formatted = format_source(f"atom a = (go(0.3 m/s), {condition}, 20 s)\n")
    assert format_source(formatted) == formatted and condition in formatted
    load_text(formatted + "run a\n")


@pytest.mark.parametrize("condition, message", [
    ("range(x) < 1 m", "`angle` of `range` is an angle such as `30 deg`, found a length (`x`)"),
    ("range(stalled) < 1 m", "`angle` of `range` is an angle such as `30 deg`, found a condition"),
    ("clear(0 deg, 2 m, margin = range(0 deg) / 2)",
     "`margin` of `clear` is a fixed value, but this reads a sensor function"),
    ("min(x, theta) > 0", "`min` needs values of one kind: found an angle beside a length"),
    ("abs(stalled) > 0", "`abs` needs numbers, found a condition"),
    ("max(x) > 1 m", "`max` takes two values or more, found 1"),
    ("abs(x, y) > 1 m", "`abs` takes one value, found 2"),
    ("at_start(at_start(x)) > 1 m", "`at_start` inside `at_start`: the inner one adds nothing"),
    ("at_start(x) > 1 s", "cannot compare a length with a time"),
    ("ever(x) and stalled", "`ever` needs a condition, found a length"),
    ("lowest(stalled) > 0", "`lowest` needs a number, found a condition"),
    ("highest(x, y) > 1 m", "`highest` takes one value, found 2"),
    ("lowest(x) > 1 s", "cannot compare a length with a time"),
])
def test_mistakes_in_expressions_get_one_message(condition: str, message: str) -> None:
    got, _ = error(f"atom a = (go(0.3 m/s), {condition}, 20 s)\nrun a\n")
    assert got == message


def test_a_definition_s_arguments_stay_fixed() -> None:
    got, hint = error("atom a(rate = 1 deg/s) = (turn(rate), never, 1 s)\n"
                      "plan main = ((a(theta / 1 s)), never, 2 s)\n")
    assert got == "expected a fixed value, but `theta` is a sensor function"
    assert hint is not None and "interrupts" in hint


def test_a_law_s_parameter_declared_fixed_takes_no_reading() -> None:
    from mdle.atoms.registry import Param, Registry, control_law
    from mdle.core.backend import Command
    from mdle.core.units import LENGTH

    @control_law(Param("d", LENGTH, fixed=True))
    def hold(args: object, ctx: Context, state: object) -> Command:
        return Command(0.0, 0.0)

    registry = default_registry().merged(Registry.from_specs([hold.__mdle_spec__]))  # type: ignore[attr-defined]
    with pytest.raises(CheckError) as err:
        load_text("atom a = (hold(at_start(x)), never, 1 s)\nrun a\n", "t.mdle", registry)
    (d,) = err.value.diagnostics
    assert d.message == "`d` of `hold` is a fixed value, but this reads a sensor function"


def test_bearing_to_a_point_and_to_a_robot_share_the_name() -> None:
    spec = default_registry().sensors["bearing_to"]
    assert sorted(tuple(p.name for p in s.params) for s in (spec, *spec.overloads)) == [
        ("robot",), ("x", "y")]
    load_text("atom a = (stop, bearing_to(leader) > 10 deg or bearing_to(x = 1 m, y = 2 m)"
              " > 10 deg, 1 s)\nrun a\n")


def test_builtin_names_cannot_name_a_definition() -> None:
    got, _ = error("interrupt abs = x > 1 m\natom a = (stop, abs, 1 s)\nrun a\n")
    assert got == "`abs` is already a built-in function; a definition cannot take its name"


# ------------------------------------------------------------------ sensor functions


def _ctx(pose: Pose, scan: Scan | None = None) -> Context:
    return Context(Observation(0.0, pose, scan=scan), 0.0, 0.1, LIMITS)


@pytest.mark.parametrize("pose, point, bearing", [
    (Pose(0.0, 0.0, 0.0), (8.0, 0.0), 0.0),
    (Pose(0.0, 0.0, math.pi / 2), (1.0, 0.0), -math.pi / 2),
    (Pose(1.0, 1.0, math.pi), (0.0, 2.0), -math.pi / 4),
    (Pose(2.0, 0.0, 0.5), (2.0, 0.0), 0.0),   # at the point itself
])
def test_bearing_to_a_point(pose: Pose, point: tuple[float, float], bearing: float) -> None:
    got = bearing_to_point({"x": point[0], "y": point[1]}, _ctx(pose))
    assert got == pytest.approx(bearing) and -math.pi <= got <= math.pi


def _wall_scan(distance: float) -> Scan:
    """An LMS-200-like fan (-90..90 deg, 1 deg) seeing a wall `distance` ahead."""
    b = np.radians(np.arange(-90.0, 90.5, 1.0))
    with np.errstate(divide="ignore"):
        r = np.where(np.cos(b) > 1e-9, distance / np.cos(b), np.inf)
    valid = r < 8.0
    return Scan(np.where(valid, r, 8.0), b, valid, 0.0, 8.0)


@pytest.mark.parametrize("bearing, distance, margin, expect", [
    (0.0, 1.5, 0.1, True),     # 1.5 m + the body's half width 0.35 m < 2 m: clear
    (0.0, 1.8, 0.1, False),    # 1.8 + 0.35 > 2: the front would reach the wall
    (0.0, 1.5, 0.3, False),    # a wider margin reaches it
    (60.0, 1.5, 0.1, True),    # slanting: the wall is beyond the corridor's end
    (95.0, 1.0, 0.1, False),   # outside the field of view: cannot be seen, not clear
])
def test_clear_tests_a_corridor_as_wide_as_the_robot(bearing: float, distance: float,
                                                     margin: float, expect: bool) -> None:
    args = {"bearing": math.radians(bearing), "distance": distance, "margin": margin}
    assert clear(args, _ctx(Pose(), _wall_scan(2.0))) is expect
    assert clear(args, _ctx(Pose(), None)) is False


# ------------------------------------------------------------------ at_start at run time


def test_at_start_is_taken_when_each_run_of_the_element_starts() -> None:
    # the scripted robot moves 0.1 m per tick at 1 m/s; each run of `step` goes 0.5 m
    text = ("atom step = (go(1 m/s), x > at_start(x) + 0.45 m, 10 s)\n"
            "plan main = ((step, step, step), never, 10 s)\n")
    assert ends(text)[:3] == [("main/step", "interrupt", 0.5), ("main/step#2", "interrupt", 1.0),
                              ("main/step#3", "interrupt", 1.5)]


def test_at_start_is_taken_at_the_start_even_where_and_skips_it() -> None:
    # `t > 0.3 s and ...` does not read the right side before 0.3 s: the start value is
    # still the start's (0 m), not the value at 0.3 s
    text = ("atom step = (go(1 m/s), t > 0.3 s and x > at_start(x) + 0.45 m, 10 s)\n"
            "plan main = ((step, step), never, 10 s)\n")
    assert ends(text)[:2] == [("main/step", "interrupt", 0.5), ("main/step#2", "interrupt", 1.0)]


def test_a_string_remembers_at_its_own_start() -> None:
    text = ("atom leg = (go(1 m/s), never, 0.3 s)\n"
            "plan main = ((leg, leg, leg, leg)..., x > at_start(x) + 0.65 m, 10 s)\n")
    assert ends(text)[-1] == ("main", "interrupt", 0.7)


# ------------------------------------------------------------------ lowest, highest, ever


def test_highest_and_lowest_follow_the_whole_run_of_the_element() -> None:
    # out 1 m, then back: the string ends 0.5 m short of the farthest x it reached
    text = ("atom out = (go(1 m/s), never, 1 s)\natom back = (go(-1 m/s), never, 5 s)\n"
            "plan main = ((out, back), x < highest(x) - 0.45 m, 10 s)\n")
    assert ends(text)[-1] == ("main", "interrupt", 1.5)
    text = text.replace("x < highest(x) - 0.45 m", "lowest(x) < -0.25 m")
    assert ends(text)[-1] == ("main", "interrupt", 2.3)


def test_running_memories_are_read_at_every_tick_whatever_and_skips() -> None:
    # `t > 1.2 s and ...` reads the right side only from 1.2 s on (x = 0.8 m): highest
    # still holds the 1 m reached at 1 s, so the string ends at x = 0.5 m, not 0.3 m
    text = ("atom out = (go(1 m/s), never, 1 s)\natom back = (go(-1 m/s), never, 5 s)\n"
            "plan main = ((out, back), t > 1.2 s and x < highest(x) - 0.45 m, 10 s)\n")
    assert ends(text)[-1] == ("main", "interrupt", 1.5)


def test_ever_latches_a_condition_that_held_at_some_tick() -> None:
    text = ("atom out = (go(1 m/s), never, 1 s)\natom back = (go(-1 m/s), never, 5 s)\n"
            "plan main = ((out, back), ever(x > 0.75 m) and x < 0.25 m, 10 s)\n")
    assert ends(text)[-1] == ("main", "interrupt", 1.8)
    # the same without ever can never hold: the string runs to its end
    assert ends(text.replace("ever(x > 0.75 m)", "x > 0.75 m"))[-1] == ("main", "completed", 6.0)


def test_each_run_of_an_element_starts_its_running_memories_afresh() -> None:
    text = ("atom step = (go(1 m/s), highest(x) - lowest(x) > 0.45 m, 10 s)\n"
            "plan main = ((step, step, step), never, 10 s)\n")
    assert ends(text)[:3] == [("main/step", "interrupt", 0.5), ("main/step#2", "interrupt", 1.0),
                              ("main/step#3", "interrupt", 1.5)]


def test_running_memories_evaluate_the_same_in_generated_code_and_closures() -> None:
    from mdle.lang import conditions

    program = load_text("atom a = (go(1 m/s), ever(x > 1 m) and dist_to(8 m, 0 m) < "
                        "lowest(dist_to(8 m, 0 m)) + 0.1 m or highest(range(0 deg)) > "
                        "at_start(x), 10 s)\nrun a\n")
    interrupt = program.elements["a"].interrupt
    assert [fold for _, _, fold in interrupt.track] == [
        conditions.FOLDS[n] for n in ("ever", "lowest", "highest")]
    node = interrupt.__dict__["_node"]
    ctx = Context(Observation(0.0, Pose(1.5, 0.5, 0.2), scan=_wall_scan(3.0)), 0.0, 0.1, LIMITS)
    ctx.memory = {key: fn(ctx) for key, fn in interrupt.remember}
    generated = conditions._compile(node, as_bool=True)
    interpreted = conditions._interpret(node, as_bool=True)
    assert generated(ctx) is interpreted(ctx) is True
    for held in ctx.memory:
        ctx.memory[held] = 0.0 if ctx.memory[held] is not True else False
    assert generated(ctx) is interpreted(ctx) is False


# ------------------------------------------------------------------ in a control law's arguments


def _commanded(text: str, until: float = 10.0) -> list[float]:
    backend = ScriptedBackend()
    run_named(load_text(text, "t.mdle"), None, backend, rate=10, until=until)
    return [round(c.v, 6) for c in backend.commanded()]


@pytest.mark.parametrize("law", ["turn(theta / 1 s)", "heading(at_start(theta) + 90 deg)",
                                 "goto(at_start(x) + 1 m, at_start(y))",
                                 "go((highest(x) - x + 0.5 m) / 1 s)",
                                 "heading(bearing_to(at_start(x) + 1 m, 2 m))"])
def test_a_control_law_s_arguments_may_read_sensor_functions(law: str) -> None:
    program = load_text(f"atom a = ({law}, never, 1 s)\nrun a\n")
    assert not program.warnings


def test_at_start_in_a_law_s_argument_is_taken_when_the_atom_starts() -> None:
    # `out` goes 0.5 m; `on` then drives at (x at its start + 0.5 m) / 1 s = 1 m/s, while
    # `chase` reads x at every tick: 1, 1.1, 1.2 m/s (x grows 0.1 m per tick at 1 m/s)
    out = "atom out = (go(1 m/s), never, 0.5 s)\n"
    on = out + ("atom on = (go((at_start(x) + 0.5 m) / 1 s), never, 0.3 s)\n"
                "plan main = ((out, on), never, 10 s)\n")
    assert _commanded(on)[5:8] == [1.0, 1.0, 1.0]
    chase = on.replace("at_start(x)", "x")
    assert _commanded(chase)[5:8] == [1.0, 1.1, 1.21]


def test_a_law_s_argument_that_folds_to_a_constant_is_that_constant() -> None:
    text = "atom a = (go(at_start(0.5 m/s) + lowest(0.25 m/s)), never, 0.3 s)\nrun a\n"
    assert _commanded(text)[:3] == [0.75] * 3


def test_a_running_memory_in_a_law_s_argument_is_folded_each_tick() -> None:
    # highest(x) follows x as it grows: the speed stays 0.5 m/s (not falling as x grows)
    text = "atom a = (go((highest(x) - x + 0.5 m) / 1 s), never, 0.5 s)\nrun a\n"
    assert _commanded(text)[:5] == [0.5] * 5


def test_each_run_of_an_atom_takes_its_own_start_values_for_its_law() -> None:
    text = ("atom quarter = (heading(at_start(theta) + 90 deg), never, 4 s)\n"
            "plan main = ((quarter, quarter), never, 10 s)\n")
    backend = ScriptedBackend()
    run_named(load_text(text, "t.mdle"), None, backend, rate=10, until=10.0)
    assert math.degrees(backend.observations[-1].pose.theta) == pytest.approx(180.0, abs=1.0)


def test_mdle_show_prints_a_law_s_argument_as_written() -> None:
    from mdle.lang import show_program

    text = show_program(load_text("atom a = (heading(at_start(theta) + 90 deg), never, 1 s)\n"
                                  "run a\n"))
    assert "heading(theta = at_start(theta) + 90 deg, rate = 57.3 deg/s)" in text


def test_a_reading_outside_the_parameter_s_range_ends_the_run_with_a_located_error() -> None:
    from mdle.core.errors import MdleRuntimeError

    # goto's speed must be more than 0: x / 1 s is 0 at the start
    program = load_text("atom a = (goto(1 m, 0 m, v = x / 1 s), never, 1 s)\nrun a\n", "t.mdle")
    with pytest.raises(MdleRuntimeError) as err:
        run_named(program, None, ScriptedBackend(), rate=10, until=2.0)
    (d,) = err.value.diagnostics
    assert d.span is not None and d.span.line == 1
    assert d.message == ("`v` of `goto` in `a` is 0 m/s at t = 0.000 s (`x / 1 s`): it must be "
                         "a finite number more than 0 (SI units)")


def test_huge_expressions_evaluate_the_new_nodes_as_the_generated_code_does() -> None:
    # past the generation limit the interpreter of closures runs them: the same values
    from mdle.lang import conditions

    program = load_text("atom a = (go(1 m/s), abs(range(bearing_to(8 m, 0 m)) - at_start(x))"
                        " > max(x, 1 m) or dist_to(8 m, 0 m) < at_start(dist_to(8 m, 0 m)),"
                        " 10 s)\nrun a\n")
    interrupt = program.elements["a"].interrupt
    node = interrupt.__dict__["_node"]
    scan = _wall_scan(3.0)
    ctx = Context(Observation(0.0, Pose(1.0, 0.5, 0.2), scan=scan), 0.0, 0.1, LIMITS)
    ctx.memory = {key: fn(ctx) for key, fn in interrupt.remember}
    generated = conditions._compile(node, as_bool=True)
    interpreted = conditions._interpret(node, as_bool=True)
    assert generated(ctx) is interpreted(ctx)
    ctx.memory = {key: 0.0 for key, _ in interrupt.remember}
    assert generated(ctx) is interpreted(ctx)
