"""A long unfinished input is lexed once, not once per line.

Piping 4,000 lines of one statement into the REPL used to re-lex the whole statement on
every line (45 s). The completeness check now keeps the lexer state at the last line
break; the cost is pinned by counting the characters handed to the lexer.
"""

from __future__ import annotations

import io

import pytest

from mdle.lang import workspace as workspace_module
from mdle.repl.commands import Repl
from mdle.repl.plain import run_plain
from mdle.repl.session import Session


def test_4000_line_statement_is_lexed_about_once(monkeypatch: pytest.MonkeyPatch) -> None:
    lexed = [0]
    real = workspace_module.lex_fragment

    def counting(text: str, opened: int = 0) -> object:
        lexed[0] += len(text)
        return real(text, opened)

    monkeypatch.setattr(workspace_module, "lex_fragment", counting)
    n = 4000
    lines = ["behavior b = (", "    ("] + ["        a," for _ in range(n)] + ["    ),",
                                                                        "    never,", "    inf,",
                                                                        ")"]
    script = "atom a = (go(0.3 m/s), never, 1 s)\n" + "\n".join(lines) + "\n:defs\n"
    out, err = io.StringIO(), io.StringIO()
    repl = Repl(Session("ellipse"), out, err)
    code = run_plain(repl, io.StringIO(script))
    assert code == 0, err.getvalue()
    assert "behavior b = " in out.getvalue()
    assert lexed[0] <= 3 * len(script), (lexed[0], len(script))


@pytest.mark.parametrize("text, complete", [
    ("atom a = (go(1 m/s),\n never,", False),
    ("atom a = (go(1 m/s),\n never, 1 s)", True),
    ("atom a =\n", False),
    ("atom a = (go(1 m/s), never, 1 s) # trailing,\n", True),
    ("atom a = " + "(" * 150, True),
    ("atom a = (\n$", False),
])
def test_completeness_line_by_line_matches_whole(text: str, complete: bool) -> None:
    repl = Repl(Session("ellipse"), io.StringIO(), io.StringIO())
    lines = text.split("\n")
    for i in range(1, len(lines)):
        repl.is_complete("\n".join(lines[:i]))
    assert repl.is_complete(text) is complete
    fresh = Repl(Session("ellipse"), io.StringIO(), io.StringIO())
    assert fresh.is_complete(text) is complete
