"""No output of a command is one of its inputs, or another of its outputs.

``mdle run p.mdle --trace p.mdle`` once replaced the plan with its trace, and
``mdle export t.jsonl -o t.jsonl`` the trace with a partial MCAP. Every command that
writes files calls :func:`refuse_clobbering` with what it writes and what it reads before
it writes anything. Paths are compared as files (device and inode), so the same file by
another name (``./p.mdle``, a symbolic or hard link) is caught too; an output that does
not exist yet cannot be an input.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Iterable, Sequence

from mdle.core.errors import Diagnostic, MdleError
from mdle.core.userfile import same_file

__all__ = ["refuse_clobbering", "run_inputs", "run_outputs"]


def _norm(path: str) -> str:
    return os.path.normcase(os.path.abspath(path))


def refuse_clobbering(outputs: Sequence[tuple[str, str | None]],
                      inputs: Iterable[tuple[str, str | None]]) -> None:
    """Refuse outputs that are inputs, or that name the same file twice.

    ``outputs`` and ``inputs`` are ``(what, path)`` pairs: ``("--trace", "run.jsonl")``,
    ``("the plan", "p.mdle")``; a None path is skipped.

    Raises
    ------
    MdleError
        Naming the output's option, its path and the input (or output) it would replace.
    """
    wanted = [(what, path) for what, path in outputs if path]
    sources = [(what, path) for what, path in inputs if path]
    for i, (option, path) in enumerate(wanted):
        for what, source in sources:
            if _norm(path) == _norm(source) or same_file(path, source):
                raise MdleError(Diagnostic(
                    None, f"{option} `{path}` is {what} `{source}`, an input of this command: "
                          "mdle never writes over its inputs",
                    hint="write the output to another file"))
        for other, earlier in wanted[:i]:
            if _norm(path) == _norm(earlier) or same_file(path, earlier):
                raise MdleError(Diagnostic(
                    None, f"{option} `{path}` and {other} `{earlier}` name the same file",
                    hint="give each output its own file"))


def run_outputs(args: argparse.Namespace) -> list[tuple[str, str | None]]:
    """Return the files ``mdle run`` writes, by option."""
    return [(option, getattr(args, option[2:], None))
            for option in ("--trace", "--record", "--rosbag", "--plot")]


def run_inputs(args: argparse.Namespace,
               sources: Iterable[str] = ()) -> list[tuple[str, str | None]]:
    """Return the files ``mdle run`` reads: the plan, its imports, world and robot files."""
    from mdle.cli.options import world_beside

    plan = getattr(args, "plan", None)
    found: list[tuple[str, str | None]] = [("the plan", plan)]
    found += [("the imported file", s) for s in sources if not s.startswith("<")]
    beside = world_beside(plan) if plan else None
    found += [("the world", getattr(args, "world", None)),
              ("the world", os.fspath(beside) if beside else None),
              ("the robot profile", getattr(args, "robot", None)),
              ("the team file", getattr(args, "team", None))]
    return found
