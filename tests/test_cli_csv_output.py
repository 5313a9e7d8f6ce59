"""CSV files in and out of the commands go through mdle.core.userfile like every user file.

``experiment navigation --csv`` opened its file with plain ``open``: naming the plan
overwrote it after the whole study, and a failing disk lost half a table. ``robots fit``
read recordings with ``Path.open``: a 200 KB cell ended in "internal error" (exit 70).
"""

from __future__ import annotations

import errno
from pathlib import Path

import pytest

from mdle.cli import main

GENERATED = ["experiment", "random-starts", "--generated", "--shapes", "1", "--starts", "1",
             "--duration", "1", "--jobs", "1"]


def test_navigation_csv_naming_the_plan_is_refused_before_the_study(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    plan = tmp_path / "nav.mdle"
    text = "atom a = (go(0.3 m/s), never, 1 s)\nrun a\n"
    plan.write_text(text)
    code = main(["experiment", "navigation", "--nav-plan", str(plan), "--runs", "1",
                 "--csv", str(plan)])
    err = capsys.readouterr().err
    assert code == 1 and "an input of this command" in err and "--csv" in err
    assert plan.read_text() == text


def test_a_full_disk_under_the_csv_keeps_the_old_file_and_exits_74(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    import mdle.core.userfile

    out = tmp_path / "runs.csv"
    out.write_text("old,table\n1,2\n")

    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(mdle.core.userfile.os, "fsync", full)
    code = main([*GENERATED, "--csv", str(out)])
    captured = capsys.readouterr()
    assert code == 74, captured.err
    assert "cannot write" in captured.err and "the disk is full" in captured.err
    assert "internal error" not in captured.err
    assert "collision-course starts" in captured.out  # the results are still shown
    assert out.read_text() == "old,table\n1,2\n"      # whole: the old table, not half a new one
    assert [p.name for p in tmp_path.iterdir()] == ["runs.csv"]  # no temporary file left


@pytest.mark.parametrize("target", ["/dev/full", "folder"])
def test_a_csv_that_cannot_be_a_file_is_refused_before_the_study(
        target: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = target if target.startswith("/") else str(tmp_path)
    code = main([*GENERATED, "--csv", path])
    captured = capsys.readouterr()
    assert code in (1, 74) and "cannot write" in captured.err, captured.err
    assert "internal error" not in captured.err
    assert "collision-course starts" not in captured.out  # nothing was run


def test_a_csv_under_a_file_is_refused_before_the_study(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "f").write_text("")
    code = main([*GENERATED, "--csv", str(tmp_path / "f" / "x.csv")])
    captured = capsys.readouterr()
    assert code == 1 and "it is a file, not a folder" in captured.err
    assert "collision-course starts" not in captured.out


@pytest.fixture
def recordings(tmp_path: Path) -> Path:
    header = "t_s,v_mps,omega_radps,cmd_v_mps,cmd_omega_radps\n"
    (tmp_path / "huge-cell.csv").write_text(header + "0," + "7" * 200_000 + ",0,0,0\n")
    return tmp_path


@pytest.mark.parametrize(("name", "message"), [
    ("huge-cell.csv", "huge-cell.csv:2: not a CSV row: field larger than field limit"),
    ("/dev/zero", "cannot read recording /dev/zero: it is a character device"),
    ("missing.csv", "missing.csv: no such file"),
])
def test_bad_recordings_are_located_messages(recordings: Path, name: str, message: str,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    path = name if name.startswith("/") else str(recordings / name)
    assert main(["robots", "fit", path]) == 1
    err = capsys.readouterr().err
    assert message in err and "internal error" not in err
