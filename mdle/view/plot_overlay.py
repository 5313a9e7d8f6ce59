"""Several runs in one figure (``mdle plot A.jsonl B.jsonl ...``): paths and following error.

The top panel draws the first run's world once and every run's path in its own colour,
named by its file, with its start and end marked. The bottom panel is, against distance
travelled, the following error ``|d - rc|`` (``d`` the true distance from the robot's
centre to the nearest boundary, on the ticks a ``follow_boundary`` atom ran with its
``rc``), or the body clearance when a run has no following atom or no ground truth.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from mdle.core.errors import Diagnostic
from mdle.record.trace import Trace
from mdle.view.figure_output import PlotError
from mdle.view.plot import draw_world, robot_radius, run_pose

if TYPE_CHECKING:
    import numpy as np
    from matplotlib.figure import Figure

__all__ = ["overlay_figure", "following_error"]


def following_error(trace: Trace, radius: float) -> "tuple[np.ndarray, str] | None":
    """Return ``|d - rc|`` per sample (NaN off a following atom) and its axis name.

    Falls back to the body clearance (m) when no sample records ``rc``; None when the
    trace has no ground truth at all.
    """
    import numpy as np

    clearance = trace.column("clearance")
    if not np.isfinite(clearance).any():
        return None
    rc = trace.column("diag.rc")
    if np.isfinite(rc).any():
        return np.abs(clearance + radius - rc), "following error |d - rc| (m, log)"
    return clearance, "clearance (m, log)"


def overlay_figure(runs: Sequence[tuple[Trace, Any]]) -> "Figure":
    """Return one figure of several runs, each a (trace, world or None) pair."""
    import numpy as np
    from matplotlib.figure import Figure

    from mdle.sweep.metrics import path_length

    if not runs:
        raise PlotError(Diagnostic(None, "no traces to plot"))
    for trace, _ in runs:
        if not trace.samples:
            raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no samples to plot"))
    world = next((w for _, w in runs if w is not None), None)
    errors = [following_error(t, robot_radius(t, w)) for t, w in runs]
    fig = Figure(figsize=(9.5, 8.5 if any(errors) else 6.0), layout="constrained")
    if any(errors):
        ax, axe = fig.subplots(2, 1, height_ratios=[3, 1.6])
    else:
        ax, axe = fig.subplots(1, 1), None
    if world is not None:
        draw_world(ax, world)
    names: list[str] = []
    for i, ((trace, w), err) in enumerate(zip(runs, errors, strict=True)):
        colour = f"C{i % 10}"
        x, y, _, _ = run_pose(trace, w if w is not None else world)
        ok = np.isfinite(x) & np.isfinite(y)
        name = os.path.basename(trace.path)
        names.append(name)
        ax.plot(x[ok], y[ok], lw=1.8, color=colour, label=name, zorder=3)
        if ok.any():
            first, last = np.flatnonzero(ok)[[0, -1]]
            ax.plot([x[first]], [y[first]], ">", color=colour, ms=9, zorder=4)
            ax.plot([x[last]], [y[last]], "s", mfc="none", mec=colour, ms=9, mew=1.5, zorder=4)
        if axe is not None and err is not None:
            values, label = err
            dist = path_length(trace.column("x"), trace.column("y"))
            axe.plot(dist, values, lw=1.0, color=colour, label=name)
            axe.set_ylabel(label)
    ax.plot([], [], ">", color="0.2", label="start")
    ax.plot([], [], "s", mfc="none", mec="0.2", label="end")
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              fontsize="small")
    ax.set_title(f"{len(runs)} runs" + (f" in world {world.name}" if world is not None and
                                        getattr(world, "name", None) else ""),
                 fontsize="medium")
    if axe is not None:
        axe.set_xlabel("distance travelled (m)")
        axe.grid(True, lw=0.3, alpha=0.5)
        # the approach's metres and the following's centimetres both readable
        axe.set_yscale("log")
        lo, hi = axe.get_ylim()
        axe.set_ylim(max(lo, 1e-3), hi)
    return fig
