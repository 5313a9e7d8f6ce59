"""No output option writes over an input of its command, or over another output.

``mdle run p.mdle --trace p.mdle`` once replaced the plan with its trace and exited 0;
``mdle export t.jsonl -o t.jsonl`` replaced the trace with a partial MCAP. Outputs are
compared with inputs as files, so another name for the same file is caught too.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from mdle.cli import main

PLAN = "atom a = (go(0.3 m/s), never, 0.5 s)\nrun a\n"


@pytest.fixture
def plan(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    p = tmp_path / "p.mdle"
    p.write_text(PLAN)
    return p


def _names_for(p: Path) -> list[str]:
    """The plan by its own name, another spelling, a symbolic and a hard link."""
    (p.parent / "soft.mdle").symlink_to(p.name)
    os.link(p, p.parent / "hard.mdle")
    return [p.name, f"./{p.name}", str(p), "soft.mdle", "hard.mdle"]


@pytest.mark.parametrize("option", ["--trace", "--record"])
def test_run_never_writes_over_its_plan(plan: Path, option: str,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    for name in _names_for(plan):
        code = main(["run", "p.mdle", "-q", "--rate", "10", option, name])
        err = capsys.readouterr().err
        assert code == 1, err
        assert f"{option} `{name}` is the plan `p.mdle`, an input of this command" in err
        assert plan.read_text() == PLAN


def test_run_never_draws_over_its_plan(plan: Path, capsys: pytest.CaptureFixture[str]) -> None:
    os.symlink(plan.name, "p.png")  # a plot's name must end in .png: the plan by that name
    assert main(["run", "p.mdle", "-q", "--rate", "10", "--plot", "p.png"]) == 1
    assert "--plot `p.png` is the plan `p.mdle`" in capsys.readouterr().err
    assert plan.read_text() == PLAN


def test_run_never_writes_over_an_imported_file_or_its_world(
        plan: Path, capsys: pytest.CaptureFixture[str]) -> None:
    Path("lib.mdle").write_text("atom b = (go(0.2 m/s), never, 0.5 s)\n")
    plan.write_text('import "lib.mdle"\n' + PLAN)
    world = Path("p.world.yaml")
    world.write_text("name: tiny\nobstacles: []\n")
    before = world.read_text()
    assert main(["run", "p.mdle", "-q", "--trace", "lib.mdle"]) == 1
    assert "is the imported file `lib.mdle`" in capsys.readouterr().err
    assert main(["run", "p.mdle", "-q", "--trace", "p.world.yaml"]) == 1
    assert "is the world `p.world.yaml`" in capsys.readouterr().err
    assert world.read_text() == before
    assert Path("lib.mdle").read_text().startswith("atom b")


def test_two_outputs_of_one_run_cannot_share_a_file(
        plan: Path, capsys: pytest.CaptureFixture[str]) -> None:
    os.symlink("run.mcap", "same.mcap")
    Path("run.mcap").write_bytes(b"")
    assert main(["run", "p.mdle", "-q", "--trace", "run.mcap", "--record", "same.mcap"]) == 1
    assert "--record `same.mcap` and --trace `run.mcap` name the same file" in \
        capsys.readouterr().err


def test_a_run_writing_elsewhere_is_untouched_by_the_check(plan: Path) -> None:
    assert main(["run", "p.mdle", "-q", "--rate", "10", "--trace", "run.jsonl"]) == 0
    assert Path("run.jsonl").read_text().startswith('{"type":"header"')


def test_export_never_writes_over_its_trace(plan: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("mcap", reason="the mcap extra is not installed")
    assert main(["run", "p.mdle", "-q", "--rate", "10", "--trace", "t.jsonl"]) == 0
    before = Path("t.jsonl").read_bytes()
    os.link("t.jsonl", "t-link.mcap")
    for name in ("t.jsonl", "t-link.mcap"):
        assert main(["export", "t.jsonl", "-o", name]) == 1
        assert f"-o `{name}` is the trace `t.jsonl`" in capsys.readouterr().err
    assert Path("t.jsonl").read_bytes() == before


def test_plot_never_writes_over_its_trace(plan: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "p.mdle", "-q", "--rate", "10", "--trace", "t.jsonl"]) == 0
    os.symlink("t.jsonl", "t.png")
    before = Path("t.jsonl").read_bytes()
    assert main(["plot", "t.jsonl", "-o", "t.png"]) == 1
    assert "-o `t.png` is the trace `t.jsonl`" in capsys.readouterr().err
    assert Path("t.jsonl").read_bytes() == before
