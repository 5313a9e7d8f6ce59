"""Measure check, show and run on plans whose expansion is exponential.

Two chains of N definitions describe trees of 2**N leaves:

* ``interrupt iN = iN-1 or iN-1`` (an atom's interrupt is the last link);
* ``behavior bN = ((bN-1, bN-1), never, inf)`` over a 1 s atom.

Shared definitions stay shared (one compiled function per distinct interrupt, memoised
structure figures, slots made when an element starts), so each row should grow
linearly with N. For each N the script prints the time and the peak memory allocated
(tracemalloc) of checking, of ``show`` and of 100 ticks of a run, and the number of
sensor readings one interrupt test makes (2**N inlined).

Run: python benchmarks/expansion.py [--sizes 10,16,20,25,30]
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
import types
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

sys.path.append(str(Path(__file__).resolve().parent.parent))  # the installed mdle wins

from mdle.atoms.registry import Args, Context, Param, Registry, sensor  # noqa: E402 (after the path fix)
from mdle.core.units import LENGTH  # noqa: E402

_READS = [0]


@sensor(Param("angle", LENGTH, 0.0), result=LENGTH)
def probe(args: Args, ctx: Context) -> float:
    """Count the readings (always 5 m: every comparison below is false)."""
    _READS[0] += 1
    return 5.0


def interrupt_chain(n: int) -> str:
    """Return the plan whose atom's interrupt is the N-th link of a doubling chain."""
    lines = ["interrupt i0 = probe() < 1 m"]
    lines += [f"interrupt i{k} = i{k - 1} or i{k - 1}" for k in range(1, n + 1)]
    return "\n".join(lines) + f"\natom a = (go(0.3 m/s), i{n}, 10 s)\nrun a\n"


def behavior_chain(n: int) -> str:
    """Return the plan whose entry holds the previous behavior twice, N levels deep."""
    lines = ["atom b0 = (go(0.3 m/s), never, 1 s)"]
    lines += [f"behavior b{k} = ((b{k - 1}, b{k - 1}), never, inf)" for k in range(1, n + 1)]
    return "\n".join(lines) + f"\nrun b{n}\n"


def measured(fn: Callable[[], Any]) -> tuple[Any, float, int]:
    """Return (result, seconds, peak bytes allocated) of one call."""
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        out = fn()
        return out, time.perf_counter() - t0, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def main() -> int:
    """Print one row per chain length."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", default="10,16,20,25,30")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]

    from mdle import sim
    from mdle.atoms import default_registry
    from mdle.core.backend import Observation, RobotLimits
    from mdle.core.pose import Pose
    from mdle.lang import load_text, show_program
    from mdle.runtime import Scheduler

    reg = default_registry().merged(Registry.from_modules(types.SimpleNamespace(probe=probe)))
    world = sim.load_world("ellipse")
    ctx = Context(Observation(time=0.0, pose=Pose()), 0.0, 0.1, RobotLimits(1.0, 1.0, 3.0))

    def ticks(element: Any) -> None:
        sched = Scheduler(element, sim.SimBackend(world, sensing="exact"))
        for _ in range(100):
            sched.tick()

    print(f"{'chain':<10}{'N':>4}  {'check s':>8} {'peak MB':>8}  {'show s':>7} "
          f"{'lines':>6}  {'100 ticks s':>11} {'peak MB':>8}  {'reads/test':>10}")
    for kind, make in (("interrupt", interrupt_chain), ("behavior", behavior_chain)):
        for n in sizes:
            text = make(n)
            program, t_check, m_check = measured(partial(load_text, text, "chain.mdle", reg))
            shown, t_show, _ = measured(partial(show_program, program))
            assert program.entry is not None
            entry = program.elements[program.entry]
            _, t_run, m_run = measured(partial(ticks, entry))
            reads = "-"
            if kind == "interrupt":
                _READS[0] = 0
                entry.interrupt.test(ctx)
                reads = str(_READS[0])
            print(f"{kind:<10}{n:>4}  {t_check:8.3f} {m_check / 1e6:8.2f}  {t_show:7.3f} "
                  f"{shown.count(chr(10)):>6}  {t_run:11.3f} {m_run / 1e6:8.2f}  {reads:>10}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
