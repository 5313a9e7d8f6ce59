"""Regenerate every figure the README and docs/ show, and every number quoted beside one.

    python docs/figures/make_figures.py [--out docs/figures] [--no-sweep] [--only NAME...]
    python docs/figures/make_figures.py --numbers-only

* the paper's runs (Figures 1-3, the hexagon followed on the left, Figures 6-9): each plan
  in plans/paper/ run in the simulator as the README's table says, its trace drawn by
  ``mdle plot`` (the same figure);
* Figures 4-5 (curvature estimates against the scan angle): ``mdle experiment curvature``;
* the kf x rate study of docs/sweep.md (72 runs, under a minute on two cores):
  ``mdle sweep plans/sweep/kf-rate.yaml`` and its report's kf plot, one line per rate;
* ``numbers.json`` beside the figures: the numbers the docs quote beside them (each figure
  run's following error and clearance, what its curvature panel shows, and the runs those
  paragraphs compare against: the hexagon at 10 Hz, the Pioneer plans on the whole-scan
  model; Figures 4-5's estimates; the kf x rate study's table and summary), measured from
  the same runs. Every such number in the README and docs/*.md is followed by a marker,
  ``0.012<!--n:hexagon-10hz.mean_err-->``, which this script rewrites to the new value;
  tests/test_docs_numbers.py checks the docs against the table and the table against fresh
  runs. ``--numbers-only`` does that part
  alone (the runs, no drawing: about 15 s); it and ``--no-sweep`` keep the study's numbers
  as the table has them. A fenced block the docs quote whole follows its own marker,
  ``<!--block:sweep-kf-rate.report-->``.

The runs go on every core (one process each). Figures are written at 100 dpi with a
128-colour palette to keep the repository small. Works from a checkout where mdle is not installed.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

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


#: Runs whose numbers the docs quote beside a figure without a figure of their own: name ->
#: (plan, `mdle run` arguments after it, the model its `follow_boundary` atoms are run with,
#: or None for the plan's own). Figure runs are named by their file, without ".png".
NUMBER_RUNS: dict[str, tuple[str, list[str], str | None]] = {
    "hexagon-10hz": ("plans/paper/fig2-hexagon.mdle", [], None),  # the default rate
    "corridor-scan": ("plans/paper/fig6-corridor.mdle", [], "scan"),
    "garden-scan": ("plans/paper/fig8-garden.mdle", [], "scan"),
}

#: Where the numbers go, beside the figures.
NUMBERS = "numbers.json"
#: The kf x rate study's entry in the table (kept as it was by --no-sweep).
SWEEP = "sweep-kf-rate"
#: A quoted block, in a fence right after its marker: ``<!--block:sweep-kf-rate.report-->``.
BLOCK = re.compile(r"(<!--block:([A-Za-z0-9_.-]+)-->\n```\n)(.*?)(\n```)", re.DOTALL)
#: A quoted number and its key: ``0.012<!--n:hexagon-10hz.mean_err-->`` (in ``+-0.1`` the
#: sign belongs to the text, not to the number).
MARKER = re.compile(r"((?:(?<!\+)-)?\d+(?:\.\d+)?)<!--n:([A-Za-z0-9_.-]+)-->")


def run_plan(name: str, work: str) -> str:
    """Run the plan of a figure or a number run, with a trace; return the trace's path."""
    from mdle.cli import main

    if name in NUMBER_RUNS:
        plan, extra, model = NUMBER_RUNS[name]
    else:
        (plan, extra), model = RUNS[name + ".png"], None
    path = ROOT / plan
    if model is not None:  # the same plan on another model, in the plan's own world
        text = path.read_text("utf-8")
        swapped = re.sub(r"model = \w+", f"model = {model}", text)
        if swapped == text:
            raise RuntimeError(f"{plan} names no model to replace by {model}")
        path = Path(work) / f"{name}.mdle"
        path.write_text(swapped, "utf-8")
        extra = [*extra, "--world", str(ROOT / plan.replace(".mdle", ".world.yaml"))]
    trace = os.path.join(work, f"{name}.jsonl")
    code = main(["run", str(path), *extra, "--quiet", "--trace", trace])
    if code != 0:
        raise RuntimeError(f"mdle run {plan} {' '.join(extra)} exited {code}")
    return trace


