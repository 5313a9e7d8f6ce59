"""A Monte Carlo study of the paper's Figure 1: this checkout against a reference checkout.

    python benchmarks/montecarlo.py --reference DIR [--seeds 100] [--rounds 3]
    python benchmarks/montecarlo.py --breakdown [--seeds 5]

The study is ``mdle sweep`` of ``plans/paper/fig1-ellipse.mdle`` in its own world (the
ideal unicycle follows the 4 m x 2 m ellipse at rc = 1 m on a noisy 181-beam scan at
50 Hz) for 60 simulated seconds, over ``--seeds`` seeds, on one core.

``--reference DIR`` is another checkout of mdle (for example ``git worktree add DIR
c06cc08``, with its compiled loops built: ``pip install -e DIR`` in a scratch venv, or a
copy of the ``sim/_kernels*.so`` built from the same ``sim/_kernels.c``). Each round runs
the whole study once with each checkout, in alternating order, each in a fresh Python
process that imports only that checkout and runs the study's runs one after the other
(mdle sweep's engine with an in-process executor); the figure is the median over the rounds of the
ratio reference / this of the CPU time (the sweep and its worker, which other load on
the machine does not inflate), with the wall times beside it. Every run's row (status,
ticks, distance, following errors, engagement, closest approach...) must be the same in
both, seed by seed: the benchmark says so, or lists the seeds that differ.

``--breakdown`` runs the study's tasks in this process and splits one run's CPU time
between the control law, the simulator's step (motion, scan, truth), its observation,
and the rest (the scheduler, the recorder, the metrics).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

_HERE = Path(__file__).resolve().parent
REPO = _HERE.parent
# A script's folder comes first on sys.path: keep benchmarks/*.py from shadowing packages.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE]

SPEC = """\
plan: {repo}/plans/paper/fig1-ellipse.mdle
worlds: [{repo}/plans/paper/fig1-ellipse.world.yaml]
rates: [50]
seeds: {{count: {seeds}}}
duration: {seconds}
"""

#: Columns that measure the machine, not the run: left out of the comparison.
MACHINE = ("worker", "wall_time", "cpu_time")

# What each checkout runs, in its own process: the study through mdle sweep's engine, its
# runs one after the other in that process (the CPU time of one core, all of it counted:
# a pool's workers would be the fork server's children, out of this process's reach);
# prints the CPU and wall time and every row, as JSON.
CHILD = """\
import json, os, sys, tempfile, time
from mdle.sweep import parse_study, run_sweep
from mdle.sweep.worker import execute

class InProcess:
    name = "in-process"

    def run(self, tasks):
        for task in tasks:
            yield execute(task)

study = parse_study(sys.argv[1])
rows = []
with tempfile.TemporaryDirectory(prefix="mdle-mc-") as out:
    t0, c0 = time.perf_counter(), time.process_time()
    summary = run_sweep(study, out, executor=InProcess(), on_row=rows.append)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps({"wall": wall, "cpu": cpu, "done": summary.done, "rows": rows}))
"""


def run_checkout(root: Path, spec: str) -> dict[str, Any]:
    """Run the study with the checkout at ``root`` in a fresh process; return its figures."""
    env = dict(os.environ, PYTHONPATH=str(root), OPENBLAS_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, "-c", CHILD, spec], env=env, cwd=tempfile.gettempdir(),
                          capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise SystemExit(f"the study failed with {root}:\n{proc.stderr}")
    out: dict[str, Any] = json.loads(proc.stdout.splitlines()[-1])
    return out


def differing_seeds(ours: list[dict[str, Any]], theirs: list[dict[str, Any]]) -> list[int]:
    """Return the seeds whose rows differ in anything but the machine's columns."""
    def by_seed(rows: list[dict[str, Any]]) -> dict[int, dict[str, Any]]:
        return {int(r["seed"]): {k: v for k, v in r.items() if k not in MACHINE} for r in rows}

    a, b = by_seed(ours), by_seed(theirs)
    return sorted(s for s in a.keys() | b.keys() if a.get(s) != b.get(s))


