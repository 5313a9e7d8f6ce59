r"""The keys of a robot profile: YAML (metres, seconds, degrees) to profile values.

A profile file holds the keys of a world's ``robot:`` section plus ``name``,
``description`` and ``source``; ``profile: NAME`` starts from another profile and
overrides some keys. Problems are reported as :class:`mdle.core.errors.WorldError` naming the
file, line, column and key path, as world files are. The keys are documented in
``docs/robots.md``. Reading a whole profile, which may start from another by name,
is :mod:`sim.profiles`'s job.
"""

from __future__ import annotations

import json
import math
from typing import Any

from mdle.sim.robot import RAMPS, HalfRate, Latency, OdometryNoise, RobotProfile
from mdle.sim.yaml_doc import _Doc
from mdle.sim.yaml_values import _mapping, _number, _show, _string

__all__ = ["ROBOT_KEYS", "PROFILE_KEYS", "REQUIRED_KEYS", "check_mount", "dump_robot",
           "robot_overrides"]

#: Keys a profile (or a world's ``robot:`` mapping) may override.
ROBOT_KEYS = ("radius", "max_speed", "max_reverse_speed", "max_turn_rate", "max_accel",
              "max_decel", "max_turn_accel", "max_turn_decel", "ramp", "command_latency",
              "sip_cycle", "control_cycle", "input_window", "report_slip",
              "report_slip_rate", "scan_period", "scan_latency", "scan_half_rate",
              "ladar_mount", "odometry")
#: Keys a profile file may hold.
PROFILE_KEYS = ("name", "description", "source", "profile", *ROBOT_KEYS)
#: Keys a profile file needs unless it starts from another (`profile: NAME`).
REQUIRED_KEYS = ("radius", "max_speed", "max_turn_rate")
_ODOM_KEYS = ("distance", "turn", "drift")
_MAX_DELAY = 10.0  # s: a longer latency or cycle is a typo (milliseconds written as seconds)
_MAX_STRETCH = 3600.0  # s: a half-rate stretch longer than an hour is a typo


def _seconds(doc: _Doc, path: str, v: Any, *, positive: bool = False) -> float:
    x = _number(doc, path, v, positive=positive, nonneg=True, unit="s")
    if x > _MAX_DELAY:
        raise doc.fail(path, f"must be at most {_MAX_DELAY:g} s, got {v} (seconds, not ms)")
    return x


def _latency(doc: _Doc, path: str, v: Any) -> Latency:
    if not isinstance(v, dict):
        d = _seconds(doc, path, v)
        return Latency("uniform", d, d)
    if "min" in v or "max" in v:
        m = _mapping(doc, path, v, ("min", "max"), "min and max in seconds")
        if "min" not in m or "max" not in m:
            raise doc.fail(path, "a uniform latency needs both `min` and `max` (seconds)")
        lo, hi = _seconds(doc, f"{path}.min", m["min"]), _seconds(doc, f"{path}.max", m["max"])
        if hi < lo:
            raise doc.fail(f"{path}.max", f"must not be below min ({lo:g} s), got {hi:g}")
        return Latency("uniform", lo, hi)
    m = _mapping(doc, path, v, ("mean", "std"), "min and max, or mean and std, in seconds")
    if "mean" not in m:
        raise doc.fail(path, "expected `min` and `max`, or `mean` and `std` (seconds)")
    return Latency("normal", _seconds(doc, f"{path}.mean", m["mean"]),
                   _seconds(doc, f"{path}.std", m.get("std", 0.0)))


def _half_rate(doc: _Doc, path: str, v: Any) -> HalfRate:
    m = _mapping(doc, path, v, ("share", "length"),
                 "`share` (of the time, in [0, 1)) and `length` (seconds)")
    if "share" not in m or "length" not in m:
        raise doc.fail(path, "needs both `share` (of the time, in [0, 1)) and `length` "
                             "(the stretches' mean, seconds)")
    share = _number(doc, f"{path}.share", m["share"], nonneg=True)
    if share >= 1:
        raise doc.fail(f"{path}.share", f"must be a share of the time in [0, 1), got {share:g}")
    length = _number(doc, f"{path}.length", m["length"], positive=True, unit="s")
    if length > _MAX_STRETCH:
        raise doc.fail(f"{path}.length", f"must be at most {_MAX_STRETCH:g} s, got {length:g}")
    return HalfRate(share, length)


