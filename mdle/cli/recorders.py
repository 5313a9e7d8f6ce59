"""The recorders and live view ``mdle run`` makes (``--record``, ``--rosbag``, ``--foxglove``)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["live_view", "recorders"]


def recorders(args: argparse.Namespace, header: dict[str, Any], world: Any) -> list[Any]:
    """Return the MCAP recorders ``--record`` and ``--rosbag`` ask for, and the live view.

    ``--foxglove`` shows the first recording's messages (or, alone, a recorder's
    without a file).
    """
    if not (args.record or args.rosbag or args.foxglove):
        return []
    from mdle.record.recorder import McapRecorder

    out: list[Any] = []
    live = live_view(args) if args.foxglove else []
    compression = "" if args.record_compression == "none" else args.record_compression
    try:
        if args.record:
            out.append(McapRecorder(args.record, header, world, compression=compression,
                                    live=live))
            live = []
        if args.rosbag:
            out.append(McapRecorder(args.rosbag, header, world, rosbag=True,
                                    compression=compression, live=live))
            live = []
        if live:
            out.append(McapRecorder(None, header, world, live=live))
    except BaseException:  # one could not be made: close what was (files, the server)
        for r in out:
            r.close()
        for sink in live:
            sink.close()
        raise
    return out


def live_view(args: argparse.Namespace) -> list[Any]:
    """Start ``--foxglove``'s server; returns its sink (a list of one)."""
    from mdle.view.foxglove import FoxgloveServer, FoxgloveSink, parse_address

    server = FoxgloveServer(*parse_address(args.foxglove))
    try:  # where to connect (port 0 picks one): on standard error with -q
        print(f"live view: ws://{server.host}:{server.port} (Foxglove: Open connection)",
              file=sys.stderr if args.quiet else sys.stdout)
    except BrokenPipeError:  # standard output closed: the run itself says so later
        pass
    return [FoxgloveSink(server, owns_server=True)]
