"""``mdle run --team TEAM.yaml`` and ``mdle run --world W --robot-plan NAME=PLAN.mdle``.

Loads the team (world with robots, each robot's plan), checks every plan and then the
team's messages and robot names, runs all robots in one tick loop, writes one trace per
robot (``--trace run.jsonl`` gives ``run.NAME.jsonl``), draws every path in one plot, and
prints a line per robot. Exit codes as for one robot: 0 done, 1 errors, 3 a collision (a
robot touched a wall or another robot) or a fault, 128 + N on a signal.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

from mdle.cli.clobber import refuse_clobbering, run_inputs
from mdle.cli.options import DEFAULT_RATE, writable_output
from mdle.console import output
from mdle.console.signals import SignalGuard, signal_name
from mdle.core.errors import Diagnostic, MdleError

__all__ = ["run_team", "trace_paths"]


def trace_paths(trace: str, names: list[str]) -> dict[str, str]:
    """Return each robot's trace file: ``run.jsonl`` -> ``run.NAME.jsonl``."""
    p = Path(trace)
    suffix = p.suffix or ".jsonl"
    return {n: str(p.with_name(f"{p.stem}.{n}{suffix}")) for n in names}


def run_team(args: argparse.Namespace) -> int:
    """Run a team; returns the exit code."""
    from mdle.record.trace import TraceWriter
    from mdle.sim.team import TeamSim
    from mdle.team.run import TeamRun

    guard: SignalGuard = getattr(args, "signals", None) or SignalGuard()
    if args.start is not None or args.robot or args.backend != "sim":
        raise MdleError(Diagnostic(None, "--start, --robot and --backend are for one robot; "
                                         "a team's robots, profiles and starts are in its "
                                         "world and team file"))
    if args.record or args.rosbag:
        from mdle.record import require

        require("--record" if args.record else "--rosbag")
    if args.plan is not None:
        raise MdleError(Diagnostic(None, f"a team run takes no PLAN ({args.plan}): each "
                                         "robot's plan is in the team file or --robot-plan"))
    if args.plot:
        writable_output(args.plot, "--plot", (".png", ".svg", ".pdf"))
    if args.trace:
        writable_output(args.trace, "--trace")
    guard.arm()
    from mdle.team.file import TeamSpec, load_team, read_team, robot_plan

    spec = read_team(args.team) if args.team else TeamSpec(None, ())
    spec = dataclasses.replace(spec, members=spec.members + tuple(
        robot_plan(t) for t in args.robot_plan))
    team = load_team(spec, world=args.world, overrides=args.overrides)
    if not args.quiet:
        for program in team.programs.values():
            if program.warnings:
                output.print_diagnostics(program.warnings, program.sources)
        if team.warnings:
            output.print_diagnostics(team.warnings, team.sources)
    world, programs, elements, plans = team.world, team.programs, team.elements, team.plans
    seed = args.seed if args.seed is not None else (
        spec.seed if spec.seed is not None else world.seed)
    rules = spec.rules
    rate = args.rate if args.rate is not None else (
        spec.rate if spec.rate is not None else DEFAULT_RATE)
    until = args.until if args.until is not None else spec.until
    names = [r.name for r in world.robots]
    traces = trace_paths(args.trace, names) if args.trace else {}
    refuse_clobbering([("--plot", args.plot), *(("--trace", t) for t in traces.values())],
                      run_inputs(args, [s for p in programs.values() for s in p.sources]))
    writers: dict[str, Any] = {}
    tmp = None
    trace = args.trace
    if args.plot and not trace:
        tmp = tempfile.TemporaryDirectory(prefix="mdle-team-")
        trace = os.path.join(tmp.name, "run.jsonl")
    run: TeamRun | None = None
    recordings: list[Any] = []
    try:
        with guard.deferring():
            sim_team = TeamSim(world, world.robots, seed=seed, sensing=args.sensing,
                               rules=rules)
            if trace:
                for name, path in trace_paths(trace, [n for n in names if n in elements]).items():
                    writers[name] = TraceWriter(path, _header(args, spec, world, seed, rate,
                                                              until, name, plans[name],
                                                              programs[name],
                                                              elements[name].label))
            observers: dict[str, list[Any]] = {n: [w] for n, w in writers.items()}
            recordings = _recordings(args, {n: _header(args, spec, world, seed, rate, until,
                                                       n, plans[n], programs[n],
                                                       elements[n].label)
                                            for n in names if n in elements}, world)
            for rec in recordings:
                for name, recorder in rec.recorders.items():
                    observers.setdefault(name, []).append(recorder)
            run = TeamRun(sim_team, elements, rate, until, observers,
                          realtime=args.realtime)
        with guard.stopping(run):
            results = run.run()
    except KeyboardInterrupt:
        with guard.deferring():
            if run is not None:
                run.stop()
        signum = guard.received if guard.received is not None else 2
        _say(f"mdle run: interrupted by {signal_name(signum)}: robots stopped"
             + (", traces ended" if writers else ""))
        return 128 + signum
    finally:
        with guard.deferring():
            for w in writers.values():
                w.close()
            for rec in recordings:
                rec.close()
    for w in writers.values():
        if w.error is not None:
            raise w.error
    for rec in recordings:
        if rec.error is not None:
            _say(f"mdle run: {rec.error}")
            return output.EXIT_IO
    if args.plot:
        from mdle.view.team_plot import plot_team

        plot_team([w.path for w in writers.values()], args.plot, world=world)
    if guard.received is not None:
        _say(f"mdle run: interrupted by {signal_name(guard.received)}: robots stopped")
        return guard.exit_code
    code = output.EXIT_OK
    for name, result in results.items():
        line = _summary(name, result)
        if not args.quiet:
            print(line)
        if result.collided or result.fault:
            code = output.EXIT_COLLISION
            if args.quiet:
                _say(line)
    if args.plot and not args.quiet:
        print(f"plot written to {args.plot}")
    if tmp is not None:
        tmp.cleanup()
    return code


