"""Syntax-tree nodes from tokens: what both MDLe parsers share.

The lark parser (:mod:`mdle.lang.parser`, the reference, used for every file with an error)
and the fast recursive-descent parser (:mod:`mdle.lang.descent`, used for valid files) build
their nodes with these functions, so the two give the same tree, spans and messages.

A token here is anything with ``line``, ``column``, ``end_line``, ``end_column`` and a
``str()`` (a lark ``Token``, or :class:`Op`); a node is anything with a ``span``.
"""

from __future__ import annotations

import difflib
import functools
import math
import re
from dataclasses import dataclass, field
from typing import Any

from mdle.core.errors import Diagnostic, Span, make_span
from mdle.core.frozen import builder
from mdle.core.units import NONE, UNITS, unit_value
from mdle.lang import syntax as st

__all__ = ["MAX_DEPTH", "POWERS", "NOT_POWER", "SIGN_POWER", "COMPARISON_POWER", "COMPARISONS",
           "BuildState", "TooDeep", "Op", "Prefixed", "token_span", "over",
           "deeper", "number", "precedence", "too_deep"]

#: Deepest nesting of parentheses and operators accepted in one expression.
MAX_DEPTH = 100

_NUMBER = re.compile(r"((?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)[ \t]*(.*)", re.S)


#: Fast constructors of the nodes the parsers make most (every field given, in order).
new_number = builder(st.Number)
new_name = builder(st.Name)
new_call = builder(st.Call)
new_argument = builder(st.Argument)
new_unary = builder(st.Unary)
new_binary = builder(st.Binary)
new_group = builder(st.Group)
new_vector = builder(st.Vector)
new_param = builder(st.Param)
new_definition = builder(st.Definition)


@dataclass
class BuildState:
    """Per-parse state: file name, comments, unit errors, nesting depth of nodes."""

    file: str
    comments: list[st.Comment] = field(default_factory=list)
    diagnostics: list[Diagnostic] = field(default_factory=list)
    depth: dict[int, int] = field(default_factory=dict)
    open_brackets: int = 0
    #: Statements in the order they were completed (kept when a later one fails)
    statements: list[Any] = field(default_factory=list)


class TooDeep(Exception):
    """An expression nests deeper than :data:`MAX_DEPTH` (at ``span``)."""

    def __init__(self, span: Span) -> None:
        super().__init__("too deep")
        self.span = span


def too_deep(span: Span) -> Diagnostic:
    """Return the message for an expression nested too deeply."""
    return Diagnostic(span, f"this nests more than {MAX_DEPTH} levels deep",
                      hint="split it into named definitions")


class Op:
    """An operator token of the fast parser (text and place), as a lark Token offers them."""

    __slots__ = ("text", "line", "column", "end_line", "end_column")

    def __init__(self, text: str, line: int, column: int, end_column: int) -> None:
        self.text = text
        self.line = self.end_line = line
        self.column = column
        self.end_column = end_column

    def __str__(self) -> str:
        return self.text


class Prefixed:
    """A prefix operator and its operand as parsed, before precedence is applied."""

    __slots__ = ("op", "operand")

    def __init__(self, op: Any, operand: Any) -> None:
        self.op = op
        self.operand = operand


def token_span(file: str, tok: Any) -> Span:
    """Return the span of a token."""
    return make_span(file, tok.line or 0, tok.column or 0, tok.end_line or 0, tok.end_column or 0)


def _start(part: Any) -> tuple[int, int]:
    span = getattr(part, "span", None)
    if span is None:
        return part.line or 0, part.column or 0
    return span.line, span.column


def _end(part: Any) -> tuple[int, int]:
    span = getattr(part, "span", None)
    if span is None:
        return part.end_line or 0, part.end_column or 0
    return span.end_line, span.end_column


def over(file: str, first: Any, last: Any) -> Span:
    """Return the span from the start of ``first`` to the end of ``last`` (tokens or nodes)."""
    line, col = _start(first)
    end_line, end_col = _end(last)
    return make_span(file, line, col, end_line, end_col)


def deeper(state: BuildState, node: Any, parts: Any) -> Any:
    """Record ``node``'s nesting depth (one more than its deepest part); refuse past the limit."""
    get = state.depth.get
    depth = 1
    for p in parts:
        d = get(id(p), 1)
        if d >= depth:
            depth = d + 1
    if depth > MAX_DEPTH:
        raise TooDeep(node.span)
    if depth > 1:
        state.depth[id(node)] = depth
    return node


