"""``mdle export``: a run's JSON lines trace as an MCAP file of ROS 2 messages.

Exit codes: 0 written (also when the trace was cut short at its last line: a killed
run), 1 the trace is not one, or a damaged record stopped the export (what came before
it is written, in a finished file), 2 usage.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from mdle.console import output

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle export``."""
    p = subparsers.add_parser(
        "export", help="write a trace as MCAP (ROS 2 messages) for Foxglove, PlotJuggler, ros2",
        description="Write the run in a JSON lines trace as an MCAP file of ROS 2 messages "
                    "(/scan, /odom, /tf, /cmd_vel, /ground_truth, /footprint, /path, /map, "
                    "/obstacles, /mdle/events, /mdle/active, /mdle/diagnostics, "
                    "/mdle/state), the messages `mdle run --record` writes. Needs the "
                    "extra: pip install 'mdle[mcap]'.",
        epilog="Exit codes: 0 written, 1 not a trace or stopped at a damaged record (the "
               "file holds everything before it), 2 usage.")
    p.add_argument("trace", metavar="TRACE.jsonl", help="a trace written by `mdle run --trace`")
    out = p.add_mutually_exclusive_group(required=True)
    out.add_argument("-o", "--output", metavar="FILE.mcap", help="the MCAP file to write")
    out.add_argument("--rosbag", metavar="DIR",
                     help="write a rosbag2 folder instead (DIR_0.mcap and metadata.yaml)")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="world for /map (default: the one the trace names, if it loads)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Export; returns the exit code."""
    from mdle.record import require

    require("mdle export")
    from mdle.cli.clobber import refuse_clobbering
    from mdle.record.export import export_trace

    target = args.output or args.rosbag
    refuse_clobbering([("-o", args.output), ("--rosbag", args.rosbag)],
                      [("the trace", args.trace), ("the world", args.world)])
    report = export_trace(args.trace, target, rosbag=args.rosbag is not None,
                          world=args.world)
    for w in report.warnings:
        print(f"mdle export: warning: {w}", file=sys.stderr)
    span = (f", t = {report.span[0]:.2f} .. {report.span[1]:.2f} s" if report.span else "")
    topics = sum(1 for n in report.counts.values() if n)
    print(f"wrote {target}: {report.messages} messages on {topics} topics{span}")
    if report.stopped is not None:
        line, why = report.stopped
        print(f"mdle export: {args.trace}:{line}: {why}: stopped there; the file holds "
              f"the records of lines 1-{line - 1}", file=sys.stderr)
        return output.EXIT_INPUT
    if report.truncated:
        print(f"mdle export: note: {args.trace}:{report.lines + 1}: the last line is cut "
              f"short (a run killed while writing); exported up to line {report.lines}",
              file=sys.stderr)
    elif not report.ended:
        print(f"mdle export: note: {args.trace} has no `end` record (the run was cut off)",
              file=sys.stderr)
    return output.EXIT_OK
