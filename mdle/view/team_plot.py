"""One plot of a team's run: every robot's true path in its own colour, in one world.

Each path starts at a circle (the robot's start) and ends at its body's footprint; a
collision is a red cross; messages (other than pose beacons) are marked where they were
sent (a triangle) and where they arrived (a diamond), labelled with their channel once;
a stream of messages (an atom sends at every tick it runs) is marked where it starts.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

from mdle.core.errors import Diagnostic
from mdle.record.load import read_trace
from mdle.record.trace import Trace

__all__ = ["team_figure", "plot_team", "is_team_trace", "robot_name"]

#: Messages of one stream (direction, channel, sender) closer than this (s) are marked once.
_GAP = 1.0


def is_team_trace(trace: Trace) -> bool:
    """Tell whether ``trace`` is one robot's of a team run (its header names the team)."""
    return isinstance(trace.header.get("team"), dict)


def robot_name(trace: Trace) -> str:
    """Return the robot a team trace is of (else the file's name)."""
    team = trace.header.get("team")
    if isinstance(team, dict) and isinstance(team.get("robot"), str):
        return team["robot"]
    return os.path.basename(trace.path)


def _at(trace: Trace, t: float) -> tuple[float, float]:
    """Return the robot's true position at time ``t`` (the first sample at or after it)."""
    import numpy as np

    ts = trace.column("t")
    i = int(np.clip(np.searchsorted(ts, t - 1e-9), 0, len(ts) - 1))
    return float(trace.column("true_x")[i]), float(trace.column("true_y")[i])


def team_figure(traces: Sequence[Trace], world: Any = None) -> Any:
    """Return the figure of the team's run (``world`` a sim.World, or None)."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    from mdle.view.figure_output import PlotError
    from mdle.view.plot import draw_world

    fig = Figure(figsize=(7.5, 6.5))
    ax = fig.add_subplot(1, 1, 1)
    if world is not None and world.obstacles:
        draw_world(ax, world)
    colours = [f"C{i % 10}" for i in range(len(traces))]
    labelled: set[str] = set()
    xs: list[float] = []
    ys: list[float] = []
    for trace, colour in zip(traces, colours, strict=True):
        if not trace.samples:
            raise PlotError(Diagnostic(None, f"trace `{trace.path}` has no samples to plot"))
        name = robot_name(trace)
        x, y = trace.column("true_x"), trace.column("true_y")
        xs += [float(v) for v in x if math.isfinite(v)]
        ys += [float(v) for v in y if math.isfinite(v)]
        ax.plot(x, y, color=colour, lw=1.6, zorder=3, label=name)
        ax.plot([x[0]], [y[0]], "o", color=colour, mfc="none", ms=7, zorder=4)
        radius = _radius(world, name)
        if radius > 0 and math.isfinite(x[-1]):
            ax.add_patch(Circle((float(x[-1]), float(y[-1])), radius, facecolor=colour,
                                alpha=0.35, edgecolor=colour, zorder=4))
        for c in trace.collisions():
            cx, cy = c.get("x"), c.get("y")
            if cx is None or cy is None:
                continue
            ax.plot([float(cx)], [float(cy)], "X", color="tab:red", ms=9, zorder=6,
                    label=None if "collision" in labelled else "collision")
            labelled.add("collision")
        last: dict[tuple[Any, ...], float] = {}
        for m in trace.extra:
            if m.get("type") != "message" or isinstance(m.get("value"), dict):
                continue
            sent = m.get("dir") == "sent"
            t = float(m.get("t") or 0.0)
            stream = (m.get("dir"), m.get("channel"), m.get("from"))
            previous = last.get(stream, -math.inf)
            last[stream] = t
            if t - previous <= _GAP:  # a stream sent at every tick: its start is marked
                continue
            px, py = _at(trace, t)
            key = f"{'sent' if sent else 'received'} {m.get('channel')}"
            ax.plot([px], [py], "^" if sent else "D", color=colour, mec="black", ms=7,
                    zorder=5, ls="none")
            if key not in labelled:
                ax.annotate(key, (px, py), xytext=(6, 6), textcoords="offset points",
                            fontsize="small", color=colour)
                labelled.add(key)
    if world is not None:
        x0, y0, x1, y1 = world.bounds
        xs += [x0, x1]
        ys += [y0, y1]
    if xs and ys:
        span = max(max(xs) - min(xs), max(ys) - min(ys), 1.0)
        pad = 0.05 * span
        ax.set_xlim(min(xs) - pad, max(xs) + pad)
        ax.set_ylim(min(ys) - pad, max(ys) + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper right", fontsize="small")
    title = "team run"
    if world is not None:
        title += f", world {world.name}"
    ax.set_title(title, fontsize="medium")
    return fig


def _radius(world: Any, name: str) -> float:
    for r in getattr(world, "robots", ()):
        if r.name == name:
            return float(r.profile.radius)
    return 0.0


def plot_team(trace_paths: Sequence[str | os.PathLike[str]], out: str | os.PathLike[str],
              world: Any = None) -> str:
    """Draw the traces of a team's robots into one plot ``out`` (.png, .svg, .pdf)."""
    from mdle.view.figure_output import save_figure
    from mdle.view.plot import world_of

    out = os.fspath(out)
    traces = [read_trace(p) for p in trace_paths]
    if world is None and traces:
        world = world_of(traces[0])
    save_figure(team_figure(traces, world), out)
    return out
