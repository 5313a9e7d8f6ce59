"""The fast path for valid files: a recursive-descent parser over a one-regex lexer.

lark's LALR parser (:mod:`mdle.lang.parser`) is the reference: it defines what is valid and
says what is wrong, in words, when something is not. It costs several microseconds of
Python per token, though, and most files are valid. This module parses the same
grammar (``grammar/mdle.lark``) by recursive descent, builds the same nodes with the
same spans (:mod:`mdle.lang.treebuild`), and gives up (:func:`parse_valid` returns None)
at the first thing it does not expect: a syntax error, an unknown unit, a number too
large, nesting past :data:`~mdle.lang.treebuild.MAX_DEPTH`. The caller then parses the file
with lark, which reports every error exactly as before. So this parser never reports
anything and never decides what is valid; tests check that both parsers give equal
trees and spans on every plan they are given.

The lexer is one regular expression made of lark's own terminal patterns, in lark's
order, so both parsers see the same tokens.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Sequence
from typing import Any, TypeVar

from mdle.core.errors import Span, make_span
from mdle.lang import syntax as st
from mdle.lang.treebuild import (
    COMPARISON_POWER,
    COMPARISONS,
    MAX_DEPTH,
    NOT_POWER,
    POWERS,
    SIGN_POWER,
    BuildState,
    TooDeep,
    new_argument,
    new_binary,
    new_call,
    new_definition,
    new_group,
    new_name,
    new_number,
    new_param,
    new_unary,
    new_vector,
    number,
)

__all__ = ["Lexer", "parse_valid"]

# (type, text, line, column, end column): no token spans a line break.
_Token = tuple[str, str, int, int, int]

_KINDS = {"ATOM": st.DefKind.ATOM, "BEHAVIOR": st.DefKind.BEHAVIOR, "PLAN": st.DefKind.PLAN,
          "INTERRUPT": st.DefKind.INTERRUPT}


#: Tokens the lexer does more than pass on: skipped ones, and brackets (counted).
_QUIET = frozenset({"WHITESPACE", "COMMENT", "LPAR", "LSQB", "RPAR", "RSQB"})
#: Characters of text the lexer splits at once (then a line break at the latest)
_CHUNK = 1 << 16


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
        groups: list[str] = []
        regexps: list[str] = []
        for t in terminals:
            regexp = t.pattern.to_regexp()
            if t.pattern.type == "str" and word.fullmatch(t.pattern.value):
                self.keywords[t.pattern.value] = t.name
                continue
            groups.append(f"(?P<{t.name}>{regexp})")
            regexps.append(regexp)
        #: Every terminal a group of its own, named (spaces before a token go with it)
        self.pattern = re.compile("[ \t\f\r]*(?:" + "|".join(groups) + ")")
        #: The same terminals in one group, and the spaces before them in another:
        #: ``findall`` splits a text into (spaces, token) pairs
        self.split = re.compile("([ \t\f\r]*)(" + "|".join(f"(?:{r})" for r in regexps) + ")")

    def tokens(self, text: str, file: str, comments: list[st.Comment]) -> Iterator[_Token]:
        """Yield the tokens of ``text``, then ``$END`` forever; comments go to ``comments``.

        Raises _GiveUp at a character no token starts with, and when more than
        :data:`MAX_DEPTH` brackets are open.
        """
        kinds: dict[str, str] = {}  # a token's kind by its text: the same text, the same kind
        kind_of = kinds.get
        findall = self.split.findall
        line, column, opened, size, pos = 1, 1, 0, len(text), 0
        while pos < size:
            # The text in chunks ending after a line break (only whitespace spans one),
            # each split into (spaces, token) pairs at C speed.
            stop = text.find("\n", pos + _CHUNK)
            stop = size if stop < 0 else stop + 1
            for spaces, value in findall(text, pos, stop):
                if spaces:
                    column += len(spaces)
                    pos += len(spaces)
                pos += len(value)
                end = column + len(value)
                kind = kind_of(value)
                if kind is None:
                    kind = kinds[value] = self.kind(value)
                if kind in _QUIET:
                    if kind == "WHITESPACE":
                        lines = value.count("\n")
                        if lines:
                            line += lines
                            end = len(value) - value.rindex("\n")
                    elif kind == "COMMENT":
                        comments.append(st.Comment(value, make_span(file, line, column, line,
                                                                    end)))
                    elif kind == "LPAR" or kind == "LSQB":
                        opened += 1
                        if opened > MAX_DEPTH:
                            raise _GiveUp
                        yield kind, value, line, column, end
                    else:
                        if opened:
                            opened -= 1
                        yield kind, value, line, column, end
                else:
                    yield kind, value, line, column, end
                column = end
            if pos != stop:  # findall skipped a character no token starts with
                raise _GiveUp
        while True:  # a parser looking past the end keeps finding it
            yield "$END", "", line, column, column

    def kind(self, value: str) -> str:
        """Return the kind of a token's text: the terminal the lexer's pattern matches it as.

        A keyword's text is the keyword (a ``NAME`` equal to one becomes it, as in lark).
        """
        m = self.pattern.fullmatch(value)
        if m is None or m.lastgroup is None:  # cannot be: the text was matched as a token
            raise _GiveUp
        return self.keywords.get(value, m.lastgroup)


_Binary = st.Binary
_N = TypeVar("_N", st.Group, st.Vector, st.Call)
_new = tuple.__new__  # a Span in one C call (make_span without the Python call)
_power = POWERS.get  # by the token's text: no other token's text is an operator's


class _Descent:
    """Recursive descent over the token stream; every method starts at its first token.

    Hot paths move to the next token inline (``self.tok = self.pull()``) and make spans
    with :func:`~mdle.core.errors.make_span` of the tokens' places.
    """

    def __init__(self, tokens: Iterator[_Token], state: BuildState) -> None:
        self.state = state
        self.file = state.file
        #: The nesting depth of the node a method has just returned (as
        #: :func:`~mdle.lang.treebuild.deeper` counts it: a name or a number is 1)
        self.d = 1
        self.pull = tokens.__next__
        self.tok: _Token = self.pull()
        #: NUMBER tokens read so far: (value in SI, dimension, digits, unit)
        self.numbers: dict[str, tuple[float, Any, str, str]] = {}

    def expect(self, kind: str) -> _Token:
        tok = self.tok
        if tok[0] != kind:
            raise _GiveUp
        self.tok = self.pull()
        return tok

    def span(self, tok: _Token) -> Span:
        return _new(Span, (self.file, tok[2], tok[3], tok[2], tok[4]))

    # ------------------------------------------------------------------ statements

    def module(self) -> list[st.Statement]:
        out: list[st.Statement] = []
        file = self.file
        while True:
            kw = self.tok
            kind = kw[0]
            if kind in _KINDS:
                out.append(self.definition())
                continue
            if kind == "$END":
                return out
            self.tok = self.pull()
            if kind == "IMPORT":
                path = self.expect("STRING")
                out.append(st.Import(path[1][1:-1], _new(Span, (file, kw[2], kw[3], path[2],
                                                              path[4]))))
            elif kind == "RUN":
                name = self.expect("NAME")
                out.append(st.Run(name[1], _new(Span, (file, kw[2], kw[3], name[2], name[4])),
                                  self.span(name)))
            else:
                raise _GiveUp

    def definition(self) -> st.Definition:
        kw = self.tok
        self.tok = self.pull()
        name = self.expect("NAME")
        params = self.params() if self.tok[0] == "LPAR" else None
        self.expect("_EQUALS")
        body = self.binary(0)
        end = body.span
        return new_definition(_KINDS[kw[0]], name[1], params, body,
                              _new(Span, (self.file, kw[2], kw[3], end[3], end[4])),
                              self.span(name))

    def params(self) -> tuple[st.Param, ...]:
        self.tok = self.pull()
        out: list[st.Param] = []
        if self.tok[0] == "RPAR":
            self.tok = self.pull()
            return ()
        while True:
            name = self.expect("NAME")
            default = None
            if self.tok[0] == "_EQUALS":
                self.tok = self.pull()
                default = self.binary(0)
                last = default.span
                end_line, end_column = last[3], last[4]
            else:
                end_line, end_column = name[2], name[4]
            out.append(new_param(name[1], default, _new(Span, (self.file, name[2], name[3],
                                                             end_line, end_column))))
            kind = self.tok[0]
            if kind == "_COMMA":
                self.tok = self.pull()
                if self.tok[0] == "RPAR":
                    self.tok = self.pull()
                    return tuple(out)
            elif kind == "RPAR":
                self.tok = self.pull()
                return tuple(out)
            else:
                raise _GiveUp

    # ------------------------------------------------------------------ expressions

    def binary(self, limit: int, first: st.Expr | None = None) -> st.Expr:
        """Parse ``unit (op unit)*`` with every operator binding tighter than ``limit``.

        Precedence climbing, left associative: the tree :func:`~mdle.lang.treebuild.precedence`
        builds from the same tokens (a prefix operator takes the operators that bind
        tighter than itself, as there). ``first`` is the first unit, when already read
        (its depth in ``self.d``).
        """
        file = self.file
        if first is not None:
            left, dl = first, self.d
        else:  # a name or a number, read here: most operands are one of those
            tok = self.tok
            kind = tok[0]
            if kind == "NAME":
                self.tok = self.pull()
                if self.tok[0] == "LPAR":
                    left = self.call(tok)
                    dl = self.d
                else:
                    left = new_name(tok[1], _new(Span, (file, tok[2], tok[3], tok[2], tok[4])))
                    dl = 1
            elif kind == "NUMBER":
                self.tok = self.pull()
                known = self.numbers.get(tok[1])
                if known is None:
                    left = self.number(tok)
                else:
                    left = new_number(known[0], known[1], known[2], known[3],
                                      _new(Span, (file, tok[2], tok[3], tok[2], tok[4])))
                dl = 1
            else:
                left = self.unit()
                dl = self.d
        while True:
            op = self.tok
            power = _power(op[1])
            if power is None or power <= limit:
                self.d = dl
                return left
            self.tok = self.pull()
            right = self.binary(power)
            if power == COMPARISON_POWER and (
                    type(left) is _Binary and left.op in COMPARISONS
                    or type(right) is _Binary and right.op in COMPARISONS):
                raise _GiveUp  # "comparisons do not chain": the reference says so
            a, b = left.span, right.span
            left = new_binary(op[1], left, right, _new(Span, (file, a[1], a[2], b[3], b[4])),
                              _new(Span, (file, op[2], op[3], op[2], op[4])))
            dr = self.d
            dl = (dl if dl > dr else dr) + 1
            if dl > MAX_DEPTH:
                raise TooDeep(left.span)

    def unit(self) -> st.Expr:
        op = self.tok
        kind = op[0]
        if kind != "NOT" and kind != "ADD_OP":
            return self.primary()
        self.tok = self.pull()
        x = self.binary(NOT_POWER if kind == "NOT" else SIGN_POWER)
        b = x.span
        node = new_unary(op[1], x, _new(Span, (self.file, op[2], op[3], b[3], b[4])))
        self.d += 1
        if self.d > MAX_DEPTH:
            raise TooDeep(node.span)
        return node

    def primary(self) -> st.Expr:
        """Parse a primary; its depth goes to ``self.d``."""
        tok = self.tok
        self.tok = self.pull()
        kind = tok[0]
        if kind == "NAME":
            if self.tok[0] == "LPAR":
                return self.call(tok)
            self.d = 1
            return new_name(tok[1], _new(Span, (self.file, tok[2], tok[3], tok[2], tok[4])))
        if kind == "NUMBER":
            self.d = 1
            return self.number(tok)
        if kind == "LPAR":
            items = self.items("RPAR")
            close = self.tok
            self.tok = self.pull()
            if self.tok[0] == "ELLIPSIS":
                close = self.tok
                self.tok = self.pull()
                repeat = True
            else:
                repeat = False
            return self.deeper(new_group(items, repeat, _new(Span, (
                self.file, tok[2], tok[3], close[2], close[4]))))
        if kind == "LSQB":
            items = self.items("RSQB")
            close = self.tok
            self.tok = self.pull()
            return self.deeper(new_vector(items, _new(Span, (
                self.file, tok[2], tok[3], close[2], close[4]))))
        self.d = 1
        if kind == "NEVER":
            return st.Never(self.span(tok))
        if kind == "INF":
            return st.Inf(self.span(tok))
        raise _GiveUp

    def deeper(self, node: _N) -> _N:
        """Return ``node``, one level deeper than its deepest part (``self.d``, set so)."""
        self.d += 1
        if self.d > MAX_DEPTH:
            raise TooDeep(node.span)
        return node

    def number(self, tok: _Token) -> st.Number:
        span = _new(Span, (self.file, tok[2], tok[3], tok[2], tok[4]))
        known = self.numbers.get(tok[1])
        if known is not None:
            return new_number(known[0], known[1], known[2], known[3], span)
        errors = len(self.state.diagnostics)
        node = number(self.state, tok[1], span)
        if len(self.state.diagnostics) > errors:
            raise _GiveUp  # an unknown unit or a number too large: the reference says so
        self.numbers[tok[1]] = (node.value, node.dim, node.text, node.unit)
        return node

    def items(self, close: str) -> tuple[st.Expr, ...]:
        """``expr (, expr)* ,?`` up to ``close``, which is left as the current token.

        The deepest item's depth goes to ``self.d``.
        """
        out = [self.binary(0)]
        deepest = self.d
        while True:
            kind = self.tok[0]
            if kind == "_COMMA":
                self.tok = self.pull()
                if self.tok[0] == close:
                    break
                out.append(self.binary(0))
                if self.d > deepest:
                    deepest = self.d
            elif kind == close:
                break
            else:
                raise _GiveUp
        self.d = deepest
        return tuple(out)

    def call(self, name: _Token) -> st.Call:
        """Parse a call from its ``(``; its depth goes to ``self.d``."""
        self.tok = self.pull()
        args: list[st.Argument] = []
        deepest = 0
        if self.tok[0] != "RPAR":
            while True:
                args.append(self.argument())
                if self.d > deepest:
                    deepest = self.d
                kind = self.tok[0]
                if kind == "_COMMA":
                    self.tok = self.pull()
                    if self.tok[0] == "RPAR":
                        break
                elif kind == "RPAR":
                    break
                else:
                    raise _GiveUp
        close = self.tok
        self.tok = self.pull()
        node = new_call(name[1], tuple(args),
                        _new(Span, (self.file, name[2], name[3], close[2], close[4])),
                        self.span(name))
        if not args:
            self.d = 1
            return node
        self.d = deepest
        return self.deeper(node)

    def argument(self) -> st.Argument:
        """Parse an argument; its value's depth goes to ``self.d``."""
        tok = self.tok
        if tok[0] != "NAME":
            value = self.binary(0)
            return new_argument(None, value, value.span)
        # A name: a keyword argument's, or the first of an expression.
        self.tok = self.pull()
        if self.tok[0] == "_EQUALS":
            self.tok = self.pull()
            value = self.binary(0)
            end = value.span
            return new_argument(tok[1], value, _new(Span, (self.file, tok[2], tok[3], end[3],
                                                         end[4])))
        if self.tok[0] == "LPAR":
            first: st.Expr = self.call(tok)
        else:
            first = new_name(tok[1], self.span(tok))
            self.d = 1
        value = self.binary(0, first)
        return new_argument(None, value, value.span)


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
