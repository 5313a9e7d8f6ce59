"""Regenerate every figure the README and docs/ show, into docs/figures/.

    python docs/figures/make_figures.py [--out docs/figures] [--no-sweep] [--only NAME...]

* the paper's runs (Figures 1-3, the hexagon followed on the left, Figures 6-9): each plan
  in plans/paper/ run in the simulator as the README's table says, its trace drawn by
  ``mdle plot`` (the same figure);
* Figures 4-5 (curvature estimates against the scan angle): ``mdle experiment curvature``;
* the kf x rate study of docs/sweep.md (72 runs, about two minutes on two idle cores):
  ``mdle sweep plans/sweep/kf-rate.yaml`` and its report's kf plot, one line per rate.

The runs go on every core (one process each). Figures are written at 100 dpi with a
128-colour palette to keep the repository small. Works from a checkout where mdle is not installed.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

# The checkout's root first: `python docs/figures/make_figures.py` from a fresh clone.
ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

DPI = 100

#: Figure file -> the `mdle run` arguments after the plan (the README's table).
RUNS: dict[str, tuple[str, list[str]]] = {
    "fig1-ellipse.png": ("plans/paper/fig1-ellipse.mdle", ["--rate", "50"]),
    "fig2-hexagon.png": ("plans/paper/fig2-hexagon.mdle", ["--rate", "50"]),
    "fig2-hexagon-left.png": ("plans/paper/fig2-hexagon.mdle",
                              ["--rate", "50", "--plan", "mirrored"]),
    "fig3-u-shape.png": ("plans/paper/fig3-u-shape.mdle",
                         ["--rate", "100", "--sensing", "exact"]),
    "fig6-corridor.png": ("plans/paper/fig6-corridor.mdle", []),
    "fig8-garden.png": ("plans/paper/fig8-garden.mdle", []),
}


def shrink(path: str | Path) -> None:
    """Rewrite a PNG with a 128-colour palette: a third of the bytes, the same to the eye."""
    from PIL import Image

    with Image.open(path) as im:
        small = im.convert("RGB").quantize(colors=128, method=Image.Quantize.MEDIANCUT,
                                           dither=Image.Dither.NONE)
    small.save(path, optimize=True)


def run_figure(name: str, out: str, work: str) -> str:
    """Run one plan with a trace and draw it; return the figure's path."""
    from mdle.cli import main
    from mdle.view.figure_output import save_figure
    from mdle.view.plot import trace_and_world, trace_figure

    plan, extra = RUNS[name]
    trace = os.path.join(work, name.replace(".png", ".jsonl"))
    code = main(["run", str(ROOT / plan), *extra, "--quiet", "--trace", trace])
    if code != 0:
        raise RuntimeError(f"mdle run {plan} {' '.join(extra)} exited {code}")
    path = os.path.join(out, name)
    save_figure(trace_figure(*trace_and_world(trace)), path, dpi=DPI)
    shrink(path)
    return path


def sweep_figure(out: Path, work: Path, jobs: int) -> Path:
    """Run the kf x rate study and draw its kf plot, one median line per rate."""
    from mdle.cli import main
    from mdle.sweep.report import plot_axes
    from mdle.sweep.table import read_rows

    results = work / "kf-rate"
    code = main(["sweep", str(ROOT / "plans/sweep/kf-rate.yaml"), "--out", str(results),
                 "--jobs", str(jobs)])
    if code != 0:
        raise RuntimeError(f"mdle sweep exited {code}")
    [plot] = plot_axes(read_rows(results), work / "plots", "follow_mean_err", ["param_kf"],
                       group="rate")
    target = out / "sweep-kf-rate.png"
    shutil.copyfile(plot, target)
    shrink(target)
    return target


def main() -> int:
    """Write the figures; print each one's path and how long it all took."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures")
    parser.add_argument("--no-sweep", action="store_true",
                        help="skip the two-minute kf x rate study (keep its figure)")
    parser.add_argument("--only", nargs="*", metavar="NAME", default=None,
                        help="only these run figures (file names, e.g. fig1-ellipse.png)")
    args = parser.parse_args()
    from mdle.experiments.curvature import plot_figures
    from mdle.sweep.executors import default_jobs

    t0 = time.perf_counter()
    args.out.mkdir(parents=True, exist_ok=True)
    names = list(RUNS) if args.only is None else args.only
    unknown = [n for n in names if n not in RUNS]
    if unknown:
        parser.error(f"unknown figure {unknown[0]}; one of: {', '.join(RUNS)}")
    jobs = default_jobs()
    with tempfile.TemporaryDirectory(prefix="mdle-figures-") as work:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            for path in pool.map(run_figure, names, [str(args.out)] * len(names),
                                 [work] * len(names)):
                print(f"wrote {path}", flush=True)
        if args.only is None:
            for path in plot_figures(args.out, dpi=DPI):
                shrink(path)
                print(f"wrote {path}", flush=True)
            if not args.no_sweep:
                print(f"wrote {sweep_figure(args.out, Path(work), jobs)}", flush=True)
    print(f"done in {time.perf_counter() - t0:.0f} s on {jobs} processes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
