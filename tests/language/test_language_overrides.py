"""Parameter overrides (`mdle run --set NAME=VALUE`, sweeps): checker rules, located errors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mdle.core.errors import MdleError, render_diagnostic
from mdle.lang import AtomNode, StringNode, load_program
from mdle.lang.overrides import parse_override

PLAN = """\
interrupt blocked(d = 0.5 m) = range(0 deg) < d
atom cruise(v = 0.3 m/s, clear = 0.8 m) = (go(v), blocked(clear) or stalled, inf)
atom hug(side = right, rc = 1 m) = (follow_boundary(side = side, rc = rc), never, 10 s)
atom spin(rate = 30 deg/s, time = 3 s) = (turn(rate), never, time)
plan main = ((cruise, hug, spin, cruise(0.1 m/s)), never, 1 min)
run main
"""


@pytest.fixture
def plan(tmp_path: Path) -> Path:
    p = tmp_path / "plan.mdle"
    p.write_text(PLAN)
    return p


def _atoms(path: Path, *overrides: str) -> list[AtomNode]:
    main = load_program(path, settings=overrides).elements["main"]
    assert isinstance(main, StringNode)
    atoms = list(main.elements)
    assert all(isinstance(a, AtomNode) for a in atoms)
    return atoms  # type: ignore[return-value]


def _error(path: Path, *overrides: str) -> str:
    with pytest.raises(MdleError) as info:
        load_program(path, settings=overrides)
    return "\n".join(render_diagnostic(d, info.value.sources) for d in info.value.diagnostics)


def test_no_override_is_the_plain_load(plan: Path) -> None:
    cruise, hug, spin, slow = _atoms(plan)
    assert cruise.args["v"] == 0.3 and hug.args["rc"] == 1.0 and spin.timer == 3.0


def test_override_changes_the_default_in_si_and_keeps_explicit_arguments(plan: Path) -> None:
    cruise, hug, spin, slow = _atoms(plan, "cruise.v=0.2 m/s", "rc=150cm", "spin.rate=-45deg/s",
                                     "time=5 s", "side = left")
    assert cruise.args["v"] == pytest.approx(0.2)
    assert slow.args["v"] == pytest.approx(0.1)  # `cruise(0.1 m/s)` passes its own
    assert hug.args["rc"] == pytest.approx(1.5) and hug.args["side"] == "left"
    assert spin.args["rate"] == pytest.approx(math.radians(-45)) and spin.timer == 5.0


def test_override_of_an_interrupt_parameter_reaches_its_uses(plan: Path) -> None:
    # `blocked(clear)` passes cruise's own parameter, so `d`'s default is not used there:
    # overriding `cruise.clear` changes the interrupt, and the program still checks
    assert load_program(plan, settings=["clear=1.2 m", "d=0.7 m"]).entry == "main"


def test_wrong_dimension_is_located_in_the_override_with_a_note_at_the_parameter(
        plan: Path) -> None:
    text = _error(plan, "cruise.v=0.2 m")
    assert text.splitlines()[:3] == [
        "--set:1:10: error: `v` of `cruise` is a speed such as `0.3 m/s`, found a length "
        "(`0.2 m`)",
        "    cruise.v=0.2 m",
        "             ^^^^^"]
    assert f"{plan}:2:13: note: `v` of `cruise` is declared here" in text


def test_bare_number_gets_the_unit_hint(plan: Path) -> None:
    assert "hint: add a unit: `1.5 m`" in _error(plan, "rc=1.5")


def test_unknown_names_ambiguity_and_symbols(plan: Path) -> None:
    assert "no definition named `crusie`" in _error(plan, "crusie.v=1 m/s")
    assert "did you mean `cruise`?" in _error(plan, "crusie.v=1 m/s")
    assert "`cruise` has no parameter `w`" in _error(plan, "cruise.w=1 m/s")
    assert "no definition has a parameter `speed`" in _error(plan, "speed=1 m/s")
    text = _error(plan, "v=0.2 m/s", "x=1 m")
    assert "`--set#1`" not in text and "--set#2:1:1: error: no definition has a parameter `x`" \
        in text
    bad_symbol = _error(plan, "side=lfet")
    assert "--set:1:6: error: `side` of `hug` is one of `right` or `left`, found `lfet`" \
        in bad_symbol and "did you mean `left`?" in bad_symbol
    assert "takes a symbol" in _error(plan, "side=1 m")
    assert "sensor function" in _error(plan, "rc=x")


def test_a_parameter_name_alone_sets_every_definition_that_has_it(tmp_path: Path) -> None:
    p = tmp_path / "two.mdle"
    p.write_text("atom a(v = 1 m/s) = (go(v), never, 1 s)\n"
                 "atom b(v = 2 m/s) = (go(v), never, 1 s)\nplan main = ((a, b), never, inf)\n")
    a, b = _atoms(p, "v=0.5 m/s")
    assert a.args["v"] == b.args["v"] == 0.5
    a, b = _atoms(p, "b.v=0.5 m/s")
    assert (a.args["v"], b.args["v"]) == (1.0, 0.5)


def test_definitions_of_imported_files_can_be_set(tmp_path: Path) -> None:
    (tmp_path / "lib.mdle").write_text("atom cruise(v = 0.3 m/s) = (go(v), never, 1 s)\n")
    p = tmp_path / "main.mdle"
    p.write_text('import "lib.mdle"\nplan main = ((cruise), never, inf)\n')
    (cruise,) = _atoms(p, "cruise.v=0.1 m/s")
    assert cruise.args["v"] == pytest.approx(0.1)


@pytest.mark.parametrize("text, message", [
    ("v", "expected NAME=VALUE"),
    ("x y=1 m", "is not a parameter name"),
    ("v=", "no value after `v=`"),
    ("v=(1 m", "the value ends before a `(` is closed"),
])
def test_malformed_overrides_are_syntax_errors_in_their_text(text: str, message: str) -> None:
    with pytest.raises(MdleError) as info:
        parse_override(text)
    (d, *_) = info.value.diagnostics
    assert d.span is not None and d.span.file == "--set" and message in d.message
    assert info.value.sources == {"--set": text}
