r"""Study specs: YAML to a validated :class:`Study` whose files travel as text.

Over 500 lines: one schema, every section of which is read against the same document
(its key paths and error positions), and the plan is checked with each parameter value.

A study names a plan, the worlds, robots, sensing modes, control rates, seeds, start
poses and plan parameters to combine; :func:`mdle.sweep.tasks.expand` turns it into one
:class:`~mdle.sweep.tasks.RunTask` per combination. Every file a spec names (plan and
its imports, world files, robot files) is read here, once: the tasks carry the texts,
so a worker on another machine needs no shared disk. Errors name the spec's file,
line, column and key path, as world files do (``parameters.grid.kf[2]: ...``).

>>> s = parse_study('''
... plan: {text: "atom f(rc = 1 m) = (follow_boundary(rc = rc, v = 1 m/s), never, 5 s)\\n"}
... entry: f
... worlds: [ellipse]
... parameters: {grid: {rc: [0.8 m, 1.2 m]}}
... ''')
>>> [dict(p) for p in s.parameters]
[{'rc': '0.8 m'}, {'rc': '1.2 m'}]
>>> try:
...     parse_study("plan: {text: 'plan main = ((halt), never, 1 s)'}\nrates: [fast]\n",
...                 file="study.yaml")
... except SpecError as err:
...     print(err)
study.yaml:2:9: error: rates[0]: expected a number, got 'fast'
"""

from __future__ import annotations

import itertools
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from mdle.core.errors import MdleError, WorldError
from mdle.core.ranges import RATE
from mdle.core.userfile import UserFileError, os_reason, read_user_file
from mdle.sim.yaml_doc import _Doc, _yaml_value
from mdle.sim.yaml_values import _closest, _integer, _mapping, _number, _show, _string

__all__ = ["SpecError", "Study", "WorldChoice", "RobotChoice", "StartRule", "parse_study",
           "read_study", "SENSING"]

SENSING = ("scan", "exact")
_TOP = ("name", "description", "plan", "entry", "worlds", "robots", "sensing", "rates",
        "seeds", "duration", "starts", "parameters", "trace_fields", "keep_traces")
_PLAN = ("file", "text")
_STARTS = ("world", "fixed", "grid", "random")
_RANDOM_STARTS = ("count", "seed", "distance", "from", "heading", "spread")
_PARAMS = ("grid", "random")
_RANDOM_PARAMS = ("count", "seed", "ranges")
#: Sample fields a spec may summarise besides the control law's diagnostics.
SAMPLE_FIELDS = ("x", "y", "theta", "v", "omega", "cmd_v", "cmd_omega", "lateness",
                 "scan_age", "clearance", "true_x", "true_y", "true_theta")
_MAX_RUNS = 10_000_000
#: Largest count one axis may list (seeds, generated worlds, random parameter sets): each
#: is made when the spec is read, before the runs are counted.
MAX_AXIS = 100_000
#: Largest seed in a study: the results table stores seeds as 64-bit signed integers.
MAX_STUDY_SEED = 2 ** 63 - 1


class SpecError(MdleError):
    """A study spec is malformed, names a missing file, or describes no run."""


@dataclass(frozen=True)
class WorldChoice:
    """A world of the study: ``label`` for tables, ``text`` its YAML (what travels)."""

    label: str
    text: str


@dataclass(frozen=True)
class RobotChoice:
    """A robot of the study: ``label`` for tables, ``value`` what travels.

    ``value`` is a profile name or a profile mapping (the world files' ``robot``
    section), None for each world's own robot.
    """

    label: str
    value: str | dict[str, Any] | None


@dataclass(frozen=True)
class StartRule:
    """Where runs start.

    ``kind`` is ``world`` (each world's start pose), ``fixed`` (``poses``), ``grid``
    (``poses``, the product of the x, y and theta lists) or ``random``: ``count`` poses
    per world drawn with ``seed``, the robot's centre ``distance`` (min, max) m from the
    nearest boundary (``origin="boundary"``) or from the obstacles' centre
    (``origin="centre"``), heading ``collision`` (aimed at the obstacle, within
    ``spread`` rad, and the ray ahead hits it) or ``any``. Poses in m, m, rad.
    """

    kind: str = "world"
    poses: tuple[tuple[float, float, float], ...] = ()
    count: int = 0
    seed: int = 0
    distance: tuple[float, float] = (1.0, 4.0)
    origin: str = "boundary"
    heading: str = "collision"
    spread: float = math.radians(30.0)