def run_numbers(trace_path: str) -> dict[str, str]:
    """Measure a run from its trace: what the docs quote, formatted as they quote it.

    ``mean_err``, ``max_err``: |d - rc| over the second half of the run for the ideal
    unicycle (the paper's 60 s runs), over its last three quarters for a robot with a body
    (the Pioneer's approach takes longer), d the true distance from the robot's centre to
    the nearest boundary; ``min_clearance``: the least true clearance of the body (of the
    point, for the ideal unicycle) over the whole run. The curvature panel's: on the
    whole-scan model, ``point_ticks`` (ticks where the model took the nearest point as a
    point, clamped), ``corner_passes`` (corners the robot's true nearest point passed) and
    ``axis`` (the panel's upper limit, 1/m); on the two rays, ``k_p5``, ``k_p95``, ``k_min``,
    ``k_max`` (the side ray's curvature, 1/m) and ``min_side_range``.
    """
    import numpy as np

    from mdle.view.plot import robot_radius, trace_and_world
    from mdle.view.plot_curvature import measured_curvature
    from mdle.view.plot_nearest import (
        NearestPanel,
        is_nearest_point_trace,
        nearest_measured,
        nearest_truth,
    )

    trace, world = trace_and_world(trace_path)
    t = trace.column("t")
    xy = np.column_stack([trace.column("true_x"), trace.column("true_y")])
    d = np.asarray(world.nearest_boundary(xy).distance, dtype=float)
    rc = float(np.nanmedian(trace.column("diag.rc")))
    radius = robot_radius(trace, world)
    tail = 0.5 if radius == 0.0 else 0.75
    late = t >= t[0] + (1.0 - tail) * (t[-1] - t[0])
    err = np.abs(d[late] - rc)
    end = trace.end or {}
    out = {"mean_err": f"{err.mean():.3f}", "max_err": f"{err.max():.3f}",
           "min_clearance": f"{float(end['min_clearance']):.3f}"}
    exact = str(trace.header.get("sensing") or "") == "exact"
    measured = nearest_measured(trace) if is_nearest_point_trace(trace) else None
    if measured is not None:
        panel = NearestPanel(measured.values, nearest_truth(trace, world), exact)
        out |= {"point_ticks": str(int(panel.point.sum())),
                "corner_passes": str(panel.episodes(panel.corner)),
                "axis": f"{panel.limits[1]:.2g}"}
    else:
        side = measured_curvature(trace)
        if side is not None:
            k = side.values[np.isfinite(side.values)]
            r = trace.column("diag.side_range")[trace.column("diag.side_hit") > 0.5]
            p5, p95 = np.percentile(k, [5.0, 95.0])
            out |= {"k_p5": f"{p5:.1f}", "k_p95": f"{p95:.1f}", "k_min": f"{k.min():.1f}",
                    "k_max": f"{k.max():.1f}", "min_side_range": f"{r.min():.2f}"}
    return out


def trashcan_numbers(seed: int = 0, draws: int = 5) -> dict[str, str]:
    """Figure 5's numbers: the can's exact curvature, the estimates' scatter, the beams."""
    import numpy as np

    from mdle.atoms import estimators as E
    from mdle.experiments.curvature import object_scans

    scans, exact = object_scans("trashcan", draws, seed)  # the scans Figure 5 draws
    on_can = np.isfinite(exact.curvatures)
    errors, estimated = [], 0
    for scan in scans:
        est = E.averaged_curvature(E.surfaces(scan.ranges, scan.bearings, scan.valid))
        ok = est.valid & on_can
        errors.append(est.curvature[ok] - exact.curvatures[ok])
        estimated = max(estimated, int(ok.sum()))
    e = np.concatenate(errors)
    return {"exact": f"{float(np.median(exact.curvatures[on_can])):g}",
            "rms": f"{float(np.sqrt(np.mean(e * e))):.1f}",
            "visible_beams": str(int(on_can.sum())), "estimated_beams": str(estimated)}


def cabinet_numbers(seed: int = 0, draws: int = 5) -> dict[str, str]:
    """Figure 4's number: how deep the corner's hump is (median over the scans, 1/m)."""
    import numpy as np

    from mdle.atoms import estimators as E
    from mdle.experiments.curvature import object_scans

    scans, _ = object_scans("cabinet", draws, seed)  # the scans Figure 4 draws
    deepest = []
    for scan in scans:
        est = E.averaged_curvature(E.surfaces(scan.ranges, scan.bearings, scan.valid))
        deepest.append(float(np.min(est.curvature[est.valid])))
    return {"hump": f"{float(np.median(deepest)):.0f}"}