def _recordings(args: argparse.Namespace, headers: dict[str, dict[str, Any]],
                world: Any) -> list[Any]:
    """Return the team recordings ``--record``, ``--rosbag`` and ``--foxglove`` ask for.

    One file each, every robot in it under ``/NAME``; the live view shows the first.
    """
    if not (args.record or args.rosbag or args.foxglove):
        return []
    from mdle.cli.recorders import live_view
    from mdle.record.team_record import TeamRecording

    live = live_view(args) if args.foxglove else []
    compression = "" if args.record_compression == "none" else args.record_compression
    out = []
    for target, rosbag in ((args.record, False), (args.rosbag, True)):
        if target:
            out.append(TeamRecording(target, headers, world, rosbag=rosbag, live=live,
                                     compression=compression))
            live = []
    if live:
        out.append(TeamRecording(None, headers, world, live=live))
    return out


def _summary(name: str, result: Any) -> str:
    t0 = result.events[0].time if result.events else 0.0
    text = (f"{name}: {result.termination.path} ended ({result.termination.cause.value}) at "
            f"t = {result.duration:.1f} s, {result.distance:.2f} m travelled")
    if result.collision is not None:
        c = result.collision
        if c.kind == "robot":
            text += (f"; collided: robots `{name}` and `{c.obstacle}` touched at x {c.x:.2f} m, "
                     f"y {c.y:.2f} m, t = {c.time - t0:.1f} s")
        else:
            text += f"; collided: {c.describe(t0)}"
    elif result.collided:
        text += "; collided"
    if result.fault:
        text += f"; {result.fault}"
    return text


def _header(args: argparse.Namespace, spec: Any, world: Any, seed: int, rate: float,
            until: float | None, name: str, plan: str, program: Any, element: str
            ) -> dict[str, Any]:
    from mdle.record.describe import profile_header  # the body and odometry noise, for recordings

    r = next(r for r in world.robots if r.name == name)
    return {"program": {"file": os.path.abspath(plan),
                        "element": element, "entry": program.entry},
            "rate": rate, "until": until, "backend": "sim", "argv": sys.argv[1:],
            "world": {"name": world.name, "spec": world.source or world.name},
            "seed": seed, "robot": r.profile.name, "sensing": args.sensing,
            "team": {"robot": name, "robots": [x.name for x in world.robots],
                     "file": spec.source},
            "start": {"x": r.start.x, "y": r.start.y, "theta": r.start.theta},
            **profile_header(r.profile)}


def _say(text: str) -> None:
    try:
        print(text, file=sys.stderr)
    except OSError:
        pass
