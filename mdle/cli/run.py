"""``mdle run``: run a plan in the embedded simulator or on a robot.

Exit codes: 0 the program ran to its end (or to ``--until``), 1 plan or world errors
(shown as ``mdle check`` shows them) and robot or connection faults, 3 the robot
collided or stalled fatally, 130 Ctrl-C (143 SIGTERM): the robot is stopped and the
trace flushed in every case.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import re
import signal
import sys
import tempfile
from pathlib import Path
from typing import Any

from mdle.cli import output
from mdle.cli.options import add_simulation_options, seconds

__all__ = ["add_parser", "run", "world_beside"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle run``."""
    p = subparsers.add_parser(
        "run", help="run a plan in the simulator or on a robot",
        description="Run an MDLe plan: in the embedded simulator by default, or on a "
                    "Pioneer with --backend pioneer. Shows a live view on a terminal; writes "
                    "a JSON lines trace and a plot on request.",
        epilog="Exit codes: 0 done, 1 errors in the plan or world (or a robot fault), "
               "3 collided or stalled, 130 interrupted.")
    p.add_argument("plan", metavar="PLAN.mdle", help="the plan file")
    p.add_argument("--world", metavar="NAME|FILE",
                   help="simulated world: a reference world name or a YAML file (default: "
                        "PLAN.world.yaml or PLAN.yaml beside the plan, else the default world)")
    p.add_argument("--plan", dest="element", metavar="NAME",
                   help="element to run (default: the file's `run` target, else `main`)")
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
    p.add_argument("--rate", type=_hertz, default=10.0, metavar="HZ",
                   help="control rate (default: 10 Hz, the Pioneer's 100 ms cycle)")
    p.add_argument("--trace", metavar="FILE.jsonl", help="write the run's trace (JSON lines)")
    p.add_argument("--record", metavar="FILE.mcap",
                   help="record the run as ROS 2 messages in an MCAP file (Foxglove, "
                        "PlotJuggler, ros2 bag); needs pip install 'mdle[mcap]'")
    p.add_argument("--rosbag", metavar="DIR",
                   help="record the run as a rosbag2 folder (DIR_0.mcap and metadata.yaml)")
    p.add_argument("--plot", metavar="FILE.png|svg", help="draw the run at the end")
    p.add_argument("--quiet", "-q", action="store_true", help="no live view or summary")
    p.add_argument("--backend", choices=("sim", "pioneer"), default="sim",
                   help="where to run (default: sim)")
    p.add_argument("--connect", metavar="URL",
                   help="robot connection for --backend pioneer (tcp://host:port, "
                        "serial:///dev/ttyS0)")
    p.add_argument("--laser", metavar="URL", help="laser connection for --backend pioneer")
    add_simulation_options(p)
    p.set_defaults(handler=run)


def _hertz(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a rate in Hz, got {text!r}") from None
    if not 0 < value <= 1000:
        raise argparse.ArgumentTypeError(f"the rate must be in (0, 1000] Hz, got {text!r}")
    return value


def start_pose(text: str) -> tuple[float, float, float]:
    """Read ``X,Y,THETA`` (an argparse ``type``): metres, metres, degrees unless units say.

    Returns (x, y, theta) in SI (m, m, rad).

    Raises
    ------
    argparse.ArgumentTypeError
        Not three comma-separated numbers, or a unit of the wrong kind.
    """
    import math

    from mdle.units import ANGLE, LENGTH, unit_value

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
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{name} of --start must be finite")
        out.append(value)
    return out[0], out[1], out[2]


def world_beside(plan: str | os.PathLike[str]) -> Path | None:
    """Find the world file of a plan: ``x.world.yaml`` or ``x.yaml`` beside ``x.mdle``."""
    p = Path(plan)
    for candidate in (p.with_suffix(".world.yaml"), p.with_suffix(".yaml")):
        if candidate.is_file():
            return candidate
    return None


class _Signals:
    """SIGINT/SIGTERM ask the scheduler to stop at the next tick; a second one forces it."""

    def __init__(self) -> None:
        self.received: int | None = None
        self._old: dict[int, Any] = {}
        self.scheduler: Any = None

    def __enter__(self) -> "_Signals":
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self._old[sig] = signal.signal(sig, self._handle)
            except ValueError:  # not the main thread: leave the defaults
                pass
        return self

    def _handle(self, signum: int, frame: Any) -> None:
        if self.received is not None or self.scheduler is None:
            self.received = signum
            raise KeyboardInterrupt  # second signal: stop now (the scheduler stops the robot)
        self.received = signum
        self.scheduler.request_stop()

    def __exit__(self, *exc: object) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old)

    @property
    def exit_code(self) -> int:
        return 128 + (self.received or signal.SIGINT)


