"""The curvature panel of a run on the whole-scan model: the nearest point's curvature.

With ``model = scan`` (the default) ``follow_boundary`` records in its ``side_*`` fields the
boundary point it followed: the nearest one of the scan on the followed side, its range,
tangent and **curvature** from a circle fitted to the scan points around it. Where those
points are no circle (a vertex, a tip, a cusp) the model takes the nearest point as a point
and records the curvature of a 1 cm circle, ``-100 1/m`` (``atoms.closest.POINT_KAPPA``).

This panel draws that curvature against the distance travelled, beside the truth: the
curvature of the world's boundary at the robot's true nearest point
(:func:`mdle.sim.nearest_truth.nearest_curvature`), which at a corner is no number at all
(the boundary turns round a point). The axis holds the values of faces (robust limits, as
:mod:`mdle.view.plot_curvature`); the ticks where the model took a point are marked at its
bottom edge (above any other value beyond the axis, marked at the edge it left by), and the
ticks where the true nearest point is a corner as a rug above those. Convex negative whichever side
is followed.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from mdle.atoms.closest import POINT_KAPPA
from mdle.record.trace import Trace
from mdle.view.plot_curvature import Curvature, finish_panel, robust_limits

if TYPE_CHECKING:
    import numpy as np
    from matplotlib.axes import Axes

__all__ = ["is_nearest_point_trace", "followed_side", "nearest_measured", "nearest_truth",
           "draw_nearest_curvature", "NearestPanel"]

#: The two-ray law's side ray looks at exactly -90 or +90 deg; a nearest point lies anywhere.
_RAY_BEARING_TOL = 1e-6  # the trace keeps 9 significant digits


def is_nearest_point_trace(trace: Trace) -> bool:
    """Tell whether ``trace``'s side fields describe the nearest point (``model = scan``).

    The two-ray law records the side ray's fixed bearing (+-90 deg) in ``side_bearing``; the
    whole-scan model records where the point it followed lay, which moves.
    """
    import numpy as np

    if "side_bearing" not in trace.diag_names():
        return False
    bearing = trace.column("diag.side_bearing")
    hit = trace.column("diag.side_hit") > 0.5
    b = bearing[hit & np.isfinite(bearing)]
    return bool(len(b)) and bool((np.abs(np.abs(b) - math.pi / 2) > _RAY_BEARING_TOL).any())


def followed_side(trace: Trace) -> "np.ndarray":
    """Per sample: -1 where the running atom follows on the right, +1 on the left.

    The side an atom follows is where most of its nearest points lay (a point on the other
    side is followed only until the law has turned it to the followed one); each atom of the
    trace (by its path) is judged on its own samples.
    """
    import numpy as np

    bearing = trace.column("diag.side_bearing")
    hit = (trace.column("diag.side_hit") > 0.5) & np.isfinite(bearing)
    paths = np.array(trace.paths(), dtype=object)
    out = np.full(len(bearing), -1.0)
    for path in dict.fromkeys(paths.tolist()):
        mine = paths == path
        b = bearing[mine & hit]
        if len(b) and float(np.median(b)) > 0.0:
            out[mine] = 1.0
    return out


def nearest_measured(trace: Trace) -> Curvature | None:
    """Return the nearest point's curvature the model used, convex negative; NaN: none seen."""
    import numpy as np

    if "side_curvature" not in trace.diag_names():
        return None
    k = trace.column("diag.side_curvature")
    k = np.where(trace.column("diag.side_hit") > 0.5, k, np.nan)
    if not np.isfinite(k).any():
        return None
    return Curvature("side_curvature", np.where(followed_side(trace) > 0, -k, k))


def nearest_truth(trace: Trace, world: Any) -> "np.ndarray | None":
    """Return the boundary's curvature at the robot's true nearest point (``-inf``: a corner).

    NaN where the sample has no true pose; None without a world or a true pose.
    """
    import numpy as np

    from mdle.sim.nearest_truth import nearest_curvature

    parts = getattr(world, "parts", None)
    if parts is None:
        return None
    tx, ty = trace.column("true_x"), trace.column("true_y")
    ok = np.isfinite(tx) & np.isfinite(ty)
    if not ok.any():
        return None
    out = np.full(len(tx), np.nan)
    out[ok] = nearest_curvature(parts, np.column_stack([tx[ok], ty[ok]]))[1]
    return out


