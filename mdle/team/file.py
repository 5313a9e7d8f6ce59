"""Team files: which plan each robot of a team world runs (YAML, documented in docs/teams.md).

>>> spec = parse_team('''
... world: relay.world.yaml
... seed: 3
... messages: {range: 5, loss: 0.1}
... robots:
...   a: a.mdle
...   b: {plan: b.mdle, set: ["gap=1 m"]}
... ''', file="plans/team.yaml")
>>> [(m.name, m.plan) for m in spec.members], spec.rules.range, spec.seed
([('a', 'plans/a.mdle'), ('b', 'plans/b.mdle')], 5.0, 3)
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mdle.core.errors import Diagnostic, MdleError, Severity, WorldError
from mdle.core.messages import DeliveryRules
from mdle.core.pose import Pose
from mdle.core.ranges import RATE

__all__ = ["MemberSpec", "TeamSpec", "LoadedTeam", "parse_team", "read_team", "robot_plan",
           "load_team"]

_TOP_KEYS = ("world", "seed", "rate", "until", "messages", "robots")
_MEMBER_KEYS = ("plan", "element", "set", "start")
_MESSAGE_KEYS = ("range", "loss", "seed")


@dataclass(frozen=True)
class MemberSpec:
    """A robot of the team and its plan.

    The plan file, the element (None: the file's entry), settings (``NAME=VALUE`` as
    ``--set`` takes them), and a start pose overriding the world's.
    """

    name: str
    plan: str
    element: str | None = None
    settings: tuple[str, ...] = ()
    start: Pose | None = None


@dataclass(frozen=True)
class TeamSpec:
    """A team: the world, the robots' plans, and the run's seed, rate, time limit, radio."""

    world: str | None
    members: tuple[MemberSpec, ...]
    seed: int | None = None
    rate: float | None = None
    until: float | None = None
    rules: DeliveryRules = field(default_factory=DeliveryRules)
    source: str | None = None


class TeamError(MdleError):
    """A team file or a ``--robot-plan`` that cannot be used (with its place)."""


def robot_plan(text: str) -> MemberSpec:
    """Read ``NAME=PLAN.mdle`` (``--robot-plan``); TeamError if it is not that."""
    name, sep, plan = text.partition("=")
    name, plan = name.strip(), plan.strip()
    if not sep or not name or not plan:
        raise TeamError(Diagnostic(None, f"--robot-plan takes NAME=PLAN.mdle, got {text!r}"))
    return MemberSpec(name, plan)


def read_team(path: str | os.PathLike[str]) -> TeamSpec:
    """Read and validate a team file (TeamError naming the place of the first problem)."""
    from mdle.core.userfile import UserFileError, read_user_file

    try:
        data = read_user_file(Path(path))
    except UserFileError as err:
        raise TeamError(Diagnostic(None, f"cannot read team file {path}: {err.reason}")) \
            from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise TeamError(Diagnostic(None, f"cannot read team file {path}: not UTF-8 text")) \
            from None
    return parse_team(text, file=os.fspath(path))


def parse_team(text: str, file: str = "<string>") -> TeamSpec:
    """Parse team YAML; plan and world files are relative to the file's folder."""
    try:
        return _parse(text, file)
    except WorldError as err:  # the YAML readers report with the world's error class
        raise TeamError(err.diagnostics, err.sources) from None


def _parse(text: str, file: str) -> TeamSpec:
    from mdle.sim.world_robots import _start
    from mdle.sim.yaml_doc import _Doc, _yaml_value
    from mdle.sim.yaml_values import _integer, _mapping, _number, _string

    doc = _Doc(file, text)
    top = _mapping(doc, "", _yaml_value(doc) or {}, _TOP_KEYS, "a team")
    base = Path(file).parent if not file.startswith("<") else Path(".")

    def near(name: str) -> str:
        return name if os.path.isabs(name) else os.path.normpath(base / name)

    world = None
    if "world" in top:
        w = _string(doc, "world", top["world"])
        world = near(w) if w.endswith((".yaml", ".yml")) else w
    seed = _integer(doc, "seed", top["seed"], maximum=2 ** 64 - 1) if "seed" in top else None
    rate = _number(doc, "rate", top["rate"], positive=True) if "rate" in top else None
    if rate is not None and (problem := RATE.problem(rate, str(top["rate"]))) is not None:
        raise doc.fail("rate", problem)
    until = _number(doc, "until", top["until"], nonneg=True) if "until" in top else None
    rules = DeliveryRules()
    if "messages" in top:
        m = _mapping(doc, "messages", top["messages"], _MESSAGE_KEYS,
                     "range in metres, loss (a probability), seed")
        rng = _number(doc, "messages.range", m["range"], positive=True) if "range" in m \
            else math.inf
        loss = _number(doc, "messages.loss", m["loss"], nonneg=True) if "loss" in m else 0.0
        if loss > 1:
            raise doc.fail("messages.loss", f"a probability is at most 1, got {m['loss']}")
        rules = DeliveryRules(rng, loss, _integer(doc, "messages.seed", m["seed"])
                              if "seed" in m else None)
    raw = top.get("robots")
    if not isinstance(raw, dict) or not raw:
        raise doc.fail("robots" if "robots" in top else "", "a team file needs `robots:`, a "
                       "mapping from each robot's name to its plan file")
    members = []
    for name, v in raw.items():
        path = f"robots.{name}"
        if isinstance(v, str):
            members.append(MemberSpec(str(name), near(v)))
            continue
        m = _mapping(doc, path, v, _MEMBER_KEYS, "plan, element, set, start")
        if "plan" not in m:
            raise doc.fail(path, "missing key `plan` (the robot's plan file)")
        settings: Any = m.get("set", [])
        if isinstance(settings, str):
            settings = [settings]
        if not isinstance(settings, list) or not all(isinstance(s, str) for s in settings):
            raise doc.fail(f"{path}.set", "expected a list of NAME=VALUE settings such as "
                           "\"gap=1 m\"")
        members.append(MemberSpec(
            str(name), near(_string(doc, f"{path}.plan", m["plan"])),
            _string(doc, f"{path}.element", m["element"]) if "element" in m else None,
            tuple(settings),
            _start(doc, f"{path}.start", m["start"]) if "start" in m else None))
    return TeamSpec(world, tuple(members), seed, rate, until, rules,
                    None if file.startswith("<") else file)


