"""The formatter: canonical layout, comments kept, and the round trip on every plan."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from mdle.lang import load_text, parse_module, structure
from mdle.lang.format import WIDTH, format_source

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
ALL_PLANS = sorted((REPO / "plans").rglob("*.mdle"))


def _plangen():  # type: ignore[no-untyped-def]
    # pytest runs with --import-mode=importlib: load the sibling helper module by path.
    name = "mdle_language_plangen"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, HERE / "plangen.py")
        assert spec and spec.loader
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


plangen = _plangen()


def roundtrip(text: str, file: str = "<t>") -> str:
    tree = parse_module(text, file)
    out = format_source(text, file)
    again = parse_module(out, file)
    assert again.statements == tree.statements
    assert [c.text for c in again.comments] == [c.text for c in tree.comments]
    assert format_source(out, file) == out  # idempotent
    return out


def test_there_are_plans_to_check() -> None:
    assert len(ALL_PLANS) >= 4


@pytest.mark.parametrize("path", ALL_PLANS, ids=[str(p.relative_to(REPO)) for p in ALL_PLANS])
def test_round_trip_on_every_plan(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    roundtrip(text, str(path))


@pytest.mark.parametrize("path", ALL_PLANS, ids=[str(p.relative_to(REPO)) for p in ALL_PLANS])
def test_shipped_plans_are_already_canonical(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    assert format_source(text, str(path)) == text


def test_fmt_check_passes_on_the_shipped_plans(mdle_command: list[str], tmp_path: Path) -> None:
    # what a user (and .ci/smoke) types: `mdle fmt --check plans/`, exit 0 and silent
    out = subprocess.run([*mdle_command, "fmt", "--check", str(REPO / "plans")], cwd=tmp_path,
                         capture_output=True, text=True, timeout=60)
    assert (out.returncode, out.stdout, out.stderr) == (0, "", "")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plangen.plan())
def test_round_trip_on_generated_plans(text: str) -> None:
    out = roundtrip(text)
    # The formatted plan is the same program.
    before, after = load_text(text), load_text(out)
    assert before.entry == after.entry and list(before.elements) == list(after.elements)
    for name in before.elements:
        assert structure(before.elements[name]) == structure(after.elements[name])


def test_layout_short_and_long() -> None:
    assert format_source("atom  a=( go( 1 m/s ),never,1s )") == "atom a = (go(1 m/s), never, 1 s)\n"
    long = ("plan main = ((patrol, ((spin, cruise), range(0 deg) < 0.3 m, 30 s), careful, "
            "patrol, careful, patrol), stalled, 10 min)")
    assert format_source(long) == (
        "plan main = (\n"
        "    (patrol, ((spin, cruise), range(0 deg) < 0.3 m, 30 s), careful, patrol, careful, "
        "patrol),\n"
        "    stalled,\n"
        "    10 min,\n"
        ")\n")
    assert all(len(line) <= WIDTH for line in format_source(long).splitlines())


def test_comments_and_blank_lines() -> None:
    text = ("# head\n\n\n\natom a = (go(1 m/s),  # inside\n  never, 1 s)  # after\n"
            "atom b = (stop, never, 1 s)\n# tail\n")
    assert format_source(text) == ("# head\n\n# inside\natom a = (go(1 m/s), never, 1 s)  # after\n"
                                   "atom b = (stop, never, 1 s)\n# tail\n")


def test_keywords_units_and_operators_are_normalised() -> None:
    text = 'import   "c.mdle"\ninterrupt i(d=1m)=not(x>d)and y<2  m or -t*2>=3s\nrun   i'
    assert format_source(text) == ('import "c.mdle"\n'
                                   "interrupt i(d = 1 m) = "
                                   "not (x > d) and y < 2 m or -t * 2 >= 3 s\n"
                                   "run i\n")


def test_empty_file_formats_to_nothing() -> None:
    assert format_source("") == ""
    assert format_source("\n\n# c\n") == "# c\n"