@dataclass(frozen=True)
class Study:
    """A validated study: everything a run needs, with file contents instead of paths."""

    name: str
    plan_label: str
    plan_text: str
    plan_files: tuple[tuple[str, str], ...]
    entry: str | None
    worlds: tuple[WorldChoice, ...]
    robots: tuple[RobotChoice, ...] = (RobotChoice("world", None),)
    sensing: tuple[str, ...] = ("scan",)
    rates: tuple[float, ...] = (10.0,)
    seeds: tuple[int, ...] = (0,)
    duration: float | None = None
    starts: StartRule = field(default_factory=StartRule)
    parameters: tuple[tuple[tuple[str, str], ...], ...] = ((),)
    parameter_names: tuple[str, ...] = ()
    trace_fields: tuple[str, ...] = ()
    keep_traces: bool = False
    description: str = ""

    def size(self) -> int:
        """Return the number of runs the study describes."""
        starts = self.starts
        per_world = (len(starts.poses) if starts.kind in ("fixed", "grid") else
                     starts.count if starts.kind == "random" else 1)
        return (len(self.worlds) * len(self.robots) * len(self.sensing) * len(self.rates)
                * len(self.seeds) * len(self.parameters) * per_world)


# ---------------------------------------------------------------- reading
def read_study(path: str | os.PathLike[str]) -> Study:
    """Read and validate a study spec file (paths in it are relative to its folder).

    Raises
    ------
    SpecError
        The file cannot be read, or what :func:`parse_study` reports.
    """
    p = Path(path)
    try:
        text = _read_text(p)
    except UserFileError as err:
        if err.reason == "no such file":
            raise SpecError(f"study spec not found: {p}") from None
        raise SpecError(f"cannot read study spec {p}: {err.reason}") from None
    except UnicodeDecodeError as err:
        raise SpecError(f"cannot read study spec {p}: not UTF-8 text ({err})") from None
    return parse_study(text, file=str(p), base=p.parent, default_name=p.stem)


def _read_text(path: Path) -> str:
    """Read a file the spec names (regular files of bounded size only), as UTF-8."""
    return read_user_file(path).decode("utf-8-sig")


def parse_study(text: str, file: str = "<spec>", base: str | os.PathLike[str] = ".",
                default_name: str = "study") -> Study:
    """Parse and validate study YAML; files it names are relative to ``base``.

    Raises
    ------
    SpecError
        With the file, line, column, key path and problem of the first error found.
    """
    doc = _Doc(file, text)
    try:
        return _parse(doc, Path(base), default_name)
    except SpecError:
        raise
    except WorldError as err:
        raise SpecError(err.diagnostics, err.sources) from None


def _fail(doc: _Doc, path: str, problem: str) -> SpecError:
    err = doc.fail(path, problem)
    return SpecError(err.diagnostics, err.sources)


def _yaml(doc: _Doc) -> Any:
    value = _yaml_value(doc)
    return {} if value is None else value


def _list(doc: _Doc, path: str, v: Any, what: str) -> list[Any]:
    """Return ``v`` as a non-empty list (a single value is a list of one)."""
    items = v if isinstance(v, list) else [v]
    if not items:
        raise _fail(doc, path, f"is empty: give at least one {what}")
    return items


