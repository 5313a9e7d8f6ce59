"""Highlighting of MDLe input in the REPL: a small pygments lexer.

(pygments is already installed as a dependency of rich.)
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

from mdle.repl.commands import DEFINITION_KEYWORDS

__all__ = ["MdleLexer"]


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
            (words(DEFINITION_KEYWORDS, suffix=r"\b"), Keyword.Declaration),
            (words(("never", "inf"), suffix=r"\b"), Keyword.Constant),
            (words(("and", "or", "xor", "not"), suffix=r"\b"), Operator.Word),
            (r"(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", Number, "unit"),
            (r"[A-Za-z_][A-Za-z0-9_]*(?=\s*\()", Name.Function),
            (r"[A-Za-z_][A-Za-z0-9_]*", Name),
            (r"\.\.\.", Keyword),
            (r"<=|>=|==|!=|[<>+\-*/=]", Operator),
            (r"[()\[\],]", Punctuation),
            (r".", Text),
        ],
        "unit": [
            ((r"[ \t]*(?!(?:and|or|xor|not|never|inf|import|run|atom|behavior|plan|interrupt)"
              r"\b)[A-Za-z_][A-Za-z0-9_]*(?:[ \t]*/[ \t]*[A-Za-z_][A-Za-z0-9_]*)?"),
             Keyword.Type, "#pop"),
            default("#pop"),
        ],
        "command": [
            (r".+$", String, "#pop"),
            default("#pop"),
        ],
    }
