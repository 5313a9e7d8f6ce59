"""Plots of a run from its trace, as the seed paper draws them (Figures 1-3, 6-9).

The top panel is the path in the plane with the obstacles (from the world; doors in wood
colour), the boundary points the robot detected (on the side it followed), the robot's
body and heading at even steps along the path, the path coloured by the atom that was
running and every element's end marked by its cause; the legend sits beside the panel.
A scene much wider than tall (a corridor) has its y axis stretched, and says so. The
bottom panel, when the steering law recorded it, is the measured boundary curvature
against the distance travelled, beside the truth (:mod:`mdle.view.plot_curvature`).
matplotlib is used headless (the Agg canvas, no pyplot state), so this works on a
machine with no display; :mod:`mdle.view.figure_output` opens a window when there is one.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from mdle.core.errors import Diagnostic, MdleError
from mdle.core.ranges import COORDINATE
from mdle.record.load import read_trace
from mdle.record.trace import Trace
from mdle.runtime.events import Cause, ended_how
from mdle.view.figure_output import PlotError, save_figure
from mdle.view.plot_curvature import (
    CURVATURE_KEYS,
    draw_curvature,
    ladar_mount,
    measured_curvature,
    true_curvature,
)

if TYPE_CHECKING:
    import numpy as np
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["plot_trace", "trace_figure", "boundary_points", "CURVATURE_KEYS",
           "run_pose", "robot_radius", "draw_world", "world_of", "trace_and_world",
           "draw_footprints", "CAUSE_WORDS"]

#: Marker, colour, size and drawing order of an element's end, by cause: the larger marks
#: are drawn first, so an atom's "timer" stays visible inside its string's "completed".
_CAUSE_STYLE = {
    "completed": ("s", "tab:green", 13, 4.0),
    "stopped": ("D", "tab:orange", 11, 4.1),
    "interrupt": ("x", "black", 8, 4.3),
    "timer": ("o", "dimgray", 6, 4.4),
    "error": ("X", "tab:red", 9, 4.5),
}
#: Legend words for the causes ("ended by completed" reads badly).
CAUSE_WORDS = {
    "completed": "string finished",
    "stopped": "stopped from outside",
    "interrupt": "interrupt fired",
    "timer": "timer ran out",
    "error": "aborted by an error",
    "ended-by-parent": "ended with its parent",
}
_CAUSES = frozenset(c.value for c in Cause)
#: A scene narrower than this (height / width) has its y axis stretched up to it.
_MIN_ASPECT = 0.3
#: Robot footprints drawn along the path.
_FOOTPRINTS = 12


def run_pose(trace: Trace, world: Any = None) -> "tuple[np.ndarray, np.ndarray, np.ndarray, bool]":
    """Return the pose to draw (x, y, theta arrays) and whether it is the ground truth.

    With a world and a true pose in every sample, where the robot really was; otherwise
    its odometry.
    """
    import numpy as np

    tx = trace.column("true_x")
    if world is not None and bool(np.isfinite(tx).all()):
        th = trace.column("true_theta")
        if not np.isfinite(th).all():
            th = trace.column("theta")
        return *_placeable(tx, trace.column("true_y")), th, True
    return *_placeable(trace.column("x"), trace.column("y")), trace.column("theta"), False


def _placeable(x: "np.ndarray", y: "np.ndarray") -> "tuple[np.ndarray, np.ndarray]":
    """Return ``x, y`` with NaN where a position lies beyond any world's coordinates.

    A damaged trace's 1e308 m would overflow the figure's arithmetic (a NaN extent, numpy
    warnings on the user's terminal); such a sample is drawn as one with no position.
    """
    import numpy as np

    with np.errstate(invalid="ignore"):  # NaN compares False, and stays NaN
        far = (np.abs(x) > COORDINATE.high) | (np.abs(y) > COORDINATE.high)
    return np.where(far, np.nan, x), np.where(far, np.nan, y)


def robot_radius(trace: Trace, world: Any = None) -> float:
    """Return the robot's body radius (m): its profile in the trace, else the world's, else 0."""
    name = trace.header.get("robot")
    if isinstance(name, str) and name:
        try:
            from mdle.sim.profiles import robot_profile

            return float(robot_profile(name).radius)
        except (MdleError, OSError, ValueError):
            pass
    robot = getattr(world, "robot", None)
    return float(getattr(robot, "radius", 0.0) or 0.0)


def boundary_points(trace: Trace, pose: "tuple[np.ndarray, np.ndarray, np.ndarray] | None"
                    = None, truth: bool = False) -> "np.ndarray":
    """Points (K, 2) of the boundary the law saw beside the robot, in the frame of ``pose``.

    From each sample whose diagnostics have a side range (``side_range``, with
    ``side_hit`` when given): the point at that range from the ladar, on the side the
    trace's ``side_bearing`` names (rad, robot frame: -pi/2 right, +pi/2 left; the right
    when not recorded). ``pose`` (x, y, theta arrays) is the path as drawn; without it the
    odometry (the plan's frame), or with ``truth`` the simulator's true pose.
    """
    import numpy as np


    r = trace.column("diag.side_range")
    if not np.isfinite(r).any():
        return np.zeros((0, 2))
    hit = trace.column("diag.side_hit")
    bearing = trace.column("diag.side_bearing")
    bearing = np.where(np.isfinite(bearing), bearing, -math.pi / 2)
    ok = np.isfinite(r) & (r > 0) & ((hit > 0.5) | np.isnan(hit))
    if pose is None:
        names = ("true_x", "true_y", "true_theta") if truth else ("x", "y", "theta")
        pose = (trace.column(names[0]), trace.column(names[1]), trace.column(names[2]))
    x, y, th = pose
    mx, my, mth = ladar_mount(trace)
    c, s = np.cos(th), np.sin(th)
    a = th + mth + bearing
    pts = np.column_stack([x + c * mx - s * my + r * np.cos(a),
                           y + s * mx + c * my + r * np.sin(a)])
    return pts[ok]


def draw_world(ax: "Axes", world: Any) -> None:
    """Draw a world's obstacles (grey; doors, named ``door...``, in wood colour)."""
    obstacles = getattr(world, "obstacles", None)
    if obstacles:
        door_shown = False
        for o in obstacles:
            door = str(getattr(o, "name", "") or "").lower().startswith("door")
            label = "door" if door and not door_shown else None
            door_shown = door_shown or door
            _draw_geometry(ax, o.geometry(), "#c8a165" if door else "0.82",
                           "#7a5521" if door else "0.35", label)
    else:
        _draw_geometry(ax, world.geometry, "0.82", "0.35", None)


def _draw_geometry(ax: "Axes", geometry: Any, face: str, edge: str, label: str | None) -> None:
    import shapely
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path as MplPath

    for part in shapely.get_parts(geometry):
        for g in shapely.get_parts(part):  # nested collections
            kind = g.geom_type
            if kind == "Polygon":
                rings = [g.exterior, *g.interiors]
                verts, codes = [], []
                for ring in rings:
                    xy = list(ring.coords)
                    verts += xy
                    codes += [MplPath.MOVETO] + [MplPath.LINETO] * (len(xy) - 2) + \
                        [MplPath.CLOSEPOLY]
                ax.add_patch(PathPatch(MplPath(verts, codes), facecolor=face,
                                       edgecolor=edge, lw=0.8, zorder=1, label=label))
            elif kind in ("LineString", "LinearRing"):
                x, y = g.xy
                ax.plot(x, y, color=edge, lw=1.5, zorder=1, label=label)
            elif kind == "Point":
                ax.plot([g.x], [g.y], ".", color=edge, zorder=1, label=label)
            label = None


def _segments_by_atom(x: "np.ndarray", y: "np.ndarray", paths: Sequence[str]
                      ) -> dict[str, "np.ndarray"]:
    """Path segments (S, 2, 2) grouped by the label of the atom running at their start."""
    import numpy as np

    labels = np.array([p.rpartition("/")[2] for p in paths], dtype=object)
    seg = np.stack([np.column_stack([x[:-1], y[:-1]]), np.column_stack([x[1:], y[1:]])],
                   axis=1)
    out: dict[str, np.ndarray] = {}
    for label in dict.fromkeys(labels[:-1]):
        if label:
            out[str(label)] = seg[labels[:-1] == label]
    return out


def draw_footprints(ax: "Axes", x: "np.ndarray", y: "np.ndarray", th: "np.ndarray",
                    radius: float, colour: str = "0.15", n: int = _FOOTPRINTS) -> None:
    """Draw the robot's body and heading at ``n`` places evenly spread along its path.

    A body of radius 0 (the paper's point unicycle) is drawn as a heading arrow only.
    """
    import numpy as np
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle

    from mdle.sweep.metrics import path_length

    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(th)
    if ok.sum() < 2:
        return
    xs, ys, ts = x[ok], y[ok], th[ok]
    s = path_length(xs, ys)
    if s[-1] <= 0:
        return
    idx = np.unique(np.searchsorted(s, np.linspace(0.0, s[-1], n + 1)[1:], side="left")
                    .clip(0, len(s) - 1))
    length = max(2.0 * radius, 0.02 * float(np.ptp(xs) + np.ptp(ys)) / 2 + 0.15)
    if radius > 0:
        ax.add_collection(PatchCollection(
            [Circle((xs[i], ys[i]), radius) for i in idx], facecolor="none",
            edgecolor=colour, lw=0.8, alpha=0.7, zorder=3.5))
    ax.quiver(xs[idx], ys[idx], length * np.cos(ts[idx]), length * np.sin(ts[idx]),
              angles="xy", scale_units="xy", scale=1.0, color=colour, width=0.003,
              headwidth=4.0, headlength=5.0, zorder=3.6)
    # a legend entry that looks like the marks (a quiver's own is a filled box)
    ax.plot([], [], marker="$\\odot$" if radius > 0 else "$\\rightarrow$", ms=10, ls="none",
            color=colour, label=(f"robot and heading, every {s[-1] / n:.1f} m" if radius > 0
                                 else f"heading, every {s[-1] / n:.1f} m"))


def trace_figure(trace: Trace, world: Any = None, title: str | None = None) -> "Figure":
    """Return the figure for ``trace`` (see the module docstring); ``world`` a sim.World."""
    import numpy as np
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    from mdle.sweep.metrics import path_length
    from mdle.view.plot_nearest import (
        draw_nearest_curvature,
        is_nearest_point_trace,
        nearest_measured,
        nearest_truth,
    )

    if not trace.samples:
        raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no samples to plot"))
    x, y, th, use_truth = run_pose(trace, world)
    placed = np.flatnonzero(np.isfinite(x) & np.isfinite(y))
    if not len(placed):
        raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no sample with a finite "
                                         "position (x, y) to plot"))
    curv = measured_curvature(trace)
    pts = boundary_points(trace, (x, y, th))
    (x0, x1), (y0, y1) = _extent(x, y, pts, world)
    stretch = max(1.0, _MIN_ASPECT * (x1 - x0) / (y1 - y0))
    # the path panel takes the shape of the scene (a long corridor makes a wide, low panel)
    width = 9.5
    path_h = float(np.clip(7.0 * stretch * (y1 - y0) / (x1 - x0) + 1.2, 3.2, 7.5))
    curv_h = 2.9 if curv else 0.0
    fig = Figure(figsize=(width, path_h + curv_h), layout="constrained")
    if curv:
        ax, axk = fig.subplots(2, 1, height_ratios=[path_h, curv_h])
    else:
        ax, axk = fig.subplots(1, 1), None

    if world is not None:
        draw_world(ax, world)
    if len(pts):
        ax.plot(pts[:, 0], pts[:, 1], ".", ms=2.0, color="tab:brown", alpha=0.6, zorder=2,
                label="detected boundary")

    colours = [f"C{i}" for i in range(10)]
    for i, (label, seg) in enumerate(_segments_by_atom(x, y, trace.paths()).items()):
        ax.add_collection(LineCollection(list(seg), colors=colours[i % 10], lw=2.0, zorder=3,
                                         label=f"atom {label}"))
    draw_footprints(ax, x, y, th, robot_radius(trace, world))
    i0 = int(placed[0])
    heading = float(th[i0]) if math.isfinite(float(th[i0])) else 0.0
    ax.plot([x[i0]], [y[i0]], marker=(3, 0, math.degrees(heading) - 90),
            ms=11, color="k", ls="none", zorder=5, label="start")

    _mark_events(ax, trace.events, use_truth, trace)
    _mark_collisions(ax, trace, x, y)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect(stretch, adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)" if stretch == 1.0 else f"y (m, drawn {stretch:.1f}x taller)")
    ax.grid(True, lw=0.3, alpha=0.5)
    # the legend goes beside the panel, never over the path
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              fontsize="small")
    ax.set_title(title or _title(trace), fontsize="medium")

    if curv and axk is not None:
        ox, oy = trace.column("x"), trace.column("y")
        exact = str(trace.header.get("sensing") or "") == "exact"
        nearest = nearest_measured(trace) if is_nearest_point_trace(trace) else None
        if nearest is not None:  # the whole-scan model: the nearest point's curvature
            draw_nearest_curvature(axk, path_length(ox, oy), nearest,
                                   nearest_truth(trace, world), exact)
        else:
            draw_curvature(axk, path_length(ox, oy), curv, true_curvature(trace, world), exact)
    # one layout pass now: constrained layout converges over two passes when a panel has a
    # fixed aspect, and a single pass at save time cut the curvature panel's y label
    fig.draw_without_rendering()
    return fig


