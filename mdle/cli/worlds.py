"""``mdle worlds``: list the reference worlds, or draw one (``mdle worlds show NAME [-o F.png]``).

Without ``-o`` the drawing opens in a window when there is a display, else it is written to
``NAME.png`` here (:mod:`mdle.view.figure_output`).
"""

from __future__ import annotations

import argparse
import math
from typing import Any

__all__ = ["add_parser", "run", "world_title", "world_figure"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle worlds`` and ``mdle worlds show``."""
    p = subparsers.add_parser(
        "worlds", help="list the simulator's reference worlds, or draw one",
        description="List the reference worlds shipped with the simulator (usable as "
                    "`mdle run --world NAME`), or draw one world, or a world file, to an image.",
        epilog="Examples: `mdle worlds`; `mdle worlds show corridor` (a window, or "
               "corridor.png); `mdle worlds show corridor -o corridor.png`; "
               "`mdle worlds show my_room.yaml -o room.png --no-scan`.")
    sub = p.add_subparsers(dest="action", metavar="ACTION")
    show = sub.add_parser("show", help="draw a world (a window, or an image)",
                          description="Draw a world's obstacles, the robot at its start pose "
                                      "and, unless --no-scan, the ladar scan it sees there.")
    show.add_argument("world", metavar="NAME|FILE", help="a reference world name or a YAML file")
    show.add_argument("-o", "--output", metavar="FILE",
                      help="the image to write: .png, .svg or .pdf (default: a window when "
                           "there is a display, else NAME.png here)")
    show.add_argument("--no-scan", action="store_true", help="do not draw the start scan")
    _add_import(sub)
    p.set_defaults(handler=run)


def _add_import(sub: Any) -> None:
    imp = sub.add_parser(
        "import", help="make a world file from a ROS map_server map or an IR-SIM world",
        description="Read a ROS map_server map (its YAML file, with a PGM or PNG image) or an "
                    "IR-SIM world file, and write an mdle world file: a map's occupied cells "
                    "become polygons with holes (their outlines, simplified within "
                    "--tolerance), an IR-SIM world's obstacles become shapes.",
        epilog="Example: `mdle worlds import office.yaml -o office.world.yaml`, then "
               "`mdle run plan.mdle --world office.world.yaml`.")
    imp.add_argument("source", metavar="FILE", help="a map_server YAML file or an IR-SIM world")
    imp.add_argument("-o", "--output", metavar="FILE",
                     help="the world file to write (default: SOURCE_STEM.world.yaml here)")
    imp.add_argument("--tolerance", metavar="M", type=float,
                     help="how far a map's simplified outline may stray from the occupied "
                          "cells, metres (default: one cell; 0 keeps every corner)")
    imp.add_argument("--name", help="the world's name (default: the source's file name)")


def run(args: argparse.Namespace) -> int:
    """List or draw worlds; return the exit code."""
    if getattr(args, "action", None) == "show":
        return _show(args)
    if getattr(args, "action", None) == "import":
        return _import(args)
    from mdle.sim.catalog import DEFAULT_WORLD, world_descriptions

    rows = world_descriptions()
    width = max(len(n) for n, _ in rows)
    for name, desc in rows:
        mark = " (default)" if name == DEFAULT_WORLD else ""
        print(f"{name:<{width}}  {desc}{mark}")
    return 0


def world_title(world: Any) -> str:
    """Return ``name: description``, without repeating a name the description starts with.

    >>> import types
    >>> world_title(types.SimpleNamespace(name="default", description="Default: a room"))
    'default: a room'
    """
    desc = str(world.description or "").strip()
    head, sep, rest = desc.partition(":")
    if sep and head.strip().lower() == str(world.name).lower():
        desc = rest.strip()
    return f"{world.name}: {desc}" if desc else str(world.name)


def world_figure(world: Any, scan: bool = True) -> Any:
    """Return a figure of ``world``: obstacles, the robot at its start and its start scan."""
    import numpy as np
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle as DiscPatch

    from mdle.view.plot import draw_world

    fig = Figure(figsize=(8, 6), layout="constrained")
    ax = fig.subplots()
    draw_world(ax, world)
    for name, s, robot, first in _robots_at_start(world, scan):
        if first is not None:
            mx, my, _ = robot.ladar_mount
            ox = s.x + math.cos(s.theta) * mx - math.sin(s.theta) * my
            oy = s.y + math.sin(s.theta) * mx + math.cos(s.theta) * my
            a = s.theta + first.bearings
            ex, ey = ox + first.ranges * np.cos(a), oy + first.ranges * np.sin(a)
            ax.plot(np.column_stack([np.full_like(ex, ox), ex]).T,
                    np.column_stack([np.full_like(ey, oy), ey]).T, color="tab:orange",
                    lw=0.3, alpha=0.5)
            ax.plot(ex[first.valid], ey[first.valid], ".", ms=2, color="tab:red")
        r = max(robot.radius, 0.1)
        ax.add_patch(DiscPatch((s.x, s.y), r, facecolor="tab:blue", alpha=0.5,
                               edgecolor="tab:blue"))
        ax.annotate("", xy=(s.x + 2 * r * math.cos(s.theta), s.y + 2 * r * math.sin(s.theta)),
                    xytext=(s.x, s.y), arrowprops={"arrowstyle": "->", "color": "tab:blue"})
        if name:
            ax.annotate(name, (s.x, s.y), xytext=(0, -14), textcoords="offset points",
                        ha="center", fontsize=8, color="tab:blue")
    x0, y0, x1, y1 = world.bounds
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(world_title(world), fontsize=9)
    return fig


def _show(args: argparse.Namespace) -> int:
    import os

    from mdle import sim
    from mdle.cli.clobber import refuse_clobbering
    from mdle.view.figure_output import save_figure, show_or_write

    refuse_clobbering([("-o", args.output)], [("the world", args.world)])
    if args.output is not None:
        ext = os.path.splitext(args.output)[1].lower().lstrip(".")
        if ext not in ("png", "svg", "pdf"):
            # matplotlib would add `.png` to a name without one and report nothing
            from mdle.core.errors import MdleError

            raise MdleError(f"cannot draw to `{args.output}`: the file name must end in .png, "
                            ".svg or .pdf")
    world = sim.load_world(args.world)
    fig = world_figure(world, scan=not args.no_scan)
    if args.output is None:
        print(show_or_write(fig, world.name))
        return 0
    save_figure(fig, args.output, dpi=120)
    print(f"world drawn to {args.output}")
    return 0


def _import(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mdle.core.errors import MdleError
    from mdle.sim.importers import import_world
    from mdle.sim.world_dump import world_to_yaml

    tol = args.tolerance
    if tol is not None and not (math.isfinite(tol) and tol >= 0):
        raise MdleError(f"--tolerance is a length of 0 m or more, not {tol!r}")
    out = Path(args.output or f"{Path(args.source).stem}.world.yaml")
    if out.resolve() == Path(args.source).resolve():
        raise MdleError(f"the world would overwrite its source {args.source}: give -o FILE")
    world = import_world(args.source, tol, args.name)
    try:
        out.write_text(world_to_yaml(world), encoding="utf-8")
    except OSError as err:
        raise MdleError(f"cannot write {out}: {err.strerror or err}") from None
    segments = world.parts.n_segments
    print(f"{out}: {len(world.obstacles)} obstacles, {segments} straight faces; start "
          f"({world.start_pose.x:.2f}, {world.start_pose.y:.2f})")
    return 0


def _robots_at_start(world: Any, scans: bool) -> list[tuple[str, Any, Any, Any]]:
    """(name, start pose, profile, noise-free start scan or None) of each robot drawn.

    A team world's robots (each seeing the others), else the one robot at the start.
    """
    from mdle import sim

    if world.robots:
        from mdle.sim.team import TeamSim

        team = TeamSim(world, world.robots, sensing="exact") if scans else None
        return [(r.name, r.start, r.profile,
                 team.members[i].observe().scan if team is not None else None)
                for i, r in enumerate(world.robots)]
    scan = sim.SimBackend(world, ladar="lms200-ideal").observe().scan if scans else None
    return [("", world.start_pose, world.robot, scan)]
