"""Text to syntax tree: parsing with lark's LALR parser, error recovery, and errors in words.

Over 500 lines: besides parsing whole files, expressions and fragments (with the parser
and tree builder of :mod:`mdle.lang.treebuild`), it recovers from syntax errors and words
them, and both work on lark's error objects and parser state, which no other module sees.

Syntax errors become :class:`~mdle.core.errors.MdleSyntaxError` with file, line, column,
the source line, a caret, what was expected in words and a hint; after an error the
parser resynchronises at the next line that starts with a statement keyword, so
several errors in one file are reported together.
"""

from __future__ import annotations

import difflib
import functools
import re
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from lark import Token
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from mdle.core.errors import Diagnostic, MdleSyntaxError, Severity, Span
from mdle.lang import syntax as st
from mdle.lang.syntax_errors import (
    EXAMPLES,
    Label,
    character_hint,
    describe_expected,
    describe_token,
)
from mdle.lang.treebuild import (
    MAX_DEPTH,
    PARSE_STATE,
    BuildState,
    TooDeep,
    lark_parser,
    over,
    token_span,
    too_deep,
)
from mdle.lang.vocabulary import definition_keywords, keywords, statement_keywords, word_of

__all__ = ["parse_module", "parse_partial", "Partial", "parse_expression", "normalise_newlines",
           "MAX_DEPTH", "MAX_ERRORS", "lark_parser", "iter_tokens", "lex_fragment"]

#: Syntax errors reported per file before giving up.
MAX_ERRORS = 20


@functools.lru_cache(maxsize=1)
def _statement_line() -> re.Pattern[str]:
    """Return the pattern of a line starting with a statement keyword (a resumption point)."""
    return re.compile(r"^[ \t]*(?:" + "|".join(statement_keywords()) + r")(?![A-Za-z0-9_])", re.M)


@functools.lru_cache(maxsize=1)
def _statement_tokens() -> frozenset[str]:
    """Return the terminals a statement starts with."""
    return frozenset(keywords()[word] for word in statement_keywords())


def _end(file: str, part: Any) -> tuple[int, int]:
    span = over(file, part, part)
    return span.end_line, span.end_column


# --------------------------------------------------------------------------------------
# Public entry points


def normalise_newlines(text: str) -> str:
    r"""Return ``text`` with ``\r\n`` and a lone ``\r`` (old Mac files) made ``\n``.

    Lines are counted at ``\n`` only, so a file with another line ending would be one
    long line 1 in every message.
    """
    if "\r" not in text:
        return text
    return text.replace("\r\n", "\n").replace("\r", "\n")


def parse_module(text: str, file: str = "<string>") -> st.Module:
    """Parse a whole file of MDLe.

    Parameters
    ----------
    text : str
        The source text.
    file : str
        The name diagnostics show (the path as the user wrote it).

    Returns
    -------
    Module
        The statements in order, with the comments (for the formatter).

    Raises
    ------
    MdleSyntaxError
        Every syntax error found (up to :data:`MAX_ERRORS`), and every unknown unit.
    """
    text = normalise_newlines(text)
    statements, comments, diagnostics = _parse_with_recovery(text, file)
    if diagnostics:
        raise MdleSyntaxError(_sorted(diagnostics), {file: text})
    return st.Module(file, tuple(statements), tuple(comments))


@dataclass(frozen=True)
class Partial:
    """What :func:`parse_partial` makes of a file: the good statements and the errors."""

    module: st.Module
    """The statements that parsed without an error (all of them for a valid file)."""
    unparsed: frozenset[str]
    """Names defined by statements left out for their errors."""
    diagnostics: tuple[Diagnostic, ...]
    """Every syntax error (as :func:`parse_module` raises them), in order."""
    broken_import: bool = False
    """An ``import`` is among the statements left out: any name may be missing."""


