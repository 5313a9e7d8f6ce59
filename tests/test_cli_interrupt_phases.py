"""Ctrl-C in every long phase of a command: a real SIGINT to a real mdle process.

Each command spends a few seconds of CPU in one phase (checking a plan of 60,000
lines, loading 60,000 circles, 8,000 rectangles or a 4000 x 4000 map, compiling a string of
60,000 atoms, a sweep, an experiment, plotting and exporting a trace of 100,000
samples). The signal is sent once the process has used enough CPU to be inside that
phase, and the process must end with exit 130, mdle's message and no traceback; a
run's trace, when there is one, must be whole. The time from the signal to the exit is
bounded generously, in the CPU the process spends (1 s: a phase that went on would
spend seconds) and, against a hang, on the wall clock (10 s: the machine is shared and
may be busy). The latency itself (milliseconds) is measured by
``benchmarks/interrupts.py``, not here.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

#: CPU seconds from the signal to the exit (freeing what the phase built included).
CPU_BOUND = 1.0
#: Wall seconds from the signal to the exit: only a hang takes this long.
WALL_BOUND = 10.0
_TICK = os.sysconf("SC_CLK_TCK")


def _cpu(pid: int) -> float:
    """Return the CPU seconds (user + system) process ``pid`` has used."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / _TICK


@dataclass(frozen=True)
class Ending:
    """How an interrupted process ended: code, CPU and wall seconds after the signal."""

    code: int
    cpu: float
    wall: float
    stderr: str


def interrupt_inside(argv: list[str], cwd: Path, cpu: float = math.inf,
                     ready: Callable[[], bool] | None = None,
                     signum: int = signal.SIGINT) -> Ending:
    """Run ``mdle argv``; ``signum`` once it has used ``cpu`` s of CPU (or once ``ready()``)."""
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.Popen([sys.executable, "-m", "mdle", *argv], cwd=cwd, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    stderr = proc.stderr
    assert stderr is not None
    try:
        deadline = time.monotonic() + 120
        while (proc.poll() is None and _cpu(proc.pid) < cpu
               and not (ready is not None and ready()) and time.monotonic() < deadline):
            time.sleep(0.02)
        assert proc.poll() is None, f"the phase ended before the signal: {stderr.read()}"
        before = _cpu(proc.pid)
        sent = time.monotonic()
        proc.send_signal(signum)
        hang = threading.Timer(60.0, proc.kill)
        hang.start()
        _, status, usage = os.wait4(proc.pid, 0)  # reaped here, for its CPU time
        hang.cancel()
        wall = time.monotonic() - sent
        proc.returncode = os.waitstatus_to_exitcode(status)
        err = stderr.read()
        return Ending(proc.returncode, usage.ru_utime + usage.ru_stime - before, wall, err)
    finally:
        if proc.returncode is None:
            proc.kill()
            proc.wait()
        stderr.close()


def _interrupted(end: Ending, signum: int = signal.SIGINT) -> None:
    assert end.code == 128 + signum, end.stderr
    assert "interrupted" in end.stderr and "Traceback" not in end.stderr, end.stderr
    assert end.cpu < CPU_BOUND and end.wall < WALL_BOUND, (end.cpu, end.wall)


def _whole_or_none(trace: Path) -> None:
    """A run's trace is whole (header to end record), or was never begun."""
    if trace.exists():
        from mdle.record.load import read_trace

        t = read_trace(trace)
        assert t.end is not None and not t.truncated


#: Stands still for a day of simulated time: the process outlives the phase under test.
PLAN = "atom a = (stop, never, 86400 s)\nrun a\n"


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    (tmp_path / "p.mdle").write_text(PLAN)
    return tmp_path


#: The phases whose work between two looks at the signals was cut (issue 26) are
#: interrupted by SIGTERM too.
BOTH = pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])


@BOTH
def test_checking_a_plan_of_60000_lines(folder: Path, signum: int) -> None:
    body = "".join(f"atom a{i} = (go(0.3 m/s), range(0 deg) < {1 + i % 7} m, {1 + i % 5} s)\n"
                   for i in range(60_000))
    (folder / "big.mdle").write_text(body + "run a0\n")
    _interrupted(interrupt_inside(["check", "big.mdle"], folder, cpu=1.5, signum=signum),
                 signum)


@BOTH
def test_loading_a_world_of_60000_circles(folder: Path, signum: int) -> None:
    rng = np.random.default_rng(0)
    xy = rng.uniform(-500.0, 500.0, size=(60_000, 2))
    xy = xy[np.hypot(xy[:, 0], xy[:, 1]) > 2.0]
    lines = ["name: circles", "start: {x: 0, y: 0, theta: 0}", "obstacles:"]
    lines += [f"  - {{type: circle, center: [{x:.3f}, {y:.3f}], radius: 0.2}}" for x, y in xy]
    (folder / "w.yaml").write_text("\n".join(lines) + "\n")
    _interrupted(interrupt_inside(["run", "p.mdle", "--world", "w.yaml", "-q", "--trace",
                                    "t.jsonl"], folder, cpu=1.4, signum=signum), signum)
    _whole_or_none(folder / "t.jsonl")


