"""``mdle plot``: draw a run from its trace (path, obstacles, events, boundary curvature).

One trace: the run's figure (:mod:`mdle.view.plot`). Several: their paths and following errors
overlaid (:mod:`mdle.view.plot_overlay`), or, for the robots of one team run, every path in one
world with the messages marked (:mod:`mdle.view.team_plot`). ``--animate F.gif|F.mp4``: the
run as an animation (:mod:`mdle.view.animate`). Without ``-o`` (and without ``--animate``) the
figure opens in a window when there is a display, else it is written to ``NAME.png`` here,
and the line printed says where (:mod:`mdle.view.figure_output`).
"""

from __future__ import annotations

import argparse
import os
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle plot``."""
    p = subparsers.add_parser(
        "plot", help="draw a run from its trace, overlay several, or animate one",
        description="Draw the path of a run (coloured by the running atom, with the "
                    "obstacles or the detected boundary and the events marked) and the "
                    "measured boundary curvature against distance travelled. Several "
                    "traces: their paths and following errors in one figure (the robots "
                    "of a team run: every path in one world, messages marked).",
        epilog="Examples: `mdle plot run.jsonl` (a window, or run.png here); "
               "`mdle plot run.jsonl -o run.png`; `mdle plot a.jsonl b.jsonl -o both.png`; "
               "`mdle plot run.jsonl --animate run.gif`.")
    p.add_argument("traces", nargs="+", metavar="TRACE.jsonl",
                   help="traces written by `mdle run --trace` (or MCAP recordings)")
    p.add_argument("-o", "--output", metavar="FILE",
                   help="the image to write: .png, .svg or .pdf (default: a window when there "
                        "is a display, else NAME.png here)")
    p.add_argument("--animate", metavar="FILE.gif|FILE.mp4",
                   help="write the run as an animation instead (robot, scan rays, the "
                        "running element); .mp4 needs ffmpeg")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="world to draw (default: the one each trace names, if it loads)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Draw, overlay or animate; returns the exit code."""
    from mdle.cli.clobber import refuse_clobbering
    from mdle.cli.options import writable_output
    from mdle.core.errors import MdleError
    from mdle.view.figure_output import save_figure, show_or_write
    from mdle.view.plot import trace_and_world, trace_figure
    from mdle.view.team_plot import is_team_trace, team_figure

    refuse_clobbering([("-o", args.output), ("--animate", args.animate)],
                      [*(("the trace", t) for t in args.traces), ("the world", args.world)])

    if args.animate is not None and len(args.traces) > 1:
        return _animate_team(args)
    if args.animate is not None:
        if len(args.traces) != 1:
            raise MdleError("--animate draws one run: give one trace")
        if args.output is not None:
            raise MdleError("--animate writes its own file: leave out -o")
        from mdle.view.animate import animate_trace

        writable_output(args.animate, "--animate", (".gif", ".mp4"))
        trace, world = trace_and_world(args.traces[0], args.world)
        print(f"animation written to {animate_trace(trace, world, args.animate)}")
        return 0
    if args.output is not None:
        writable_output(args.output, "-o", (".png", ".svg", ".pdf"))
    runs = [trace_and_world(path, args.world) for path in args.traces]
    if len(runs) == 1:
        fig = trace_figure(*runs[0])
        name = os.path.splitext(os.path.basename(args.traces[0]))[0] or "plot"
    elif all(is_team_trace(trace) for trace, _ in runs):
        fig = team_figure([trace for trace, _ in runs], runs[0][1])
        name = "team"
    else:
        from mdle.view.plot_overlay import overlay_figure

        fig = overlay_figure(runs)
        name = "overlay"
    if args.output is None:
        print(show_or_write(fig, name))
        return 0
    save_figure(fig, args.output)
    print(f"plot written to {args.output}")
    return 0


def _animate_team(args: argparse.Namespace) -> int:
    """Animate the robots of one team run together (``--animate`` with several traces)."""
    from mdle.cli.options import writable_output
    from mdle.core.errors import MdleError
    from mdle.view.plot import trace_and_world
    from mdle.view.team_animate import animate_team
    from mdle.view.team_plot import is_team_trace

    if args.output is not None:
        raise MdleError("--animate writes its own file: leave out -o")
    runs = [trace_and_world(path, args.world) for path in args.traces]
    if not all(is_team_trace(trace) for trace, _ in runs):
        raise MdleError("--animate draws one run: give one trace, or the traces of the "
                        "robots of one team run (mdle run --team --trace)")
    writable_output(args.animate, "--animate", (".gif", ".mp4"))
    out = animate_team([trace for trace, _ in runs], runs[0][1], args.animate)
    print(f"animation written to {out}")
    return 0