def _mark_collisions(ax: "Axes", trace: Trace, x: "np.ndarray", y: "np.ndarray") -> None:
    """Mark each contact (a red star, named) on whichever path is drawn."""
    import numpy as np

    hits = trace.collisions()
    first = np.flatnonzero(trace.column("collided") > 0.5)
    if hits:  # at the sample of the contact's time
        t = trace.column("t")
        for n, c in enumerate(hits):
            i = int(np.clip(np.searchsorted(t, float(c["t"]) - 1e-9), 0, len(t) - 1))
            what = f"hit `{c.get('obstacle') or 'an obstacle'}` at {float(c['t']) - t[0]:.1f} s"
            ax.plot([x[i]], [y[i]], marker="*", ms=16, color="tab:red", ls="none", zorder=6,
                    label=what if n == 0 else None)
            ax.annotate(what, (x[i], y[i]), xytext=(8, 8), textcoords="offset points",
                        color="tab:red", fontsize="small", zorder=6)
    elif len(first):
        ax.plot([x[first[0]]], [y[first[0]]], marker="*", ms=16, color="tab:red", ls="none",
                zorder=6, label="first collision")


def _extent(x: "np.ndarray", y: "np.ndarray", pts: "np.ndarray", world: Any
            ) -> tuple[tuple[float, float], tuple[float, float]]:
    """Plot limits holding the path, the detected boundary and the obstacles, with a margin.

    The world's free-space extent is left out: it is often much larger than the scene.
    """
    import numpy as np

    # a sample with no finite pose (a damaged trace) places neither itself nor its boundary
    seen = pts[np.isfinite(pts).all(axis=1)]
    xs = [x[np.isfinite(x)], seen[:, 0]]
    ys = [y[np.isfinite(y)], seen[:, 1]]
    geometry = getattr(world, "geometry", None)
    if geometry is not None and not geometry.is_empty:
        wx0, wy0, wx1, wy1 = geometry.bounds
        xs.append(np.array([wx0, wx1]))
        ys.append(np.array([wy0, wy1]))
    ax_, ay_ = np.concatenate(xs), np.concatenate(ys)
    lo_x, hi_x = float(ax_.min()), float(ax_.max())
    lo_y, hi_y = float(ay_.min()), float(ay_.max())
    pad_x = max(0.05 * (hi_x - lo_x), 0.3)
    pad_y = max(0.05 * (hi_y - lo_y), 0.3)
    return (lo_x - pad_x, hi_x + pad_x), (lo_y - pad_y, hi_y + pad_y)


