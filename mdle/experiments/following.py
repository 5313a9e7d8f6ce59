"""Boundary-following runs in the simulator: one run with its metrics, and random starts.

Used by the end-to-end tests (tests/atoms), ``benchmarks/random_starts.py`` and docs/steering.md.
A run loads a real MDLe plan (``follow_boundary`` inside an atom with a timer), runs it with
:func:`mdle.runtime.run` on a :class:`sim.SimBackend`, and measures the true distance from the
robot's centre to the boundary ``d`` (the sample's clearance plus the body radius).
:func:`run_follow` runs one in this process; :func:`run_many` (and :func:`random_starts`) run
many as sweep tasks (:mod:`mdle.sweep`) on every core, optionally resumable.
"""

from __future__ import annotations

import math
import os
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the runtime is imported inside run_follow, when a run needs it
    from mdle.runtime.observer import Recorder
    from mdle.sweep.tasks import RunTask

__all__ = ["FollowRun", "follow_plan", "follow_task", "run_follow", "run_many", "random_starts",
           "random_start_tasks", "SHAPES", "table", "table_rows", "TABLE_NOTES", "ENGAGED_ERR"]

#: The paper's shapes with their following distance (reference world name -> rc, m).
SHAPES: dict[str, float] = {"ellipse": 1.0, "hexagon": 0.5, "u-shape": 0.5, "square": 0.5,
                            "arrow": 0.5, "wall": 0.5}


@dataclass(frozen=True)
class FollowRun:
    """Metrics of one run. Distances in metres, times in seconds.

    ``mean_err``/``max_err`` are mean and max of ``|d - rc|`` over the second half of the run
    (``d`` the true distance from the robot's centre to the nearest boundary);
    ``min_clearance`` the smallest true body clearance over the whole run.
    """

    world: str
    side: str
    sensing: str
    seed: int
    rc: float
    collided: bool
    min_clearance: float
    mean_err: float
    max_err: float
    duration: float
    corner_fraction: float
    safety_fraction: float


def follow_plan(side: str, rc: float, v: float, duration: float, extra: str = "") -> str:
    """Write the MDLe text of a plan that follows a boundary for ``duration`` seconds."""
    return (f"atom follow = (follow_boundary(side = {side}, rc = {rc:g} m, v = {v:g} m/s{extra}),"
            f" never, {duration:g} s)\nplan main = ((follow), never, inf)\n")


def run_follow(world: str, *, side: str = "right", rc: float | None = None, v: float = 1.0,
               sensing: str = "scan", robot: str | None = "ideal", seed: int = 0,
               duration: float = 60.0, rate: float | None = None,
               pose: tuple[float, float, float] | None = None, extra: str = "",
               plan: str | None = None, element: str = "main",
               recorder: Recorder | None = None) -> FollowRun:
    """Run a following plan in a world (reference name or YAML path) and measure it.

    ``rate`` defaults to control-law.md section 5: 100 Hz with exact sensing, 50 Hz with
    the scan. ``plan`` is a path to an MDLe file that replaces the generated plan, run from
    its ``element``. ``robot=None`` keeps the world's robot.
    """
    import numpy as np

    from mdle.core.pose import Pose
    from mdle.lang import load_text
    from mdle.runtime import run
    from mdle.runtime.observer import Recorder
    from mdle.sim import SimBackend, load_world

    rc = SHAPES.get(world, 0.5) if rc is None else rc
    rate = (100.0 if sensing == "exact" else 50.0) if rate is None else rate
    if plan is None:
        program = load_text(follow_plan(side, rc, v, duration, extra), file=f"<{world}>")
    else:
        from mdle.lang import load_program

        program = load_program(plan)
    w = load_world(world)
    backend = SimBackend(w, seed=seed, robot=robot, sensing=sensing)
    if pose is not None:
        backend.reset(Pose(*pose))
    rec = recorder if recorder is not None else Recorder()
    result = run(program.elements[element], backend, rate=rate, observers=[rec])
    samples = rec.samples
    t = np.array([s.time for s in samples])
    radius = backend.limits.radius
    d = np.array([s.clearance for s in samples]) + radius
    half = t >= t[-1] / 2.0
    err = np.abs(d[half] - rc)
    modes = np.array([s.diag.get("mode", 0.0) for s in samples])
    safety = np.array([s.diag.get("safety", 0.0) for s in samples])
    return FollowRun(world, side, sensing, seed, rc, bool(result.collided),
                     float(np.min(d) - radius), float(err.mean()), float(err.max()),
                     float(t[-1]), float(modes.mean()), float(safety.mean()))


