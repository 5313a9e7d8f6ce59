"""The curvature panel of a run's plot: measured against true curvature, by distance.

The boundary curvature the law measured, against distance travelled, beside the true
curvature of the boundary it was looking at.

Convention: every curve is drawn **convex negative** whichever side was followed (a trace of
left-side following records its curvature in the left's orientation, convex positive: it is
negated here, and the axis label says so). The axis is clipped to robust limits (a few
percentiles of the data, never less than the truth's range) so that the spikes a noisy
scan gives at corners do not flatten the signal; every clipped value is marked at the edge.
The truth comes from the world: an exact ray from the true ladar position along the side
ray's bearing; a polygon's faces are straight, so their true curvature is exactly 0 and only
the corners, which the exact sensor spreads over its side window, show.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from mdle.record.trace import Trace

if TYPE_CHECKING:
    import numpy as np
    from matplotlib.axes import Axes

__all__ = ["CURVATURE_KEYS", "Curvature", "measured_curvature", "true_curvature",
           "robust_limits", "draw_curvature", "finish_panel", "side_sign", "ladar_mount"]

#: Diagnostic names tried, in order, for the measured boundary curvature (1/m).
CURVATURE_KEYS = ("side_curvature", "curvature", "boundary_curvature")

#: At most this many exact rays are cast for the truth line (evenly spread over the run).
_TRUTH_RAYS = 1500


@dataclass(frozen=True)
class Curvature:
    """A run's measured curvature (1/m, convex negative; NaN where the ray missed)."""

    key: str
    values: "np.ndarray"


def side_sign(trace: Trace) -> "np.ndarray":
    """Per sample: -1 where the followed boundary was on the robot's right, +1 on its left.

    From the ``side_bearing`` diagnostic (rad, robot frame) that ``follow_boundary`` records;
    a trace without it (older ones) is taken as right-side following.
    """
    import numpy as np

    bearing = trace.column("diag.side_bearing")
    return np.where(np.isfinite(bearing) & (bearing > 0.0), 1.0, -1.0)


def ladar_mount(trace: Trace) -> tuple[float, float, float]:
    """Return the ladar's pose on the robot (x, y m; theta rad) from the trace's laser record."""
    for rec in trace.lasers:
        mount = rec.get("mount")
        if isinstance(mount, (list, tuple)) and len(mount) == 3:
            try:
                return float(mount[0]), float(mount[1]), float(mount[2])
            except (TypeError, ValueError):
                break
    return 0.0, 0.0, 0.0


def measured_curvature(trace: Trace) -> Curvature | None:
    """Return the curvature the law measured, convex negative, NaN where its ray saw nothing."""
    import numpy as np

    names = trace.diag_names()
    for key in CURVATURE_KEYS:
        if key not in names:
            continue
        k = trace.column("diag." + key)
        hit_key = key.replace("curvature", "hit")
        if hit_key in names:
            k = np.where(trace.column("diag." + hit_key) > 0.5, k, np.nan)
        if np.isfinite(k).any():
            if key == "side_curvature":  # left-side values are convex positive: flip them
                k = np.where(side_sign(trace) > 0, -k, k)
            return Curvature(key, k)
    return None


def true_curvature(trace: Trace, world: Any) -> "np.ndarray | None":
    """Return the true curvature (1/m, convex negative) where the side ray met the boundary.

    Cast from the true ladar pose along each sample's side bearing; NaN where the ray
    misses or no truth was recorded; None when there is no world or no true pose.
    """
    import numpy as np

    if world is None or not hasattr(world, "cast"):
        return None
    tx, ty, tth = trace.column("true_x"), trace.column("true_y"), trace.column("true_theta")
    ok = np.isfinite(tx) & np.isfinite(ty) & np.isfinite(tth)
    if not ok.any():
        return None
    mx, my, mth = ladar_mount(trace)
    bearing = np.where(side_sign(trace) > 0, math.pi / 2, -math.pi / 2)
    c, s = np.cos(tth), np.sin(tth)
    ox, oy = tx + c * mx - s * my, ty + s * mx + c * my
    ang = tth + mth + bearing
    out = np.full(len(tx), np.nan)
    idx = np.flatnonzero(ok)
    if len(idx) > _TRUTH_RAYS:
        idx = idx[np.linspace(0, len(idx) - 1, _TRUTH_RAYS).astype(int)]
    max_range = float(trace.lasers[0].get("range_max") or math.inf) if trace.lasers else math.inf
    # one origin per ray: the caster takes a fan from one point, so this loops over rays
    for i in idx:
        hit = world.cast((ox[i], oy[i]), [ang[i]], max_range)
        if hit.hit[0] and hit.curvatures is not None:
            out[i] = float(hit.curvatures[0])
    return out


