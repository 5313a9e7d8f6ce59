"""``mdle repl``: compose atoms and try them on a simulated robot (or a real one), interactively.

On a terminal: a prompt with history, completion and highlighting. With input piped in:
plain lines, no control codes, exit 0 or 1 if any input failed. With ``--backend pioneer``
the same session drives a robot: it asks before the first motion (``--yes`` skips the
question), and every way out stops the robot and closes the connection.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING, Any

from mdle.cli.options import add_simulation_options, positive_seconds
from mdle.cli.ros2 import add_ros2_options, check_ros2_options, open_ros2_backend

if TYPE_CHECKING:
    from mdle.repl.robot import RobotSession

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle repl``."""
    p = subparsers.add_parser(
        "repl", help="compose and try atoms interactively on a simulated robot (or a real one)",
        description="An interactive session with a simulated robot, or with a Pioneer "
                    "(--backend pioneer): type MDLe definitions to add them and elements to "
                    "run them from where the robot is; `:help` lists the commands. With "
                    "input piped in, reads it line by line and exits with 0, or 1 if any "
                    "input failed. On a robot the first motion is confirmed (--yes skips "
                    "it) and every way out stops the robot.",
        epilog="History is kept in $XDG_DATA_HOME/mdle/repl_history "
               "(~/.local/share/mdle/repl_history).")
    p.add_argument("file", nargs="?", metavar="FILE.mdle", help="definitions to load first")
    p.add_argument("--laws", metavar="FILE.py",
                   help="a Python file of your own control laws and sensor functions")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="simulated world: a reference world name or a YAML file "
                        "(default: the default world)")
    add_simulation_options(p)
    p.add_argument("--backend", choices=("sim", "pioneer", "ros2"), default="sim",
                   help="what the session drives: the simulator (default), a Pioneer or a "
                        "ROS 2 robot")
    p.add_argument("--connect", metavar="URL",
                   help="robot connection for --backend pioneer (tcp://host:port, "
                        "serial:///dev/ttyS0?baud=9600)")
    p.add_argument("--laser", metavar="URL",
                   help="laser for --backend pioneer: sim or lms200:///dev/DEVICE?baud=38400")
    add_ros2_options(p)
    p.add_argument("--yes", "-y", action="store_true",
                   help="on a robot, do not ask before the first motion (scripted sessions)")
    p.add_argument("--until", type=positive_seconds, metavar="SECONDS",
                   help="stop any run after this many seconds (simulated, or wall-clock on "
                        "a robot; default 600; `inf`: no limit)")
    p.add_argument("--realtime", action="store_true",
                   help="pace runs to the wall clock (default: as fast as the simulator goes)")
    p.add_argument("--foxglove", metavar="[HOST:]PORT",
                   help="show every run live in Foxglove: a WebSocket server on PORT "
                        "(127.0.0.1 unless HOST); needs pip install 'mdle[foxglove]'")
    p.add_argument("--plain", action="store_true",
                   help="read input plainly even on a terminal (no line editing)")
    p.add_argument("--echo", action="store_true",
                   help="with plain input, print each input after the prompt (a transcript)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Start the session; returns the exit code."""
    from mdle.console import output
    from mdle.repl.commands import Repl
    from mdle.repl.session import DEFAULT_UNTIL, Session

    until = DEFAULT_UNTIL if args.until is None else (None if math.isinf(args.until)
                                                      else args.until)
    interactive = sys.stdin.isatty() and sys.stdout.isatty() and not args.plain
    if args.backend == "sim" and (args.connect or args.laser or args.yes):
        from mdle.core.errors import Diagnostic, MdleError

        given = next(f for f, v in (("--connect", args.connect), ("--laser", args.laser),
                                    ("--yes", args.yes)) if v)
        raise MdleError(Diagnostic(None, f"{given} drives a robot: it needs --backend pioneer",
                                   hint="e.g. mdle repl --backend pioneer --connect "
                                        "tcp://localhost:8101 --laser sim"))
    check_ros2_options(args)
    session: Session
    if args.backend == "ros2":
        session = _ros2_session(args, until)
    elif args.backend == "pioneer":
        session = _robot_session(args, until)
    else:
        from mdle.atoms.installed_laws import registry_option

        session = Session(args.world, seed=args.seed, until=until, robot=args.robot,
                          sensing=args.sensing, realtime=args.realtime,
                          registry=registry_option(args.laws))
    repl = Repl(session, debug=getattr(args, "debug", False))
    live = None
    try:
        if args.foxglove:
            from mdle.view.foxglove import FoxgloveServer, LiveRuns, parse_address

            live = LiveRuns(FoxgloveServer(*parse_address(args.foxglove)))
            repl.run_observers.append(live)
            print(f"live view: ws://{live.server.host}:{live.server.port} "
                  "(Foxglove: Open connection)")
        if args.file:
            repl.handle(f":load {_quote(args.file)}")
            if repl.failures and not interactive:
                return output.EXIT_INPUT
        if interactive:
            from mdle.repl.prompt import run_prompt

            return run_prompt(repl)
        from mdle.repl.plain import run_plain

        stdin = sys.stdin
        if hasattr(stdin, "reconfigure"):  # bytes that are not UTF-8 reach run_plain as such
            stdin.reconfigure(errors="surrogateescape")
        return run_plain(repl, stdin, echo=args.echo)
    finally:
        if live is not None:
            live.close()
        _close(session, repl)


def _robot_session(args: argparse.Namespace, until: float | None) -> RobotSession:
    """Connect to the robot the options name and wrap it in a REPL session."""
    from mdle.core.errors import Diagnostic, MdleError
    from mdle.drivers import open_backend
    from mdle.drivers.pioneer import PioneerBackend
    from mdle.repl.robot import RobotSession

    if not args.connect:
        raise MdleError(Diagnostic(None, "--backend pioneer needs --connect URL",
                                   hint="e.g. --connect tcp://localhost:8101 or "
                                        "--connect serial:///dev/ttyS0"))
    profile = None
    if args.robot:  # read before connecting: a bad profile touches no robot
        from mdle.sim.profiles import robot_profile

        profile = robot_profile(args.robot)
    try:
        backend = open_backend("pioneer", args.connect, args.laser)
    except (KeyboardInterrupt, SystemExit):  # a signal while connecting: the backend
        # stopped and closed the robot
        print("interrupted while connecting: robot stopped, session closed", file=sys.stderr)
        raise
    assert isinstance(backend, PioneerBackend), "open_backend('pioneer') makes a Pioneer"
    if profile is not None:  # the law's latency and the ladar, as in `mdle run`
        from mdle.drivers.profile import apply_robot_profile

        apply_robot_profile(backend, profile)
    info = backend.info
    name = f"`{info.name or 'Pioneer'}` ({info.subtype or 'unknown model'})"
    try:
        session = RobotSession(backend, connect=args.connect, laser=args.laser,
                               until=until, armed=args.yes, name=name)
    except BaseException:
        backend.close()
        raise
    if sys.stdin.isatty():  # plain input on a terminal: ask there (the prompt asks itself)
        session.confirm = _ask_on_stdin
    return session


def _ros2_session(args: argparse.Namespace, until: float | None) -> RobotSession:
    """Connect to the ROS 2 robot the options name and wrap it in a REPL session."""
    from mdle.repl.robot import RobotSession

    backend = open_ros2_backend(args, 10.0, {})
    try:
        session = RobotSession(backend, connect=backend.description, laser=None,
                               until=until, armed=args.yes, name="the ROS 2 robot")
    except BaseException:
        backend.close()
        raise
    if sys.stdin.isatty():
        session.confirm = _ask_on_stdin
    return session


def _ask_on_stdin(question: str) -> bool:
    """Ask a yes/no question on the terminal; only `y` or `yes` is a yes."""
    try:
        answer = input(f"{question} [y/N] ")
    except EOFError:
        return False
    return answer.strip().lower() in ("y", "yes")


def _close(session: Any, repl: Any) -> None:
    """Release the session's robot and say so (nothing to say in simulation)."""
    if session.simulated:
        return
    session.close()
    how = getattr(session.hardware, "goodbye", None)
    what = {"stopped": "robot stopped", "link lost": "the link was already lost",
            "not confirmed": "stop sent, but the robot did not report its wheels stopped",
            }.get(how or "", "robot stopped")
    print(f"{what}; connection to {session.hardware.description} closed", file=sys.stderr)


def _quote(path: str) -> str:
    import shlex

    return shlex.quote(path)
