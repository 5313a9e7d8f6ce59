"""The live view: plain lines off a terminal, a rich panel on one, and the summary."""

from __future__ import annotations

import io
from types import SimpleNamespace

from mdle.live import LiveView, summary_rows
from mdle.program import StringNode
from mdle.runtime import run
from mdle.runtime.scripted import ScriptedBackend


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def _plan(ir: SimpleNamespace) -> StringNode:
    r = ir.string("r", ir.atom("a", 1.0, timer=0.2), ir.atom("b", 0.0, 0.5, timer=0.1),
                  repeat=True, timer=0.7)
    return ir.string("main", r, ir.atom("c", timer=0.1))


def test_plain_lines_off_a_terminal(ir: SimpleNamespace) -> None:
    out = io.StringIO()
    view = LiveView(stream=out)
    assert view.plain
    script = lambda t, k: {"truth": {"clearance": 1.0 - t, "collided": False}}  # noqa: E731
    run(_plan(ir), ScriptedBackend(script), observers=[view])
    text = out.getvalue()
    assert "\x1b" not in text
    lines = text.splitlines()
    assert lines[0].split() == ["0.00", "s", "start", "main", "(x", "0.00", "m,", "y", "0.00",
                                "m,", "heading", "0", "deg)"]
    assert "    0.70 s  end   main/r/a  ended-by-parent" in text
    assert "  main/r/a  ran 3x  ended: timer x2, ended-by-parent" in lines
    assert "  main/r/b  ran 2x  ended: timer x2" in lines
    assert "ended: main: completed at 0.8 s" in lines
    assert "minimum clearance: 0.200 m" in lines and "collided: no" in lines
    assert "ticks: 9" in lines


def test_rich_panel_on_a_terminal_shows_levels_and_summary(ir: SimpleNamespace) -> None:
    out = _Tty()
    view = LiveView(stream=out)
    assert not view.plain
    run(_plan(ir), ScriptedBackend(), observers=[view])
    text = out.getvalue()
    assert "\x1b[" in text  # control codes: it drew a live panel
    assert "mdle run" in text and "timer left" in text  # the panel's title and columns
    assert "elements run" in text and "main/r/a" in text and "ended-by-parent" in text
    assert "real-time factor" in text


def test_summary_rows_report_faults_and_collisions(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend(lambda t, k: {"stalled": True, "truth": {"collided": True}})
    result = run(ir.atom("push", 1.0), backend, stall_timeout=0.3)
    rows = dict(summary_rows(result, wall_seconds=0.01))
    assert rows["collided"] == "YES"
    assert rows["fault"].startswith("the robot stalled for 0.3 s")
    assert rows["ended"] == "push: error at 0.3 s"
    assert rows["real-time factor"] == "30.0x"
