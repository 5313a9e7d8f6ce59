"""What the REPL's runs tell: run reports, the rows of ``:step``, and loaded recordings.

Plain records a :class:`~mdle.repl.session.Session` returns, and how they are computed
from a run's samples (the closest approach, the boundary distance, a step's scan);
:mod:`mdle.repl.views` turns them into text.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from mdle.core.errors import MdleError
from mdle.core.pose import Pose
from mdle.runtime import Cause, RunResult, Sample, Termination

if TYPE_CHECKING:
    from mdle.sim.backend import SimEvent

__all__ = ["SETTLED_WINDOW", "LoadedRun", "RunReport", "SideStats", "StepOutcome", "StepRow"]


@dataclass(frozen=True)
class SideStats:
    """The boundary distance a following law reported during a run (m).

    Smallest and largest over the run, and mean and standard deviation over its last
    ``window`` seconds (the settled part, when the run is longer than that), from ``n``
    ticks.
    """

    low: float
    high: float
    mean: float
    std: float
    window: float
    n: int


#: Seconds at the end of a run over which the settled boundary distance is averaged.
SETTLED_WINDOW = 10.0


@dataclass(frozen=True)
class RunReport:
    """How one run (or a stepped run, once it ended) went.

    ``label`` is the element's label, ``t0`` the backend time of its first tick (s),
    ``pose`` the odometry pose at the end, ``true_pose`` the simulator's pose (None on a
    robot),
    ``interrupted`` True after Ctrl-C, ``limit`` the run limit when it stopped the run
    (s, else None), ``collision`` the simulator's record of the first contact during the
    run, ``error`` the error that aborted it (a failing law or interrupt), ``closest``
    where the robot came closest to an obstacle: (time since the start (s), x, y (m, true
    position)), None without ground truth, ``side`` the distance to the followed boundary
    the control law reported (its ``side_range`` diagnostic on ticks with ``side_hit``), as
    :class:`SideStats`, None when the law reported none.
    """

    label: str
    result: RunResult
    t0: float
    pose: Pose
    true_pose: Pose | None
    interrupted: bool = False
    limit: float | None = None
    collision: SimEvent | None = None
    error: MdleError | None = None
    closest: tuple[float, float, float] | None = None
    side: SideStats | None = None

    @property
    def decisive(self) -> Termination:
        """The termination that ended the run.

        The outermost element that ended by its own interrupt or timer (or was stopped) at
        the final tick, else the root's.
        """
        root = self.result.termination
        final = [t for t in self.result.terminations
                 if abs(t.time - root.time) < 1e-9
                 and t.cause not in (Cause.COMPLETED, Cause.ENDED_BY_PARENT)]
        return min(final, key=lambda t: t.level) if final else root

    @property
    def ok(self) -> bool:
        """False when the robot collided, the run was aborted or stopped by Ctrl-C."""
        return (not self.interrupted and self.error is None and self.collision is None
                and not self.result.collided and self.result.fault is None)


@dataclass(frozen=True)
class StepRow:
    """One tick shown by ``:step``: the sample, and the scan the tick saw.

    ``front`` is the range of the beam nearest 0 deg (m), ``nearest`` the smallest valid
    range (m) and ``nearest_bearing`` its bearing (rad); None without a scan.
    """

    tick: int
    sample: Sample
    front: float | None
    nearest: float | None
    nearest_bearing: float | None


@dataclass(frozen=True)
class StepOutcome:
    """What ``:step N`` did.

    The rows, the report when the element ended, and whether a new run of the element was
    started for it.
    """

    rows: tuple[StepRow, ...]
    report: RunReport | None
    started: bool
    label: str
    t0: float


@dataclass(frozen=True)
class LoadedRun:
    """What ``:load`` of a recording brought in: the element, result, ticks, world, notes.

    ``cut`` is True when the recording was cut short (no ``end`` record); ``note`` says
    what could not be restored (the world, the robot's place), None when everything was.
    """

    label: str
    result: RunResult
    ticks: int
    world: str
    cut: bool
    note: str | None


def _row(tick: int, sample: Sample, scan: Any) -> StepRow:
    if scan is None or len(scan.ranges) == 0:
        return StepRow(tick, sample, None, None, None)
    import numpy as np

    ranges = np.asarray(scan.ranges, dtype=float)
    bearings = np.asarray(scan.bearings, dtype=float)
    valid = np.asarray(scan.valid, dtype=bool) & np.isfinite(ranges)
    front = float(ranges[int(np.argmin(np.abs(bearings)))])
    if not valid.any():
        return StepRow(tick, sample, front, None, None)
    i = int(np.argmin(np.where(valid, ranges, np.inf)))
    return StepRow(tick, sample, front, float(ranges[i]), float(bearings[i]))


def _closest(samples: Sequence[Sample], t0: float) -> tuple[float, float, float] | None:
    """(t - t0, x, y) of the sample with the smallest true clearance, None without truth."""
    known = [s for s in samples if s.clearance is not None]
    if not known:
        return None
    best = min(known, key=lambda s: float(s.clearance))  # type: ignore[arg-type]
    x = best.true_x if best.true_x is not None else best.x
    y = best.true_y if best.true_y is not None else best.y
    return best.time - t0, x, y


def _side_stats(samples: Sequence[Sample]) -> SideStats | None:
    """Statistics of the ``side_range`` diagnostic on the ticks where the side ray hit."""
    import numpy as np

    rows = [(s.time, s.diag["side_range"]) for s in samples
            if "side_range" in s.diag and s.diag.get("side_hit", 1.0) > 0.5]
    if not rows:
        return None
    t, r = np.asarray(rows, dtype=float).T
    window = min(SETTLED_WINDOW, float(t[-1] - t[0]))
    last = r[t >= t[-1] - window - 1e-9]  # both ends: tick stamps are products
    return SideStats(float(r.min()), float(r.max()), float(last.mean()), float(last.std()),
                     window, len(r))
