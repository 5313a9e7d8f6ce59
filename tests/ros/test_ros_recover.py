"""A recording cut by SIGKILL: ``mdle recover`` makes it open in the mcap and rosbags readers."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

PLAN = """\
atom hug = (follow_boundary(side = right, rc = 0.6 m, v = 0.3 m/s), never, inf)
run hug
"""


def _mdle() -> list[str]:
    exe = Path(sys.executable).with_name("mdle")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "mdle"]


def _killed(tmp_path: Path) -> tuple[Path, Path]:
    """Run a paced recording into a file and a rosbag2 folder; SIGKILL it after chunks."""
    plan = tmp_path / "p.mdle"
    plan.write_text(PLAN)
    mcap, bag = tmp_path / "r.mcap", tmp_path / "bag"
    proc = subprocess.Popen(
        [*_mdle(), "run", str(plan), "--world", "default", "--rate", "20", "--realtime",
         "-q", "--record", str(mcap), "--rosbag", str(bag)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=tmp_path)
    try:
        # chunks close every second of wall time: wait for a few in both files (the
        # first holds the world's occupancy grid, some 50 kB)
        inner = bag / "bag_0.mcap"
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline and not all(
                p.exists() and p.stat().st_size > 250_000 for p in (mcap, inner)):
            time.sleep(0.1)
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    return mcap, bag


def test_a_killed_recording_is_recovered(tmp_path: Path, doctor: Any,
                                         rosbags_read: Any) -> None:
    from mcap.reader import make_reader

    mcap, bag = _killed(tmp_path)
    assert not (bag / "metadata.yaml").exists()
    from rosbags.rosbag2 import ReaderError

    with pytest.raises(ReaderError):  # as the kill left it, the reader refuses it
        rosbags_read(mcap)
    fixed = tmp_path / "fixed.mcap"
    done = subprocess.run([*_mdle(), "recover", str(mcap), "-o", str(fixed)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "cut off after its last whole chunk" in done.stdout
    counts = doctor(fixed)  # strictly valid: summary, indexes, footer
    assert counts["/odom"] == counts["/mdle/state"] > 20
    with open(fixed, "rb") as f:
        assert sum(1 for _ in make_reader(f).iter_messages()) == sum(counts.values())
    msgs = rosbags_read(fixed)
    assert len(msgs) == sum(counts.values())
    # the folder: recovered in place, with a metadata.yaml rosbags reads
    done = subprocess.run([*_mdle(), "recover", str(bag)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert (bag / "metadata.yaml").exists()
    from rosbags.rosbag2 import Reader

    with Reader(bag) as reader:
        topics = {c.topic for c in reader.connections}
        assert {"/scan", "/odom", "/mdle/state", "/map"} <= topics
        assert reader.message_count == len(rosbags_read(bag)) > 20


def test_recover_refuses_what_is_not_mcap(tmp_path: Path) -> None:
    bad = tmp_path / "x.mcap"
    bad.write_text("hello")
    done = subprocess.run([*_mdle(), "recover", str(bad)], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 1 and "is not an MCAP file" in done.stderr
    assert "Traceback" not in done.stderr and bad.read_text() == "hello"