def _mark_events(ax: "Axes", events: Sequence[Mapping[str, Any]], truth: bool,
                 trace: Trace) -> None:
    """Mark where elements ended, one marker shape per cause (ended-by-parent omitted)."""
    import numpy as np

    if truth:  # event poses are odometry: place them on the true path by time
        t = trace.column("t")
        tx, ty = trace.column("true_x"), trace.column("true_y")

        def where(e: Mapping[str, Any]) -> tuple[float, float]:
            i = int(np.clip(np.searchsorted(t, float(e["t"]) - 1e-9), 0, len(t) - 1))
            return float(tx[i]), float(ty[i])
    else:
        def where(e: Mapping[str, Any]) -> tuple[float, float]:
            return float(e["x"]), float(e["y"])

    shown: set[str] = set()
    for e in events:
        cause = e.get("cause")
        if e.get("kind") != "end" or cause not in _CAUSE_STYLE:
            continue
        marker, colour, size, z = _CAUSE_STYLE[cause]
        try:
            px, py = where(e)
        except (KeyError, TypeError):  # an event without a time or place: not drawn
            continue
        if not (math.isfinite(px) and math.isfinite(py)):
            continue
        ax.plot([px], [py], marker=marker, color=colour, ms=size, mew=1.5, ls="none", zorder=z,
                mfc="none" if marker in ("s", "D") else colour,
                label=None if cause in shown else f"end: {CAUSE_WORDS[cause]}")
        shown.add(cause)


