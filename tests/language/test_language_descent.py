"""The fast parser (mdle/lang/descent.py) against the reference (lark): same trees, same spans.

The fast parser may only give up (then lark reads the file and reports); whenever it
returns a tree, that tree, every span in it and the comments must be lark's.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hs

from mdle.lang import parser
from mdle.lang.descent import parse_valid
from mdle.lang.syntax_errors import EXAMPLES

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PLANS = sorted((ROOT / "plans").rglob("*.mdle")) + sorted((ROOT / "tests").rglob("*.mdle"))


def _helper(name: str, path: Path) -> ModuleType:
    """Return a helper module loaded by path (tests are imported in importlib mode)."""
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None and spec.loader is not None
        module = sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return module


plangen = _helper("mdle_language_plangen", HERE / "plangen.py")
bench = _helper("mdle_bench_parse", ROOT / "benchmarks" / "parse.py")


def reference(text: str) -> tuple[Any, Any, list[Any]]:
    statements, comments, diagnostics = parser._parse_with_recovery(text, "f.mdle")
    return statements, comments, diagnostics


def fast(text: str) -> tuple[list[Any], list[Any]] | None:
    return parse_valid(text, "f.mdle", parser._fast_lexer())


def with_spans(nodes: Any) -> list[Any]:
    """Every field, spans included (node equality ignores spans)."""
    return [dataclasses.astuple(n) for n in nodes]


def same_as_reference(text: str) -> bool:
    """Check the fast parser against lark on ``text``; return whether it gave a tree."""
    got = fast(text)
    statements, comments, diagnostics = reference(text)
    if got is None:
        return False
    assert not diagnostics, "the fast parser accepted a text lark refuses"
    assert with_spans(got[0]) == with_spans(statements)
    assert with_spans(got[1]) == with_spans(comments)
    return True


@pytest.mark.parametrize("path", PLANS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_plan_parses_the_same(path: Path) -> None:
    text = parser.normalise_newlines(path.read_text(encoding="utf-8", errors="replace"))
    accepted = same_as_reference(text)
    assert accepted == (not reference(text)[2])  # gives up exactly on the files with errors


def test_benchmark_plans_parse_the_same() -> None:
    assert same_as_reference(bench.generated_plan(400))
    assert same_as_reference(bench.definitions_plan(20_000))


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plangen.plan())
def test_generated_plans_parse_the_same(text: str) -> None:
    assert same_as_reference(text)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(hs.lists(hs.sampled_from(["(", ")", ",", "...", "[", "]", "=", "==", "<", "not", "and",
                                 "or", "-", "+", "*", "atom", "plan", "run", "import", "inf",
                                 "never", "1 m", "2 s", "3 ft", "x", "go", "a", '"f"', "\n",
                                 "# c\n", "1e999", "v = 1", "interrupt"]),
                max_size=30).map(" ".join))
def test_token_soup_never_differs(text: str) -> None:
    same_as_reference(text)


def test_gives_up_on_every_labelled_syntax_error() -> None:
    for snippets in EXAMPLES.values():
        for snippet in snippets:
            assert fast(snippet) is None, snippet


@pytest.mark.parametrize("text", [
    "atom a = (go(3 ft), never, 1 s)",  # unknown unit
    "atom a = (go(1e999 m/s), never, 1 s)",  # too large
    "interrupt i = 0 m < x < 1 m",  # chained comparison
    "interrupt i = " + "(" * 101 + "x" + ")" * 101,  # brackets too deep
    "interrupt i = " + "x + " * 150 + "x",  # operators too deep
    "atom a = (go(1 m/s), never, 1 s) \x00",  # a character no token starts with
])
def test_gives_up_where_lark_reports(text: str) -> None:
    assert fast(text) is None
    assert reference(text)[2]


@pytest.mark.parametrize("levels", [98, 99, 100, 101, 102])
@pytest.mark.parametrize("shape", [
    lambda n: "x + " * (n - 1) + "x",  # a chain of operators, left associative
    lambda n: "not " * (n - 1) + "x",  # prefix operators
    lambda n: "- " * (n - 2) + "(x)",  # prefix operators around a group
    lambda n: "f(" * (n - 1) + "x" + ")" * (n - 1),  # calls
    lambda n: "[" * (n - 1) + "x" + "]" * (n - 1),  # vectors
    lambda n: "(" * (n // 2) + "x * " * (n - n // 2 - 1) + "x" + ")" * (n // 2),
    lambda n: "g(a = " * (n // 2) + "-" * (n - n // 2 - 1) + "x" + ")" * (n // 2),
], ids=["operators", "not", "signs", "calls", "vectors", "groups-operators", "keywords"])
def test_depth_limit_is_the_reference_s(levels: int, shape: Callable[[int], str]) -> None:
    # The fast parser counts nesting as the reference does: it accepts exactly the
    # expressions lark accepts, at the limit and on either side of it.
    text = "interrupt i = " + shape(levels) + "\n"
    assert same_as_reference(text) == (not reference(text)[2])


def test_keyword_arguments_and_trailing_commas() -> None:
    text = ("atom a(v = 1 m/s, w = -2 deg/s,) = (arc(v = v, omega = w,), not (x > 1 m), "
            "inf)\nbehavior b = (([0.5, 2,], 1, a), never, 2 min)\nrun b\n")
    assert same_as_reference(text)
