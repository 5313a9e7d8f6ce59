"""The REPL's Workspace: incremental definitions, elements, completeness, formatting."""

from __future__ import annotations

from pathlib import Path

import pytest

from mdle.atoms.registry import Registry
from mdle.core.errors import CheckError, MdleSyntaxError
from mdle.lang import AtomNode, StringNode, Workspace


def test_define_element_names_format(reg: Registry) -> None:
    ws = Workspace(reg)
    assert ws.define("atom cruise(v = 0.3 m/s) = (drive(v), beam(0 deg) < 1 m, inf)") == ()
    ws.define("behavior patrol = ((cruise, (spin(1 rad/s), never, 2 s))..., bumped, 1 min)")
    assert ws.names() == ["cruise", "patrol"]
    e = ws.element("cruise")
    assert isinstance(e, AtomNode) and e.label == "cruise"
    e2 = ws.element("(drive(0.3 m/s), beam(0 deg) < 1 m, 10 s)")
    assert isinstance(e2, AtomNode) and e2.timer == 10.0 and e2.label == "drive"
    p = ws.element("patrol")
    assert isinstance(p, StringNode) and p.repeat
    assert ws.element("cruise(0.1 m/s)").args["v"] == 0.1  # type: ignore[union-attr]
    assert ws.format() == (
        "atom cruise(v = 0.3 m/s) = (drive(v), beam(0 deg) < 1 m, inf)\n"
        "behavior patrol = ((cruise, (spin(1 rad/s), never, 2 s))..., bumped, 1 min)\n")


def test_errors_leave_the_workspace_unchanged(reg: Registry) -> None:
    ws = Workspace(reg)
    ws.define("atom a = (drive(1 m/s), never, 1 s)")
    before = ws.format()
    with pytest.raises(CheckError):
        ws.define("atom a = (drive(1 m), never, 1 s)")   # a bad redefinition
    with pytest.raises(CheckError):
        ws.define("atom b = (drive(1 m/s), never, 1 s)\natom b = (stop, never, 1 s)")
    with pytest.raises(MdleSyntaxError):
        ws.define("atom c = (")
    assert ws.format() == before and ws.names() == ["a"]


def test_redefinition_replaces_and_rechecks_users(reg: Registry) -> None:
    ws = Workspace(reg)
    ws.define("interrupt near(d = 1 m) = beam(0 deg) < d")
    ws.define("atom a = (drive(1 m/s), near, inf)")
    with pytest.raises(CheckError):  # `a` compares with a time now: refused
        ws.define("interrupt near(d = 1 s) = clock > d and beam(0 deg) < d")
    ws.define("interrupt near(d = 2 m) = beam(0 deg) < d")
    assert ws.element("a").interrupt.source == "near"


def test_warnings_are_returned_once(reg: Registry) -> None:
    ws = Workspace(reg)
    ws.define("atom forever = (drive(1 m/s), never, inf)")
    (w,) = ws.define("behavior b = ((forever, forever), never, 1 s)")
    assert "never reached" in w.message
    assert ws.define("atom other = (spin(1 rad/s), never, 1 s)") == ()


def test_program_and_entry(reg: Registry) -> None:
    ws = Workspace(reg)
    ws.define("atom a = (drive(1 m/s), never, 1 s)")
    assert ws.program().entry is None
    ws.define("plan main = ((a), never, inf)")
    assert ws.program().entry == "main"
    ws.define("run a")
    assert ws.program().entry == "a"


@pytest.mark.parametrize("text, complete", [
    ("atom a = (drive(1 m/s),", False), ("plan m = ((a, b),\n  never,", False),
    ("atom a = (drive(1 m/s), never, 1 s)", True), ("atom a =", False),
    ("interrupt i = x >", False), ("interrupt i = x > 1 m and", False), ("", True),
    ("cruise", True), ("atom a = (drive(1 m/s), never, 1 s))", True), ("\x00 (", True),
    ("(" * 500, True),
])
def test_is_complete(text: str, complete: bool, reg: Registry) -> None:
    assert Workspace(reg).is_complete(text) is complete


def test_element_errors(reg: Registry) -> None:
    ws = Workspace(reg)
    with pytest.raises(CheckError, match="unknown name `crusie`"):
        ws.element("crusie")
    with pytest.raises(MdleSyntaxError):
        ws.element("(drive(1 m/s), never")


def test_load_and_imports(tmp_path: Path) -> None:
    (tmp_path / "lib.mdle").write_text("atom a = (go(1 m/s), never, 1 s)\n")
    (tmp_path / "m.mdle").write_text('import "lib.mdle"\nplan main = ((a), never, inf)\n')
    ws = Workspace()
    ws.load(tmp_path / "m.mdle")
    assert ws.names() == ["a", "main"]
    assert isinstance(ws.program().elements["main"], StringNode)
