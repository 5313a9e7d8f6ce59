"""Imports: relative paths, shared namespace, clashes across files, cycles, missing files."""

from __future__ import annotations

from pathlib import Path

import pytest

from mdle.core.errors import CheckError, Diagnostic, MdleSyntaxError, Span
from mdle.lang import load_program


def _at(d: Diagnostic) -> Span:
    """The place of a diagnostic that must have one."""
    assert d.span is not None, d.message
    return d.span


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def test_import_relative_to_the_importing_file(tmp_path: Path) -> None:
    write(tmp_path, "lib/common.mdle",
          'import "deeper/more.mdle"\natom a = (go(1 m/s), never, 1 s)')
    write(tmp_path, "lib/deeper/more.mdle", "atom b = (stop, never, 1 s)\nrun b")
    main = write(tmp_path, "plans/main.mdle",
                 'import "../lib/common.mdle"\nplan main = ((a, b), never, inf)')
    p = load_program(main)
    assert p.entry == "main"  # the imported file's `run` is ignored
    assert set(p.elements) == {"a", "b", "main"}
    assert len(p.sources) == 3


def test_diamond_imports_are_read_once(tmp_path: Path) -> None:
    write(tmp_path, "base.mdle", "atom a = (stop, never, 1 s)")
    write(tmp_path, "l.mdle", 'import "base.mdle"\natom l = (stop, never, 1 s)')
    write(tmp_path, "r.mdle", 'import "base.mdle"\natom r = (stop, never, 1 s)')
    main = write(tmp_path, "m.mdle", 'import "l.mdle"\nimport "r.mdle"\n'
                                     "plan main = ((a, l, r), never, inf)")
    assert set(load_program(main).elements) == {"a", "l", "r", "main"}


def test_clash_across_files_names_both(tmp_path: Path) -> None:
    write(tmp_path, "common.mdle", "\natom cruise = (stop, never, 1 s)")
    main = write(tmp_path, "a.mdle", 'import "common.mdle"\natom cruise = (go(1 m/s), never, 1 s)')
    with pytest.raises(CheckError) as err:
        load_program(main)
    (d,) = err.value.diagnostics
    common = str(tmp_path / "common.mdle")
    assert d.message == (f"`cruise` is defined twice: {common}:2:6 and {main}:2:6")


def test_import_cycle(tmp_path: Path) -> None:
    write(tmp_path, "a.mdle", 'import "b.mdle"\natom a = (stop, never, 1 s)')
    write(tmp_path, "b.mdle", 'import "a.mdle"\natom b = (stop, never, 1 s)')
    with pytest.raises(CheckError) as err:
        load_program(tmp_path / "a.mdle")
    (d,) = err.value.diagnostics
    a, b = tmp_path / "a.mdle", tmp_path / "b.mdle"
    assert d.message == f"import cycle: {a} \u2192 {b} \u2192 {a}"
    assert _at(d).file == str(b) and _at(d).line == 1


def test_missing_import(tmp_path: Path) -> None:
    main = write(tmp_path, "m.mdle", 'import "nowhere.mdle"\natom a = (stop, never, 1 s)')
    with pytest.raises(CheckError) as err:
        load_program(main)
    (d,) = err.value.diagnostics
    assert d.message == "cannot import `nowhere.mdle`: no such file"
    assert (_at(d).line, _at(d).column) == (1, 1)
    assert str(tmp_path / "nowhere.mdle") in (d.hint or "")


def test_syntax_errors_in_several_files_together(tmp_path: Path) -> None:
    write(tmp_path, "lib.mdle", "atom a = (stop never, 1 s)")
    main = write(tmp_path, "m.mdle", 'import "lib.mdle"\natom b = (stop, never 1 s)')
    with pytest.raises(MdleSyntaxError) as err:
        load_program(main)
    assert sorted(Path(_at(d).file).name for d in err.value.diagnostics) == ["lib.mdle", "m.mdle"]


def test_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "x.mdle"
    path.write_bytes(b"atom a = \xff")
    with pytest.raises(MdleSyntaxError, match="not UTF-8 text"):
        load_program(path)


@pytest.mark.parametrize("text", ['import "a\x00b.mdle"', 'import ""', 'import "a\x00"\natom ('])
def test_impossible_import_names(text: str) -> None:
    from mdle.core.errors import MdleError
    from mdle.lang import load_text

    with pytest.raises(MdleError) as err:
        load_text(text)
    assert _at(err.value.diagnostics[0]).line == 1


def test_impossible_file_names() -> None:
    for name in ("a\x00b.mdle", "x" * 5000 + ".mdle"):
        with pytest.raises(CheckError, match="cannot read"):
            load_program(name)
