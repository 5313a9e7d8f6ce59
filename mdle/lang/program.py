"""The checked program: the immutable form the runtime executes.

The checker turns the syntax tree into these nodes: every name resolved, every call
instantiated with its arguments (SI values), every interrupt compiled once into a
closure, every scale applied. The runtime never looks at the syntax tree.

An :data:`Element` is an :class:`AtomNode` (sigma = (U, xi, T)) or a
:class:`StringNode` (((e1, ..., en), xi, T), a behavior, a plan or an anonymous
nested element). Nesting has no fixed depth.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Union

from mdle.atoms.registry import Args, Context, LawSpec
from mdle.core.errors import Diagnostic, Span
from mdle.core.units import Dim

__all__ = [
    "Interrupt",
    "Send",
    "MessageUse",
    "NEVER",
    "AtomNode",
    "LiveArg",
    "LiveArgs",
    "StringNode",
    "StringKind",
    "Element",
    "Program",
    "INF",
]

INF = math.inf


@dataclass(frozen=True)
class Interrupt:
    """A compiled interrupt xi: ``test(ctx)`` is true when the element must end.

    ``source`` is the canonical text (for ``mdle show``, traces and messages);
    ``never`` marks the interrupt that never fires, so the runtime can skip it.
    ``remember`` lists the values the condition reads as they were when the element
    started (``at_start(...)``, and the first reading of ``lowest``, ``highest``,
    ``ever``): a key, and the function the runtime evaluates once, at the start, to
    store under it in ``ctx.memory``, inner before outer. ``track`` lists the running
    memories (``lowest(e)``...): a key, the function read, and the fold that joins
    each tick's reading to the value held, applied before each test.
    """

    test: Callable[[Context], bool]
    source: str
    never: bool = False
    remember: tuple[tuple[Any, Callable[[Context], Any]], ...] = ()
    track: tuple[tuple[Any, Callable[[Context], Any], Callable[[Any, Any], Any]], ...] = ()
    #: The conditions joined by a top-level ``or`` (``at_goal or stalled``): each one's
    #: text and test, so that the runtime can say which fired. Empty for one condition.
    parts: tuple[tuple[str, Callable[[Context], bool]], ...] = ()


def _never(ctx: Context) -> bool:
    return False


NEVER = Interrupt(_never, "never", never=True)


@dataclass(frozen=True)
class Send:
    """What an atom sends at every tick it runs: ``send(channel, value)`` or ``send(pose)``.

    ``value(ctx)`` reads the number sent (SI); None sends the robot's pose. ``dim`` is the
    number's dimension (None: not known, or a pose).
    """

    channel: str
    value: Callable[[Context], float] | None
    dim: Dim | None
    source: str
    span: Span | None = None


@dataclass(frozen=True)
class MessageUse:
    """A place where a plan names a channel or another robot, for a team's checks.

    ``kind`` is ``send`` (a channel sent on, ``dim`` its number's dimension, or the
    string ``pose``), ``read`` (a channel read: ``received``, ``message``; ``dim`` the
    dimension its use asks of ``message``, None if none) or ``robot`` (a robot named by
    ``range_to``, ``bearing_to``, ``pursue``).
    """

    kind: str
    name: str
    dim: Dim | str | None
    span: Span | None
    what: str = ""


class StringKind(enum.Enum):
    """What a string of elements was declared as (it runs the same way in each case)."""

    PLAN = "plan"
    BEHAVIOR = "behavior"
    GROUP = "group"
    """An anonymous ``((...), xi, T)`` element written inside another."""


@dataclass(frozen=True)
class LiveArg:
    """A control law's argument read while its atom runs: ``theta`` of ``heading(theta + 90 deg)``.

    ``read(ctx)`` evaluates it (SI), ``text`` is its canonical text, ``param`` the law's
    parameter it is given to (its declared range is checked at each reading).
    """

    name: str
    text: str
    read: Callable[[Context], Any]
    param: Any


@dataclass(frozen=True)
class LiveArgs:
    """The arguments of an atom's control law that are read while it runs.

    ``args`` lists them; ``remember`` and ``track`` are what their expressions remember
    (``at_start``, ``lowest``...), as for :class:`Interrupt`: evaluated when the atom
    starts, and folded at each tick before the arguments are read.
    """

    args: tuple[LiveArg, ...]
    remember: tuple[tuple[Any, Callable[[Context], Any]], ...] = ()
    track: tuple[tuple[Any, Callable[[Context], Any], Callable[[Any, Any], Any]], ...] = ()


@dataclass(frozen=True)
class AtomNode:
    """An atom sigma = (U, xi, T), instantiated and ready to run.

    ``label`` names it in element paths (``patrol/cruise``): the atom's name, or the
    control law's name for an atom written inline. ``args`` are the law's arguments in
    SI (defaults filled in). ``scale`` is the scaled atom's alpha for the (v, omega)
    channels; the timer already includes beta. ``live`` holds the arguments read while
    the atom runs (an expression of sensor functions, ``at_start``...), whose place in
    ``args`` is a NaN; None when every argument is fixed.
    """

    label: str
    law: LawSpec
    args: Args
    interrupt: Interrupt = NEVER
    timer: float = INF
    scale: tuple[float, float] = (1.0, 1.0)
    span: Span | None = None
    sends: tuple[Send, ...] = ()
    live: LiveArgs | None = None


@dataclass(frozen=True)
class StringNode:
    """A string of elements with its own interrupt and timer: ((e1, ..., en), xi, T).

    With ``repeat`` (``...`` in the source) the string starts again from its first
    element after its last ends, until its own or an enclosing interrupt or timer ends
    it.
    """

    label: str
    elements: tuple["Element", ...]
    interrupt: Interrupt = NEVER
    timer: float = INF
    repeat: bool = False
    kind: StringKind = StringKind.GROUP
    span: Span | None = None


Element = Union[AtomNode, StringNode]


@dataclass(frozen=True)
class Program:
    """A checked program: runnable elements by name, the entry, and where they came from.

    ``elements`` holds every named definition that can run as it stands (atoms,
    behaviors and plans whose parameters all have defaults), instantiated with those
    defaults. ``entry`` is the ``run`` target, else ``main`` if defined, else None.
    ``sources`` maps each file read (imports included) to its text, for diagnostics.
    ``warnings`` are the checker's warnings (the program is valid). ``uses`` lists where
    it sends, reads channels and names other robots (:class:`MessageUse`), anywhere;
    ``element_uses`` those of each runnable element as it runs, with its defaults.
    """

    elements: Mapping[str, Element]
    entry: str | None
    sources: Mapping[str, str] = field(default_factory=lambda: MappingProxyType({}))
    warnings: tuple[Diagnostic, ...] = ()
    uses: tuple[MessageUse, ...] = ()
    element_uses: Mapping[str, tuple[MessageUse, ...]] = field(
        default_factory=lambda: MappingProxyType({}))

    def uses_of(self, name: str) -> tuple[MessageUse, ...]:
        """Return what element ``name`` names as it runs (every use for an unknown name)."""
        return self.element_uses.get(name, self.uses)
