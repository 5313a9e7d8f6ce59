"""Robot profiles by name (shipped in ``sim/robots/*.yaml``) or by file path.

>>> "ideal" in list_robots() and "pioneer2dx" in list_robots()
True
>>> robot_profile("ideal").command_latency
0.0
"""

from __future__ import annotations

import os
from functools import cache
from importlib import resources
from pathlib import Path

from mdle.errors import WorldError
from mdle.sim.robot import RobotProfile
from mdle.sim.robot_yaml import parse_robot, read_robot

__all__ = ["DEFAULT_ROBOT", "list_robots", "robot_descriptions", "robot_profile",
           "robot_source_text"]

#: The robot of a world file that names none.
DEFAULT_ROBOT = "pioneer2dx"


def _folder() -> resources.abc.Traversable:
    return resources.files("mdle.sim").joinpath("robots")


def list_robots() -> list[str]:
    """Return the names of the shipped robot profiles, sorted."""
    return sorted(p.name[:-5] for p in _folder().iterdir() if p.name.endswith(".yaml"))


def robot_source_text(name: str) -> str:
    """Return the YAML text of a shipped profile (WorldError if there is none)."""
    if name not in list_robots():
        raise WorldError(f"unknown robot profile `{name}` (known: {', '.join(list_robots())})")
    return _folder().joinpath(f"{name}.yaml").read_text(encoding="utf-8")


@cache
def _shipped(name: str) -> RobotProfile:
    # Shipped profiles may start from each other (`profile: NAME`), never from a file.
    return parse_robot(robot_source_text(name), file=f"sim/robots/{name}.yaml",
                       default_name=name, lookup=_shipped_only)


def _shipped_only(name: str) -> RobotProfile:
    return _shipped(name)


def robot_profile(spec: str | os.PathLike[str]) -> RobotProfile:
    """Return a shipped profile by name (``pioneer-p3dx``, ``ideal``, ...) or read a YAML file.

    Raises
    ------
    WorldError
        Unknown name (the message lists the known ones), unreadable or invalid file.
    """
    text = os.fspath(spec)
    names = list_robots()
    if text in names:
        return _shipped(text)
    looks_like_path = text.endswith((".yaml", ".yml")) or os.sep in text or "/" in text
    if looks_like_path or _is_file(text):
        return read_robot(text)
    import difflib

    close = difflib.get_close_matches(text, names, n=1)
    hint = f" (did you mean `{close[0]}`?)" if close else ""
    raise WorldError(f"unknown robot profile `{text}`{hint} (known: {', '.join(names)}; "
                     "or give the path of a .yaml profile file)")


def _is_file(path: str) -> bool:
    """Whether a file of that name exists (a name too long for the system does not)."""
    try:
        return Path(path).is_file()
    except (OSError, ValueError):
        return False


def robot_descriptions() -> list[tuple[str, str]]:
    """Return (name, one-line description) of every shipped profile."""
    return [(n, _shipped(n).description) for n in list_robots()]
