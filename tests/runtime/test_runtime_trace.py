"""The JSON lines trace: written as the run goes, strict JSON, read back (also cut short)."""

from __future__ import annotations

import gc
import json
import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from mdle.atoms.registry import Context
from mdle.core.backend import Command
from mdle.core.errors import MdleRuntimeError
from mdle.record.load import read_trace
from mdle.record.trace import TraceError, TraceWriteError, TraceWriter
from mdle.runtime import Cause, Scheduler, run
from mdle.runtime.scripted import ScriptedBackend


def test_trace_has_header_events_samples_and_end(ir: SimpleNamespace, tmp_path: Path) -> None:
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
    assert trace.end is not None
    assert trace.end["cause"] == "completed" and trace.end["ticks"] == 4
    assert len(trace.end["terminations"]) == 3 and not trace.truncated


def test_non_finite_values_become_null_and_diagnostics_are_kept(ir: SimpleNamespace,
                                                                tmp_path: Path) -> None:
    def step(args: Any, ctx: Context, state: Any) -> Command:
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


def test_without_a_flush_period_every_record_is_on_disk_at_once(ir: SimpleNamespace,
                                                                tmp_path: Path) -> None:
    # flush_period=0: one write per record, the file is complete before each law step
    seen = []
    path = tmp_path / "t.jsonl"

    def step(args: Any, ctx: Context, state: Any) -> Command:
        seen.append(len(path.read_text().splitlines()))
        return Command()

    run(ir.atom("a", law=ir.const_law("a", step=step), timer=0.2), ScriptedBackend(),
        observers=[TraceWriter(path, flush_period=0.0)])
    # header + start + START event before tick 0's law runs; then one sample per tick
    assert seen == [3, 4]


