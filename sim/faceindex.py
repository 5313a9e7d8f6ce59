"""A uniform grid over a world's straight faces, for ray casts whose cost follows the view.

Built once per world (:attr:`sim.raycast.RayCaster.grid`) and shared by every ladar that
casts in it. A face is listed in every cell that comes within :data:`PAD` of it, so a beam
that walks the cells it crosses, in order (the compiled loop in ``sim/_kernels.c``),
meets every face it can hit before it leaves the cell of its nearest hit, and stops
there: a scan reads the faces near the robot and along its beams, not the whole map.

The build is vectorised: each face is cut into pieces no longer than a cell, each piece
lists the cells its padded bounding box covers (at most 3 x 3), and one sort groups the
(cell, face) pairs by cell.

>>> import numpy as np
>>> s0 = np.array([[0.0, 0.0], [0.0, 4.0]])
>>> s1 = np.array([[4.0, 0.0], [4.0, 4.0]])
>>> g = FaceGrid.build(s0, s1, cell=1.0)   # the box is padded: 4 m take 5 cells
>>> (g.nx, g.ny), g.faces_in(0, 0).tolist(), g.faces_in(2, 2).tolist()
((5, 5), [0], [])
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from mdle.sim.shapes import Parts

__all__ = ["MAX_CELLS", "PAD", "BoxGrid", "FaceGrid"]

#: Metres: a face is listed in the cells within this of it. A beam's hit may lie just
#: beyond a face's end (its bearing interval is widened by 1e-10 rad), so the pad must
#: exceed that; it also exceeds the walk's stopping margin (``sim/raycast.py``).
PAD = 1e-6
#: The most cells a grid has: a world whose faces would want more gets larger cells.
MAX_CELLS = 4_000_000


@dataclass(frozen=True, eq=False)
class FaceGrid:
    """Faces by cell: cell ``(ix, iy)`` lists ``faces[start[i]:start[i + 1]]``, ``i = iy nx + ix``.

    Attributes
    ----------
    x0, y0 : float, metres
        The grid's lower-left corner (world frame).
    cell : float, metres
        The side of a cell.
    nx, ny : int
        Cells along x and y.
    start : (nx ny + 1,) intp array
        Where each cell's run of face indices begins in ``faces``.
    faces : intp array
        Face indices (into the caster's segments), grouped by cell, ascending in each.
    """

    x0: float
    y0: float
    cell: float
    nx: int
    ny: int
    start: np.ndarray
    faces: np.ndarray

    @property
    def box(self) -> np.ndarray:
        """``(x0, y0, cell, nx, ny)`` as floats: the compiled walk's view of the grid."""
        return np.array([self.x0, self.y0, self.cell, float(self.nx), float(self.ny)])

    def faces_in(self, ix: int, iy: int) -> np.ndarray:
        """Return the face indices listed in cell ``(ix, iy)``."""
        i = iy * self.nx + ix
        return self.faces[self.start[i]:self.start[i + 1]]

    @staticmethod
    def cell_for(s0: np.ndarray, s1: np.ndarray) -> float:
        """Choose a cell side for these faces, metres.

        About three faces a cell over the faces' bounding box (measured best in floor
        plans: smaller cells cost more steps, larger ones more faces a step), but no
        smaller than the median face (a long wall is then listed in few cells) and never
        more than :data:`MAX_CELLS` cells.
        """
        lo, hi = np.minimum(s0, s1).min(axis=0), np.maximum(s0, s1).max(axis=0)
        w, h = float(hi[0] - lo[0]), float(hi[1] - lo[1])
        n = s0.shape[0]
        area = max(w * h, 1e-12)
        median = float(np.median(np.hypot(*(s1 - s0).T)))
        side = max(math.sqrt(3.0 * area / n), median, 1e-3)
        cells = (w / side + 1.0) * (h / side + 1.0)
        if cells > MAX_CELLS:
            side *= math.sqrt(cells / MAX_CELLS) * 1.01
        return side

    @classmethod
    def build(cls, s0: np.ndarray, s1: np.ndarray, cell: float | None = None) -> FaceGrid:
        """Index the faces ``s0[i] -> s1[i]`` ((F, 2) arrays, metres, at least one).

        ``cell``: the side of a cell, metres (default :meth:`cell_for`).
        """
        s0 = np.asarray(s0, dtype=float).reshape(-1, 2)
        s1 = np.asarray(s1, dtype=float).reshape(-1, 2)
        if s0.shape[0] == 0 or s0.shape != s1.shape:
            raise ValueError("a face grid needs one or more faces, as two (F, 2) arrays")
        if not (np.isfinite(s0).all() and np.isfinite(s1).all()):
            raise ValueError("a face grid needs finite face ends")
        side = cls.cell_for(s0, s1) if cell is None else float(cell)
        if not (math.isfinite(side) and side > 0):
            raise ValueError(f"a face grid's cell must be finite and positive, not {side!r}")
        lo = np.minimum(s0, s1).min(axis=0) - 2 * PAD
        hi = np.maximum(s0, s1).max(axis=0) + 2 * PAD
        nx = max(1, math.ceil(float(hi[0] - lo[0]) / side))
        ny = max(1, math.ceil(float(hi[1] - lo[1]) / side))
        # Pieces no longer than a cell: their padded boxes cover at most 3 x 3 cells.
        length = np.hypot(*(s1 - s0).T)
        pieces = np.maximum(1, np.ceil(length / side)).astype(np.intp)
        face = np.repeat(np.arange(s0.shape[0], dtype=np.intp), pieces)
        first = np.cumsum(pieces) - pieces
        k = np.arange(face.shape[0], dtype=np.intp) - np.repeat(first, pieces)
        frac0 = (k / pieces[face])[:, None]
        frac1 = ((k + 1) / pieces[face])[:, None]
        edge = (s1 - s0)[face]
        a, b = s0[face] + frac0 * edge, s0[face] + frac1 * edge
        c_lo = np.floor((np.minimum(a, b) - PAD - lo) / side).astype(np.intp)
        c_hi = np.floor((np.maximum(a, b) + PAD - lo) / side).astype(np.intp)
        np.clip(c_lo, 0, (nx - 1, ny - 1), out=c_lo)
        np.clip(c_hi, 0, (nx - 1, ny - 1), out=c_hi)
        keys = []
        for dx in range(3):
            for dy in range(3):
                ix, iy = c_lo[:, 0] + dx, c_lo[:, 1] + dy
                ok = (ix <= c_hi[:, 0]) & (iy <= c_hi[:, 1])
                keys.append((iy[ok] * nx + ix[ok]) * s0.shape[0] + face[ok])
        pairs = np.unique(np.concatenate(keys))      # sorted by cell, then face; no repeats
        cells, faces = np.divmod(pairs, s0.shape[0])
        start = np.searchsorted(cells, np.arange(nx * ny + 1), side="left").astype(np.intp)
        return cls(float(lo[0]), float(lo[1]), side, nx, ny, start, faces.astype(np.intp))


@dataclass(frozen=True, eq=False)
class BoxGrid:
    """Curved obstacles (arcs, ellipses) by cell, through their bounding boxes.

    A ray cast meets a curve in closed form, so it needs no walk: only the curves that
    can come within the ladar's range. :meth:`near` lists them from the cells of the
    range's square, a superset of the curves within range that the cast then tests
    exactly as it tests all of them, so the numbers are the same. An item is listed in
    every cell its box, padded by :data:`PAD`, covers; a cell lists its items ascending.

    >>> import numpy as np
    >>> g = BoxGrid.build(np.array([[0.0, 0.0], [8.0, 8.0]]),
    ...                   np.array([[1.0, 1.0], [9.0, 9.0]]), cell=1.0)
    >>> g.near(0.5, 0.5, 2.0).tolist(), g.near(5.0, 5.0, 10.0).tolist()
    ([0], [0, 1])
    """

    x0: float
    y0: float
    cell: float
    nx: int
    ny: int
    start: np.ndarray
    items: np.ndarray
    size: int
    """How many boxes were indexed."""

    @classmethod
    def of_arcs(cls, parts: Parts) -> BoxGrid:
        """Index the arcs of ``parts`` by their circles' boxes (at least one arc)."""
        r = parts.arc_radius[:, None]
        return cls.build(parts.arc_center - r, parts.arc_center + r)

    @classmethod
    def of_ellipses(cls, parts: Parts) -> BoxGrid:
        """Index the ellipses of ``parts`` by their bounding circles' boxes (at least one)."""
        r = parts.ell_axes.max(axis=1)[:, None]
        return cls.build(parts.ell_center - r, parts.ell_center + r)

    @classmethod
    def build(cls, lo: np.ndarray, hi: np.ndarray, cell: float | None = None) -> BoxGrid:
        """Index the boxes ``lo[i] .. hi[i]`` ((N, 2) arrays, metres, at least one).

        ``cell``: the side of a cell, metres (default: about three boxes a cell, no
        smaller than the median box; larger where the boxes would fill too many cells).
        """
        lo = np.asarray(lo, dtype=float).reshape(-1, 2) - PAD
        hi = np.asarray(hi, dtype=float).reshape(-1, 2) + PAD
        n = lo.shape[0]
        if n == 0 or lo.shape != hi.shape:
            raise ValueError("a box grid needs one or more boxes, as two (N, 2) arrays")
        if not (np.isfinite(lo).all() and np.isfinite(hi).all() and (hi >= lo).all()):
            raise ValueError("a box grid needs finite boxes, each corner below the other")
        g_lo, g_hi = lo.min(axis=0), hi.max(axis=0)
        w, h = (float(v) for v in g_hi - g_lo)
        if cell is None:
            side = max(math.sqrt(3.0 * max(w * h, 1e-12) / n),
                       float(np.median(np.maximum(*(hi - lo).T))), 1e-3)
        else:
            side = float(cell)
        if not (math.isfinite(side) and side > 0):
            raise ValueError(f"a box grid's cell must be finite and positive, not {side!r}")
        for _ in range(64):     # bounded: each pass at least doubles the side
            nx = max(1, math.ceil(w / side))
            ny = max(1, math.ceil(h / side))
            c_lo = np.floor((lo - g_lo) / side).astype(np.intp)
            c_hi = np.floor((hi - g_lo) / side).astype(np.intp)
            np.clip(c_lo, 0, (nx - 1, ny - 1), out=c_lo)
            np.clip(c_hi, 0, (nx - 1, ny - 1), out=c_hi)
            span = c_hi - c_lo + 1
            count = span[:, 0] * span[:, 1]
            total = int(count.sum())
            if nx * ny <= MAX_CELLS and total <= 16 * n + MAX_CELLS:
                break
            side *= 2.0
        # Every (cell, item) pair: item i covers span[i] cells from c_lo[i], row by row.
        item = np.repeat(np.arange(n, dtype=np.intp), count)
        k = np.arange(total, dtype=np.intp) - np.repeat(np.cumsum(count) - count, count)
        ix = c_lo[item, 0] + k % span[item, 0]
        iy = c_lo[item, 1] + k // span[item, 0]
        order = np.argsort(iy * nx + ix, kind="stable")   # by cell; items ascend in each
        cells = (iy * nx + ix)[order]
        start = np.searchsorted(cells, np.arange(nx * ny + 1), side="left").astype(np.intp)
        return cls(float(g_lo[0]), float(g_lo[1]), side, nx, ny, start, item[order], n)

    def near(self, x: float, y: float, r: float) -> np.ndarray:
        """Return the items whose boxes meet the square of half-side ``r`` about ``(x, y)``.

        Ascending, each once; every item whose box comes within ``r`` of the point (by
        more than rounding) is among them, and some farther ones may be. A place or reach
        that is not finite gives every item.
        """
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(r)):
            return np.arange(self.size, dtype=np.intp)
        side = self.cell
        ix0 = max(0, math.floor((x - r - self.x0) / side))
        iy0 = max(0, math.floor((y - r - self.y0) / side))
        ix1 = min(self.nx - 1, math.floor((x + r - self.x0) / side))
        iy1 = min(self.ny - 1, math.floor((y + r - self.y0) / side))
        if ix0 > ix1 or iy0 > iy1:
            return np.zeros(0, dtype=np.intp)
        rows = np.arange(iy0, iy1 + 1, dtype=np.intp) * self.nx
        first, last = self.start[rows + ix0], self.start[rows + ix1 + 1]
        count = last - first                   # a row's cells are consecutive in `items`
        total = int(count.sum())
        at = np.arange(total, dtype=np.intp) + np.repeat(first - (np.cumsum(count) - count),
                                                         count)
        return np.unique(self.items[at])
