"""Cost of the curvature estimators per 181-beam scan (target: averaged estimate <= 60 us).

    python benchmarks/estimators.py [--repeat N]

Each figure is the best of several timing rounds (least disturbed by other load on the
machine), in microseconds per scan, for a noisy LMS-200-like scan of a wall and a cylinder.
"averaged, full" is the whole path from ranges: points, connected surfaces, windows 7-9.
The boundary view (what ``follow_boundary`` computes every tick) is timed on that scan, where
only the side ray hits, and on one with the cylinder straight ahead, where both rays hit.
"""

from __future__ import annotations

import argparse
import sys
import timeit
from pathlib import Path

import numpy as np

# A script's folder comes first on sys.path: keep benchmarks/*.py (benchmarks/sim.py, say)
# from shadowing the packages of the same name.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

# The project's imports must come after the sys.path fix above, hence the E402 waivers.
from mdle.atoms import estimators as E  # noqa: E402 (after the sys.path fix)
from mdle.atoms.boundary import boundary_view  # noqa: E402 (after the sys.path fix)
from mdle.core.backend import Scan  # noqa: E402 (after the sys.path fix)


def _scan(rng: np.random.Generator, centre: tuple[float, float] = (2.0, 0.5)) -> Scan:
    """Scan a wall 0.6 m to the right and a cylinder of radius 0.5 m at ``centre`` (0.8 % noise)."""
    b = np.radians(np.arange(-90.0, 90.5, 1.0))
    d = np.stack((np.cos(b), np.sin(b)), axis=1)
    wall = np.where(np.sin(b) < -0.05, -0.6 / np.minimum(np.sin(b), -0.05), np.inf)
    c = np.array(centre)
    bb = d @ c
    disc = bb * bb - (c @ c - 0.25)
    cyl = np.where(disc > 0, bb - np.sqrt(np.abs(disc)), np.inf)
    r = np.minimum(wall, cyl)
    r = r * (1 + rng.normal(0, 0.008, r.shape))
    valid = np.isfinite(r) & (r < 10)
    return Scan(np.where(valid, r, 10.0), b, valid, 0.0, 10.0)


def main() -> None:
    """Time each estimator on the two scans and print microseconds per scan."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2000, help="calls per timing round")
    args = parser.parse_args()
    scan = _scan(np.random.default_rng(0))
    ahead = _scan(np.random.default_rng(0), centre=(1.5, 0.0))  # the front ray hits it too
    s = E.surfaces(scan.ranges, scan.bearings, scan.valid)
    cases = {
        "surfaces (points + connectivity)": lambda: E.surfaces(scan.ranges, scan.bearings,
                                                               scan.valid),
        "averaged w 7-9, full": lambda: E.averaged_curvature(
            E.surfaces(scan.ranges, scan.bearings, scan.valid)),
        "averaged w 7-9, given surfaces": lambda: E.averaged_curvature(s),
        "geometric w 1": lambda: E.geometric_curvature(s, 1),
        "classical w 8": lambda: E.classical_curvature(s, 8),
        "Gaussian smoothing (sigma 1)": lambda: E.smooth_positions(s, 1.0),
        "boundary view (side ray hits)": lambda: boundary_view(scan, "right"),
        "boundary view (both rays hit)": lambda: boundary_view(ahead, "right"),
    }
    print(f"{'estimator':36} {'us per scan':>12}")
    assert boundary_view(ahead, "right").front.hit and boundary_view(ahead, "right").side.hit
    for name, fn in cases.items():
        best = min(timeit.repeat(fn, number=args.repeat, repeat=7)) / args.repeat
        print(f"{name:36} {best * 1e6:12.1f}")


if __name__ == "__main__":
    main()
