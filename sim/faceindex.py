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

import numpy as np

__all__ = ["MAX_CELLS", "PAD", "FaceGrid"]

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
