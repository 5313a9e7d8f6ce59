"""Hints rewritten with the user's own text, once the source of a diagnostic is known.

The parser reports some mistakes with a generic example (``comparisons do not chain``:
``write `0 m < x and x < 10 m```). Here such a hint is rewritten from the very text the
user wrote, so it can be copied as it stands:

>>> from mdle.core.errors import Diagnostic, Span
>>> text = "atom b = (go(0.3 m/s), 0 m < x < 1 m, 1 s)"
>>> d = Diagnostic(Span("t.mdle", 1, 32, 1, 33), CHAINED, hint="write `0 m < x and x < 10 m`")
>>> refine_hints([d], {"t.mdle": text})[0].hint
'write `0 m < x and x < 1 m`'
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping, Sequence

from mdle.core.errors import Diagnostic, MdleError, MdleSyntaxError, source_line

__all__ = ["CHAINED", "chained_hint", "refine_error", "refine_hints", "yaml_as_plan"]

#: The message of a chained comparison (``0 m < x < 1 m``), as the parser words it.
CHAINED = "comparisons do not chain"

_TOKEN = re.compile(r"(?P<cmp><=|>=|==|!=|<|>)|(?P<open>[(\[])|(?P<close>[)\]])|(?P<stop>,|=|#)"
                    r"|(?P<word>\b(?:and|or|xor|not)\b)")


def chained_hint(line: str, column: int) -> str | None:
    """Rewrite ``a < x < b`` as ``a < x and x < b``, from the second operator's column.

    ``line`` is the source line, ``column`` the 1-based column of the comparison the
    parser pointed at. None when the parts cannot be told apart on that line.
    """
    tokens = [(m.start(), m.end(), m.lastgroup) for m in _TOKEN.finditer(line)]
    at = next((i for i, t in enumerate(tokens) if t[0] == column - 1 and t[2] == "cmp"), None)
    if at is None:
        return None
    first = _walk(tokens, at, -1, stop_at_comparison=False)
    if first is None or tokens[first][2] != "cmp":
        return None
    begin = _walk(tokens, first, -1, stop_at_comparison=True)
    end = _walk(tokens, at, +1, stop_at_comparison=True)
    left = line[tokens[begin][1] if begin is not None else 0:tokens[first][0]].strip()
    middle = line[tokens[first][1]:tokens[at][0]].strip()
    right = line[tokens[at][1]:tokens[end][0] if end is not None else len(line)].strip()
    if not (left and middle and right):
        return None
    op1 = line[tokens[first][0]:tokens[first][1]]
    op2 = line[tokens[at][0]:tokens[at][1]]
    return f"write `{left} {op1} {middle} and {middle} {op2} {right}`"


def _walk(tokens: list[tuple[int, int, str | None]], start: int, step: int,
          stop_at_comparison: bool) -> int | None:
    """Index of the first token from ``start`` (excluded) that ends the operand at depth 0.

    A comparison ends it (the next comparison, when not ``stop_at_comparison``, is what is
    looked for); so do a comma, ``=``, ``and``/``or``/``xor``/``not``, a comment and an
    unmatched bracket. None: the line's end.
    """
    depth = 0
    i = start + step
    opens, closes = ("open", "close") if step > 0 else ("close", "open")
    while 0 <= i < len(tokens):
        kind = tokens[i][2]
        if kind == opens:
            depth += 1
        elif kind == closes:
            if depth == 0:
                return i
            depth -= 1
        elif depth == 0 and kind in ("stop", "word", "cmp"):
            return i
        i += step
    return None


def refine_hints(diagnostics: Sequence[Diagnostic], sources: Mapping[str, str]
                 ) -> list[Diagnostic]:
    """Return the diagnostics with the hints rewritten in the user's text where possible."""
    out = []
    for d in diagnostics:
        if d.message == CHAINED and d.span is not None and d.span.file in sources:
            line = source_line(sources[d.span.file], d.span.line)
            hint = chained_hint(line, d.span.column) if line is not None else None
            if hint is not None:
                d = dataclasses.replace(d, hint=hint)
        out.append(d)
    return out


def refine_error(err: MdleError, sources: Mapping[str, str]) -> MdleError:
    """Return an error of the same class with its hints refined (``err`` if none changed)."""
    refined = refine_hints(err.diagnostics, {**sources, **err.sources})
    if refined == list(err.diagnostics):
        return err
    new = type(err)(refined, {**err.sources, **sources} if err.sources else None)
    return new


def yaml_as_plan(path: str, err: MdleError, instead: str) -> MdleError:
    """Turn the syntax errors of a YAML file read as a plan into one message saying so.

    ``instead`` is the hint: how to use the file as a world (``mdle run PLAN.mdle
    --world FILE``). Any other error, or a file not named ``.yaml``/``.yml``, is ``err``.
    """
    if not path.lower().endswith((".yaml", ".yml")) or not isinstance(err, MdleSyntaxError):
        return err
    return MdleSyntaxError(Diagnostic(
        None, f"`{path}` is a YAML file (a world file?), not an MDLe plan",
        hint=instead))
