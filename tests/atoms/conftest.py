"""Catalogue of canonical scans for the atoms tests (analytic ray casts, no simulator).

Every scan is an LMS-200-like sweep: 181 beams from -90 to +90 degrees (index 0 on the
robot's right), maximum range 10 m, beams with no return at max range and ``valid=False``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from mdle import sim
from mdle.core.backend import Scan
from mdle.core.pose import Pose
from mdle.experiments.generated import RunSpec, StudyConfig, plan_text, study_specs
from mdle.lang import load_text
from mdle.runtime import Recorder, run, run_named
from mdle.sim.generated import generate_shape
from mdle.sim.profiles import robot_profile
from mdle.sweep.engagement import follow_metrics

MAX_RANGE = 10.0
BEARINGS: np.ndarray = np.radians(np.arange(-90.0, 90.5, 1.0))


def cast_circle(center: tuple[float, float], radius: float,
                bearings: np.ndarray = BEARINGS) -> np.ndarray:
    """Cast rays from the origin at a circle: range per bearing (inf where the ray misses)."""
    d = np.stack((np.cos(bearings), np.sin(bearings)), axis=1)
    c = np.asarray(center, dtype=float)
    b = d @ c
    disc = b * b - (c @ c - radius * radius)
    r = b - np.sqrt(np.where(disc >= 0, disc, np.nan))
    return np.where((disc >= 0) & (r > 0), r, np.inf)


def cast_line(point: tuple[float, float], normal: tuple[float, float],
              bearings: np.ndarray = BEARINGS) -> np.ndarray:
    """Cast rays at the line through ``point`` with ``normal`` (inf where parallel/behind)."""
    n = np.asarray(normal, dtype=float)
    d = np.stack((np.cos(bearings), np.sin(bearings)), axis=1)
    den = d @ n
    with np.errstate(divide="ignore"):
        r = (np.asarray(point, dtype=float) @ n) / den
    return np.where((den != 0) & (r > 0), r, np.inf)


def make_scan(ranges: np.ndarray, bearings: np.ndarray = BEARINGS,
              max_range: float = MAX_RANGE) -> Scan:
    """Build a Scan from ranges (inf/NaN or beyond max range: no return)."""
    r = np.asarray(ranges, dtype=float)
    valid = np.isfinite(r) & (r < max_range)
    return Scan(np.where(valid, r, max_range), np.asarray(bearings, dtype=float), valid, 0.0,
                max_range)


@dataclass(frozen=True)
class Case:
    """A catalogue entry: the scan and what the truth is where the estimate is defined."""

    name: str
    scan: Scan
    # truth per beam index; None: no beam valid
    curvature: Callable[[np.ndarray], np.ndarray] | None
    min_valid: int  # beams at least this many must be valid for a 1-beam window


def _zero(idx: np.ndarray) -> np.ndarray:
    return np.zeros(idx.shape)


def _catalogue() -> dict[str, Case]:
    empty = Scan(np.zeros(0), np.zeros(0), np.zeros(0, bool), 0.0, MAX_RANGE)
    invalid = Scan(np.full(181, np.nan), BEARINGS, np.zeros(181, bool), 0.0, MAX_RANGE)
    at_max = make_scan(np.full(181, MAX_RANGE))
    wall = make_scan(cast_line((0.0, -0.5), (0.0, -1.0)))          # wall on the right, y = -0.5
    circle = make_scan(cast_circle((2.0, 0.0), 1.0))                # R = 1 m, 1 m ahead
    corner_r = np.minimum(cast_line((1.5, 0.0), (1.0, 0.0)), cast_line((0.0, -0.8), (0.0, -1.0)))
    corner = make_scan(corner_r)                                     # concave right-angle corner
    return {
        "empty": Case("empty", empty, None, 0),
        "all_invalid": Case("all_invalid", invalid, None, 0),
        "all_max_range": Case("all_max_range", at_max, None, 0),
        "straight_wall": Case("straight_wall", wall, _zero, 80),
        "circle_R1": Case("circle_R1", circle, lambda idx: np.full(idx.shape, -1.0), 50),
        "right_angle_corner": Case("right_angle_corner", corner, _zero, 150),
    }


CATALOGUE = _catalogue()


@pytest.fixture(params=sorted(CATALOGUE))
def case(request: pytest.FixtureRequest) -> Case:
    """Give each catalogue scan in turn."""
    return CATALOGUE[request.param]


class Raycast:
    """The analytic ray-cast helpers, for tests that build their own scans."""

    circle = staticmethod(cast_circle)
    line = staticmethod(cast_line)
    scan = staticmethod(make_scan)
    bearings: np.ndarray = BEARINGS
    max_range: float = MAX_RANGE
    catalogue: dict[str, Case] = CATALOGUE


@pytest.fixture
def raycast() -> Raycast:
    """Provide the analytic ray-cast helpers, for tests that build their own scans."""
    return Raycast()


# ---- a tiny exact world for closed-loop tests of the law (no simulator needed) --------------

class Shape:
    """An obstacle as a shapely geometry with exact ray hits (range, tangent, curvature).

    Polygons are given counter-clockwise; tangents returned are oriented with the obstacle on
    the right (clockwise), curvature signed so convex is negative, as control-law.md wants.
    """

    def __init__(self, kind: str, **kw: Any) -> None:
        import shapely

        self.kind = kind
        self.kw = kw
        if kind == "circle":
            self.geom = shapely.Point(*kw["center"]).buffer(kw["radius"], quad_segs=256)
        else:
            self.geom = shapely.Polygon(kw["vertices"])
        shapely.prepare(self.geom)

    def cast(self, x: float, y: float, theta: float, bearings: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cast the beams: ranges (inf: miss), robot-frame tangent angles and curvatures."""
        ang = theta + bearings
        d = np.stack((np.cos(ang), np.sin(ang)), axis=1)
        if self.kind == "circle":
            c = np.asarray(self.kw["center"], float) - (x, y)
            rad = self.kw["radius"]
            b = d @ c
            disc = b * b - (c @ c - rad * rad)
            r = b - np.sqrt(np.where(disc >= 0, disc, 0.0))
            r = np.where((disc >= 0) & (r > 0), r, np.inf)
            h = np.array([x, y]) + d * np.where(np.isfinite(r), r, 0.0)[:, None]
            n = (h - np.asarray(self.kw["center"])) / rad
            tang = np.arctan2(-n[:, 0], n[:, 1])
            kap = np.full(r.shape, -1.0 / rad)
        else:
            v = np.asarray(self.kw["vertices"], float)
            a, bb = v, np.roll(v, -1, axis=0)
            e = bb - a                                              # (S, 2), CCW edges
            w = a - (x, y)
            den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / den
                s = (w[None, :, 0] * d[:, None, 1] - w[None, :, 1] * d[:, None, 0]) / den
            ok = (den != 0) & (t > 1e-9) & (s >= 0) & (s <= 1)
            t = np.where(ok, t, np.inf)
            j = np.argmin(t, axis=1)
            r = t[np.arange(len(j)), j]
            tang = np.arctan2(-e[j, 1], -e[j, 0])                   # reversed CCW edge
            kap = np.zeros(r.shape)
        rel = np.arctan2(np.sin(tang - theta), np.cos(tang - theta))
        hit = np.isfinite(r)
        return r, np.where(hit, rel, np.nan), np.where(hit, kap, np.nan)

    def clearance(self, x: float, y: float) -> float:
        import shapely

        p = shapely.Point(x, y)
        dist = float(self.geom.exterior.distance(p))
        return -dist if self.geom.contains(p) else dist


