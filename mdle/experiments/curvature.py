"""Reproduce the seed paper's Table 1 and Figures 4-5: curvature estimates from ladar scans.

The simulated robot stands still in front of the trash can (a cylinder) and the file cabinet
(flat sides, sharp corners) of the reference worlds ``trashcan`` and ``cabinet``, and its
LMS-200 (the ``lms200`` profile: 0.8 % relative range noise, 1 mm resolution) takes ``draws``
scans. Every estimator configuration of Table 1 runs on every scan; the error against the
exact curvature of the simulated shape (the oracle scan from the same pose) is reduced to one
RMS per scan over the beams where the estimate is defined, and averaged over the draws
("averaged RMS error", the paper's wording).

Filtering is a Gaussian filter on the positions along each connected surface, sigma one beam
(the paper does not give its kernel).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["Row", "ROWS", "PAPER", "Result", "run_table", "format_table", "plot_figures"]

SMOOTHING_SIGMA = 1.0  # beams


@dataclass(frozen=True)
class Row:
    """One line of Table 1: estimator, filtered or not, windows."""

    method: str
    filtered: bool
    windows: tuple[int, ...]

    @property
    def label(self) -> str:
        """The row as Table 1 names it."""
        w = (f"{self.windows[0]}-{self.windows[-1]}" if len(self.windows) > 1
             else str(self.windows[0]))
        return f"{self.method}, {'filtered' if self.filtered else 'unfiltered'}, w {w}"


ROWS: tuple[Row, ...] = tuple(
    [Row("geometric", f, w) for f in (False, True) for w in ((1, 2, 3), (4, 5, 6), (7, 8, 9))]
    + [Row("classical", f, (w,)) for f in (False, True) for w in (1, 5, 8)])

#: The paper's Table 1 (trash can, cabinet), 1/m, in the order of :data:`ROWS`.
PAPER: dict[Row, tuple[float, float]] = dict(zip(ROWS, [
    (15.47, 13.47), (1.72, 4.29), (0.71, 3.43),
    (5.12, 7.74), (1.23, 4.40), (0.58, 3.56),
    (14.52, 15.75), (1.87, 5.46), (0.79, 4.51),
    (6.44, 10.35), (0.79, 5.53), (0.80, 4.73),
], strict=True))

OBJECTS = (("trash can", "trashcan"), ("cabinet", "cabinet"))


@dataclass(frozen=True)
class Result:
    """Averaged RMS error per row and object (1/m), with the number of scans used."""

    rms: dict[Row, dict[str, float]]
    draws: int
    seed: int


def _estimate(row: Row, scan: Any) -> Any:
    from mdle.atoms import estimators as E

    s = E.surfaces(scan.ranges, scan.bearings, scan.valid)
    if row.filtered:
        s = E.smooth_positions(s, SMOOTHING_SIGMA)
    fn = E.geometric_curvature if row.method == "geometric" else E.classical_curvature
    return fn(s, row.windows)


def object_scans(world: str, draws: int, seed: int) -> tuple[list[Any], Any]:
    """Scan a reference world from its start pose: ``draws`` noisy scans and the exact one."""
    from mdle.sim import SimBackend, load_world

    w = load_world(world)
    noisy = SimBackend(w, seed=seed, ladar="lms200")
    period = 1.0 / noisy.ladar_profile.rate if noisy.ladar_profile.rate > 0 else 0.1
    scans = []
    for _ in range(draws):
        noisy.advance(period)
        scans.append(noisy.observe().scan)
    exact = SimBackend(w, seed=seed, sensing="exact").observe().scan
    return scans, exact


def run_table(draws: int = 200, seed: int = 0, rows: Sequence[Row] = ROWS,
              step: Callable[[], None] | None = None) -> Result:
    """Compute Table 1 from ``draws`` noisy scans of each object.

    ``step`` is called once per (object, estimator) pair done (``2 * len(rows)`` calls):
    a progress bar's counter.
    """
    import numpy as np

    out: dict[Row, dict[str, float]] = {r: {} for r in rows}
    for label, world in OBJECTS:
        scans, exact = object_scans(world, draws, seed)
        truth = np.asarray(exact.curvatures, dtype=float)
        for row in rows:
            per_scan = []
            for scan in scans:
                est = _estimate(row, scan)
                ok = est.valid & np.isfinite(truth)
                if ok.any():
                    per_scan.append(math.sqrt(float(np.mean((est.curvature[ok] - truth[ok]) ** 2))))
            out[row][label] = float(np.mean(per_scan)) if per_scan else math.nan
            if step is not None:
                step()
    return Result(out, draws, seed)


def format_table(result: Result) -> str:
    """Format Table 1 as plain text: ours beside the paper's, per object."""
    head = (f"{'estimate':36} {'trash can':>9} {'(paper)':>8} {'cabinet':>9} {'(paper)':>8}")
    lines = [head, "-" * len(head)]
    for row, vals in result.rms.items():
        p = PAPER.get(row, (math.nan, math.nan))
        lines.append(f"{row.label:36} {vals['trash can']:9.2f} {p[0]:8.2f} "
                     f"{vals['cabinet']:9.2f} {p[1]:8.2f}")
    lines.append(f"averaged RMS error of the curvature, 1/m; {result.draws} scans per object, "
                 f"seed {result.seed}")
    return "\n".join(lines)


