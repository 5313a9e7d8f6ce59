"""Runs of a study: one :class:`RunTask` per combination, keyed by a hash of its content.

A task is plain picklable data (texts, numbers): it runs the same in this process, in a
local worker process or on a Dask worker on another machine. Its :attr:`RunTask.key`
hashes everything that decides the run's outcome (plan and import texts, parameter
values, world text, robot profile, sensing, rate, seed, start pose, duration, the trace
fields asked for), never a path or a label, so a results table can be resumed by key.
"""

from __future__ import annotations

import hashlib
import itertools
import math
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from mdle.sweep.keys import canonical
from mdle.sweep.spec import SpecError, StartRule, Study, WorldChoice

__all__ = ["RunTask", "expand", "start_poses"]

#: Bumped when the metrics a run computes change meaning (old tables then rerun).
METRICS_VERSION = 2


@dataclass(frozen=True)
class RunTask:
    """One run: everything a worker needs, as text and numbers.

    ``pose`` is the start (x, y, theta in m, m, rad), None for the world's start;
    ``robot`` a profile name or mapping (None: the world's); ``settings`` the plan
    parameter values (``NAME -> value text``); ``until`` the longest run, s (None: until
    the plan ends). ``labels`` name the world, robot and plan for tables.
    """

    plan_text: str
    plan_files: tuple[tuple[str, str], ...]
    entry: str | None
    settings: tuple[tuple[str, str], ...]
    world_text: str
    robot: str | dict[str, Any] | None
    sensing: str
    rate: float
    seed: int
    pose: tuple[float, float, float] | None
    until: float | None
    trace_fields: tuple[str, ...] = ()
    keep_trace: bool = False
    index: int = 0
    labels: dict[str, str] = field(default_factory=dict, compare=False)
    attempt: int = 0

    @property
    def key(self) -> str:
        """Return the hash of the run's content (hex, 20 characters)."""
        content = [METRICS_VERSION, self.plan_text, list(self.plan_files), self.entry,
                   sorted(self.settings), self.world_text, self.robot, self.sensing,
                   float(self.rate), self.seed,
                   None if self.pose is None else [float(x) for x in self.pose],
                   self.until, list(self.trace_fields)]
        return hashlib.sha256(canonical(content).encode()).hexdigest()[:20]

    def row(self) -> dict[str, Any]:
        """Return the columns that describe the run (known before it runs)."""
        pose = self.pose
        row: dict[str, Any] = {
            "key": self.key, "index": self.index, "plan": self.labels.get("plan", ""),
            "entry": self.entry or "", "world": self.labels.get("world", ""),
            "robot": self.labels.get("robot", ""), "sensing": self.sensing, "rate": self.rate,
            "seed": self.seed,
            "x0": None if pose is None else pose[0], "y0": None if pose is None else pose[1],
            "theta0": None if pose is None else math.degrees(pose[2]),
        }
        for name, value in self.settings:
            row[f"param_{name}"] = value
        return row


def expand(study: Study) -> Iterator[RunTask]:
    """Yield the study's runs in a fixed order (worlds outermost, seeds innermost).

    Raises
    ------
    SpecError
        Random starts that the rules cannot place in a world.
    """
    index = 0
    for world in study.worlds:
        poses = start_poses(study.starts, world)
        for robot, sensing, rate, params, pose, seed in itertools.product(
                study.robots, study.sensing, study.rates, study.parameters, poses,
                study.seeds):
            labels = {"plan": study.plan_label, "world": world.label, "robot": robot.label}
            yield RunTask(study.plan_text, study.plan_files, study.entry, params, world.text,
                          robot.value, sensing, rate, seed, pose, study.duration,
                          study.trace_fields, study.keep_traces, index, labels)
            index += 1


def start_poses(rule: StartRule, world: WorldChoice
                ) -> list[tuple[float, float, float] | None]:
    """Return the start poses a rule gives in a world (None: the world's own start).

    Random starts are drawn from a generator seeded by the rule's seed and the world's
    name, so adding a world to a study leaves the others' starts unchanged.

    Raises
    ------
    SpecError
        The rules cannot be met in this world (no obstacle, or no place found).
    """
    if rule.kind == "world":
        return [None]
    if rule.kind in ("fixed", "grid"):
        return list(rule.poses)
    return list(_random_poses(rule, world))


def _random_poses(rule: StartRule, choice: WorldChoice) -> list[tuple[float, float, float]]:
    import numpy as np

    from mdle.sweep.worlds import build_world

    world = build_world(choice.text, choice.label)
    if not world.obstacles:
        raise SpecError(f"starts.random: world `{choice.label}` has no obstacle to start "
                        "near or head for")
    rng = np.random.default_rng([rule.seed, zlib.crc32(world.name.encode())])
    radius = world.robot.radius
    lo, hi = rule.distance
    centre = world.geometry.centroid
    cx, cy = float(centre.x), float(centre.y)
    xmin, ymin, xmax, ymax = world.geometry.bounds
    out: list[tuple[float, float, float]] = []
    batch = 256
    for _ in range(400):      # bounded: rules no place can meet end with a message
        if rule.origin == "centre":
            bearing = rng.uniform(-math.pi, math.pi, batch)
            dist = rng.uniform(lo, hi, batch)
            xy = np.column_stack((cx + dist * np.cos(bearing), cy + dist * np.sin(bearing)))
            ok = np.ones(batch, dtype=bool)
        else:
            xy = np.column_stack((rng.uniform(xmin - hi, xmax + hi, batch),
                                  rng.uniform(ymin - hi, ymax + hi, batch)))
            d = np.asarray(world.nearest_boundary(xy).distance)
            ok = (d >= lo) & (d <= hi)
        ok &= ~np.asarray(world.inside(xy)) & (np.asarray(world.clearance(xy, radius)) > 0.0)
        for x, y in xy[ok]:
            th = _heading(rule, world, float(x), float(y), cx, cy, rng)
            if th is not None:
                out.append((float(x), float(y), th))
                if len(out) == rule.count:
                    return out
    raise SpecError(f"starts.random: found only {len(out)} of {rule.count} starts in world "
                    f"`{choice.label}` that meet the rules (distance {lo:g}-{hi:g} m from the "
                    f"{rule.origin}, heading {rule.heading}); widen the distance range")


def _heading(rule: StartRule, world: Any, x: float, y: float, cx: float, cy: float,
             rng: Any) -> float | None:
    """Draw a heading for a start at (x, y), or None when the rules reject the place."""
    import numpy as np

    if rule.heading == "any":
        return float(rng.uniform(-math.pi, math.pi))
    if rule.origin == "centre":
        tx, ty = cx, cy
    else:
        tx, ty = (float(c) for c in world.nearest_boundary((x, y)).point)
    aim = math.atan2(ty - y, tx - x)
    for _ in range(8):
        th = aim + float(rng.uniform(-rule.spread, rule.spread))
        if bool(world.cast((x, y), np.array([th]), 1e4).hit[0]):
            return math.atan2(math.sin(th), math.cos(th))
    return None
