"""ROS 2 names on the DDS wire: topics, types, namespaces and frames (no DDS import).

ROS 2 maps a topic ``/robot1/cmd_vel`` to the DDS topic ``rt/robot1/cmd_vel`` and a
message type ``geometry_msgs/msg/Twist`` to the DDS type
``geometry_msgs::msg::dds_::Twist_``; a real ROS 2 node only matches endpoints named
that way. A namespace (``--ns robot1``) prefixes the relative topics (``cmd_vel``,
``odom``, ``scan``, ``tf``) and, as a multi-robot setup needs, the frame ids
(``robot1/odom``, ``robot1/base_link``); absolute topics (``/clock``) stay as they are.
"""

from __future__ import annotations

import re

from mdle.core.errors import BackendError

__all__ = ["dds_topic", "dds_type", "frame_id", "namespace", "ros_topic"]

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def namespace(text: str | None, where: str = "--ns") -> str:
    """Return a ROS namespace in its canonical form: ``""`` or ``/a/b`` (no trailing ``/``).

    Raises
    ------
    BackendError
        The text is not a ROS name: each part must be letters, digits and underscores,
        not start with a digit, and hold no double underscore.
    """
    if text is None:
        return ""
    parts = [p for p in text.strip().strip("/").split("/")]
    if parts == [""]:
        return ""
    for part in parts:
        if not _TOKEN.fullmatch(part) or "__" in part:
            raise BackendError(
                f"{where} `{text}`: `{part or '//'}` is not a ROS name part (letters, digits "
                f"and underscores, not starting with a digit, no double underscore), e.g. "
                f"`robot1` or `lab/robot1`")
    return "/" + "/".join(parts)


def ros_topic(ns: str, name: str) -> str:
    """Return the full ROS topic of ``name`` in namespace ``ns`` (absolute names stay)."""
    if name.startswith("/"):
        return name
    return f"{ns}/{name}"


def dds_topic(ros_name: str) -> str:
    """Return the DDS topic of a full ROS topic: ``/cmd_vel`` -> ``rt/cmd_vel``."""
    return "rt" + ros_name


def dds_type(ros_type: str) -> str:
    """Return the DDS type of a ROS type: ``pkg/msg/Type`` -> ``pkg::msg::dds_::Type_``."""
    package, kind, name = ros_type.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def frame_id(ns: str, name: str) -> str:
    """Return a frame id in namespace ``ns``: ``odom`` or ``robot1/odom``."""
    return f"{ns.strip('/')}/{name}" if ns else name