def _parse(doc: _Doc, base: Path, default_name: str) -> Study:
    data = _yaml(doc)
    if data is None:
        data = {}
    top = _mapping(doc, "", data, _TOP, "a study")
    if "plan" not in top:
        raise _fail(doc, "", "missing key `plan` (a plan file, or {file: ..} / {text: ..})")
    name = _string(doc, "name", top["name"]) if "name" in top else default_name
    description = _string(doc, "description", top.get("description", ""))
    plan_label, plan_text, plan_files = _plan(doc, base, top["plan"])
    entry = _string(doc, "entry", top["entry"]) if "entry" in top else None
    worlds = tuple(c for i, w in
                   enumerate(_list(doc, "worlds", top.get("worlds", ["default"]), "world"))
                   for c in _worlds(doc, f"worlds[{i}]", base, w))
    robots = (tuple(_robot(doc, f"robots[{i}]", base, r) for i, r in
                    enumerate(_list(doc, "robots", top["robots"], "robot")))
              if "robots" in top else (RobotChoice("world", None),))
    sensing = tuple(_choice(doc, f"sensing[{i}]", s, SENSING) for i, s in
                    enumerate(_list(doc, "sensing", top.get("sensing", "scan"), "sensing mode")))
    rates = tuple(_rate(doc, f"rates[{i}]", r) for i, r in
                  enumerate(_list(doc, "rates", top.get("rates", 10.0), "rate")))
    seeds = _seeds(doc, top.get("seeds", 0))
    duration = None
    if "duration" in top:
        duration = _number(doc, "duration", top["duration"], positive=True)
    starts = _starts(doc, top.get("starts", "world"))
    names, params = _parameters(doc, top.get("parameters"))
    fields = tuple(_string(doc, f"trace_fields[{i}]", f) for i, f in
                   enumerate(top.get("trace_fields") or []))
    keep = top.get("keep_traces", False)
    if not isinstance(keep, bool):
        raise _fail(doc, "keep_traces", f"expected true or false, got {_show(keep)}")
    for path, v in (("seeds", seeds), ("worlds", worlds)):
        seen: set[Any] = set()  # a set: 100,000 generated worlds compared pairwise took hours
        for i, item in enumerate(v):
            if item in seen:
                raise _fail(doc, f"{path}[{i}]", "repeats an earlier entry")
            seen.add(item)
    study = Study(name=name, plan_label=plan_label, plan_text=plan_text,
                  plan_files=plan_files, entry=entry, worlds=worlds, robots=robots,
                  sensing=sensing, rates=rates, seeds=seeds, duration=duration, starts=starts,
                  parameters=params, parameter_names=names, trace_fields=fields,
                  keep_traces=keep, description=description)
    _check_plan(doc, study)
    if study.size() > _MAX_RUNS:
        raise _fail(doc, "", f"describes {study.size()} runs (at most {_MAX_RUNS})")
    return study


# ---------------------------------------------------------------- sections
def _plan(doc: _Doc, base: Path, v: Any) -> tuple[str, str, tuple[tuple[str, str], ...]]:
    from mdle.lang import plan_bundle

    if isinstance(v, str):
        v = {"file": v}
    m = _mapping(doc, "plan", v, _PLAN, "a plan file name, or {file: ..} or {text: ..}")
    if ("file" in m) == ("text" in m):
        raise _fail(doc, "plan", "give either `file` or `text`")
    if "text" in m:
        return "<plan>", _string(doc, "plan.text", m["text"]), ()
    key = "plan.file" if isinstance(doc.marks.get("plan.file"), tuple) else "plan"
    rel = _string(doc, key, m["file"])
    path = base / rel
    if not path.is_file():
        raise _fail(doc, key, f"plan file not found: {rel} (looked for {path})")
    try:
        text, files = plan_bundle(path)
    except MdleError as err:
        raise SpecError(err.diagnostics, err.sources) from None
    return Path(rel).name, text, tuple(sorted(files.items()))


def _check_plan(doc: _Doc, study: Study) -> None:
    """Check the plan, its entry, and each parameter value on its own."""
    from mdle.lang import load_text
    from mdle.runtime.api import element_of

    files = dict(study.plan_files)

    def load(path: str, settings: Mapping[str, str]) -> None:
        try:
            program = load_text(study.plan_text, study.plan_label, settings=settings,
                                files=files, base_dir="/")
            element_of(program, study.entry)
        except MdleError as err:
            msg = "; ".join(d.message.removeprefix(f"--set {n}: ") + (f" ({d.hint})" if d.hint
                                                                       else "")
                            for d in err.diagnostics[:3] for n in [*settings, ""][:1])
            if err.diagnostics and err.diagnostics[0].span is not None and not settings:
                raise SpecError(err.diagnostics, err.sources) from None
            raise _fail(doc, path, msg) from None

    load("entry" if study.entry else "plan", {})
    grid = "parameters.grid" in doc.marks
    values: dict[str, list[str]] = {}
    for combo in study.parameters:
        for name, value in combo:
            seen = values.setdefault(name, [])
            if value in seen or (seen and not grid):   # a random sample: its first value
                continue
            seen.append(value)
            where = (f"parameters.grid.{name}[{len(seen) - 1}]" if grid
                     else f"parameters.random.ranges.{name}")
            load(where, {name: value})


