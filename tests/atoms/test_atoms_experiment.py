"""The curvature experiment (Table 1, Figures 4-5) and its command line."""

from __future__ import annotations

from pathlib import Path

import pytest

from mdle.cli import main
from mdle.experiments.curvature import ROWS, Row, run_table


@pytest.fixture(scope="module")
def table() -> dict[Row, dict[str, float]]:
    return run_table(draws=30, seed=3).rms


def _g(table: dict[Row, dict[str, float]], filtered: bool, w: tuple[int, ...], obj: str) -> float:
    return table[Row("geometric", filtered, w)][obj]


def test_every_row_has_both_objects(table: dict[Row, dict[str, float]]) -> None:
    assert list(table) == list(ROWS)
    for vals in table.values():
        assert set(vals) == {"trash can", "cabinet"}
        assert all(v > 0 for v in vals.values())


@pytest.mark.parametrize("obj", ["trash can", "cabinet"])
@pytest.mark.parametrize("filtered", [False, True])
def test_error_falls_with_window_size(table: dict[Row, dict[str, float]], obj: str,
                                      filtered: bool) -> None:
    g = [_g(table, filtered, w, obj) for w in ((1, 2, 3), (4, 5, 6), (7, 8, 9))]
    assert g[0] > g[1] > g[2] or (obj == "cabinet" and g[0] > g[1] and g[2] <= g[1] * 1.1)
    c = [table[Row("classical", filtered, (w,))][obj] for w in (1, 5, 8)]
    assert c[0] > c[1] > c[2] or (obj == "cabinet" and c[0] > c[1])


@pytest.mark.parametrize("obj", ["trash can", "cabinet"])
def test_filtering_helps_small_windows(table: dict[Row, dict[str, float]], obj: str) -> None:
    assert _g(table, True, (1, 2, 3), obj) < 0.6 * _g(table, False, (1, 2, 3), obj)
    classical_w1 = {f: table[Row("classical", f, (1,))][obj] for f in (False, True)}
    assert classical_w1[True] < 0.6 * classical_w1[False]


def test_cabinet_corners_leave_a_floor(table: dict[Row, dict[str, float]]) -> None:
    for f in (False, True):
        assert _g(table, f, (7, 8, 9), "cabinet") > 2.0
        assert _g(table, f, (7, 8, 9), "cabinet") > 3 * _g(table, f, (7, 8, 9), "trash can")
    # and the trash can, a true circle here, is estimated well with the paper's windows
    assert _g(table, False, (7, 8, 9), "trash can") < 1.2


def test_cli_prints_table_1_and_writes_figures(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiment", "curvature", "--draws", "3", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "geometric, unfiltered, w 7-9" in text and "15.47" in text  # the paper's column
    assert (tmp_path / "figure4-cabinet.png").stat().st_size > 1000
    assert (tmp_path / "figure5-trashcan.png").stat().st_size > 1000


def test_cli_refuses_zero_draws(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiment", "curvature", "--draws", "0"]) == 2
    assert "at least 1" in capsys.readouterr().err


def test_cli_following_prints_one_line_per_shape(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiment", "following", "--duration", "3"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [ln.split()[0] for ln in lines[1:]] == ["ellipse", "hexagon", "u-shape", "square",
                                                   "arrow", "wall"]
    assert all(ln.split()[2] == "False" for ln in lines[1:])  # no collision in 3 s
