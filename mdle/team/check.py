"""Checks across the plans of a team: robots named, channels sent on, units of messages.

Each plan is checked alone first (names, units, structure). Then, knowing which robot
runs which plan: a robot named by ``range_to``, ``bearing_to`` or ``pursue`` must be in
the team (error); a channel read that no plan sends on is a warning (the interrupt can
never fire); ``message(channel)`` used as a length where the sender sends a time is an
error, as are two senders of different units on one channel, and ``message(pose)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from mdle.core.errors import Diagnostic, Severity, Span
from mdle.core.messages import POSE_CHANNEL
from mdle.core.units import Dim
from mdle.lang import MessageUse, dim_words, same_kind

__all__ = ["check_team"]


def _where(span: Span | None) -> str:
    return str(span) if span is not None else "?"


def _unit(dim: Dim | str | None) -> str:
    return "poses" if dim == POSE_CHANNEL else dim_words(dim if isinstance(dim, Dim) else None)


def check_team(uses: Mapping[str, Sequence[MessageUse]], robots: Sequence[str]
               ) -> tuple[list[Diagnostic], list[Diagnostic]]:
    """Return (errors, warnings) about the team's messages and robot names.

    ``uses`` holds, by robot, what the element it runs names
    (:meth:`mdle.lang.Program.uses_of`); ``robots`` every robot of the world.
    """
    errors: list[Diagnostic] = []
    warnings: list[Diagnostic] = []
    senders: dict[str, list[tuple[str, MessageUse]]] = {}
    for robot, robot_uses in uses.items():
        for use in robot_uses:
            if use.kind == "send":
                senders.setdefault(use.name, []).append((robot, use))
    for channel, sends in senders.items():
        first_robot, first = sends[0]
        for robot, use in sends[1:]:
            a, b = first.dim, use.dim
            if isinstance(a, Dim) and isinstance(b, Dim) and not same_kind(a, b):
                errors.append(Diagnostic(
                    use.span, f"robot `{robot}` sends {_unit(b)} on `{channel}`, but robot "
                    f"`{first_robot}` sends {_unit(a)} there ({_where(first.span)})",
                    Severity.ERROR, hint="one channel carries one kind of number"))
    names = ", ".join(f"`{r}`" for r in robots)
    for robot, robot_uses in uses.items():
        for use in robot_uses:
            if use.kind == "robot":
                if use.name not in robots:
                    errors.append(Diagnostic(
                        use.span, f"`{use.what}` names robot `{use.name}`, which is not in "
                        f"the team", Severity.ERROR, hint=f"the robots: {names}"))
                elif use.name == robot:
                    warnings.append(Diagnostic(
                        use.span, f"robot `{robot}` runs this plan: `{use.what}({robot})` "
                        "asks about itself, and it never receives its own pose",
                        Severity.WARNING))
                continue
            if use.kind != "read":
                continue
            sends = senders.get(use.name, [])
            if not sends:
                warnings.append(Diagnostic(
                    use.span, f"no robot of the team sends on channel `{use.name}`: "
                    f"`{use.what}({use.name})` never sees a message", Severity.WARNING,
                    hint="send on it in an atom: `(..., send({0}, 1))`".format(use.name)))
                continue
            if use.what == "message" and any(s.dim == POSE_CHANNEL for _, s in sends):
                errors.append(Diagnostic(
                    use.span, f"channel `{use.name}` carries poses, not numbers",
                    Severity.ERROR, hint="read a robot's pose with `range_to(ROBOT)` and "
                                         "`bearing_to(ROBOT)`"))
                continue
            if isinstance(use.dim, Dim):
                for sender, s in sends:
                    if isinstance(s.dim, Dim) and not same_kind(s.dim, use.dim):
                        errors.append(Diagnostic(
                            use.span, f"`message({use.name})` is used as {_unit(use.dim)} "
                            f"here, but robot `{sender}` sends {_unit(s.dim)} on "
                            f"`{use.name}` ({_where(s.span)})", Severity.ERROR))
                        break
    return _unique(errors), _unique(warnings)


def _unique(diags: list[Diagnostic]) -> list[Diagnostic]:
    seen: set[tuple[Span | None, str]] = set()
    out = []
    for d in diags:
        if (d.span, d.message) not in seen:
            seen.add((d.span, d.message))
            out.append(d)
    return out
