"""The numbers the docs quote beside the figures are the figures' own, and still true.

docs/figures/make_figures.py measures them from the runs it draws, writes them to
docs/figures/numbers.json and rewrites every marked number (``0.012<!--n:KEY-->``) in the
README and docs/*.md. Here: every marker names a number of the table and quotes it as the
table has it, and a fresh run of every figure gives the table again (a law that changes
makes this fail until the script is rerun). And every figure the README and docs show is
one the script makes.
"""

from __future__ import annotations

import importlib.util
import json
import re
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parent.parent
FIGURES = ROOT / "docs" / "figures"


def _script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_figures", FIGURES / "make_figures.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    saved = list(sys.path)  # the script puts the checkout first on sys.path, as a script
    try:                    # needs; other tests in this process must not see it there
        spec.loader.exec_module(module)
    finally:
        sys.path[:] = saved
    return module


@pytest.fixture(scope="module")
def script() -> ModuleType:
    return _script()


@pytest.fixture(scope="module")
def table() -> dict[str, Any]:
    data = json.loads((FIGURES / "numbers.json").read_text("utf-8"))
    assert isinstance(data, dict)
    return data


def test_every_quoted_number_is_the_tables(script: ModuleType, table: dict[str, Any]) -> None:
    quoted = 0
    for doc in script.doc_files():
        for m in script.MARKER.finditer(doc.read_text("utf-8")):
            value = script.lookup(table, m.group(2))
            assert value is not None, f"{doc.name}: `{m.group(2)}` is not in numbers.json"
            assert m.group(1) == value, (f"{doc.name} quotes {m.group(1)} for {m.group(2)}, "
                                         f"numbers.json has {value}: rerun make_figures.py")
            quoted += 1
        for m in script.BLOCK.finditer(doc.read_text("utf-8")):
            value = script.lookup(table, m.group(2))
            assert value is not None, f"{doc.name}: block `{m.group(2)}` is not in numbers.json"
            assert m.group(3) == value, f"{doc.name}: block {m.group(2)}: rerun make_figures.py"
            quoted += 1
    # the figures' runs, the hexagon at 10 Hz, the Pioneer on both models, the trash can
    assert quoted >= 30


def test_the_stale_numbers_are_gone() -> None:
    steering = (ROOT / "docs" / "steering.md").read_text("utf-8")
    assert "hexagon's error doubles (0.11 m)" not in steering
    assert "0.10 m body clearance" not in steering
    assert "0.012<!--n:hexagon-10hz.mean_err-->" in steering


def test_the_table_is_what_the_runs_give_now(script: ModuleType, table: dict[str, Any],
                                             tmp_path: Path) -> None:
    fresh = script.all_numbers(str(tmp_path), jobs=1)
    assert set(fresh) == set(table) - {"about", script.SWEEP}  # the study: too long for a test
    for run, numbers in fresh.items():
        assert numbers == table[run], f"{run}: rerun docs/figures/make_figures.py"


def test_a_marker_is_rewritten_and_an_unknown_one_named(script: ModuleType) -> None:
    text = "error 0.5<!--n:a.err--> m, axis +-0.3<!--n:a.axis--> 1/m, -2<!--n:a.k-->"
    table = {"a": {"err": "0.012", "axis": "0.1", "k": "-12.0"}}
    assert script.rewrite_numbers(text, table, "x.md") == (
        "error 0.012<!--n:a.err--> m, axis +-0.1<!--n:a.axis--> 1/m, -12.0<!--n:a.k-->")
    block = "<!--block:a.report-->\n```\nold\nlines\n```\n"
    assert script.rewrite_numbers(block, {"a": {"report": "new"}}, "x.md") == (
        "<!--block:a.report-->\n```\nnew\n```\n")
    with pytest.raises(KeyError, match=r"x\.md: no number `a\.gone`"):
        script.rewrite_numbers("1<!--n:a.gone-->", table, "x.md")


def test_every_shown_figure_comes_from_the_figures_script() -> None:
    module = _script()
    made = set(module.RUNS) | {"figure4-cabinet.png", "figure5-trashcan.png",
                               "sweep-kf-rate.png"}
    shown = set()
    for doc in [ROOT / "README.md", *(ROOT / "docs").glob("*.md")]:
        shown |= {Path(p).name for p in re.findall(r"!\[[^]]*\]\(([^)]+\.png)\)",
                                                     doc.read_text("utf-8"))}
    assert shown and shown <= made
    # and the script really writes those three (its own functions name them)
    text = (FIGURES / "make_figures.py").read_text("utf-8")
    assert "plot_figures(" in text and '"sweep-kf-rate.png"' in text
    for name in shown:
        assert (FIGURES / name).stat().st_size < 200_000  # kept small