def _start_poses(world: str, n: int, seed: int, distance: float = 8.0
                 ) -> list[tuple[float, float, float]]:
    """Draw seeded starts ``distance`` from the obstacle's centre, heading at it +-17 deg.

    The wall: a random position 1-6 m above it, heading -11 to -169 deg.
    """
    import numpy as np

    from mdle.sim import load_world

    rng = np.random.default_rng(seed)
    w = load_world(world)
    if world == "wall":
        xs = rng.uniform(-5.0, 5.0, n)
        ys = rng.uniform(1.0, 6.0, n)
        th = -rng.uniform(math.radians(11.0), math.radians(169.0), n)
        return list(zip(xs.tolist(), ys.tolist(), th.tolist(), strict=True))
    cx, cy = w.geometry.centroid.x, w.geometry.centroid.y
    bearing = rng.uniform(-math.pi, math.pi, n)
    off = rng.uniform(-math.radians(17.0), math.radians(17.0), n)
    x = cx + distance * np.cos(bearing)
    y = cy + distance * np.sin(bearing)
    th = bearing + math.pi + off
    return list(zip(x.tolist(), y.tolist(), np.arctan2(np.sin(th), np.cos(th)).tolist(),
                    strict=True))


#: Trace fields the sweep summarises for a FollowRun: the corner mode and the safety layer.
_FIELDS = ("mode", "safety")


def follow_task(world: str, *, side: str = "right", rc: float | None = None, v: float = 1.0,
                sensing: str = "scan", robot: str | None = "ideal", seed: int = 0,
                duration: float = 60.0, rate: float | None = None,
                pose: tuple[float, float, float] | None = None, index: int = 0) -> RunTask:
    """Return the sweep task of one following run (what :func:`run_follow` runs in-process).

    ``world`` is a reference world name; the task carries its text, so it runs anywhere.
    """
    from importlib import resources

    from mdle.sweep.tasks import RunTask

    rc = SHAPES.get(world, 0.5) if rc is None else rc
    rate = (100.0 if sensing == "exact" else 50.0) if rate is None else rate
    text = resources.files("mdle.sim").joinpath("worlds", f"{world}.yaml").read_text("utf-8")
    return RunTask(follow_plan(side, rc, v, duration), (), "main", (), text, robot, sensing,
                   rate, seed, pose, None, _FIELDS, False, index,
                   {"plan": f"follow-{side}", "world": world, "robot": robot or "world",
                    "rc": repr(float(rc)), "side": side})


def _as_run(task: RunTask, row: dict[str, Any], rc: float, side: str) -> FollowRun:
    """Turn a sweep row back into the FollowRun the tables print (NaN where it failed)."""
    nan = math.nan

    def num(name: str) -> float:
        v = row.get(name)
        return nan if v is None else float(v)

    return FollowRun(task.labels["world"], side, task.sensing, task.seed, rc,
                     bool(row.get("collided")), num("min_clearance"), num("follow_mean_err"),
                     num("follow_max_err"), num("duration"), num("mode_mean"),
                     num("safety_mean"))


