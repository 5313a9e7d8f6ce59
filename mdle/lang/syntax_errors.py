"""Syntax errors in plain words: the labelled bad-snippet table and the terminal names.

lark reports a syntax error as a parser state and an unexpected token. This module
turns that into words a robot programmer uses: :data:`EXAMPLES` maps each kind of
mistake to a few bad snippets that fail in the same parser state
(``UnexpectedInput.match_examples``), and :func:`terminal_words` names every terminal
of ``grammar/mdle.lark`` (the keywords as the grammar has them, from
:mod:`mdle.lang.vocabulary`). Each label is tested (tests/language/test_language_syntax.py).
"""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass

from mdle.lang.vocabulary import keywords, statement_keywords

__all__ = [
    "Label",
    "EXAMPLES",
    "TERMINAL_WORDS",
    "terminal_words",
    "describe_token",
    "describe_expected",
    "character_hint",
]

#: Every terminal of the grammar but the keywords, in words (messages never show a
#: terminal's name); a keyword's terminal is its word (:func:`terminal_words`).
TERMINAL_WORDS: dict[str, str] = {
    "NAME": "a name",
    "NUMBER": "a number such as `1 m` or `10 s`",
    "STRING": "a file name in double quotes",
    "COMPARE": "a comparison (`<`, `<=`, `>`, `>=`, `==`, `!=`)",
    "ADD_OP": "`+` or `-`",
    "MUL_OP": "`*` or `/`",
    "ELLIPSIS": "`...`",
    "_EQUALS": "`=`",
    "LPAR": "`(`",
    "RPAR": "`)`",
    "LSQB": "`[`",
    "RSQB": "`]`",
    "_COMMA": "`,`",
    "$END": "the end of the file",
}


def terminal_words() -> dict[str, str]:
    """Return every terminal of the grammar in words: :data:`TERMINAL_WORDS` and the keywords."""
    return {**TERMINAL_WORDS, **{terminal: f"`{word}`" for word, terminal in keywords().items()}}


@dataclass(frozen=True)
class Label:
    """What a kind of syntax error means, in words, and what would fix it."""

    message: str
    hint: str | None = None


_STATEMENT_START = Label(
    "expected a statement: every statement starts with `atom`, `behavior`, `plan`, "
    "`interrupt`, `import` or `run`",
    "a definition reads `atom NAME = (control law, interrupt, timer)`")
_UNCLOSED = Label("unbalanced parentheses: the file ends before a `(` is closed",
                  "add the missing `)`")
_EXTRA_CLOSE = Label("unbalanced parentheses: this `)` has no matching `(`",
                     "remove it, or add the `(` it closes")
_CLOSED_EARLY = Label("the definition is already complete before this: a `)` closes it too early",
                      "check the parentheses: an element is ((elements), interrupt, timer)")
_MISSING_COMMA = Label("two parts side by side: a comma or an operator is missing between them",
                       "parts of a tuple are separated by `,`; conditions are joined with "
                       "`and`, `or`, `xor`")
_MISSING_EQUALS = Label("expected `=` after the name of the definition",
                        "write `atom NAME = (control law, interrupt, timer)` or "
                        "`atom NAME(v = 0.3 m/s) = ...`")
_MISSING_BODY = Label("expected the body of the definition after `=`",
                      "an atom reads `(go(0.3 m/s), stalled, 10 s)`; a behavior "
                      "`((a, b), never, inf)`; an interrupt `range(0 deg) < 1 m`")
_MISSING_NAME = Label("expected the name of the definition after its keyword",
                      "for example `atom cruise = (go(0.3 m/s), never, inf)`")
_IMPORT = Label("expected a file name in double quotes after `import`",
                'for example `import "common.mdle"`')
_RUN = Label("expected the name of an atom, behavior or plan after `run`",
             "for example `run main`")
_ASSIGN = Label("`=` gives a default or a keyword argument; it does not compare",
                "to compare two values write `==`")
_MISSING_VALUE = Label("expected a value here: a number such as `1 m`, a name, a call or `(`")
_ELLIPSIS = Label("`...` repeats a string of elements and goes right after its closing `)`",
                  "for example `((cruise, spin)..., x > 10 m, inf)`")
