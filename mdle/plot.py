"""Plots of a run from its trace, as the seed paper draws them (Figures 6-9).

The top panel is the path in the plane with the obstacles (from the world) and the
boundary points the robot detected, the path coloured by the atom that was running and
every element's end marked by its cause. The bottom panel, when the steering law
recorded it, is the measured boundary curvature against the distance travelled.
matplotlib is used headless (the Agg canvas, no pyplot state), so this works on a
machine with no display.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from mdle.errors import Diagnostic, MdleError
from mdle.trace import Trace, read_trace

if TYPE_CHECKING:
    import numpy as np
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["plot_trace", "trace_figure", "PlotError", "boundary_points", "CURVATURE_KEYS"]

#: Diagnostic names tried, in order, for the measured boundary curvature (1/m).
CURVATURE_KEYS = ("side_curvature", "curvature", "boundary_curvature")

#: Marker and colour of an element's end, by cause.
_CAUSE_STYLE = {
    "interrupt": ("x", "black"),
    "timer": ("o", "dimgray"),
    "completed": ("s", "tab:green"),
    "stopped": ("X", "tab:orange"),
    "error": ("X", "tab:red"),
}


class PlotError(MdleError):
    """A plot cannot be made: unknown output format, or a trace with no samples."""


def boundary_points(trace: Trace, truth: bool = False) -> "np.ndarray":
    """Points (K, 2) of the boundary the law saw beside the robot.

    From each sample whose diagnostics have a side range (``side_range``, with
    ``side_hit`` when given): the point at that range from the robot's pose, at bearing
    ``side_bearing`` (rad, robot frame; -pi/2, the robot's right, when not recorded). The
    pose is the odometry (the plan's frame), or with ``truth`` the simulator's true pose,
    so that the points lie in the frame the path is drawn in.
    """
    import numpy as np

    r = trace.column("diag.side_range")
    if not np.isfinite(r).any():
        return np.zeros((0, 2))
    hit = trace.column("diag.side_hit")
    bearing = trace.column("diag.side_bearing")
    bearing = np.where(np.isfinite(bearing), bearing, -math.pi / 2)
    ok = np.isfinite(r) & (r > 0) & ((hit > 0.5) | np.isnan(hit))
    pose = ("true_x", "true_y", "true_theta") if truth else ("x", "y", "theta")
    x, y, th = (trace.column(name) for name in pose)
    a = th + bearing
    pts = np.column_stack([x + r * np.cos(a), y + r * np.sin(a)])
    return pts[ok]


def _curvature(trace: Trace) -> "tuple[str, np.ndarray] | None":
    import numpy as np

    names = trace.diag_names()
    for key in CURVATURE_KEYS:
        if key in names:
            k = trace.column("diag." + key)
            hit_key = key.replace("curvature", "hit")
            if hit_key in names:
                k = np.where(trace.column("diag." + hit_key) > 0.5, k, np.nan)
            if np.isfinite(k).any():
                return key, k
    return None


def _draw_world(ax: "Axes", geometry: Any) -> None:
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
                ax.add_patch(PathPatch(MplPath(verts, codes), facecolor="0.82",
                                       edgecolor="0.35", lw=0.8, zorder=1))
            elif kind in ("LineString", "LinearRing"):
                x, y = g.xy
                ax.plot(x, y, color="0.35", lw=1.5, zorder=1)
            elif kind == "Point":
                ax.plot([g.x], [g.y], ".", color="0.35", zorder=1)


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


def trace_figure(trace: Trace, world: Any = None, title: str | None = None) -> "Figure":
    """Return the figure for ``trace`` (see the module docstring); ``world`` a sim.World."""
    import numpy as np
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    if not trace.samples:
        raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no samples to plot"))
    true_x = trace.column("true_x")
    use_truth = world is not None and bool(np.isfinite(true_x).all())
    if use_truth:  # with the world, draw where the robot really was
        x, y = true_x, trace.column("true_y")
    else:
        x, y = trace.column("x"), trace.column("y")
    placed = np.flatnonzero(np.isfinite(x) & np.isfinite(y))
    if not len(placed):
        raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no sample with a finite "
                                         "position (x, y) to plot"))
    curv = _curvature(trace)
    pts = boundary_points(trace, truth=use_truth)
    (x0, x1), (y0, y1) = _extent(x, y, pts, world)
    # the path panel takes the shape of the scene (a long corridor makes a wide, low panel)
    width = 8.0
    path_h = float(np.clip(width * (y1 - y0) / (x1 - x0) + 1.0, 2.8, 7.5))
    curv_h = 2.8 if curv else 0.0
    fig = Figure(figsize=(width, path_h + curv_h), layout="constrained")
    if curv:
        ax, axk = fig.subplots(2, 1, height_ratios=[path_h, curv_h])
    else:
        ax, axk = fig.subplots(1, 1), None

    if world is not None:
        _draw_world(ax, world.geometry)
    if len(pts):
        ax.plot(pts[:, 0], pts[:, 1], ".", ms=2.0, color="tab:brown", alpha=0.6, zorder=2,
                label="detected boundary")

    colours = [f"C{i}" for i in range(10)]
    for i, (label, seg) in enumerate(_segments_by_atom(x, y, trace.paths()).items()):
        ax.add_collection(LineCollection(list(seg), colors=colours[i % 10], lw=2.0, zorder=3,
                                         label=f"atom {label}"))
    i0 = int(placed[0])
    heading = float(trace.column("theta")[i0])
    heading = heading if math.isfinite(heading) else 0.0
    ax.plot([x[i0]], [y[i0]], marker=(3, 0, math.degrees(heading) - 90),
            ms=11, color="k", ls="none", zorder=5, label="start")

    _mark_events(ax, trace.events, world is not None and use_truth, trace)
    hits = trace.collisions()
    first = np.flatnonzero(trace.column("collided") > 0.5)
    if hits:  # at the sample of the contact's time, on whichever path is drawn
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
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, lw=0.3, alpha=0.5)
    if path_h < 4.0:  # a wide, low scene (a corridor) has no room for the legend inside
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                  fontsize="small")
    else:
        ax.legend(loc="best", fontsize="small", framealpha=0.8)
    ax.set_title(title or _title(trace), fontsize="medium")

    if curv and axk is not None:
        key, k = curv
        ox, oy = trace.column("x"), trace.column("y")
        dist = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(ox), np.diff(oy)))])
        axk.plot(dist, k, lw=1.0, color="tab:blue")
        axk.axhline(0.0, color="0.5", lw=0.6)
        axk.set_xlabel("distance travelled (m)")
        axk.set_ylabel(f"{key.replace('_', ' ')} (1/m)")
        axk.grid(True, lw=0.3, alpha=0.5)
        axk.set_title("measured boundary curvature", fontsize="medium")
    return fig


def _extent(x: "np.ndarray", y: "np.ndarray", pts: "np.ndarray", world: Any
            ) -> tuple[tuple[float, float], tuple[float, float]]:
    """Plot limits holding the path, the detected boundary and the world, with a margin."""
    import numpy as np

    xs = [x[np.isfinite(x)], pts[:, 0]]
    ys = [y[np.isfinite(y)], pts[:, 1]]
    if world is not None:
        wx0, wy0, wx1, wy1 = world.bounds
        xs.append(np.array([wx0, wx1]))
        ys.append(np.array([wy0, wy1]))
    ax_, ay_ = np.concatenate(xs), np.concatenate(ys)
    lo_x, hi_x = float(ax_.min()), float(ax_.max())
    lo_y, hi_y = float(ay_.min()), float(ay_.max())
    span = max(hi_x - lo_x, hi_y - lo_y, 1.0)
    pad = 0.05 * span
    return (lo_x - pad, hi_x + pad), (lo_y - pad, hi_y + pad)


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
        marker, colour = _CAUSE_STYLE[cause]
        try:
            px, py = where(e)
        except (KeyError, TypeError):  # an event without a time or place: not drawn
            continue
        if not (math.isfinite(px) and math.isfinite(py)):
            continue
        ax.plot([px], [py], marker=marker, color=colour, ms=7, mew=1.5, ls="none", zorder=4,
                mfc="none" if marker in ("o", "s") else colour,
                label=None if cause in shown else f"end: {cause}")
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
        parts.append(f"{end.get('cause')} at {float(end.get('duration') or 0.0):.1f} s")
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
        import sim

        return sim.load_world(spec)
    except MdleError:
        return None


def plot_trace(trace_path: str | os.PathLike[str], out: str | os.PathLike[str],
               world: Any = None) -> str:
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
    trace = read_trace(trace_path)
    if isinstance(world, (str, os.PathLike)):
        import sim

        world = sim.load_world(world)
    elif world is None:
        world = world_of(trace)
    fig = trace_figure(trace, world)
    _save(fig, out, ext)
    return out


def _save(fig: "Figure", out: str, ext: str) -> None:
    """Write the figure to ``out`` whole or not at all (a temporary file, then a rename).

    Raises
    ------
    PlotError
        The file cannot be written (the message names it and says why).
    """
    head, name = os.path.split(os.path.abspath(out))
    tmp: str | None = os.path.join(head, f".{name}.{os.getpid()}.part")
    try:
        assert tmp is not None
        with open(tmp, "wb") as f:  # created as any new file is (the umask applies)
            fig.savefig(f, format=ext, dpi=130)
        os.replace(tmp, out)
        tmp = None
    except OSError as exc:
        raise PlotError(Diagnostic(None, f"cannot write the plot `{out}`: "
                                         f"{exc.strerror or exc}")) from None
    finally:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
