"""Syntax errors: every labelled bad snippet, the exact message shape, several at once."""

from __future__ import annotations

import pytest

from mdle.core.errors import Diagnostic, MdleSyntaxError, Span, render_diagnostic
from mdle.lang import load_text
from mdle.lang.parser import MAX_ERRORS, parse_expression, parse_module
from mdle.lang.syntax_errors import EXAMPLES, terminal_words

CASES = [(label.message, snippet) for label, snippets in EXAMPLES.items() for snippet in snippets]


def _at(d: Diagnostic) -> Span:
    """The place of a diagnostic that must have one."""
    assert d.span is not None, d.message
    return d.span


@pytest.mark.parametrize("message, snippet", CASES)
def test_each_labelled_snippet_gets_its_message(message: str, snippet: str) -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(snippet, "bad.mdle")
    first = err.value.diagnostics[0]
    assert first.message.startswith(message)
    assert "__ANON" not in first.message and "__ANON" not in (first.hint or "")
    assert first.span is not None and first.span.file == "bad.mdle" and first.span.line >= 1


def test_labels_work_after_other_statements_too() -> None:
    text = "atom ok = (go(1 m/s), never, 1 s)\n\ninterrupt i = 0 m < x < 1 m\n"
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(text, "p.mdle")
    assert err.value.diagnostics[0].message.startswith("comparisons do not chain")


def test_exact_message_shape_with_caret_and_hint() -> None:
    text = "atom a = (go(1 m/s), never, 1 s)\natom b = (go(1 m/s) never, 1 s)\n"
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(text, "plans/p.mdle")
    (d,) = err.value.diagnostics
    assert render_diagnostic(d, err.value.sources) == (
        "plans/p.mdle:2:21: error: two parts side by side: a comma or an operator is missing "
        "between them (found the keyword `never`)\n"
        "    atom b = (go(1 m/s) never, 1 s)\n"
        "                        ^^^^^\n"
        "  hint: parts of a tuple are separated by `,`; conditions are joined with `and`, "
        "`or`, `xor`")


def test_unclosed_parenthesis_points_at_the_end_and_notes_the_opening() -> None:
    text = "atom a = (go(1 m/s),\n         never,\n         1 s\n"
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(text, "u.mdle")
    (d,) = err.value.diagnostics
    assert d.message.startswith("unbalanced parentheses: the file ends before a `(` is closed")
    assert (_at(d).line, _at(d).column) == (3, 13)
    assert d.notes and (_at(d.notes[0]).line, _at(d.notes[0]).column) == (1, 10)
    assert d.notes[0].message == "this `(` is not closed"


def test_several_errors_are_reported_together() -> None:
    text = ("atom a = (go(1 m/s) never, 1 s)\n"
            "atom ok = (go(1 m/s), never, 1 s)\n"
            "atom b = (go(3 ft), never, 1 s)\n"
            "interrupt i = x >\n"
            "atom c = stalled)\n")
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(text, "m.mdle")
    lines = [_at(d).line for d in err.value.diagnostics]
    assert lines == [1, 3, 4, 5]


def test_error_count_is_capped() -> None:
    text = "atom a = (go(1 m/s) never, 1 s)\n" * (MAX_ERRORS + 10)
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(text)
    assert len(err.value.diagnostics) == MAX_ERRORS


@pytest.mark.parametrize("text, message, hint", [
    ("atom a = (go(1 ft/s), never, 1 s)", "unknown unit `ft`", "units are cm, deg, m, min, mm"),
    ("atom a = (go(1 mps), never, 1 s)", "unknown unit `mps`", "did you mean `ms`?"),
    ("atom a = (go(1 m/sec), never, 1 s)", "unknown unit `sec`", "did you mean `s`?"),
    ("atom a = (turn(30 degs), never, 1 s)", "unknown unit `degs`", "did you mean `deg`?"),
])
def test_unknown_units(text: str, message: str, hint: str) -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(text)
    (d,) = err.value.diagnostics
    assert d.message == message and hint in (d.hint or "")


@pytest.mark.parametrize("char, hint", [("&", "`and`"), ("|", "`or`"), (";", "no `;`"),
                                        ("{", "parentheses"), ("\u2264", "`<=`")])
def test_stray_characters_get_a_hint(char: str, hint: str) -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_module(f"interrupt i = x > 1 m {char} stalled")
    (d,) = err.value.diagnostics
    assert d.message.startswith("unexpected character") and hint in (d.hint or "")
    assert _at(d).column == 23


def test_binary_junk_is_reported_as_such() -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_module("\x00\x01\x02 atom")
    assert err.value.diagnostics[0].message == "unexpected control character U+0000"


def test_a_megabyte_of_parentheses_is_a_plain_error() -> None:
    for text in ("(" * 1_000_000, "atom a = " + "(" * 1_000_000, "atom a = " + "()" * 500_000):
        with pytest.raises(MdleSyntaxError):
            parse_module(text)


def test_number_too_large() -> None:
    with pytest.raises(MdleSyntaxError, match="too large"):
        parse_module("atom a = (go(1e999 m/s), never, 1 s)")


def test_unterminated_file_name() -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_module('import "common.mdle\n')
    assert err.value.diagnostics[0].message.startswith("unterminated file name")


def test_expression_errors_in_the_repl() -> None:
    with pytest.raises(MdleSyntaxError) as err:
        parse_expression("(go(1 m/s), never, 1 s", "<repl>")
    assert err.value.diagnostics[0].message.startswith("unbalanced parentheses")


def test_terminal_words_cover_the_grammar() -> None:
    from mdle.lang.parser import lark_parser

    names = {t.name for t in lark_parser().terminals} - {"COMMENT", "WHITESPACE"}
    assert names <= set(terminal_words())


def test_load_text_reports_syntax_errors_with_sources() -> None:
    with pytest.raises(MdleSyntaxError) as err:
        load_text("atom = 1", "x.mdle")
    assert err.value.sources == {"x.mdle": "atom = 1"}
