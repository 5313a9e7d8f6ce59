"""``mdle plot``: draw a run from its trace (path, obstacles, events, boundary curvature)."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle plot``."""
    p = subparsers.add_parser(
        "plot", help="draw a run from its trace",
        description="Draw the path of a run (coloured by the running atom, with the "
                    "obstacles or the detected boundary and the events marked) and the "
                    "measured boundary curvature against distance travelled.")
    p.add_argument("trace", metavar="TRACE.jsonl", nargs="+",
                   help="a trace written by `mdle run --trace`; several (the robots of a "
                        "team run) are drawn together, every path in one plot")
    p.add_argument("-o", "--output", required=True, metavar="FILE",
                   help="the image to write: .png, .svg or .pdf")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="world to draw (default: the one the trace names, if it loads)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Write the plot; returns the exit code."""
    from mdle.cli.options import writable_output
    from mdle.plot import plot_trace

    writable_output(args.output, "-o", (".png", ".svg", ".pdf"))
    if len(args.trace) > 1:
        import sim
        from mdle.team_plot import plot_team

        world = sim.load_world(args.world) if args.world else None
        out = plot_team(args.trace, args.output, world=world)
    else:
        out = plot_trace(args.trace[0], args.output, world=args.world)
    print(f"plot written to {out}")
    return 0