def robot_overrides(doc: _Doc, path: str, m: dict[str, Any]) -> dict[str, Any]:
    """Read the :data:`ROBOT_KEYS` present in mapping ``m`` into SI profile fields."""
    def at(key: str) -> str:
        return f"{path}.{key}" if path else key

    ch: dict[str, Any] = {}
    if "radius" in m:
        ch["radius"] = _number(doc, at("radius"), m["radius"], nonneg=True, unit="m")
    for key in ("max_speed", "max_reverse_speed", "max_accel", "max_decel"):
        if key in m:
            ch[key] = _number(doc, at(key), m[key], positive=True,
                              unit="m/s" if "speed" in key else "m/s^2")
    for key in ("max_turn_rate", "max_turn_accel", "max_turn_decel"):
        if key in m:
            ch[key] = math.radians(_number(doc, at(key), m[key], positive=True,
                                           unit="deg/s" if key == "max_turn_rate" else "deg/s^2"))
    if "ramp" in m:
        ramp = _string(doc, at("ramp"), m["ramp"])
        if ramp not in RAMPS:
            raise doc.fail(at("ramp"), f"unknown ramp {ramp!r}; one of: {', '.join(RAMPS)}")
        ch["ramp"] = ramp
    for key in ("command_latency", "sip_cycle", "control_cycle", "input_window"):
        if key in m:
            ch[key] = _seconds(doc, at(key), m[key])
    if "scan_period" in m:
        ch["scan_period"] = _seconds(doc, at("scan_period"), m["scan_period"], positive=True)
    if "scan_latency" in m:
        ch["scan_latency"] = _latency(doc, at("scan_latency"), m["scan_latency"])
    if "scan_half_rate" in m:
        ch["scan_half_rate"] = _half_rate(doc, at("scan_half_rate"), m["scan_half_rate"])
    if "report_slip" in m:
        ch["report_slip"] = _latency(doc, at("report_slip"), m["report_slip"])
    if "report_slip_rate" in m:
        rate = _number(doc, at("report_slip_rate"), m["report_slip_rate"], nonneg=True)
        if rate > 1:
            raise doc.fail(at("report_slip_rate"), f"must be a chance in [0, 1], got {rate:g}")
        ch["report_slip_rate"] = rate
    if "ladar_mount" in m:
        lm = m["ladar_mount"]
        if not isinstance(lm, list) or len(lm) != 3:
            raise doc.fail(at("ladar_mount"), f"expected [x, y, theta] (m, m, deg), got "
                           f"{_show(lm)}")
        ch["ladar_mount"] = (_number(doc, at("ladar_mount") + "[0]", lm[0], unit="m"),
                             _number(doc, at("ladar_mount") + "[1]", lm[1], unit="m"),
                             math.radians(_number(doc, at("ladar_mount") + "[2]", lm[2],
                                                  unit="deg")))
    if "odometry" in m:
        o = _mapping(doc, at("odometry"), m["odometry"], _ODOM_KEYS, "odometry noise")
        vals = {k: _number(doc, f"{at('odometry')}.{k}", o.get(k, 0.0), nonneg=True)
                for k in _ODOM_KEYS}
        ch["odometry"] = OdometryNoise(distance=vals["distance"],
                                       turn=vals["turn"] * math.sqrt(math.pi / 180.0),
                                       drift=math.radians(vals["drift"]))
    return ch


def check_mount(doc: _Doc, path: str, m: dict[str, Any], robot: RobotProfile) -> None:
    """Fail unless the ladar sits within the body."""
    mx, my, _ = robot.ladar_mount
    if math.hypot(mx, my) > robot.radius + 1e-12:
        key = "ladar_mount" if "ladar_mount" in m else "radius"
        raise doc.fail(f"{path}.{key}" if path else key,
                       f"the ladar at ({mx:g}, {my:g}) m must sit within the body "
                       f"(radius {robot.radius:g} m)")


def _g(x: float) -> str:
    return f"{x:.6g}"


def dump_robot(robot: RobotProfile, comment: str = "") -> str:
    """Return a profile as YAML text in the file units (m, s, deg), readable by :func:`parse_robot`.

    ``comment`` goes first, each line prefixed with ``# ``.
    """
    lines = [f"# {c}".rstrip() for c in comment.splitlines()]
    lines.append("# Units: metres, seconds, degrees.")
    lines.append(f"name: {robot.name}")
    for key in ("description", "source"):
        text = getattr(robot, key)
        if text:
            lines.append(f"{key}: {json.dumps(text)}")
    lines += [f"radius: {_g(robot.radius)}", f"max_speed: {_g(robot.max_speed)}",
              f"max_reverse_speed: {_g(robot.max_reverse_speed)}",
              f"max_turn_rate: {_g(math.degrees(robot.max_turn_rate))}   # deg/s"]
    for key in ("max_accel", "max_decel"):
        if math.isfinite(getattr(robot, key)):
            lines.append(f"{key}: {_g(getattr(robot, key))}   # m/s^2")
    for key in ("max_turn_accel", "max_turn_decel"):
        if math.isfinite(getattr(robot, key)):
            lines.append(f"{key}: {_g(math.degrees(getattr(robot, key)))}   # deg/s^2")
    if robot.ramp != "firmware":
        lines.append(f"ramp: {robot.ramp}")
    lines += [f"command_latency: {_g(robot.command_latency)}   # s",
              f"sip_cycle: {_g(robot.sip_cycle)}   # s"]
    if robot.control_cycle > 0:
        lines += [f"control_cycle: {_g(robot.control_cycle)}   # s",
                  f"input_window: {_g(robot.input_window)}   # s"]
    if robot.scan_period is not None:
        lines.append(f"scan_period: {_g(robot.scan_period)}   # s")
    for key in ("scan_latency", "report_slip"):
        lat = getattr(robot, key)
        if lat.enabled:
            inner = (f"min: {_g(lat.a)}, max: {_g(lat.b)}" if lat.kind == "uniform"
                     else f"mean: {_g(lat.a)}, std: {_g(lat.b)}")
            lines.append(f"{key}: {{{inner}}}   # s")
            if key == "report_slip":
                lines.append(f"report_slip_rate: {_g(robot.report_slip_rate)}")
    half = robot.scan_half_rate
    if half.enabled:
        lines.append(f"scan_half_rate: {{share: {_g(half.share)}, length: {_g(half.length)}}}"
                     "   # of the time, s")
    mx, my, mth = robot.ladar_mount
    lines.append(f"ladar_mount: [{_g(mx)}, {_g(my)}, {_g(math.degrees(mth))}]   # m, m, deg")
    o = robot.odometry
    if o.enabled:
        lines.append(f"odometry: {{distance: {_g(o.distance)}, "
                     f"turn: {_g(o.turn / math.sqrt(math.pi / 180.0))}, "
                     f"drift: {_g(math.degrees(o.drift))}}}")
    return "\n".join(lines) + "\n"
