"""What recording a run as MCAP costs: per tick, and as a share of a whole simulated run.

1. Per tick: :class:`mdle.record.McapRecorder` fed prepared ticks of a robot on an arc, each
   with a new 181-beam scan (noisy ranges, a third of the beams with no return), ground
   truth and follow_boundary-like diagnostics, written to a real file (chunks indexed,
   written as they fill, not compressed: ``mdle run --record``'s default). The figure
   includes everything: the sample line, CDR encoding, the MCAP records and the writes;
   the trace writer on the same ticks is timed beside it. Target: at most 30 us per tick.
2. A whole run: the paper's Figure 1 plan (follow_boundary around the ellipse, a new
   181-beam scan every tick) for 60 simulated seconds at 50 Hz, with and without
   ``--record`` (the recorder as an observer), in the same process. Each round runs
   both, in alternating order, and gives the ratio recorded / plain of CPU and wall
   time; the figure is the median ratio over the rounds (with its range), for each
   ``--compression`` asked (default: none, then lz4). Target: x1.25 at most.

Timings are noisy on a shared machine (the load average is printed); a ratio measured
within one round is much steadier than two separate timings. Instruction counts do not
depend on the load: ``--part NAME`` runs one part once (for ``valgrind
--tool=callgrind``, with ``OPENBLAS_NUM_THREADS=1`` so that idle BLAS workers do not
count; run it with two ``--ticks`` or ``--seconds`` values and take the difference per
tick). There batches and chunks close by size alone, as in a run at full speed
(:data:`NO_AGE`).

Last figures (``docs/trace.md``, "Cost"): the recorder alone about 128 000 instructions
and 17-20 us of CPU per tick (load 7-11; 21-22 us before the batch encoding); the whole
run 927 000 instructions per tick without recording, 159 000 more with it (+17 %, from
+21 % before the batch encoding; lz4 +20 %); CPU ratio x1.22-x1.25 uncompressed and
x1.26-x1.27 lz4 at load 3-11, at the x1.25 target within the noise, as the code before
was; on an idle machine that code gave x1.40.

Run: ``python benchmarks/mcap.py [--ticks N] [--repeat R] [--seconds S]``.
"""

from __future__ import annotations

import argparse
import gc
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
sys.path.append(str(_HERE.parent))     # the installed mdle wins, else this checkout's

from mdle.core.backend import Scan  # noqa: E402
from mdle.core.pose import Pose  # noqa: E402
from mdle.lang import load_program  # noqa: E402
from mdle.record.mcap_file import MAX_CHUNK_AGE  # noqa: E402
from mdle.record.recorder import BATCH_AGE, McapRecorder  # noqa: E402
from mdle.record.trace import TraceWriter  # noqa: E402
from mdle.runtime import Scheduler  # noqa: E402
from mdle.runtime.events import Event, EventKind, Sample  # noqa: E402

BEAMS = 181

#: For an instruction counter: batches and chunks closed by size alone. Under valgrind a
#: run goes some fifty times slower, so the wall-clock limits (0.5 s for a batch, 1 s
#: for a chunk) would close them after a few ticks, which a run at full speed (32 ticks
#: in a few milliseconds) never does.
NO_AGE = math.inf
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


def per_tick(ticks: list[Sample], make: Any) -> tuple[float, float]:
    """Microseconds per tick of an observer's on_tick: (wall, CPU); setup excluded.

    The prepared ticks are moved out of the garbage collector's sight first: a real run
    does not keep its samples, so collections would not walk them.
    """
    gc.collect()
    gc.freeze()
    with tempfile.TemporaryDirectory() as tmp:
        obs = make(tmp)
        obs.on_start(_Sched())
        obs.on_event(Event(0.0, EventKind.START, "main", 0, "plan", Pose()))
        on_tick = obs.on_tick
        t0, c0 = time.perf_counter(), time.process_time()
        for s in ticks:
            on_tick(s)
        elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
        obs.close()
    gc.unfreeze()
    return elapsed / len(ticks) * 1e6, cpu / len(ticks) * 1e6


