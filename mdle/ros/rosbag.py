"""rosbag2 folders: the MCAP file beside a ``metadata.yaml`` as ``ros2 bag record`` writes it.

A folder ``DIR`` holds ``DIR_0.mcap`` and ``metadata.yaml`` (format version 5, which
ROS 2 Humble writes and later distributions read), naming each topic's type, QoS and
message count, so ``ros2 bag info DIR`` and ``ros2 bag play DIR`` take it.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from mdle.errors import Diagnostic, MdleError

__all__ = ["prepare_folder", "write_metadata", "mcap_in"]


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


def write_metadata(folder: str, mcap_name: str, topics: Sequence[Any],
                   counts: Mapping[str, int], span: tuple[int, int],
                   qos: Callable[[bool], str]) -> str:
    """Write ``metadata.yaml`` for the recording; returns its path.

    ``topics`` are :class:`~mdle.ros.topics.Topic` records, ``counts`` messages per
    topic name, ``span`` the first and last log time (ns).
    """
    import yaml

    start, end = span
    total = sum(counts.values())
    duration = end - start if total else 0
    info = {
        "version": 5,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start if total else 0},
        "message_count": total,
        "topics_with_message_count": [
            {"topic_metadata": {"name": t.name, "type": t.type, "serialization_format": "cdr",
                                "offered_qos_profiles": qos(t.latched)},
             "message_count": counts.get(t.name, 0)}
            for t in topics],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [mcap_name],
        "files": [{"path": mcap_name,
                   "starting_time": {"nanoseconds_since_epoch": start if total else 0},
                   "duration": {"nanoseconds": duration},
                   "message_count": total}],
    }
    path = os.path.join(folder, "metadata.yaml")
    with open(path, "w", encoding="utf-8") as f:
        yaml.safe_dump({"rosbag2_bagfile_information": info}, f, sort_keys=False)
    return path