_GENERATED = ("seed", "count", "first", "index", "family")


def _worlds(doc: _Doc, path: str, base: Path, v: Any) -> list[WorldChoice]:
    """Return the worlds one ``worlds`` entry names: a name, a file, or generated shapes."""
    if not isinstance(v, dict):
        return [_world(doc, path, base, v)]
    _mapping(doc, path, v, ("generated",), "a world name, a file, or {generated: ..}")
    if "generated" not in v:  # `worlds: [{}]`
        raise _fail(doc, path, "expected a world name, a file, or {generated: ..}")
    from mdle.sim.generated import FAMILIES
    from mdle.sweep.worlds import generated_text

    gpath = f"{path}.generated"
    g = _mapping(doc, gpath, v["generated"], _GENERATED,
                 "seed and count (and first), or seed and index; family")
    seed = _integer(doc, f"{gpath}.seed", g.get("seed", 0), maximum=MAX_STUDY_SEED)
    family = None
    if "family" in g:
        family = _choice(doc, f"{gpath}.family", g["family"], FAMILIES)
    if "index" in g:
        if "count" in g or "first" in g:
            raise _fail(doc, gpath, "give `index` (one shape) or `count` (and `first`)")
        indices = [_integer(doc, f"{gpath}.index", g["index"], maximum=MAX_STUDY_SEED)]
    else:
        # bounded before the list is made: `count: 1e40` would allocate up front
        count = _integer(doc, f"{gpath}.count", g.get("count", 1), minimum=1,
                         maximum=MAX_AXIS)
        first = _integer(doc, f"{gpath}.first", g.get("first", 0), maximum=MAX_STUDY_SEED)
        indices = list(range(first, first + count))
    out = []
    for i in indices:
        fam = family if family is not None else FAMILIES[i % len(FAMILIES)]
        out.append(WorldChoice(f"{fam}-{seed}-{i}", generated_text(seed, i, family)))
    return out


def _world(doc: _Doc, path: str, base: Path, v: Any) -> WorldChoice:
    from mdle.sim.catalog import list_worlds
    from mdle.sim.world_yaml import parse_world

    name = _string(doc, path, v)
    if name in list_worlds():

        text = resources.files("mdle.sim").joinpath("worlds", f"{name}.yaml").read_text("utf-8")
        return WorldChoice(name, text)
    p = base / name
    try:
        found = p.is_file()
    except (OSError, ValueError) as err:  # a name too long for a file, a NUL in it
        why = os_reason(err) if isinstance(err, OSError) else "not a file name"
        shown = name if len(name) <= 60 else name[:57] + "..."
        raise _fail(doc, path, f"no reference world `{shown}`, and not a world file "
                               f"({why})") from None
    if not found:
        hint = _closest(name, tuple(list_worlds()))
        raise _fail(doc, path, f"no reference world or world file `{name}`"
                    + (f" (did you mean `{hint}`?)" if hint else
                       f"; reference worlds: {', '.join(list_worlds())}"))

    try:
        text = _read_text(p)
    except UserFileError as err:
        raise _fail(doc, path, f"cannot read world file {p}: {err.reason}") from None
    except UnicodeDecodeError as err:
        raise _fail(doc, path, f"cannot read world file {p}: not UTF-8 text ({err})") from None
    parse_world(text, file=str(p), default_name=p.stem)   # located errors of the file itself
    return WorldChoice(Path(name).stem.removesuffix(".world"), text)


def _robot(doc: _Doc, path: str, base: Path, v: Any) -> RobotChoice:
    import yaml

    from mdle.sim.world_robots import _robot as robot_section

    if isinstance(v, str) and (v.endswith((".yaml", ".yml")) or "/" in v):

        p = base / v
        try:
            text = _read_text(p)
            data = yaml.safe_load(text)
        except UserFileError as err:
            if err.reason == "no such file":
                raise _fail(doc, path, f"robot profile file not found: {v} (looked for {p})"
                            ) from None
            raise _fail(doc, path, f"cannot read robot profile {p}: {err.reason}") from None
        except (UnicodeDecodeError, yaml.YAMLError) as err:
            raise _fail(doc, path, f"cannot read robot profile {p}: {err}") from None
        if isinstance(data, dict) and "robot" in data and len(data) == 1:
            data = data["robot"]
        sub = _Doc(str(p), text)
        robot_section(sub, "", data)
        return RobotChoice(Path(v).stem, data)
    if v == "world":
        return RobotChoice("world", None)
    profile = robot_section(doc, path, v)
    if isinstance(v, str):
        return RobotChoice(v, v)
    label = v.get("name") if isinstance(v.get("name"), str) else profile.name
    return RobotChoice(f"{label}*", v)


