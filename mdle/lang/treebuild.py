"""The tree builder: lark's LALR parser of ``grammar/mdle.lark``, and the callbacks making nodes.

lark calls :class:`_Build`'s methods as the LALR parser reduces each rule, so the tree is
built during parsing, without recursion (1 MB of parentheses cannot exhaust the stack);
a nesting limit of :data:`MAX_DEPTH` keeps the later recursive stages safe. The state of
one parse (file name, comments, unit errors, nesting depths, the statements completed so
far) is a :class:`BuildState` that :mod:`mdle.lang.parser` sets in :data:`PARSE_STATE`
around each call.

The grammar is read once through :mod:`importlib.resources` (it ships inside the
package as ``mdle.grammar``), and lark's analysed parser (its LALR tables) is cached in a
per-user file (``$XDG_CACHE_HOME/mdle``, else ``~/.cache/mdle``) named by a hash of the
grammar and lark's version, so ``mdle check`` does not rebuild the tables at every start.
lark checks the cache's hash when it loads it, and rebuilds and rewrites it when the hash
does not fit or the file is corrupt; a folder it cannot write only costs the rebuild.
"""

from __future__ import annotations

import contextvars
import difflib
import functools
import hashlib
import importlib.resources
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import lark
from lark import Lark, Token, Transformer, v_args

from mdle.core.errors import Diagnostic, Span
from mdle.core.units import NONE, UNITS, unit_value
from mdle.lang import syntax as st

__all__ = ["MAX_DEPTH", "POWERS", "PREFIX_POWERS", "COMPARISONS", "BuildState", "PARSE_STATE",
           "TooDeep", "Prefixed", "lark_parser", "token_span", "over", "deeper",
           "number", "precedence", "too_deep"]

#: Deepest nesting of parentheses and operators accepted in one expression.
MAX_DEPTH = 100

_NUMBER = re.compile(r"((?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)[ \t]*(.*)", re.S)


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


class Prefixed:
    """A prefix operator and its operand as parsed, before precedence is applied."""

    __slots__ = ("op", "operand")

    def __init__(self, op: Token, operand: Any) -> None:
        self.op = op
        self.operand = operand


def token_span(file: str, tok: Any) -> Span:
    """Return the span of a token."""
    return Span(file, tok.line or 0, tok.column or 0, tok.end_line or 0, tok.end_column or 0)


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
    return Span(file, line, col, end_line, end_col)


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
    return st.Number(value * factor, dim, text, unit, span)


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


#: Binding power of each binary operator terminal (higher binds tighter): the order of
#: ``_binary_op``'s alternatives in the grammar, loosest first (a test checks it).
POWERS = {"OR": 1, "XOR": 2, "AND": 3, "COMPARE": 5, "ADD_OP": 6, "MUL_OP": 7}
#: Binding power of each prefix operator terminal (``prefixed`` in the grammar): `not`
#: sits between `and` and the comparisons, as in Python, and a sign above `*`.
PREFIX_POWERS = {"NOT": 4, "ADD_OP": 8}
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
            operands.append(deeper(state, st.Unary(str(tok), x, over(file, tok, x)), (x,)))
            return
        right = operands.pop()
        left = operands.pop()
        if power == POWERS["COMPARE"] and any(isinstance(side, st.Binary) and side.op in COMPARISONS
                                        for side in (left, right)):
            state.diagnostics.append(Diagnostic(
                token_span(file, tok), "comparisons do not chain",
                hint="write `0 m < x and x < 10 m`"))
        node = st.Binary(str(tok), left, right, over(file, left, right), token_span(file, tok))
        operands.append(deeper(state, node, (left, right)))

    for i, part in enumerate(parts):
        if i % 2:  # a binary operator
            power = POWERS[part.type]
            while ops and ops[-1][0] >= power:
                apply()
            ops.append((power, part, False))
            continue
        while isinstance(part, Prefixed):
            ops.append((PREFIX_POWERS[part.op.type], part.op, True))
            part = part.operand
        operands.append(part)
    while ops:
        apply()
    (result,) = operands
    return result


# --------------------------------------------------------------------------------------
# The state of the parse under way, and the lexer's callbacks

#: The :class:`BuildState` of the parse under way (set by :mod:`mdle.lang.parser` around
#: each call, so concurrent parses in threads or tasks never share one).
PARSE_STATE: contextvars.ContextVar[BuildState] = contextvars.ContextVar("mdle_parse_state")


def _on_comment(token: Token) -> None:
    state = PARSE_STATE.get(None)
    if state is not None:
        state.comments.append(st.Comment(str(token), token_span(state.file, token)))


def _on_open(token: Token) -> Token:
    # Refuse deep nesting as soon as it is lexed: 1 MB of `(` fails in microseconds.
    state = PARSE_STATE.get(None)
    if state is not None:
        state.open_brackets += 1
        if state.open_brackets > MAX_DEPTH:
            raise TooDeep(token_span(state.file, token))
    return token


def _on_close(token: Token) -> Token:
    state = PARSE_STATE.get(None)
    if state is not None and state.open_brackets > 0:
        state.open_brackets -= 1
    return token


# --------------------------------------------------------------------------------------
# The callbacks of the rules, called as the LALR parser reduces them


