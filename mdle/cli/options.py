"""Options and argument types that ``mdle run`` and ``mdle repl`` share.

Both drive the embedded simulator, so they take the same simulation options and read
durations the same way (a number of seconds; ``inf`` for no limit).
"""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_simulation_options", "positive_seconds", "seconds"]


def add_simulation_options(p: Any) -> None:
    """Add ``--seed``, ``--robot`` and ``--sensing`` (the simulated robot) to a parser."""
    p.add_argument("--seed", type=int, help="random seed of the simulation (default: the world's)")
    p.add_argument("--robot", metavar="PROFILE",
                   help="robot profile in simulation: a name (`mdle robots` lists them) or "
                        "a profile YAML file (default: the world's)")
    p.add_argument("--sensing", choices=("scan", "exact"), default="scan",
                   help="simulated ladar: a noisy scan (default) or exact oracle geometry")


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