def parse_partial(text: str, file: str = "<string>") -> Partial:
    """Parse a file, keeping the statements that parse when others do not.

    After a syntax error the parser resumes at the next statement, so every
    independent error is found; the statements before and between the errors are kept,
    so the checker can report their errors in the same pass. A statement holding an
    error (a broken one, or one with an unknown unit) is left out, and the name it
    defines is listed in ``unparsed`` so its uses are not reported as unknown.
    """
    text = normalise_newlines(text)
    statements, comments, diagnostics = _parse_with_recovery(text, file)
    if not diagnostics:
        return Partial(st.Module(file, tuple(statements), tuple(comments)), frozenset(), ())
    places = [(d.span.line, d.span.column) for d in diagnostics if d.span is not None]
    kept = [s for s in statements if not any(_inside(s.span, place) for place in places)]
    names, imports = _defined_outside(text, kept, comments)
    return Partial(st.Module(file, tuple(kept), tuple(comments)), names,
                   tuple(_sorted(diagnostics)), imports)


def _inside(span: Span, place: tuple[int, int]) -> bool:
    return (span.line, span.column) <= place < (span.end_line, span.end_column)


@functools.lru_cache(maxsize=1)
def _definition_head() -> re.Pattern[str]:
    """Return the pattern of a definition's keyword and the name after it."""
    return re.compile(r"(?<![A-Za-z0-9_])(?:" + "|".join(definition_keywords()) +
                      r")[ \t\f\n]+([A-Za-z_][A-Za-z0-9_]*)")


@functools.lru_cache(maxsize=1)
def _import_word() -> re.Pattern[str]:
    """Return the pattern of the keyword of an import statement, as a word."""
    return re.compile(r"(?<![A-Za-z0-9_])" + word_of("IMPORT") + r"(?![A-Za-z0-9_])")


def _defined_outside(text: str, statements: list[st.Statement],
                     comments: list[st.Comment]) -> tuple[frozenset[str], bool]:
    """Return the names after a definition keyword outside the given statements and comments.

    And whether the keyword ``import`` stands there too.
    """
    starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def offset(line: int, column: int) -> int:
        return starts[line - 1] + column - 1 if 0 < line <= len(starts) else len(text)

    taken = sorted((offset(x.span.line, x.span.column), offset(x.span.end_line, x.span.end_column))
                   for x in [*statements, *comments])
    rest, at = [], 0
    for begin, end in taken:
        rest.append(text[at:max(at, begin)])
        at = max(at, end)
    rest.append(text[at:])
    names = {m.group(1) for piece in rest for m in _definition_head().finditer(piece)}
    return frozenset(names - keywords().keys()), any(_import_word().search(piece) for piece in rest)


def parse_expression(text: str, file: str = "<repl>") -> st.Expr:
    """Parse one expression: a bare element such as ``cruise`` or ``(go(1 m/s), never, 2 s)``.

    Raises
    ------
    MdleSyntaxError
        If the text is not one expression.
    """
    state = BuildState(file)
    token = PARSE_STATE.set(state)
    try:
        expr = lark_parser().parse(text, start="expr_start")
    except UnexpectedInput as err:
        raise MdleSyntaxError(_describe(err, text, file, "expr_start"), {file: text}) from None
    except TooDeep as err:
        raise MdleSyntaxError(too_deep(err.span), {file: text}) from None
    finally:
        PARSE_STATE.reset(token)
    if state.diagnostics:
        raise MdleSyntaxError(_sorted(state.diagnostics), {file: text})
    return expr  # type: ignore[return-value]


def _sorted(diags: list[Diagnostic]) -> list[Diagnostic]:
    seen: set[tuple[Any, str]] = set()
    out = []
    for d in sorted(diags, key=lambda d: (d.span.line, d.span.column) if d.span else (0, 0)):
        key = (d.span, d.message)
        if key not in seen:
            seen.add(key)
            out.append(d)
    return out


