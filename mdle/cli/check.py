"""``mdle check FILE...``: parse and check plans; report every error and warning.

Everything the command prints goes to standard output (diagnostics and the summary),
so ``mdle check plan.mdle | less`` shows it all; the exit code tells the result:
0 clean (warnings allowed unless ``--strict``), 1 errors, 2 usage errors.

Constant speeds and turn rates are compared with the robot ``mdle run`` would use
(``--robot``, else the robot of ``--world``, of the world beside the plan, or the default
robot). A file with nothing to run is a warning, unless another file checked with it
imports it (a library of definitions).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mdle.core.errors import Diagnostic, MdleError
    from mdle.core.motion_limits import KnownRobot
    from mdle.lang import Program

__all__ = ["add_parser", "run", "expand_paths"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle check``."""
    p = subparsers.add_parser(
        "check", help="check plans for errors (syntax, names, units, timers)",
        description="Parse and check MDLe plans: names, arguments, units, interrupts, "
                    "timers, imports, constant speeds and turn rates against the robot's "
                    "limits. Prints every error and warning (to standard output) with "
                    "file:line:col and the source line. Exit code: 0 clean, 1 errors, "
                    "2 usage errors.")
    p.add_argument("files", nargs="+", metavar="FILE",
                   help="plan files; a folder means every .mdle file under it; a team file "
                        "(.yaml) is checked whole: its world, every robot's plan, and the "
                        "messages and robot names across them; a world file (.yaml with "
                        "obstacles, start, robot... and no `world:` key) is checked as a world")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="print errors only (no warnings, no summary)")
    p.add_argument("--strict", action="store_true", help="treat warnings as errors (exit 1)")
    p.add_argument("--laws", metavar="FILE.py",
                   help="a Python file of your own control laws and sensor functions")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="the world the plans run in: its robot's limits are checked (default: "
                        "PLAN.world.yaml or PLAN.yaml beside each plan, else the default world)")
    p.add_argument("--robot", metavar="PROFILE",
                   help="the robot profile the plans run on (a name or a YAML file; default: "
                        "the world's)")
    p.set_defaults(handler=run)


def expand_paths(paths: list[str]) -> list[str]:
    """Files as given; a folder becomes its .mdle files (recursively, sorted)."""
    out: list[str] = []
    for p in paths:
        if os.path.isdir(p):
            found = sorted(os.path.join(root, f) for root, _, files in os.walk(p)
                           for f in files if f.endswith(".mdle"))
            out.extend(found)
        else:
            out.append(p)
    return out


def _load(path: str, args: argparse.Namespace,
          robots: dict[tuple[str, ...], KnownRobot]) -> Program | MdleError:
    from mdle.cli.options import known_robot
    from mdle.core.errors import MdleError
    from mdle.lang import load_program

    try:
        robot = known_robot(path, args.world, args.robot, robots)
        return load_program(path, getattr(args, "registry", None), robot=robot)
    except MdleError as err:
        return err


#: Top-level keys only a world file has (a team file names its world under ``world:``).
_WORLD_KEYS = frozenset(("name", "description", "start", "robot", "ladar", "extent",
                         "obstacles"))
_TOP_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)[ \t]*:", re.MULTILINE)


def _is_world_file(path: str) -> bool:
    """Return True for a YAML file whose top-level keys are a world's, not a team's.

    Only the keys at column 0 are looked at (no YAML is loaded here): the file is read
    whole later, with the size and nesting limits, by whichever reader it goes to.
    """
    from mdle.core.userfile import UserFileError, read_user_file

    try:
        text = read_user_file(path).decode("utf-8", "replace")
    except (UserFileError, OSError):
        return False  # the team reader reports it
    keys = set(_TOP_KEY.findall(text))
    return "world" not in keys and bool(keys & _WORLD_KEYS)


def _check_world(path: str, quiet: bool) -> None:
    """Check a world file (WorldError on errors) and say what it holds."""
    from mdle.sim.world_yaml import read_world

    world = read_world(path)
    if not quiet:
        n = len(world.obstacles)
        print(f"{path}: a world, {n} obstacle{'s' * (n != 1)}", file=sys.stdout)


def _check_team(path: str, quiet: bool) -> int:
    """Check a team file and its plans (MdleError on errors); returns the warnings."""
    from mdle.console.output import print_diagnostics
    from mdle.team.file import load_team, read_team

    if _is_world_file(path):
        _check_world(path, quiet)
        return 0
    team = load_team(read_team(path))
    found = list(team.warnings)
    for program in team.programs.values():
        found += program.warnings
    if found and not quiet:
        print_diagnostics(found, team.sources, stream=sys.stdout)
    return len(found)


def run(args: argparse.Namespace) -> int:
    """Check each file; returns the exit code."""
    from mdle.cli.frames import FRAME_NOTE, reads_pose
    from mdle.console.ending import keep_to_the_end
    from mdle.console.output import EXIT_INPUT, EXIT_OK, print_diagnostics
    from mdle.core.errors import MdleError
    from mdle.lang import missing_entry

    files = expand_paths(args.files)
    from mdle.atoms.installed_laws import registry_option

    args.registry = registry_option(args.laws)  # installed packages' laws, --laws
    robots: dict[tuple[str, ...], KnownRobot] = {}  # each world or profile read once
    teams = (".yaml", ".yml")  # a team file (its plans are checked with it)
    results = {path: _load(path, args, robots) for path in files if not path.endswith(teams)}
    keep_to_the_end(args, results)  # freed by the process's end, not one by one here
    imported = {os.path.realpath(name) for path, r in results.items()
                if not isinstance(r, MdleError)
                for name in r.sources if name != path and not name.startswith("<")}
    errors = warnings = failed = 0
    pose = False
    for path in files:
        if path.endswith(teams):
            try:
                warnings += _check_team(path, args.quiet)
            except MdleError as err:
                failed += 1
                errors += len(err.diagnostics)
                print_diagnostics(err.diagnostics, err.sources, stream=sys.stdout)
            continue
        result = results[path]
        if isinstance(result, MdleError):
            failed += 1
            errors += len(result.diagnostics)
            print_diagnostics(result.diagnostics, result.sources, stream=sys.stdout)
            continue
        pose = pose or reads_pose(result)
        found: list[Diagnostic] = list(result.warnings)
        if os.path.realpath(path) not in imported:
            no_entry = missing_entry(result, path)
            if no_entry is not None:
                found.append(no_entry)
        warnings += len(found)
        if found and not args.quiet:
            print_diagnostics(found, result.sources, stream=sys.stdout)
    if not args.quiet:
        summary = (f"checked {len(files)} file{'s' * (len(files) != 1)}: "
                   f"{errors} error{'s' * (errors != 1)}, {warnings} warning"
                   f"{'s' * (warnings != 1)}")
        print(summary if files else "no .mdle files found", file=sys.stdout)
        if pose:
            print(f"note: {FRAME_NOTE}", file=sys.stdout)
    if failed or (args.strict and warnings) or not files:
        return EXIT_INPUT
    return EXIT_OK