def whole_run(record: bool, seconds: float, compression: str = "",
              age: float = 1.0) -> tuple[float, float]:
    """Wall and CPU seconds of the Figure 1 run (50 Hz), recorded or not.

    ``age`` scales the recorder's wall-clock limits (``inf``: see :data:`NO_AGE`).
    """
    from mdle import sim

    program = load_program(REPO / "plans" / "paper" / "fig1-ellipse.mdle")
    world = sim.load_world(REPO / "plans" / "paper" / "fig1-ellipse.world.yaml")
    backend = sim.SimBackend(world)
    with tempfile.TemporaryDirectory() as tmp:
        observers = ([McapRecorder(os.path.join(tmp, "r.mcap"), HEADER, world,
                                   compression=compression, batch_age=BATCH_AGE * age,
                                   max_age=MAX_CHUNK_AGE * age)] if record else [])
        sch = Scheduler(program.elements["main"], backend, 50.0, observers, until=seconds)
        t0, c0 = time.perf_counter(), time.process_time()
        while sch.tick():
            pass
        for o in observers:  # finishing the file is part of the cost
            o.close()
        elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
    return elapsed, cpu


def overhead(repeat: int, seconds: float, compression: str) -> dict[str, list[float]]:
    """Return recorded / plain time of the Figure 1 run per round: {"cpu": [..], "wall": [..]}.

    Each round runs both, in alternating order (plain first in even rounds), so a
    change of machine load between rounds affects both sides of a round alike.
    """
    whole_run(True, 1.0, compression)  # imports and first-call costs out of the way
    ratios: dict[str, list[float]] = {"cpu": [], "wall": []}
    for k in range(repeat):
        if k % 2 == 0:
            plain = whole_run(False, seconds)
            recorded = whole_run(True, seconds, compression)
        else:
            recorded = whole_run(True, seconds, compression)
            plain = whole_run(False, seconds)
        ratios["wall"].append(recorded[0] / plain[0])
        ratios["cpu"].append(recorded[1] / plain[1])
    return ratios


def _compression(text: str) -> str:
    if text not in ("none", "lz4"):
        raise argparse.ArgumentTypeError("none or lz4")
    return "" if text == "none" else text


def main() -> None:
    """Print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ticks", type=int, default=3000)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--compression", nargs="+", default=["", "lz4"], type=_compression,
                    help="chunk compression(s) of the whole-run overhead: none, lz4")
    ap.add_argument("--part", choices=("tick-none", "tick-record", "tick-trace", "run-plain",
                                       "run-record"),
                    help="run only this part, once (for an instruction counter)")
    args = ap.parse_args()
    if args.part:
        if args.part.startswith("tick"):
            ticks = prepared_ticks(args.ticks)
            if args.part == "tick-none":  # preparing the ticks alone, to subtract
                per_tick(ticks[:1], lambda d: TraceWriter(os.path.join(d, "t.jsonl"), HEADER))
            elif args.part == "tick-record":
                per_tick(ticks, lambda d: McapRecorder(os.path.join(d, "r.mcap"), HEADER,
                                                       batch_age=NO_AGE, max_age=NO_AGE))
            else:
                per_tick(ticks, lambda d: TraceWriter(os.path.join(d, "t.jsonl"), HEADER))
        else:
            whole_run(args.part == "run-record", args.seconds, args.compression[0], NO_AGE)
        return
    print(f"load average {os.getloadavg()[0]:.2f}; {BEAMS} beams, {args.ticks} ticks, "
          f"{args.repeat} repeats")
    ticks = prepared_ticks(args.ticks)
    rec: list[tuple[float, float]] = []
    trace: list[tuple[float, float]] = []
    for _ in range(args.repeat):
        rec.append(per_tick(ticks, lambda d: McapRecorder(os.path.join(d, "r.mcap"), HEADER)))
        trace.append(per_tick(ticks, lambda d: TraceWriter(os.path.join(d, "t.jsonl"), HEADER)))
    for name, xs, note in (("MCAP recorder", rec, "target <= 30 us"),
                           ("trace writer ", trace, "for comparison")):
        wall, cpu = [x[0] for x in xs], [x[1] for x in xs]
        print(f"{name} per tick: CPU median {statistics.median(cpu):6.1f} us "
              f"(min {min(cpu):5.1f}), wall median {statistics.median(wall):6.1f} us "
              f"(min {min(wall):5.1f})  ({note})")
    n = int(args.seconds * 50) + 1
    for compression in args.compression:
        ratios = overhead(args.repeat, args.seconds, compression)
        for what in ("cpu", "wall"):
            rs = ratios[what]
            print(f"Figure 1 run, {n} ticks at 50 Hz, {what.upper():4s} with --record "
                  f"(chunks {compression or 'uncompressed'}) / without, median of "
                  f"{len(rs)} interleaved rounds: x{statistics.median(rs):.3f} "
                  f"(min x{min(rs):.3f}, max x{max(rs):.3f}; target <= x1.25)")


if __name__ == "__main__":
    main()