def _choice(doc: _Doc, path: str, v: Any, options: tuple[str, ...]) -> str:
    s = _string(doc, path, v)
    if s not in options:
        raise _fail(doc, path, f"unknown value {s!r}; one of: {', '.join(options)}")
    return s


def _rate(doc: _Doc, path: str, v: Any) -> float:
    r = _number(doc, path, v, positive=True)
    problem = RATE.problem(r, str(v))
    if problem is not None:
        raise _fail(doc, path, problem)
    return r


def _seeds(doc: _Doc, v: Any) -> tuple[int, ...]:
    if isinstance(v, dict):
        m = _mapping(doc, "seeds", v, ("count", "first"), "count and first seed")
        if "count" not in m:
            raise _fail(doc, "seeds", "missing key `count`")
        # bounded before the seeds are made: `count: 2**31` would take 16 GiB up front
        n = _integer(doc, "seeds.count", m["count"], minimum=1, maximum=MAX_AXIS)
        first = _integer(doc, "seeds.first", m.get("first", 0),
                         maximum=MAX_STUDY_SEED - n + 1)
        return tuple(range(first, first + n))
    return tuple(_integer(doc, f"seeds[{i}]" if isinstance(v, list) else "seeds", s,
                          maximum=MAX_STUDY_SEED)
                 for i, s in enumerate(_list(doc, "seeds", v, "seed")))


def _pose(doc: _Doc, path: str, v: Any) -> tuple[float, float, float]:
    if not isinstance(v, list) or len(v) != 3:
        raise _fail(doc, path, f"expected [x, y, theta] (m, m, deg), got {_show(v)}")
    x, y, th = (_number(doc, f"{path}[{i}]", v[i]) for i in range(3))
    return (x, y, math.radians(th))


def _starts(doc: _Doc, v: Any) -> StartRule:
    if v == "world":
        return StartRule()
    if isinstance(v, list):
        v = {"fixed": v}
    if not isinstance(v, dict) or len(v) != 1:
        raise _fail(doc, "starts", "expected `world`, a list of [x, y, theta], or one of "
                    "{fixed: ..}, {grid: ..}, {random: ..}")
    _mapping(doc, "starts", v, _STARTS, "one rule")
    kind, body = next(iter(v.items()))
    path = f"starts.{kind}"
    if kind == "world":
        return StartRule()
    if kind == "fixed":
        poses = tuple(_pose(doc, f"{path}[{i}]", p) for i, p in
                      enumerate(_list(doc, path, body, "pose")))
        return StartRule("fixed", poses)
    if kind == "grid":
        m = _mapping(doc, path, body, ("x", "y", "theta"), "x, y (m) and theta (deg) lists")
        axes = []
        for key in ("x", "y", "theta"):
            if key not in m:
                raise _fail(doc, path, f"missing key `{key}`")
            axes.append([_number(doc, f"{path}.{key}[{i}]", x) for i, x in
                         enumerate(_list(doc, f"{path}.{key}", m[key], "value"))])
        return StartRule("grid", tuple((x, y, math.radians(t)) for x, y, t in
                                       itertools.product(*axes)))
    m = _mapping(doc, path, body, _RANDOM_STARTS, "count, seed, distance, from, heading, spread")
    if "count" not in m:
        raise _fail(doc, path, "missing key `count` (starts per world)")
    count = _integer(doc, f"{path}.count", m["count"], minimum=1, maximum=_MAX_RUNS)
    seed = _integer(doc, f"{path}.seed", m.get("seed", 0), maximum=MAX_STUDY_SEED)
    dist = m.get("distance", [1.0, 4.0])
    if isinstance(dist, list) and len(dist) == 2:
        lo = _number(doc, f"{path}.distance[0]", dist[0], nonneg=True)
        hi = _number(doc, f"{path}.distance[1]", dist[1], nonneg=True)
        if hi < lo:
            raise _fail(doc, f"{path}.distance", f"the range [{lo:g}, {hi:g}] m is empty")
    else:
        lo = hi = _number(doc, f"{path}.distance", dist, nonneg=True)
    origin = _choice(doc, f"{path}.from", m.get("from", "boundary"), ("boundary", "centre"))
    heading = _choice(doc, f"{path}.heading", m.get("heading", "collision"),
                      ("collision", "any"))
    spread = _number(doc, f"{path}.spread", m.get("spread", 30.0), nonneg=True)
    if spread >= 90:
        raise _fail(doc, f"{path}.spread", f"must be under 90 degrees, got {m['spread']}")
    return StartRule("random", (), count, seed, (lo, hi), origin, heading,
                     math.radians(spread))


