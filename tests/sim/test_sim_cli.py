"""`mdle worlds` and `mdle worlds show`: listing, drawing, and errors without tracebacks."""

from __future__ import annotations

from pathlib import Path

import pytest

from mdle import sim
from mdle.cli import main


def test_worlds_lists_every_reference_world(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["worlds"]) == 0
    out = capsys.readouterr().out.splitlines()
    names = [line.split()[0] for line in out]
    assert names == sim.list_worlds()
    assert any(line.startswith("default") and "(default)" in line for line in out)
    assert all(len(line.split(None, 1)) == 2 for line in out)   # every one has a description


def test_worlds_show_draws_a_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "corridor.png"
    assert main(["worlds", "show", "corridor", "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "world drawn to" in capsys.readouterr().out


def test_worlds_show_a_file_without_scan(tmp_path: Path) -> None:
    world = tmp_path / "room.yaml"
    world.write_text("start: [0, 0, 0]\nobstacles:\n"
                     "  - {type: arc, center: [0, 0], radius: 3, start: -90, end: 180}\n")
    out = tmp_path / "room.svg"
    assert main(["worlds", "show", str(world), "-o", str(out), "--no-scan"]) == 0
    assert out.read_text().lstrip().startswith("<?xml")


@pytest.mark.parametrize(("argv", "expected"), [
    (["worlds", "show", "corridr", "-o", "x.png"],
     "unknown world `corridr` (did you mean `corridor`?)"),
    (["worlds", "show", "missing.yaml", "-o", "x.png"], "world file not found: missing.yaml"),
])
def test_worlds_show_errors_are_diagnostics(argv: list[str], expected: str,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err


def test_malformed_world_file_points_at_the_key(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("obstacles:\n  - {type: polygon, points: [[0, 0], [1, 0]]}\n")
    assert main(["worlds", "show", str(bad), "-o", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err
    assert (f"{bad}:2:29: error: obstacles[0].points: a polygon needs at least 3 points, got 2"
            in err)
    assert "^" in err and "Traceback" not in err
