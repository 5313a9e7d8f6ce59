"""Compare with a previous release: `mdle check` on the shipped plans, and a tick.

Two versions of mdle cannot share one process, so each measurement runs in a fresh
interpreter, the two versions alternating (old, new, old, new, ...) so that the machine's
load falls on both alike; a figure is the ratio of the two medians. The previous release is
checked out with ``git worktree`` into a temporary folder and its C kernels are built in
place with the same compiler flags as this checkout's, so both run the same kind of code.

* ``check``: the wall time of ``python -m mdle check PLAN`` (start-up, parse, check), summed
  over every shipped plan that checks clean in both versions.
* ``tick``: the time per controlled tick of ``follow_boundary`` at 10 Hz around a seeded
  generated obstacle (the simulator, the law and the scheduler; no trace), measured in the
  child process after the plan is compiled and 50 ticks have warmed it up.

Run: ``python benchmarks/release.py [--against REV] [--repeat R] [--ticks N]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The release the house issue (28) measures against: main before its moves.
DEFAULT_AGAINST = "c06cc08"

# The tick measured in a child: only names that exist in every release since the layers.
_TICK = textwrap.dedent("""
    import sys, time
    from mdle.lang import load_text
    from mdle.runtime import Scheduler
    from mdle.sim import SimBackend
    from mdle.sim.generated import generate_shape
    ticks = int(sys.argv[1])
    program = load_text("atom f = (follow_boundary(side = right, rc = 0.5 m, v = 0.3 m/s), "
                        "never, inf)\\nplan main = ((f), never, inf)\\n")
    backend = SimBackend(generate_shape(7, 3).world(), seed=0)
    sch = Scheduler(program.elements["main"], backend, 10.0, [], stall_timeout=None)
    for _ in range(50):
        sch.tick()
    t0 = time.perf_counter()
    for _ in range(ticks):
        if not sch.tick():
            raise SystemExit("the run ended early")
    print((time.perf_counter() - t0) / ticks * 1e6)
""")


def _build_kernels(tree: Path) -> None:
    """Build ``sim/_kernels.c`` in place in ``tree`` (as the install does)."""
    src = tree / "sim" / "_kernels.c"
    if not src.exists():
        return
    out = tree / "sim" / ("_kernels" + sysconfig.get_config_var("EXT_SUFFIX"))
    if out.exists():
        return
    include = sysconfig.get_paths()["include"]
    import numpy

    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-ffp-contract=off", f"-I{include}",
                    f"-I{numpy.get_include()}", str(src), "-o", str(out), "-lm"], check=True)


def _env(tree: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(tree)}


def _plans(old: Path, new: Path) -> list[str]:
    """Return the shipped plans (relative paths) that check clean in both trees."""
    found = sorted(str(p.relative_to(new)) for p in (new / "plans").rglob("*.mdle"))
    ok = []
    for rel in found:
        if not (old / rel).exists():
            continue
        if all(subprocess.run([sys.executable, "-m", "mdle", "check", rel], cwd=tree,
                              env=_env(tree), capture_output=True).returncode == 0
               for tree in (old, new)):
            ok.append(rel)
    return ok


def _check_seconds(tree: Path, plans: list[str]) -> float:
    total = 0.0
    for rel in plans:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "mdle", "check", rel], cwd=tree, env=_env(tree),
                       capture_output=True, check=True)
        total += time.perf_counter() - t0
    return total


def _tick_us(tree: Path, ticks: int) -> float:
    out = subprocess.run([sys.executable, "-c", _TICK, str(ticks)], cwd=tree, env=_env(tree),
                         capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    """Measure and print the ratios (this checkout / the release)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", default=DEFAULT_AGAINST, help="the release (a git revision)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--ticks", type=int, default=2000)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "release"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(old),
                        args.against], check=True)
        try:
            for tree in (old, ROOT):
                _build_kernels(tree)
            plans = _plans(old, ROOT)
            check: dict[str, list[float]] = {"old": [], "new": []}
            tick: dict[str, list[float]] = {"old": [], "new": []}
            for _ in range(args.repeat):
                for name, tree in (("old", old), ("new", ROOT)):
                    check[name].append(_check_seconds(tree, plans))
                    tick[name].append(_tick_us(tree, args.ticks))
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(old)],
                           check=False)
    print(f"against {args.against}, {args.repeat} alternating rounds, "
          f"load average {os.getloadavg()[0]:.1f}")
    for what, data, unit in (("mdle check, %d plans" % len(plans), check, "s"),
                             ("controlled tick", tick, "us")):
        o, n = statistics.median(data["old"]), statistics.median(data["new"])
        print(f"  {what:28s} release {o:9.3f} {unit}   this {n:9.3f} {unit}   "
              f"ratio {n / o:5.3f}")


if __name__ == "__main__":
    main()
