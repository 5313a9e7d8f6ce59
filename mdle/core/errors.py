"""Errors and diagnostics shared by every stage of mdle.

Diagnostics are data (:class:`Diagnostic`), rendered by one function
(:func:`render_diagnostic`) as ``file:line:col: severity: message``, the source line
and a caret. Each stage raises its own :class:`MdleError` subclass; the CLI shows any
``MdleError`` as diagnostics and treats every other exception as an internal error.
"""

from __future__ import annotations

import enum
import functools
import re
from dataclasses import dataclass
from typing import NamedTuple

__all__ = [
    "Span",
    "Severity",
    "Diagnostic",
    "MdleError",
    "MdleSyntaxError",
    "CheckError",
    "WorldError",
    "MdleRuntimeError",
    "BackendError",
    "render_diagnostic",
    "source_line",
]


class Span(NamedTuple):
    """A place in a source file: 1-based line and column, end exclusive.

    ``file`` is the path as the user named it (or ``<repl>``, ``<string>``). A named
    tuple, not a dataclass: a parser makes one per token and node, and a tuple is made
    in one C call and takes a third of the memory of an object with a ``__dict__``.
    """

    file: str
    line: int
    column: int
    end_line: int
    end_column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


class Severity(enum.Enum):
    """How serious a diagnostic is."""

    ERROR = "error"
    """The program cannot run."""
    WARNING = "warning"
    """The program runs, but probably not as meant (an unreachable element, say)."""
    NOTE = "note"
    """Extra context attached to another diagnostic (the other place of a clash)."""


@dataclass(frozen=True)
class Diagnostic:
    """One message about one place: what is wrong, where, and what would help.

    ``hint`` is a short suggestion (``did you mean `follow_boundary`?``); ``notes``
    are further diagnostics pointing at related places.
    """

    span: Span | None
    message: str
    severity: Severity = Severity.ERROR
    hint: str | None = None
    notes: tuple["Diagnostic", ...] = ()


class MdleError(Exception):
    """Base of every error mdle reports to a user; carries one or more diagnostics."""

    def __init__(self, diagnostics: Diagnostic | list[Diagnostic] | tuple[Diagnostic, ...] | str,
                 sources: dict[str, str] | None = None):
        #: File texts by name, so the CLI can show the source line under each diagnostic.
        self.sources: dict[str, str] = dict(sources or {})
        if isinstance(diagnostics, str):
            diagnostics = Diagnostic(None, diagnostics)
        if isinstance(diagnostics, Diagnostic):
            diagnostics = (diagnostics,)
        self.diagnostics: tuple[Diagnostic, ...] = tuple(diagnostics)
        super().__init__("\n".join(_one_line(d) for d in self.diagnostics))


class MdleSyntaxError(MdleError):
    """The text is not MDLe: a token or construct the grammar does not allow."""


class CheckError(MdleError):
    """The program parses but is not valid: unknown names, wrong units, cycles..."""


class WorldError(MdleError):
    """A world file (YAML) is malformed or inconsistent."""


class MdleRuntimeError(MdleError):
    """A program failed while running (not a robot fault: see BackendError)."""


class BackendError(MdleError):
    """The robot or its connection failed: no answer, dropped link, stale data, refused."""


def _one_line(d: Diagnostic) -> str:
    where = f"{d.span}: " if d.span else ""
    return f"{where}{d.severity.value}: {d.message}"


#: Characters shown as a space in a quoted source line: a tab, and the characters
#: Python's ``splitlines`` (and terminals) take as line breaks, which in MDLe are not.
_BLANKS = {ord(c): " " for c in "\t\r\v\f\x1c\x1d\x1e\x85\u2028\u2029"}


@functools.lru_cache(maxsize=8)
def _line_starts(text: str) -> tuple[int, ...]:
    r"""Return the offset of each line of ``text`` (lines end at ``\n`` only, as in MDLe)."""
    return (0, *(m.end() for m in re.finditer("\n", text)))


def source_line(text: str, line: int) -> str | None:
    r"""Return line ``line`` (1-based) of ``text`` without its newline; None past the end.

    Lines end at ``\n`` only, as the parser counts them (a form feed or U+2028 is not a
    line break). The line offsets of a text are computed once, so rendering thousands of
    diagnostics of a large file stays linear.
    """
    starts = _line_starts(text)
    if not 1 <= line <= len(starts):
        return None
    begin = starts[line - 1]
    end = starts[line] - 1 if line < len(starts) else len(text)
    if begin == len(text) and line > 1:
        return None  # the empty "line" after a final newline
    return text[begin:end]


def render_diagnostic(d: Diagnostic, sources: dict[str, str] | None = None) -> str:
    """Render a diagnostic as plain text: header, source line, caret, hint, notes.

    ``sources`` maps file names to their text; without the text, only the header and
    hint are shown.

    >>> s = Span("a.mdle", 1, 5, 1, 8)
    >>> print(render_diagnostic(Diagnostic(s, "unknown name `foo`", hint="did you mean `go`?"),
    ...                         {"a.mdle": "run foo"}))
    a.mdle:1:5: error: unknown name `foo`
        run foo
            ^^^
      hint: did you mean `go`?
    """
    lines = [_one_line(d)]
    text = (sources or {}).get(d.span.file) if d.span else None
    if d.span is not None and text is not None:
        found = source_line(text, d.span.line)
        if found is not None:
            raw = found.translate(_BLANKS)
            col = max(1, min(d.span.column, len(raw) + 1))
            width = 1
            if d.span.end_line == d.span.line and d.span.end_column > col:
                width = d.span.end_column - col
            # Long lines (a 1 MB one-liner) are cut to a window around the column.
            start = max(0, col - 80) if len(raw) > 160 else 0
            shown = raw[start:start + 160]
            if start:
                shown, col = "... " + shown, col - start + 4
            width = max(1, min(width, len(shown) - col + 1))
            if start + 160 < len(raw):
                shown += " ..."
            lines.append("    " + shown)
            lines.append("    " + " " * (col - 1) + "^" * width)
    if d.hint:
        lines.append(f"  hint: {d.hint}")
    for note in d.notes:
        lines.extend("  " + ln for ln in render_diagnostic(note, sources).splitlines())
    return "\n".join(lines)
