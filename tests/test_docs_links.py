"""The README and docs/ stand alone: every file they link to or name exists in the repository.

Markdown links (``[text](path)``) resolve from the page's folder; paths written in
backticks (``plans/paper/fig1-ellipse.mdle``, ``atoms/steering.py::name``) from the
repository root. Files outside the repository (``../shared/...``, ``control-law.md``) are
never cited: the docs summarise what a reader needs.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
_LINK = re.compile(r"\]\(([^)\s]+)\)")
#: a backticked repository path: a known top-level folder, then a file or folder name
_PATH = re.compile(r"`((?:grammar|mdle|atoms|sim|plans|docs|benchmarks|tests|\.ci)/[\w./-]*)"
                   r"(?:::[\w\[\]-]+)?`")
_FOREIGN = re.compile(r"control-law\.md|shared/(?:paper|hardware|design)/")


def _without_code_blocks(text: str) -> str:
    return re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_linked_or_named_file_exists(page: Path) -> None:
    text = _without_code_blocks(page.read_text(encoding="utf-8"))
    missing = []
    for target in _LINK.findall(text):
        if re.match(r"[a-z]+:|#", target):
            continue
        if not (page.parent / target.split("#")[0]).exists():
            missing.append(target)
    for target in _PATH.findall(text):
        if not (REPO / target).exists():
            missing.append(target)
    assert not missing, f"{page.name} names files the repository lacks: {missing}"


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_no_page_cites_files_outside_the_repository(page: Path) -> None:
    found = _FOREIGN.findall(page.read_text(encoding="utf-8"))
    assert not found, f"{page.name} cites {found}: summarise what the reader needs instead"
