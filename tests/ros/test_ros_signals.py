"""A real `mdle run --record` ended by SIGINT, SIGTERM, an error and SIGKILL.

SIGINT, SIGTERM and an error end the run through the scheduler: the file is finished
(summary, index, footer) and passes the strict validation, holding every tick the trace
holds. SIGKILL gives no chance to finish: the file must read, with the mcap library's
record-by-record reader, up to its last whole chunk, and end on a record boundary.
"""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from mdle.record.load import read_trace

SPIN = """\
atom spin = (turn(20 deg/s), never, inf)
plan main = ((spin), never, inf)
run main
"""

# drives straight into the ellipse, stalls there, and is aborted after 5 s stalled
RAM = """\
atom ram = (go(1 m/s), never, inf)
run ram
"""


def _start(cmd: list[str], tmp_path: Path, text: str, *extra: str) -> subprocess.Popen[str]:
    plan = tmp_path / "p.mdle"
    plan.write_text(text)
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.Popen([*cmd, "run", str(plan), "--world", "ellipse", "--trace",
                             str(tmp_path / "t.jsonl"), "--record", str(tmp_path / "r.mcap"),
                             *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, cwd=tmp_path)


def _wait_for(proc: subprocess.Popen[str], ready: Any, what: str) -> None:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if ready():
            return
        if proc.poll() is not None:
            pytest.fail(f"the run ended before {what}: {proc.communicate()[1]}")
        time.sleep(0.02)
    pytest.fail(f"no {what} within 60 s")


def _samples_in(trace: Path) -> int:
    try:
        return trace.read_bytes().count(b'"type":"sample"')
    except OSError:
        return 0


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_leaves_a_finished_valid_file(
        tmp_path: Path, mdle_command: list[str], doctor: Any, rosbags_read: Any,
        sig: signal.Signals, code: int) -> None:
    proc = _start(mdle_command, tmp_path, SPIN, "-q")
    try:
        # several chunks written (about 25 ticks each), the run going on
        _wait_for(proc, lambda: _samples_in(tmp_path / "t.jsonl") > 150, "150 ticks")
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == code, err
    assert f"recording in {tmp_path / 'r.mcap'}" in err
    trace = read_trace(tmp_path / "t.jsonl")
    counts = doctor(tmp_path / "r.mcap")
    assert counts["/mdle/state"] == counts["/odom"] == len(trace.samples) > 150
    assert counts["/scan"] == len(trace.scans)
    events = [json.loads(m.msg.data) for m in rosbags_read(tmp_path / "r.mcap")
              if m.topic == "/mdle/events"]
    assert events[-1] == trace.end and events[-1]["cause"] == "stopped"
    assert events[-2]["kind"] == "end" and events[-2]["cause"] == "stopped"


def test_an_aborted_run_leaves_a_finished_valid_file(
        tmp_path: Path, mdle_command: list[str], doctor: Any) -> None:
    proc = _start(mdle_command, tmp_path, RAM, "-q")
    try:
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 3, err
    trace = read_trace(tmp_path / "t.jsonl")
    assert trace.end is not None and trace.end["cause"] == "error"
    assert "stalled" in trace.end["fault"]
    counts = doctor(tmp_path / "r.mcap")
    assert counts["/mdle/state"] == len(trace.samples)
    back = read_trace(tmp_path / "r.mcap")
    assert back.end == trace.end and back.samples == trace.samples


def test_sigkill_leaves_a_file_readable_up_to_its_last_chunk(
        tmp_path: Path, mdle_command: list[str]) -> None:
    from mcap.exceptions import EndOfFile
    from mcap.records import Chunk, Footer, Message, MessageIndex
    from mcap.stream_reader import StreamReader
    from mcap_ros2.decoder import DecoderFactory

    mcap = tmp_path / "r.mcap"
    proc = _start(mdle_command, tmp_path, SPIN, "-q")
    try:
        # (the first chunk holds the world's occupancy grid, some 100 kB)
        _wait_for(proc, lambda: mcap.exists() and mcap.stat().st_size > 300_000,
                  "300 kB recorded")
        proc.kill()
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    data = mcap.read_bytes()
    stream = io.BytesIO(data)
    reader = StreamReader(stream, validate_crcs=True, emit_chunks=True)
    records = []
    with pytest.raises(EndOfFile):
        for record in reader.records:
            records.append(record)
    # the kill came between two writes: the file ends where a whole record ends
    ends = [r for r in records if isinstance(r, (Chunk, MessageIndex))]
    assert ends and isinstance(records[-1], MessageIndex)
    assert not any(isinstance(r, Footer) for r in records)
    chunks = [r for r in records if isinstance(r, Chunk)]
    assert len(chunks) >= 2
    # every message of every chunk reads and decodes
    reader = StreamReader(io.BytesIO(data), validate_crcs=True)
    messages: list[Message] = []
    try:
        for record in reader.records:
            if isinstance(record, Message):
                messages.append(record)
    except EndOfFile:
        pass
    back = read_trace(mcap)  # mdle's own reader recovers the same
    assert back.truncated and back.end is None
    assert len(messages) > 100
    factory = DecoderFactory()
    from mcap.records import Channel, Schema

    schemas = {r.id: r for r in records if isinstance(r, Schema)}
    channels = {r.id: r for r in records if isinstance(r, Channel)}
    for m in messages:
        ch = channels[m.channel_id]
        dec = factory.decoder_for(ch.message_encoding, schemas[ch.schema_id])
        assert dec is not None
        dec(m.data)
    # what was recovered is the run as the trace has it, short of at most the open chunk
    # and the ticks waiting to be encoded (one batch)
    from mdle.record.recorder import BATCH_TICKS

    trace = read_trace(tmp_path / "t.jsonl")
    k = min(len(back.samples), len(trace.samples))
    assert back.samples[:k] == trace.samples[:k]
    per_tick = sum(c.uncompressed_size for c in chunks) / max(1, len(back.samples))
    one_chunk = 64 * 1024 / per_tick + BATCH_TICKS + 2
    # (the trace itself may lag: it writes samples in batches of 20 ms of wall time)
    assert len(trace.samples) - len(back.samples) <= one_chunk
