"""The other robots of a team as seen by one robot: discs its ladar sees and its body meets.

Each robot's body is a disc (its profile's radius about the rotation centre), so the
others are a handful of circles that move from tick to tick. :class:`Discs` holds where
they are for one robot's step; :func:`cast_discs` intersects a fan of rays with all of
them at once (a (beams, discs) array: no loop over either); :class:`CrowdCollider` adds
them to the static world's clearance, so the swept motion of
:class:`sim.collision.Collider` stops at another robot exactly as at a wall.

>>> import numpy as np
>>> d = Discs(np.array([3.0]), np.array([0.0]), np.array([0.5]), np.array([7]))
>>> t, who = cast_discs(0.0, 0.0, np.array([0.0, 1.5]), d, which=True)
>>> t.tolist(), who.tolist()
([2.5, inf], [0, -1])
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from mdle.sim.collision import Clearance, Collider
from mdle.sim.shapes import Parts

__all__ = ["COMPILED", "Discs", "NO_DISCS", "CrowdCollider", "cast_discs", "occlude",
           "occlusions"]


@dataclass(frozen=True, eq=False)
class Discs:
    """Circles of the robots: centres ``cx``, ``cy`` (m), radii ``r`` (m), owner ids.

    A team keeps one for all its robots, its centres views of the positions it updates in
    place as each robot moves; each robot skips its own disc (``skip``, -1: none).
    """

    cx: np.ndarray
    cy: np.ndarray
    r: np.ndarray
    owner: np.ndarray
    z: np.ndarray | None = None
    """The centres as complex numbers ``x + iy`` (kept by the team beside cx, cy)."""

    def __len__(self) -> int:
        return int(self.cx.shape[0])


NO_DISCS = Discs(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, dtype=np.intp))


def cast_discs(ox: float, oy: float, angles: np.ndarray, discs: Discs, skip: int = -1,
               which: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """Intersect rays from ``(ox, oy)`` at world ``angles`` with the discs (but ``skip``).

    Returns the distance to the nearest disc along each ray (``inf``: none ahead) and,
    with ``which``, that disc's position in ``discs`` (-1: none). A ray starting inside a
    disc does not see it.
    """
    n = angles.shape[0]
    if not len(discs):
        return np.full(n, math.inf), (np.full(n, -1, dtype=np.intp) if which else None)
    w = np.empty((2, len(discs)))
    np.subtract(discs.cx, ox, out=w[0])          # centres relative to the origin
    np.subtract(discs.cy, oy, out=w[1])
    c = np.einsum("ij,ij->j", w, w)
    c -= discs.r * discs.r                       # > 0: the origin is outside the disc
    if skip >= 0:
        c[skip] = -1.0
    u = np.empty((n, 2))
    np.cos(angles, out=u[:, 0])
    np.sin(angles, out=u[:, 1])
    proj = u @ w                                 # (B, M): the centre's projection on each ray
    disc = proj * proj
    disc -= c                                    # discriminant of t^2 - 2 proj t + c = 0
    miss = disc < 0.0
    miss |= proj <= 0.0                          # behind the origin
    miss |= c <= 0.0                             # around the origin
    np.maximum(disc, 0.0, out=disc)
    np.sqrt(disc, out=disc)
    proj -= disc                                 # the nearer root
    proj[miss] = math.inf
    best = proj.min(axis=1)
    if not which:
        return best, None
    j = proj.argmin(axis=1)
    return best, np.where(np.isfinite(best), j, -1)


def _compiled_occlusions() -> tuple[Callable[..., int], Callable[..., int]] | None:
    """Return the loops of :func:`occlusions` and :func:`occlude` in C (sim/_kernels.c).

    None where it was not built (an optional build: numpy gives the same numbers), or where
    numpy's cos and sin do not round as libm's, which the loop uses, do (checked here).
    """
    try:
        from mdle.sim._kernels import occlude, occlusions
    except ImportError:
        return None
    x = np.linspace(-40.0, 40.0, 97)
    if (np.cos(x).tolist() != [math.cos(v) for v in x.tolist()]
            or np.sin(x).tolist() != [math.sin(v) for v in x.tolist()]):
        return None
    return occlusions, occlude


_KERNELS = _compiled_occlusions()
#: Whether :func:`occlusions` runs compiled (False: numpy, the same numbers).
COMPILED = _KERNELS is not None
_as_f = partial(np.ascontiguousarray, dtype=np.float64)
_as_i = partial(np.ascontiguousarray, dtype=np.intp)


def _kernels(compiled: bool | None) -> tuple[Callable[..., int], Callable[..., int]] | None:
    """Return the C loops to use for ``compiled`` (None: numpy); True without them raises."""
    if compiled and _KERNELS is None:
        raise ValueError("this install of mdle has no compiled occlusions")
    return None if compiled is False else _KERNELS


def _kernel_inputs(ox: np.ndarray, oy: np.ndarray, first: np.ndarray, step: np.ndarray,
                   beams: np.ndarray, max_range: np.ndarray, skip: np.ndarray, discs: Discs
                   ) -> tuple[np.ndarray, ...]:
    """Return the C loops' scan and disc arguments: contiguous float64 or intp, each.

    (No copy where an array already is.)
    """
    return (_as_f(ox), _as_f(oy), _as_f(first), _as_f(step), _as_i(beams), _as_f(max_range),
            _as_i(skip), _as_f(discs.cx), _as_f(discs.cy), _as_f(discs.r))


def occlusions(ox: np.ndarray, oy: np.ndarray, first: np.ndarray, step: np.ndarray,
               beams: np.ndarray, max_range: np.ndarray, skip: np.ndarray, discs: Discs,
               compiled: bool | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Find where the discs cut the rays of several scans at once: one call per team tick.

    Scan ``s`` has ``beams[s]`` rays from ``(ox[s], oy[s])``, ray ``b`` at the world
    angle ``first[s] + b * step[s]`` (a ladar's even fan), and does not see disc
    ``skip[s]`` (its own robot). Only the rays a disc can cut are computed: each disc's
    angular window, found for every (scan, disc) pair together, gives a run of beams;
    the runs are laid end to end and cast in one pass, so the work grows with the beams
    the robots cover, not with scans times beams times robots.

    Returns (scan, beam, distance) of every ray that meets a disc within the scan's
    ``max_range``, grouped by scan in increasing order (a beam may appear more than
    once: keep the nearest). The windows assume a fan narrower than a full turn.

    ``compiled``: the loop in C (True), numpy (False), or C where this install has it
    (None; :data:`COMPILED`). Both give the same arrays.
    """
    kernels = _kernels(compiled)
    if kernels is not None:
        n_scan = ox.shape[0]
        cap = int(beams.sum()) * len(discs) if n_scan else 0
        scan, beam, t = np.empty(cap, np.intp), np.empty(cap, np.intp), np.empty(cap)
        n = kernels[0](*_kernel_inputs(ox, oy, first, step, beams, max_range, skip, discs),
                       scan, beam, t)
        return scan[:n], beam[:n], t[:n]
    dx = discs.cx[None, :] - ox[:, None]          # (S, N): each disc from each origin
    dy = discs.cy[None, :] - oy[:, None]
    d2 = dx * dx + dy * dy
    reach = max_range[:, None] + discs.r[None, :]
    near = (d2 > discs.r * discs.r) & (d2 < reach * reach)
    near[np.arange(ox.shape[0]), skip] = False
    si, ki = np.nonzero(near)                     # row-major: grouped by scan
    if not si.size:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty, np.zeros(0)
    wx, wy = dx[si, ki], dy[si, ki]
    d = np.sqrt(d2[si, ki])
    rp = discs.r[ki]
    half = np.arcsin(rp / d)                      # the disc's half-width seen from there
    phi = np.mod(np.arctan2(wy, wx) - first[si], 2.0 * math.pi)
    st = step[si]
    lo = np.maximum(np.ceil((phi - half) / st), 0.0).astype(np.intp)
    hi = np.minimum(np.floor((phi + half) / st), beams[si] - 1).astype(np.intp)
    count = np.maximum(hi - lo + 1, 0)
    pair = np.repeat(np.arange(si.shape[0]), count)
    start = np.cumsum(count) - count
    beam = lo[pair] + (np.arange(pair.shape[0]) - start[pair])
    scan = si[pair]
    angle = first[scan] + beam * step[scan]
    proj = wx[pair] * np.cos(angle) + wy[pair] * np.sin(angle)
    disc = proj * proj - (d2[si, ki] - rp * rp)[pair]
    t = proj - np.sqrt(np.maximum(disc, 0.0))
    keep = (disc >= 0.0) & (proj > 0.0) & (t <= max_range[scan])
    return scan[keep], beam[keep], t[keep]


