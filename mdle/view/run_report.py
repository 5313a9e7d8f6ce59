"""What a run leaves on the screen when it ends: how boundary following went, and a map.

:class:`FollowingStats` collects, tick by tick, the true distance ``d`` from the robot's
centre to the nearest boundary while a ``follow_boundary`` atom runs (the sample's
clearance plus the body radius; the measured side range when there is no ground truth),
against the atom's ``rc`` (recorded in its trace diagnostics). At the end: per atom, the
mean and max of ``|d - rc|`` over the second half of its ticks (the approach excluded, as
the experiments measure it) and the closest approach (smallest body clearance).
:func:`path_map` draws the path, and the boundary the robot detected, as a few lines of
text: the live view prints it under the summary, on a terminal and in a log alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mdle.runtime.events import Sample

__all__ = ["FollowingStats", "FollowRow", "path_map", "MapPoints"]


@dataclass(frozen=True)
class FollowRow:
    """One following atom's figures; distances in metres."""

    path: str
    rc: float
    ticks: int
    mean_err: float
    max_err: float
    closest: float | None
    truth: bool
    """True: ``d`` from the simulator's ground truth; False: from the measured side range."""


@dataclass
class _Acc:
    rc: float
    truth: bool = True
    errs: list[float] = field(default_factory=list)
    closest: float = math.inf


class FollowingStats:
    """Collect boundary-following errors per atom path; :meth:`rows` gives the figures."""

    def __init__(self, radius: float) -> None:
        self.radius = radius
        self._by: dict[str, _Acc] = {}

    def add(self, s: Sample) -> None:
        """Count one tick (only ticks of an atom that records ``rc``)."""
        rc = s.diag.get("rc")
        if rc is None:
            return
        acc = self._by.get(s.path)
        if acc is None:
            acc = self._by[s.path] = _Acc(float(rc))
        if s.clearance is not None and math.isfinite(s.clearance):
            d = s.clearance + self.radius
            acc.closest = min(acc.closest, s.clearance)
        elif s.diag.get("side_hit", 0.0) > 0.5:
            d = float(s.diag.get("side_range", math.nan))
            acc.truth = False
        else:
            return
        acc.errs.append(abs(d - acc.rc))

    def rows(self) -> list[FollowRow]:
        """Return one row per following atom that ran, in the order they first ran."""
        out = []
        for path, acc in self._by.items():
            if not acc.errs:
                continue
            half = acc.errs[len(acc.errs) // 2:]
            out.append(FollowRow(path, acc.rc, len(acc.errs), sum(half) / len(half), max(half),
                                 acc.closest if math.isfinite(acc.closest) else None,
                                 acc.truth))
        return out


@dataclass
class MapPoints:
    """The path (x, y), where it started and the detected boundary points, all metres."""

    path: list[tuple[float, float]] = field(default_factory=list)
    boundary: list[tuple[float, float]] = field(default_factory=list)

    def add(self, s: Sample) -> None:
        """Remember the tick's pose and, when the side ray hit, the boundary point it saw."""
        self.path.append((s.x, s.y))
        r = s.diag.get("side_range")
        if r and s.diag.get("side_hit", 0.0) > 0.5:
            a = s.theta + s.diag.get("side_bearing", -math.pi / 2)
            self.boundary.append((s.x + r * math.cos(a), s.y + r * math.sin(a)))


def path_map(points: MapPoints, width: int = 56, height: int = 16) -> list[str]:
    """Draw the path as text lines: ``S`` start, ``E`` end, ``.`` path, ``#`` boundary.

    A terminal cell is about twice as tall as wide, so one cell spans twice the metres
    across as it does down; the drawing keeps the scene's proportions inside
    ``width`` x ``height`` cells. Empty when there is nothing to draw.

    >>> m = MapPoints([(0.25 * i, 0.0) for i in range(9)], [(1.0, -0.5)])
    >>> path_map(m, width=9, height=3)
    ['S.......E', '    #', 'x 0.0..2.0 m, y -0.5..0.0 m']
    """
    pts = [(x, y) for x, y in points.path if math.isfinite(x) and math.isfinite(y)]
    if len(pts) < 2:
        return []
    wall = [(x, y) for x, y in points.boundary if math.isfinite(x) and math.isfinite(y)]
    xs = [p[0] for p in pts + wall]
    ys = [p[1] for p in pts + wall]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    # metres per cell: down = 2 * across (cells are twice as tall as wide)
    across = max((x1 - x0) / max(width - 1, 1), (y1 - y0) / max(height - 1, 1) / 2, 1e-9)
    down = 2 * across
    cols = min(width, int((x1 - x0) / across) + 1)
    rows = min(height, int((y1 - y0) / down) + 1)
    grid = np.full((rows, cols), " ", dtype="<U1")

    def cells(xy: "np.ndarray") -> "tuple[np.ndarray, np.ndarray]":
        c = np.clip(((xy[:, 0] - x0) / across + 0.5).astype(int), 0, cols - 1)
        r = np.clip(((y1 - xy[:, 1]) / down + 0.5).astype(int), 0, rows - 1)
        return r, c

    if wall:
        grid[cells(np.array(wall))] = "#"
    # the path as a connected line: each step filled cell by cell between its ends
    r, c = cells(np.array(pts))
    n = np.maximum(np.abs(np.diff(r)), np.abs(np.diff(c))) + 1
    frac = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
    f = frac / np.repeat(n, n)
    rr = np.rint(np.repeat(r[:-1], n) + f * np.repeat(np.diff(r), n)).astype(int)
    cc = np.rint(np.repeat(c[:-1], n) + f * np.repeat(np.diff(c), n)).astype(int)
    grid[rr, cc] = "."
    grid[r[0], c[0]] = "S"
    grid[r[-1], c[-1]] = "E"
    lines = ["".join(row).rstrip() for row in grid.tolist()]
    lines.append(f"x {x0:.1f}..{x1:.1f} m, y {y0:.1f}..{y1:.1f} m")
    return lines