def compare(reference: Path, spec: str, rounds: int) -> None:
    """Print the CPU and wall ratios of the reference to this checkout, round by round."""
    ratios: list[float] = []
    walls: list[float] = []
    for r in range(rounds):
        order = [("this", REPO), ("reference", reference)]
        if r % 2:
            order.reverse()
        got = {name: run_checkout(root, spec) for name, root in order}
        this, ref = got["this"], got["reference"]
        ratios.append(ref["cpu"] / this["cpu"])
        walls.append(ref["wall"] / this["wall"])
        diff = differing_seeds(this["rows"], ref["rows"])
        print(f"round {r + 1}: CPU {ref['cpu']:.2f} s (reference) / {this['cpu']:.2f} s "
              f"(this) = x{ratios[-1]:.2f}; wall {ref['wall']:.2f} / {this['wall']:.2f} s "
              f"= x{walls[-1]:.2f}; {this['done']} runs; rows "
              + ("identical, seed by seed" if not diff else f"DIFFER for seeds {diff}"))
    print(f"median over {rounds} rounds: CPU x{statistics.median(ratios):.2f} "
          f"(range x{min(ratios):.2f}-x{max(ratios):.2f}), wall "
          f"x{statistics.median(walls):.2f}")


def breakdown(spec: str) -> None:
    """Split the CPU time of the study's runs between the law, the simulator and the rest."""
    from mdle.runtime import scheduler
    from mdle.sim import backend
    from mdle.sweep import parse_study
    from mdle.sweep.tasks import expand
    from mdle.sweep.worker import execute

    tasks = list(expand(parse_study(spec)))
    execute(tasks[0])                       # warm: imports, the compiled loops, caches
    spent = {"law": 0.0, "sim step": 0.0, "sim observe": 0.0}
    clock = time.process_time

    def timed(f: Any, part: str) -> Any:
        def inner(*args: Any) -> Any:
            t = clock()
            try:
                return f(*args)
            finally:
                spent[part] += clock() - t
        inner.timed = True                  # type: ignore[attr-defined]
        return inner

    tick = scheduler.Scheduler._tick

    def tick_timing_the_law(self: Any) -> bool:
        # the running atom's law, wrapped once per slot (slots are the scheduler's own)
        for frame in self._stack:
            slot = frame.slot
            if slot.is_atom and not hasattr(slot.step, "timed"):
                slot.step = timed(slot.step, "law")
        return tick(self)

    whole = 0.0
    sim = backend.SimBackend
    advance, observe = sim.advance, sim.observe
    sim.advance = timed(advance, "sim step")                  # type: ignore[method-assign]
    sim.observe = timed(observe, "sim observe")               # type: ignore[method-assign]
    scheduler.Scheduler._tick = tick_timing_the_law           # type: ignore[method-assign]
    try:
        for task in tasks:
            t = clock()
            execute(task)
            whole += clock() - t
    finally:
        sim.advance, sim.observe = advance, observe           # type: ignore[method-assign]
        scheduler.Scheduler._tick = tick                      # type: ignore[method-assign]
    n = len(tasks)
    print(f"{n} runs, {whole / n * 1e3:.1f} ms of CPU a run (timers included):")
    for part, s in spent.items():
        print(f"  {part:12} {s / n * 1e3:7.1f} ms  {100 * s / whole:5.1f} %")
    rest = whole - sum(spent.values())
    print(f"  {'the rest':12} {rest / n * 1e3:7.1f} ms  {100 * rest / whole:5.1f} %  "
          "(scheduler, samples, recorder, metrics, world and plan)")


def main() -> None:
    """Compare with a reference checkout, or break one run's cost down."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", type=Path, help="another checkout of mdle")
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--breakdown", action="store_true")
    args = parser.parse_args()
    spec = SPEC.format(repo=REPO, seeds=args.seeds, seconds=args.seconds)
    print(f"Figure 1, {args.seeds} seeds of {args.seconds:g} s at 50 Hz, one worker; "
          f"load average {', '.join(f'{x:.1f}' for x in os.getloadavg())}")
    if args.breakdown:
        breakdown(spec)
    if args.reference is not None:
        if not (args.reference / "mdle" / "__init__.py").is_file():
            raise SystemExit(f"--reference {args.reference}: not a checkout of mdle")
        compare(args.reference.resolve(), spec, args.rounds)
    elif not args.breakdown:
        parser.error("give --reference DIR, --breakdown, or both")


if __name__ == "__main__":
    main()
