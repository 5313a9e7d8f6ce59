"""Run the fuzz tier at scale: ``python tests/fuzz/at_scale.py [--scale N] [--jobs J]``.

Every fuzz test in ``tests/fuzz/`` draws ``N`` times its CI count of hostile inputs
(``MDLE_FUZZ_SCALE``, see ``tests/fuzz/conftest.py``), on ``J`` processes (pytest-xdist),
at low priority (``nice``), with hypothesis's database kept in ``.hypothesis/`` so a
failure found once is tried first next time. Scale 100 draws about 100,000 inputs and
takes on the order of an hour on two cores. The exit code is pytest's: 0 when nothing
was found; otherwise pytest prints the shrunk failing input.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    """Parse the options and run the tier; return pytest's exit code."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scale", type=int, default=100,
                        help="examples per test, as a multiple of its CI count (default 100)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                        help="pytest-xdist processes (default: every core)")
    parser.add_argument("pytest_args", nargs="*", help="more pytest arguments (after --)")
    args = parser.parse_args(argv)
    if args.scale < 1 or args.jobs < 1:
        parser.error("--scale and --jobs must be at least 1")
    here = Path(__file__).resolve().parent
    env = dict(os.environ, MDLE_FUZZ_SCALE=str(args.scale), MPLBACKEND="Agg")
    cmd = ["nice", sys.executable, "-m", "pytest", str(here), "-q", "-n", str(args.jobs),
           *args.pytest_args]
    return subprocess.run(cmd, env=env, cwd=here.parent.parent, check=False).returncode


if __name__ == "__main__":
    sys.exit(main())
