"""The fast path for valid files: a recursive-descent parser over a one-regex lexer.

lark's LALR parser (:mod:`mdle.parser`) is the reference: it defines what is valid and
says what is wrong, in words, when something is not. It costs several microseconds of
Python per token, though, and most files are valid. This module parses the same
grammar (``grammar/mdle.lark``) by recursive descent, builds the same nodes with the
same spans (:mod:`mdle.treebuild`), and gives up (:func:`parse_valid` returns None)
at the first thing it does not expect: a syntax error, an unknown unit, a number too
large, nesting past :data:`~mdle.treebuild.MAX_DEPTH`. The caller then parses the file
with lark, which reports every error exactly as before. So this parser never reports
anything and never decides what is valid; tests check that both parsers give equal
trees and spans on every plan they are given.

The lexer is one regular expression made of lark's own terminal patterns, in lark's
order, so both parsers see the same tokens.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Sequence
from typing import Any

from mdle.errors import Span, make_span
from mdle.lang import syntax as st
from mdle.lang.treebuild import (
    MAX_DEPTH,
    BuildState,
    Op,
    Prefixed,
    TooDeep,
    deeper,
    new_argument,
    new_call,
    new_definition,
    new_group,
    new_name,
    new_param,
    new_vector,
    number,
    over,
    precedence,
)

__all__ = ["Lexer", "parse_valid"]

# (type, text, line, column, end column): no token spans a line break.
_Token = tuple[str, str, int, int, int]

_BINARY = frozenset({"OR", "XOR", "AND", "COMPARE", "ADD_OP", "MUL_OP"})
_PREFIX = frozenset({"NOT", "ADD_OP"})
_KINDS = {"ATOM": st.DefKind.ATOM, "BEHAVIOR": st.DefKind.BEHAVIOR, "PLAN": st.DefKind.PLAN,
          "INTERRUPT": st.DefKind.INTERRUPT}


class _GiveUp(Exception):
    """The text is not plainly valid: let the reference parser read it."""


class Lexer:
    """One regular expression of the grammar's terminals (lark's ``Terminal`` objects).

    Keywords, whose patterns are plain words, are not alternatives of their own: a
    ``NAME`` equal to one becomes that keyword, as lark's basic lexer does.
    """

    def __init__(self, terminals: Sequence[Any]) -> None:
        names = next(t for t in terminals if t.name == "NAME")
        word = re.compile(names.pattern.to_regexp())
        self.keywords: dict[str, str] = {}
        groups = []
        for t in terminals:
            regexp = t.pattern.to_regexp()
            if t.pattern.type == "str" and word.fullmatch(t.pattern.value):
                self.keywords[t.pattern.value] = t.name
                continue
            groups.append(f"(?P<{t.name}>{regexp})")
        # Spaces before a token are matched with it: one match per token, not two.
        self.pattern = re.compile("[ \t\f\r]*(?:" + "|".join(groups) + ")")

    def tokens(self, text: str, file: str, comments: list[st.Comment]) -> Iterator[_Token]:
        """Yield the tokens of ``text``, then ``$END`` forever; comments go to ``comments``.

        Raises _GiveUp at a character no token starts with, and when more than
        :data:`MAX_DEPTH` brackets are open.
        """
        match = self.pattern.match
        keywords = self.keywords
        count = text.count
        pos, line, line_start, size, opened = 0, 1, 0, len(text), 0
        while pos < size:
            m = match(text, pos)
            if m is None:
                raise _GiveUp
            kind: str = m.lastgroup  # type: ignore[assignment]  # a group always matched
            end = m.end()
            if kind == "WHITESPACE":
                lines = count("\n", pos, end)
                if lines:
                    line += lines
                    line_start = text.rindex("\n", pos, end) + 1
                pos = end
                continue
            value = m.group(kind)
            column = end - len(value) - line_start + 1
            end_column = end - line_start + 1
            pos = end
            if kind == "NAME":
                kind = keywords.get(value, "NAME")
            elif kind == "COMMENT":
                comments.append(st.Comment(value, make_span(file, line, column, line, end_column)))
                continue
            elif kind == "LPAR" or kind == "LSQB":
                opened += 1
                if opened > MAX_DEPTH:
                    raise _GiveUp
            elif (kind == "RPAR" or kind == "RSQB") and opened:
                opened -= 1
            yield kind, value, line, column, end_column
        column = pos - line_start + 1
        while True:  # a parser looking past the end keeps finding it
            yield "$END", "", line, column, column


class _Descent:
    """Recursive descent over the token stream; every method starts at its first token."""

    def __init__(self, tokens: Iterator[_Token], state: BuildState) -> None:
        self.state = state
        self.file = state.file
        self.pull = tokens.__next__
        self.tok: _Token = self.pull()
        self.ahead: _Token | None = None

    def advance(self) -> _Token:
        """Move to the next token; return the one left."""
        tok = self.tok
        if self.ahead is not None:
            self.tok, self.ahead = self.ahead, None
        else:
            self.tok = self.pull()
        return tok

    def expect(self, kind: str) -> _Token:
        if self.tok[0] != kind:
            raise _GiveUp
        return self.advance()

    def span(self, tok: _Token) -> Span:
        return make_span(self.file, tok[2], tok[3], tok[2], tok[4])

    # ------------------------------------------------------------------ statements

    def module(self) -> list[st.Statement]:
        out: list[st.Statement] = []
        while True:
            kind = self.tok[0]
            if kind in _KINDS:
                out.append(self.definition())
            elif kind == "IMPORT":
                kw = self.advance()
                path = self.expect("STRING")
                out.append(st.Import(path[1][1:-1], make_span(self.file, kw[2], kw[3], path[2],
                                                         path[4])))
            elif kind == "RUN":
                kw = self.advance()
                name = self.expect("NAME")
                out.append(st.Run(name[1], make_span(self.file, kw[2], kw[3], name[2], name[4]),
                                  self.span(name)))
            elif kind == "$END":
                return out
            else:
                raise _GiveUp

    def definition(self) -> st.Definition:
        kw = self.advance()
        name = self.expect("NAME")
        params = self.params() if self.tok[0] == "LPAR" else None
        self.expect("_EQUALS")
        body = self.expr()
        end = body.span
        return new_definition(_KINDS[kw[0]], name[1], params, body,
                             make_span(self.file, kw[2], kw[3], end.end_line, end.end_column),
                             self.span(name))

    def params(self) -> tuple[st.Param, ...]:
        self.advance()
        out: list[st.Param] = []
        if self.tok[0] == "RPAR":
            self.advance()
            return ()
        while True:
            name = self.expect("NAME")
            default = None
            if self.tok[0] == "_EQUALS":
                self.advance()
                default = self.expr()
            last = default.span if default is not None else self.span(name)
            out.append(new_param(name[1], default, make_span(self.file, name[2], name[3],
                                                       last.end_line, last.end_column)))
            kind = self.tok[0]
            if kind == "_COMMA":
                self.advance()
                if self.tok[0] == "RPAR":
                    self.advance()
                    return tuple(out)
            elif kind == "RPAR":
                self.advance()
                return tuple(out)
            else:
                raise _GiveUp

    # ------------------------------------------------------------------ expressions

    def expr(self) -> st.Expr:
        first = self.unit()
        if self.tok[0] not in _BINARY:
            return first if not isinstance(first, Prefixed) else precedence(self.state, (first,))
        parts: list[Any] = [first]
        while self.tok[0] in _BINARY:
            op = self.advance()
            parts.append(Op(op[1], op[2], op[3], op[4]))
            parts.append(self.unit())
        return precedence(self.state, parts)

    def unit(self) -> Any:
        if self.tok[0] not in _PREFIX:
            return self.primary()
        ops = []
        while self.tok[0] in _PREFIX:
            op = self.advance()
            ops.append(Op(op[1], op[2], op[3], op[4]))
        node: Any = self.primary()
        for op_ in reversed(ops):
            node = Prefixed(op_, node)
        return node

    def primary(self) -> st.Expr:
        tok = self.advance()
        kind = tok[0]
        if kind == "NAME":
            if self.tok[0] == "LPAR":
                return self.call(tok)
            return new_name(tok[1], self.span(tok))
        if kind == "NUMBER":
            return number(self.state, tok[1], self.span(tok))
        if kind == "LPAR":
            items = self.items("RPAR")
            close = self.advance()
            if self.tok[0] == "ELLIPSIS":
                close = self.advance()
                repeat = True
            else:
                repeat = False
            return deeper(self.state, new_group(tuple(items), repeat, make_span(
                self.file, tok[2], tok[3], close[2], close[4])), items)
        if kind == "LSQB":
            items = self.items("RSQB")
            close = self.advance()
            return deeper(self.state, new_vector(tuple(items), make_span(
                self.file, tok[2], tok[3], close[2], close[4])), items)
        if kind == "NEVER":
            return st.Never(self.span(tok))
        if kind == "INF":
            return st.Inf(self.span(tok))
        raise _GiveUp

    def items(self, close: str) -> list[st.Expr]:
        """``expr (, expr)* ,?`` up to ``close``, which is left as the current token."""
        out = [self.expr()]
        while True:
            kind = self.tok[0]
            if kind == "_COMMA":
                self.advance()
                if self.tok[0] == close:
                    return out
                out.append(self.expr())
            elif kind == close:
                return out
            else:
                raise _GiveUp

    def call(self, name: _Token) -> st.Call:
        self.advance()
        args: list[st.Argument] = []
        if self.tok[0] != "RPAR":
            while True:
                args.append(self.argument())
                kind = self.tok[0]
                if kind == "_COMMA":
                    self.advance()
                    if self.tok[0] == "RPAR":
                        break
                elif kind == "RPAR":
                    break
                else:
                    raise _GiveUp
        close = self.advance()
        node = new_call(name[1], tuple(args),
                       make_span(self.file, name[2], name[3], close[2], close[4]),
                       self.span(name))
        return deeper(self.state, node, [a.value for a in args])

    def argument(self) -> st.Argument:
        if self.tok[0] == "NAME":
            if self.ahead is None:
                self.ahead = self.pull()
            if self.ahead[0] == "_EQUALS":
                name = self.advance()
                self.advance()
                value = self.expr()
                return new_argument(name[1], value, over(self.file, _At(name), value))
        value = self.expr()
        return new_argument(None, value, value.span)


class _At:
    """A token's place, as :func:`mdle.treebuild.over` reads it."""

    __slots__ = ("line", "column", "end_line", "end_column")

    def __init__(self, tok: _Token) -> None:
        self.line = self.end_line = tok[2]
        self.column = tok[3]
        self.end_column = tok[4]


def parse_valid(text: str, file: str, lexer: Lexer
                ) -> tuple[list[st.Statement], list[st.Comment]] | None:
    """Return the statements and comments of a valid text, or None if it is not plainly valid.

    None means: parse it with the reference parser, which says what is wrong.
    """
    state = BuildState(file)
    try:
        parser = _Descent(lexer.tokens(text, file, state.comments), state)
        statements = parser.module()
    except (_GiveUp, TooDeep, RecursionError):
        return None
    if state.diagnostics:
        return None
    return statements, state.comments
