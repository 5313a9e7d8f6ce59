"""Sweep throughput: runs per second on 1 and 2 local processes and on a Dask LocalCluster.

    python benchmarks/sweep.py [--runs 24] [--seconds 30] [--rounds 1]

Targets (issue 13): >= 1.8x from 1 to 2 processes on 2 idle cores; the Dask LocalCluster
(2 worker processes, 1 thread each) within 15 % of 2 local processes. The study: one
boundary-following plan on the paper's ellipse, the ideal unicycle at 1 m/s, the noisy
scan at 20 Hz, ``--runs`` seeded random starts of ``--seconds`` simulated seconds each.
Each row also gives the CPU seconds a run costs its worker (``time.process_time``), which
other load on the machine does not inflate. Every figure includes starting the local worker
pool (a fork server that imports mdle once); the Dask cluster is started before the clock
(a cluster outlives a sweep). The machine's load average is printed beside the figures:
on a shared machine the ratios, taken in one process minutes apart, mean more than the
absolute rates.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

# A script's folder comes first on sys.path: keep benchmarks/*.py (benchmarks/sim.py, say)
# from shadowing the packages of the same name.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

from mdle.sweep import DaskExecutor, LocalExecutor, parse_study, run_sweep  # noqa: E402

SPEC = """\
plan:
  text: |
    atom follow(rc = 1 m) = (follow_boundary(rc = rc, v = 1 m/s), never, {seconds} s)
    plan main = ((follow), stalled, inf)
worlds: [ellipse]
robots: [ideal]
rates: [20]
starts: {{random: {{count: {runs}, distance: [1, 4], seed: 7}}}}
"""


def _rate(study: Any, executor: Any) -> tuple[float, float]:
    """Return runs per second and the workers' CPU seconds per run."""
    cpu: list[float] = []
    with tempfile.TemporaryDirectory(prefix="mdle-bench-") as out:
        t0 = time.perf_counter()
        summary = run_sweep(study, out, executor=executor,
                            on_row=lambda row: cpu.append(row["cpu_time"]))
        elapsed = time.perf_counter() - t0
    assert summary.done == study.size() and summary.failed == 0, summary
    return summary.done / elapsed, sum(cpu) / len(cpu)


def main() -> None:
    """Print runs per second for each executor and the two ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=24)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--rounds", type=int, default=1,
                        help="repeat the three measurements; the best of each is kept")
    parser.add_argument("--no-dask", action="store_true")
    args = parser.parse_args()
    study = parse_study(SPEC.format(runs=args.runs, seconds=args.seconds))
    print(f"{study.size()} runs of {args.seconds:g} s (ellipse, 20 Hz scan); "
          f"{os.cpu_count()} cores; load average before: "
          f"{', '.join(f'{x:.1f}' for x in os.getloadavg())}")
    cluster = client = None
    if not args.no_dask:
        import distributed

        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                           host="127.0.0.1", dashboard_address=None,
                                           silence_logs=40)
        client = distributed.Client(cluster)
    best: dict[str, float] = {}
    cpu_per_run: dict[str, float] = {}
    try:
        for _ in range(args.rounds):
            for name, make in (("1 process", lambda: LocalExecutor(1)),
                               ("2 processes", lambda: LocalExecutor(2)),
                               ("Dask LocalCluster (2 workers)",
                                lambda: DaskExecutor(client) if client else None)):
                executor = make()
                if executor is None:
                    continue
                rate, cpu = _rate(study, executor)
                best[name] = max(best.get(name, 0.0), rate)
                cpu_per_run[name] = min(cpu_per_run.get(name, cpu), cpu)
                print(f"  {name:30} {rate:6.2f} runs/s   worker CPU {cpu:5.3f} s/run")
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    one, two = best["1 process"], best["2 processes"]
    print(f"speed-up 2 processes / 1 process: {two / one:.2f}x (target >= 1.8x on 2 idle "
          "cores)")
    if "Dask LocalCluster (2 workers)" in best:
        dask = best["Dask LocalCluster (2 workers)"]
        print(f"Dask overhead against 2 local processes: {100 * (1 - dask / two):+.1f} % "
              "(target <= 15 %)")
    # On a loaded machine the wall-clock ratios measure the other load as much as the sweep;
    # the CPU a run costs in each executor does not depend on it.
    c1 = cpu_per_run["1 process"]
    for name, c in cpu_per_run.items():
        print(f"CPU per run, {name}: {c / c1:.2f}x that of 1 process")
    print(f"load average after: {', '.join(f'{x:.1f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
