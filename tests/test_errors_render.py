"""render_diagnostic: header, source line and caret, also on very long lines."""

from __future__ import annotations

from mdle.core.errors import Diagnostic, Span, render_diagnostic


def _caret_target(text: str) -> str:
    """The characters of the shown source line that the carets sit under."""
    _, shown, carets = text.splitlines()[:3]
    start = carets.index("^")
    return shown[start:start + carets.count("^")]


def test_caret_marks_the_span_on_a_short_line() -> None:
    out = render_diagnostic(Diagnostic(Span("a.mdle", 1, 5, 1, 8), "unknown name `foo`"),
                            {"a.mdle": "run foo"})
    assert out.splitlines()[0] == "a.mdle:1:5: error: unknown name `foo`"
    assert _caret_target(out) == "foo"


def test_caret_marks_the_span_far_into_a_long_line() -> None:
    line = "x" * 5000 + "BAD" + "y" * 5000
    out = render_diagnostic(Diagnostic(Span("f", 1, 5001, 1, 5004), "bad"), {"f": line})
    assert _caret_target(out) == "BAD"
    assert len(out.splitlines()[1]) < 200


def test_span_past_the_end_of_the_line_is_clipped() -> None:
    out = render_diagnostic(Diagnostic(Span("f", 1, 5, 1, 80), "bad"), {"f": "run foo"})
    assert _caret_target(out) == "foo"


def test_without_the_source_only_header_and_hint_are_shown() -> None:
    out = render_diagnostic(Diagnostic(Span("f", 3, 1, 3, 2), "bad", hint="try this"))
    assert out.splitlines() == ["f:3:1: error: bad", "  hint: try this"]
