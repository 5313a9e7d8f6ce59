"""docs/repl.md's walkthrough transcript is what the REPL prints, to the character.

The section "Tuning `follow_boundary`'s rc on the ellipse world" gives the session's
inputs (the `tune.txt` block) and then its output in several blocks, each starting with an
echoed ``mdle> `` line, with prose between them. This test feeds the inputs to the plain
front end (as ``mdle repl --world ellipse --echo < tune.txt`` does, with standard output
and standard error on one stream) and checks that the blocks, joined, are the output, and
that the ``$ cat hug.mdle`` block is the file ``:save`` wrote.

When the REPL's output changes on purpose, regenerate the blocks from the real output and
then reread the prose around them::

    MDLE_REGENERATE_DOCS=1 pytest tests/repl/test_repl_docs_transcript.py
"""

from __future__ import annotations

import io
import os
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

from mdle.repl.commands import Repl
from mdle.repl.plain import PROMPT, run_plain
from mdle.repl.session import Session

DOC = Path(__file__).resolve().parents[2] / "docs" / "repl.md"
SECTION = "## Tuning `follow_boundary`'s rc on the ellipse world"
SAVED = "hug.mdle"
CAT = f"$ cat {SAVED}"
REGENERATE = os.environ.get("MDLE_REGENERATE_DOCS") == "1"

_FENCE = re.compile(r"^```[^\n]*\n(.*?)^```$", re.MULTILINE | re.DOTALL)


@dataclass
class Block:
    """A fenced block's content, as offsets into the whole document."""

    start: int
    end: int
    lines: list[str]


def _section_bounds(doc: str) -> tuple[int, int]:
    """Offsets of the walkthrough section (its heading up to the next ``## `` heading)."""
    start = doc.index(SECTION)
    after = doc.find("\n## ", start + len(SECTION))
    return start, len(doc) if after < 0 else after


def _blocks(doc: str) -> list[Block]:
    """The fenced blocks of the walkthrough section, in order."""
    lo, hi = _section_bounds(doc)
    return [Block(m.start(1), m.end(1), m.group(1).splitlines())
            for m in _FENCE.finditer(doc, lo, hi)]


def _inputs(blocks: list[Block]) -> list[str]:
    """The session's input lines: the first block (the `tune.txt` one)."""
    return blocks[0].lines


def _transcript(blocks: list[Block]) -> list[Block]:
    """The blocks that show the session's output: those starting with an echoed input."""
    return [b for b in blocks if b.lines and b.lines[0].startswith(PROMPT)]


def _cat_block(blocks: list[Block]) -> Block:
    """The block that shows the saved file."""
    (block,) = [b for b in blocks if b.lines and b.lines[0] == CAT]
    return block


def _run(inputs: list[str], where: Path) -> tuple[int, list[str], str]:
    """Run the inputs in the ellipse world in ``where``: (exit code, output lines, saved file)."""
    stream = io.StringIO()
    repl = Repl(Session("ellipse"), stream, stream)  # one stream, as a terminal shows both
    cwd = Path.cwd()
    os.chdir(where)
    try:
        code = run_plain(repl, io.StringIO("\n".join(inputs) + "\n"), echo=True)
    finally:
        os.chdir(cwd)
    return code, stream.getvalue().splitlines(), (where / SAVED).read_text(encoding="utf-8")


def _split(output: list[str], heads: list[str]) -> list[list[str]]:
    """Cut the output into pieces, each starting at the next of ``heads`` (echoed inputs)."""
    assert output and output[0] == heads[0], "the output must start with the first block's input"
    cuts = []
    at = 0
    for head in heads:
        assert head in output[at:], f"the output no longer has the input line {head!r}"
        at = output.index(head, at)
        cuts.append(at)
        at += 1
    return [output[a:b] for a, b in zip(cuts, cuts[1:] + [len(output)], strict=True)]


def _replace(doc: str, pieces: list[tuple[Block, list[str]]]) -> str:
    """The document with each block's content replaced by its new lines."""
    for block, lines in sorted(pieces, key=lambda p: p[0].start, reverse=True):
        doc = doc[:block.start] + "".join(line + "\n" for line in lines) + doc[block.end:]
    return doc


def test_transcript_is_the_repl_output(tmp_path: Path) -> None:
    doc = DOC.read_text(encoding="utf-8")
    blocks = _blocks(doc)
    shown = _transcript(blocks)
    assert len(shown) >= 2, "the walkthrough's transcript blocks were not found"
    code, output, saved = _run(_inputs(blocks), tmp_path)
    cat = _cat_block(blocks)
    if REGENERATE:
        pieces = _split(output, [b.lines[0] for b in shown])
        new = _replace(doc, [*zip(shown, pieces, strict=True),
                             (cat, [CAT, *saved.splitlines()])])
        if new != doc:
            DOC.write_text(new, encoding="utf-8")
        doc = new
        blocks = _blocks(doc)
        shown, cat = _transcript(blocks), _cat_block(blocks)
    documented = [line for b in shown for line in b.lines]
    hint = "rerun with MDLE_REGENERATE_DOCS=1 and reread the prose around the transcript"
    assert documented == output, f"docs/repl.md's transcript is not what the REPL prints; {hint}"
    assert cat.lines == [CAT, *saved.splitlines()], f"the saved file differs; {hint}"
    assert code == 1  # the `hgu` typo, as the prose says


def test_split_and_replace_round_trip() -> None:
    doc = ("x\n" + SECTION + "\n```\na\n```\n\ntext\n```\nmdle> a\n1\n```\nmid\n"
           "```\nmdle> b\n2\n```\n## next\n```\nmdle> c\n```\n")
    shown = _transcript(_blocks(doc))
    assert [b.lines for b in shown] == [["mdle> a", "1"], ["mdle> b", "2"]]
    pieces = _split(["mdle> a", "3", "4", "mdle> b"], ["mdle> a", "mdle> b"])
    assert pieces == [["mdle> a", "3", "4"], ["mdle> b"]]
    new = _replace(doc, list(zip(shown, pieces, strict=True)))
    assert new == ("x\n" + SECTION + "\n```\na\n```\n\ntext\n```\nmdle> a\n3\n4\n```\nmid\n"
                   "```\nmdle> b\n```\n## next\n```\nmdle> c\n```\n")
    with pytest.raises(AssertionError):
        _split(["mdle> a"], ["mdle> a", "mdle> b"])
