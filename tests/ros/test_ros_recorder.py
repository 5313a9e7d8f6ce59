"""The recorder as an observer: a robot with no ground truth, and a recording that fails."""

from __future__ import annotations

import errno
import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from mdle.core.backend import Observation
from mdle.lang import load_text
from mdle.record.load import read_trace
from mdle.record.recorder import McapRecorder
from mdle.record.trace import TraceWriter
from mdle.runtime import Scheduler

PLAN = "atom hug = (follow_boundary(side = right, rc = 1 m, v = 1 m/s), never, 8 s)\n"


class _Robot:
    """The simulator seen as a robot: no ground truth, no mount attribute."""

    def __init__(self) -> None:
        from mdle import sim

        self._sim = sim.SimBackend(sim.load_world("ellipse"))
        self.clock = self._sim.clock
        self.limits = self._sim.limits

    def observe(self) -> Observation:
        return replace(self._sim.observe(), truth={})

    def command(self, cmd: Any) -> None:
        self._sim.command(cmd)

    def advance(self, dt: float) -> float:
        return self._sim.advance(dt)

    def stop(self) -> None:
        self._sim.stop()

    def close(self) -> None:
        self._sim.close()


def test_a_robot_run_has_no_simulation_topics(tmp_path: Path, doctor: Any,
                                              rosbags_read: Any) -> None:
    element = load_text(PLAN, "<test>").elements["hug"]
    header = {"program": {"element": "hug"}, "backend": "pioneer", "rate": 10.0}
    rec = McapRecorder(tmp_path / "r.mcap", header)
    trace = TraceWriter(tmp_path / "t.jsonl", header)
    sch = Scheduler(element, _Robot(), 10.0, [trace, rec])
    while sch.tick():
        pass
    counts = doctor(tmp_path / "r.mcap")
    n = len(read_trace(tmp_path / "t.jsonl").samples)
    assert counts == {"/tf_static": 1, "/scan": n, "/odom": n, "/tf": n, "/cmd_vel": n,
                      "/mdle/state": n, "/mdle/events": 4, "/mdle/active": 2,
                      "/mdle/diagnostics": n, "/path": math.ceil((n - 1) / 10)}
    msgs = rosbags_read(tmp_path / "r.mcap")
    tfs = [m.msg for m in msgs if m.topic == "/tf"]
    assert all(len(t.transforms) == 1 and t.transforms[0].child_frame_id == "base_link"
               for t in tfs)
    # a robot's odometry noise is unknown: -1 first (REP-145), never zeros read as exact
    odoms = [m.msg for m in msgs if m.topic == "/odom"]
    assert all(o.pose.covariance[0] == -1.0 == o.twist.covariance[0]
               and not o.pose.covariance[1:].any() for o in odoms)
    (static,) = [m.msg.transforms[0] for m in msgs if m.topic == "/tf_static"]
    assert static.transform.translation.x == 0.0  # no mount known: at the robot's origin
    # nor the scans' timing: 0, as LaserScan says for unknown
    assert all(m.msg.scan_time == 0.0 == m.msg.time_increment for m in msgs
               if m.topic == "/scan")
    # the exported trace gives the same messages
    from mdle.record.export import export_trace

    export_trace(tmp_path / "t.jsonl", tmp_path / "e.mcap")
    assert doctor(tmp_path / "e.mcap") == counts


@pytest.mark.parametrize("when", ["mid-run", "at the end"])
def test_a_disk_that_fills_up_ends_the_run_cleanly(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str], when: str) -> None:
    from mdle.cli import main
    from mdle.record import mcap_file

    real = mcap_file.McapFile.close_chunk
    finishing: list[bool] = []

    def close_chunk(self: mcap_file.McapFile) -> None:
        # mid-run: the first chunk; at the end: the last one, when the file is finished
        if self._used and (when == "mid-run" or finishing):
            raise OSError(errno.ENOSPC, "No space left on device")
        real(self)

    monkeypatch.setattr(mcap_file.McapFile, "close_chunk", close_chunk)
    real_finish = mcap_file.McapFile.finish

    def finish(self: mcap_file.McapFile) -> None:
        finishing.append(True)
        real_finish(self)

    monkeypatch.setattr(mcap_file.McapFile, "finish", finish)
    (tmp_path / "p.mdle").write_text(PLAN + "run hug\n")
    code = main(["run", str(tmp_path / "p.mdle"), "--world", "ellipse", "--trace",
                 str(tmp_path / "t.jsonl"), "--record", str(tmp_path / "r.mcap"), "-q"])
    err = capsys.readouterr().err
    assert code == 74  # an output that could not be written (docs/runtime.md)
    assert f"cannot write the recording `{tmp_path / 'r.mcap'}`: No space left on device" in err
    assert "Traceback" not in err
    trace = read_trace(tmp_path / "t.jsonl")  # the trace is whole and says how it ended
    assert trace.end is not None
    if when == "mid-run":  # the run was aborted, the robot stopped
        assert trace.end["cause"] == "error" and "No space left" in trace.end["fault"]
        assert trace.end["t"] < 7.0
    else:
        assert trace.end["cause"] == "timer"


