"""``mdle run``: run a plan in the embedded simulator or on a robot.

Over 500 lines: one command, whose options, backends (simulator, Pioneer, ROS 2) and
outputs share one run's parts and its clean end from wherever it is interrupted.

Exit codes: 0 the program ran to its end (or to ``--until``), 1 plan or world errors
(shown as ``mdle check`` shows them) and robot or connection faults, 3 the robot
collided or stalled fatally, 74 the trace or a recording could not be written (disk
full: the run is ended), 130 Ctrl-C (143 SIGTERM, 129 SIGHUP), 141 standard output
closed (``| head``: the run is ended). The robot is stopped, and a requested trace
ends with its end record and the stop command, in every case; a signal that comes
before the run could start still leaves a trace (header and end record) saying so.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import re
import sys
import tempfile
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mdle.cli.clobber import refuse_clobbering, run_inputs, run_outputs
from mdle.cli.options import (
    DEFAULT_RATE,
    add_simulation_options,
    hertz,
    known_robot,
    seconds,
    world_beside,
    writable_output,
)
from mdle.cli.recorders import recorders
from mdle.cli.ros2 import add_ros2_options, check_ros2_options, open_ros2_backend
from mdle.console import output
from mdle.console.ending import keep_to_the_end
from mdle.console.signals import SignalGuard, interruption_of, signal_name
from mdle.core.errors import Diagnostic, MdleError
from mdle.core.ranges import COORDINATE, HEADING

if TYPE_CHECKING:
    from mdle.record.trace import TraceWriter
    from mdle.runtime import RunResult, Scheduler
    from mdle.view.live import LiveView

__all__ = ["add_parser", "run", "world_beside"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle run``."""
    p = subparsers.add_parser(
        "run", help="run a plan in the simulator or on a robot",
        description="Run an MDLe plan: in the embedded simulator by default, or on a "
                    "Pioneer with --backend pioneer. Shows a live view on a terminal; writes "
                    "a JSON lines trace and a plot on request.",
        epilog="Exit codes: 0 done, 1 errors in the plan or world (or a robot fault), "
               "3 collided or stalled, 74 the trace could not be written (disk full), "
               "130 Ctrl-C, 143 SIGTERM, 141 standard output closed.")
    p.add_argument("plan", metavar="PLAN.mdle", nargs="?",
                   help="the plan file (none with --team or --robot-plan)")
    p.add_argument("--team", metavar="TEAM.yaml",
                   help="run a team: several robots of one world, each with its own plan "
                        "(a team file maps robots to plans; docs/teams.md)")
    p.add_argument("--robot-plan", dest="robot_plan", action="append", default=[],
                   metavar="NAME=PLAN.mdle",
                   help="run a team: robot NAME of the world (--world) runs PLAN.mdle; "
                        "repeatable, and overrides the team file's plan for that robot")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="simulated world: a reference world name or a YAML file (default: "
                        "PLAN.world.yaml or PLAN.yaml beside the plan, else the default world)")
    p.add_argument("--plan", dest="element", metavar="NAME",
                   help="element to run (default: the file's `run` target, else `main`)")
    p.add_argument("--laws", metavar="FILE.py",
                   help="a Python file of your own control laws and sensor functions")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="NAME=VALUE",
                   help="override a parameter's default, with units as in a plan: "
                        "`--set cruise.v=0.2m/s`, `--set 'rc=1 m'` (DEFINITION.PARAMETER, or "
                        "a parameter name: every definition's parameter of that name); "
                        "repeatable")
    p.add_argument("--start", type=start_pose, metavar="X,Y,THETA",
                   help="simulator only: start the robot at X, Y (metres) heading THETA "
                        "(degrees, counter-clockwise from the world's x axis) instead of the "
                        "world's start; units may be written: `--start '150cm,-2m,1.57rad'`")
    p.add_argument("--until", type=seconds, metavar="SECONDS",
                   help="stop after this many seconds of (simulated) time")
    p.add_argument("--realtime", action="store_true",
                   help="pace the simulation to the wall clock")
    # default None: a team file's `rate:` applies unless --rate is given (even --rate 10)
    p.add_argument("--rate", type=hertz, default=None, metavar="HZ",
                   help="control rate (default: 10 Hz, the Pioneer's 100 ms cycle; with a "
                        "team, the team file's rate:)")
    p.add_argument("--trace", metavar="FILE.jsonl", help="write the run's trace (JSON lines)")
    p.add_argument("--record", metavar="FILE.mcap",
                   help="record the run as ROS 2 messages in an MCAP file (Foxglove, "
                        "PlotJuggler, ros2 bag); needs pip install 'mdle[mcap]'")
    p.add_argument("--rosbag", metavar="DIR",
                   help="record the run as a rosbag2 folder (DIR_0.mcap and metadata.yaml)")
    p.add_argument("--record-compression", choices=("none", "lz4"), default="none",
                   help="compression of the recording's chunks (default: none, the "
                        "cheapest to write; lz4: about a third smaller)")
    p.add_argument("--foxglove", metavar="[HOST:]PORT",
                   help="a live view for Foxglove: a WebSocket server on PORT (127.0.0.1 "
                        "unless HOST is given) with the recording's messages; needs pip "
                        "install 'mdle[foxglove]'")
    p.add_argument("--plot", metavar="FILE.png|svg", help="draw the run at the end")
    p.add_argument("--quiet", "-q", action="store_true", help="no live view or summary")
    p.add_argument("--backend", choices=("sim", "pioneer", "ros2"), default="sim",
                   help="where to run (default: sim; ros2: a ROS 2 robot, docs/ros2.md)")
    p.add_argument("--connect", metavar="URL",
                   help="robot connection for --backend pioneer (tcp://host:port, "
                        "serial:///dev/ttyS0)")
    p.add_argument("--laser", metavar="URL", help="laser connection for --backend pioneer")
    add_simulation_options(p)
    add_ros2_options(p)
    p.set_defaults(handler=run, own_signals=True)