def _title(trace: Trace) -> str:
    h = trace.header
    prog = h.get("program")
    prog = prog if isinstance(prog, dict) else {}
    world = h.get("world")
    world = world if isinstance(world, dict) else {}
    parts = [str(prog.get("element") or "run")]
    if prog.get("file"):
        parts[0] += f" ({os.path.basename(str(prog['file']))})"
    if world.get("name"):
        parts.append(f"world {world['name']}")
    if h.get("seed") is not None:
        parts.append(f"seed {h['seed']}")
    end = trace.end
    if end:
        cause = str(end.get("cause"))
        how = ended_how(Cause(cause)) if cause in _CAUSES else f"ended: {cause}"
        parts.append(f"{how} at {float(end.get('duration') or 0.0):.1f} s")
        if end.get("collided"):
            parts.append("COLLIDED")
    elif trace.truncated or end is None:
        parts.append("(trace cut short)")
    return ", ".join(parts)


def world_of(trace: Trace) -> Any:
    """Return the world named in the trace header, or None when it cannot be loaded."""
    header_world = trace.header.get("world")
    spec = header_world.get("spec") if isinstance(header_world, dict) else None
    if not spec or not isinstance(spec, str):
        return None
    try:
        from mdle import sim

        return sim.load_world(spec)
    except MdleError:
        return None


