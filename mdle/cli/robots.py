"""``mdle robots``: list robot profiles, show one, or fit one to a recorded run."""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register ``mdle robots``, ``mdle robots show`` and ``mdle robots fit``."""
    p = subparsers.add_parser(
        "robots", help="list the simulator's robot profiles, show one, or fit one",
        description="List the robot profiles shipped with the simulator (usable as "
                    "`mdle run --robot NAME` or `robot: NAME` in a world file), show one "
                    "profile or profile file, or fit a profile's timing to a recorded run.",
        epilog="Examples: `mdle robots`; `mdle robots show pioneer-p3dx`; "
               "`mdle robots fit run.jsonl -o my-robot.yaml --name my-robot`.")
    sub = p.add_subparsers(dest="action", metavar="ACTION")
    show = sub.add_parser("show", help="print a profile's values, in the profile file's units",
                          description="Print a robot profile (a shipped name or a YAML "
                                      "file) as a profile file, with its timing summary.")
    show.add_argument("robot", metavar="NAME|FILE", help="a profile name or a YAML file")
    fit = sub.add_parser(
        "fit", help="fit latency or server loop, ramps and scan latency to recorded runs",
        description="Replay the commands of recorded runs through the simulator's motion "
                    "model and fit the command latency (or the robot server's loop: its "
                    "cycle, when it reads commands, its clock in each run), the speed and "
                    "turn-rate ramps and the scan latency that reproduce the measured speed "
                    "and turn rate (least RMS error); print the fit and write a profile.",
        epilog="A recording is a trace of a run on the robot (`mdle run --backend pioneer "
               "--trace F.jsonl`) or a CSV with columns t_s, v_mps, omega_radps, cmd_v_mps, "
               "cmd_omega_radps and optionally scan_age_s, one row per control tick.")
    fit.add_argument("recordings", nargs="+", metavar="RECORDING",
                     help="trace (.jsonl) or CSV files of the same robot")
    fit.add_argument("-o", "--output", metavar="FILE",
                     help="write the fitted profile here (default: print it)")
    fit.add_argument("--name", default="fitted", help="the profile's name (default: fitted)")
    fit.add_argument("--description", default="",
                     help="the profile's one-line description (default: what it was fitted to)")
    fit.add_argument("--base", default="pioneer2dx", metavar="NAME|FILE",
                     help="profile giving what the fit does not (body, speed limits, ladar "
                          "mount, odometry noise; default: pioneer2dx)")
    fit.add_argument("--sip-cycle", type=float, default=0.1, metavar="S",
                     help="the robot's report cycle in seconds (default: 0.1, a Pioneer's); "
                          "the server loop's cycle is searched from here")
    fit.add_argument("--scan-period", type=float, default=0.1, metavar="S",
                     help="seconds between ladar scans (default: 0.1)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """List, show or fit robot profiles; return the exit code."""
    action = getattr(args, "action", None)
    if action == "show":
        return _show(args)
    if action == "fit":
        return _fit(args)
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_descriptions

    rows = robot_descriptions()
    width = max(len(n) for n, _ in rows)
    for name, desc in rows:
        mark = " (default)" if name == DEFAULT_ROBOT else ""
        print(f"{name:<{width}}  {desc}{mark}")
    return 0


def _timing(robot: Any) -> str:
    if not robot.timed:
        return "timing: ideal (commands act at once, observations and scans are current)"
    period = f"every {robot.scan_period:g} s" if robot.scan_period else "at the ladar's rate"
    if robot.control_cycle > 0:
        acts = (f"commands reach the server after {robot.command_latency * 1e3:.0f} ms and act "
                f"at its next motion step (every {robot.control_cycle * 1e3:.1f} ms; "
                f"{robot.effective_latency * 1e3:.0f} ms on average until they show)")
    else:
        acts = f"commands act after {robot.command_latency * 1e3:.0f} ms"
    half = robot.scan_half_rate
    return (f"timing: {acts}, reports every {robot.sip_cycle * 1e3:.1f} ms, scans {period} "
            f"readable after {robot.scan_latency.describe()}"
            + (f", at half rate {half.describe()}" if half.enabled else ""))


def _show(args: argparse.Namespace) -> int:
    from mdle.sim.profiles import robot_profile
    from mdle.sim.robot_yaml import dump_robot

    robot = robot_profile(args.robot)
    print(dump_robot(robot, _timing(robot)), end="")
    return 0


def _fit(args: argparse.Namespace) -> int:
    from mdle.cli.clobber import refuse_clobbering
    from mdle.core.errors import MdleError
    from mdle.fit.profile import fit_profile
    from mdle.fit.recording import read_recording
    from mdle.sim.profiles import robot_profile
    from mdle.sim.robot_yaml import dump_robot

    refuse_clobbering([("-o", args.output)], [("the recording", r) for r in args.recordings])
    for key in ("sip_cycle", "scan_period"):
        value = getattr(args, key)
        if not (math.isfinite(value) and 0 < value <= 10):
            raise MdleError(f"--{key.replace('_', '-')} must be a number of seconds in "
                            f"(0, 10], got {value:g}")
    base = robot_profile(args.base)
    recs = [read_recording(r) for r in args.recordings]
    fit = fit_profile(recs, sip_cycle=args.sip_cycle, scan_period=args.scan_period)
    print(fit.report())
    command = "mdle robots fit " + " ".join(args.recordings) + (
        f" --name {args.name}" if args.name != "fitted" else "") + (
        f" --base {args.base}" if args.base != "pioneer2dx" else "") + (
        f" --description {json.dumps(args.description)}" if args.description else "")
    description = args.description or f"fitted to {', '.join(args.recordings)}"
    fitted = "server loop" if fit.control_cycle else "command latency"
    profile = fit.profile(base, args.name, description=description,
                          source=f"mdle robots fit ({fitted}, ramps, scan latency"
                                 f"{', half-rate scans' if fit.scan_half_rate.enabled else ''}); "
                                 f"the rest from {base.name}")
    comment = (f"Written by `{command}`.\n"
               f"Fit: RMS error v {fit.v.rms:.4f} m/s, omega {fit.omega.rms:.4f} rad/s over "
               f"{sum(len(r) for r in recs)} ticks; body, speed limits and ladar mount from "
               f"`{base.name}`.")
    text = dump_robot(profile, comment)
    if args.output:
        from mdle.cli.csv_output import write_failed
        from mdle.core.userfile import UserFileError, write_user_file

        try:
            write_user_file(args.output, text)
        except UserFileError as err:  # a full disk: 74, a refused path: 1
            return write_failed("mdle robots fit", err)
        print(f"profile `{args.name}` written to {args.output}")
    else:
        print(text, end="")
    return 0