class NearestPanel:
    """What the panel shows, counted: the figures' numbers come from the same masks.

    Parameters
    ----------
    measured : (N,) float array
        The model's curvature, convex negative (NaN where it followed nothing).
    truth : (N,) float array or None
        The true curvature at the nearest point (``-inf`` at a corner).
    exact : bool
        The scan was exact: the axis holds the truth (padded), and every value of the model
        off it is marked, so a polygon's exact run has an axis of +-0.1 1/m. From a noisy
        scan the axis holds all but the outer 1 % of the model's face values as well.
    """

    def __init__(self, measured: "np.ndarray", truth: "np.ndarray | None",
                 exact: bool = False) -> None:
        import numpy as np

        self.measured = measured
        self.truth = truth
        #: ticks where the model took the nearest point as a point (the clamp)
        self.point = np.isfinite(measured) & (measured == POINT_KAPPA)
        face = np.where(self.point, np.nan, measured)
        #: the model's fitted curvature (NaN at points)
        self.face = face
        finite_truth = None if truth is None else np.where(np.isfinite(truth), truth, np.nan)
        truth_only = exact and finite_truth is not None and bool(np.isfinite(finite_truth).any())
        self.limits = robust_limits(np.full(0, np.nan) if truth_only else face, finite_truth)
        lo, hi = self.limits
        self.over = np.isfinite(face) & (face > hi)
        self.under = np.isfinite(face) & (face < lo)
        #: ticks where the robot's true nearest point is a corner
        self.corner = (np.zeros(len(measured), dtype=bool) if truth is None
                       else np.isneginf(truth) | np.isposinf(truth))

    @staticmethod
    def episodes(mask: "np.ndarray") -> int:
        """Count the runs of consecutive True values (a corner passed, one dip)."""
        import numpy as np

        m = np.asarray(mask, dtype=bool)
        return int(np.count_nonzero(m[1:] & ~m[:-1]) + (1 if len(m) and m[0] else 0))


def draw_nearest_curvature(ax: "Axes", dist: "np.ndarray", measured: Curvature,
                           truth: "np.ndarray | None", exact: bool) -> NearestPanel:
    """Draw the nearest point's curvature (and the truth) against distance; return the panel."""
    import numpy as np

    panel = NearestPanel(measured.values, truth, exact)
    lo, hi = panel.limits
    span = hi - lo
    ax.plot(dist, panel.face, lw=0.9, color="tab:blue",
            label="model (exact scan)" if exact else "model (noisy scan)")
    if truth is not None and np.isfinite(truth).any():
        ok = np.isfinite(truth)
        ax.plot(dist, np.where(ok, truth, np.nan), lw=1.4, color="black", ls="--", alpha=0.8,
                label="truth at the nearest point")
    if panel.point.any():
        ax.plot(dist[panel.point], np.full(int(panel.point.sum()), lo + 0.09 * span), "v",
                ms=4, color="tab:red", ls="none",
                label=f"model: a point, {POINT_KAPPA:g} 1/m ({int(panel.point.sum())} ticks)")
    if panel.corner.any():
        ax.plot(dist[panel.corner], np.full(int(panel.corner.sum()), lo + 0.16 * span), "|",
                ms=7, color="black", ls="none",
                label=f"truth: a corner ({panel.episodes(panel.corner)} passed)")
    beyond = int(panel.over.sum() + panel.under.sum())
    label: str | None = f"beyond the axis ({beyond} values)"
    for mask, edge, marker in ((panel.over, hi - 0.03 * span, "^"),
                               (panel.under, lo + 0.03 * span, "v")):
        if mask.any():
            ax.plot(dist[mask], np.full(int(mask.sum()), edge), marker, ms=4,
                    color="tab:orange", ls="none", label=label)
            label = None
    note = None
    if truth is not None:
        t = truth[np.isfinite(truth)]
        if len(t) and bool(np.all(t == 0.0)):
            note = ("straight faces: true curvature 0; at a corner the boundary turns round a "
                    "point, and so does the model, clamped")
    finish_panel(ax, lo, hi, "boundary curvature at the nearest point (whole-scan model)",
                 note)
    return panel