def oracle_scan(shape: Shape, x: float, y: float, theta: float, *, exact: bool = True,
                noise: float = 0.0, rng: np.random.Generator | None = None) -> Scan:
    """Scan ``shape`` from the pose with 181 beams; exact adds oracle tangents/curvatures."""
    r, tang, kap = shape.cast(x, y, theta, BEARINGS)
    if noise > 0 and rng is not None:
        r = r * (1.0 + rng.normal(0.0, noise, r.shape))
    valid = np.isfinite(r) & (r < MAX_RANGE)
    return Scan(np.where(valid, r, MAX_RANGE), BEARINGS, valid, 0.0, MAX_RANGE,
                tang if exact else None, kap if exact else None)


@dataclass
class LoopResult:
    """Trajectory of a closed-loop run: times, poses and true clearance per step."""

    t: np.ndarray
    xy: np.ndarray
    clearance: np.ndarray
    modes: list[float]


def closed_loop(shape: Shape, args: dict[str, Any], pose: tuple[float, float, float], *,
                duration: float, dt: float, exact: bool = True, noise: float = 0.0,
                seed: int = 0, umax: float = 3.0, radius: float = 0.0) -> LoopResult:
    """Run the real ``follow_boundary`` atom against ``shape`` with exact unicycle arcs."""
    from mdle.atoms.follow import follow_boundary, start_follow
    from mdle.atoms.registry import Context
    from mdle.core.backend import Observation, RobotLimits
    from mdle.core.pose import Pose

    limits = RobotLimits(1.0, 0.0, umax, radius=radius)
    rng = np.random.default_rng(seed)
    x, y, th = pose
    ts, xs, cl, modes = [], [], [], []
    state = None
    for i in range(int(round(duration / dt))):
        t = i * dt
        obs = Observation(t, Pose(x, y, th), scan=oracle_scan(shape, x, y, th, exact=exact,
                                                              noise=noise, rng=rng))
        ctx = Context(obs, t, dt, limits)
        if state is None:
            state = start_follow(args, ctx)
        cmd = follow_boundary(args, ctx, state)
        v, u = cmd.v, max(-umax, min(umax, cmd.omega))
        if abs(u) > 1e-9:
            x += v / u * (np.sin(th + u * dt) - np.sin(th))
            y += v / u * (np.cos(th) - np.cos(th + u * dt))
        else:
            x += v * dt * np.cos(th)
            y += v * dt * np.sin(th)
        th = float(np.arctan2(np.sin(th + u * dt), np.cos(th + u * dt)))
        ts.append(t + dt)
        xs.append((x, y))
        cl.append(shape.clearance(x, y))
        modes.append(ctx.cache["trace"]["mode"])
    return LoopResult(np.array(ts), np.array(xs), np.array(cl), modes)


