"""The checker: names, arguments, dimensions, interrupts, timers, structure, warnings."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import pytest

from mdle.atoms.registry import Context, Registry
from mdle.core.errors import CheckError, Diagnostic, Span, render_diagnostic
from mdle.lang import AtomNode, Program, StringKind, StringNode, load_text


def _at(d: Diagnostic) -> Span:
    """The place of a diagnostic that must have one."""
    assert d.span is not None, d.message
    return d.span


def check(text: str, reg: Registry) -> Program:
    return load_text(text, "t.mdle", reg)


def errors(text: str, reg: Registry) -> list[str]:
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle", reg)
    return [d.message for d in err.value.diagnostics]


def first(text: str, reg: Registry) -> str:
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle", reg)
    return render_diagnostic(err.value.diagnostics[0], err.value.sources)


# ------------------------------------------------------------------ constructs


def test_atom_with_defaults_runs_as_it_stands(reg: Registry) -> None:
    p = check("atom cruise(v = 0.3 m/s) = (drive(v), beam(0 deg) < 1 m, 20 s)", reg)
    a = p.elements["cruise"]
    assert isinstance(a, AtomNode)
    assert (a.label, a.law.name, dict(a.args), a.timer, a.scale) == (
        "cruise", "drive", {"v": 0.3}, 20.0, (1.0, 1.0))
    assert a.interrupt.source == "beam(0 deg) < 1 m" and not a.interrupt.never


def test_interrupt_closures_read_the_sensors(reg: Registry, make_ctx) -> None:  # type: ignore[no-untyped-def]
    p = check("interrupt near(d = 1 m) = beam(0 deg) < d\n"
              "atom a = (drive(1 m/s), near(2 m) or bumped, inf)", reg)
    test = p.elements["a"].interrupt.test
    assert test(make_ctx(x=0.0)) is False          # beam = 10 m
    assert test(make_ctx(x=8.5)) is True           # beam = 1.5 m < 2 m
    assert test(make_ctx(x=0.0, stalled=True)) is True


@pytest.mark.parametrize("expr, x, t, expected", [
    ("px > 2 m and not bumped", 3.0, 0.0, True),
    ("px > 2 m xor clock > 1 s", 3.0, 2.0, False),
    ("px * 2 >= 4 m", 2.0, 0.0, True),
    ("px - 1 m == 1 m", 2.0, 0.0, True),
    ("px / 2 != 1 m", 2.0, 0.0, False),
    ("-px < -1 m", 2.0, 0.0, True),
    ("(px + 1 m) * 2 > 5 m", 2.0, 0.0, True),
    ("gap(left) > gap(side = right)", 0.0, 0.0, True),
    ("clock >= 1.5 s", 0.0, 1.5, True),
    ("never", 0.0, 0.0, False),
    ("not never", 0.0, 0.0, True),
    ("px > 0", 1.0, 0.0, True),
])
def test_interrupt_expressions(expr: str, x: float, t: float, expected: bool, reg: Registry,
                               make_ctx: Callable[..., Context]) -> None:
    p = check(f"atom a = (drive(1 m/s), {expr}, inf)", reg)
    assert p.elements["a"].interrupt.test(make_ctx(x=x, t=t)) is expected


def test_never_is_marked_so_the_runtime_can_skip_it(reg: Registry) -> None:
    p = check("atom a = (drive(1 m/s), never, 2)", reg)
    assert p.elements["a"].interrupt.never
    assert p.elements["a"].timer == 2.0  # a bare number as a timer is seconds


def test_behavior_plan_group_and_labels(reg: Registry) -> None:
    p = check("atom a = (drive(1 m/s), never, 1 s)\n"
              "behavior b = ((a, (spin(10 deg/s), bumped, 2 s)), never, 10 s)\n"
              "plan main = ((b, ((a), px > 1 m, 5 s)), bumped, 1 min)", reg)
    main = p.elements["main"]
    assert isinstance(main, StringNode) and main.kind is StringKind.PLAN and main.timer == 60
    b, group = main.elements
    assert isinstance(b, StringNode) and b.kind is StringKind.BEHAVIOR and b.label == "b"
    assert [e.label for e in b.elements] == ["a", "spin"]
    assert isinstance(group, StringNode) and group.kind is StringKind.GROUP
    assert group.label == "group" and group.elements[0].label == "a"
    assert p.entry == "main"


def test_scaled_atoms(reg: Registry) -> None:
    p = check("atom a(v = 1 m/s) = (drive(v), never, 4 s)\n"
              "behavior s = (((0.5, 2, a), ([0.5, 0.25], 0.5, a(2 m/s)),"
              " (2, 1, (spin(1 rad/s), never, 1 s)), (0.5, 1, (2, 3, a))), never, inf)", reg)
    e = p.elements["s"]
    assert isinstance(e, StringNode)
    got = [(x.label, x.scale, x.timer, dict(x.args)) for x in e.elements]  # type: ignore[union-attr]
    assert got == [("a", (0.5, 0.5), 8.0, {"v": 1.0}), ("a", (0.5, 0.25), 2.0, {"v": 2.0}),
                   ("spin", (2.0, 2.0), 1.0, {"rate": 1.0}), ("a", (1.0, 1.0), 12.0, {"v": 1.0})]


def test_single_atom_string_and_repeat(reg: Registry) -> None:
    p = check("behavior r = ((drive(1 m/s), px > 1 m, 5 s)..., never, 1 min)\n"
              "behavior one = (r, bumped, 10 s)", reg)
    r = p.elements["r"]
    assert isinstance(r, StringNode) and r.repeat and len(r.elements) == 1
    one = p.elements["one"]
    assert isinstance(one, StringNode) and one.elements[0] is r


def test_symbols_and_keywords(reg: Registry) -> None:
    p = check("atom h(side = left) = (hug(side = side, rc = 0.4 m), never, inf)\n"
              "atom r = (hug(right, 0.2 m/s), never, inf)\nplan main = ((h(right), r), never, 1 s)",
              reg)
    assert dict(p.elements["h"].args) == {"side": "left", "v": 0.3, "rc": 0.4}  # type: ignore[union-attr]
    assert dict(p.elements["r"].args) == {"side": "right", "v": 0.2, "rc": 0.5}  # type: ignore[union-attr]
    main = p.elements["main"]
    assert isinstance(main, StringNode)
    assert main.elements[0].args["side"] == "right"  # type: ignore[union-attr]


def test_entry_rules(reg: Registry) -> None:
    assert check("atom a = (drive(1 m/s), never, 1 s)", reg).entry is None
    assert check("atom a = (drive(1 m/s), never, 1 s)\nrun a", reg).entry == "a"
    assert check("plan main = ((drive(1 m/s), never, 1 s), never, 1 s)", reg).entry == "main"


def test_required_parameters_are_checked_per_use(reg: Registry) -> None:
    p = check("interrupt near(d) = beam(0 deg) < d\natom a(v) = (drive(v), near(1 m), inf)\n"
              "plan main = ((a(1 m/s), a(v = 2 m/s)), never, 10 s)", reg)
    assert "a" not in p.elements  # needs an argument to run
    main = p.elements["main"]
    assert isinstance(main, StringNode)
    assert [x.args["v"] for x in main.elements] == [1.0, 2.0]  # type: ignore[union-attr]
    msgs = errors("interrupt near(d) = beam(0 deg) < d\n"
                  "atom a = (drive(1 m/s), near(1 s), inf)", reg)
    assert msgs == ["cannot compare a length with a time"]


def test_unreachable_element_warning(reg: Registry) -> None:
    p = check("atom forever = (drive(1 m/s), never, inf)\natom b = (spin(1 rad/s), never, 1 s)\n"
              "behavior s = ((forever, b), bumped, 10 s)\n"
              "behavior loop = ((((b)..., never, inf), b), never, 5 s)\n", reg)
    assert [w.message for w in p.warnings] == [
        "`b` is never reached: `forever` before it never ends (its interrupt is `never` and its "
        "timer `inf`)",
        "`b` is never reached: `((b)..., never, inf)` before it never ends (its interrupt is "
        "`never` and its timer `inf`)"]
    assert [(_at(w).line, _at(w).column) for w in p.warnings] == [(3, 25), (4, 41)]


def test_always_true_interrupt_warning(reg: Registry) -> None:
    p = check("atom a = (drive(1 m/s), not never, 1 s)\n"
              "interrupt near(d) = beam(0 deg) < d\natom b = (drive(1 m/s), near(1 m), 1 s)", reg)
    assert [w.message for w in p.warnings] == [
        "the interrupt `not never` is always true: the element ends as soon as it starts"]


# ------------------------------------------------------------------ errors (exact shape)


def test_unknown_law_with_did_you_mean(reg: Registry) -> None:
    assert first("atom a = (drvie(1 m/s), never, 1 s)", reg) == (
        "t.mdle:1:11: error: unknown name `drvie`: not a control law, atom, behavior or plan\n"
        "    atom a = (drvie(1 m/s), never, 1 s)\n"
        "              ^^^^^\n"
        "  hint: did you mean `drive`?")


def test_missing_timer_message(reg: Registry) -> None:
    assert first("atom a = (drive(1 m/s), bumped)", reg) == (
        "t.mdle:1:31: error: expected a timer such as `10 s` or `inf` after the interrupt: an "
        "atom is (control law, interrupt, timer)\n"
        "    atom a = (drive(1 m/s), bumped)\n"
        "                                  ^\n"
        "  hint: add `, inf` to run until the interrupt fires")


@pytest.mark.parametrize("text, message", [
    ("atom a = (drive(1 m/s), never, 10 m)",
     "expected a timer such as `10 s` or `inf`, found a length (`10 m`)"),
    ("atom a = (drive(1 m/s), never, never)",
     "expected a timer such as `10 s` or `inf`, found `never`"),
    ("atom a = (drive(1 m/s), never, px > 1 m)",
     "expected a timer such as `10 s` or `inf`, found a condition"),
    ("atom a = (drive(1 m/s), never, -1 s)", "a timer cannot be negative"),
    ("atom a = (drive(1 m/s), never, px)",
     "expected a fixed value, but `px` is a sensor function"),
    ("atom a = (drive(1 m), never, 1 s)",
     "`v` of `drive` is a speed such as `0.3 m/s`, found a length (`1 m`)"),
    ("atom a = (drive(0.3), never, 1 s)",
     "`v` of `drive` is a speed such as `0.3 m/s`, found a plain number (`0.3`)"),
    ("atom a = (drive(1 m/s, 2 m/s), never, 1 s)",
     "too many arguments: `drive` takes 1 argument (v), found 2"),
    ("atom a = (drive(), never, 1 s)", "`drive` needs `v` (a speed such as `0.3 m/s`)"),
    ("atom a = (drive(w = 1 m/s), never, 1 s)", "`drive` has no parameter `w`"),
    ("atom a = (drive(v = 1 m/s, v = 1 m/s), never, 1 s)", "`v` of `drive` is given twice"),
    ("atom a = (drive(v = 1 m/s, 2 m/s), never, 1 s)",
     "a positional argument cannot follow a keyword argument"),
    ("atom a = (hug(side = rihgt), never, 1 s)",
     "`side` of `hug` is one of `right` or `left`, found `rihgt`"),
    ("atom a = (drive(1 m/s), beam(0 deg) < 1 s, 1 s)", "cannot compare a length with a time"),
    ("atom a = (drive(1 m/s), px > 10, 1 s)", "cannot compare a length with a plain number"),
    ("atom a = (drive(1 m/s), px + clock > 1 m, 1 s)", "cannot add a time and a length"),
    ("atom a = (drive(1 m/s), px, 1 s)",
     "expected an interrupt such as `stalled` or `range(0 deg) < 1 m`, found a length"),
    ("atom a = (drive(1 m/s), bumped and px, 1 s)", "`and` joins conditions, but this is a length"),
    ("atom a = (drive(1 m/s), not px, 1 s)", "`not` needs a condition, found a length"),
    ("atom a = (drive(1 m/s), bumped < 1 m, 1 s)", "`<` needs numbers, found a condition"),
    ("atom a = (drive(1 m/s), bumpd, 1 s)", "unknown name `bumpd`"),
    ("atom a = (drive(1 m/s), inf, 1 s)",
     "`inf` is the timer that never expires; the interrupt that never fires is `never`"),
    ("atom a = (drive(1 m/s), drive(1 m/s), 1 s)",
     "expected an interrupt such as `stalled` or `range(0 deg) < 1 m`; `drive` is a control law"),
    ("behavior b = ((drive(1 m/s)), never, 1 s)",
     "`drive` is a control law; an atom needs an interrupt and a timer too"),
    ("behavior b = ((bumped), never, 1 s)",
     "expected an element (an atom, behavior or plan); `bumped` is a sensor function"),
    ("behavior b = ((1, 2, 3), never, 1 s)", "expected an element: an atom such as "
     "`(go(0.3 m/s), stalled, 10 s)`, a named atom, behavior or plan, found `3`"),
    ("atom a = (drive(1 m/s), never, 1 s)\nbehavior b = ((0.5, 1 s, a), never, 1 s)",
     "beta is a plain number such as `0.5`, found a time"),
    ("atom a = (drive(1 m/s), never, 1 s)\nbehavior b = ((0.5, 0, a), never, 1 s)",
     "beta scales the timer and must be positive"),
    ("atom a = (drive(1 m/s), never, 1 s)\nbehavior b = (([1, 2, 3], 1, a), never, 1 s)",
     "a per-channel scale is `[alpha_v, alpha_omega]`: two factors, found 3"),
    ("atom a = (drive(1 m/s), never, 1 s)\nbehavior b = ((a), never, 1 s)\n"
     "behavior c = ((2, 1, b), never, 1 s)",
     "only atoms can be scaled; `b` is a string of elements"),
    ("atom a = ((drive(1 m/s), never, 1 s), never, 1 s)",
     "`a` is declared an atom but is a string of elements"),
    ("behavior b = (drive(1 m/s), never, 1 s)",
     "`b` is declared a behavior but is an atom: a behavior is ((elements), interrupt, timer)"),
    ("atom a = (drive(1 m/s), never, 1 s, 2 s)",
     "an atom is (control law, interrupt, timer); this has 4 parts"),
    ("atom a(v = 1 m/s) = (drive(1 m/s), never, 1 s)\nbehavior b = ((v), never, 1 s)",
     "unknown name `v`: not a control law, atom, behavior or plan"),
    ("interrupt i = px\natom a = (drive(1 m/s), i, 1 s)",
     "an interrupt is a condition such as `range(0 deg) < 1 m`; `i` is a length"),
    ("atom a = (drive(1 m/s), never, 1 s)\nrun b", "unknown element `b`"),
    ("atom a(v) = (drive(v), never, 1 s)\nrun a", "`a` cannot run as it stands: it needs `v`"),
    ("interrupt i = bumped\nrun i", "`run` takes an atom, behavior or plan; `i` is an interrupt"),
    ("atom a = (drive(1 m/s), never, 1 s)\nrun a\nrun a",
     "`run` is given twice: t.mdle:2:1 and t.mdle:3:1"),
    ("atom drive = (spin(1 rad/s), never, 1 s)",
     "`drive` is already a control law; a definition cannot take its name"),
    ("atom a(v = 1 m/s, v = 2 m/s) = (drive(v), never, 1 s)",
     "parameter `v` of `a` is declared twice"),
    ("atom a = (drive(1 m/s / 0), never, 1 s)", "division by zero"),
])
def test_each_error_class(text: str, message: str, reg: Registry) -> None:
    msgs = errors(text, reg)
    assert message in msgs, msgs


def test_clash_names_both_places(reg: Registry) -> None:
    text = "atom a = (drive(1 m/s), never, 1 s)\n\natom a = (spin(1 rad/s), never, 1 s)"
    with pytest.raises(CheckError) as err:
        load_text(text, "t.mdle", reg)
    (d,) = err.value.diagnostics
    assert d.message == "`a` is defined twice: t.mdle:1:6 and t.mdle:3:6"
    assert _at(d.notes[0]).line == 1


def test_recursive_definitions(reg: Registry) -> None:
    msgs = errors("behavior a = ((b), never, inf)\nbehavior b = ((c), never, inf)\n"
                  "behavior c = ((a), never, inf)\natom self = (0.5, 1, self)\n"
                  "interrupt i = j\ninterrupt j = i or bumped", reg)
    assert "`a` is defined in terms of itself: a \u2192 b \u2192 c \u2192 a" in msgs
    assert "`self` is defined in terms of itself: self \u2192 self" in msgs
    assert "`i` is defined in terms of itself: i \u2192 j \u2192 i" in msgs


def test_several_check_errors_together(reg: Registry) -> None:
    msgs = errors("atom a = (drive(1 m), never, 1 s)\natom b = (drive(1 m/s), nope, 1 s)\n"
                  "atom c = (drive(1 m/s), never, 1 m)", reg)
    assert len(msgs) == 3


def test_errors_in_a_use_note_the_call(reg: Registry) -> None:
    with pytest.raises(CheckError) as err:
        load_text("interrupt near(d) = beam(0 deg) < d\natom a = (drive(1 m/s), near(1 s), inf)",
                  "t.mdle", reg)
    (d,) = err.value.diagnostics
    assert _at(d).line == 1 and d.notes[0].message == "in this use of `near`"
    assert _at(d.notes[0]).line == 2


def test_long_definition_chains_fail_cleanly(reg: Registry) -> None:
    n = 2000
    lines = ["atom a0 = (drive(1 m/s), never, 1 s)"]
    lines += [f"behavior a{i} = ((a{i - 1}), never, inf)" for i in range(1, n)]
    # Written last-first, so the first definition checked uses the whole chain.
    msgs = errors("\n".join(reversed(lines)), reg)
    assert any("levels deep here; mdle allows at most 120" in m for m in msgs)
    short = "\n".join(reversed(lines[:100]))
    assert len(check(short, reg).elements) == 100


def test_default_registry_plans(plans_dir: Path) -> None:
    from mdle.lang import load_program

    p = load_program(plans_dir / "language" / "tour.mdle")
    assert p.entry == "main" and not p.warnings
    spin = p.elements["spin"]
    assert isinstance(spin, AtomNode)
    assert math.isclose(float(spin.args["rate"]), math.radians(30))


def test_declared_symbols_win_over_definitions_of_the_same_name(reg: Registry) -> None:
    # A plan called `left` must not change what `side = left` means, nor make the atoms
    # that say it "defined in terms of themselves".
    p = check("atom left = (hug(side = left), gap(left) < 1 m, 5 s)\n"
              "atom right = (hug(right), never, 5 s)\n"
              "plan main = ((left, right), never, inf)", reg)
    main = p.elements["main"]
    assert isinstance(main, StringNode)
    assert [e.label for e in main.elements] == ["left", "right"]
    assert all(isinstance(e, AtomNode) for e in main.elements)
    assert [dict(e.args)["side"] for e in main.elements if isinstance(e, AtomNode)] == [
        "left", "right"]
    # Where no symbol is declared the name still means the definition.
    assert "expected a fixed value, but `left` is" in errors(
        "atom left = (hug(), never, 5 s)\natom a = (drive(left), never, 5 s)", reg)[0]


def test_long_chains_of_named_interrupts_compile_and_evaluate(
        reg: Registry, make_ctx: Callable[..., Context]) -> None:
    # Inlined, the chain is one 300-deep expression: deeper than one generated Python
    # function may nest, so the compiler splits it; the answer must not change.
    lines = ["interrupt i0 = px > 1 m"]
    lines += [f"interrupt i{i} = i{i - 1} and px < {i + 1} m" for i in range(1, 300)]
    lines.append("atom a = (drive(1 m/s), not i299, 1 s)")
    test = check("\n".join(lines), reg).elements["a"].interrupt.test
    assert test(make_ctx(x=0.5)) is True     # px > 1 m fails at the bottom of the chain
    assert test(make_ctx(x=1.5)) is False    # every link holds