def occlude(ox: np.ndarray, oy: np.ndarray, first: np.ndarray, step: np.ndarray,
            beams: np.ndarray, max_range: np.ndarray, skip: np.ndarray, discs: Discs,
            ranges: np.ndarray, valid: np.ndarray, compiled: bool | None = None) -> None:
    """Put the discs into scans cast without them: :func:`occlusions`, applied in place.

    ``ranges`` and ``valid`` (S, B), row ``s`` scan ``s``: a range becomes the nearer of
    itself and any disc's cut, and a cut beam is valid. ``compiled`` as for
    :func:`occlusions`; both paths leave the same numbers.
    """
    kernels = _kernels(compiled)
    if kernels is not None and ranges.flags.c_contiguous and valid.flags.c_contiguous:
        kernels[1](*_kernel_inputs(ox, oy, first, step, beams, max_range, skip, discs),
                   ranges, valid)
        return
    scan, beam, t = occlusions(ox, oy, first, step, beams, max_range, skip, discs, compiled)
    np.minimum.at(ranges, (scan, beam), t)
    valid[scan, beam] = True


class CrowdCollider(Collider):
    """A :class:`Collider` for the static world plus the discs of the other robots.

    ``discs`` is set before each of the robot's steps (the others stand still while it
    moves). A disc's obstacle index is ``robot_base + owner`` (after the world's
    obstacles), so contacts name the robot touched; ``skip`` is the robot's own disc.
    """

    def __init__(self, parts: Parts, radius: float, robot_base: int) -> None:
        super().__init__(parts, radius)
        self.robot_base = robot_base
        self.discs = NO_DISCS
        #: the robot's own disc in ``discs`` (-1: not there)
        self.skip = -1
        self._others = False  # any disc but its own?
        self._reach = np.zeros(0)  # radius of each disc plus the body's (-inf: its own)
        # the last static clearance asked for, and where: asked again at the same place
        self._static_at: tuple[float, float] | None = None
        self._static_clear = Clearance(math.inf, -1)

    def join(self, discs: Discs, skip: int) -> None:
        """Meet the robots at ``discs`` (a live view), except disc ``skip``, its own."""
        self.discs = discs
        self.skip = skip
        self._others = len(discs) > (skip >= 0)
        self._reach = discs.r + self.radius
        if skip >= 0:
            self._reach[skip] = -math.inf

    def static_clearance(self, x: float, y: float) -> Clearance:
        """Return the clearance to the nearest wall (kept: asked again at the same place)."""
        if self._static_at == (x, y):
            return self._static_clear
        self._static_clear = super().clearance(x, y)
        self._static_at = (x, y)
        return self._static_clear

    def clearance(self, x: float, y: float) -> Clearance:
        """Return the clearance to the nearest wall or robot, and its index."""
        c, owner = self.static_clearance(x, y)
        d = self.discs
        if self._others:
            gaps = np.abs(d.z - complex(x, y)) if d.z is not None else np.hypot(d.cx - x,
                                                                                d.cy - y)
            gaps -= self._reach                  # its own disc: +inf
            j = int(gaps.argmin())
            gap = float(gaps[j])
            if gap < c:
                return Clearance(gap, self.robot_base + int(d.owner[j]))
        return Clearance(c, owner)

    def _outward(self, x: float, y: float) -> tuple[float, float]:
        """Return the unit vector away from the nearest wall or robot."""
        d = self.discs
        if self._others:
            gaps = np.hypot(d.cx - x, d.cy - y) - d.r
            if self.skip >= 0:
                gaps[self.skip] = math.inf
            j = int(gaps.argmin())
            if gaps[j] < Collider.distance(self, x, y)[0]:
                dx, dy = x - float(d.cx[j]), y - float(d.cy[j])
                n = math.hypot(dx, dy)
                return (dx / n, dy / n) if n > 0 else (0.0, 0.0)
        return super()._outward(x, y)
