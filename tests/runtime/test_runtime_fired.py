"""The run says which condition of an interrupt fired: terminations, events, trace, summary."""

from __future__ import annotations

import json
from pathlib import Path

from mdle.lang import load_text
from mdle.record.trace import TraceWriter
from mdle.runtime import Cause, run_named
from mdle.runtime.scripted import ScriptedBackend
from mdle.view.live import summary_rows


def _run(text: str, tmp_path: Path | None = None) -> object:
    program = load_text(text, "t.mdle")
    observers = [] if tmp_path is None else [TraceWriter(tmp_path / "t.jsonl", {})]
    return run_named(program, None, ScriptedBackend(), rate=10, until=20,
                     observers=observers)


def test_the_part_of_an_or_that_held_is_named(tmp_path: Path) -> None:
    result = _run("interrupt far(d = 0.45 m) = x > d\n"
                  "atom a = (go(1 m/s), stalled or far or t > 5 s, 10 s)\n"
                  "plan main = ((a), never, 20 s)\n", tmp_path)
    end = next(t for t in result.terminations if t.path == "main/a")  # type: ignore[attr-defined]
    assert end.cause is Cause.INTERRUPT and end.fired == "far"
    records = [json.loads(line) for line in (tmp_path / "t.jsonl").read_text().splitlines()]
    ends = [r for r in records if r.get("type") == "event" and r.get("kind") == "end"]
    assert [r.get("fired") for r in ends] == ["far", None]
    final = records[-1]
    assert final["type"] == "end"
    assert [x.get("fired") for x in final["terminations"]] == ["far", None]


def test_conditions_that_held_together_are_all_named() -> None:
    result = _run("atom a = (go(1 m/s), x > 0.45 m or t >= 0.5 s or stalled, 10 s)\nrun a\n")
    t = result.termination  # type: ignore[attr-defined]
    assert t.fired == "x > 0.45 m and t >= 0.5 s"
    assert summary_rows(result)[0][1].startswith(  # type: ignore[arg-type]
        "a ended by interrupt (x > 0.45 m and t >= 0.5 s) at")


def test_one_condition_is_named_whole_and_timers_name_none() -> None:
    result = _run("atom a = (go(1 m/s), x > 0.45 m and t > 0.1 s, 10 s)\nrun a\n")
    assert result.termination.fired == "x > 0.45 m and t > 0.1 s"  # type: ignore[attr-defined]
    timed = _run("atom a = (go(1 m/s), x > 5 m or stalled, 0.3 s)\nrun a\n")
    assert timed.termination.cause is Cause.TIMER  # type: ignore[attr-defined]
    assert timed.termination.fired is None  # type: ignore[attr-defined]
