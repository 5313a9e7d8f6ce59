"""The parser: each construct becomes the right syntax node, with units in SI and spans."""

from __future__ import annotations

import math

import pytest

from mdle.core.errors import Diagnostic, MdleSyntaxError, Span
from mdle.core.units import ANGLE, LENGTH, NONE, SPEED, TIME, TURN_RATE
from mdle.lang import syntax as st
from mdle.lang.parser import MAX_DEPTH, parse_expression, parse_module


def _at(d: Diagnostic) -> Span:
    """The place of a diagnostic that must have one."""
    assert d.span is not None, d.message
    return d.span


def body(text: str) -> st.Expr:
    (d,) = parse_module(text).statements
    assert isinstance(d, st.Definition)
    return d.body


@pytest.mark.parametrize("text, value, dim", [
    ("0.3 m/s", 0.3, SPEED), ("30 deg/s", math.radians(30), TURN_RATE),
    ("2 min", 120.0, TIME), ("10s", 10.0, TIME), ("250 ms", 0.25, TIME),
    ("5 cm", 0.05, LENGTH), ("300 mm", 0.3, LENGTH), ("90 deg", math.pi / 2, ANGLE),
    ("1 rad", 1.0, ANGLE), ("1.5 rad/s", 1.5, TURN_RATE), ("7", 7.0, NONE),
    ("1e-3", 0.001, NONE), (".5 m", 0.5, LENGTH), ("2 m / s", 2.0, SPEED),
])
def test_numbers_convert_to_si(text: str, value: float, dim: object) -> None:
    n = parse_expression(text)
    assert isinstance(n, st.Number)
    assert n.value == pytest.approx(value) and n.dim == dim


def test_atom_definition_with_parameters() -> None:
    (d,) = parse_module("atom cruise(v = 0.3 m/s, d) = (go(v), blocked(d), inf)").statements
    assert isinstance(d, st.Definition) and d.kind is st.DefKind.ATOM and d.name == "cruise"
    assert [p.name for p in d.param_list] == ["v", "d"]
    assert d.param_list[1].default is None
    assert d.body == st.Group((st.Call("go", (st.Argument(None, st.Name("v")),)),
                               st.Call("blocked", (st.Argument(None, st.Name("d")),)), st.Inf()))


def test_definition_without_parentheses_has_no_params() -> None:
    d = parse_module("atom a = (stop, never, 1)").statements[0]
    assert isinstance(d, st.Definition) and d.params is None
    d2 = parse_module("atom a() = (stop, never, 1)").statements[0]
    assert isinstance(d2, st.Definition) and d2.params == ()


def test_every_statement_kind() -> None:
    m = parse_module('import "common.mdle"\ninterrupt i = stalled\nbehavior b = ((a), never, inf)\n'
                     "plan main = ((b), never, inf)\nrun main")
    kinds = [type(s).__name__ if not isinstance(s, st.Definition) else s.kind.value
             for s in m.statements]
    assert kinds == ["Import", "interrupt", "behavior", "plan", "Run"]
    assert m.statements[0] == st.Import("common.mdle")


def test_keyword_arguments_and_symbols() -> None:
    e = parse_expression("follow_boundary(side = right, rc = 0.5 m)")
    assert isinstance(e, st.Call)
    assert [(a.name, type(a.value).__name__) for a in e.args] == [
        ("side", "Name"), ("rc", "Number")]


def test_repeat_and_vector() -> None:
    e = body("behavior c = ((a, b)..., x > 10 m, inf)")
    assert isinstance(e, st.Group) and isinstance(e.items[0], st.Group) and e.items[0].repeat
    v = body("behavior s = (([0.5, 1], 2, a), never, inf)")
    assert isinstance(v, st.Group) and isinstance(v.items[0], st.Group)
    assert isinstance(v.items[0].items[0], st.Vector)


def test_operator_precedence() -> None:
    e = parse_expression("not x > 1 m and y < 2 m or stalled xor t * 2 >= 3 s + 1 s")
    # or( and( not(x > 1 m), y < 2 m ), xor(stalled, (t*2) >= (3 s + 1 s)) )
    assert isinstance(e, st.Binary) and e.op == "or"
    left, right = e.left, e.right
    assert isinstance(left, st.Binary) and left.op == "and"
    assert isinstance(left.left, st.Unary) and left.left.op == "not"
    assert isinstance(right, st.Binary) and right.op == "xor"
    cmp = right.right
    assert isinstance(cmp, st.Binary) and cmp.op == ">="
    assert isinstance(cmp.left, st.Binary) and cmp.left.op == "*"
    assert isinstance(cmp.right, st.Binary) and cmp.right.op == "+"


def test_subtraction_is_left_associative_and_unary_minus() -> None:
    e = parse_expression("-a - b - c")
    assert isinstance(e, st.Binary) and isinstance(e.left, st.Binary)
    assert isinstance(e.left.left, st.Unary) and e.left.left.op == "-"


def test_spans_are_one_based_and_end_exclusive() -> None:
    m = parse_module("\n  atom cruise = (go(1 m/s), never, 10 s)", "f.mdle")
    d = m.statements[0]
    assert isinstance(d, st.Definition)
    assert d.name_span == Span("f.mdle", 2, 8, 2, 14)
    assert isinstance(d.body, st.Group)
    assert d.body.span == Span("f.mdle", 2, 17, 2, 41)
    assert d.body.items[2].span == Span("f.mdle", 2, 36, 2, 40)


def test_definitions_span_lines_freely_and_comments_are_kept() -> None:
    m = parse_module("# head\natom a = (go(1 m/s),  # why\n   never,\n   10 s)\nrun a  # go")
    assert len(m.statements) == 2
    assert [c.text for c in m.comments] == ["# head", "# why", "# go"]
    assert m.comments[1].span.line == 2


def test_keywords_are_reserved_even_where_only_a_name_fits() -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_module("atom run = (stop, never, 1 s)", "k.mdle")
    (d,) = err.value.diagnostics
    assert d.message == "`run` is a keyword of MDLe and cannot be used as a name"
    assert (_at(d).line, _at(d).column) == (1, 6)


def test_names_may_contain_keywords() -> None:
    m = parse_module("atom atomic = (stop, never, 1 s)\natom running = (stop, never, 1 s)")
    assert [s.name for s in m.definitions] == ["atomic", "running"]


def test_nesting_limit_is_a_syntax_error() -> None:
    ok = "(" * (MAX_DEPTH - 1) + "x" + ")" * (MAX_DEPTH - 1)
    parse_expression(ok)
    with pytest.raises(MdleSyntaxError, match=f"nests more than {MAX_DEPTH} levels"):
        parse_expression("(" * (MAX_DEPTH + 1) + "x" + ")" * (MAX_DEPTH + 1))
    with pytest.raises(MdleSyntaxError, match="nests more than"):
        parse_module("interrupt i = " + "not " * 1000 + "stalled")


def test_empty_and_comment_only_files_parse_to_nothing() -> None:
    assert parse_module("").statements == ()
    assert parse_module("# only a comment\n\n").statements == ()


def test_trees_compare_without_spans() -> None:
    a = parse_module("atom a = (go(1 m/s), never, 1 s)")
    b = parse_module("atom a=(go(1 m/s),\n never,1 s)")
    assert a.statements == b.statements