def start_pose(text: str) -> tuple[float, float, float]:
    """Read ``X,Y,THETA`` (an argparse ``type``): metres, metres, degrees unless units say.

    Returns (x, y, theta) in SI (m, m, rad).

    Raises
    ------
    argparse.ArgumentTypeError
        Not three comma-separated numbers, a unit of the wrong kind, or a number out of
        range (a coordinate beyond 1e6 m, a heading beyond one turn, inf, nan).
    """
    from mdle.core.units import ANGLE, LENGTH, unit_value

    parts = text.split(",")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(
            f"expected X,Y,THETA (metres, metres, degrees), got {text!r}")
    out: list[float] = []
    for part, name, dim, unit in zip(parts, ("X", "Y", "THETA"), (LENGTH, LENGTH, ANGLE),
                                     ("m", "m", "deg"), strict=True):
        m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/ ]*?)\s*",
                         part)
        if m is None:
            raise argparse.ArgumentTypeError(f"{name} of --start: expected a number, got "
                                             f"{part.strip()!r}")
        try:
            factor, got = unit_value(m.group(2) or unit)
        except KeyError:
            raise argparse.ArgumentTypeError(
                f"{name} of --start: unknown unit {m.group(2)!r}") from None
        if got != dim:
            kind = "a length (m, cm, mm)" if dim == LENGTH else "an angle (deg, rad)"
            raise argparse.ArgumentTypeError(f"{name} of --start is {kind}, got "
                                             f"{part.strip()!r}")
        value = float(m.group(1)) * factor
        problem = (COORDINATE if dim == LENGTH else HEADING).problem(value, part.strip())
        if problem is not None:
            raise argparse.ArgumentTypeError(f"{name} of --start: {problem}")
        out.append(value)
    return out[0], out[1], out[2]


@dataclass
class _Parts:
    """What a run has opened so far, for a clean end from wherever it was interrupted."""

    header: dict[str, Any]
    backend: Any = None
    world: Any = None
    trace_path: str | None = None
    writer: TraceWriter | None = None
    live: LiveView | None = None
    scheduler: Scheduler | None = None
    tmpdir: Any = None
    observers: list[Any] = field(default_factory=list)
    recorders: list[Any] = field(default_factory=list)

    def close(self) -> None:
        """Close the observers, the backend (the robot) and the temporary folder."""
        for o in self.observers:
            close = getattr(o, "close", None)
            if close is not None:
                close()
        if self.backend is not None:
            self.backend.close()
        if self.tmpdir is not None:
            self.tmpdir.cleanup()