_EMPTY = Label("empty parentheses: a string needs at least one element, a tuple at least "
               "one part")
_PARAM = Label("a parameter is a name with an optional default",
               "for example `atom cruise(v = 0.3 m/s) = (go(v), never, inf)`")
_ARGUMENT = Label("expected an argument: a value, or `name = value`",
                  "for example `follow_boundary(side = right, v = 0.3 m/s)`")

#: Labelled bad snippets for ``UnexpectedInput.match_examples``: each snippet fails in
#: the parser state its label describes. Order matters: the first exact match wins.
EXAMPLES: dict[Label, list[str]] = {
    _STATEMENT_START: [
        "cruise = (go(1 m/s), never, 1 s)",
        "(go(1 m/s), never, 1 s)",
        "atom a = (go(1 m/s), never, 1 s) cruise",
        "atom a = (go(1 m/s), never, 1 s) 1 s",
        "run a b",
        'import "a.mdle" b',
    ],
    _UNCLOSED: [
        "atom a = (go(1 m/s), never, 1 s",
        "atom a = ((go(1 m/s), never, 1 s)",
        "atom a = (go(1 m/s",
        "atom a = (go(1 m/s),",
        "atom a = (go(v = 1 m/s",
        "behavior b = ([1, 2",
        "behavior b = ([1, 2,",
        "atom a(v = 1 m/s",
        "atom a(v",
        "atom a(v,",
    ],
    _EXTRA_CLOSE: [
        "atom a = (go(1 m/s), never, 1 s))",
        "atom a = stalled)",
        "atom a = go())",
        "interrupt i = x > 1 m)",
    ],
    _CLOSED_EARLY: [
        "atom a = (go(1 m/s), never, 1 s), b",
        "atom a = b, c",
        "atom a = (b, never, 1 s), never, 1 s)",
        "interrupt i = x > 1 m, 2",
    ],
    _MISSING_COMMA: [
        "atom a = (go(1 m/s) never, 1 s)",
        "atom a = (go(1 m/s), stalled 1 s)",
        "atom a = (go(1 m/s), x > 1 m 1 s)",
        "atom a = ((a b), never, 1 s)",
        "atom a = ((a)(b), never, 1 s)",
        "atom a = (1 (b), never, 1 s)",
        "atom a = (go(1 m/s 2 m/s), never, 1 s)",
        "atom a = (go(v = 1 m/s 2), never, 1 s)",
        "atom a = (go(1 m/s) (x), never, 1 s)",
        "atom a = ([1 2], 1, b)",
        "atom a = (go(1 m/s), never, inf 1)",
        "atom a = (go(1 m/s), never never, 1 s)",
        "atom a(v = 1 m/s 2) = b",
        "atom a(v w) = b",
    ],
    _MISSING_EQUALS: [
        "atom a",
        "atom a (go(1 m/s), never, 1 s)",
        "atom a atom b = c",
        "atom a stalled",
        "atom a() (go(1 m/s), never, 1 s)",
        "atom a()",
    ],
    _MISSING_BODY: [
        "atom a =",
        "atom a = atom b = c",
        "atom a = run b",
        "atom a = )",
        "atom a() =",
    ],
    _MISSING_NAME: [
        "atom = (go(1 m/s), never, 1 s)",
        "atom (go(1 m/s), never, 1 s)",
        "atom",
        "behavior 1 = b",
    ],
    _IMPORT: [
        "import common.mdle",
        "import",
        "import (a)",
        "import 1",
    ],
    _RUN: [
        "run",
        'run "main"',
        "run (main)",
        "run 1",
    ],
    _ASSIGN: [
        "interrupt i = x = 1 m",
        "interrupt i = range(0 deg) = 1 m",
        "interrupt i = x + 1 m = y",
        "interrupt i = (x) = 1 m",
    ],
    _ELLIPSIS: [
        "atom a = (go(1 m/s)..., never, 1 s)",
        "atom a = (b..., never, 1 s)",
        "atom a = (b, never, 1 s...)",
        "atom a = (b, never...)",
        "atom a = [1, 2]...",
    ],
    _EMPTY: [
        "behavior b = ((), never, 1 s)",
        "behavior b = ()",
        "behavior b = []",
    ],
    _MISSING_VALUE: [
        "interrupt i = x >",
        "interrupt i = x > and y",
        "interrupt i = not",
        "interrupt i = x and",
        "interrupt i = x or or y",
        "interrupt i = x xor",
        "interrupt i = -",
        "interrupt i = x *",
        "interrupt i = x + ",
        "atom a = (go(1 m/s), , 1 s)",
        "atom a = (, b)",
        "atom a = (b, never, 1 s, , c)",
        "atom a = [1, , 2]",
        "atom a(v = ) = b",
        "atom a(v = 1 m/s, w = ) = b",
    ],
    _PARAM: [
        "atom a(1 m) = b",
        "atom a(v = 1, 2) = b",
        "atom a((v)) = b",
        "atom a(, v) = b",
    ],
    _ARGUMENT: [
        "atom a = (go(, 1), never, 1 s)",
        "atom a = (go(v = ), never, 1 s)",
        "atom a = (go(1, ,), never, 1 s)",
    ],
}


