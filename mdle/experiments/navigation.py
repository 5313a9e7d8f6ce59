"""The navigation experiment: a plan of ``plans/nav/`` over seeded random cluttered worlds.

Each world (:func:`generate_world`) holds 3 to 8 obstacles of mixed shapes (discs,
rotated boxes, ellipses, random star-shaped polygons, L-shaped blocks) between the start
(0, 0, heading 0) and a goal 8-11 m away, at least 1.6 m apart from each other and clear of
the start and the goal, in open space: the goal is always reachable around them. The
plan runs with its goal set by ``--set``-style overrides (``gx``, ``gy``); a run succeeds
when the plan ends by its goal interrupt. Everything is drawn from
``numpy.random.default_rng(seed)``: the same seed gives the same world.

>>> text, goal = generate_world(3)
>>> text == generate_world(3)[0] and 8.0 <= goal[0] <= 11.0
True
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["NavRun", "generate_world", "run_navigation", "run_study", "summary_rows",
           "PLAN", "ROBOTS"]

#: The plan the experiment runs by default: Bug2 with follow_boundary, from the
#: repository's top folder (the plans are not part of the installed package)
PLAN = Path("plans") / "nav" / "bug2.mdle"
#: The robots it runs on: the paper's ideal unicycle and the Pioneer 3-DX's timing.
ROBOTS = ("ideal", "pioneer-p3dx")
#: Least gap between two obstacles (their bounding discs), m: a Pioneer (0.5 m wide)
#: passes between them with room to spare
GAP = 1.6
#: How far the goal interrupt of the plans fires from the goal, m
GOAL_TOL = 0.3


@dataclass(frozen=True)
class NavRun:
    """One run: the world's seed, robot, outcome and figures (SI units)."""

    seed: int
    robot: str
    obstacles: int
    reached: bool
    collided: bool
    straight: float       # straight-line distance from start to goal, m
    path: float           # distance travelled, m
    time: float           # until the goal (or the end of the run), s
    min_clearance: float  # least gap between the robot's body and an obstacle, m
    ended: str            # how the run ended, in words


def _shape(rng: np.random.Generator, cx: float, cy: float) -> tuple[str, float]:
    """Return one obstacle as a YAML flow mapping, and the radius of a disc bounding it."""
    kind = int(rng.integers(5))
    angle = float(rng.uniform(0.0, 180.0))
    if kind == 0:
        r = float(rng.uniform(0.3, 0.9))
        return f"{{type: circle, center: [{cx:.3f}, {cy:.3f}], radius: {r:.3f}}}", r
    if kind == 1:
        w, h = (float(v) for v in rng.uniform(0.4, 1.8, 2))
        return (f"{{type: rectangle, center: [{cx:.3f}, {cy:.3f}], size: [{w:.3f}, {h:.3f}], "
                f"angle: {angle:.1f}}}", math.hypot(w, h) / 2)
    if kind == 2:
        a, b = (float(v) for v in rng.uniform(0.3, 1.0, 2))
        return (f"{{type: ellipse, center: [{cx:.3f}, {cy:.3f}], axes: [{a:.3f}, {b:.3f}], "
                f"angle: {angle:.1f}}}", max(a, b))
    if kind == 3:  # star-shaped: 5-9 vertices at random radii around the centre
        n = int(rng.integers(5, 10))
        # spread around the centre (jittered by under half a step): never crossing
        turns = (np.arange(n) + rng.uniform(-0.4, 0.4, n)) * (2 * math.pi / n)
        radii = rng.uniform(0.35, 1.0, n)
        pts = [(cx + r * math.cos(a), cy + r * math.sin(a)) for a, r in zip(turns, radii,
                                                                           strict=True)]
        return (f"{{type: polygon, points: [{', '.join(f'[{x:.3f}, {y:.3f}]' for x, y in pts)}]}}",
                float(radii.max()))
    # an L-shaped block, rotated
    s, t = float(rng.uniform(0.9, 1.6)), float(rng.uniform(0.35, 0.6))
    local = [(0, 0), (s, 0), (s, t), (t, t), (t, s), (0, s)]
    c, si = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    pts = [(cx + c * (x - s / 2) - si * (y - s / 2), cy + si * (x - s / 2) + c * (y - s / 2))
           for x, y in local]
    return (f"{{type: polygon, points: [{', '.join(f'[{x:.3f}, {y:.3f}]' for x, y in pts)}]}}",
            s / math.sqrt(2))