def run(args: argparse.Namespace) -> int:
    """Run the plan; returns the exit code.

    The signal guard (``args.signals``, installed by :func:`mdle.cli.main`) is armed
    while the plan and world load, deferred while the trace and scheduler are made and
    while everything closes, and stops the scheduler while it ticks.
    """
    from mdle.record.recorder import RecordingError  # imports none of the mcap extra
    from mdle.record.trace import TraceWriteError

    if args.team or args.robot_plan:
        from mdle.cli.team import run_team

        return run_team(args)
    if args.rate is None:
        args.rate = DEFAULT_RATE
    if args.plan is None:
        _say("mdle run: give a PLAN.mdle, or a team with --team TEAM.yaml or --robot-plan "
             "NAME=PLAN.mdle")
        return output.EXIT_USAGE
    guard: SignalGuard = getattr(args, "signals", None) or SignalGuard()
    parts = _Parts(_header(args))
    keep_to_the_end(args, parts)  # the world, the program: freed by the process's end
    try:
        guard.arm()
        try:
            return _run(args, guard, parts)
        except Exception as exc:
            signal_exc = interruption_of(exc)  # a signal Python wrapped (class creation)
            if signal_exc is None:
                raise
            raise signal_exc from None
    except KeyboardInterrupt as exc:
        keep_to_the_end(args, exc)  # what its frames built is freed by the process's end
        with guard.deferring():
            stopped = _end_interrupted(args, parts, exc)
        signum = guard.received if guard.received is not None else getattr(exc, "signum", 2)
        where = f", trace in {args.trace}" if args.trace and _trace_ended(parts) else ""
        _say(f"mdle run: interrupted by {signal_name(signum)}"
             + (f": robot stopped{where}" if stopped else f" before the run started{where}"))
        return 128 + signum
    except (TraceWriteError, RecordingError) as err:
        with guard.deferring():
            output.print_diagnostics(err.diagnostics)
        return output.EXIT_IO
    finally:
        with guard.deferring():
            parts.close()


