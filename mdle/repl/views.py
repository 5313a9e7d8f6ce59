"""Text views for the REPL: a run's report, the scan, the map, the ticks of ``:step``.

Plain text only (no control codes), so the same lines serve a terminal, a pipe and a test.
Angles are shown in degrees, lengths in metres, times in seconds since the run started.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from mdle.atoms.registry import Context
from mdle.core.backend import Observation
from mdle.core.pose import Pose
from mdle.core.units import ANGLE, CURVATURE, NONE, TURN_RATE
from mdle.runtime.events import ended_how

if TYPE_CHECKING:
    import numpy as np

    from mdle.atoms.registry import Registry, Report
    from mdle.core.backend import RobotLimits
    from mdle.repl.reports import RunReport, StepRow
    from mdle.sim import World

__all__ = ["format_pose", "format_report", "format_scan", "format_step_rows", "law_reports",
           "render_map"]

#: Fewest rows of the map (a long, narrow world gets flatter cells rather than a sliver).
MIN_ROWS = 12
#: Sectors of the compact scan view, degrees wide.
SECTOR_DEG = 15.0


def _deg(a: float) -> float:
    d = math.degrees(math.atan2(math.sin(a), math.cos(a)))
    return 0.0 if abs(d) < 0.05 else d


def format_pose(p: Pose) -> str:
    """``x -4.95 m  y 0.30 m  heading 12.0 deg``."""
    return f"x {p.x:.2f} m  y {p.y:.2f} m  heading {_deg(p.theta):.1f} deg"


def format_report(report: RunReport) -> list[str]:
    """How a run ended (level, cause, time since it started), the pose, the distance."""
    r = report.result
    d = report.decisive
    root = r.termination
    lines = []
    how = f"{d.path} (level {d.level}) {ended_how(d.cause)} at {d.time - report.t0:.2f} s"
    if d is not root:
        how += f"; {root.path} {ended_how(root.cause)}"
    if report.interrupted:
        how += " (Ctrl-C: robot stopped)"
    elif report.limit is not None:
        how += (f" (the run limit of {report.limit:g} s; change it with "
                "`:set until SECONDS`)")
    lines.append(how)
    lines.append(f"  pose      {format_pose(report.pose)}")
    closest = ""
    if r.min_clearance is not None:
        closest = f", min clearance {r.min_clearance:.2f} m"
        if report.closest is not None:
            t, x, y = report.closest
            closest += f" (t = {t:.1f} s at x {x:.2f} m, y {y:.2f} m)"
    lines.append(f"  travelled {r.distance:.2f} m in {r.duration:.2f} s ({r.ticks} ticks)"
                 + closest)
    side = report.side
    if side is not None:
        lines.append(f"  boundary  {side.low:.2f}..{side.high:.2f} m from the side ray; last "
                     f"{side.window:.0f} s: mean {side.mean:.2f} m, sd {side.std:.3f} m")
    c = report.collision
    if c is not None:
        what = f"`{c.label}`" if c.label else "an obstacle"
        lines.append(f"  COLLIDED with {what} at x {c.x:.2f} m, y {c.y:.2f} m, "
                     f"t = {c.time - report.t0:.2f} s (`:reset` puts the robot back)")
    if r.fault:
        lines.append(f"  aborted: {r.fault}")
    return lines


def format_scan(obs: Observation, registry: Registry, limits: RobotLimits,
                rate: float = 10.0) -> list[str]:
    """Show the scan by sectors (nearest range in each) and the boundary estimates.

    The estimates are those the steering law and the sensor functions ``boundary_*`` read,
    on both sides.
    """
    import numpy as np

    from mdle.atoms.boundary import boundary_view

    scan = obs.scan
    if scan is None or len(scan.ranges) == 0:
        return ["no scan yet"]
    ranges = np.asarray(scan.ranges, dtype=float)
    bearings = np.asarray(scan.bearings, dtype=float)
    valid = np.asarray(scan.valid, dtype=bool) & np.isfinite(ranges)
    deg = np.degrees(bearings)
    lo = math.floor(deg.min() / SECTOR_DEG) * SECTOR_DEG
    edges = np.arange(lo, deg.max() + SECTOR_DEG, SECTOR_DEG)
    idx = np.clip(np.digitize(deg, edges) - 1, 0, len(edges) - 2)
    near = np.full(len(edges) - 1, np.inf)
    np.minimum.at(near, idx[valid], ranges[valid])
    lines = [f"scan at t = {scan.stamp:.2f} s: {len(ranges)} beams from {deg[0]:.0f} to "
             f"{deg[-1]:.0f} deg, {int(valid.sum())} returns, max range {scan.max_range:g} m"
             + (" (exact)" if scan.tangents is not None else "")]
    # right to left, as the beams are ordered
    head = "  ".join(f"{e:+5.0f}" for e in edges[:-1])
    body = "  ".join("    -" if not math.isfinite(v) else f"{v:5.2f}" for v in near)
    lines.append(f"  sector from (deg) {head}")
    lines.append(f"  nearest (m)       {body}")
    c = int(np.argmin(np.abs(bearings)))
    front = f"{ranges[c]:.2f} m" if valid[c] else f"none within {scan.max_range:g} m"
    if valid.any():
        i = int(np.argmin(np.where(valid, ranges, np.inf)))
        lines.append(f"  ahead {front}; nearest {ranges[i]:.2f} m at {deg[i]:.0f} deg")
    else:
        lines.append(f"  ahead {front}; nothing within range")
    ctx = Context(obs, 0.0, 1.0 / rate, limits, {})
    for side in ("right", "left"):
        args = {"side": side}
        sensors = registry.sensors
        view = boundary_view(scan, side)
        sgn = 1.0 if side == "right" else -1.0
        if "boundary_range" in sensors and view.side.hit:
            r = sensors["boundary_range"].fn(args, ctx)
            k = sensors["boundary_curvature"].fn(args, ctx)
            t = sensors["boundary_tangent"].fn(args, ctx)
            text = (f"boundary_range {r:.2f} m, boundary_tangent {_deg(float(t)):.1f} deg, "
                    f"boundary_curvature {k:+.3f} 1/m")
        else:
            text = "no boundary on the side ray"
        f = view.front
        front_text = (f"front ray {f.r:.2f} m, tangent {_deg(sgn * f.beta):.1f} deg, "
                      f"curvature {sgn * f.kappa:+.3f} 1/m" if f.hit else "front ray: no hit")
        lines.append(f"  {side:<5}: {text}; {front_text}")
    return lines


def format_step_rows(rows: Sequence[StepRow], t0: float,
                     reports: Mapping[str, Report] | None = None) -> list[str]:
    """Show one line per tick (time, active atom, command, pose, ranges).

    When the control law reported diagnostics, a second line shows them, with the units
    ``reports`` declares (see :func:`law_reports`).
    """
    out = []
    for row in rows:
        s = row.sample
        ranges = ""
        if row.front is not None:
            ranges = f"  ahead {row.front:.2f} m"
        if row.nearest is not None and row.nearest_bearing is not None:
            ranges += f"  nearest {row.nearest:.2f} m @ {math.degrees(row.nearest_bearing):.0f} deg"
        path = s.path or "(ended)"
        out.append(f"  #{row.tick:<4d} t {s.time - t0:6.2f} s  {path}  "
                   f"cmd v {s.cmd_v:+.3f} m/s  omega {s.cmd_omega:+.3f} rad/s  "
                   f"x {s.x:.2f} y {s.y:.2f} heading {_deg(s.theta):.1f} deg{ranges}")
        if s.diag:
            out.append("         " + _diag(s.diag, reports or {}))
    return out


def law_reports(registry: Registry) -> dict[str, Report]:
    """Return the diagnostics every control law of ``registry`` declares, by name."""
    out: dict[str, Report] = {}
    for law in registry.laws.values():
        for name, report in law.reports.items():
            out.setdefault(name, report)
    return out


def _diag(diag: Mapping[str, float], reports: Mapping[str, Report]) -> str:
    return "  ".join(f"{k} {_reported(v, reports.get(k))}" for k, v in diag.items())


def _reported(v: float, report: Report | None) -> str:
    """Show a diagnostic's value as read: with its unit, a flag as yes/no, a mode by name.

    Angles in degrees, turn rates in rad/s (as the command above), curvatures in 1/m.
    """
    if report is None:
        return f"{v:.3g}"
    if report.absent is not None and v == report.absent:
        return "none"
    if report.flag:
        return "yes" if v else "no"
    if report.codes and float(v).is_integer() and 0 <= int(v) < len(report.codes):
        return report.codes[int(v)]
    dim = report.dim
    if dim == ANGLE:
        return f"{math.degrees(v):.3g} deg"
    unit = {NONE: "", TURN_RATE: "rad/s", CURVATURE: "1/m"}.get(dim, dim.symbol())
    return f"{v:.3g} {unit}".rstrip()


def render_map(world: World, path: np.ndarray, pose: Pose, width: int = 72,
               height: int | None = None) -> list[str]:
    """Draw an ASCII map of the world.

    ``#`` obstacles, ``.`` the path, ``o`` where the path began, an arrow for the robot
    (``> ^ < v``, its heading to the nearest quarter).

    Parameters
    ----------
    world : sim.World
    path : (N, 2) float array, metres
        Positions since the last reset.
    pose : Pose
        The robot now.
    width : int
        Columns of the map; a cell is twice as tall as it is wide, as characters are.
    height : int, optional
        Rows; by default as many as keep the world's aspect ratio.
    """
    import numpy as np

    x0, y0, x1, y1 = world.bounds
    # keep the robot and the path on the map
    pts = np.vstack([np.asarray(path, dtype=float).reshape(-1, 2), [[pose.x, pose.y]]])
    x0, y0 = min(x0, float(pts[:, 0].min()) - 0.5), min(y0, float(pts[:, 1].min()) - 0.5)
    x1, y1 = max(x1, float(pts[:, 0].max()) + 0.5), max(y1, float(pts[:, 1].max()) + 0.5)
    cw = (x1 - x0) / width
    # cells twice as tall as wide (as characters are), but at least MIN_ROWS rows
    rows = height or max(MIN_ROWS, math.ceil((y1 - y0) / (2.0 * cw)))
    ch = (y1 - y0) / rows
    xs = x0 + (np.arange(width) + 0.5) * cw
    ys = y1 - (np.arange(rows) + 0.5) * ch  # top row first
    grid = np.full((rows, width), " ", dtype="<U1")
    if world.obstacles:
        # a cell is an obstacle when some point of it lies within half a column of one:
        # tall cells are probed at `sub` heights so thin walls along x are not missed
        sub = max(1, math.ceil(ch / cw))
        dy = (np.arange(sub) + 0.5) / sub * ch - 0.5 * ch
        gx, gy, gd = np.meshgrid(xs, ys, dy, indexing="ij")
        probes = np.column_stack([gx.ravel(), (gy + gd).ravel()])
        clear = np.asarray(world.clearance(probes, 0.0)).reshape(width, rows, sub)
        near = (clear <= 0.5 * max(cw, ch / sub)).any(axis=2).T
        grid[near] = "#"

    def cell(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c = np.clip(((x - x0) / cw).astype(int), 0, width - 1)
        r = np.clip(((y1 - y) / ch).astype(int), 0, rows - 1)
        return r, c

    if len(path):
        # dense enough that consecutive points land in touching cells
        p = np.asarray(path, dtype=float).reshape(-1, 2)
        d = np.diff(p, axis=0)
        # points every half cell along each segment: segment i gets n_i points at
        # fractions 1/n_i .. 1 of the way
        n = np.maximum(1, np.ceil(np.hypot(d[:, 0], d[:, 1]) / (0.5 * min(cw, ch)))
                       ).astype(int)
        seg = np.repeat(np.arange(len(d)), n)
        k = np.arange(seg.size) - np.repeat(np.cumsum(n) - n, n) + 1
        q = np.vstack([p[:1], p[seg] + d[seg] * (k / n[seg])[:, None]])
        r, c = cell(q[:, 0], q[:, 1])
        grid[r, c] = "."
        r, c = cell(p[:1, 0], p[:1, 1])
        grid[r, c] = "o"
    arrow = ">^<v"[round(math.atan2(math.sin(pose.theta), math.cos(pose.theta))
                         / (math.pi / 2)) % 4]
    r, c = cell(np.array([pose.x]), np.array([pose.y]))
    grid[r, c] = arrow
    border = "+" + "-" * width + "+"
    lines = [border] + ["|" + "".join(row) + "|" for row in grid] + [border]
    lines.append(f"x {x0:.1f}..{x1:.1f} m, y {y0:.1f}..{y1:.1f} m; a cell is {cw:.2f} m wide, "
                 f"{ch:.2f} m tall. "
                 f"# obstacle  . path  o path start  {arrow} robot ({format_pose(pose)})")
    return lines