def measure(name: str, work: str) -> tuple[str, dict[str, str], str]:
    """Run one figure or number run; return its name, its numbers and its trace's path."""
    trace = run_plan(name, work)
    return name, run_numbers(trace), trace


def all_numbers(work: str, jobs: int) -> dict[str, Any]:
    """Run every figure and number run (on ``jobs`` processes); return the numbers table."""
    names = [n.removesuffix(".png") for n in RUNS] + list(NUMBER_RUNS)
    table: dict[str, Any] = {}
    if jobs <= 1:  # in this process (a test's)
        results = [measure(name, work) for name in names]
    else:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            results = list(pool.map(measure, names, [work] * len(names)))
    for name, numbers, _ in results:
        table[name] = numbers
    table["figure4-cabinet"] = cabinet_numbers()
    table["figure5-trashcan"] = trashcan_numbers()
    return table


def kept_sweep_numbers(out: Path) -> dict[str, str]:
    """Return the kf x rate study's numbers as the table in ``out`` has them (none: empty)."""
    path = out / NUMBERS
    if not path.is_file():
        return {}
    kept = json.loads(path.read_text("utf-8")).get(SWEEP)
    return kept if isinstance(kept, dict) else {}


def write_numbers(table: dict[str, Any], out: Path) -> Path:
    """Write the numbers table as JSON (keys sorted, one run per block)."""
    path = out / NUMBERS
    doc = {"about": "the numbers the docs quote beside the figures; written by "
                    "docs/figures/make_figures.py, do not edit", **table}
    path.write_text(json.dumps(doc, indent=1, sort_keys=False) + "\n", "utf-8")
    return path


def lookup(table: dict[str, Any], key: str) -> str | None:
    """Return the quoted text of ``run.number`` in the table, or None when it has none."""
    run, _, number = key.partition(".")
    value = table.get(run, {}).get(number) if isinstance(table.get(run), dict) else None
    return value if isinstance(value, str) else None