def _run(args: argparse.Namespace, guard: SignalGuard, parts: _Parts) -> int:
    from mdle.atoms.installed_laws import registry_option
    from mdle.lang import load_program
    from mdle.runtime import Scheduler, element_of

    if args.plot:
        writable_output(args.plot, "--plot", (".png", ".svg", ".pdf"))
    if args.trace:
        writable_output(args.trace, "--trace")
    if args.record or args.rosbag:
        from mdle.record import require

        require("--record" if args.record else "--rosbag")
    if args.start is not None and args.backend != "sim":
        raise MdleError(Diagnostic(None, "--start places the simulated robot; a real robot "
                                         "starts where it stands"))
    check_ros2_options(args)
    robot = known_robot(args.plan, args.world, args.robot) if args.backend == "sim" \
        else known_robot(None, None, args.robot if args.backend == "ros2" else None)
    registry = registry_option(args.laws)
    try:
        program = load_program(args.plan, registry, settings=args.overrides, robot=robot)
    except MdleError as err:
        from mdle.lang import yaml_as_plan

        raise yaml_as_plan(args.plan, err, "to run a plan in this world: "
                          f"`mdle run PLAN.mdle --world {args.plan}`") from None
    if program.warnings and not args.quiet:
        output.print_diagnostics(program.warnings, program.sources)
    refuse_clobbering(run_outputs(args), run_inputs(args, program.sources))
    element = element_of(program, args.element)
    parts.header["program"].update(element=element.label, entry=program.entry)
    if args.overrides:
        parts.header["overrides"] = list(args.overrides)
    parts.backend, parts.world = _open_backend(args, parts.header)
    from mdle.record.describe import body_header  # the body and odometry noise, for recordings

    parts.header.update(body_header(parts.backend))
    from mdle.cli.frames import FRAME_NOTE, reads_pose

    if not args.quiet and reads_pose(program):
        where = ""
        if parts.world is not None:
            s = parts.world.start_pose
            where = (f" (here: the start pose in the world, x {s.x:g} m, y {s.y:g} m, heading "
                     f"{math.degrees(s.theta):.4g} deg)")
        _print(f"note: {FRAME_NOTE}{where}")

    with guard.deferring():  # the trace is made whole, header first, or not at all
        parts.trace_path = args.trace
        if args.plot and not args.trace:
            parts.tmpdir = tempfile.TemporaryDirectory(prefix="mdle-")
            parts.trace_path = os.path.join(parts.tmpdir.name, "run.jsonl")
        if parts.trace_path:
            parts.writer = _open_trace(parts.trace_path, parts.header)
            parts.observers.append(parts.writer)
        try:
            parts.recorders = recorders(args, parts.header, parts.world)
        except MdleError as err:  # cannot be created: a bad option (exit 1), not a full disk
            raise MdleError(err.diagnostics) from None
        parts.observers += parts.recorders
        if not args.quiet:
            from mdle.view.live import LiveView

            parts.live = LiveView()
            parts.observers.append(parts.live)
        scheduler = parts.scheduler = Scheduler(element, parts.backend, args.rate,
                                                parts.observers, until=args.until,
                                                realtime=args.realtime)
    with guard.stopping(scheduler):  # a signal that came meanwhile stops it at once
        scheduler.start()
        while scheduler.tick():
            pass
    result = scheduler.result
    assert result is not None
    writer = parts.writer
    if writer is not None and writer.error is not None:
        raise writer.error
    failed = False
    for r in parts.recorders:
        r.close()
        if r.error is not None:
            _say(f"mdle run: {r.error}")
            failed = True
    lost = parts.live.output_lost if parts.live is not None else None
    if args.plot:
        from mdle.view.plot import plot_trace

        assert parts.trace_path is not None
        plot_trace(parts.trace_path, args.plot, world=parts.world)
        if not args.quiet and lost is None:
            _print(f"plot written to {args.plot}")
    if guard.received is not None:
        _say(f"mdle run: interrupted by {signal_name(guard.received)}: robot stopped"
             + (f", trace in {args.trace}" if args.trace else "")
             + "".join(f", recording in {r.target}" for r in parts.recorders
                       if r.error is None))
        return guard.exit_code
    if lost is not None:
        output.output_closed()
        _say(f"mdle run: {result.reason or 'standard output lost'}: run stopped, robot "
             "stopped" + (f", trace in {args.trace}" if args.trace else ""))
        return output.EXIT_PIPE if isinstance(lost, BrokenPipeError) else output.EXIT_IO
    if failed:
        return output.EXIT_IO
    if result.collided or result.fault:
        hit = ("the robot collided: " + result.collision.describe(_t0(result))
               if result.collision is not None else "the robot collided")
        why = [w for w in (hit if result.collided else None,
                           result.fault) if w]
        _say(f"mdle run: {'; '.join(why)}")
        return output.EXIT_COLLISION
    return output.EXIT_OK


def _header(args: argparse.Namespace) -> dict[str, Any]:
    """Return the trace header's fields known before anything is loaded."""
    return {"program": {"file": os.path.abspath(args.plan), "element": args.element,
                        "entry": None},
            "rate": args.rate, "until": args.until, "backend": args.backend,
            "argv": sys.argv[1:]}


def _open_trace(path: str, header: dict[str, Any]) -> TraceWriter:
    from mdle.record.trace import TraceWriter

    if "\x00" in path:  # open() would raise ValueError, not OSError
        raise MdleError(Diagnostic(None, f"cannot write the trace `{path!r}`: the name holds "
                                         "a NUL character"))
    try:
        return TraceWriter(path, header)
    except OSError as exc:
        raise MdleError(Diagnostic(None, f"cannot write the trace `{path}`: "
                                         f"{exc.strerror}")) from None


