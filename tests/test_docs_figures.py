"""Every figure the README and docs/ show is made by docs/figures/make_figures.py."""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_shown_figure_comes_from_the_figures_script() -> None:
    spec = importlib.util.spec_from_file_location("make_figures",
                                                  ROOT / "docs" / "figures" / "make_figures.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    saved = list(sys.path)  # the script puts the checkout first on sys.path, as a script
    try:                    # needs; other tests in this process must not see it there
        spec.loader.exec_module(module)
    finally:
        sys.path[:] = saved
    made = set(module.RUNS) | {"figure4-cabinet.png", "figure5-trashcan.png",
                               "sweep-kf-rate.png"}
    shown = set()
    for doc in [ROOT / "README.md", *(ROOT / "docs").glob("*.md")]:
        shown |= {Path(p).name for p in re.findall(r"!\[[^]]*\]\(([^)]+\.png)\)",
                                                     doc.read_text("utf-8"))}
    assert shown and shown <= made
    # and the script really writes those three (its own functions name them)
    text = (ROOT / "docs" / "figures" / "make_figures.py").read_text("utf-8")
    assert "plot_figures(" in text and '"sweep-kf-rate.png"' in text
    for name in shown:
        assert (ROOT / "docs" / "figures" / name).stat().st_size < 200_000  # kept small