class _Clock:
    """A wall clock the test moves by hand."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_samples_wait_at_most_the_flush_period_and_events_none(ir: SimpleNamespace,
                                                               tmp_path: Path) -> None:
    clock = _Clock()
    seen = []
    path = tmp_path / "t.jsonl"

    def step(args: Any, ctx: Context, state: Any) -> Command:
        seen.append([json.loads(x)["type"] for x in path.read_text().splitlines()])
        clock.now += 0.004  # each tick takes 4 ms of wall time
        return Command()

    main = ir.string("main", ir.atom("a", law=ir.const_law("a", step=step), timer=0.5),
                     ir.atom("b", law=ir.const_law("b", step=step), timer=0.2))
    run(main, ScriptedBackend(), observers=[TraceWriter(path, flush_period=0.01, clock=clock)])
    head = ["header", "start", "event", "event"]
    assert seen[0] == head  # header, start and the START events are written at once
    # samples queued at +4, +8, +12 ms after the last write go out together at +12 ms
    # (none waits more than 10 ms); the next batch 12 ms later
    assert [s.count("sample") for s in seen[:5]] == [0, 0, 0, 3, 3]
    # a's timer ends it at tick 5: its END and b's START are written at once, together
    # with the two samples still queued before them
    assert seen[5] == head + ["sample"] * 5 + ["event", "event"]
    trace = read_trace(path)
    assert len(trace.samples) == 8 and trace.end is not None and not trace.truncated


@pytest.mark.parametrize("error", [KeyboardInterrupt, RuntimeError])
def test_a_run_ended_by_ctrl_c_or_a_crash_leaves_every_sample_on_disk(
        ir: SimpleNamespace, tmp_path: Path, error: type[BaseException]) -> None:
    # a long flush period: only the run's end can have written the samples
    calls = []

    def step(args: Any, ctx: Context, state: Any) -> Command:
        calls.append(ctx.t)
        if len(calls) == 5:
            raise error("boom")
        return Command(0.1, 0.0)

    path = tmp_path / "t.jsonl"
    writer = TraceWriter(path, flush_period=3600.0)
    with pytest.raises((KeyboardInterrupt, MdleRuntimeError)):
        run(ir.atom("a", law=ir.const_law("a", step=step)), ScriptedBackend(),
            observers=[writer])
    trace = read_trace(path)
    # the four ticks, then the stop command sent as the run was aborted
    assert len(trace.samples) == 5 and not trace.truncated
    assert [s["cmd_v"] for s in trace.samples] == [0.1] * 4 + [0.0]
    assert trace.samples[-1]["path"] == ""
    assert trace.end is not None
    assert trace.end["cause"] == ("stopped" if error is KeyboardInterrupt else "error")


def test_a_writer_dropped_without_close_still_writes_what_it_queued(ir: SimpleNamespace,
                                                                    tmp_path: Path) -> None:
    path = tmp_path / "t.jsonl"
    writer = TraceWriter(path, flush_period=3600.0)
    sch = Scheduler(ir.atom("a", 0.1), ScriptedBackend(), observers=[writer])
    for _ in range(3):
        sch.tick()
    del sch, writer
    gc.collect()
    trace = read_trace(path)
    assert len(trace.samples) == 3 and trace.end is None and not trace.truncated


def test_flush_period_must_not_be_negative(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="flush_period"):
        TraceWriter(tmp_path / "t.jsonl", flush_period=-1.0)


def test_reader_accepts_a_cut_off_last_line(ir: SimpleNamespace, tmp_path: Path) -> None:
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
def test_reader_rejects_what_is_not_a_trace(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.jsonl"
    path.write_text(text)
    with pytest.raises(TraceError, match=message):
        read_trace(path)


def test_missing_trace_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(TraceError, match="cannot read trace"):
        read_trace(tmp_path / "nope.jsonl")


def test_trace_of_an_aborted_run_ends_with_the_abort(ir: SimpleNamespace, tmp_path: Path) -> None:
    path = tmp_path / "t.jsonl"
    result = run(ir.atom("a", 1.0), ScriptedBackend(), until=0.3, observers=[TraceWriter(path)])
    trace = read_trace(path)
    assert trace.end is not None
    assert result.cause is Cause.STOPPED and trace.end["cause"] == "stopped"
    assert trace.events[-1]["cause"] == "stopped"


class _FillsUp:
    """The trace's raw file on a disk with ``room`` bytes left: a write that does not fit
    is written in part (as the kernel does), and the next one fails with ENOSPC."""

    def __init__(self, raw: Any, room: int) -> None:
        self.raw, self.room = raw, room

    def write(self, data: Any) -> int:
        import errno

        if self.room <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        n = min(len(data), self.room)
        self.room -= n
        return int(self.raw.write(bytes(data[:n])))

    def __getattr__(self, name: str) -> Any:
        return getattr(self.raw, name)


def _whole_lines(path: Path) -> list[dict[str, Any]]:
    data = path.read_bytes()
    assert data == b"" or data.endswith(b"\n"), "a record was cut"
    return [json.loads(line) for line in data.splitlines()]


@pytest.mark.parametrize("room", [700, 2000, 5000])
def test_a_full_disk_keeps_whole_records_and_ends_the_run(
        ir: SimpleNamespace, tmp_path: Path, room: int) -> None:
    path = tmp_path / "t.jsonl"
    backend = ScriptedBackend()
    writer = TraceWriter(path, flush_period=0.0)
    writer._file = _FillsUp(writer._file, room)  # type: ignore[assignment]
    atom = ir.atom("a", law=ir.const_law("a", 0.5))
    with pytest.raises(TraceWriteError, match="No space left on device"):
        run(atom, backend, until=100.0, observers=[writer])
    records = _whole_lines(path)  # every line whole, nothing cut
    assert records[0]["type"] == "header"
    assert writer.error is not None and str(path) in str(writer.error)
    assert writer.error.records == len(records) - (1 if writer.ended else 0)
    # the run was ended by the failure and the robot stopped
    assert backend.stops and backend.stops[-1] >= backend.commands[-1][0]
    if writer.ended:  # cutting the failed batch made room for the end record
        assert records[-1]["type"] == "end" and records[-1]["cause"] == "error"
        assert "No space left" in records[-1]["fault"]
    assert read_trace(path).header["type"] == "header"


def test_a_write_cut_by_a_signal_leaves_no_partial_record(tmp_path: Path) -> None:
    path = tmp_path / "t.jsonl"
    writer = TraceWriter(path, flush_period=3600.0)

    class _CutShort:
        """A write that stops half way, then a Ctrl-C before the rest is written."""

        def __init__(self, raw: Any) -> None:
            self.raw, self.calls = raw, 0

        def write(self, data: Any) -> int:
            self.calls += 1
            if self.calls == 1:
                return int(self.raw.write(bytes(data[: len(data) // 2])))
            raise KeyboardInterrupt

        def __getattr__(self, name: str) -> Any:
            return getattr(self.raw, name)

    size = path.stat().st_size
    raw = writer._file
    writer._file = _CutShort(raw)  # type: ignore[assignment]
    writer._pending.append('{"type":"extra","n":1}')
    with pytest.raises(KeyboardInterrupt):
        writer.flush()
    assert path.stat().st_size == size  # taken back to the header
    writer._file = raw
    writer._pending.append('{"type":"extra","n":2}')
    writer.close()
    assert [r["type"] for r in _whole_lines(path)] == ["header", "extra"]


def test_a_header_that_cannot_be_written_is_an_error_naming_the_file(tmp_path: Path) -> None:
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    with pytest.raises(TraceWriteError, match="cannot write the trace `/dev/full`"):
        TraceWriter("/dev/full")


def _sample(**changes: Any) -> Any:
    from types import MappingProxyType

    from mdle.runtime.events import Sample

    base: dict[str, Any] = dict(time=12.340000000000002, x=1.25, y=-2.000000001, theta=0.1234567891,
                v=0.6, omega=-0.01, cmd_v=0.6, cmd_omega=0.0, path='main/"a"%s',
                lateness=0.0, scan_age=0.02, stalled=False,
                diag=MappingProxyType({"side_range": 1.0000000004, "mo%de": 2.0}),
                clearance=0.81234, collided=False, true_x=3.0, true_y=4.0, true_theta=-3.1,
                scan=None)
    base.update(changes)
    return Sample(**base)


@pytest.mark.parametrize("changes, finite", [
    ({}, True), ({"stalled": True, "collided": True}, True),
    ({"scan_age": None, "clearance": None}, True),
    ({"collided": None, "true_x": None, "true_y": None, "true_theta": None}, True),
    ({"diag": {}}, True), ({"true_theta": None}, True), ({"path": ""}, True),
    ({"diag": {"a": math.inf}}, False), ({"x": math.nan}, False),
    ({"scan_age": math.inf}, False), ({"diag": {"label": "not a number"}}, False),
])
def test_the_fast_sample_line_is_the_trace_line(changes: dict[str, Any], finite: bool) -> None:
    """line_and_numbers (one template per shape of line) gives the line the trace writer
    writes, and the sample's numbers that line writes with 9 significant digits."""
    from mdle.record.trace import SampleFormat

    fmt = SampleFormat()
    s = _sample(**changes)
    for _ in range(2):  # the template made, then the template kept
        line, values = fmt.line_and_numbers(s)
        assert line == SampleFormat()(s)
        rec = json.loads(line)
        assert (values is not None) == finite
        if values is not None:
            keys = ["x", "y", "theta", "v", "omega", "cmd_v", "cmd_omega"]
            if "true_x" in rec:
                keys += ["true_x", "true_y", "true_theta"]
            assert values == tuple(getattr(s, k) for k in keys)
            assert tuple(float("%.9g" % v) for v in values) == tuple(rec[k] for k in keys)