def _parse_with_recovery(text: str, file: str
                         ) -> tuple[list[st.Statement], list[st.Comment], list[Diagnostic]]:
    """Parse, resuming after each syntax error.

    After an error, blank out what came before and resume at the next line that starts
    with a statement keyword (positions stay exact).
    """
    parser = lark_parser()
    diagnostics: list[Diagnostic] = []
    comments: list[st.Comment] = []
    statements: list[st.Statement] = []
    source = text
    errors = 0
    while True:
        state = BuildState(file)
        token = PARSE_STATE.set(state)
        resume_at: int | None = None
        try:
            parser.parse(source, start="start")
        except UnexpectedInput as err:
            diagnostics.append(_describe(err, text, file, "start", source))
            errors += 1
            resume_at = _resume_offset(source, err)
        except TooDeep as err:
            diagnostics.append(too_deep(err.span))
            errors += 1
            resume_at = _resume_offset(source, None, err.span)
        finally:
            PARSE_STATE.reset(token)
        comments.extend(state.comments)
        diagnostics.extend(state.diagnostics)
        statements.extend(state.statements)  # those completed before an error too
        if resume_at is None or errors >= MAX_ERRORS:
            break
        # Keep newlines so every later line and column is where it was.
        source = re.sub(r"[^\n]", " ", text[:resume_at]) + text[resume_at:]
    comments.sort(key=lambda c: (c.span.line, c.span.column))
    unique = {(c.span.line, c.span.column): c for c in comments}
    return statements, list(unique.values()), diagnostics


def _error_offset(source: str, err: UnexpectedInput | None, span: Span | None) -> int:
    if err is not None:
        if isinstance(err, UnexpectedEOF):
            return len(source)
        if isinstance(err, UnexpectedToken) and err.token.type == "$END":
            return len(source)
        pos = getattr(err, "pos_in_stream", None)
        if pos is None and isinstance(err, UnexpectedToken):
            pos = err.token.start_pos
        return int(pos) if pos is not None and pos >= 0 else len(source)
    assert span is not None
    return _offset_of(source, span.end_line, span.end_column)


def _offset_of(text: str, line: int, column: int) -> int:
    offset = 0
    for _ in range(line - 1):
        nl = text.find("\n", offset)
        if nl < 0:
            return len(text)
        offset = nl + 1
    return min(len(text), offset + column - 1)


def _resume_offset(source: str, err: UnexpectedInput | None,
                   span: Span | None = None) -> int | None:
    at = _error_offset(source, err, span)
    tok = getattr(err, "token", None)
    if isinstance(err, UnexpectedToken) and tok is not None and tok.type in _statement_tokens() \
            and tok.start_pos is not None and tok.start_pos > 0 \
            and not source[source.rfind("\n", 0, tok.start_pos) + 1:tok.start_pos].strip():
        return int(tok.start_pos)  # the statement that interrupted the broken one is fine
    line_end = source.find("\n", at)
    if line_end < 0:
        return None
    m = _statement_line().search(source, line_end)
    return m.start() if m else None


# --------------------------------------------------------------------------------------
# Syntax errors in words


def _example_parse(start: str) -> Any:
    def parse(snippet: str) -> Any:
        token = PARSE_STATE.set(BuildState("<example>"))
        try:
            return lark_parser().parse(snippet, start=start)
        finally:
            PARSE_STATE.reset(token)
    return parse


def _end_span(text: str, file: str) -> Span:
    lines = text.split("\n")
    # Point just after the last non-blank character.
    for i in range(len(lines) - 1, -1, -1):
        if lines[i].strip():
            col = len(lines[i].rstrip()) + 1
            return Span(file, i + 1, col, i + 1, col + 1)
    return Span(file, 1, 1, 1, 2)