def test_loading_a_world_of_8000_rectangles(folder: Path) -> None:
    lines = ["name: rectangles", "start: {x: 1, y: 1, theta: 0}", "obstacles:"]
    lines += [f"  - {{type: rectangle, center: [{2 * (i % 90) + 4}, {2 * (i // 90) + 4}], "
              "size: [0.7, 0.4]}" for i in range(8_000)]
    (folder / "w.yaml").write_text("\n".join(lines) + "\n")
    _interrupted(interrupt_inside(["run", "p.mdle", "--world", "w.yaml", "-q", "--trace",
                                    "t.jsonl", "--until", "1000"], folder, cpu=1.0))
    _whole_or_none(folder / "t.jsonl")


@BOTH
def test_loading_a_map_of_4000_by_4000_cells(folder: Path, signum: int) -> None:
    rng = np.random.default_rng(1)
    img = np.full((4000, 4000), 254, dtype=np.uint8)
    for r, c, n, down in zip(rng.integers(0, 4000, 2000), rng.integers(0, 4000, 2000),
                             rng.integers(5, 60, 2000), rng.random(2000) < 0.5, strict=True):
        if down:
            img[r:r + n, c] = 0
        else:
            img[r, c:c + n] = 0
    img[1480:1520, 1480:1520] = 254
    (folder / "m.pgm").write_bytes(b"P5\n4000 4000\n255\n" + img.tobytes())
    (folder / "m.yaml").write_text("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n"
                                   "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    (folder / "w.yaml").write_text("name: mapped\nstart: {x: 75, y: 75, theta: 0}\n"
                                   "map: m.yaml\n")
    # start-up and an empty world take about 0.38 s of CPU, the whole load about 0.65 s (it
    # reads the image in bands since issue 26): the signal lands in the middle of the load,
    # and the run after it stands still until the signal ends it
    _interrupted(interrupt_inside(["run", "p.mdle", "--world", "w.yaml", "-q"], folder,
                                  cpu=0.5, signum=signum), signum)


def test_compiling_a_string_of_60000_atoms(folder: Path) -> None:
    parts = ", ".join(f"(go({0.1 + (i % 9) / 100:.2f} m/s), never, 0.01 s)"
                      for i in range(60_000))
    (folder / "s.mdle").write_text(f"plan main = (({parts}), never, 1 s)\nrun main\n")
    _interrupted(interrupt_inside(["run", "s.mdle", "--world", "empty", "-q", "--trace",
                                    "t.jsonl"], folder, cpu=1.2))
    _whole_or_none(folder / "t.jsonl")


def test_a_sweep(folder: Path) -> None:
    # the runs are made by a worker process: the signal goes once some rows are in
    (folder / "s.yaml").write_text("plan: p.mdle\nworlds: [default]\nseeds: {count: 1000}\n"
                                   "duration: 5\n")
    table = folder / "o" / "results.csv"

    def running() -> bool:
        return table.exists() and table.read_text().count("\n") > 3

    _interrupted(interrupt_inside(["sweep", "s.yaml", "--out", "o", "--jobs", "1"], folder,
                                   ready=running))


def test_an_experiment(folder: Path) -> None:
    _interrupted(interrupt_inside(["experiment", "random-starts", "--generated", "--shapes",
                                    "40", "--jobs", "1"], folder, cpu=1.5))


@pytest.fixture
def big_trace(folder: Path) -> Path:
    """A trace of 100,000 samples (written directly: running it would take a minute)."""
    path = folder / "t.jsonl"
    head = [{"type": "header", "format": "mdle-trace", "version": 1,
             "program": {"file": "p.mdle", "element": "a", "entry": "a"}, "rate": 100.0,
             "backend": "sim", "world": "empty"},
            {"type": "start", "element": "a", "rate": 100.0}]
    sample = {"type": "sample", "path": "a", "v": 0.1, "omega": 0.0, "cmd_v": 0.1,
              "cmd_omega": 0.0, "lateness": 0, "stalled": False, "scan_age": 0,
              "clearance": 1.0, "collided": False, "theta": 0.0}
    with path.open("w") as f:
        for h in head:
            f.write(json.dumps(h) + "\n")
        for i in range(100_000):
            x, y = i * 1e-3, (i % 100) * 1e-3
            f.write(json.dumps({**sample, "t": i * 0.01, "x": x, "y": y}) + "\n")
        f.write(json.dumps({"type": "end", "path": "a", "cause": "completed", "t": 1000.0,
                            "ticks": 100_000, "duration": 1000.0, "distance": 100.0,
                            "collided": False, "fault": None}) + "\n")
    return path


def test_plotting_a_trace_of_100000_samples(folder: Path, big_trace: Path) -> None:
    _interrupted(interrupt_inside(["plot", big_trace.name, "-o", "t.png"], folder, cpu=1.0))


def test_exporting_a_trace_of_100000_samples(folder: Path, big_trace: Path) -> None:
    _interrupted(interrupt_inside(["export", big_trace.name, "-o", "t.mcap"], folder,
                                   cpu=1.0))
    # written to a temporary file renamed into place: no part of an MCAP is left behind
    assert not (folder / "t.mcap").exists()
    assert not [p.name for p in folder.iterdir() if p.name.endswith(".part")]