def _value_text(doc: _Doc, path: str, v: Any) -> str:
    if isinstance(v, bool) or v is None or isinstance(v, (list, dict)):
        raise _fail(doc, path, f"expected a number or a value such as `0.8 m`, got {_show(v)}")
    if isinstance(v, float):
        if not math.isfinite(v):
            raise _fail(doc, path, f"expected a finite number, got {v}")
        return repr(v)
    text = str(v).strip()
    if not text:
        raise _fail(doc, path, "is empty")
    return text


def _split_unit(text: str) -> tuple[float, str] | None:

    m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*", text)
    return (float(m.group(1)), m.group(2)) if m else None


def _parameters(doc: _Doc, v: Any) -> tuple[tuple[str, ...], tuple[tuple[tuple[str, str], ...],
                                                                      ...]]:
    if v is None:
        return (), ((),)
    m = _mapping(doc, "parameters", v, _PARAMS, "a grid or a random sample")
    if len(m) != 1:
        raise _fail(doc, "parameters", "give either `grid` or `random`")
    if "grid" in m:
        g = m["grid"]
        if not isinstance(g, dict) or not g:
            raise _fail(doc, "parameters.grid", f"expected parameter names with lists of "
                        f"values, got {_show(g)}")
        names = tuple(g)
        axes = [[_value_text(doc, f"parameters.grid.{n}[{i}]", x) for i, x in
                 enumerate(_list(doc, f"parameters.grid.{n}", g[n], "value"))] for n in names]
        for n, axis in zip(names, axes, strict=True):
            for i, x in enumerate(axis):
                if x in axis[:i]:
                    raise _fail(doc, f"parameters.grid.{n}[{i}]", "repeats an earlier value")
        combos = tuple(tuple(zip(names, c, strict=True)) for c in itertools.product(*axes))
        return names, combos
    path = "parameters.random"
    r = _mapping(doc, path, m["random"], _RANDOM_PARAMS, "count, seed and ranges")
    if "count" not in r or "ranges" not in r:
        raise _fail(doc, path, "needs `count` and `ranges`")
    count = _integer(doc, f"{path}.count", r["count"], minimum=1, maximum=MAX_AXIS)
    seed = _integer(doc, f"{path}.seed", r.get("seed", 0), maximum=MAX_STUDY_SEED)
    ranges = r["ranges"]
    if not isinstance(ranges, dict) or not ranges:
        raise _fail(doc, f"{path}.ranges", f"expected NAME: [low, high], got {_show(ranges)}")
    import numpy as np

    rng = np.random.default_rng(seed)
    names = tuple(ranges)
    columns = []
    for n in names:
        rp = f"{path}.ranges.{n}"
        pair = ranges[n]
        if not isinstance(pair, list) or len(pair) != 2:
            raise _fail(doc, rp, f"expected [low, high], got {_show(pair)}")
        ends = []
        for i, x in enumerate(pair):
            parsed = _split_unit(_value_text(doc, f"{rp}[{i}]", x))
            if parsed is None:
                raise _fail(doc, f"{rp}[{i}]", f"expected a number (with a unit), got {x!r}")
            ends.append(parsed)
        (lo, u0), (hi, u1) = ends
        if u0 != u1:
            raise _fail(doc, rp, f"low and high need the same unit, got `{u0}` and `{u1}`")
        if not hi > lo:
            raise _fail(doc, rp, f"the range [{lo:g}, {hi:g}] is empty")
        draws = rng.uniform(lo, hi, count)
        columns.append([f"{x:.6g}" + (f" {u0}" if u0 else "") for x in draws.tolist()])
    combos = tuple(tuple(zip(names, c, strict=True)) for c in zip(*columns, strict=True))
    return names, combos


