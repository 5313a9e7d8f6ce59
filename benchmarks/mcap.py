"""What recording a run as MCAP costs: per tick, and as a share of a whole simulated run.

1. Per tick: :class:`mdle.ros.McapRecorder` fed prepared ticks of a robot on an arc, each
   with a new 181-beam scan (noisy ranges, a third of the beams with no return), ground
   truth and follow_boundary-like diagnostics, written to a real file (chunks
   compressed, indexed, written as they fill). The figure includes everything: the
   sample line, CDR encoding, the MCAP records, compression and the writes; the trace
   writer on the same ticks is timed beside it. Target: at most 30 us per tick.
2. A whole run: the paper's Figure 1 plan (follow_boundary around the ellipse, a new
   181-beam scan every tick) for 60 simulated seconds at 50 Hz, with and without
   ``--record`` (the recorder as an observer), the two interleaved in the same process.
   Target: recording makes the run at most 25 % slower.

Timings are noisy on a shared machine: each figure is the median (and minimum) of
``--repeat`` runs, the variants interleaved, with the load average printed.

Run: ``python benchmarks/mcap.py [--ticks N] [--repeat R]``.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

# this file is named mcap.py: its own folder must not shadow the `mcap` package
_HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE]
sys.path.insert(0, str(_HERE.parent))

from mdle.backend import Pose, Scan  # noqa: E402
from mdle.loader import load_program  # noqa: E402
from mdle.ros.recorder import McapRecorder  # noqa: E402
from mdle.runtime import Scheduler  # noqa: E402
from mdle.runtime.events import Event, EventKind, Sample  # noqa: E402
from mdle.trace import TraceWriter  # noqa: E402

BEAMS = 181
REPO = Path(__file__).resolve().parent.parent
HEADER: dict[str, Any] = {"program": {"file": "bench", "element": "main"},
                          "world": {"name": "ellipse", "spec": "ellipse"}, "backend": "sim"}


class _Backend:
    laser_mount = (0.017, 0.008, 0.0)


class _Sched:
    """What the observers read at the start of a run."""

    def __init__(self) -> None:
        self.backend = _Backend()
        self.rate = 10.0
        self.until = None

        class _E:
            label = "main"

        self.element = _E()


def prepared_ticks(n: int) -> list[Sample]:
    """Make samples of a robot on an arc, each with a new noisy 181-beam scan."""
    rng = np.random.default_rng(1)
    bearings = np.linspace(-math.pi / 2, math.pi / 2, BEAMS)
    bearings.setflags(write=False)
    out = []
    v, w = 0.6, 0.15
    for k in range(n):
        t = k * 0.1
        th = 0.3 + w * t
        x = 1.0 + v / w * (math.sin(th) - math.sin(0.3))
        y = 2.0 - v / w * (math.cos(th) - math.cos(0.3))
        ranges = np.round(rng.uniform(0.4, 9.0, BEAMS), 3)
        valid = rng.uniform(size=BEAMS) > 0.33
        ranges[~valid] = 10.0
        scan = Scan(ranges, bearings, valid, t, 10.0)
        diag = MappingProxyType({"side_range": 1.0 + 0.01 * math.sin(t),
                                 "side_curvature": -0.25 + 0.001 * k, "mode": 1.0,
                                 "safety": 0.0, "front_range": 3.3 + math.cos(t)})
        out.append(Sample(t, x, y, math.remainder(th, math.tau), v * 1.001, w * 0.999,
                          v, w + 0.001 * math.sin(t), "main/follow_right", 0.0, 0.0, False,
                          diag, 1.2 + 0.1 * math.sin(t), False, x + 0.01, y - 0.02,
                          math.remainder(th + 0.003, math.tau), scan))
    return out


def per_tick(ticks: list[Sample], make: Any) -> float:
    """Microseconds per tick of an observer's on_tick (file setup and finish excluded)."""
    with tempfile.TemporaryDirectory() as tmp:
        obs = make(tmp)
        obs.on_start(_Sched())
        obs.on_event(Event(0.0, EventKind.START, "main", 0, "plan", Pose()))
        on_tick = obs.on_tick
        t0 = time.perf_counter()
        for s in ticks:
            on_tick(s)
        elapsed = time.perf_counter() - t0
        obs.close()
    return elapsed / len(ticks) * 1e6


def whole_run(record: bool, seconds: float) -> float:
    """Wall seconds of the Figure 1 run (50 Hz), recorded or not."""
    import sim

    program = load_program(REPO / "plans" / "paper" / "fig1-ellipse.mdle")
    world = sim.load_world(REPO / "plans" / "paper" / "fig1-ellipse.world.yaml")
    backend = sim.SimBackend(world)
    with tempfile.TemporaryDirectory() as tmp:
        observers = ([McapRecorder(os.path.join(tmp, "r.mcap"), HEADER, world)]
                     if record else [])
        sch = Scheduler(program.elements["main"], backend, 50.0, observers, until=seconds)
        t0 = time.perf_counter()
        while sch.tick():
            pass
        elapsed = time.perf_counter() - t0
        for o in observers:
            o.close()
    return elapsed


def main() -> None:
    """Print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ticks", type=int, default=3000)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f}; {BEAMS} beams, {args.ticks} ticks, "
          f"{args.repeat} repeats")
    ticks = prepared_ticks(args.ticks)
    rec_us, trace_us = [], []
    for _ in range(args.repeat):
        rec_us.append(per_tick(ticks, lambda d: McapRecorder(os.path.join(d, "r.mcap"),
                                                             HEADER)))
        trace_us.append(per_tick(ticks, lambda d: TraceWriter(os.path.join(d, "t.jsonl"),
                                                              HEADER)))
    print(f"MCAP recorder  per tick: median {statistics.median(rec_us):6.1f} us, "
          f"min {min(rec_us):6.1f} us  (target <= 30 us)")
    print(f"trace writer   per tick: median {statistics.median(trace_us):6.1f} us, "
          f"min {min(trace_us):6.1f} us  (for comparison)")
    plain, recorded = [], []
    for _ in range(args.repeat):
        plain.append(whole_run(False, args.seconds))
        recorded.append(whole_run(True, args.seconds))
    ticks_run = int(args.seconds * 50) + 1
    ratio = statistics.median(recorded) / statistics.median(plain)
    pairs = sorted(r / p for r, p in zip(recorded, plain, strict=True))
    print(f"Figure 1 run, {ticks_run} ticks at 50 Hz: without "
          f"{statistics.median(plain) / ticks_run * 1e6:6.1f} us/tick, with --record "
          f"{statistics.median(recorded) / ticks_run * 1e6:6.1f} us/tick")
    print(f"slowdown with --record: {100 * (ratio - 1):+.1f} % (median of medians; "
          f"paired ratios {pairs[0]:.3f}..{pairs[-1]:.3f}; target <= +25 %)")


if __name__ == "__main__":
    main()
