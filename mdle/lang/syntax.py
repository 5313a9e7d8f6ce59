"""The MDLe syntax tree: immutable, typed nodes with source spans.

The parser (:mod:`mdle.lang.parser`) builds these from text; the checker
(:mod:`mdle.lang.check`) reads them and builds the runnable program
(:mod:`mdle.lang.program`); the formatter (:mod:`mdle.lang.format`) prints them back.
Nothing downstream of the parser reads a lark tree.

Tuples are kept generic (:class:`Group`): what ``(a, b, c)`` means (an atom, a scaled
atom, a string of elements, a nested element) depends on where it stands and on what
its names resolve to, which only the checker knows.

Spans do not take part in equality (``field(compare=False)``), so two trees parsed
from differently laid out texts compare equal when they mean the same program: the
formatter's round trip is tested that way.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Union

from mdle.core.errors import Span
from mdle.core.units import Dim

__all__ = [
    "Number",
    "Name",
    "Never",
    "Inf",
    "Argument",
    "Call",
    "Unary",
    "Binary",
    "Group",
    "Vector",
    "Expr",
    "Param",
    "DefKind",
    "Definition",
    "Import",
    "Run",
    "Statement",
    "Comment",
    "Module",
    "Loaded",
    "NO_SPAN",
    "children",
]

#: The span of a node made by code rather than parsed (tests, generated plans).
NO_SPAN = Span("<none>", 0, 0, 0, 0)


def _span() -> Span:
    return field(default=NO_SPAN, compare=False, repr=False)


@dataclass(frozen=True)
class Number:
    """A number with its unit: ``0.3 m/s``.

    ``value`` is in SI units (here 0.3), ``dim`` its dimension; ``text`` is the number
    as written (``0.3``) and ``unit`` the unit as written, normalised without spaces
    (``m/s``), or ``""`` for a bare number.
    """

    value: float
    dim: Dim
    text: str
    unit: str = ""
    span: Span = _span()


@dataclass(frozen=True)
class Name:
    """A name: a parameter, a definition, a sensor function, a symbol such as ``right``."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class Never:
    """``never``: the interrupt that never fires."""

    span: Span = _span()


@dataclass(frozen=True)
class Inf:
    """``inf``: the timer that never expires."""

    span: Span = _span()


@dataclass(frozen=True)
class Argument:
    """One argument of a call: positional (``name`` is None) or keyword (``v = 0.3 m/s``)."""

    name: str | None
    value: "Expr"
    span: Span = _span()


@dataclass(frozen=True)
class Call:
    """A call ``name(arguments)``: a control law, sensor function or definition with arguments."""

    name: str
    args: tuple[Argument, ...]
    span: Span = _span()
    name_span: Span = _span()


@dataclass(frozen=True)
class Unary:
    """``not e``, ``-e`` or ``+e``."""

    op: str
    operand: "Expr"
    span: Span = _span()


@dataclass(frozen=True)
class Binary:
    """``a op b`` for ``and or xor``, comparisons and arithmetic."""

    op: str
    left: "Expr"
    right: "Expr"
    span: Span = _span()
    op_span: Span = _span()


@dataclass(frozen=True)
class Group:
    """A parenthesised tuple ``(a, b, ...)``, with ``repeat`` for a trailing ``...``.

    A one-item group without ``...`` is a plain parenthesised expression in an
    interrupt or argument.
    """

    items: tuple["Expr", ...]
    repeat: bool = False
    span: Span = _span()


@dataclass(frozen=True)
class Vector:
    """``[a, b]``: a per-channel scale factor (alpha_v, alpha_omega) of a scaled atom."""

    items: tuple["Expr", ...]
    span: Span = _span()


Expr = Union[Number, Name, Never, Inf, Call, Unary, Binary, Group, Vector]


@dataclass(frozen=True)
class Param:
    """A parameter of a definition, with its default expression (None: required)."""

    name: str
    default: Expr | None = None
    span: Span = _span()


class DefKind(enum.Enum):
    """The keyword a definition starts with."""

    ATOM = "atom"
    BEHAVIOR = "behavior"
    PLAN = "plan"
    INTERRUPT = "interrupt"


@dataclass(frozen=True)
class Definition:
    """``kind name(params) = body``. ``params`` is None when no parentheses were written."""

    kind: DefKind
    name: str
    params: tuple[Param, ...] | None
    body: Expr
    span: Span = _span()
    name_span: Span = _span()

    @property
    def param_list(self) -> tuple[Param, ...]:
        """The parameters (empty when none were written)."""
        return self.params or ()


@dataclass(frozen=True)
class Import:
    """``import "path"``: the path as written, relative to the importing file."""

    path: str
    span: Span = _span()


@dataclass(frozen=True)
class Run:
    """``run name``: the entry of the program."""

    name: str
    span: Span = _span()
    name_span: Span = _span()


Statement = Union[Import, Run, Definition]


@dataclass(frozen=True)
class Comment:
    """A ``# comment`` (text including the ``#``), kept so ``mdle fmt`` does not drop it."""

    text: str
    span: Span = _span()


@dataclass(frozen=True)
class Module:
    """One parsed file: its statements in order, and its comments."""

    file: str
    statements: tuple[Statement, ...]
    comments: tuple[Comment, ...] = field(default=(), compare=False)

    @property
    def definitions(self) -> tuple[Definition, ...]:
        """The definitions, in order."""
        return tuple(s for s in self.statements if isinstance(s, Definition))


def children(expr: Expr) -> tuple[Expr, ...]:
    """Return the sub-expressions of an expression, left to right (for non-recursive walks)."""
    if isinstance(expr, Call):
        return tuple(a.value for a in expr.args)
    if isinstance(expr, Unary):
        return (expr.operand,)
    if isinstance(expr, Binary):
        return (expr.left, expr.right)
    if isinstance(expr, (Group, Vector)):
        return expr.items
    return ()


@dataclass(frozen=True)
class Loaded:
    """The files of a program: modules in dependency order (imports first), their texts.

    (Made by :func:`mdle.lang.loader.load_modules`; here so the loader and the parameter
    overrides, which both take and give it, need not import each other.)
    """

    modules: tuple[Module, ...]
    sources: dict[str, str]
    main: Module | None