def plot_figures(out: Path, seed: int = 0, draws: int = 5, dpi: int = 120) -> list[Path]:
    """Plot Figures 4 (cabinet) and 5 (trash can); return the files written.

    The averaged geometric estimate (w 7-9) of a few scans against the scan angle, one
    colour and one legend entry per scan, with the exact curvature over the beams that saw
    the object (where the estimates are).
    """
    import numpy as np
    from matplotlib.figure import Figure

    from mdle.atoms import estimators as E

    out.mkdir(parents=True, exist_ok=True)
    files = []
    for fig_no, (label, world) in ((4, OBJECTS[1]), (5, OBJECTS[0])):
        scans, exact = object_scans(world, draws, seed)
        fig = Figure(figsize=(8, 4), layout="constrained")
        ax = fig.subplots()
        seen = np.zeros(exact.ranges.shape, bool)
        for i, scan in enumerate(scans):
            est = E.averaged_curvature(E.surfaces(scan.ranges, scan.bearings, scan.valid))
            seen |= est.valid
            ax.plot(np.degrees(scan.bearings), est.curvature, ".-", lw=0.8, ms=3,
                    color=f"C{i % 10}", alpha=0.85, label=f"scan {i + 1}: estimate, w 7-9")
        truth = np.where(np.isfinite(exact.curvatures) & seen, exact.curvatures, np.nan)
        ax.plot(np.degrees(exact.bearings), truth, "k--", lw=1.4, label="exact curvature")
        ax.axhline(0.0, color="0.6", lw=0.6, ls=":")
        # a corner is a jump of the exact tangent between neighbouring beams (its curvature
        # is infinite: no value to draw), marked where it lies
        tan = np.asarray(exact.tangents, dtype=float) if exact.tangents is not None else None
        if tan is not None:
            jump = np.abs(np.angle(np.exp(1j * np.diff(tan))))
            corner = np.flatnonzero(np.nan_to_num(jump) > math.radians(20.0))
            b = np.degrees(exact.bearings)
            for n, k in enumerate(corner):
                ax.axvline(0.5 * (b[k] + b[k + 1]), color="0.3", lw=1.0, ls=":",
                           label="corner (curvature infinite)" if n == 0 else None)
        idx = np.flatnonzero(seen)
        if idx.size:
            b = np.degrees(exact.bearings)
            ax.set_xlim(b[max(idx[0] - 2, 0)], b[min(idx[-1] + 2, b.size - 1)])
        ax.set_xlabel("scan angle (deg, counter-clockwise from the heading)")
        ax.set_ylabel("curvature (1/m, convex negative)")
        ax.set_title(f"Figure {fig_no}: geometric estimate over windows 7-9, {label}")
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                  fontsize="small")
        path = out / f"figure{fig_no}-{world}.png"
        fig.savefig(path, dpi=dpi)
        files.append(path)
    return files