def _unclosed(text: str, file: str) -> Span | None:
    """Where the innermost `(` or `[` still open at the end of the text was opened."""
    stack: list[Token] = []
    for tok in iter_tokens(text):
        if tok.type in ("LPAR", "LSQB"):
            stack.append(tok)
        elif tok.type in ("RPAR", "RSQB") and stack:
            stack.pop()
    return token_span(file, stack[-1]) if stack else None


def _describe(err: UnexpectedInput, text: str, file: str, start: str,
              source: str | None = None) -> Diagnostic:
    """Turn a lark error into a diagnostic: where, what, what was expected, a hint."""
    source = text if source is None else source
    if isinstance(err, UnexpectedCharacters):
        span = Span(file, err.line, err.column, err.line, err.column + 1)
        pos = err.pos_in_stream if err.pos_in_stream is not None else -1
        char = source[pos] if 0 <= pos < len(source) else ""
        what, hint = character_hint(char)
        if char == '"':
            return Diagnostic(span, "unterminated file name: the closing `\"` is missing on this "
                              "line", hint=hint)
        return Diagnostic(span, f"unexpected {what}", hint=hint)

    at_end = isinstance(err, UnexpectedEOF) or (
        isinstance(err, UnexpectedToken) and err.token.type == "$END")
    if at_end:
        span = _end_span(source, file)
        found = "the end of the file"
    else:
        tok = err.token  # type: ignore[attr-defined]
        span = token_span(file, tok)
        found = describe_token(tok.type, str(tok))
        stack = getattr(getattr(err, "state", None), "value_stack", None) or []
        if tok.type in _statement_tokens() and stack:
            # The next statement began before this one was complete: point just after
            # the last thing this one has, where the missing part belongs.
            line, col = _end(file, stack[-1])
            if line:
                span = Span(file, line, col, line, col + 1)
    expected = set(getattr(err, "expected", None) or getattr(err, "accepts", None) or ())
    if isinstance(err, UnexpectedToken) and err.accepts:
        expected = set(err.accepts)
    expected.discard("$END") if not at_end else None

    # A keyword where a name was expected: say so directly.
    if not at_end and "NAME" in expected and "NUMBER" not in expected and \
            str(err.token) in keywords():  # type: ignore[attr-defined]
        word = str(err.token)  # type: ignore[attr-defined]
        span = token_span(file, err.token)  # type: ignore[attr-defined]
        return Diagnostic(span, f"`{word}` is a keyword of MDLe and cannot be used as a name",
                          hint=f"pick another name, such as `{word}_1`")

    label = _label(err, source, start)
    notes: tuple[Diagnostic, ...] = ()
    if at_end:
        opened = _unclosed(source, file)
        if opened is not None:
            notes = (Diagnostic(opened, "this `(` is not closed", Severity.NOTE),)
            label = Label("unbalanced parentheses: the file ends before a `(` is closed",
                          "add the missing `)`")
    expected_words = describe_expected(expected)
    if label is not None:
        message = f"{label.message} (found {found})"
        hint = label.hint or f"expected {expected_words}"
    else:
        message = "unexpected end of the file" if at_end else f"unexpected {found}"
        hint = f"expected {expected_words}"
    if found.startswith("the name") and "NAME" not in expected:
        close = _close_keyword(str(err.token), expected)  # type: ignore[attr-defined]
        if close:
            hint = f"did you mean `{close}`?"
    return Diagnostic(span, message, hint=hint, notes=notes)


def _label(err: UnexpectedInput, source: str, start: str) -> Label | None:
    """Return the label of the bad snippet that fails like this error, if any.

    lark compares parser states including the stack depth, and the examples are lone
    statements; so the failing statement is parsed again alone (what precedes it
    blanked out) and that error is matched. An expression (REPL) is matched as the
    body of a definition.
    """
    probe: UnexpectedInput | None = err
    if start == "expr_start":
        probe = _fail(_example_parse("start"), "atom a = " + source)
    else:
        stack = [v[0] if isinstance(v, tuple) and v and isinstance(v[0], Token) else v
                 for v in getattr(getattr(err, "state", None), "value_stack", None) or []]
        first = next((i for i, v in enumerate(stack) if isinstance(v, Token)
                      and v.type in _statement_tokens()), None)
        if first is not None and first > 0 and stack[first].start_pos is not None:
            at = stack[first].start_pos
            probe = _fail(_example_parse("start"), re.sub(r"[^\n]", " ", source[:at]) + source[at:])
    if probe is None or getattr(probe, "state", None) is None:
        return None
    return _match(probe)


