"""The live view: plain lines off a terminal, a rich panel on one, and the summary."""

from __future__ import annotations

import io
import math
import re
from types import SimpleNamespace
from typing import Any

from mdle.lang import StringNode
from mdle.runtime import run
from mdle.runtime.scripted import ScriptedBackend
from mdle.view.live import LiveView, summary_rows


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
    assert "  main/r/a  ran 3x  ended by timer x2, ended with its parent" in lines
    assert "  main/r/b  ran 2x  ended by timer x2" in lines
    assert "ended: main ran to its end at 0.8 s" in lines
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
    assert "elements run" in text and "main/r/a" in text and "ended with its parent" in text
    assert "how it ended" in text and "ended by completed" not in text
    assert "real-time factor" in text


def test_summary_rows_report_faults_and_collisions(ir: SimpleNamespace) -> None:
    backend = ScriptedBackend(lambda t, k: {"stalled": True, "truth": {"collided": True}})
    result = run(ir.atom("push", 1.0), backend, stall_timeout=0.3)
    rows = dict(summary_rows(result, wall_seconds=0.01))
    assert rows["collided"] == "YES"
    assert rows["fault"].startswith("the robot stalled for 0.3 s")
    assert rows["ended"] == "push was aborted by an error at 0.3 s"
    assert rows["real-time factor"] == "30.0x"


def _follower(ir: SimpleNamespace) -> StringNode:
    """A plan whose atom records rc as follow_boundary does, 0.5 m from a wall on its right."""
    from mdle.core.backend import Command

    def step(args: Any, ctx: Any, state: Any) -> Command:
        ctx.cache["trace"] = {"rc": 0.5, "side_hit": 1.0, "side_range": 0.55,
                              "side_bearing": -math.pi / 2}
        return Command(1.0, 0.0)

    hug = ir.atom("hug", law=ir.const_law("follow_boundary", step=step), timer=2.0)
    return ir.string("main", ir.atom("go", 1.0, timer=0.3), hug)


def _wall_truth(t: float, k: int) -> dict[str, Any]:
    # the distance from the centre to the wall swings 0.5 +- 0.1 m (radius 0: a point robot)
    return {"truth": {"clearance": 0.5 + 0.1 * math.sin(k), "collided": False}}


def test_the_final_frame_stays_on_a_terminal(ir: SimpleNamespace) -> None:
    out = _Tty()
    run(_follower(ir), ScriptedBackend(_wall_truth), observers=[LiveView(stream=out)])
    text = re.sub(r"\x1b\[[0-9;?]*[a-zA-Z]", "", out.getvalue())
    final = text[text.rindex("timeline"):]  # what stays after the live panel is cleared
    # the timeline of events, in order, as a pipe shows them
    assert re.search(r"0\.00 s  start main .*\n.*0\.00 s  start main/go", final)
    assert "end   main/hug  timer" in final and "end   main  completed" in final
    assert "main/hug (rc 0.5 m): mean |d - rc| 0.0" in final and "closest approach 0.4" in final
    assert re.search(r"\n  S\.+E\n", final)  # the path map
    assert "x 0.0..2.3 m" in final


def test_plain_output_reports_following_and_the_map(ir: SimpleNamespace) -> None:
    out = io.StringIO()
    run(_follower(ir), ScriptedBackend(_wall_truth), observers=[LiveView(stream=out)])
    text = out.getvalue()
    [line] = [ln for ln in text.splitlines() if ln.startswith("  main/hug (rc 0.5 m)")]
    errs = [abs(0.1 * math.sin(k)) for k in range(3, 23)]
    half = errs[len(errs) // 2:]
    assert f"mean |d - rc| {sum(half) / len(half):.3f} m, max {max(half):.3f} m" in line
    assert "path (S start, E end, # boundary seen beside the robot):" in text
    assert "  S" + "." * 54 + "E" in text.splitlines()  # the path, one connected line
    # the wall seen 0.55 m to the right: a row of # below the path
    assert any(ln.count("#") > 10 and set(ln.strip()) <= {"#", " "} for ln in text.splitlines())
