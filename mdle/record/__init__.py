"""Runs as ROS 2 data: MCAP files (and rosbag2 folders) that robotics tools open.

The trace's records (:mod:`mdle.record.trace`) become ROS 2 messages on the usual topics
(``/scan``, ``/odom``, ``/tf``, ``/tf_static``, ``/cmd_vel``, ``/ground_truth``,
``/footprint``, ``/path``, ``/map``, ``/obstacles``, ``/mdle/events``, ``/mdle/active``,
``/mdle/diagnostics``, ``/mdle/state``; ``docs/trace.md`` lists them), CDR-encoded, in a
chunked, indexed MCAP file. The same mapping serves a live run (:class:`McapRecorder`,
``mdle run --record``) and a trace read back (:func:`export_trace`, ``mdle export``), so
both give the same messages; a live view (``--foxglove``, :mod:`mdle.view.foxglove`) gets
the very same bytes (:mod:`mdle.record.outlet`), a team's robots share one file
(:mod:`mdle.record.team_record`), and ``mdle recover`` (:mod:`mdle.record.recover`) finishes
a file a kill cut off.

Writing needs the optional extra ``mdle[mcap]`` (the ``mcap`` and ``mcap-ros2-support``
libraries and ``lz4``); :func:`require` says how to install it when it is missing.
"""

from __future__ import annotations

from mdle.core.errors import Diagnostic, MdleError

__all__ = ["MissingExtraError", "require", "INSTALL_HINT"]

INSTALL_HINT = "install the extra: pip install 'mdle[mcap]' (mcap, mcap-ros2-support, lz4)"


class MissingExtraError(MdleError):
    """The MCAP libraries are not installed."""


def require(what: str) -> None:
    """Check that the MCAP libraries import; raise :class:`MissingExtraError` if not.

    ``what`` names the feature that needs them (``--record``, ``mdle export``...).
    """
    missing = []
    for module in ("mcap.records", "mcap_ros2.decoder", "lz4.frame"):
        try:
            __import__(module)
        except ImportError:
            missing.append(module.partition(".")[0])
    if missing:
        raise MissingExtraError(Diagnostic(
            None, f"{what} needs the MCAP libraries, which are not installed "
                  f"(missing: {', '.join(missing)})", hint=INSTALL_HINT))
