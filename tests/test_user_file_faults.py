"""Faults of the machine while reading or writing a user's file are messages, not exit 70.

A read error (EIO: a failing disk, a lost network share) on any input of ``check``,
``show``, ``fmt``, ``run`` (the plan, an import, ``--world``, ``--robot``, ``--team``),
``sweep``, ``plot`` and ``export``, and in the REPL's ``:load``, used to end in
"internal error". The fault is injected in-process: every file opened through
:mod:`mdle.core.userfile` whose path is the chosen one fails its reads with EIO.
"""

from __future__ import annotations

import errno
import io
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from mdle.cli import main

PLAN = "atom a = (go(0.3 m/s), never, 0.5 s)\nrun a\n"
WORLD = "name: tiny\nstart: [0, 0, 0]\nobstacles: []\n"
ROBOT = "robot:\n  name: slow\n  max_speed: 0.5\n"


class _Failing(io.RawIOBase):
    """A file whose every read fails as a failing disk's does."""

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        raise OSError(errno.EIO, "Input/output error")


@pytest.fixture
def eio(monkeypatch: pytest.MonkeyPatch) -> Callable[[Path], None]:
    """Make reads of one file fail with EIO (call it with the file)."""
    import mdle.core.userfile

    real = os.fdopen
    failing: list[str] = []

    def fdopen(fd: int, *args: Any, **kwargs: Any) -> Any:
        if os.path.realpath(f"/proc/self/fd/{fd}") in failing:
            os.close(fd)
            return io.BufferedReader(_Failing())
        return real(fd, *args, **kwargs)

    monkeypatch.setattr(mdle.core.userfile.os, "fdopen", fdopen)
    return lambda path: failing.append(os.path.realpath(path))


@pytest.fixture
def files(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.mdle").write_text(PLAN)
    (tmp_path / "lib.mdle").write_text("atom b = (go(0.2 m/s), never, 0.5 s)\n")
    (tmp_path / "q.mdle").write_text('import "lib.mdle"\n' + PLAN)
    (tmp_path / "w.yaml").write_text(WORLD)
    (tmp_path / "r.yaml").write_text(ROBOT)
    (tmp_path / "s.yaml").write_text('plan: p.mdle\nworlds: [default]\n')
    return tmp_path


@pytest.mark.parametrize(("argv", "failing"), [
    (["check", "p.mdle"], "p.mdle"),
    (["check", "q.mdle"], "lib.mdle"),
    (["show", "p.mdle"], "p.mdle"),
    (["fmt", "p.mdle"], "p.mdle"),
    (["run", "p.mdle", "-q"], "p.mdle"),
    (["run", "q.mdle", "-q"], "lib.mdle"),
    (["run", "p.mdle", "-q", "--world", "w.yaml"], "w.yaml"),
    (["run", "p.mdle", "-q", "--robot", "r.yaml"], "r.yaml"),
    (["sweep", "s.yaml", "--out", "o", "--jobs", "1"], "s.yaml"),
    (["sweep", "s.yaml", "--out", "o", "--jobs", "1"], "p.mdle"),
])
def test_a_read_error_on_an_input_is_a_message(
        files: Path, eio: Callable[[Path], None], capsys: pytest.CaptureFixture[str],
        argv: list[str], failing: str) -> None:
    eio(files / failing)
    code = main(argv)
    cap = capsys.readouterr()
    err = cap.err + cap.out  # `check` reports on standard output
    assert code == 1, err
    assert "input/output error" in err and failing in err, err
    assert "internal error" not in err


def test_a_read_error_on_a_trace_is_a_message(
        files: Path, eio: Callable[[Path], None], capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "p.mdle", "-q", "--rate", "10", "--trace", "t.jsonl"]) == 0
    eio(files / "t.jsonl")
    for argv in (["plot", "t.jsonl", "-o", "t.png"], ["export", "t.jsonl", "-o", "t.mcap"]):
        if argv[0] == "export":
            pytest.importorskip("mcap", reason="the mcap extra is not installed")
        code = main(argv)
        err = capsys.readouterr().err
        assert code == 1, (argv, err)
        assert "input/output error" in err and "internal error" not in err, err


def test_a_read_error_in_the_repl_load_is_a_message(
        files: Path, eio: Callable[[Path], None]) -> None:
    from mdle.repl.commands import Repl
    from mdle.repl.session import Session

    out, err = io.StringIO(), io.StringIO()
    repl = Repl(Session("default"), out, err)
    eio(files / "lib.mdle")
    assert not repl.handle(":load lib.mdle")
    assert "input/output error" in err.getvalue() and "internal error" not in err.getvalue()
    assert repl.handle("atom c = (go(0.1 m/s), never, 1 s)")  # the session goes on


def test_the_robot_profile_is_read_as_every_user_file_is(
        files: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # `--robot /dev/zero` read until memory ran out
    assert main(["run", "p.mdle", "-q", "--robot", "/dev/zero"]) == 1
    assert "it is a character device, not a regular file" in capsys.readouterr().err


# ------------------------------------------------------------------- writing outputs


@pytest.fixture
def read_only(monkeypatch: pytest.MonkeyPatch) -> Callable[[Path], None]:
    """Make one folder refuse new files as a read-only mount does (root ignores chmod)."""
    import tempfile

    real = tempfile.mkstemp
    folders: list[str] = []

    def mkstemp(*args: Any, **kwargs: Any) -> Any:
        if os.path.realpath(kwargs.get("dir") or ".") in folders:
            raise OSError(errno.EROFS, "Read-only file system")
        return real(*args, **kwargs)

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    return lambda path: folders.append(os.path.realpath(path))


def test_a_read_only_results_folder_is_refused_before_any_run(
        files: Path, read_only: Callable[[Path], None], monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    import mdle.sweep

    ran: list[object] = []
    monkeypatch.setattr(mdle.sweep, "run_sweep", lambda *a, **k: ran.append(a))
    (files / "o").mkdir()
    read_only(files / "o")
    assert main(["sweep", "s.yaml", "--out", "o", "--jobs", "1"]) == 1
    err = capsys.readouterr().err
    assert "--out: cannot write in `o`: the file system is read-only" in err
    assert ran == []


def test_a_read_only_experiment_folder_is_refused_before_the_computing(
        files: Path, read_only: Callable[[Path], None], monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    import mdle.experiments.curvature

    monkeypatch.setattr(mdle.experiments.curvature, "run_table",
                        lambda *a, **k: pytest.fail("computed before checking --out"))
    (files / "figs").mkdir()
    read_only(files / "figs")
    assert main(["experiment", "curvature", "--out", "figs", "--draws", "1"]) == 1
    assert "--out: cannot write in `figs`: the file system is read-only" in \
        capsys.readouterr().err


def test_a_full_disk_under_the_results_table_is_a_message(
        files: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.sweep.table import ResultsTable

    def full(self: ResultsTable, cells: Any) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(ResultsTable, "_write_line", full)
    code = main(["sweep", "s.yaml", "--out", "o", "--jobs", "1"])
    err = capsys.readouterr().err
    assert code == 74, err
    assert "the disk is full" in err and "internal error" not in err
