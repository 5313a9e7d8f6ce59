"""Parameter overrides (``--set NAME=VALUE``): new defaults in the main file's definitions."""

from __future__ import annotations

import pytest

from mdle.core.errors import CheckError
from mdle.lang import AtomNode, Program, load_text


def atom(p: Program, name: str) -> AtomNode:
    node = p.elements[name]
    assert isinstance(node, AtomNode)
    return node

PLAN = """\
atom follow(rc = 1 m, side = right, kf = 0.5) =
    (follow_boundary(side = side, rc = rc, kf = kf), never, 5 s)
plan main = ((follow), stalled, inf)
"""


def test_a_bare_number_follows_the_checkers_unit_rules() -> None:
    # a plain number fits a plain default (kf); where metres are meant it is an error
    # with the unit to add, as everywhere in MDLe (a plan never guesses units)
    p = load_text(PLAN, settings={"rc": "80 cm", "kf": "2"})
    assert atom(p, "follow").args["rc"] == pytest.approx(0.8)
    assert atom(p, "follow").args["kf"] == 2.0
    with pytest.raises(CheckError) as err:
        load_text(PLAN, settings={"rc": "80"})
    (d,) = err.value.diagnostics
    assert d.hint == "add a unit: `80 m`" and d.span is not None and d.span.file == "--set"


def test_symbols_and_the_elements_that_use_the_definition_follow() -> None:
    p = load_text(PLAN, settings={"side": "left"})
    main = p.elements["main"]
    assert main.elements[0].args["side"] == "left"  # type: ignore[union-attr]


def test_an_unknown_name_lists_the_parameters() -> None:
    with pytest.raises(CheckError) as err:
        load_text(PLAN, settings={"rcc": "1"})
    d = err.value.diagnostics[0]
    assert "no definition" in d.message and "`rcc`" in d.message
    assert d.hint is not None and "`rc`" in d.hint


def test_a_value_of_the_wrong_dimension_is_a_check_error() -> None:
    with pytest.raises(CheckError) as err:
        load_text(PLAN, settings={"rc": "2 s"})
    assert "rc" in str(err.value)


def test_a_value_that_does_not_parse_names_the_setting() -> None:
    with pytest.raises(CheckError) as err:
        load_text(PLAN, settings={"rc": "1 m m"})
    (d,) = err.value.diagnostics
    assert d.span is not None and (d.span.file, d.span.column) == ("--set", 8)
    assert err.value.sources["--set"] == "rc=1 m m"