def doc_files() -> list[Path]:
    """Return the README and every page of docs/: where numbers beside figures are quoted."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def rewrite_numbers(text: str, table: dict[str, Any], where: str) -> str:
    """Return ``text`` with every marked number (and block) replaced by the table's.

    Raises
    ------
    KeyError
        A marker names a number the table does not have (``where`` names the file).
    """
    def value(key: str) -> str:
        found = lookup(table, key)
        if found is None:
            raise KeyError(f"{where}: no number `{key}` in {NUMBERS}")
        return found

    text = BLOCK.sub(lambda m: m.group(1) + value(m.group(2)) + m.group(4), text)
    return MARKER.sub(lambda m: f"{value(m.group(2))}<!--n:{m.group(2)}-->", text)


def update_docs(table: dict[str, Any]) -> list[str]:
    """Rewrite every marked number in the docs from the table; return the files changed."""
    changed = []
    for doc in doc_files():
        text = doc.read_text("utf-8")
        updated = rewrite_numbers(text, table, doc.name)
        if updated != text:
            doc.write_text(updated, "utf-8")
            changed.append(str(doc.relative_to(ROOT)))
    return changed


def draw_figure(name: str, trace: str, out: str) -> str:
    """Draw a figure run's trace as `mdle plot` does; return the figure's path."""
    from mdle.view.figure_output import save_figure
    from mdle.view.plot import trace_and_world, trace_figure

    path = os.path.join(out, name)
    save_figure(trace_figure(*trace_and_world(trace)), path, dpi=DPI)
    shrink(path)
    return path


def sweep_figure(out: Path, work: Path, jobs: int) -> tuple[Path, dict[str, str]]:
    """Run the kf x rate study and draw its kf plot, one median line per rate.

    Returns the figure's path and the numbers docs/sweep.md quotes beside it
    (:func:`sweep_numbers`).
    """
    from mdle.cli import main
    from mdle.sweep.report import plot_axes
    from mdle.sweep.table import read_rows

    results = work / "kf-rate"
    code = main(["sweep", str(ROOT / "plans/sweep/kf-rate.yaml"), "--out", str(results),
                 "--jobs", str(jobs)])
    if code != 0:
        raise RuntimeError(f"mdle sweep exited {code}")
    rows = read_rows(results)
    [plot] = plot_axes(rows, work / "plots", "follow_mean_err", ["param_kf"], group="rate")
    target = out / "sweep-kf-rate.png"
    shutil.copyfile(plot, target)
    shrink(target)
    return target, sweep_numbers(rows)


def sweep_numbers(rows: list[dict[str, Any]]) -> dict[str, str]:
    """Return what docs/sweep.md quotes of the kf x rate study's results rows.

    ``runs``, ``collisions``, ``engaged``, ``closest`` (the least body clearance, m); per
    cell ``mean_kf{kf}_{rate}hz`` (the median over its runs of the mean |d - rc|) and
    ``max_kf{kf}_{rate}hz`` (the worst single tick); ``fall_lo`` and ``fall_hi``: by how much
    the median falls from the smallest kf to the largest, at the rate where it falls least and
    most; ``report``: what ``mdle sweep report DIR --by rate --by world --no-plots`` prints,
    without its closing notes.
    """
    import numpy as np

    from mdle.sweep.report import format_summary

    def key(value: Any) -> str:
        return f"{float(value):g}"

    out = {"runs": str(len(rows)),
           "collisions": str(sum(bool(r.get("collided")) for r in rows)),
           "engaged": str(sum(bool(r.get("engaged")) for r in rows)),
           "closest": f"{min(float(r['min_clearance']) for r in rows):.3f}"}
    kfs = sorted({float(r["param_kf"]) for r in rows})
    falls = []
    for rate in sorted({float(r["rate"]) for r in rows}):
        medians = {}
        for kf in kfs:
            cell = [r for r in rows if float(r["param_kf"]) == kf and float(r["rate"]) == rate]
            medians[kf] = float(np.median([float(r["follow_mean_err"]) for r in cell]))
            out[f"mean_kf{key(kf)}_{key(rate)}hz"] = f"{medians[kf]:.3f}"
            out[f"max_kf{key(kf)}_{key(rate)}hz"] = \
                f"{max(float(r['follow_max_err']) for r in cell):.2f}"
        falls.append(medians[kfs[0]] / medians[kfs[-1]])
    out |= {"fall_lo": f"{min(falls):.0f}", "fall_hi": f"{max(falls):.0f}"}
    # the summary's tables, without the notes after the last one
    report = format_summary(rows, ["rate", "world"])
    out["report"] = report[:report.index("\n\nengaged:")]
    return out


def main() -> int:
    """Write the figures, the numbers and the docs' quotes; print what and how long it took."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures")
    parser.add_argument("--no-sweep", action="store_true",
                        help="skip the kf x rate study (keep its figure and its numbers)")
    parser.add_argument("--only", nargs="*", metavar="NAME", default=None,
                        help="only these run figures (file names, e.g. fig1-ellipse.png); "
                             "the numbers and the docs are left as they are")
    parser.add_argument("--numbers-only", action="store_true",
                        help="only the runs' numbers: numbers.json and the docs' quotes")
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
        if args.only is not None:
            with ProcessPoolExecutor(max_workers=jobs) as pool:
                stems = [n.removesuffix(".png") for n in names]
                traces = [tr for _, _, tr in pool.map(measure, stems, [work] * len(stems))]
                for path in pool.map(draw_figure, names, traces, [str(args.out)] * len(names)):
                    print(f"wrote {path}", flush=True)
        else:
            table = all_numbers(work, jobs)
            if args.no_sweep or args.numbers_only:  # the study's numbers stay as they were
                table[SWEEP] = kept_sweep_numbers(args.out)
            else:
                target, table[SWEEP] = sweep_figure(args.out, Path(work), jobs)
                print(f"wrote {target}", flush=True)
            print(f"wrote {write_numbers(table, args.out)}", flush=True)
            for doc in update_docs(table):
                print(f"updated the quoted numbers in {doc}", flush=True)
            if not args.numbers_only:
                with ProcessPoolExecutor(max_workers=jobs) as pool:
                    traces = [os.path.join(work, n.replace(".png", ".jsonl")) for n in names]
                    for path in pool.map(draw_figure, names, traces,
                                         [str(args.out)] * len(names)):
                        print(f"wrote {path}", flush=True)
                for path in plot_figures(args.out, dpi=DPI):
                    shrink(path)
                    print(f"wrote {path}", flush=True)
    print(f"done in {time.perf_counter() - t0:.0f} s on {jobs} processes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
