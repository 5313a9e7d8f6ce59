"""Fuzzing: no input, however malformed, raises anything but an MdleError."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hs

from mdle.core.errors import MdleError, render_diagnostic
from mdle.lang import Workspace, format_source, load_program, load_text

HERE = Path(__file__).resolve().parent
SEEDS = [p.read_text(encoding="utf-8") for p in sorted((HERE.parents[1] / "plans").rglob("*.mdle"))]

_spec = importlib.util.spec_from_file_location("mdle_language_plangen", HERE / "plangen.py")
assert _spec and _spec.loader
plangen = sys.modules.get("mdle_language_plangen") or importlib.util.module_from_spec(_spec)
if "mdle_language_plangen" not in sys.modules:
    sys.modules["mdle_language_plangen"] = plangen
    _spec.loader.exec_module(plangen)

#: Pieces a mutation inserts: tokens of the language and a few troublemakers.
PIECES = ["(", ")", ",", "...", "[", "]", "=", "==", "<", "not", "and", "atom", "plan", "run",
          "inf", "never", "1 m", "2 s", "3 ft", "x", "go", "cruise", "#", '"', "\n", "\x00",
          "\u00e9", "1e999", "-", "/", "* 0", "main", "import", '"nowhere.mdle"', "10 m/s/s"]


def only_mdle_errors(text: str) -> None:
    try:
        load_text(text, "<fuzz>")
    except MdleError as err:
        for d in err.diagnostics:  # rendering must not fail either
            render_diagnostic(d, err.sources)
    try:
        format_source(text, "<fuzz>")
    except MdleError:
        pass


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(hs.binary(max_size=300))
def test_random_bytes(data: bytes) -> None:
    only_mdle_errors(data.decode("utf-8", "replace"))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(hs.lists(hs.sampled_from(PIECES + list("()[],.=<>!+-*/ \n\tabcxyz0123456789")),
               max_size=60).map(" ".join))
def test_random_token_soup(text: str) -> None:
    only_mdle_errors(text)


@hs.composite
def mutated(draw: hs.DrawFn) -> str:
    text = draw(hs.one_of(hs.sampled_from(SEEDS), plangen.plan()))
    for _ in range(draw(hs.integers(1, 4))):
        if not text:
            break
        i = draw(hs.integers(0, len(text) - 1))
        j = draw(hs.integers(i, min(len(text), i + 12)))
        op = draw(hs.sampled_from(["delete", "insert", "duplicate", "replace"]))
        if op == "delete":
            text = text[:i] + text[j:]
        elif op == "insert":
            text = text[:i] + draw(hs.sampled_from(PIECES)) + text[i:]
        elif op == "duplicate":
            text = text[:j] + text[i:j] + text[j:]
        else:
            text = text[:i] + draw(hs.sampled_from(PIECES)) + text[j:]
    return text


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_plans(text: str) -> None:
    only_mdle_errors(text)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_plans_in_the_repl(text: str) -> None:
    ws = Workspace()
    try:
        ws.define(text)
    except MdleError:
        assert ws.names() == []  # unchanged on errors
    try:
        ws.element(text.splitlines()[0] if text.strip() else text)
    except MdleError:
        pass
    ws.is_complete(text)


def test_binary_file_and_missing_import(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mdle"
    junk.write_bytes(bytes(range(256)) * 4)
    for path in (junk, tmp_path / "absent.mdle"):
        try:
            load_program(path)
        except MdleError:
            pass
        else:  # pragma: no cover - the test fails here
            raise AssertionError("no error")


def test_huge_inputs() -> None:
    for text in ("(" * 1_000_000, ")" * 1_000_000, "atom a = " + "[" * 500_000,
                 "interrupt i = " + "x + " * 200_000 + "x", "atom a = " + "-" * 300_000 + "1",
                 "# " + "x" * 1_000_000):
        only_mdle_errors(text)