def run(args: argparse.Namespace) -> int:
    """Run the plan; returns the exit code."""
    from mdle.errors import Diagnostic, MdleError
    from mdle.loader import load_program
    from mdle.runtime import Scheduler, element_of

    if args.plot and os.path.splitext(args.plot)[1].lower() not in (".png", ".svg", ".pdf"):
        raise MdleError(Diagnostic(None, f"--plot `{args.plot}`: the file name must end in "
                                         ".png, .svg or .pdf"))
    if args.record or args.rosbag:
        from mdle.ros import require

        require("--record" if args.record else "--rosbag")
    if args.start is not None and args.backend != "sim":
        raise MdleError(Diagnostic(None, "--start places the simulated robot; a real robot "
                                         "starts where it stands"))
    program = load_program(args.plan, settings=args.overrides)
    if program.warnings and not args.quiet:
        output.print_diagnostics(program.warnings, program.sources)
    element = element_of(program, args.element)

    header: dict[str, Any] = {
        "program": {"file": os.path.abspath(args.plan), "element": element.label,
                    "entry": program.entry},
        "rate": args.rate, "until": args.until, "backend": args.backend,
        "argv": sys.argv[1:],
    }
    if args.overrides:
        header["overrides"] = list(args.overrides)
    backend, world = _open_backend(args, header)
    from mdle.frames import FRAME_NOTE, reads_pose

    if not args.quiet and reads_pose(program):
        where = ""
        if world is not None:
            s = world.start_pose
            where = (f" (here: the start pose in the world, x {s.x:g} m, y {s.y:g} m, heading "
                     f"{math.degrees(s.theta):.4g} deg)")
        print(f"note: {FRAME_NOTE}{where}")
    observers: list[Any] = []
    trace_path = args.trace
    tmpdir = None
    try:
        if args.plot and not trace_path:
            tmpdir = tempfile.TemporaryDirectory(prefix="mdle-")
            trace_path = os.path.join(tmpdir.name, "run.jsonl")
        if trace_path:
            from mdle.trace import TraceWriter

            try:
                observers.append(TraceWriter(trace_path, header))
            except OSError as exc:
                raise MdleError(Diagnostic(None, f"cannot write the trace `{trace_path}`: "
                                                 f"{exc.strerror}")) from None
        recorders = _recorders(args, header, world)
        observers += recorders
        if not args.quiet:
            from mdle.live import LiveView

            observers.append(LiveView())
        scheduler = Scheduler(element, backend, args.rate, observers, until=args.until,
                              realtime=args.realtime)
        with _Signals() as signals:
            signals.scheduler = scheduler
            try:
                scheduler.start()
                while scheduler.tick():
                    pass
            except KeyboardInterrupt:
                # A second Ctrl-C: inside a tick the scheduler has already ended the run;
                # between two ticks it has not, so end it here (stop() does nothing twice).
                scheduler.stop()
        result = scheduler.result
        assert result is not None
        failed = False
        for r in recorders:
            r.close()
            if r.error is not None:
                print(f"mdle run: {r.error}", file=sys.stderr)
                failed = True
        if args.plot:
            from mdle.plot import plot_trace

            plot_trace(trace_path, args.plot, world=world)
            if not args.quiet:
                print(f"plot written to {args.plot}")
        if signals.received is not None:
            print("interrupted: robot stopped" + (f", trace in {args.trace}" if args.trace
                                                  else "")
                  + "".join(f", recording in {r.target}" for r in recorders
                            if r.error is None), file=sys.stderr)
            return signals.exit_code
        if failed:
            return output.EXIT_INPUT
        if result.collided or result.fault:
            hit = ("the robot collided: " + result.collision.describe(_t0(result))
                   if result.collision is not None else "the robot collided")
            why = [w for w in (hit if result.collided else None,
                               result.fault) if w]
            print(f"mdle run: {'; '.join(why)}", file=sys.stderr)
            return output.EXIT_COLLISION
        return output.EXIT_OK
    finally:
        for o in observers:
            close = getattr(o, "close", None)
            if close is not None:
                close()
        backend.close()
        if tmpdir is not None:
            tmpdir.cleanup()


def _recorders(args: argparse.Namespace, header: dict[str, Any], world: Any) -> list[Any]:
    """Return the MCAP recorders ``--record`` and ``--rosbag`` ask for."""
    if not (args.record or args.rosbag):
        return []
    from mdle.ros.recorder import McapRecorder

    out = []
    if args.record:
        out.append(McapRecorder(args.record, header, world))
    if args.rosbag:
        out.append(McapRecorder(args.rosbag, header, world, rosbag=True))
    return out


def _t0(result: Any) -> float:
    """Return the time of the run's first tick (the first event's), to report run times."""
    return result.events[0].time if result.events else 0.0


def _open_backend(args: argparse.Namespace, header: dict[str, Any]) -> tuple[Any, Any]:
    """Return the backend the options ask for and its world (None on hardware).

    Fills the header's world, seed and robot.
    """
    from mdle.errors import Diagnostic, MdleError

    if args.backend == "pioneer":
        if not args.connect:
            raise MdleError(Diagnostic(None, "--backend pioneer needs --connect URL",
                                       hint="e.g. --connect tcp://localhost:8101 or "
                                            "--connect serial:///dev/ttyS0"))
        from mdle.drivers import open_backend

        header.update(connect=args.connect, laser=args.laser)
        try:
            return open_backend("pioneer", args.connect, args.laser, rate=args.rate), None
        except SystemExit:  # SIGTERM while connecting: the backend stopped and closed it
            print("interrupted while connecting: robot stopped, session closed",
                  file=sys.stderr)
            raise
    import sim

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
        from mdle.backend import Pose

        world = dataclasses.replace(world, start_pose=Pose(*args.start))
        header["start"] = {"x": args.start[0], "y": args.start[1], "theta": args.start[2]}
    return sim.SimBackend(world, **kwargs), world