def trace_and_world(trace_path: str | os.PathLike[str], world: Any = None) -> tuple[Trace, Any]:
    """Read a trace and the world to draw it in (``world`` as :func:`plot_trace` takes it)."""
    trace = read_trace(trace_path)
    if isinstance(world, (str, os.PathLike)):
        from mdle import sim

        world = sim.load_world(world)
    elif world is None:
        world = world_of(trace)
    return trace, world


def plot_trace(trace_path: str | os.PathLike[str], out: str | os.PathLike[str],
               world: Any = None, dpi: int = 130) -> str:
    """Draw the trace at ``trace_path`` into ``out`` (.png, .svg or .pdf); returns ``out``.

    ``world`` is a :class:`sim.World`, a world name or file, or None to use the world the
    trace header names (if it can be loaded; otherwise only the detected boundary).

    Raises
    ------
    TraceError
        The trace cannot be read.
    PlotError
        The output format is not supported, or the trace has no samples.
    WorldError
        ``world`` names a world that cannot be loaded.
    """
    out = os.fspath(out)
    ext = os.path.splitext(out)[1].lower().lstrip(".")
    if ext not in ("png", "svg", "pdf"):
        raise PlotError(Diagnostic(None, f"cannot write a plot to `{out}`: the file name must "
                                         "end in .png, .svg or .pdf"))
    trace, world = trace_and_world(trace_path, world)
    save_figure(trace_figure(trace, world), out, dpi)
    return out