@dataclass(frozen=True)
class LoadedTeam:
    """A team ready to run.

    The world (robots placed), and by robot its checked program, the element it runs and
    its plan file; the team checks' warnings and every source.
    """

    spec: TeamSpec
    world: Any
    programs: dict[str, Any]
    elements: dict[str, Any]
    plans: dict[str, str]
    warnings: list[Diagnostic]
    sources: dict[str, str]


def load_team(spec: TeamSpec, *, world: str | None = None, overrides: Sequence[str] = ()
              ) -> LoadedTeam:
    """Load the world and every robot's plan, and check them together.

    ``world`` replaces the spec's world; ``overrides`` (``NAME=VALUE``) apply to every
    plan after its own settings. A robot named twice keeps its last plan.

    Raises
    ------
    MdleError
        The world or a plan has errors, a robot is not in the world, two robots overlap,
        or the team's messages and robot names do not fit (every error, with places).
    """
    from mdle import sim
    from mdle.lang import load_program
    from mdle.runtime import element_of
    from mdle.team.check import check_team

    members: dict[str, MemberSpec] = {m.name: m for m in spec.members}
    world_spec = world or spec.world
    if world_spec is None:
        raise TeamError(Diagnostic(None, "a team needs a world with robots: give `world:` "
                                         "in the team file or --world"))
    w = sim.load_world(world_spec)
    robots = [r.name for r in w.robots]
    if not robots:
        raise TeamError(Diagnostic(None, f"world `{w.name}` has no `robots:` list, so it "
                                         "cannot hold a team", hint="list each robot with its "
                                         "name and start (docs/teams.md)"))
    if not members:
        raise TeamError(Diagnostic(None, "no robot has a plan: map robots to plans in the "
                                         "team file, or give --robot-plan NAME=PLAN.mdle"))
    for name in members:
        if name not in robots:
            raise TeamError(Diagnostic(None, f"robot `{name}` is not in world `{w.name}`",
                                       hint=f"its robots: {', '.join(robots)}"))
    places = []
    for r in w.robots:
        start = members[r.name].start if r.name in members else None
        places.append(r if start is None else dataclasses.replace(r, start=start))
    w = dataclasses.replace(w, robots=tuple(places))
    programs: dict[str, Any] = {}
    elements: dict[str, Any] = {}
    for name, m in members.items():
        programs[name] = load_program(m.plan, settings=[*m.settings, *overrides])
        elements[name] = element_of(programs[name], m.element)
    sources: dict[str, str] = {}
    for p in programs.values():
        sources.update(p.sources)
    errors, warnings = check_team({n: programs[n].uses_of(e.label)
                                   for n, e in elements.items()}, robots)
    if errors:
        raise TeamError(errors, sources)
    # A point robot has no body: the others' ladars cannot see it and no contact with it
    # can be detected; a team almost always means robots with bodies.
    warnings += [Diagnostic(None, f"robot `{r.name}` of world `{w.name}` is a point (profile "
                                  f"`{r.profile.name}`, radius 0 m): the other robots' ladars "
                                  "do not see it and no contact with it is detected",
                            hint="give it a robot with a body, e.g. `robot: pioneer2dx`",
                            severity=Severity.WARNING)
                 for r in w.robots if r.name in members and r.profile.radius <= 0]
    return LoadedTeam(spec, w, programs, elements, {n: m.plan for n, m in members.items()},
                      warnings, sources)
