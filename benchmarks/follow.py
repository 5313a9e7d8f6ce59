"""Cost of ``follow_boundary`` per tick at 181 beams (target: <= 60 us for its own work).

    python benchmarks/follow.py [--repeat N]

The observations of a real 20 s run (the ideal unicycle following the hexagon at 1 m/s,
noisy LMS-200 scan, 50 Hz) are recorded once; then the atom's step is replayed over them
with a fresh tick context each time (so nothing is cached across ticks), and so are its
parts: the boundary view alone and the scan points the safety layer reads. The law, the
latency bookkeeping and the safety layer are the difference. Each figure is the best of
``--repeat`` rounds, in microseconds per tick; the shares are ratios within the process,
which stay meaningful on a loaded machine.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

# A script's folder comes first on sys.path: keep benchmarks/*.py from shadowing packages.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import sim  # noqa: E402 (after the sys.path fix)
from atoms.boundary import cached_view  # noqa: E402 (after the sys.path fix)
from atoms.follow import follow_boundary, scan_points_cached, start_follow  # noqa: E402
from atoms.registry import Context  # noqa: E402 (after the sys.path fix)
from mdle.backend import Observation  # noqa: E402 (after the sys.path fix)
from mdle.loader import load_text  # noqa: E402 (after the sys.path fix)
from mdle.runtime import run  # noqa: E402 (after the sys.path fix)

ARGS: dict[str, Any] = {"side": "right", "rc": 0.5, "v": 1.0, "zeta": 1.0, "kf": 0.5,
                        "umax": math.inf, "tau": 0.2, "margin": 0.15, "lookahead": 0.8,
                        "latency": math.inf}
DT = 0.02


class _Grab:
    """Keep every observation the run saw."""

    def __init__(self, backend: sim.SimBackend) -> None:
        self.backend = backend
        self.obs: list[Observation] = []

    def on_start(self, scheduler: Any) -> None:
        """Start a run (nothing to do)."""

    def on_event(self, event: Any) -> None:
        """Take an event (nothing to do)."""

    def on_tick(self, sample: Any) -> None:
        """Keep the observation of this tick."""
        self.obs.append(self.backend.observe())

    def on_end(self, result: Any) -> None:
        """End a run (nothing to do)."""


def _observations() -> tuple[list[Observation], sim.SimBackend]:
    backend = sim.SimBackend(sim.load_world("hexagon"), seed=1)
    grab = _Grab(backend)
    program = load_text("atom f = (follow_boundary(side = right, rc = 0.5 m, v = 1 m/s), "
                        "never, 20 s)\nplan main = ((f), never, inf)\n")
    run(program.elements["main"], backend, rate=1 / DT, observers=[grab])
    return grab.obs, backend


def _per_tick(obs: list[Observation], backend: sim.SimBackend,
              part: Callable[[Context, Any], object]) -> float:
    state = start_follow(ARGS, Context(obs[0], 0.0, DT, backend.limits))
    t0 = time.perf_counter()
    for i, o in enumerate(obs):
        part(Context(o, i * DT, DT, backend.limits), state)
    return (time.perf_counter() - t0) / len(obs) * 1e6


def main() -> None:
    """Print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timing rounds (best is kept)")
    a = ap.parse_args()
    obs, backend = _observations()
    parts: dict[str, Callable[[Context, Any], object]] = {
        "follow_boundary (whole step)": lambda c, s: follow_boundary(ARGS, c, s),
        "boundary view alone": lambda c, s: cached_view(c, "right"),
        "scan points alone": lambda c, s: scan_points_cached(c),
    }
    best = {name: min(_per_tick(obs, backend, fn) for _ in range(a.repeat))
            for name, fn in parts.items()}
    print(f"{len(obs)} ticks of a hexagon run, 181 beams; best of {a.repeat} rounds")
    for name, us in best.items():
        print(f"  {name:30} {us:7.1f} us/tick")
    whole = best["follow_boundary (whole step)"]
    rest = whole - best["boundary view alone"] - best["scan points alone"]
    print(f"  law + latency + safety layer   {rest:7.1f} us/tick")
    print(f"whole step: {whole / 60.0:.2f}x the 60 us target")


if __name__ == "__main__":
    main()
