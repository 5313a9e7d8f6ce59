"""Boundary-following runs in the simulator: one run with its metrics, and random starts.

Used by the end-to-end tests (tests/atoms), ``benchmarks/random_starts.py`` and docs/steering.md.
A run loads a real MDLe plan (``follow_boundary`` inside an atom with a timer), runs it with
:func:`mdle.runtime.run` on a :class:`sim.SimBackend`, and measures the true distance from the
robot's centre to the boundary ``d`` (the sample's clearance plus the body radius).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the runtime is imported inside run_follow, when a run needs it
    from mdle.runtime.observer import Recorder

__all__ = ["FollowRun", "follow_plan", "run_follow", "random_starts", "SHAPES"]

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

    from mdle.backend import Pose
    from mdle.loader import load_text
    from mdle.runtime import run
    from mdle.runtime.observer import Recorder
    from sim import SimBackend, load_world

    rc = SHAPES.get(world, 0.5) if rc is None else rc
    rate = (100.0 if sensing == "exact" else 50.0) if rate is None else rate
    if plan is None:
        program = load_text(follow_plan(side, rc, v, duration, extra), file=f"<{world}>")
    else:
        from mdle.loader import load_program

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

    from sim import load_world

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


def random_starts(world: str, n: int = 50, *, seed: int = 0, side: str = "right",
                  sensing: str = "scan", duration: float = 40.0, rate: float | None = None,
                  v: float = 1.0) -> list[FollowRun]:
    """Run ``n`` seeded random starts headed roughly at the obstacle; one FollowRun each."""
    runs = []
    for i, pose in enumerate(_start_poses(world, n, seed)):
        runs.append(run_follow(world, side=side, sensing=sensing, seed=seed * 1000 + i,
                               duration=duration, rate=rate, pose=pose, v=v))
    return runs


def table(runs: Sequence[FollowRun]) -> str:
    """Return a plain-text summary: collisions, worst clearance, mean error, per world."""
    from collections import defaultdict

    by: dict[tuple[str, str], list[FollowRun]] = defaultdict(list)
    for r in runs:
        by[(r.world, r.sensing)].append(r)
    lines = [f"{'world':10} {'sensing':7} {'runs':>4} {'collisions':>10} {'worst clearance':>15} "
             f"{'median |d-rc|':>13} {'engaged':>7}"]
    for (world, sensing), rs in sorted(by.items()):
        errs = sorted(r.mean_err for r in rs)
        engaged = sum(r.mean_err < 0.25 for r in rs)
        lines.append(f"{world:10} {sensing:7} {len(rs):4d} {sum(r.collided for r in rs):10d} "
                     f"{min(r.min_clearance for r in rs):15.3f} {errs[len(errs) // 2]:13.3f} "
                     f"{engaged:4d}/{len(rs)}")
    return "\n".join(lines)
