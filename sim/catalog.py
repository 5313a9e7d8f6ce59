"""The reference worlds shipped in ``sim/worlds/*.yaml``, loadable by name.

>>> "corridor" in list_worlds() and "ellipse" in list_worlds()
True
>>> load_world("ellipse").name
'ellipse'
"""

from __future__ import annotations

import os
from functools import cache
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from mdle.core.errors import WorldError
from mdle.sim.world_yaml import parse_world, parse_world_robot, read_world, read_world_robot

if TYPE_CHECKING:
    from mdle.sim.robot import RobotProfile
    from mdle.sim.world import World

__all__ = ["DEFAULT_WORLD", "list_worlds", "load_world", "world_descriptions", "world_robot"]

#: The world a newcomer's first ``mdle run`` uses.
DEFAULT_WORLD = "default"


def _folder() -> resources.abc.Traversable:
    return resources.files("mdle.sim").joinpath("worlds")


def list_worlds() -> list[str]:
    """Return the names of the reference worlds, sorted."""
    return sorted(p.name[:-5] for p in _folder().iterdir() if p.name.endswith(".yaml"))


@cache
def _reference(name: str) -> World:
    entry = _folder().joinpath(f"{name}.yaml")
    text = entry.read_text(encoding="utf-8")
    return parse_world(text, file=f"sim/worlds/{name}.yaml", default_name=name)


def load_world(spec: str | os.PathLike[str]) -> World:
    """Load a reference world by name (``corridor``, ``ellipse``, ...) or a YAML file by path.

    Raises
    ------
    WorldError
        Unknown name, unreadable file, or an invalid world (file, key path, problem).
    """
    text = os.fspath(spec)
    if _is_reference(text):
        return _reference(text)
    return read_world(text)


def world_robot(spec: str | os.PathLike[str]) -> RobotProfile:
    """Return the robot a world names, reading only its ``robot`` key (no geometry).

    What ``mdle check`` compares a plan's speeds with; cheaper than :func:`load_world`.

    Raises
    ------
    WorldError
        Unknown name, unreadable file, not YAML, or a bad ``robot`` entry.
    """
    text = os.fspath(spec)
    if _is_reference(text):
        entry = _folder().joinpath(f"{text}.yaml")
        return parse_world_robot(entry.read_text(encoding="utf-8"), f"sim/worlds/{text}.yaml")
    return read_world_robot(text)


def _is_reference(text: str) -> bool:
    """Tell a reference world's name (True) from a file (False); WorldError for neither."""
    if text in list_worlds():
        return True
    looks_like_path = text.endswith((".yaml", ".yml")) or os.sep in text or "/" in text
    if looks_like_path or _exists(text):
        return False
    import difflib

    names = list_worlds()
    close = difflib.get_close_matches(text, names, n=1) if len(text) < 100 else []
    hint = f" (did you mean `{close[0]}`?)" if close else ""
    shown = text if len(text) <= 80 else text[:60] + f"... ({len(text)} characters)"
    raise WorldError(f"unknown world `{shown}`{hint}; reference worlds: {', '.join(names)}; "
                     "or give the path of a .yaml world file")


def _exists(path: str) -> bool:
    """Whether a file of that name exists (a name too long for the system does not)."""
    try:
        return Path(path).exists()
    except (OSError, ValueError):
        return False


def world_descriptions() -> list[tuple[str, str]]:
    """Return (name, one-line description) of every reference world."""
    return [(n, _reference(n).description) for n in list_worlds()]
