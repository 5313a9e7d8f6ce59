"""A world file's robot, ladar and start pose: profiles by name or file, with overrides."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mdle.core.errors import WorldError
from mdle.core.pose import Pose
from mdle.core.ranges import HEADING
from mdle.sim.yaml_doc import _Doc
from mdle.sim.yaml_values import _integer, _mapping, _number, _show, _string

__all__ = ["MAX_LADAR_RATE"]

_LADAR_KEYS = ("profile", "beams", "fov", "max_range", "noise", "sigma", "resolution", "rate")
_MAX_BEAMS = 100_000
#: Fastest ladar scan rate accepted, Hz (the LMS-200 scans at up to 75 Hz).
MAX_LADAR_RATE = 1000.0


def _robot(doc: _Doc, path: str, v: Any) -> Any:
    from mdle.sim.profiles import DEFAULT_ROBOT, robot_profile
    from mdle.sim.robot_yaml import ROBOT_KEYS, check_mount, robot_overrides

    def lookup(name: str) -> Any:
        # A profile file named in a world file is found next to the world file.
        if doc.file and not doc.file.startswith("<") and not os.path.isabs(name):
            near = Path(doc.file).parent / name
            if name.endswith((".yaml", ".yml")) and near.exists():
                return robot_profile(str(near))
        return robot_profile(name)

    if isinstance(v, str):
        return _named(doc, path, v, lookup)
    m = _mapping(doc, path, v, ("profile", *ROBOT_KEYS),
                 "a profile name or file, or `profile` and overrides")
    base = _named(doc, f"{path}.profile", m.get("profile", DEFAULT_ROBOT), lookup)
    robot = base.with_overrides(**robot_overrides(doc, path, m))
    check_mount(doc, path, m, robot)
    return robot


def _ladar(doc: _Doc, path: str, v: Any) -> Any:
    from mdle.sim.ladar import NOISE_MODELS, ladar_profile

    if isinstance(v, str):
        return _named(doc, path, v, ladar_profile)
    m = _mapping(doc, path, v, _LADAR_KEYS, "a profile name, or `profile` and overrides")
    base = _named(doc, f"{path}.profile", m.get("profile", "lms200"), ladar_profile)
    ch: dict[str, Any] = {}
    if "beams" in m:
        ch["beams"] = _integer(doc, f"{path}.beams", m["beams"], minimum=1)
        if ch["beams"] > _MAX_BEAMS:
            raise doc.fail(f"{path}.beams", f"must be at most {_MAX_BEAMS}, got {m['beams']}")
    if "fov" in m:
        fov = _number(doc, f"{path}.fov", m["fov"], positive=True, unit="deg")
        if fov > 360:
            raise doc.fail(f"{path}.fov", f"must be at most 360 degrees, got {m['fov']}")
        ch["fov"] = math.radians(fov)
    if "max_range" in m:
        ch["max_range"] = _number(doc, f"{path}.max_range", m["max_range"], positive=True,
                                   unit="m")
    if "noise" in m:
        if m["noise"] not in NOISE_MODELS:
            raise doc.fail(f"{path}.noise", f"unknown noise model {m['noise']!r}; one of: "
                           f"{', '.join(NOISE_MODELS)}")
        ch["noise"] = m["noise"]
    for key in ("sigma", "resolution", "rate"):
        if key in m:
            ch[key] = _number(doc, f"{path}.{key}", m[key], nonneg=True)
    if ch.get("rate", 0.0) > MAX_LADAR_RATE:
        raise doc.fail(f"{path}.rate", f"must be at most {MAX_LADAR_RATE:g} Hz, got {m['rate']}")
    return base.with_overrides(**ch)


def _named(doc: _Doc, path: str, v: Any, lookup: Callable[[str], Any]) -> Any:
    name = _string(doc, path, v)
    try:
        return lookup(name)
    except WorldError as err:
        raise doc.fail(path, err.diagnostics[0].message) from None


def _start(doc: _Doc, path: str, v: Any) -> Pose:
    if isinstance(v, list):
        if len(v) != 3:
            raise doc.fail(path, f"expected [x, y, theta] (m, m, deg), got {_show(v)}")
        x, y, th = (_number(doc, f"{path}[{i}]", v[i], coordinate=i < 2,
                             unit="m" if i < 2 else "deg") for i in range(3))
    else:
        m = _mapping(doc, path, v, ("x", "y", "theta"), "x, y in metres, theta in degrees")
        for key in ("x", "y"):
            if key not in m:
                raise doc.fail(path, f"missing key `{key}`")
        x = _number(doc, f"{path}.x", m["x"], coordinate=True)
        y = _number(doc, f"{path}.y", m["y"], coordinate=True)
        th = _number(doc, f"{path}.theta", m.get("theta", 0.0), unit="deg")
    problem = HEADING.problem(math.radians(th), f"{th:g}")
    if problem is not None:
        raise doc.fail(f"{path}[2]" if isinstance(v, list) else f"{path}.theta", problem)
    return Pose(x, y, math.radians(th))