@pytest.mark.parametrize("changes", [
    {}, {"v": math.nan}, {"x": math.inf, "true_y": -math.inf},
    {"diag": {"side_range": math.nan, "mode": 2.0, "u": 0.1234567891234}},
    {"diag": {"label": "not a number", "side_range": 1.0000000004}},
    {"clearance": math.nan, "stalled": True},
])
def test_every_value_of_a_sample_line_has_one_rounding(changes: dict[str, Any]) -> None:
    """t in full; every other number 9 significant digits; NaN and infinities null; a
    diagnostic that is not a number its JSON value: whatever else the line holds."""
    from mdle.record.trace import SampleFormat

    s = _sample(**changes)
    rec = json.loads(SampleFormat()(s))
    assert rec["t"] == s.time  # every digit
    for key in ("x", "y", "theta", "v", "omega", "cmd_v", "cmd_omega", "lateness",
                "scan_age", "clearance", "true_x", "true_y", "true_theta"):
        value = getattr(s, key)
        assert rec[key] == (float("%.9g" % value) if math.isfinite(value) else None), key
    for name, value in s.diag.items():
        if isinstance(value, str):
            assert rec["diag"][name] == value
        else:
            assert rec["diag"][name] == (float("%.9g" % value) if math.isfinite(value)
                                         else None), name
