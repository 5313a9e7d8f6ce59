"""Exact distance from points to boundary primitives, and the nearest boundary point.

Segments and circular arcs in closed form; ellipses by Eberly's monotone Newton
iteration on the distance equation (converges from below, so a fixed number of steps
gives a bound that only tightens). Vectorised over query points and primitives.

>>> import numpy as np
>>> from sim.shapes import Circle, Rectangle, Parts
>>> shapes = [Circle((0.0, 0.0), 1.0), Rectangle((5.0, 0.0), (2.0, 2.0))]
>>> parts = Parts.concat([s.parts() for s in shapes])
>>> d, p, owner = nearest_boundary(parts, np.array([[2.5, 0.0]]))
>>> d.tolist(), p.tolist(), owner.tolist()
([1.5], [[4.0, 0.0]], [1])
"""

from __future__ import annotations

import math

import numpy as np

from sim.shapes import Parts

__all__ = ["ellipse_nearest", "nearest_boundary"]

_TAU = 2.0 * math.pi
_NEWTON_STEPS = 60  # an upper bound; outside points converge in a handful


def ellipse_nearest(a: np.ndarray, b: np.ndarray, y0: np.ndarray, y1: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Nearest point on the axis-aligned ellipse ``(x/a)^2 + (y/b)^2 = 1`` to ``(y0, y1)``.

    Works for points inside and outside. Arrays broadcast together; returns ``(x, y)``.

    References
    ----------
    D. Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a Hyperellipsoid"
    (Geometric Tools, 2013): the root of F(t) = (a y0/(t+a^2))^2 + (b y1/(t+b^2))^2 - 1.
    """
    a, b, y0, y1 = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float),
                                       np.asarray(y0, float), np.asarray(y1, float))
    swap = a < b                     # work with the major axis first
    A = np.where(swap, b, a)
    Bx = np.where(swap, a, b)
    z0 = np.abs(np.where(swap, y1, y0))
    z1 = np.abs(np.where(swap, y0, y1))
    a2, b2 = A * A, Bx * Bx
    # On the minor axis (z0 = 0, inside) the nearest point may be the axis end; the
    # Newton form handles z1 > 0; degenerate z1 = 0 needs the closed form below.
    t = np.maximum(A * z0 - a2, Bx * z1 - b2)       # lower bound of the root
    for _ in range(_NEWTON_STEPS):                  # stops early once converged
        with np.errstate(divide="ignore", invalid="ignore"):
            p = A * z0 / (t + a2)
            q = Bx * z1 / (t + b2)
            f = p * p + q * q - 1.0
            df = -2.0 * (p * p / (t + a2) + q * q / (t + b2))
            step = np.where(df < 0, f / df, 0.0)
        step = np.nan_to_num(step)
        t = t - step
        if bool(np.all(np.abs(step) <= 1e-14 * (np.abs(t) + a2))):
            break
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a2 * z0 / (t + a2)
        y = b2 * z1 / (t + b2)
    # z1 == 0: on the major axis. Inside and near the centre the nearest point is off-axis.
    on_axis = z1 == 0
    if on_axis.any():
        lim = (a2 - b2) / A
        inner = on_axis & (z0 < lim)
        xi = a2 * z0 / np.where(inner, a2 - b2, 1.0)
        yi = Bx * np.sqrt(np.clip(1.0 - (xi / A) ** 2, 0.0, None))
        x = np.where(on_axis, np.where(inner, xi, A), x)
        y = np.where(on_axis, np.where(inner, yi, 0.0), y)
    x = np.where(np.where(swap, y1, y0) < 0, -x, x)
    y = np.where(np.where(swap, y0, y1) < 0, -y, y)
    return np.where(swap, y, x), np.where(swap, x, y)


def nearest_boundary(parts: Parts, xy: np.ndarray, bound: float = math.inf
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distance from each point to the nearest boundary, that point, and its obstacle.

    Parameters
    ----------
    parts : Parts
        The world's primitives.
    xy : (N, 2) float array, metres
    bound : float, metres
        Primitives whose cheap lower bound exceeds this are skipped (the answer is then
        ``inf`` if nothing is closer); ``inf`` computes everything.

    Returns
    -------
    dist : (N,) float array, metres (``inf`` with no obstacles)
    point : (N, 2) float array, metres (NaN with no obstacles)
    owner : (N,) int array (index of the obstacle; -1 with none)
    """
    q = np.asarray(xy, dtype=float).reshape(-1, 2)
    n = q.shape[0]
    best = np.full(n, math.inf)
    point = np.full((n, 2), math.nan)
    owner = np.full(n, -1, dtype=np.intp)
    rows = np.arange(n)

    def take(d: np.ndarray, px: np.ndarray, py: np.ndarray, own: np.ndarray) -> None:
        j = np.argmin(d, axis=1)
        dj = d[rows, j]
        better = dj < best
        best[better] = dj[better]
        point[better, 0] = px[rows, j][better]
        point[better, 1] = py[rows, j][better]
        owner[better] = own[j][better]

    if parts.n_segments:
        s0, s1 = parts.seg_start, parts.seg_end
        ex, ey = (s1 - s0)[:, 0], (s1 - s0)[:, 1]
        wx = q[:, 0:1] - s0[:, 0]
        wy = q[:, 1:2] - s0[:, 1]
        ll = ex * ex + ey * ey
        u = np.clip((wx * ex + wy * ey) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
        px = s0[:, 0] + u * ex
        py = s0[:, 1] + u * ey
        take(np.hypot(q[:, 0:1] - px, q[:, 1:2] - py), px, py, parts.seg_owner)
    if len(parts.arc_radius):
        c, r = parts.arc_center, parts.arc_radius
        wx = q[:, 0:1] - c[:, 0]
        wy = q[:, 1:2] - c[:, 1]
        a = np.arctan2(wy, wx)
        rel = np.mod(a - parts.arc_start, _TAU)
        inside = rel <= parts.arc_sweep
        # Outside the angular span the nearest arc point is an end point.
        a0, a1 = parts.arc_start, parts.arc_start + parts.arc_sweep
        e0x, e0y = c[:, 0] + r * np.cos(a0), c[:, 1] + r * np.sin(a0)
        e1x, e1y = c[:, 0] + r * np.cos(a1), c[:, 1] + r * np.sin(a1)
        d0 = np.hypot(q[:, 0:1] - e0x, q[:, 1:2] - e0y)
        d1 = np.hypot(q[:, 0:1] - e1x, q[:, 1:2] - e1y)
        pa_x, pa_y = c[:, 0] + r * np.cos(a), c[:, 1] + r * np.sin(a)
        dr = np.abs(np.hypot(wx, wy) - r)
        use0 = d0 <= d1
        d = np.where(inside, dr, np.where(use0, d0, d1))
        px = np.where(inside, pa_x, np.where(use0, e0x, e1x))
        py = np.where(inside, pa_y, np.where(use0, e0y, e1y))
        take(d, px, py, parts.arc_owner)
    if len(parts.ell_angle):
        c, ax, ang = parts.ell_center, parts.ell_axes, parts.ell_angle
        cu, su = np.cos(ang), np.sin(ang)
        wx = q[:, 0:1] - c[:, 0]
        wy = q[:, 1:2] - c[:, 1]
        lb = np.hypot(wx, wy) - ax.max(axis=1)
        if bool((lb <= np.minimum(best, bound)[:, None]).any()):
            lx = wx * cu + wy * su
            ly = -wx * su + wy * cu
            ex, ey = ellipse_nearest(ax[:, 0], ax[:, 1], lx, ly)
            px = c[:, 0] + ex * cu - ey * su
            py = c[:, 1] + ex * su + ey * cu
            take(np.hypot(q[:, 0:1] - px, q[:, 1:2] - py), px, py, parts.ell_owner)
    return best, point, owner
