"""rosbag2 folders: the MCAP file beside a ``metadata.yaml`` as ``ros2 bag record`` writes it.

A folder ``DIR`` holds ``DIR_0.mcap`` and ``metadata.yaml`` (format version 9, which
ROS 2 Jazzy and later write), naming each topic's type, QoS and message count, so
``ros2 bag info DIR`` and ``ros2 bag play DIR`` take it. Version 9 writes each topic's
offered QoS profiles as a list of named values (earlier versions: a YAML string), and
has ``custom_data`` and ``ros_distro``; the message definitions mdle writes are Jazzy's
(and Humble's: the same for these types).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

from mdle.core.errors import Diagnostic, MdleError

__all__ = ["prepare_folder", "qos_profiles", "write_metadata", "mcap_in"]


def prepare_folder(folder: str) -> str:
    """Create the folder (it must be new or empty); returns the path of its MCAP file.

    Raises
    ------
    MdleError
        The folder exists and is not empty, or cannot be created.
    """
    folder = os.path.normpath(folder)
    if os.path.exists(folder):
        if not os.path.isdir(folder):
            raise MdleError(Diagnostic(None, f"--rosbag `{folder}`: a file of that name exists",
                                       hint="give the name of a new folder"))
        if os.listdir(folder):
            raise MdleError(Diagnostic(None, f"--rosbag `{folder}`: the folder is not empty",
                                       hint="give the name of a new folder (as ros2 bag "
                                            "record does, mdle will not mix recordings)"))
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as exc:
        raise MdleError(Diagnostic(None, f"cannot create the folder `{folder}`: "
                                         f"{exc.strerror}")) from None
    name = os.path.basename(os.path.abspath(folder))
    return os.path.join(folder, f"{name}_0.mcap")


def mcap_in(folder: str) -> str | None:
    """Return the MCAP file a rosbag2 folder's ``metadata.yaml`` names (None: none)."""
    import yaml

    try:
        with open(os.path.join(folder, "metadata.yaml"), encoding="utf-8") as f:
            meta = yaml.safe_load(f)
        info = meta["rosbag2_bagfile_information"]
        files = [p for p in info["relative_file_paths"] if str(p).endswith(".mcap")]
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        files = sorted(p for p in os.listdir(folder) if p.endswith(".mcap"))
    return os.path.join(folder, os.path.basename(str(files[0]))) if files else None


#: Version 9's "never" of a QoS duration (what rclcpp writes for an infinite one).
_NEVER = {"sec": 9223372036, "nsec": 854775807}


def qos_profiles(latched: bool) -> list[dict[str, Any]]:
    """Return a topic's ``offered_qos_profiles`` as version 9 writes them.

    One profile: history unknown, reliable, transient-local durability for a latched
    topic (``/tf_static``, ``/map``), else volatile; liveliness automatic.
    """
    return [{"history": "unknown", "depth": 0, "reliability": "reliable",
             "durability": "transient_local" if latched else "volatile",
             "deadline": dict(_NEVER), "lifespan": dict(_NEVER), "liveliness": "automatic",
             "liveliness_lease_duration": dict(_NEVER),
             "avoid_ros_namespace_conventions": False}]


def write_metadata(folder: str, mcap_name: str, topics: Sequence[Any],
                   counts: Mapping[str, int], span: tuple[int, int]) -> str:
    """Write ``metadata.yaml`` (version 9) for the recording; returns its path.

    ``topics`` are :class:`~mdle.record.topics.Topic` records, ``counts`` messages per
    topic name, ``span`` the first and last log time (ns).
    """
    import yaml

    start, end = span
    total = sum(counts.values())
    duration = end - start if total else 0
    info = {
        "version": 9,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start if total else 0},
        "message_count": total,
        "topics_with_message_count": [
            {"topic_metadata": {"name": t.name, "type": t.type, "serialization_format": "cdr",
                                "offered_qos_profiles": qos_profiles(t.latched),
                                "type_description_hash": ""},
             "message_count": counts.get(t.name, 0)}
            for t in topics],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [mcap_name],
        "files": [{"path": mcap_name,
                   "starting_time": {"nanoseconds_since_epoch": start if total else 0},
                   "duration": {"nanoseconds": duration},
                   "message_count": total}],
        "custom_data": {},
        "ros_distro": "jazzy",
    }
    path = os.path.join(folder, "metadata.yaml")
    with open(path, "w", encoding="utf-8") as f:
        yaml.safe_dump({"rosbag2_bagfile_information": info}, f, sort_keys=False)
    return path
