"""Options and argument types that ``mdle run`` and ``mdle repl`` share.

Both drive the embedded simulator, so they take the same simulation options and read
durations the same way (a number of seconds; ``inf`` for no limit).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mdle.core.ranges import MAX_SEED, RATE

if TYPE_CHECKING:
    from mdle.core.motion_limits import KnownRobot

__all__ = ["DEFAULT_RATE", "add_simulation_options", "hertz", "known_robot", "positive_seconds",
           "seconds", "seed", "world_beside", "writable_output"]

#: Control rate (Hz) when neither ``--rate`` nor a team file gives one: the Pioneer's
#: 100 ms server cycle.
DEFAULT_RATE = 10.0


def add_simulation_options(p: Any) -> None:
    """Add ``--seed``, ``--robot`` and ``--sensing`` (the simulated robot) to a parser."""
    p.add_argument("--seed", type=seed, help="random seed of the simulation, 0 to 2**32 - 1 "
                                             "(default: the world's)")
    p.add_argument("--robot", metavar="PROFILE",
                   help="robot profile in simulation: a name (`mdle robots` lists them) or "
                        "a profile YAML file (default: the world's); on a robot, the "
                        "profile whose latency laws predict over (default 0.15 s) and whose "
                        "ladar mount and scan period recordings use")
    p.add_argument("--sensing", choices=("scan", "exact"), default="scan",
                   help="simulated ladar: a noisy scan (default) or exact oracle geometry")


def world_beside(plan: str | os.PathLike[str]) -> Path | None:
    """Find the world file of a plan: ``x.world.yaml`` or ``x.yaml`` beside ``x.mdle``."""
    p = Path(plan)
    for candidate in (p.with_suffix(".world.yaml"), p.with_suffix(".yaml")):
        if candidate.is_file():
            return candidate
    return None


def known_robot(plan: str | os.PathLike[str] | None, world: str | None = None,
                robot: str | None = None,
                memo: dict[tuple[str, ...], KnownRobot] | None = None) -> KnownRobot:
    """Return the robot a plan runs on in simulation, as ``mdle run`` chooses it.

    ``--robot`` first, else the robot of ``--world``, else of the world beside the plan,
    else of the default world. Only the robot is read (no world geometry: no numpy).
    ``memo`` (a dict kept by the caller) reads each world or profile once across plans.

    Raises
    ------
    WorldError
        The profile or the world cannot be read, or its ``robot`` is bad.
    """
    from mdle.core.motion_limits import KnownRobot
    from mdle.sim.catalog import DEFAULT_WORLD, world_robot
    from mdle.sim.profiles import robot_profile

    beside = world_beside(plan) if plan is not None and not (robot or world) else None
    key = ("robot", robot) if robot else ("world", world) if world else (
        ("beside", str(beside)) if beside is not None else ("default",))
    found = memo.get(key) if memo is not None else None
    if found is not None:
        return found
    if robot:
        found = KnownRobot.of(robot_profile(robot), "--robot")
    elif world:
        found = KnownRobot.of(world_robot(world), f"the robot of --world `{world}`")
    elif beside is not None:
        found = KnownRobot.of(world_robot(beside), f"the robot of `{beside.name}` beside the plan")
    else:
        found = KnownRobot.of(world_robot(DEFAULT_WORLD), "the default robot")
    if memo is not None:
        memo[key] = found
    return found


def _number_of_seconds(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None


def seconds(text: str) -> float:
    """Read a duration of zero or more seconds (an argparse ``type``).

    Raises
    ------
    argparse.ArgumentTypeError
        ``text`` is not a number, or is negative (or NaN).
    """
    value = _number_of_seconds(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be zero or more seconds, got {text!r}")
    return value


def positive_seconds(text: str) -> float:
    """Read a duration of more than zero seconds (an argparse ``type``).

    Raises
    ------
    argparse.ArgumentTypeError
        ``text`` is not a number, or is zero, negative or NaN.
    """
    value = _number_of_seconds(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be more than zero seconds, got {text!r}")
    return value



def seed(text: str) -> int:
    """Read a simulation seed: a whole number from 0 to :data:`MAX_SEED` (argparse ``type``).

    Raises
    ------
    argparse.ArgumentTypeError
        ``text`` is not a whole number, or is out of range.
    """
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"a seed is a whole number from 0 to {MAX_SEED}, "
                                         f"got {text!r}")
    return value


def hertz(text: str) -> float:
    """Read a control rate in Hz (an argparse ``type``), in the range every input shares."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a rate in Hz, got {text!r}") from None
    problem = RATE.problem(value, text)
    if problem is not None:
        raise argparse.ArgumentTypeError(problem)
    return value


def writable_output(path: str, option: str, suffixes: tuple[str, ...] = ()) -> None:
    """Check, before any work, that ``path`` can be written (created or replaced).

    ``option`` names the place in the message (``--plot``, ``-o``); ``suffixes`` are the
    file name endings accepted (any when empty).

    Raises
    ------
    MdleError
        The suffix is not accepted, the folder does not exist or cannot be written, or
        the path is a folder or a file that cannot be written.
    """
    from mdle.core.errors import Diagnostic, MdleError

    def refuse(why: str) -> MdleError:
        return MdleError(Diagnostic(None, f"{option} `{path}`: {why}"))

    if suffixes and os.path.splitext(path)[1].lower() not in suffixes:
        raise refuse("the file name must end in " + _either(suffixes))
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise refuse(f"there is no folder `{folder}`")
    if os.path.isdir(path):
        raise refuse("that is a folder, not a file")
    if os.path.exists(path):
        if not os.access(path, os.W_OK):
            raise refuse("the file cannot be written (permission denied or read-only)")
    elif not os.access(folder, os.W_OK | os.X_OK):
        raise refuse(f"files cannot be created in `{folder}` (permission denied or "
                     "read-only)")


def _either(items: tuple[str, ...]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " or " + items[-1]
