"""How often the corridor's doors swing the robot: a real ARCOS server against the simulator.

The paper's corridor (``plans/paper/fig6-corridor.mdle``): follow the right wall at 0.55 m
and 0.3 m/s past four closed doors. At each door jamb the wall steps back 5 cm, the law
turns towards it and back, and the robot's heading swings. Two numbers per door, read the
same way from a recorded run and from a simulated one:

* the **swing**: the largest ``|theta|`` (odometry heading) from 1 m before the jamb to
  3 m after it (``x`` is odometry: 0 where the run starts, as on the robot);
* the **least side range**: the smallest side range the law measured there
  (``diag.side_range`` where ``side_hit``).

What the tables compare is how often a door swings over 30 deg, and the least side
range, per condition: the law as the server runs were made, against ``pioneer-p3dx``
over seeds. The recordings (in the repository, ``tests/data/recordings/amrisim-2026-11-28/``)
are mdle traces of AMRISim runs; :data:`CONDITIONS` names them.

In a checkout, ``python benchmarks/door_swings.py`` prints the table.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from mdle.runtime.events import Sample

__all__ = ["CONDITIONS", "DOORS", "SWING_LIMIT", "Condition", "DoorStats", "Summary",
           "door_stats", "recorded_doors", "recordings_of", "simulated_doors", "summarise"]

#: Where the door openings begin, m along the corridor from the start (odometry x).
DOORS = (3.0, 7.0, 11.0, 15.0)
#: The window of a door: from this far before its jamb to this far after it (m).
BEFORE, AFTER = 1.0, 3.0
#: A swing over this is a big one (deg).
SWING_LIMIT = 30.0


@dataclass(frozen=True)
class Condition:
    """A version of the corridor's law, its server recordings and how to simulate it.

    ``edit`` turns the shipped plan's atom into this condition's law (``kf = 2)`` is
    replaced by it); ``glob`` finds its recordings in the session's folder.
    """

    name: str
    description: str
    glob: str | None
    edit: str


#: The laws compared. ``uncompensated``: no lag prediction, the paper's damping (the
#: recordings' ``fig6-uncompensated.mdle``). ``as recorded``: the shipped plan as it ran
#: on the server, where the backend reported no latency, so the law predicted over the
#: scan's age only (``latency = 0.001 ms`` does the same in the simulator). ``shipped``: the
#: shipped plan as it runs now, predicting over the robot's latency (no recordings yet).
CONDITIONS = (
    Condition("uncompensated", "no lag prediction, the paper's damping",
              "corridor-uncompensated-*.jsonl", "kf = 2, latency = 0 s, damping = paper)"),
    Condition("as recorded", "the shipped plan with the latency the backend reported (0)",
              "corridor-default-*.jsonl", "kf = 2, latency = 0.001 ms)"),
    Condition("shipped", "the shipped plan, predicting over the robot's latency",
              None, "kf = 2)"),
)


@dataclass(frozen=True)
class DoorStats:
    """One door of one run: the heading's swing (deg) and the least side range (m)."""

    swing: float
    least_side: float


def door_stats(x: np.ndarray, theta: np.ndarray, side: np.ndarray) -> list[DoorStats]:
    """Return the swing and least side range at each of :data:`DOORS`.

    ``x`` (m, odometry), ``theta`` (rad) and ``side`` (the law's side range, m; NaN
    where it saw no side) are per tick. A door the run never reached is left out.
    """
    out = []
    for d in DOORS:
        near = (x >= d - BEFORE) & (x < d + AFTER)
        if not near.any():
            continue
        sides = side[near]
        least = float(np.nanmin(sides)) if np.isfinite(sides).any() else math.nan
        out.append(DoorStats(math.degrees(float(np.max(np.abs(theta[near])))), least))
    return out


def recorded_doors(path: str | os.PathLike[str]) -> list[DoorStats]:
    """Return the door statistics of a recorded run (an mdle trace)."""
    from mdle.record.load import read_trace

    trace = read_trace(path)
    hit = trace.column("diag.side_hit")
    side = np.where(hit > 0, trace.column("diag.side_range"), np.nan)
    return door_stats(trace.column("x"), trace.column("theta"), side)


def _samples_doors(samples: Sequence[Sample]) -> list[DoorStats]:
    x = np.array([s.x for s in samples])
    theta = np.array([s.theta for s in samples])
    side = np.array([s.diag["side_range"] if s.diag.get("side_hit") else math.nan
                     for s in samples], dtype=float)
    return door_stats(x, theta, side)


def simulated_doors(condition: Condition, seed: int, plan: Path, world: Path,
                    robot: str = "pioneer-p3dx") -> list[DoorStats]:
    """Run the corridor in the simulator with ``condition``'s law; return its doors.

    ``plan`` and ``world``: the corridor's plan (``plans/paper/fig6-corridor.mdle``) and
    world (``plans/paper/fig6-corridor.world.yaml``).
    """
    from mdle.lang import load_text
    from mdle.runtime import run
    from mdle.runtime.observer import Recorder
    from mdle.sim import SimBackend, load_world

    text = plan.read_text()
    if "kf = 2)" not in text:
        raise ValueError(f"{plan}: the corridor atom's `kf = 2)` is not there to edit")
    program = load_text(text.replace("kf = 2)", condition.edit), file=str(plan))
    backend = SimBackend(load_world(world), robot=robot, seed=seed)
    rec = Recorder()
    run(program.elements["main"], backend, rate=10.0, observers=[rec])
    return _samples_doors(rec.samples)


@dataclass(frozen=True)
class Summary:
    """Doors of many runs: how many swung over :data:`SWING_LIMIT`, and the side ranges."""

    runs: int
    doors: int
    big: int
    median_swing: float
    max_swing: float
    median_least_side: float
    least_side: float

    @property
    def big_rate(self) -> float:
        """Return the share of doors that swung over the limit."""
        return self.big / self.doors if self.doors else math.nan


def summarise(runs: Sequence[Sequence[DoorStats]]) -> Summary:
    """Summarise the doors of ``runs`` (one list of doors per run)."""
    doors = [d for r in runs for d in r]
    swings = np.array([d.swing for d in doors])
    sides = np.array([d.least_side for d in doors])
    if not doors:
        return Summary(len(runs), 0, 0, math.nan, math.nan, math.nan, math.nan)
    return Summary(len(runs), len(doors), int(np.sum(swings > SWING_LIMIT)),
                   float(np.median(swings)), float(swings.max()),
                   float(np.nanmedian(sides)), float(np.nanmin(sides)))


def recordings_of(condition: Condition, folder: Path) -> list[Path]:
    """Return the recorded runs of ``condition``, sorted (none without a glob)."""
    return sorted(folder.glob(condition.glob)) if condition.glob else []
