"""The true curvature of the boundary at a point's nearest boundary point (for plots).

The whole-scan model of ``follow_boundary`` reads the curvature of the nearest boundary point;
a plot draws it against this truth. On a face the curvature is the face's (0 on a polygon's
straight faces, the sampled curve's on a curve's facets, ``-1/R`` on a convex arc, an
ellipse's own); where the nearest point is a **corner** (a polygon vertex, an arc's or a
wall's end, seen from inside the corner's normal cone) the boundary has no curvature there:
it turns around a point, and the answer is ``-inf`` (convex negative, as everywhere in mdle).

>>> import numpy as np
>>> from mdle.sim.shapes import Rectangle, Parts
>>> parts = Parts.concat([Rectangle((0.0, 0.0), (2.0, 2.0)).parts()])
>>> d, k = nearest_curvature(parts, np.array([[0.0, 1.5], [1.5, 1.5]]))
>>> d.round(3).tolist(), k.tolist()
([0.5, 0.707], [0.0, -inf])
"""

from __future__ import annotations

import math

import numpy as np

from mdle.sim.distance import ellipse_nearest
from mdle.sim.shapes import Parts

__all__ = ["nearest_curvature", "CORNER_SIN"]

#: The nearest point is a corner when the line to it leaves the face's normal by more than
#: this (sine of the angle): on a face's interior the line is normal to rounding error.
CORNER_SIN = 1e-6


def nearest_curvature(parts: Parts, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the distance to the nearest boundary point of each point, and its curvature.

    Parameters
    ----------
    parts : Parts
        The world's primitives (``World.parts``).
    xy : (N, 2) float array, metres
        Points outside the obstacles (a robot's true positions).

    Returns
    -------
    dist : (N,) float array, metres (``inf`` with no obstacles)
    kappa : (N,) float array, 1/m
        Convex negative; ``-inf`` where the nearest point is a corner (from outside the
        obstacles only a convex corner can be nearest: next to a concave one a face is
        nearer); NaN with no obstacles. A segment of a sampled curve (nonzero
        ``seg_kappa``) carries its curvature up to its ends: its joints turn by at most
        30 deg and are no corners.
    """
    q = np.asarray(xy, dtype=float).reshape(-1, 2)
    n = q.shape[0]
    best = np.full(n, math.inf)
    kappa = np.full(n, math.nan)
    rows = np.arange(n)

    def take(d: np.ndarray, k: np.ndarray) -> None:
        j = np.argmin(d, axis=1)
        dj, kj = d[rows, j], k[rows, j]
        better = dj < best
        best[better] = dj[better]
        kappa[better] = kj[better]

    qx, qy = q[:, 0:1], q[:, 1:2]
    if parts.n_segments:
        s0, s1 = parts.seg_start, parts.seg_end
        ex, ey = s1[:, 0] - s0[:, 0], s1[:, 1] - s0[:, 1]
        ll = ex * ex + ey * ey
        u = np.clip(((qx - s0[:, 0]) * ex + (qy - s0[:, 1]) * ey) / np.where(ll > 0, ll, 1.0),
                    0.0, 1.0)
        wx, wy = qx - (s0[:, 0] + u * ex), qy - (s0[:, 1] + u * ey)
        d = np.hypot(wx, wy)
        # the line to the point against the face's direction: 0 on the face's interior
        along = np.abs(wx * ex + wy * ey) / np.maximum(d * np.sqrt(ll), 1e-300)
        corner = (along > CORNER_SIN) & (parts.seg_kappa == 0.0)
        take(d, np.where(corner, -math.inf, parts.seg_kappa))
    if len(parts.arc_radius):
        c, r = parts.arc_center, parts.arc_radius
        wx, wy = qx - c[:, 0], qy - c[:, 1]
        a = np.arctan2(wy, wx)
        inside = np.mod(a - parts.arc_start, 2.0 * math.pi) <= parts.arc_sweep
        a0, a1 = parts.arc_start, parts.arc_start + parts.arc_sweep
        d0 = np.hypot(qx - (c[:, 0] + r * np.cos(a0)), qy - (c[:, 1] + r * np.sin(a0)))
        d1 = np.hypot(qx - (c[:, 0] + r * np.cos(a1)), qy - (c[:, 1] + r * np.sin(a1)))
        d = np.where(inside, np.abs(np.hypot(wx, wy) - r), np.minimum(d0, d1))
        # beyond the span the nearest point is an end; whatever continues the arc there is
        # a primitive of its own and nearer if it is tangent, so an end that wins is a corner
        take(d, np.where(inside, parts.arc_side / r, -math.inf))
    if len(parts.ell_angle):
        c, axes, ang = parts.ell_center, parts.ell_axes, parts.ell_angle
        cu, su = np.cos(ang), np.sin(ang)
        wx, wy = qx - c[:, 0], qy - c[:, 1]
        lx, ly = wx * cu + wy * su, -wx * su + wy * cu
        ea, eb = axes[:, 0], axes[:, 1]
        px, py = ellipse_nearest(ea, eb, lx, ly)
        d = np.hypot(lx - px, ly - py)
        # the curvature of (x/a)^2 + (y/b)^2 = 1 at (x, y): 1 / (a^2 b^2 (x^2/a^4 + y^2/b^4)^1.5)
        k = 1.0 / (ea * ea * eb * eb * ((px / ea**2) ** 2 + (py / eb**2) ** 2) ** 1.5)
        take(d, -k)
    return best, kappa
