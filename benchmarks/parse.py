"""Measure the parser and checker speed.

Lines per second on a generated 10,000-line plan (parsing alone, and parsing and
checking, in one process); `mdle check` on plans of 10,000 lines, 1 MB and 5 MB of two shapes
(blocks of atoms and behaviors laid out as `mdle fmt` does; one definition per line),
as lines per CPU second with the peak memory per source byte; and the wall time of
`mdle check` on a small plan (targets: >= 10,000 lines/s for plans laid out as `mdle fmt`
writes them, <= 200 bytes per source byte; < 0.5 s).

Measured on the reference two-core machine at a load average of 15 (`mdle check`,
lines per CPU second, start-up included; bytes of memory per source byte), with lark's
parser alone:

    shape                    10,000 lines
    blocks                   13,800  79 B
    one definition per line   5,000 115 B

and in the same run, the release before (a hand-written parser read valid files, lark
only files with errors): 23,800 90 B and 9,300 132 B. That parser was removed: on the
shipped plans (at most 55 lines) it saved at most 4 ms of parsing a file, against about
0.15 s of CPU time for the whole `mdle check`.

Run: python benchmarks/parse.py [--lines N] [--repeat R]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
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
    """Return the least CPU time of ``repeat`` calls of ``fn`` (seconds; steadier under load)."""
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return min(times)


def _cpu_of_check(mdle: Path, path: Path, bytecode: str | None = None
                  ) -> tuple[float, float, int]:
    """Run `mdle check` on a file; return (CPU seconds, wall seconds, peak RSS in bytes).

    CPU time (user + system, of the child) is what the machine gave the check: on a
    loaded machine it is far steadier than the wall time. The peak RSS is read by the
    child itself: Linux's ``VmHWM``, the peak of its own memory (elsewhere ``ru_maxrss``,
    which Linux carries over from the parent through fork and exec: it would read the
    benchmark's own size for small plans). With ``bytecode`` (a folder), the child keeps
    its compiled modules there, as an installed mdle does (pip compiles them); without,
    it runs as the environment says (with ``PYTHONDONTWRITEBYTECODE`` set, every start
    compiles mdle's modules again).
    """
    env = dict(os.environ)
    if bytecode is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = bytecode
    probe = ("import resource, sys; from mdle.cli import main; sys.argv = ['mdle', 'check', "
             f"'-q', {str(path)!r}]\n"
             "try:\n    code = main()\nexcept SystemExit as e:\n    code = e.code\n"
             "r = resource.getrusage(resource.RUSAGE_SELF)\n"
             "try:\n    rss = 1024 * int(next(line.split()[1] for line in open('/proc/self/status')"
             " if line.startswith('VmHWM:')))\n"
             "except (OSError, StopIteration):\n    rss = r.ru_maxrss * 1024\n"
             "print(r.ru_utime + r.ru_stime, rss, code, file=sys.stderr)")
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    cpu, rss, code = r.stderr.split()[-3:]
    if code not in ("0", "None"):
        raise SystemExit(f"mdle check {path} failed:\n{r.stdout}{r.stderr}")
    return float(cpu), wall, int(rss)


def main() -> int:
    """Print the figures; exit status 1 when `mdle check` fails."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--lines", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sizes", default="10k,1MB,5MB",
                    help="plans `mdle check` reads: 10k (lines), 1MB, 5MB (bytes)")
    args = ap.parse_args()

    from mdle.lang import load_text
    from mdle.lang.parser import iter_tokens, lark_parser, parse_module

    text = generated_plan(args.lines)
    n = text.count("\n")
    tokens = sum(1 for _ in iter_tokens(text))
    lark_parser()  # build (or load the cached tables) outside the timing
    parse = best_of(lambda: parse_module(text, "bench.mdle"), args.repeat)
    whole = best_of(lambda: load_text(text, "bench.mdle"), args.repeat)
    print(f"generated plan: {n} lines, {len(text)} bytes, {tokens} tokens "
          f"({tokens / n:.1f} per line; the plans in plans/ have 3-9)")
    print(f"parse:          {parse * 1000:8.1f} ms  {n / parse:10,.0f} lines/s")
    print(f"parse + check:  {whole * 1000:8.1f} ms  {n / whole:10,.0f} lines/s")
    print(f"                            {tokens / parse:10,.0f} tokens/s parsed")

    mdle = Path(sys.executable).parent / "mdle"
    print("mdle check, whole process (CPU = user + system time of the check; target "
          ">= 10,000 lines/s for blocks, <= 200 bytes of memory per source byte):")
    with tempfile.TemporaryDirectory() as folder:
        empty = Path(folder) / "empty.mdle"
        empty.write_text("atom a = (stop, never, 1 s)\nrun a\n", encoding="utf-8")
        cache = str(Path(folder) / "bytecode")
        _cpu_of_check(mdle, empty, cache)  # compiles the modules into the cache
        start, _, base_rss = _cpu_of_check(mdle, empty, cache)
        cold = min(_cpu_of_check(mdle, empty)[0] for _ in range(args.repeat))
        start = min([start] + [_cpu_of_check(mdle, empty, cache)[0] for _ in range(args.repeat)])
        how = ("compiling them at each start, as PYTHONDONTWRITEBYTECODE here asks"
               if os.environ.get("PYTHONDONTWRITEBYTECODE") else "as this environment runs it")
        print(f"  (a one-line plan: CPU {start:.2f} s with compiled modules, {cold:.2f} s {how};"
              f" peak RSS {base_rss / 1e6:.0f} MB. The figures below are with compiled "
              "modules; memory is counted above the one-line plan's)")
        for size in args.sizes.split(","):
            for shape, make in (("blocks", generated_plan), ("one definition per line",
                                                             definitions_plan)):
                if size.endswith("MB"):
                    nbytes = int(float(size[:-2]) * 1_000_000)
                    body = make(nbytes // 27) if make is generated_plan else make(nbytes)
                else:
                    lines = int(size.rstrip("k")) * 1000 if size.endswith("k") else int(size)
                    body = make(lines) if make is generated_plan else make(lines * 65)
                path = Path(folder) / "plan.mdle"
                path.write_text(body, encoding="utf-8")
                lines_n = body.count("\n")
                cpu, wall, rss = min((_cpu_of_check(mdle, path, cache)
                                      for _ in range(args.repeat if lines_n < 50_000 else 1)),
                                     key=lambda r: r[0])
                print(f"  {size:>5} {shape:<24} {lines_n:7,} lines {len(body) / 1e6:5.2f} MB: "
                      f"CPU {cpu:6.2f} s {lines_n / cpu:8,.0f} lines/s (wall {wall:6.2f} s), "
                      f"peak RSS {rss / 1e6:4.0f} MB, "
                      f"{(rss - base_rss) / len(body):4.0f} B/source byte")

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
