"""Hand-built IR for the runtime tests: small laws, signal interrupts, event tables.

Nothing here uses the parser: elements are built from :mod:`mdle.lang.program` nodes, and
interrupts read scripted signals from ``ctx.obs.truth`` so a test says per tick which
conditions hold. Tests get the helpers through the ``ir`` fixture (pytest runs with
``--import-mode=importlib``, so a helper module could not be imported by name).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from types import SimpleNamespace
from typing import Any

import pytest

from mdle.atoms.registry import Context, LawSpec
from mdle.core.backend import Command
from mdle.lang import INF, NEVER, AtomNode, Element, Interrupt, StringKind, StringNode
from mdle.runtime import Event, EventKind


def const_law(name: str, v: float = 0.0, omega: float = 0.0,
              start: Callable[[Any, Context], Any] | None = None,
              step: Callable[[Any, Context, Any], Command] | None = None) -> LawSpec:
    """A law that always commands (v, omega), or runs ``step`` when given."""

    def constant(args: Any, ctx: Context, state: Any) -> Command:
        return Command(v, omega)

    return LawSpec(name, (), step or constant, start)


def sig(name: str) -> Interrupt:
    """An interrupt true at the ticks whose scripted truth holds ``name``."""

    def test(ctx: Context) -> bool:
        return bool(ctx.obs.truth.get(name, False))

    return Interrupt(test, name)


def atom(label: str, v: float = 0.0, omega: float = 0.0, *, when: str | Interrupt | None = None,
         timer: float = INF, scale: tuple[float, float] = (1.0, 1.0),
         law: LawSpec | None = None) -> AtomNode:
    """An atom commanding (v, omega), ended by the signal ``when`` and/or ``timer``."""
    interrupt = sig(when) if isinstance(when, str) else (when or NEVER)
    return AtomNode(label, law or const_law(label, v, omega), {}, interrupt, timer, scale)


def string(label: str, *elements: Element, when: str | Interrupt | None = None,
           timer: float = INF, repeat: bool = False,
           kind: StringKind = StringKind.BEHAVIOR) -> StringNode:
    """A string of elements with an optional signal interrupt and timer."""
    interrupt = sig(when) if isinstance(when, str) else (when or NEVER)
    return StringNode(label, tuple(elements), interrupt, timer, repeat, kind)


def signals(ticks: int, **on: Sequence[int]) -> list[dict[str, Any]]:
    """A script of ``ticks`` entries; ``on[name]`` lists the ticks where signal ``name`` holds."""
    return [{"truth": {name: True for name, at in on.items() if k in at}} for k in range(ticks)]


def fmt(e: Event) -> str:
    """``+path`` for a start, ``-path:cause`` for an end."""
    if e.kind is EventKind.START:
        return f"+{e.path}"
    assert e.cause is not None
    return f"-{e.path}:{e.cause.value}"


def table(events: Sequence[Event], dt: float = 0.1) -> dict[int, list[str]]:
    """Events grouped by tick number (time / dt rounded)."""
    out: dict[int, list[str]] = {}
    for e in events:
        out.setdefault(round(e.time / dt), []).append(fmt(e))
    return out


@pytest.fixture
def ir() -> SimpleNamespace:
    """The helpers above: ``ir.atom``, ``ir.string``, ``ir.sig``, ``ir.table``, ..."""
    return SimpleNamespace(const_law=const_law, sig=sig, atom=atom, string=string,
                           signals=signals, fmt=fmt, table=table)