@functools.lru_cache(maxsize=4096)
def _split_number(token: str) -> tuple[str, str, float, Any]:
    """(digits, unit without spaces, factor to SI, dimension or None if unknown)."""
    m = _NUMBER.fullmatch(token)
    assert m is not None  # the token's own pattern guarantees the shape
    text, unit = m.group(1), m.group(2).replace(" ", "").replace("\t", "")
    if not unit:
        return text, "", 1.0, NONE
    try:
        factor, dim = unit_value(unit)
    except KeyError:
        return text, unit, 1.0, None
    return text, unit, factor, dim


def number(state: BuildState, token: str, span: Span) -> st.Number:
    """Return the node of a NUMBER token (its unit looked up; errors go to ``state``)."""
    text, unit, factor, dim = _split_number(token)
    value = float(text)
    if not math.isfinite(value):
        state.diagnostics.append(Diagnostic(span, f"the number `{text}` is too large"))
        return st.Number(0.0, NONE, text, unit, span)
    if dim is None:
        state.diagnostics.append(_unknown_unit(unit, span, text))
        return st.Number(value, NONE, text, unit, span)
    return new_number(value * factor, dim, text, unit, span)


def _unknown_unit(unit: str, span: Span, digits: str) -> Diagnostic:
    known = sorted(UNITS)
    parts = unit.split("/")
    bad = next((p for p in parts if p not in UNITS), unit)
    close = difflib.get_close_matches(bad, known, n=1, cutoff=0.5)
    hint = (f"did you mean `{close[0]}`? " if close else "") + \
        f"units are {', '.join(known)} and quotients such as m/s, deg/s"
    if len(parts) == 2 and parts[0] in UNITS and bad == parts[1]:
        # `0.4 m/v`: a tight `/` joins the unit; spaces make it a division
        hint += f"; to divide by `{bad}`, put spaces around `/`: `{digits} {parts[0]} / {bad}`"
    elif bad in ("x", "y", "v", "t") or len(parts) == 1 and bad not in UNITS and not close:
        hint += "; to multiply, write `*`"
    return Diagnostic(span, f"unknown unit `{bad}`", hint=hint)


#: Binding power of each operator (higher binds tighter); `not` sits between `and` and
#: the comparisons, as in Python, and unary minus above `*`.
POWERS = {"or": 1, "xor": 2, "and": 3, "<": 5, "<=": 5, ">": 5, ">=": 5, "==": 5, "!=": 5,
          "+": 6, "-": 6, "*": 7, "/": 7}
NOT_POWER, SIGN_POWER, COMPARISON_POWER = 4, 8, 5
COMPARISONS = frozenset({"<", "<=", ">", ">=", "==", "!="})


def precedence(state: BuildState, parts: tuple[Any, ...] | list[Any]) -> st.Expr:
    """Build the operator tree of ``unit (op unit)*`` by operator precedence.

    Shunting yard: iterative, left associative, prefix operators as in Python.
    """
    file = state.file
    operands: list[st.Expr] = []
    ops: list[tuple[int, Any, bool]] = []  # (binding power, operator, is prefix)

    def apply() -> None:
        power, tok, prefix = ops.pop()
        if prefix:
            x = operands.pop()
            operands.append(deeper(state, new_unary(str(tok), x, over(file, tok, x)), (x,)))
            return
        right = operands.pop()
        left = operands.pop()
        if power == COMPARISON_POWER and any(isinstance(side, st.Binary) and side.op in COMPARISONS
                                        for side in (left, right)):
            state.diagnostics.append(Diagnostic(
                token_span(file, tok), "comparisons do not chain",
                hint="write `0 m < x and x < 10 m`"))
        node = new_binary(str(tok), left, right, over(file, left, right), token_span(file, tok))
        operands.append(deeper(state, node, (left, right)))

    for i, part in enumerate(parts):
        if i % 2:  # a binary operator
            power = POWERS[str(part)]
            while ops and ops[-1][0] >= power:
                apply()
            ops.append((power, part, False))
            continue
        while isinstance(part, Prefixed):
            ops.append((NOT_POWER if str(part.op) == "not" else SIGN_POWER, part.op, True))
            part = part.operand
        operands.append(part)
    while ops:
        apply()
    (result,) = operands
    return result
