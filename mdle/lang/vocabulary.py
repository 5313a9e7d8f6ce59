"""MDLe's words, read from the grammar: keywords, statement keywords, operators.

``grammar/mdle.lark`` is the only definition of MDLe's syntax; the parser's error
messages and recovery, and the REPL's highlighting and completion, take its words from
here, which reads them from lark's own objects of the grammar (the terminals and rules
of :func:`~mdle.lang.treebuild.lark_parser`), so no list of keywords is written twice.
Each answer is computed once per process.
"""

from __future__ import annotations

import functools
import re

from mdle.lang.treebuild import lark_parser

__all__ = ["keywords", "word_of", "definition_keywords", "statement_keywords",
           "operator_keywords", "binary_operators", "prefix_operators"]


@functools.lru_cache(maxsize=1)
def keywords() -> dict[str, str]:
    """Return every keyword of MDLe, by its word: the name of its terminal, in the grammar's order.

    A keyword is a terminal whose pattern is a plain word that ``NAME`` would match too;
    lark's lexer gives such a word the keyword's terminal wherever it stands, so a keyword
    can name nothing.
    """
    terminals = lark_parser().terminals
    name = next(t for t in terminals if t.name == "NAME")
    word = re.compile(name.pattern.to_regexp())
    return {t.pattern.value: t.name for t in terminals
            if t.pattern.type == "str" and word.fullmatch(t.pattern.value)}


def word_of(terminal: str) -> str:
    """Return the word of a keyword's terminal (``"IMPORT"`` -> ``"import"``)."""
    return next(word for word, name in keywords().items() if name == terminal)


def _alternatives(rule: str) -> list[list[str]]:
    """Return the symbols of each alternative of a rule, in the grammar's order."""
    return [[s.name for s in r.expansion] for r in lark_parser().rules if r.origin.name == rule]


def _first(symbol: str, seen: frozenset[str] = frozenset()) -> list[str]:
    """Return the terminals a rule can start with, in the grammar's order."""
    out: list[str] = []
    for r in lark_parser().rules:
        if r.origin.name != symbol or not r.expansion:
            continue
        head = r.expansion[0]
        found = [head.name] if head.is_term else (
            [] if head.name in seen else _first(head.name, seen | {symbol}))
        out += [t for t in found if t not in out]
    return out


@functools.lru_cache(maxsize=1)
def definition_keywords() -> tuple[str, ...]:
    """Return the keywords a definition starts with (``_def_kind``): ``atom``, ``behavior``..."""
    return tuple(word_of(t) for t in _first("_def_kind"))


@functools.lru_cache(maxsize=1)
def statement_keywords() -> tuple[str, ...]:
    """Return the keywords a statement starts with: the definitions' first, then the others.

    (The order messages list them in.)
    """
    others = [word_of(t) for t in _first("_statement")]
    return definition_keywords() + tuple(w for w in others if w not in definition_keywords())


@functools.lru_cache(maxsize=1)
def binary_operators() -> tuple[str, ...]:
    """Return the terminals of the binary operators (``_binary_op``), loosest first."""
    return tuple(t for (t,) in _alternatives("_binary_op"))


@functools.lru_cache(maxsize=1)
def prefix_operators() -> tuple[str, ...]:
    """Return the terminals of the prefix operators (the alternatives of ``unit`` they start)."""
    return tuple(e[0] for e in _alternatives("unit") if len(e) == 2)


@functools.lru_cache(maxsize=1)
def operator_keywords() -> tuple[str, ...]:
    """Return the keywords that are operators (``and``, ``or``, ``xor``, ``not``)."""
    operators = set(binary_operators()) | set(prefix_operators())
    return tuple(word for word, terminal in keywords().items() if terminal in operators)
