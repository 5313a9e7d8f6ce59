"""Highlighting of MDLe input in the REPL: a small pygments lexer.

(pygments is already installed as a dependency of rich.) The keywords are the grammar's.
"""

from __future__ import annotations

from typing import Any, ClassVar

from pygments.lexer import RegexLexer, default, words
from pygments.token import (
    Comment,
    Keyword,
    Name,
    Number,
    Operator,
    Punctuation,
    String,
    Text,
    Whitespace,
)

from mdle.lang import keywords, operator_keywords, statement_keywords

__all__ = ["MdleLexer"]

_STATEMENTS = statement_keywords()
_OPERATORS = operator_keywords()
#: The other keywords stand for values (`never`, `inf`).
_CONSTANTS = tuple(k for k in keywords() if k not in _STATEMENTS and k not in _OPERATORS)


class MdleLexer(RegexLexer):
    """Pygments lexer for MDLe text and the REPL's ``:`` commands."""

    name = "MDLe"
    aliases: ClassVar[list[str]] = ["mdle"]
    filenames: ClassVar[list[str]] = ["*.mdle"]

    tokens: ClassVar[dict[str, list[Any]]] = {
        "root": [
            (r"^\s*:[a-z]+", Name.Builtin, "command"),
            (r"#.*?$", Comment.Single),
            (r"\s+", Whitespace),
            (r'"[^"\n]*"', String),
            (words(_STATEMENTS, suffix=r"\b"), Keyword.Declaration),
            (words(_CONSTANTS, suffix=r"\b"), Keyword.Constant),
            (words(_OPERATORS, suffix=r"\b"), Operator.Word),
            (r"(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", Number, "unit"),
            (r"[A-Za-z_][A-Za-z0-9_]*(?=\s*\()", Name.Function),
            (r"[A-Za-z_][A-Za-z0-9_]*", Name),
            (r"\.\.\.", Keyword),
            (r"<=|>=|==|!=|[<>+\-*/=]", Operator),
            (r"[()\[\],]", Punctuation),
            (r".", Text),
        ],
        "unit": [
            ((r"[ \t]*(?!(?:" + "|".join(keywords()) +
              r")\b)[A-Za-z_][A-Za-z0-9_]*(?:[ \t]*/[ \t]*[A-Za-z_][A-Za-z0-9_]*)?"),
             Keyword.Type, "#pop"),
            default("#pop"),
        ],
        "command": [
            (r".+$", String, "#pop"),
            default("#pop"),
        ],
    }
