"""Values that used to pass ``check`` and fail at run time, and places that were wrong.

A NaN timer, a non-finite scale, a law argument outside the range the law declares
(``rc = -1 m``), a RecursionError without a place, line breaks other than ``\\n``, and
``rad/m`` against ``1/m``. Each must be a located check error (or, for the last, fine).
"""

from __future__ import annotations

import pytest

from mdle.atoms import default_registry
from mdle.atoms.registry import Param
from mdle.core.errors import CheckError, MdleError, MdleSyntaxError, render_diagnostic
from mdle.core.units import LENGTH
from mdle.lang import check as compile_module
from mdle.lang import load_text


def error_at(text: str) -> tuple[str, int, int]:
    """Return (message, line, column) of the first error ``text`` must raise."""
    with pytest.raises(MdleError) as err:
        load_text(text, "t.mdle", default_registry())
    d = err.value.diagnostics[0]
    assert d.span is not None, d.message
    return d.message, d.span.line, d.span.column


@pytest.mark.parametrize("timer", ["inf * 0", "(inf - inf) * 1 s", "0 * inf"])
def test_a_nan_timer_is_refused_at_its_place(timer: str) -> None:
    msg, line, col = error_at(f"atom a = (go(0.3 m/s), never, {timer})\nrun a\n")
    assert "not a number" in msg and (line, col) == (1, 31)


@pytest.mark.parametrize("scale, word", [("inf", "alpha"), ("inf * 0", "alpha"),
                                         ("[1, inf]", "alpha_omega")])
def test_a_non_finite_alpha_is_refused(scale: str, word: str) -> None:
    msg, line, _ = error_at(f"atom a = (go(0.3 m/s), never, 1 s)\n"
                            f"behavior b = ((({scale}, 1, a)), never, inf)\nrun b\n")
    assert word in msg and "finite" in msg and line == 2


def test_a_non_finite_beta_is_refused() -> None:
    msg, line, _ = error_at("atom a = (go(0.3 m/s), never, 1 s)\n"
                            "behavior b = (((1, inf, a)), never, inf)\nrun b\n")
    assert "beta" in msg and line == 2


@pytest.mark.parametrize("call, param", [
    ("follow_boundary(rc = -1 m)", "rc"),
    ("follow_boundary(v = -0.3 m/s)", "v"),
    ("follow_boundary(v = 0 m/s)", "v"),
    ("follow_boundary(kf = -1)", "kf"),
    ("follow_boundary(tau = -1 s)", "tau"),
    ("goto(1 m, 1 m, v = -1 m/s)", "v"),
    ("heading(90 deg, rate = -1 deg/s)", "rate"),
    ("go(inf * 1 m/s)", "v"),
])
def test_law_arguments_outside_their_declared_range_are_refused(call: str, param: str) -> None:
    text = f"atom a = ({call}, never, 1 s)\nrun a\n"
    msg, line, col = error_at(text)
    assert f"`{param}` of" in msg and line == 1 and col > 10, msg


def test_ranges_are_checked_with_the_arguments_of_each_use() -> None:
    text = ("atom f(r) = (follow_boundary(rc = r), never, 1 s)\n"
            "behavior b = ((f(0.5 m), f(-2 m)), never, inf)\nrun b\n")
    msg, line, _ = error_at(text)
    assert "`rc` of `follow_boundary`" in msg and "-2 m" in msg
    load_text(text.replace("-2 m", "2 m"), "t.mdle", default_registry())  # fine


def test_param_declares_its_range() -> None:
    p = Param("rc", LENGTH, 0.5, low=0.0, low_open=True)
    assert p.accepts(0.1) and not p.accepts(0.0) and not p.accepts(float("nan"))
    assert not p.accepts(float("inf"))
    assert Param("umax", LENGTH, float("inf"), low=0.0, low_open=True,
                 finite=False).accepts(float("inf"))
    assert "more than 0" in p.range_words()


def test_too_deep_to_check_names_a_place(monkeypatch: pytest.MonkeyPatch) -> None:
    original = compile_module.Checker.check_definition

    def deep(self: compile_module.Checker, d: object) -> object:
        if getattr(d, "name", "") == "b":
            raise RecursionError("maximum recursion depth exceeded")
        return original(self, d)  # type: ignore[arg-type]

    monkeypatch.setattr(compile_module.Checker, "check_definition", deep)
    msg, line, col = error_at("atom a = (go(0.3 m/s), never, 1 s)\n"
                              "behavior b = ((a), never, inf)\nrun a\n")
    assert "too deeply" in msg and (line, col) == (2, 1)


@pytest.mark.parametrize("sep", ["\r", "\r\n", "\n"])
def test_line_numbers_with_any_newline(sep: str) -> None:
    text = sep.join(["atom a = (go(0.3 m/s), never, 1 s)", "", "atom b = (go(1 ft), never, 1 s)",
                     "run a"]) + sep
    with pytest.raises(MdleSyntaxError) as err:
        load_text(text, "t.mdle", default_registry())
    d = err.value.diagnostics[0]
    assert d.span is not None and d.span.line == 3
    shown = render_diagnostic(d, err.value.sources)
    assert "atom b = (go(1 ft)" in shown and "atom a" not in shown


@pytest.mark.parametrize("odd", ["\f", "\v", "\u2028", "\u2029", "\x1c", "\x85"])
def test_odd_breaks_do_not_shift_lines(odd: str) -> None:
    text = f"atom a = (go(0.3 m/s),{odd} never, 1 s)\n\natom b = (go(1 ft), never, 1 s)\n"
    with pytest.raises(MdleError) as err:
        load_text(text, "t.mdle", default_registry())
    diags = err.value.diagnostics
    for d in diags:
        assert d.span is not None
        shown = render_diagnostic(d, err.value.sources)
        # the source line shown is the line the position names
        expected = text.split("\n")[d.span.line - 1].strip()[:15]
        assert expected.replace("\t", " ") in shown.replace(odd, " "), (shown, d.span)
    assert any(d.span is not None and d.span.line == 3 for d in diags), diags


def test_curvatures_compare_whatever_their_angle_unit() -> None:
    text = ("atom a = (go(0.3 m/s), boundary_curvature() > 1 / 2 m, 10 s)\n"
            "atom b = (go(0.3 m/s), boundary_curvature() < 0.5 rad/m, 10 s)\nrun a\n")
    load_text(text, "t.mdle", default_registry())
    msg, _, _ = error_at("atom a = (go(0.3 m/s), boundary_curvature() > 2 m, 10 s)\nrun a\n")
    assert "cannot compare a curvature with a length" in msg


def test_check_error_type_for_ranges() -> None:
    with pytest.raises(CheckError):
        load_text("atom a = (follow_boundary(rc = -1 m), never, 1 s)\n", "t.mdle",
                  default_registry())