def describe_token(type_: str, value: str) -> str:
    """Describe the unexpected token in words.

    For example ``the name `foo```, ``the keyword `run```, or ``the end of the file``.
    """
    if type_ == "$END" or type_ == "<EOF>" or value == "":
        return "the end of the file"
    shown = value if len(value) <= 40 else value[:37] + "..."
    if type_ == "NAME":
        return f"the name `{shown}`"
    if type_ == "NUMBER":
        return f"the number `{shown}`"
    if type_ == "STRING":
        return f"the text {shown}"
    if value in keywords():
        return f"the keyword `{value}`"
    return f"`{shown}`"


def describe_expected(expected: set[str] | frozenset[str]) -> str:
    """Return the set of acceptable terminals in words, short enough for one line."""
    names = set(expected)
    parts: list[str] = []
    words = keywords()
    statement = {words[k] for k in statement_keywords()}
    if statement <= names:
        parts.append("a statement (" + ", ".join(f"`{k}`" for k in statement_keywords()) + ")")
        names -= statement
    operators = {"AND", "OR", "XOR", "COMPARE", "ADD_OP", "MUL_OP"}
    if len(names & operators) >= 3:
        parts.append("an operator")
        names -= operators
    values = {"NUMBER", "NAME", "LPAR"}
    if values <= names:
        parts.append("a value (a number, a name or `(`)")
        names -= values | {"NEVER", "INF", "NOT", "ADD_OP", "LSQB"}
    described = terminal_words()
    for n in sorted(names):
        parts.append(described.get(n, n.lower()))
    if not parts:
        return "nothing more"
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " or " + parts[-1]


_CHAR_HINTS = {
    "&": "join conditions with `and`",
    "|": "join conditions with `or`",
    "!": "negate a condition with `not`; `!=` means not equal",
    "'": 'file names take double quotes: `import "common.mdle"`',
    '"': "a file name in double quotes must end on the same line",
    ";": "statements need no `;`: each starts with its keyword",
    "{": "MDLe groups with parentheses `(` `)`",
    "}": "MDLe groups with parentheses `(` `)`",
    ":": "a definition reads `atom NAME = ...`",
    "^": "MDLe has no powers: multiply, as in `v * v`",
    "%": "MDLe has no remainder operator",
    "\u2264": "write `<=`",
    "\u2265": "write `>=`",
    "\u2260": "write `!=`",
    "\u00b0": "write angles as `30 deg`",
    "\u2026": "write `...` with three dots",
}


def character_hint(char: str) -> tuple[str, str | None]:
    """Describe a character no token starts with, and a hint about what was meant."""
    if char == "":
        return "the end of the file", None
    if not char.isprintable() or unicodedata.category(char).startswith("C"):
        return (f"control character U+{ord(char):04X}",
                "MDLe files are plain text: is this a binary file?")
    return f"character `{char}`", _CHAR_HINTS.get(char)