class World2D:
    """Exact shapes and the closed-loop runner for law tests."""

    Shape = Shape
    scan = staticmethod(oracle_scan)
    run = staticmethod(closed_loop)


@pytest.fixture
def world2d() -> World2D:
    """Provide exact shapes and the closed-loop runner for law tests."""
    return World2D()


def follow_run(world: Any, seconds: float, rate: float = 50.0, extra: str = ""
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Follow ``world``'s obstacle on the right (rc 0.5 m, 1 m/s, noisy scan, seed 2).

    ``extra``: more ``follow_boundary`` arguments (", model = rays"). Returns the samples'
    times, true positions and clearances.
    """
    program = load_text(f"atom f = (follow_boundary(side = right, rc = 0.5 m, v = 1 m/s{extra}),"
                        f" never, {seconds} s)\nrun f\n")
    rec = Recorder()
    run(program.elements["f"], sim.SimBackend(world, seed=2, sensing="scan"), rate=rate,
        observers=[rec])
    t = np.array([s.time for s in rec.samples])
    xy = np.array([(s.true_x, s.true_y) for s in rec.samples])
    d = np.array([s.clearance for s in rec.samples], dtype=float)
    return t, xy, d


def p3dx_lab_run(side: str, index: int, start: int, seed: int = 0
                 ) -> tuple[RunSpec, np.ndarray, bool, float]:
    """Run one collision-course start of the P3-DX lab study (shapes of ``seed``, ``index``).

    Returns the run's spec, its measured turn rates, whether it engaged and its
    second-half mean |d - rc|.
    """
    cfg = StudyConfig(shapes=index + 1, starts=start + 1, seed=seed, suite="lab",
                      robot="pioneer-p3dx", v=0.3, rc=0.55, kf=2.0, rate=10.0, side=side)
    spec = next(s for s in study_specs(cfg) if s.shape_index == index and s.start == start)
    shape = generate_shape(spec.shape_seed, spec.shape_index, spec.family)
    world = shape.world(Pose(spec.x0, spec.y0, spec.theta0), robot_profile(spec.robot))
    program = load_text(plan_text(spec.side, spec.rc, spec.v, spec.kf, spec.duration))
    backend = sim.SimBackend(world, seed=spec.sim_seed, robot=spec.robot, sensing=spec.sensing)
    rec = Recorder()
    result = run_named(program, "f", backend, rate=spec.rate, observers=[rec])
    assert not result.collided
    s = rec.samples
    pose = np.array([(x.true_x, x.true_y, x.true_theta) for x in s])
    near = world.nearest_boundary(pose[:, :2])
    m = follow_metrics(np.array([x.time for x in s]), pose[:, 0], pose[:, 1], pose[:, 2],
                       np.asarray(near.distance), np.asarray(near.point),
                       np.array([x.clearance for x in s]), collided=False, side=side,
                       rc=spec.rc)
    return spec, np.array([x.omega for x in s]), m.engaged, m.mean_err