def _end_interrupted(args: argparse.Namespace, parts: _Parts, exc: BaseException) -> bool:
    """End what the interruption left open; True when the run had begun (robot stopped).

    A scheduler that has not ended is stopped (the robot too, and the trace ends with the
    stop); a trace asked for before the run could begin gets its header and an end
    record that says so.
    """
    reason = getattr(exc, "reason", None) or "KeyboardInterrupt"
    scheduler = parts.scheduler
    if scheduler is not None:
        if scheduler.result is None:
            scheduler.request_stop(reason)
            scheduler.stop()
        return True
    if parts.backend is not None:
        parts.backend.stop()
    writer = parts.writer
    if writer is None and args.trace:
        try:
            writer = _open_trace(args.trace, parts.header)
        except Exception:  # noqa: BLE001 - nothing more to save; the signal is reported
            return parts.backend is not None
        parts.observers.append(writer)
    if writer is not None and not writer.ended:
        writer.on_end(_not_started(parts.header, f"{reason} before the run started"))
    return parts.backend is not None


def _not_started(header: dict[str, Any], reason: str) -> RunResult:
    """Return the result of a run that never began: stopped at t = 0, no tick."""
    from mdle.runtime import Cause, RunResult, Termination

    label = str(header["program"].get("element") or "")
    return RunResult(Termination(label, 0, Cause.STOPPED, 0.0), (), (), 0, 0.0, 0.0,
                     reason=reason)


def _trace_ended(parts: _Parts) -> bool:
    return any(getattr(o, "ended", False) for o in parts.observers)


def _say(text: str) -> None:
    """Print on standard error (nothing if that is gone too)."""
    try:
        print(text, file=sys.stderr)
    except OSError:
        pass


def _print(text: str) -> None:
    """Print on standard output; a closed one is left alone."""
    try:
        print(text)
    except BrokenPipeError:
        output.output_closed()


def _t0(result: Any) -> float:
    """Return the time of the run's first tick (the first event's), to report run times."""
    return result.events[0].time if result.events else 0.0


def _open_backend(args: argparse.Namespace, header: dict[str, Any]) -> tuple[Any, Any]:
    """Return the backend the options ask for and its world (None on hardware).

    Fills the header's world, seed and robot.
    """
    if args.backend == "ros2":  # mdle/cli/ros2.py
        return open_ros2_backend(args, args.rate, header), None
    if args.backend == "pioneer":
        if not args.connect:
            raise MdleError(Diagnostic(None, "--backend pioneer needs --connect URL",
                                       hint="e.g. --connect tcp://localhost:8101 or "
                                            "--connect serial:///dev/ttyS0"))
        from mdle.drivers import open_backend

        header.update(connect=args.connect, laser=args.laser)
        profile = None
        if args.robot:  # read before connecting: a bad profile touches no robot
            from mdle.sim.profiles import robot_profile

            profile = robot_profile(args.robot)
            header["robot"] = args.robot
        try:
            backend = open_backend("pioneer", args.connect, args.laser, rate=args.rate)
        except (KeyboardInterrupt, SystemExit):  # a signal while connecting: the backend
            # stopped and closed the robot
            print("interrupted while connecting: robot stopped, session closed",
                  file=sys.stderr)
            raise
        from mdle.drivers.pioneer import PioneerBackend

        if profile is not None and isinstance(backend, PioneerBackend):
            # the law's latency, the recording's base_link -> laser and scan period
            from mdle.drivers.profile import apply_robot_profile

            apply_robot_profile(backend, profile)
        return backend, None
    from mdle import sim

    spec: str | os.PathLike[str] | None = args.world
    if spec is None:
        spec = world_beside(args.plan)
    if spec is None:
        spec = sim.DEFAULT_WORLD
    world = sim.load_world(spec)
    spec_text = os.path.abspath(spec) if os.path.exists(spec) else str(spec)
    header["world"] = {"name": world.name, "spec": spec_text}
    header["seed"] = args.seed if args.seed is not None else world.seed
    header["robot"] = args.robot
    header["sensing"] = args.sensing
    kwargs: dict[str, Any] = {"seed": args.seed, "sensing": args.sensing}
    if args.robot:
        kwargs["robot"] = args.robot
    if args.start is not None:
        from mdle.core.pose import Pose

        world = dataclasses.replace(world, start_pose=Pose(*args.start))
        header["start"] = {"x": args.start[0], "y": args.start[1], "theta": args.start[2]}
    return sim.SimBackend(world, **kwargs), world