@functools.lru_cache(maxsize=1)
def _example_errors() -> tuple[tuple[Label, UnexpectedInput], ...]:
    parse = _example_parse("start")
    out = []
    for label, snippets in EXAMPLES.items():
        for snippet in snippets:
            err = _fail(parse, snippet)
            if err is not None and getattr(err, "state", None) is not None:
                out.append((label, err))
    return tuple(out)


def _match(err: UnexpectedInput) -> Label | None:
    """Match an error against the labelled examples as ``match_examples`` does.

    Its rules (same parser state and accepted set; an exact token first, then the same
    token type, then the state alone), over example errors computed once. (lark 1.3's own
    version can raise a TypeError while formatting a debug message when two examples share
    a state.)
    """
    same_type: Label | None = None
    same_state: Label | None = None
    token = getattr(err, "token", None)
    for label, ex in _example_errors():
        if ex.state != err.state:
            continue
        if isinstance(err, UnexpectedToken) and isinstance(ex, UnexpectedToken) and \
                ex.accepts != err.accepts:
            continue
        ex_token = getattr(ex, "token", None)
        if token is not None and ex_token is not None:
            if ex_token == token and ex_token.type == token.type:
                return label
            if ex_token.type == token.type and same_type is None:
                same_type = label
        if same_state is None:
            same_state = label
    return same_type or same_state


def _fail(parse: Any, text: str) -> UnexpectedInput | None:
    try:
        parse(text)
    except UnexpectedInput as err:
        return err
    except TooDeep:
        return None
    return None


def _close_keyword(word: str, expected: set[str]) -> str | None:
    candidates = [word for word, terminal in keywords().items() if terminal in expected]
    match = difflib.get_close_matches(word, candidates, n=1, cutoff=0.7)
    return match[0] if match else None


def iter_tokens(text: str) -> Iterator[Token]:
    """Return the tokens of a text (comments and whitespace skipped).

    Stops at the first bad character (and after :data:`MAX_DEPTH` unclosed brackets).
    """
    state = BuildState("<lex>")
    lexer = lark_parser().lex(text, dont_ignore=False)
    while True:
        token = PARSE_STATE.set(state)
        try:
            tok = next(lexer)
        except (StopIteration, UnexpectedInput, TooDeep):
            return
        finally:
            PARSE_STATE.reset(token)
        yield tok



def lex_fragment(text: str, opened: int = 0) -> tuple[list[Token], int, bool]:
    """Lex a piece of a longer text that starts at a line boundary.

    No token spans a newline, so lexing line by line gives the tokens lexing the whole
    text would. ``opened`` is the count of brackets still open before the piece (the
    :data:`MAX_DEPTH` guard of :func:`iter_tokens` carries over). Returns the tokens,
    the open count after them, and whether lexing stopped early (a bad character, or
    more than :data:`MAX_DEPTH` brackets open), after which nothing more is lexed.
    """
    state = BuildState("<lex>", open_brackets=opened)
    lexer = lark_parser().lex(text, dont_ignore=False)
    out: list[Token] = []
    while True:
        token = PARSE_STATE.set(state)
        try:
            tok = next(lexer)
        except StopIteration:
            return out, state.open_brackets, False
        except (UnexpectedInput, TooDeep):
            return out, state.open_brackets, True
        finally:
            PARSE_STATE.reset(token)
        out.append(tok)
