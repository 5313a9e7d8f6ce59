"""One syntax error does not hide the other errors of a file (syntax and check, one pass)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from mdle.core.errors import MdleError, MdleSyntaxError
from mdle.lang import load_program, load_text
from mdle.lang.parser import parse_partial

SEVERAL = """\
# several independent mistakes
atom cruise = (go(0.3 m/s), range(0 deg) < 1 m, 10 s)
atom broken = (go(1 m/s) never, 1 s)
atom fast = (go(3 ft), never, 1 s)
atom spin = (turn(30 deg/s), stalld, 5 s)
behavior patrol = ((cruise, broken, spin, fast), never, inf)
interrupt bad = range(0 deg) < 1 s
atom a2 = (go(1 m/s), never, 1 s
atom a3 = (go(1 m/s), never, 10 m)
behavior tour = ((cruise, a2, a3, nowhere), never, inf)
plan main = ((patrol, tour), never, inf)
run main
"""


def places(err: MdleError) -> list[tuple[int, int, str]]:
    return [(d.span.line, d.span.column, d.message) for d in err.diagnostics if d.span]


def test_every_independent_error_is_reported_in_one_pass() -> None:
    with pytest.raises(MdleSyntaxError) as caught:
        load_text(SEVERAL, "several.mdle")
    found = places(caught.value)
    assert [(line, col) for line, col, _ in found] == [
        (3, 26),  # missing comma: a syntax error
        (4, 17),  # unknown unit
        (5, 30),  # unknown interrupt name: a check error beside the syntax errors
        (7, 30),  # length compared with a time
        (8, 33),  # unclosed parenthesis
        (9, 30),  # a length as a timer
        (10, 35),  # unknown element
    ]
    messages = [m for _, _, m in found]
    assert messages[0].startswith("two parts side by side")
    assert messages[1] == "unknown unit `ft`"
    assert messages[2] == "unknown name `stalld`"
    assert messages[3] == "cannot compare a length with a time"
    assert messages[4].startswith("unbalanced parentheses")
    assert messages[5].startswith("expected a timer such as `10 s` or `inf`, found a length")
    assert messages[6].startswith("unknown name `nowhere`")


def test_uses_of_a_broken_definition_are_not_reported_again() -> None:
    with pytest.raises(MdleError) as caught:
        load_text(SEVERAL, "several.mdle")
    text = str(caught.value)
    for name in ("broken", "fast", "a2"):  # each defined by a statement with an error
        assert f"`{name}`" not in text


def test_partial_parse_keeps_the_good_statements() -> None:
    part = parse_partial(SEVERAL, "several.mdle")
    kept = [getattr(s, "name", None) for s in part.module.statements]
    assert kept == ["cruise", "spin", "patrol", "bad", "a3", "tour", "main", "main"]
    assert part.unparsed == {"broken", "fast", "a2"}
    assert len(part.diagnostics) == 3
    assert not parse_partial("atom a = (stop, never, 1 s)\nrun a\n").diagnostics


def test_errors_in_two_files_are_reported_together(tmp_path: Path) -> None:
    (tmp_path / "common.mdle").write_text(
        "atom a = (go(1 m/s), never 1 s)\natom b = (go(1 m/s), nevr, 1 s)\n")
    main = tmp_path / "main.mdle"
    main.write_text('import "common.mdle"\natom c = (go(1 m), never, 1 s)\n'
                    "plan main = ((a, b, c), never, inf)\nrun main\n")
    with pytest.raises(MdleSyntaxError) as caught:
        load_program(main)
    found = [(d.span.file, d.span.line, d.message) for d in caught.value.diagnostics if d.span]
    common = str(tmp_path / "common.mdle")
    assert [f[:2] for f in found] == [(str(main), 2), (common, 1), (common, 2)]  # main first
    assert found[1][2].startswith("two parts side by side")
    assert found[2][2].startswith("unknown name `nevr`")
    assert "of `go`" in str(caught.value)  # `1 m` is not a speed


def test_no_check_errors_when_an_import_is_missing(tmp_path: Path) -> None:
    main = tmp_path / "main.mdle"
    main.write_text('import "absent.mdle"\natom c = (go(1 m/s), never 1 s)\n'
                    "plan main = ((a, c), never, inf)\nrun main\n")
    with pytest.raises(MdleError) as caught:
        load_program(main)
    messages = [d.message for d in caught.value.diagnostics]
    assert len(messages) == 2 and "cannot import" in messages[0]
    assert not any("unknown name" in m for m in messages)  # `a` would be in absent.mdle


def test_no_check_errors_when_an_import_has_a_syntax_error() -> None:
    text = 'import common.mdle\natom c = (go(1 m/s), never 1 s)\nplan main = ((a), never, inf)\n'
    with pytest.raises(MdleError) as caught:
        load_text(text, "main.mdle")
    messages = [d.message for d in caught.value.diagnostics]
    assert len(messages) == 2 and messages[0].startswith("expected a file name in double quotes")
    assert parse_partial(text).broken_import


def test_cli_lists_every_error(tmp_path: Path) -> None:
    plan = tmp_path / "several.mdle"
    plan.write_text(SEVERAL)
    r = subprocess.run([sys.executable, "-m", "mdle", "check", str(plan)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 1
    assert "7 errors" in r.stdout + r.stderr
    for line, col in ((3, 26), (5, 30), (10, 35)):
        assert f"several.mdle:{line}:{col}:" in r.stdout + r.stderr
