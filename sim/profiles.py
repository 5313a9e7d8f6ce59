r"""Robot profiles by name (shipped in ``sim/robots/*.yaml``) or by file path.

>>> p = parse_robot('''
... name: slow
... radius: 0.2
... max_speed: 0.5
... max_turn_rate: 90
... command_latency: 0.15
... scan_latency: {min: 0.02, max: 0.06}
... ''')
>>> p.name, round(p.max_turn_rate, 4), p.command_latency, p.scan_latency.describe()
('slow', 1.5708, 0.15, 'uniform 20-60 ms')
>>> try:
...     parse_robot("name: x\nradius: 0.2\nmax_speed: -1\nmax_turn_rate: 90\n", file="r.yaml")
... except WorldError as err:
...     print(err)
r.yaml:3:12: error: max_speed: must be positive, got -1

>>> "ideal" in list_robots() and "pioneer2dx" in list_robots()
True
>>> robot_profile("ideal").command_latency
0.0
"""

from __future__ import annotations

import os
from collections.abc import Callable
from functools import cache
from importlib import resources
from pathlib import Path

from mdle.core.errors import WorldError
from mdle.sim.robot import RobotProfile
from mdle.sim.robot_yaml import PROFILE_KEYS, REQUIRED_KEYS, check_mount, robot_overrides
from mdle.sim.yaml_doc import _Doc, _yaml_value
from mdle.sim.yaml_values import _mapping, _string

__all__ = ["DEFAULT_ROBOT", "list_robots", "parse_robot", "read_robot", "robot_descriptions",
           "robot_profile", "robot_source_text"]

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


def parse_robot(text: str, file: str = "<string>", default_name: str = "robot",
                lookup: Callable[[str], RobotProfile] | None = None) -> RobotProfile:
    """Parse and validate robot profile YAML text.

    ``lookup`` resolves a ``profile:`` base (default :func:`sim.profiles.robot_profile`).

    Raises
    ------
    WorldError
        With the file, line, column, key path and problem of the first error found.
    """
    doc = _Doc(file, text)
    data = _yaml_value(doc)
    top = _mapping(doc, "", {} if data is None else data, PROFILE_KEYS, "a robot profile")
    name = _string(doc, "name", top["name"]) if "name" in top else default_name
    ch = robot_overrides(doc, "", top)
    for key in ("description", "source"):
        if key in top:
            ch[key] = " ".join(_string(doc, key, top[key]).split())
    if "profile" in top:
        if lookup is None:
            lookup = robot_profile
        base_name = _string(doc, "profile", top["profile"])
        try:
            base = lookup(base_name)
        except WorldError as err:
            raise doc.fail("profile", err.diagnostics[0].message) from None
        robot = base.with_overrides(name=name, **ch)
    else:
        for key in REQUIRED_KEYS:
            if key not in top:
                raise doc.fail("", f"missing key `{key}` (a profile needs "
                                   f"{', '.join(REQUIRED_KEYS)}, or `profile: NAME` to start from)")
        ch.setdefault("max_reverse_speed", ch["max_speed"])
        robot = RobotProfile(name=name, **ch)
    check_mount(doc, "", top, robot)
    return robot


def read_robot(path: str | os.PathLike[str]) -> RobotProfile:
    """Read and validate a robot profile file (WorldError if unreadable or invalid)."""
    from mdle.core.userfile import UserFileError, read_user_file

    p = Path(path)
    try:  # a regular file of bounded size: `--robot /dev/zero` would read until memory ran out
        text = read_user_file(p).decode("utf-8")
    except UserFileError as err:
        if err.reason == "no such file":
            raise WorldError(f"robot profile file not found: {p}") from None
        raise WorldError(f"cannot read robot profile file {p}: {err.reason}") from None
    except UnicodeDecodeError as err:
        raise WorldError(f"cannot read robot profile file {p}: {err}") from None
    return parse_robot(text, file=str(path), default_name=p.stem)
