"""Cost of ``follow_boundary`` per tick at 181 beams (target: <= 60 us for its own work).

    python benchmarks/follow.py [--repeat N] [--controlled TICKS]

The observations of a real 20 s run (the ideal unicycle following the hexagon at 1 m/s,
noisy LMS-200 scan, 50 Hz) are recorded once; then the atom's step is replayed over them
with a fresh tick context each time (so nothing is cached across ticks), and so are its
parts: the boundary view alone and the scan points the safety layer reads, and the same
step on the paper's two rays (``model = rays``, the previous release's law), in alternating
rounds: the ratio of the two is the whole-scan model's cost. The law, the
latency bookkeeping and the safety layer are the difference. Each figure is the best of
``--repeat`` rounds, in microseconds per tick; the shares are ratios within the process,
which stay meaningful on a loaded machine. Last, a whole controlled tick is timed
(simulator, atom and scheduler: ``follow_boundary`` at 0.3 m/s on the default robot in the
100-segment world of ``benchmarks/sim.py``, a scan every tick at 10 Hz; target 120 us), in
rounds that alternate between the install's compiled simulator loops and numpy's (the same
numbers), and the ratio of the two is printed.

    python benchmarks/follow.py --split

times the controlled tick's parts instead: the backend's observe, command and advance, and
the exact clearance it measures when the scheduler reads it (together the simulator's
share), the atom's step, and the rest (the scheduler).

    python benchmarks/follow.py --instructions

counts instructions instead (valgrind's callgrind, repeatable whatever else the machine
does; ``PYTHONHASHSEED=0``, ``OPENBLAS_NUM_THREADS=1``): the recorded observations are
saved once, then each part is replayed under callgrind with 0 and with ``--rounds``
passes, and the controlled run with 0 and ``--controlled`` ticks; the difference per tick
is the part's own count. The replayed scans share one read-only bearing array, as the
simulator's and the drivers' do.

Figures (Python 3.11, numpy 2.4, the compiled searches of ``atoms/_searches.c`` and the
simulator's compiled loops; callgrind with ``OPENBLAS_NUM_THREADS=1`` so that idle BLAS
threads add no count, 2 rounds, repeated runs within about 2 %; wall time best of 20
rounds on a shared 2-core machine at a load average of about 5, where the absolute times
drift with the load and only the ratios taken within one run mean much):

    per tick                              callgrind   wall       before the compiled searches
    whole-scan step (replay)              360 k       71.5 us    478 k, 90.0 us
    the same, two rays (model = rays)     297 k       57.6 us    297 k, 53.2 us
      ratio (target 1.3x)                 1.21x       1.24x      1.61x, 1.69x
      view + scan points                  172 k       26.6 us    172 k
      law + latency + safety layer        188 k       44.9 us    306 k

With the next face's corner rules and the turn-away shaping (1 callgrind round; wall best
of 10 at a load average of 1): the whole-scan step 369 k and 37.1 us, the two rays' 298 k
and 28.6 us, ratios 1.24x and 1.30x.
With a tip seen from one flank taken as a point (1 callgrind round): the whole-scan step
382 k, the two rays' 305 k, 1.25x (main's code counted in the same session: 375 k and
305 k, 1.23x).
With the step's per-tick objects as named tuples, the squared ranges in the compiled
searches and the safety layer's points within reach from the compiled ``within`` (2
callgrind rounds, the same runs to the bit): the whole-scan step 337.5 k, the two rays'
268.1 k, 1.26x (main's code before them: 376.4 k and 291.3 k, 1.29x); a controlled tick
702.3 k (747.7 k).
    controlled tick (500 ticks)           757 k       163 us     885 k
      with numpy's simulator loops                    198 us

The step costs more in the controlled run than in the replay: the room returns a point on
most beams, the front ray hits in 74 % of the ticks and corner mode runs in 38 %
(docs/steering.md, "Limits and known weak points", says what remains).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import pickle
import re
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

# A script's folder comes first on sys.path: keep benchmarks/*.py from shadowing packages.
# The checkout's root goes last: the installed mdle (with its compiled fan cast) wins, and
# a checkout where mdle is not installed still runs.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]
sys.path.append(str(Path(__file__).resolve().parents[1]))

from mdle import sim  # noqa: E402 (after the sys.path fix)
from mdle.atoms import follow as follow_module  # noqa: E402 (after the sys.path fix)
from mdle.atoms.boundary import cached_view  # noqa: E402 (after the sys.path fix)
from mdle.atoms.follow import follow_boundary, scan_points_cached, start_follow  # noqa: E402
from mdle.atoms.registry import Context  # noqa: E402 (after the sys.path fix)
from mdle.core.backend import Observation  # noqa: E402 (after the sys.path fix)
from mdle.lang import load_text  # noqa: E402 (after the sys.path fix)
from mdle.runtime import Scheduler, run  # noqa: E402 (after the sys.path fix)
from mdle.sim.raycast import COMPILED  # noqa: E402 (after the sys.path fix)

ARGS: dict[str, Any] = {"side": "right", "rc": 0.5, "v": 1.0, "zeta": 1.0, "kf": 0.5,
                        "umax": math.inf, "tau": 0.2, "margin": 0.15, "lookahead": 0.8,
                        "latency": math.inf}
#: The same atom on the seed paper's two rays (``model = rays``: the previous release's law).
RAYS: dict[str, Any] = {**ARGS, "model": "rays"}
DT = 0.02
#: The controlled tick's part name, and its control period (s).
CONTROLLED = "controlled tick (sim + follow_boundary + scheduler, 100 segments)"
CONTROLLED_DT = 0.1
#: The whole step before issue 10's cost work: instructions per tick and us on a quiet machine.
BASELINE_INSTRUCTIONS = 625.5e3
BASELINE_US = 83.0


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
              part: Callable[[Context, Any], object], args: dict[str, Any] = ARGS) -> float:
    state = start_follow(args, Context(obs[0], 0.0, DT, backend.limits))
    t0 = time.perf_counter()
    for i, o in enumerate(obs):
        part(Context(o, i * DT, DT, backend.limits), state)
    return (time.perf_counter() - t0) / len(obs) * 1e6


def _controlled(compiled: bool | None = None) -> Scheduler:
    """Return a scheduler running ``follow_boundary`` on the simulator, after its first tick.

    The 100-segment world of ``benchmarks/sim.py`` (boxes at fixed density in a room), its
    default robot (pioneer2dx), a noisy LMS-200 scan every tick at 10 Hz, no observers.
    ``compiled``: the fan cast's loop, as :class:`mdle.sim.SimBackend` takes it.
    """
    here = Path(__file__).with_name("sim.py")  # not importable as `sim`: that is the package
    spec = importlib.util.spec_from_file_location("sim_benchmark", here)
    assert spec is not None and spec.loader is not None
    worlds = sys.modules.setdefault(spec.name, importlib.util.module_from_spec(spec))
    spec.loader.exec_module(worlds)
    backend = sim.SimBackend(worlds.scattered_world(100), seed=0, compiled=compiled)
    program = load_text("atom f = (follow_boundary(side = right, rc = 0.5 m, v = 0.3 m/s), "
                        "never, inf)\nplan main = ((f), never, inf)\n")
    sch = Scheduler(program.elements["main"], backend, 1 / CONTROLLED_DT, [], stall_timeout=None)
    sch.tick()  # starts the atom
    return sch


def _controlled_ticks(sch: Scheduler, ticks: int) -> None:
    for _ in range(ticks):
        if not sch.tick():
            raise SystemExit(f"the controlled run ended early: {sch.result}")


TWO_RAYS = "the same, two rays (model = rays)"
PARTS: dict[str, Callable[[Context, Any], object]] = {
    "follow_boundary (whole step)": lambda c, s: follow_boundary(ARGS, c, s),
    TWO_RAYS: lambda c, s: follow_boundary(RAYS, c, s),
    "boundary view alone": lambda c, s: cached_view(c, "right"),
    "scan points alone": lambda c, s: scan_points_cached(c),
    # the step reads both, and they share the tick's masked points (atoms.boundary.cached_beams)
    "view + scan points": lambda c, s: (cached_view(c, "right"), scan_points_cached(c)),
}


def _replay(saved: str, part: str, rounds: int) -> None:
    """Replay ``part`` over the saved observations ``rounds`` times (run under callgrind).

    For :data:`CONTROLLED`, ``rounds`` is a number of controlled ticks instead.
    """
    if part == CONTROLLED:
        _controlled_ticks(_controlled(), rounds)
        return
    with open(saved, "rb") as fh:
        obs, limits = pickle.load(fh)
    obs = _fixed_bearings(obs)
    fn = PARTS[part]
    args = RAYS if part == TWO_RAYS else ARGS
    fn(Context(obs[0], 0.0, DT, limits), start_follow(args, Context(obs[0], 0.0, DT, limits)))
    for _ in range(rounds):  # the first call above made every import and cache
        state = start_follow(args, Context(obs[0], 0.0, DT, limits))
        for i, o in enumerate(obs):
            fn(Context(o, i * DT, DT, limits), state)


def _fixed_bearings(obs: list[Observation]) -> list[Observation]:
    """Give every scan one read-only bearing array, as the simulator and the drivers do.

    (Unpickled, the bearings are a view of the pickle's bytes, which the estimators' memo of
    a sensor's fixed bearings does not trust.)
    """
    fixed: dict[bytes, Any] = {}
    out = []
    for o in obs:
        if o.scan is not None:
            b = fixed.setdefault(o.scan.bearings.tobytes(), o.scan.bearings.copy())
            b.setflags(write=False)
            o = replace(o, scan=replace(o.scan, bearings=b))
        out.append(o)
    return out


def _instructions(saved: str, part: str, rounds: int) -> int:
    out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                          sys.executable, __file__, "--replay", saved, part, str(rounds)],
                         capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONHASHSEED": "0",
                              "OPENBLAS_NUM_THREADS": "1"}).stderr  # idle BLAS threads count
    found = re.search(r"Collected : (\d+)", out)
    if found is None:
        raise SystemExit(f"callgrind gave no count:\n{out[-2000:]}")
    return int(found.group(1))


def _count(obs: list[Observation], backend: sim.SimBackend, rounds: int,
           controlled: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        saved = f"{tmp}/obs.pkl"
        with open(saved, "wb") as fh:
            pickle.dump((obs, backend.limits), fh)
        per = {}
        for name in PARTS:
            base = _instructions(saved, name, 0)
            per[name] = (_instructions(saved, name, rounds) - base) / (rounds * len(obs))
        if controlled:
            base = _instructions(saved, CONTROLLED, 0)
            tick = (_instructions(saved, CONTROLLED, controlled) - base) / controlled
    print(f"{len(obs)} ticks of a hexagon run, 181 beams; callgrind, {rounds} rounds")
    for name, n in per.items():
        print(f"  {name:30} {n / 1e3:8.1f} k instructions/tick")
    rest = per["follow_boundary (whole step)"] - per["view + scan points"]
    print(f"  law + latency + safety layer   {rest / 1e3:8.1f} k instructions/tick")
    whole = per["follow_boundary (whole step)"]
    print(f"whole step: {whole / BASELINE_INSTRUCTIONS:.2f}x the "
          f"{BASELINE_INSTRUCTIONS / 1e3:.1f}k of {BASELINE_US:.0f} us; "
          f"about {whole / BASELINE_INSTRUCTIONS * BASELINE_US:.0f} us on a quiet machine "
          f"(target: 60 us); {whole / per[TWO_RAYS]:.2f}x the two rays' step (target 1.3x)")
    if controlled:
        print(f"{CONTROLLED}: {tick / 1e3:.1f} k instructions/tick over {controlled} ticks")


def _controlled_split(ticks: int) -> dict[str, float]:
    """Time a controlled run's parts (us per tick): the backend's calls, the atom's step, the rest.

    Within the step, its sensing is timed too: the boundary view and the scan points (the
    first of the two computes the tick's masked points both read).

    Each part is wrapped in a clock read (about 0.1 us each), so the parts add up to a little
    more than :func:`_controlled_us` gives; the shares are what they are for.
    """
    sch = _controlled()
    spent = dict.fromkeys(("backend.observe", "backend.command", "backend.advance",
                           "backend.clearance read", "follow_boundary step"), 0.0)
    clock = time.perf_counter

    def timed(fn: Callable[..., Any], key: str) -> Callable[..., Any]:
        def call(*a: Any) -> Any:
            t0 = clock()
            out = fn(*a)
            spent[key] += clock() - t0
            return out
        return call

    backend = sch.backend
    # and the exact clearance, measured when the scheduler reads it (the simulator's work)
    for name, key in (("observe", "backend.observe"), ("command", "backend.command"),
                      ("advance", "backend.advance"),
                      ("_measure_clearance", "backend.clearance read")):
        setattr(backend, name, timed(getattr(backend, name), key))
    slot = sch._stack[-1].slot  # the running atom's slot: its step is what the tick calls
    slot.step = timed(slot.step, "follow_boundary step")
    # inside the step: its sensing (the module globals the step looks up at each call)
    sensing = {"cached_view": "  of which boundary view",
               "scan_points_cached": "  of which scan points"}
    saved = {name: getattr(follow_module, name) for name in sensing}
    for name, key in sensing.items():
        spent[key] = 0.0
        setattr(follow_module, name, timed(saved[name], key))
    try:
        t0 = clock()
        _controlled_ticks(sch, ticks)
        whole = clock() - t0
    finally:
        for name, fn in saved.items():
            setattr(follow_module, name, fn)
    out = {k: v / ticks * 1e6 for k, v in spent.items()}
    out["scheduler (the rest)"] = whole / ticks * 1e6 - sum(
        v for k, v in out.items() if not k.startswith(" "))
    out["whole tick"] = whole / ticks * 1e6
    out["simulator (backend.*)"] = sum(v for k, v in out.items() if k.startswith("backend."))
    return out


def _controlled_us(ticks: int, compiled: bool | None = None) -> float:
    sch = _controlled(compiled)
    t0 = time.perf_counter()
    _controlled_ticks(sch, ticks)
    return (time.perf_counter() - t0) / ticks * 1e6


def main() -> None:
    """Print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timing rounds (best is kept)")
    ap.add_argument("--instructions", action="store_true",
                    help="count instructions under callgrind instead of timing")
    ap.add_argument("--rounds", type=int, default=2, help="callgrind passes per part")
    ap.add_argument("--controlled", type=int, default=500, metavar="TICKS",
                    help="controlled ticks timed or counted (0: skip)")
    ap.add_argument("--split", action="store_true",
                    help="time the controlled tick's parts (backend, atom, scheduler) instead")
    ap.add_argument("--replay", nargs=3, metavar=("SAVED", "PART", "ROUNDS"),
                    help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.replay:
        _replay(a.replay[0], a.replay[1], int(a.replay[2]))
        return
    if a.split:
        rounds = [_controlled_split(a.controlled or 500) for _ in range(a.repeat)]
        print(f"{CONTROLLED}, median of {a.repeat} runs of {a.controlled or 500} ticks, "
              f"load average {os.getloadavg()[0]:.2f}:")
        for key in rounds[0]:
            us = statistics.median(r[key] for r in rounds)
            print(f"  {key:24} {us:7.1f} us/tick")
        return
    obs, backend = _observations()
    if a.instructions:
        _count(obs, backend, a.rounds, a.controlled)
        return
    parts = PARTS
    # rounds alternate between the parts, so that their ratios are taken under one load
    per_round: dict[str, list[float]] = {name: [] for name in parts}
    for _ in range(a.repeat):
        for name, fn in parts.items():
            per_round[name].append(_per_tick(obs, backend, fn,
                                             RAYS if name == TWO_RAYS else ARGS))
    best = {name: min(t) for name, t in per_round.items()}
    print(f"{len(obs)} ticks of a hexagon run, 181 beams; best of {a.repeat} rounds; "
          f"load average {os.getloadavg()[0]:.2f}")
    for name, us in best.items():
        print(f"  {name:30} {us:7.1f} us/tick")
    whole = best["follow_boundary (whole step)"]
    rest = whole - best["view + scan points"]
    print(f"  law + latency + safety layer   {rest:7.1f} us/tick")
    print(f"whole step: {whole / 60.0:.2f}x the 60 us target, "
          f"{whole / best[TWO_RAYS]:.2f}x the two rays' step (target 1.3x)")
    if a.controlled:
        # Rounds alternate between the install's fan cast and numpy's (the same numbers),
        # so that the ratio of the two is taken under the same load.
        runs: dict[bool | None, list[float]] = {None: [], False: []}
        for _ in range(a.repeat):
            for compiled, times in runs.items():
                if compiled is None or COMPILED:
                    times.append(_controlled_us(a.controlled, compiled))
        us = min(runs[None])
        how = "compiled" if COMPILED else "numpy (no compiled fan cast in this install)"
        print(f"{CONTROLLED}: {us:.1f} us/tick, best of {a.repeat} runs of {a.controlled} "
              f"ticks (target: 120 us); fan cast: {how}")
        if runs[False]:
            slow = min(runs[False])
            print(f"  the same with numpy's fan cast: {slow:.1f} us/tick "
                  f"(compiled: {us / slow:.2f}x)")


if __name__ == "__main__":
    main()