def robust_limits(values: "np.ndarray", truth: "np.ndarray | None" = None,
                  pct: float = 1.0) -> tuple[float, float]:
    """Axis limits holding all but the outer ``pct`` percent at each end, and all the truth.

    >>> import numpy as np
    >>> lo, hi = robust_limits(np.r_[np.zeros(200), -15.0, 12.0])
    >>> -1.0 < lo < 0.0 < hi < 1.0
    True
    """
    import numpy as np

    v = values[np.isfinite(values)]
    parts = [np.percentile(v, [pct, 100.0 - pct])] if len(v) else []
    if truth is not None and np.isfinite(truth).any():
        t = truth[np.isfinite(truth)]
        parts.append(np.array([t.min(), t.max()]))
    if not parts:
        return -1.0, 1.0
    both = np.concatenate(parts)
    lo, hi = float(both.min()), float(both.max())
    pad = max(0.15 * (hi - lo), 0.1)
    return lo - pad, hi + pad


def draw_curvature(ax: "Axes", dist: "np.ndarray", measured: Curvature,
                   truth: "np.ndarray | None", exact: bool) -> int:
    """Draw the measured (and true) curvature against distance; returns how many were clipped."""
    import numpy as np

    k = measured.values
    lo, hi = robust_limits(k, truth)
    ax.plot(dist, k, lw=0.9, color="tab:blue",
            label="measured by the exact sensor" if exact else "estimated from the scan")
    if truth is not None and np.isfinite(truth).any():
        ok = np.isfinite(truth)
        ax.plot(dist[ok], truth[ok], lw=1.4, color="black", ls="--", alpha=0.8,
                label="true curvature at the side ray")
    over, under = np.isfinite(k) & (k > hi), np.isfinite(k) & (k < lo)
    span = hi - lo
    clipped = int(over.sum() + under.sum())
    label: str | None = f"beyond the axis ({clipped} values)"
    for mask, edge, marker in ((over, hi - 0.03 * span, "^"), (under, lo + 0.03 * span, "v")):
        if mask.any():
            ax.plot(dist[mask], np.full(int(mask.sum()), edge), marker, ms=4,
                    color="tab:red", ls="none", label=label)
            label = None
    if truth is not None and np.isfinite(truth).any() and \
            bool(np.all(truth[np.isfinite(truth)] == 0.0)):
        note = "straight faces: true curvature 0; the " + (
            "exact sensor spreads each corner's turn over its side window" if exact
            else "scan's fit smears each corner over its window")
    else:
        note = None
    finish_panel(ax, lo, hi, "boundary curvature at the side ray", note)
    return clipped


def finish_panel(ax: Axes, lo: float, hi: float, title: str, note: str | None) -> None:
    """Give a curvature panel its limits, zero line, labels, grid, legend and title.

    ``note`` (if any) stands beside the panel, under its legend: never over the curves.
    """
    if note is not None:
        ax.text(1.015, 0.0, textwrap.fill(note, 34), transform=ax.transAxes, va="bottom",
                ha="left", fontsize="small", color="0.25")
    ax.set_ylim(lo, hi)
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel("distance travelled (m)")
    ax.set_ylabel("curvature (1/m)\nconvex negative")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              fontsize="small")
    ax.set_title(title, fontsize="medium")
