"""Measure the parser and checker speed.

Lines per second on a generated 10,000-line plan, and the wall time of `mdle check` on a
small plan (targets: >= 10,000 lines/s; < 0.5 s).

Run: python benchmarks/parse.py [--lines N] [--repeat R]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def generated_plan(lines: int) -> str:
    """Return a plan of ``lines`` lines written the way plans in plans/ are.

    Comments, blank lines, one-line atoms and interrupts, behaviors and plans laid out one
    element per line (the `mdle fmt` layout). Every construct appears; the result checks
    cleanly.
    """
    out = ["# Generated benchmark plan.", "",
           "interrupt blocked(d = 0.5 m) = range(0 deg) < d",
           "interrupt astray = min_range(-100 deg, -80 deg) > 2 m or stalled", ""]
    i = 0
    while len(out) < lines - 12:
        out += [
            f"# Block {i}: cruise, spin and veer, then a nested patrol.",
            f"atom cruise{i}(v = 0.3 m/s) = (go(v), blocked(0.{i % 9 + 1} m) or x > {i} m, inf)",
            f"atom spin{i} = (turn({(i % 90) + 1} deg/s), never, {i % 7 + 1} s)",
            f"atom veer{i} = (arc(0.2 m/s, -15 deg/s), astray and not (y < -1 m), 2 min)",
            "",
            f"behavior patrol{i} = (",
            f"    (cruise{i}, (0.5, 2, spin{i}), veer{i})...,",
            "    t > 30 s,",
            "    300 s,",
            ")",
            f"behavior nest{i} = (",
            "    (",
            f"        patrol{i},",
            f"        ((spin{i}, cruise{i}(0.1 m/s)), range(0 deg) < 0.3 m, 30 s),",
            f"        ([0.5, 1], 1, veer{i}),",
            "    ),",
            "    stalled,",
            "    10 min,",
            ")",
            "",
        ]
        i += 1
    out += ["plan main = (", "    ("]
    out += [f"        nest{k}," for k in range(min(i, 8))]
    out += ["    ),", "    stalled,", "    inf,", ")", "", "run main"]
    return "\n".join(out) + "\n"


def definitions_plan(size: int) -> str:
    """Return a plan of about ``size`` bytes with one definition per line.

    Atoms, named interrupts and behaviors using the lines before them, each with its
    own numbers (no two interrupts alike): the checker's work per definition, not the
    parser's per line, dominates such a file. The result checks cleanly.
    """
    out = ["# Generated benchmark plan: one definition per line."]
    n, i = len(out[0]) + 1, 0
    while n < size - 200:
        k = 4 * i
        lines = [
            f"atom a{k}(v = 0.{i % 9 + 1} m/s) = (go(v), range({i % 180} deg) < 0.{i % 7 + 2} m, "
            f"{i % 50 + 1} s)",
            f"interrupt near{k} = range({i % 90} deg) < {i % 5 + 1}.5 m and not stalled",
            f"atom t{k} = (turn({i % 60 + 1} deg/s), near{k} or y > {i} m, {i % 9 + 1} s)",
            f"behavior b{k} = ((a{k}, t{k}, a{k}(0.1 m/s)), near{k} or x > {i} m, 2 min)",
        ]
        out += lines
        n += sum(len(line) + 1 for line in lines)
        i += 1
    out += [f"plan main = ((b{4 * (i - 1)}), stalled, inf)", "run main"]
    return "\n".join(out) + "\n"


def best_of(fn: Callable[[], object], repeat: int) -> float:
    """Return the best wall time of ``repeat`` calls of ``fn`` (seconds)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> int:
    """Print the figures; exit status 1 when `mdle check` fails."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--lines", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    from mdle.loader import load_text
    from mdle.parser import iter_tokens, lark_parser, parse_module

    text = generated_plan(args.lines)
    n = text.count("\n")
    tokens = sum(1 for _ in iter_tokens(text))
    lark_parser()  # build (or load the cached tables) outside the timing
    parse = best_of(lambda: parse_module(text, "bench.mdle"), args.repeat)
    whole = best_of(lambda: load_text(text, "bench.mdle"), args.repeat)
    print(f"generated plan: {n} lines, {len(text)} bytes, {tokens} tokens "
          f"({tokens / n:.1f} per line; the plans in plans/ have 3-9)")
    print(f"parse:          {parse * 1000:8.1f} ms  {n / parse:10,.0f} lines/s  (target >= 10,000)")
    print(f"parse + check:  {whole * 1000:8.1f} ms  {n / whole:10,.0f} lines/s")
    print(f"                            {tokens / parse:10,.0f} tokens/s parsed")

    mdle = Path(sys.executable).parent / "mdle"
    small = REPO / "plans" / "language" / "tour.mdle"
    runs = []
    for _ in range(max(5, args.repeat)):
        t0 = time.perf_counter()
        r = subprocess.run([str(mdle), "check", "-q", str(small)], capture_output=True)
        runs.append(time.perf_counter() - t0)
        if r.returncode != 0:
            print(r.stdout.decode(), r.stderr.decode())
            return 1
    print(f"mdle check {small.relative_to(REPO)}: median {statistics.median(runs):.3f} s, "
          f"best {min(runs):.3f} s  (target < 0.5 s)")
    print(f"(load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