def test_a_recording_that_cannot_be_created(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli import main

    (tmp_path / "p.mdle").write_text(PLAN + "run hug\n")
    code = main(["run", str(tmp_path / "p.mdle"), "--world", "ellipse", "--record",
                 str(tmp_path / "no" / "such" / "r.mcap"), "-q"])
    err = capsys.readouterr().err
    assert code == 1 and "cannot write the recording" in err
    assert "No such file or directory" in err


@pytest.mark.parametrize("rate", [10.0, 20.0])
def test_scans_taken_at_every_tick_are_a_tick_apart(tmp_path: Path, rate: float,
                                                    doctor: Any) -> None:
    """The reference world's ladar scans at every tick: scan_time is the tick."""
    from mdle import sim

    element = load_text(PLAN, "<test>").elements["hug"]
    header = {"program": {"element": "hug"}, "world": {"name": "ellipse"}, "backend": "sim"}
    rec = McapRecorder(tmp_path / "r.mcap", header)
    trace = TraceWriter(tmp_path / "t.jsonl", header)
    sch = Scheduler(element, sim.SimBackend(sim.load_world("ellipse")), rate, [trace, rec],
                    until=1.0)
    while sch.tick():
        pass
    assert doctor(tmp_path / "r.mcap")["/scan"] == int(rate) + 1
    (laser,) = read_trace(tmp_path / "t.jsonl").lasers
    assert (laser["scan_time"], laser["time_increment"]) == (1.0 / rate, 0.0)
    back = read_trace(tmp_path / "r.mcap")
    assert back.lasers[0]["scan_time"] == pytest.approx(1.0 / rate, rel=1e-7)  # float32


def test_record_compression_lz4(tmp_path: Path, doctor: Any) -> None:
    from mcap.reader import make_reader

    from mdle.cli import main

    (tmp_path / "p.mdle").write_text(PLAN + "run hug\n")
    code = main(["run", str(tmp_path / "p.mdle"), "--world", "ellipse", "--until", "3",
                 "--record", str(tmp_path / "r.mcap"), "--record-compression", "lz4", "-q"])
    assert code == 0
    counts = doctor(tmp_path / "r.mcap")
    assert counts["/odom"] == 31
    with open(tmp_path / "r.mcap", "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    assert {c.compression for c in summary.chunk_indexes} == {"lz4"}


def test_ticks_are_encoded_in_batches_and_an_event_flushes_them(tmp_path: Path,
                                                                doctor: Any) -> None:
    """Ticks wait until the batch is full or old; an event publishes them first."""
    from mdle import sim

    now = [0.0]
    element = load_text(PLAN, "<test>").elements["hug"]
    header = {"program": {"element": "hug"}, "world": {"name": "ellipse"}, "backend": "sim"}
    rec = McapRecorder(tmp_path / "r.mcap", header, batch_ticks=4, batch_age=0.5,
                       clock=lambda: now[0])
    sch = Scheduler(element, sim.SimBackend(sim.load_world("ellipse")), 10.0, [rec],
                    until=2.0)
    sch.start()
    odom = rec.recording.channels["/odom"]
    published = []
    for _ in range(7):
        sch.tick()
        published.append(rec.recording.out.channel_counts()[odom])
    # the element's start event (first tick) flushed nothing; then 4 by 4
    assert published == [0, 0, 0, 4, 4, 4, 4]
    now[0] = 0.6  # older than batch_age: the next tick publishes what waits
    sch.tick()
    assert rec.recording.out.channel_counts()[odom] == 8
    while sch.tick():  # the end event publishes the last ticks before the end record
        pass
    assert doctor(tmp_path / "r.mcap")["/odom"] == 21
    back = read_trace(tmp_path / "r.mcap")
    assert len(back.samples) == 21 and back.end is not None


class _Gappy(_Robot):
    """The simulator, with ground truth, whose speed and turn-rate readings are missing
    (NaN) every third tick and whose true clearance is infinite every seventh."""

    def __init__(self) -> None:
        super().__init__()
        self._k = 0

    def observe(self) -> Observation:
        obs = self._sim.observe()
        self._k += 1
        if self._k % 3 == 0:
            obs = replace(obs, v=math.nan, omega=math.nan)
        if self._k % 7 == 0:
            obs = replace(obs, truth={**obs.truth, "clearance": math.inf})
        return obs


def test_a_run_with_nan_fields_gives_the_trace_s_numbers_to_the_recording(
        tmp_path: Path) -> None:
    """One formatter: a sample with a NaN or an infinity writes every other number with
    9 significant digits (null for those), and the recording holds the numbers of the
    trace's lines: the export of the trace gives the same messages, byte for byte."""
    from mcap.reader import make_reader

    from mdle.record.export import export_trace

    element = load_text(PLAN, "<test>").elements["hug"]
    header = {"program": {"element": "hug"}, "backend": "sim", "rate": 10.0}
    rec = McapRecorder(tmp_path / "r.mcap", header)
    trace = TraceWriter(tmp_path / "t.jsonl", header)
    sch = Scheduler(element, _Gappy(), 10.0, [trace, rec])
    while sch.tick():
        pass
    lines = [json.loads(line) for line in (tmp_path / "t.jsonl").read_text().splitlines()]
    samples = [r for r in lines if r["type"] == "sample"]
    gappy = [r for r in samples if r["v"] is None]
    assert len(gappy) >= 20 and any(r["clearance"] is None for r in samples)
    for r in samples:
        numbers = [r[k] for k in ("x", "y", "v", "omega", "cmd_v", "cmd_omega", "lateness",
                                  "scan_age", "clearance", "true_x", "true_y", "true_theta")]
        numbers += list(r.get("diag", {}).values())
        for n in numbers:
            if isinstance(n, float):
                assert len(repr(n).lstrip("-").replace(".", "").split("e")[0]
                           .lstrip("0")) <= 9, r
    export_trace(tmp_path / "t.jsonl", tmp_path / "e.mcap")

    def messages(p: Path) -> list[tuple[str, int, bytes]]:
        with open(p, "rb") as f:
            found = [(c.topic, m.sequence, m.data)
                     for _, c, m in make_reader(f).iter_messages(log_time_order=False)]
        return sorted(found)

    assert messages(tmp_path / "e.mcap") == messages(tmp_path / "r.mcap")