def generate_world(seed: int, robot: str = "ideal") -> tuple[str, tuple[float, float]]:
    """Return a cluttered world as YAML text, and its goal (x, y) in metres.

    The start is (0, 0) heading along +x, so the world frame is the odometry frame.
    """
    rng = np.random.default_rng(seed)
    gx, gy = float(rng.uniform(8.0, 11.0)), float(rng.uniform(-2.0, 2.0))
    count = int(rng.integers(3, 9))
    placed: list[tuple[float, float, float, str]] = []
    tries = 0
    while len(placed) < count:
        tries += 1
        if tries % 500 == 0:  # crowded out: place them all again (the draws go on)
            placed.clear()
        # about half of them on the way (near the straight line), the others anywhere
        u = float(rng.uniform(0.15, 0.85))
        if rng.random() < 0.5:
            cx, cy = u * gx, u * gy + float(rng.normal(0.0, 0.6))
        else:
            cx, cy = float(rng.uniform(1.0, gx + 1.0)), float(rng.uniform(-4.5, 4.5))
        text, r = _shape(rng, cx, cy)
        if (math.hypot(cx, cy) - r < 1.5 or math.hypot(cx - gx, cy - gy) - r < 1.2
                or any(math.hypot(cx - x, cy - y) - r - q < GAP for x, y, q, _ in placed)):
            continue
        placed.append((cx, cy, r, text))
    lines = [f"# navigation experiment, world {seed}: goal at ({gx:.3f}, {gy:.3f})",
             f"name: nav-{seed}", f"seed: {seed}", f"robot: {robot}", "start: [0, 0, 0]",
             "extent: [-2, -7, 14, 7]", "obstacles:"]
    lines += [f"  - {t}" for *_, t in placed]
    return "\n".join(lines) + "\n", (gx, gy)


def run_navigation(seed: int, robot: str = "ideal", plan: Path = PLAN, rate: float = 10.0
                   ) -> NavRun:
    """Run ``plan`` in world ``seed`` with ``robot``; its goal is set through ``gx``, ``gy``."""
    from mdle import sim
    from mdle.lang import load_program
    from mdle.runtime import Cause, ended_how, run_named
    from mdle.sim.world_yaml import parse_world

    text, (gx, gy) = generate_world(seed, robot)
    world = parse_world(text, f"nav-{seed}.world.yaml")
    program = load_program(plan, settings={"gx": f"{gx!r} m", "gy": f"{gy!r} m"})
    backend = sim.SimBackend(world, seed=seed)
    try:
        result = run_named(program, None, backend, rate=rate, until=900.0)
    finally:
        backend.close()
    # the goal interrupt is the one of the innermost string that repeats seek and hug
    goal_end = next((t for t in result.terminations
                     if t.cause is Cause.INTERRUPT and t.level == 1), None)
    reached = goal_end is not None and not result.collided
    obstacles = text.count("\n  - ")
    return NavRun(seed, robot, obstacles, reached, result.collided, math.hypot(gx, gy),
                  result.distance, goal_end.time if goal_end else result.duration,
                  result.min_clearance if result.min_clearance is not None else math.nan,
                  ended_how(result.termination.cause))


def _one(task: tuple[int, str, str, float]) -> NavRun:
    seed, robot, plan, rate = task
    return run_navigation(seed, robot, Path(plan), rate)


def run_study(seeds: Sequence[int], robots: Sequence[str] = ROBOTS, plan: Path = PLAN, *,
              rate: float = 10.0, jobs: int = 1,
              step: Callable[[NavRun], None] | None = None) -> list[NavRun]:
    """Run every (seed, robot) pair, on ``jobs`` processes; results in task order."""
    tasks = [(s, r, str(plan), rate) for r in robots for s in seeds]
    runs: list[NavRun] = []
    if jobs <= 1:
        for t in tasks:
            runs.append(_one(t))
            if step is not None:
                step(runs[-1])
        return runs
    import multiprocessing

    with multiprocessing.get_context("spawn").Pool(min(jobs, os.cpu_count() or 1)) as pool:
        for run in pool.imap(_one, tasks):
            runs.append(run)
            if step is not None:
                step(run)
    return runs


def summary_rows(runs: Sequence[NavRun]) -> list[tuple[str, ...]]:
    """One row per robot: runs, reached %, collisions, path / straight line, time, clearance."""
    rows: list[tuple[str, ...]] = []
    for robot in dict.fromkeys(r.robot for r in runs):
        mine = [r for r in runs if r.robot == robot]
        ok = [r for r in mine if r.reached]
        ratio = [r.path / r.straight for r in ok]
        rows.append((
            robot, str(len(mine)), f"{100.0 * len(ok) / len(mine):.1f}",
            str(sum(r.collided for r in mine)),
            f"{np.mean(ratio):.2f}" if ratio else "-",
            f"{np.max(ratio):.2f}" if ratio else "-",
            f"{np.mean([r.time for r in ok]):.0f}" if ok else "-",
            f"{np.min([r.min_clearance for r in mine]):.3f}",
        ))
    return rows


#: The columns of :func:`summary_rows`: (header, alignment)
COLUMNS = (("robot", "left"), ("worlds", "right"), ("reached (%)", "right"),
           ("collisions", "right"), ("path / straight line, mean", "right"),
           ("max", "right"), ("time to goal, mean (s)", "right"),
           ("least clearance (m)", "right"))