@v_args(inline=True)
class _Build(Transformer):
    """Builds :mod:`mdle.lang.syntax` nodes as the LALR parser reduces each rule.

    One method per rule or alias of the grammar. The lexer gives a keyword its own
    terminal wherever it stands, so a keyword never reaches a method as a name.
    """

    def start(self, *statements: st.Statement) -> tuple[st.Statement, ...]:
        return statements

    def expr_start(self, expr: st.Expr) -> st.Expr:
        return expr

    def import_stmt(self, kw: Token, path: Token) -> st.Import:
        state = PARSE_STATE.get()
        node = st.Import(str(path)[1:-1], over(state.file, kw, path))
        state.statements.append(node)
        return node

    def run_stmt(self, kw: Token, name: Token) -> st.Run:
        state = PARSE_STATE.get()
        node = st.Run(str(name), over(state.file, kw, name), token_span(state.file, name))
        state.statements.append(node)
        return node

    def def_head(self, kw: Token, name: Token, params: list[Any] | None
                 ) -> tuple[Token, Token, list[Any] | None]:
        return kw, name, params

    def definition(self, head: tuple[Token, Token, list[Any] | None],
                   body: st.Expr) -> st.Definition:
        kw, name, params = head
        state = PARSE_STATE.get()
        node = st.Definition(st.DefKind(str(kw)), str(name),
                             None if params is None else tuple(params[1:-1]), body,
                             over(state.file, kw, body), token_span(state.file, name))
        state.statements.append(node)
        return node

    def params(self, *parts: Any) -> list[Any]:
        return list(parts)  # (LPAR, params..., RPAR): the brackets are dropped by `definition`

    def param(self, name: Token, default: st.Expr | None = None) -> st.Param:
        file = PARSE_STATE.get().file
        return st.Param(str(name), default, over(file, name, default if default else name))

    def number(self, tok: Token) -> st.Number:
        state = PARSE_STATE.get()
        return number(state, str(tok), token_span(state.file, tok))

    def name(self, tok: Token) -> st.Name:
        return st.Name(str(tok), token_span(PARSE_STATE.get().file, tok))

    def never(self, tok: Token) -> st.Never:
        return st.Never(token_span(PARSE_STATE.get().file, tok))

    def inf(self, tok: Token) -> st.Inf:
        return st.Inf(token_span(PARSE_STATE.get().file, tok))

    def call(self, name: Token, lpar: Token, args: list[st.Argument] | None,
             rpar: Token) -> st.Call:
        state = PARSE_STATE.get()
        args = args or []
        node = st.Call(str(name), tuple(args), over(state.file, name, rpar),
                       token_span(state.file, name))
        return deeper(state, node, [a.value for a in args])

    def arguments(self, *args: Any) -> list[st.Argument]:
        return [a if isinstance(a, st.Argument) else st.Argument(None, a, a.span) for a in args]

    def keyword(self, name: Token, value: st.Expr) -> st.Argument:
        return st.Argument(str(name), value, over(PARSE_STATE.get().file, name, value))

    def prefixed(self, op: Token, operand: Any) -> Prefixed:
        return Prefixed(op, operand)

    def expr(self, *parts: Any) -> st.Expr:
        if len(parts) == 1 and not isinstance(parts[0], Prefixed):
            return parts[0]
        return precedence(PARSE_STATE.get(), parts)

    def group(self, lpar: Token, *parts: Any) -> st.Group:
        state = PARSE_STATE.get()
        *items, rpar, ellipsis = parts
        node = st.Group(tuple(items), ellipsis is not None,
                        over(state.file, lpar, ellipsis if ellipsis is not None else rpar))
        return deeper(state, node, items)

    def vector(self, lsqb: Token, *parts: Any) -> st.Vector:
        state = PARSE_STATE.get()
        *items, rsqb = parts
        return deeper(state, st.Vector(tuple(items), over(state.file, lsqb, rsqb)), items)


# --------------------------------------------------------------------------------------
# The parser (once per process; the analysed tables are cached on disk)


def _cache_file(grammar: str) -> str | None:
    """Return a per-user cache file for the analysed grammar (None: nowhere to write)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    key = hashlib.sha256(f"{grammar}{lark.__version__}".encode()).hexdigest()[:16]
    folder = Path(base) / "mdle"
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        if not os.access(folder, os.W_OK):
            return None
    except OSError:
        return None
    return str(folder / f"grammar-{key}.lark-cache")


@functools.lru_cache(maxsize=1)
def lark_parser() -> Lark:
    """Return the LALR parser of ``mdle.lark``, built once per process (tables cached per user)."""
    grammar = importlib.resources.files("mdle.grammar").joinpath("mdle.lark").read_text("utf-8")
    options: dict[str, Any] = dict(parser="lalr", lexer="basic", propagate_positions=False,
                                   start=["start", "expr_start"], maybe_placeholders=True,
                                   transformer=_Build(),
                                   lexer_callbacks={"COMMENT": _on_comment, "LPAR": _on_open,
                                                    "LSQB": _on_open, "RPAR": _on_close,
                                                    "RSQB": _on_close})
    cache = _cache_file(grammar)
    try:
        return Lark(grammar, cache=cache or False, **options)
    except OSError:  # an unreadable or unwritable cache: build without it
        return Lark(grammar, **options)
