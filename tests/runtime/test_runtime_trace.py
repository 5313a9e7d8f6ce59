"""The JSON lines trace: written as the run goes, strict JSON, read back (also cut short)."""

from __future__ import annotations

import json
import math

import pytest

from mdle.backend import Command
from mdle.runtime import Cause, run
from mdle.runtime.scripted import ScriptedBackend
from mdle.trace import TraceError, TraceWriter, read_trace


def test_trace_has_header_events_samples_and_end(ir, tmp_path):
    path = tmp_path / "run.jsonl"
    main = ir.string("main", ir.atom("a", 1.0, timer=0.2), ir.atom("b", 0.0, 0.5, timer=0.1))
    script = lambda t, k: {"truth": {"clearance": 2.0 - t, "collided": False}}  # noqa: E731
    result = run(main, ScriptedBackend(script),
                 observers=[TraceWriter(path, {"program": {"file": "x.mdle", "element": "main"},
                                               "world": "none", "seed": 7})])
    lines = path.read_text().splitlines()
    records = [json.loads(line) for line in lines]  # every line is strict JSON
    assert [r["type"] for r in records][:2] == ["header", "start"]
    head = records[0]
    assert head["format"] == "mdle-trace" and head["seed"] == 7 and "python" in head["versions"]
    trace = read_trace(path)
    assert [(e["kind"], e["path"], e["cause"]) for e in trace.events] == [
        ("start", "main", None), ("start", "main/a", None), ("end", "main/a", "timer"),
        ("start", "main/b", None), ("end", "main/b", "timer"), ("end", "main", "completed")]
    assert len(trace.samples) == result.ticks == 4
    assert trace.paths() == ["main/a", "main/a", "main/b", ""]
    assert trace.column("x").tolist() == pytest.approx([0.0, 0.1, 0.2, 0.2])
    assert trace.column("clearance").tolist() == pytest.approx([2.0, 1.9, 1.8, 1.7])
    assert trace.column("cmd_omega").tolist() == [0.0, 0.0, 0.5, 0.0]
    assert trace.end["cause"] == "completed" and trace.end["ticks"] == 4
    assert len(trace.end["terminations"]) == 3 and not trace.truncated


def test_non_finite_values_become_null_and_diagnostics_are_kept(ir, tmp_path):
    def step(args, ctx, state):
        ctx.cache["trace"] = {"front": math.inf, "curvature": -0.5 if ctx.t else math.nan}
        return Command(0.2, 0.0)

    path = tmp_path / "t.jsonl"
    run(ir.atom("f", law=ir.const_law("f", step=step), timer=0.2), ScriptedBackend(),
        observers=[TraceWriter(path)])
    for line in path.read_text().splitlines():
        json.loads(line, parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    trace = read_trace(path)
    assert trace.diag_names() == ["curvature", "front"]
    curv = trace.column("diag.curvature")
    assert math.isnan(curv[0]) and curv[1] == -0.5 and math.isnan(curv[2])
    assert math.isnan(trace.column("diag.front")[1])


def test_records_are_on_disk_before_the_run_ends(ir, tmp_path):
    # flushed per record: a crash (here: a failing law) loses nothing already written
    seen = []
    path = tmp_path / "t.jsonl"

    def step(args, ctx, state):
        seen.append(len(path.read_text().splitlines()))
        return Command()

    run(ir.atom("a", law=ir.const_law("a", step=step), timer=0.2), ScriptedBackend(),
        observers=[TraceWriter(path)])
    # header + start + START event before tick 0's law runs; then one sample per tick
    assert seen == [3, 4]


def test_reader_accepts_a_cut_off_last_line(ir, tmp_path):
    path = tmp_path / "t.jsonl"
    run(ir.atom("a", 1.0, timer=0.3), ScriptedBackend(), observers=[TraceWriter(path)])
    text = path.read_text()
    cut = text[: text.rindex('{"type":"end"') + 20]
    path.write_text(cut)
    trace = read_trace(path)
    assert trace.truncated and trace.end is None and len(trace.samples) == 4


@pytest.mark.parametrize("text, message", [
    ("", "empty file"),
    ('{"type":"sample"}\n', "not an mdle trace"),
    ('{"type":"header","format":"mdle-trace","version":99}\n', "newer"),
    ('{"type":"header","format":"mdle-trace","version":1}\nnot json\n{"type":"end"}\n',
     ":2:1: error: not JSON"),
    ('{"type":"header","format":"mdle-trace","version":1}\n[1, 2]\n', "JSON object"),
])
def test_reader_rejects_what_is_not_a_trace(tmp_path, text, message):
    path = tmp_path / "bad.jsonl"
    path.write_text(text)
    with pytest.raises(TraceError, match=message):
        read_trace(path)


def test_missing_trace_is_a_clear_error(tmp_path):
    with pytest.raises(TraceError, match="cannot read trace"):
        read_trace(tmp_path / "nope.jsonl")


def test_trace_of_an_aborted_run_ends_with_the_abort(ir, tmp_path):
    path = tmp_path / "t.jsonl"
    result = run(ir.atom("a", 1.0), ScriptedBackend(), until=0.3, observers=[TraceWriter(path)])
    trace = read_trace(path)
    assert result.cause is Cause.STOPPED and trace.end["cause"] == "stopped"
    assert trace.events[-1]["cause"] == "stopped"