def run_many(tasks: Sequence[RunTask], *, jobs: int | None = None,
             out: str | os.PathLike[str] | None = None, progress: Any = None
             ) -> list[FollowRun]:
    """Run following tasks on all cores (the sweep engine); FollowRuns in task order.

    With ``out`` the rows go to ``out/results.csv`` and a rerun skips finished runs.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C: the finished rows are in the table (rerun to resume).
    MdleError
        A run failed (its cause), or ``out`` holds another experiment's table.
    """
    from mdle.core.errors import MdleError
    from mdle.sweep.engine import run_tasks
    from mdle.sweep.table import columns_for

    rows: dict[str, dict[str, Any]] = {}
    summary = run_tasks(tasks, columns_for((), _FIELDS), out, jobs=jobs, progress=progress,
                        on_row=lambda r: rows.__setitem__(r["key"], r))
    if summary.interrupted:
        raise KeyboardInterrupt
    if out is not None and summary.skipped:
        from mdle.sweep.table import read_rows

        for r in read_rows(Path(out) / "results.csv"):
            rows.setdefault(r["key"], r)
    runs = []
    for task in tasks:
        row = rows[task.key]
        if row.get("status") in ("error", "lost"):
            raise MdleError(f"run {task.labels['world']} seed {task.seed}: {row.get('cause')}")
        runs.append(_as_run(task, row, float(task.labels["rc"]), task.labels["side"]))
    return runs


def random_start_tasks(world: str, n: int = 50, *, seed: int = 0, side: str = "right",
                       sensing: str = "scan", duration: float = 40.0,
                       rate: float | None = None, v: float = 1.0) -> list[RunTask]:
    """Return the tasks of ``n`` seeded random starts headed roughly at the obstacle."""
    return [follow_task(world, side=side, sensing=sensing, seed=seed * 1000 + i,
                        duration=duration, rate=rate, pose=pose, v=v, index=i)
            for i, pose in enumerate(_start_poses(world, n, seed))]


def random_starts(world: str, n: int = 50, *, seed: int = 0, side: str = "right",
                  sensing: str = "scan", duration: float = 40.0, rate: float | None = None,
                  v: float = 1.0, jobs: int | None = None,
                  out: str | os.PathLike[str] | None = None) -> list[FollowRun]:
    """Run ``n`` seeded random starts headed roughly at the obstacle; one FollowRun each."""
    return run_many(random_start_tasks(world, n, seed=seed, side=side, sensing=sensing,
                                       duration=duration, rate=rate, v=v), jobs=jobs, out=out)


#: A run counts as engaged when its mean |d - rc| over the second half is below this (m).
ENGAGED_ERR = 0.25


def table_rows(runs: Sequence[FollowRun]) -> list[tuple[str, str, int, int, float, float, int]]:
    """Summarise the runs per world and sensing.

    Each row: world, sensing, runs, collisions, worst clearance (m), median of the mean
    |d - rc| (m), engaged runs (mean |d - rc| over the second half below
    :data:`ENGAGED_ERR`).
    """
    by: dict[tuple[str, str], list[FollowRun]] = defaultdict(list)
    for r in runs:
        by[(r.world, r.sensing)].append(r)
    out = []
    for (world, sensing), rs in sorted(by.items()):
        errs = sorted(r.mean_err for r in rs)
        out.append((world, sensing, len(rs), sum(r.collided for r in rs),
                    min(r.min_clearance for r in rs), errs[len(errs) // 2],
                    sum(r.mean_err < ENGAGED_ERR for r in rs)))
    return out


#: What the random-starts table's columns measure (printed under it).
TABLE_NOTES = (
    "d: true distance from the robot's centre to the nearest boundary; mean |d - rc| over "
    "the second half of each run",
    "worst clearance: the smallest gap between the robot's body and an obstacle in any run",
    f"engaged: runs that ended up following (mean |d - rc| below {ENGAGED_ERR:g} m)",
)


def table(runs: Sequence[FollowRun]) -> str:
    """Return a plain-text summary per world: collisions, worst clearance, error, engaged."""
    lines = [f"{'world':10} {'sensing':7} {'runs':>4} {'collisions':>10} "
             f"{'worst clearance (m)':>19} {'median mean |d-rc| (m)':>22} {'engaged':>7}"]
    for world, sensing, n, hits, worst, err, engaged in table_rows(runs):
        lines.append(f"{world:10} {sensing:7} {n:4d} {hits:10d} {worst:19.3f} {err:22.3f} "
                     f"{engaged:4d}/{n}")
    return "\n".join(lines + list(TABLE_NOTES))
