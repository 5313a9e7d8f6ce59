"""Every plan the README and docs/ show runs to its end in its world without a collision.

A plan shown in Markdown is a ```mdle block holding a whole program (an entry: `run NAME`
or a plan `main`) and a comment line `# world: NAME` naming the reference world it runs
in (optionally `# rate: HZ`, default 10). Fragments (a statement, a definition alone, a
layout example) go in plain ``` blocks; a plain block with a `run` line is refused, so no
plan hides from this test.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
_FENCE = re.compile(r"^```([A-Za-z]*)[ \t]*\n(.*?)^```[ \t]*$", re.M | re.S)


@dataclass(frozen=True)
class Block:
    """A fenced code block: the page, the line its text starts on, its language, text."""

    page: Path
    line: int
    lang: str
    text: str

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(REPO)}:{self.line}"


def blocks(page: Path) -> list[Block]:
    text = page.read_text(encoding="utf-8")
    out = []
    for m in _FENCE.finditer(text):
        line = text.count("\n", 0, m.start(2)) + 1
        out.append(Block(page, line, m.group(1), m.group(2)))
    return out


PLANS = [b for page in PAGES for b in blocks(page) if b.lang == "mdle"]


def _option(block: Block, name: str) -> str | None:
    m = re.search(rf"^#\s*{name}:\s*(\S+)\s*$", block.text, re.M)
    return m.group(1) if m else None


def test_the_readme_and_docs_show_plans() -> None:
    pages = {b.page.name for b in PLANS}
    assert {"README.md", "language.md"} <= pages


@pytest.mark.parametrize("block", PLANS, ids=[b.where for b in PLANS])
def test_shown_plan_runs_to_its_end_without_a_collision(block: Block) -> None:
    from mdle import sim
    from mdle.lang import load_text
    from mdle.runtime import Cause, run_named

    world = _option(block, "world")
    assert world, f"{block.where}: a ```mdle block needs a `# world: NAME` comment line"
    rate = float(_option(block, "rate") or 10)
    program = load_text(block.text, block.where)
    assert program.entry, f"{block.where}: a shown plan needs `run NAME` or a plan `main`"
    assert not program.warnings, program.warnings
    backend = sim.SimBackend(sim.load_world(world))
    try:
        result = run_named(program, None, backend, rate=rate)
    finally:
        backend.close()
    assert not result.collided, f"{block.where}: collided"
    assert result.fault is None, result.fault
    assert result.cause in (Cause.COMPLETED, Cause.INTERRUPT, Cause.TIMER), result.cause


def test_no_plan_hides_in_an_untagged_block() -> None:
    hidden = [b.where for page in PAGES for b in blocks(page)
              if b.lang == "" and re.search(r"^run [a-z_][a-z0-9_]*\s*(#|$)", b.text, re.M)
              and not b.text.lstrip().startswith(("$", "mdle>"))]
    assert not hidden, f"whole plans must be ```mdle blocks with a `# world:` line: {hidden}"


def test_the_language_patrol_example_actually_turns() -> None:
    # plans/language/patrol.mdle once ended its patrol before the first turn
    from mdle import sim
    from mdle.lang import load_program
    from mdle.runtime import run_named

    plan = REPO / "plans" / "language" / "patrol.mdle"
    backend = sim.SimBackend(sim.load_world(plan.with_suffix(".world.yaml")))
    result = run_named(load_program(plan), None, backend, rate=10)
    spins = [t for t in result.terminations if t.path == "main/patrol/spin"]
    assert len(spins) >= 4 and not result.collided and result.ok
