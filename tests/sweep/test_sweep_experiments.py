"""`mdle experiment following|random-starts` on the sweep engine: same tables, resumable."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from mdle.cli import main
from mdle.experiments.following import SHAPES, follow_task, run_follow, run_many


def test_run_many_matches_the_in_process_run() -> None:
    tasks = [follow_task(w, seed=2, duration=4.0, rate=20.0, index=i)
             for i, w in enumerate(("ellipse", "hexagon"))]
    many = run_many(tasks, jobs=2)
    for task, r in zip(tasks, many, strict=True):
        one = run_follow(task.labels["world"], seed=2, duration=4.0, rate=20.0)
        assert (r.world, r.rc, r.collided) == (one.world, one.rc, one.collided)
        assert r.min_clearance == pytest.approx(one.min_clearance, abs=1e-9)
        assert r.max_err == pytest.approx(one.max_err, abs=1e-9)
        assert r.mean_err == pytest.approx(one.mean_err, abs=1e-9)
        assert r.corner_fraction == pytest.approx(one.corner_fraction, abs=0.03)


def _table(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def test_following_resumes_from_its_table(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["experiment", "following", "--duration", "3", "--resume", "--out", str(tmp_path)]
    assert main(argv) == 0
    first = capsys.readouterr()
    table = tmp_path / "following" / "results.csv"
    rows = _table(table)
    assert len(rows) == len(SHAPES) and all(r["status"] == "ok" for r in rows)
    assert main(argv) == 0
    again = capsys.readouterr()
    assert again.out == first.out                    # the same table, from the rows kept
    assert f"{len(SHAPES)} already in the table" in again.err
    assert _table(table) == rows


def test_generated_random_starts_resume(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["experiment", "random-starts", "--generated", "--shapes", "2", "--starts", "1",
            "--duration", "3", "--rate", "20", "--jobs", "2", "--resume", "--out",
            str(tmp_path)]
    code = main(argv)
    first = capsys.readouterr().out
    table = tmp_path / "random-starts-generated" / "results.csv"
    rows = _table(table)
    assert code in (0, 3) and len(rows) == 2 and {r["family"] for r in rows} == {
        "star", "nonconvex"}
    table.write_text("".join(table.read_text().splitlines(keepends=True)[:2]))  # lose one
    assert main(argv) == code
    assert capsys.readouterr().out == first
    assert [r["key"] for r in _table(table)] == [r["key"] for r in rows[:1]] + [
        r["key"] for r in rows if r["key"] != rows[0]["key"]]
