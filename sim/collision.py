"""Collision handling: exact clearance of the robot's disc and swept motion without tunnelling.

The body is a disc of the profile's radius centred on the rotation centre, so turning
in place never collides. Motion along a phase is advanced *conservatively*: the disc
can travel the current clearance before it can touch anything (the centre moves at
most ``|v| dt``, a chord is never longer than its arc), so the robot advances by that
much and measures again. A step the clearance covers whole is taken at once (the
common case: one distance query per tick). Approaching a wall the steps shrink
geometrically; at ``CONTACT`` metres the robot stops, unless the motion leads away
from the obstacle. No speed can carry the robot through a wall, however thin.

The distance query is exact and cheap: per-world constants in complex form (about ten
numpy calls for all segments), nearest points on ellipses in plain floats, in large
worlds a list of the segments that can be nearest within 0.5 m of where it was made, and
above 256 arcs or ellipses a grid of their boxes (:class:`sim.faceindex.BoxGrid`) that
gives those near the query.

>>> from mdle.sim.shapes import Rectangle, Parts
>>> from mdle.sim.robot import Phase
>>> thin = Parts.concat([Rectangle((5.0, 0.0), (0.01, 4.0)).parts()])
>>> c = Collider(thin, radius=0.25)
>>> r = c.sweep(0.0, 0.0, 0.0, Phase(1.0, 100.0, 0.0, 0.0, 0.0))  # 100 m/s for 1 s
>>> r.contact, round(r.x, 3), r.tau < 0.05
(True, 4.745, True)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from mdle.sim import raycast
from mdle.sim.distance import ellipse_nearest, ellipse_nearest_point, nearest_boundary
from mdle.sim.faceindex import BoxGrid
from mdle.sim.robot import Phase, integrate
from mdle.sim.shapes import Parts

__all__ = ["CONTACT", "Clearance", "Collider", "SweepResult"]

#: Clearance (m) at which the body counts as touching an obstacle.
CONTACT = 1e-4
_MARGIN = CONTACT / 2  # advancing stops this far short of touching
_MAX_STEPS = 2000
_TAU = 2.0 * math.pi
_FEW_ELLIPSES = 8  # up to this many near ellipses, one at a time in plain floats
_CULL_ABOVE = 256  # segments: larger worlds keep a list of the candidates near the robot
_NEAR_SLACK = 0.5  # m: the list stays valid while the robot is this close to where it was made
# 0 and 1 as 0-d arrays: a ufunc takes them far faster than Python floats
_ZERO, _ONE = np.array(0.0), np.array(1.0)


def _compiled_ellipse_near() -> Callable[..., list[tuple[float, float, float, float, int]]] | None:
    """Return the few-ellipses query in C (sim/_kernels.c, ``ellipse_near``), or None.

    Only where the fan's compiled ellipses are (:data:`sim.raycast.COMPILED_ELLIPSES`):
    the same probes of how numpy rounds its complex products and absolute values.
    """
    if not raycast.COMPILED_ELLIPSES:
        return None
    try:
        from mdle.sim._kernels import ellipse_near
    except ImportError:
        return None
    return ellipse_near


_ELLIPSE_NEAR = _compiled_ellipse_near()


def _reach(distance: float) -> float:
    """Return the half-side of a grid search holding everything within ``distance``.

    Widened well beyond rounding, so that it holds every curve whose distance, as the
    query computes it, is below ``distance``.
    """
    return distance * (1.0 + 1e-9) + 1e-9


class Clearance(NamedTuple):
    """How far the body is from the nearest obstacle (m), and which obstacle that is."""

    distance: float
    obstacle: int


@dataclass(frozen=True)
class SweepResult:
    """Where a swept motion ended.

    ``tau`` seconds of the phase were travelled (all of it unless ``contact``); the
    pose reached; ``clearance`` there (m, body to nearest obstacle) and the index of the
    nearest obstacle (-1 if none).
    """

    tau: float
    x: float
    y: float
    theta: float
    contact: bool
    clearance: float
    obstacle: int


class Collider:
    """Clearance queries and swept motion for a disc robot in a static world.

    Parameters
    ----------
    parts : Parts
        The world's primitives.
    radius : float, metres
        The body's radius (0 for a point robot).
    curve_grids : bool
        Where there are more than 256 arcs (or ellipses), find those near a query in a
        grid of their boxes: the same numbers (False: measure to every one).
    compiled : bool, optional
        In a world of at most 8 ellipses, find the ones to measure and their nearest
        points in one compiled call where the install has it (None, the default, or
        True) or in numpy and Python floats (False): the same numbers.
    """

    def __init__(self, parts: Parts, radius: float, curve_grids: bool = True,
                 compiled: bool | None = None) -> None:
        self.parts = parts
        self.radius = float(radius)
        self.curve_grids = curve_grids
        # Per-world constants in complex form (a point is x + iy): a query then costs
        # about a dozen numpy calls whatever the number of primitives.
        s0, s1 = parts.seg_start, parts.seg_end
        self._s0 = s0[:, 0] + 1j * s0[:, 1]
        self._e = (s1[:, 0] + 1j * s1[:, 1]) - self._s0
        ll = (self._e * self._e.conjugate()).real
        # Re(w * conj(e) / |e|^2) is the projection of w on e, in units of the segment.
        self._proj = np.divide(self._e.conjugate(), ll, out=np.zeros_like(self._e),
                               where=ll > 0)
        self._bufs = self._buffers(len(ll))
        # Large worlds: the segments that can be nearest anywhere within _NEAR_SLACK of
        # _near_at (indices, then their s0, e, proj and buffers); made on demand.
        self._near_at: complex | None = None
        self._near: tuple = ()
        c, r = parts.arc_center, parts.arc_radius
        self._arc_c = c[:, 0] + 1j * c[:, 1]
        a0, a1 = parts.arc_start, parts.arc_start + parts.arc_sweep
        self._arc_e0 = self._arc_c + r * np.exp(1j * a0)
        self._arc_e1 = self._arc_c + r * np.exp(1j * a1)
        # The axis-aligned frame of each ellipse: l = conj(u) (q - c).
        self._ell_c = parts.ell_center[:, 0] + 1j * parts.ell_center[:, 1]
        self._ell_uconj = np.exp(-1j * parts.ell_angle)
        self._ell_bound = (parts.ell_axes.max(axis=1) if len(parts.ell_angle)
                           else np.zeros(0))
        self._ell_axes = parts.ell_axes.tolist()
        self._ell_owner = parts.ell_owner.tolist()
        self._ell_axes_c = np.ascontiguousarray(parts.ell_axes, dtype=float)
        few = 0 < len(self._ell_owner) <= _FEW_ELLIPSES      # never the grid, never vectorised
        self._ell_near = _ELLIPSE_NEAR if few and compiled is not False else None

    def distance(self, x: float, y: float) -> tuple[float, int]:
        """Return the distance from the point to the nearest boundary, and that obstacle's index."""
        best, owner = math.inf, -1
        P = self.parts
        q = complex(x, y)
        if self._s0.shape[0]:
            if self._s0.shape[0] <= _CULL_ABOVE:
                d = self._segments(q, self._s0, self._e, self._proj, self._bufs)
                j = int(d.argmin())
                best = float(d[j])
            elif self._near_at is not None and abs(q - self._near_at) <= _NEAR_SLACK:
                keep, s0, e, proj, bufs = self._near
                d = self._segments(q, s0, e, proj, bufs)
                i = int(d.argmin())
                best, j = float(d[i]), int(keep[i])
            else:
                j, best = self._remake_near(q)
            owner = int(P.seg_owner[j])
        if len(P.arc_radius):
            idx, d = self._arcs_in_reach(q, best)
            if d.shape[0]:
                j = int(d.argmin())
                if d[j] < best:
                    best, owner = float(d[j]), int(P.arc_owner[j if idx is None else idx[j]])
        if self._ell_near is not None:
            # A few ellipses: which to measure and their nearest points in one C call
            # (the branch below, the same numbers); the distances with Python's hypot.
            for lx, ly, ex, ey, i in self._ell_near(
                    x, y, best, self._ell_c, self._ell_uconj, self._ell_bound,
                    self._ell_axes_c, bool(raycast._FUSED), bool(raycast._ABS_FUSED)):
                de = math.hypot(lx - ex, ly - ey)
                if de < best:
                    best, owner = de, self._ell_owner[i]
        elif len(P.ell_angle):
            # Many ellipses, and a nearest obstacle already: only those of the cells
            # within its distance (a superset of the ones that can be nearer).
            grid = self._ellipse_grid if math.isfinite(best) else None
            cand = None if grid is None else grid.near(q.real, q.imag, _reach(best))
            w = q - (self._ell_c if cand is None else self._ell_c[cand])
            lower = np.abs(w)
            lower -= self._ell_bound if cand is None else self._ell_bound[cand]
            keep = np.flatnonzero(lower < best)
            near = keep if cand is None else cand[keep]
            if near.size > _FEW_ELLIPSES:
                de, i = self._ellipses_vectorised(w[keep], near)
                if de < best:
                    best, owner = de, i
            elif near.size:
                local = (w[keep] * self._ell_uconj[near]).tolist()   # the query in each frame
                for lq, i in zip(local, near.tolist(), strict=True):  # few: plain floats
                    a, b = self._ell_axes[i]
                    ex, ey = ellipse_nearest_point(a, b, lq.real, lq.imag)
                    de = math.hypot(lq.real - ex, lq.imag - ey)
                    if de < best:
                        best, owner = de, self._ell_owner[i]
        return best, owner

    @cached_property
    def _arc_grid(self) -> BoxGrid | None:
        """The arcs' boxes by cell, above _CULL_ABOVE arcs (built on first use)."""
        P = self.parts
        if not self.curve_grids or P.arc_radius.shape[0] <= _CULL_ABOVE:
            return None
        return BoxGrid.of_arcs(P)

    @cached_property
    def _ellipse_grid(self) -> BoxGrid | None:
        """The ellipses' bounding circles' boxes by cell, above _CULL_ABOVE ellipses."""
        P = self.parts
        if not self.curve_grids or P.ell_angle.shape[0] <= _CULL_ABOVE:
            return None
        return BoxGrid.of_ellipses(P)

    def _arcs_in_reach(self, q: complex, best: float) -> tuple[np.ndarray | None, np.ndarray]:
        """Return arcs (None: all) and their distances from ``q``: all that are below ``best``.

        Many arcs: those of the cells within ``best`` of ``q``. With no bound yet (no
        segments), the square searched doubles from one cell until it holds an arc as
        near as its half-side: no arc outside it can be nearer.
        """
        grid = self._arc_grid
        if grid is None:
            return None, self._arc_distances(q, None)
        reach = best if math.isfinite(best) else grid.cell
        while True:
            idx = grid.near(q.real, q.imag, _reach(reach))
            d = self._arc_distances(q, idx)
            if (math.isfinite(best) or idx.shape[0] == grid.size
                    or (d.shape[0] and float(d.min()) <= reach)):
                return idx, d
            reach *= 2.0

    def _arc_distances(self, q: complex, idx: np.ndarray | None) -> np.ndarray:
        """Return the distances from ``q`` to arcs ``idx`` (None: all), element by element."""
        P = self.parts
        if idx is None:
            c, e0, e1 = self._arc_c, self._arc_e0, self._arc_e1
            start, radius, sweep = P.arc_start, P.arc_radius, P.arc_sweep
        else:
            c, e0, e1 = self._arc_c[idx], self._arc_e0[idx], self._arc_e1[idx]
            start, radius, sweep = P.arc_start[idx], P.arc_radius[idx], P.arc_sweep[idx]
        w = q - c
        within = np.arctan2(w.imag, w.real)
        within -= start
        np.mod(within, _TAU, out=within)
        radial = np.abs(w)
        radial -= radius
        np.abs(radial, out=radial)
        ends = np.minimum(np.abs(q - e0), np.abs(q - e1))
        return np.where(within <= sweep, radial, ends)

    @staticmethod
    def _buffers(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return np.empty(n, dtype=complex), np.empty(n, dtype=complex), np.empty(n)

    @staticmethod
    def _segments(q: complex, s0: np.ndarray, e: np.ndarray, proj: np.ndarray,
                  bufs: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
        """Measure from ``q`` to the segments ``s0 + [0, 1] e`` (written into a buffer)."""
        w, r, u = bufs
        np.subtract(q, s0, out=w)
        ur = np.multiply(w, proj, out=r).real          # position of q along each segment
        np.maximum(ur, _ZERO, out=u)
        np.minimum(u, _ONE, out=u)
        np.multiply(e, u, out=r)
        np.subtract(w, r, out=r)                       # w less its nearest segment point
        return np.abs(r, out=u)

    def _remake_near(self, q: complex) -> tuple[int, float]:
        """Measure all segments from ``q`` and keep those that can be nearest near it.

        Within _NEAR_SLACK of ``q`` a segment farther than the nearest by twice the slack
        never is (a distance changes no faster than the point moves). Returns (index of
        the nearest segment, its distance).
        """
        d = self._segments(q, self._s0, self._e, self._proj, self._bufs)
        j = int(d.argmin())
        best = float(d[j])
        keep = np.flatnonzero(d <= best + 2.0 * _NEAR_SLACK)
        self._near = (keep, self._s0[keep], self._e[keep], self._proj[keep],
                      self._buffers(keep.shape[0]))
        self._near_at = q
        return j, best

    def _ellipses_vectorised(self, w: np.ndarray, near: np.ndarray) -> tuple[float, int]:
        """Return (distance, owner) of the nearest of ellipses ``near``; ``w`` = q - theirs."""
        local = w * self._ell_uconj[near]
        axes = self.parts.ell_axes[near]
        ex, ey = ellipse_nearest(axes[:, 0], axes[:, 1], local.real, local.imag)
        d = np.abs(local - (ex + 1j * ey))
        j = int(d.argmin())
        return float(d[j]), int(self.parts.ell_owner[near[j]])

    def clearance(self, x: float, y: float) -> Clearance:
        """Return the distance from the body (disc) to the nearest obstacle, and that obstacle."""
        d, owner = self.distance(x, y)
        return Clearance(d - self.radius, owner)

    def sweep(self, x: float, y: float, th: float, phase: Phase,
              start_clearance: Clearance | None = None) -> SweepResult:
        """Move along ``phase`` from ``(x, y, th)`` until its end or first contact.

        ``start_clearance`` (clearance, obstacle) at the start, if already known, saves
        a query.
        """
        c, owner = start_clearance if start_clearance is not None else self.clearance(x, y)
        vmax = phase.max_abs_v
        total = phase.duration
        if vmax == 0.0 or c - _MARGIN >= vmax * total:
            x1, y1, th1 = integrate(x, y, th, phase, total)
            if vmax == 0.0 and start_clearance is not None:
                return SweepResult(total, x1, y1, th1, False, c, owner)
            c1, o1 = self.clearance(x1, y1)
            return SweepResult(total, x1, y1, th1, False, c1, o1)
        tau = 0.0
        cx, cy = x, y
        for _ in range(_MAX_STEPS):
            if c <= CONTACT:
                # Touching: go on only if the motion leads away from the obstacle, by half
                # the clearance at a time (never closer to anything else).
                probe = min(total, tau + 0.5 * c / vmax)
                px, py, _ = integrate(x, y, th, phase, probe)
                nx, ny = self._outward(cx, cy)
                if (px - cx) * nx + (py - cy) * ny <= 0.0:
                    _, _, cth = integrate(x, y, th, phase, tau)
                    return SweepResult(tau, cx, cy, cth, True, c, owner)
                tau, cx, cy = probe, px, py
                c, owner = self.clearance(cx, cy)
                if tau >= total:
                    break
                continue
            # Advance by the clearance less a margin, so the body never quite touches.
            step = (c - _MARGIN) / vmax
            if tau + step >= total:
                tau = total
                cx, cy, _ = integrate(x, y, th, phase, tau)
                c, owner = self.clearance(cx, cy)
                break
            tau += step
            cx, cy, _ = integrate(x, y, th, phase, tau)
            c, owner = self.clearance(cx, cy)
        else:
            # Grazing for too long: treat as contact rather than risk a pass-through.
            _, _, cth = integrate(x, y, th, phase, tau)
            return SweepResult(tau, cx, cy, cth, True, c, owner)
        _, _, th1 = integrate(x, y, th, phase, tau)
        return SweepResult(tau, cx, cy, th1, False, c, owner)

    def _outward(self, x: float, y: float) -> tuple[float, float]:
        """Return the unit vector from the nearest boundary point to ``(x, y)``."""
        _, p, _ = nearest_boundary(self.parts, np.array([[x, y]]))
        dx, dy = x - float(p[0, 0]), y - float(p[0, 1])
        n = math.hypot(dx, dy)
        return (dx / n, dy / n) if n > 0 else (0.0, 0.0)
