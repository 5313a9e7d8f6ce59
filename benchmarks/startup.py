"""Measure how long `mdle check` takes to start: the wall time of a whole check of a shipped plan.

Each round runs ``python -c pass`` and then ``python -m mdle check -q PLAN`` for every plan
given (default: every ``plans/**/*.mdle``), so the interpreter's own start and the machine's
load are measured in the same loop as the check. It prints, per plan, the median wall time
and CPU time (user + system of the child: on a loaded machine, about the wall time a quiet
one would show) of the check over the rounds, the same for the interpreter's bare start,
and the slowest plan's median CPU time against the target (issue 27: <= 0.3 s). The
modules run compiled, as an installed mdle does (pip compiles them): their bytecode is
kept in a temporary folder (``PYTHONPYCACHEPREFIX``) even where
``PYTHONDONTWRITEBYTECODE`` is set. The parser's tables come from the per-user cache,
built by the first run if missing.

Then one more check of the first plan runs under ``python -X importtime``, and the modules
that took longest to import (with what they imported) are listed.

Run: python benchmarks/startup.py [--rounds R] [PLAN ...]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
#: Issue 27's target for a whole `mdle check` of a shipped plan, in seconds.
TARGET = 0.3


def _run(command: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Return the wall time and the CPU time (user + system) of a command, in seconds.

    The CPU time is what the machine gave the command: on a loaded machine it is what the
    wall time would be on a quiet one. The benchmark stops if the command fails.
    """
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=REPO)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed:\n{done.stdout}{done.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def slowest_imports(plan: str, env: dict[str, str], count: int) -> list[tuple[int, str]]:
    """Return the ``count`` top-level imports of a check that took longest (microseconds, name).

    Top level: imported by the program itself, not by another module; the time includes
    what the module imported.
    """
    done = subprocess.run([sys.executable, "-X", "importtime", "-m", "mdle", "check", "-q", plan],
                          capture_output=True, text=True, env=env, cwd=REPO)
    found: list[tuple[int, str]] = []
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cumulative, name = line.split("|")
        if cumulative.strip().isdigit() and not name.startswith("  "):
            found.append((int(cumulative), name.strip()))
    return sorted(found, reverse=True)[:count]


def main() -> int:
    """Print the figures; exit status 1 when the slowest plan's median CPU is over the target."""
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("plans", nargs="*", help="plan files (default: every plans/**/*.mdle)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--imports", type=int, default=12, help="slowest imports to list")
    args = ap.parse_args()
    plans = args.plans or sorted(str(p.relative_to(REPO)) for p in REPO.glob("plans/**/*.mdle"))

    with tempfile.TemporaryDirectory() as folder:
        env = dict(os.environ)
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = folder
        check = [sys.executable, "-m", "mdle", "check", "-q"]
        _run(check + plans[:1], env)  # compiles the modules (and the parser's tables)
        bare: list[tuple[float, float]] = []
        runs: dict[str, list[tuple[float, float]]] = {p: [] for p in plans}
        for _ in range(args.rounds):
            bare.append(_run([sys.executable, "-c", "pass"], env))
            for plan in plans:
                runs[plan].append(_run(check + [plan], env))
        wall0 = statistics.median(w for w, _ in bare)
        cpu0 = statistics.median(c for _, c in bare)
        print(f"medians over {args.rounds} rounds; `python -c pass`: wall {wall0 * 1000:.0f} ms, "
              f"CPU {cpu0 * 1000:.0f} ms")
        print(f"{'mdle check -q PLAN':36} {'wall':>8} {'less pass':>10} {'CPU':>8} "
              f"{'less pass':>10}")
        cpus: dict[str, float] = {}
        for plan in plans:
            wall = statistics.median(w for w, _ in runs[plan])
            cpus[plan] = cpu = statistics.median(c for _, c in runs[plan])
            print(f"{plan:36} {wall * 1000:5.0f} ms {(wall - wall0) * 1000:7.0f} ms "
                  f"{cpu * 1000:5.0f} ms {(cpu - cpu0) * 1000:7.0f} ms")
        worst = max(plans, key=lambda p: cpus[p])
        slowest = cpus[worst]
        print(f"slowest: {worst}, CPU {slowest:.3f} s (target <= {TARGET} s): "
              f"{'met' if slowest <= TARGET else 'NOT met'}; load average "
              f"{os.getloadavg()[0]:.1f}")
        print(f"slowest imports of `mdle check {plans[0]}` (cumulative, microseconds):")
        for us, name in slowest_imports(plans[0], env, args.imports):
            print(f"  {us:8d}  {name}")
    return 0 if slowest <= TARGET else 1


if __name__ == "__main__":
    sys.exit(main())
