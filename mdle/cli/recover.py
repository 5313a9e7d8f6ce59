"""``mdle recover``: make a recording cut off by a kill or a power cut readable again.

Exit codes: 0 recovered (or already whole), 1 not an MCAP recording or not writable,
2 usage.
"""

from __future__ import annotations

import argparse
from typing import Any

from mdle.console import output

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle recover``."""
    p = subparsers.add_parser(
        "recover", help="finish a recording cut off by a kill (MCAP file or rosbag2 folder)",
        description="Rewrite an MCAP recording that a killed `mdle run --record` (or "
                    "--rosbag) left without its summary: every whole chunk is kept, the "
                    "summary, index and footer are written, and a rosbag2 folder gets its "
                    "metadata.yaml. Needs the extra: pip install 'mdle[mcap]'.",
        epilog="Exit codes: 0 recovered, 1 not an MCAP recording, 2 usage.")
    p.add_argument("source", metavar="FILE.mcap|DIR", help="the recording (replaced "
                   "in place unless -o is given)")
    p.add_argument("-o", "--output", metavar="FILE.mcap",
                   help="write the recovered file here and leave the source as it is")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Recover; returns the exit code."""
    from mdle.record.recover import recover

    report = recover(args.source, args.output)
    span = ""
    if report.span is not None:
        span = f", t = {report.span[0] / 1e9:.2f} .. {report.span[1] / 1e9:.2f} s"
    state = "it was whole" if report.complete else "cut off after its last whole chunk"
    print(f"wrote {report.path}: {report.messages} messages on {len(report.counts)} "
          f"topics{span} ({state})")
    return output.EXIT_OK
