"""The checker's shared state: diagnostics, nesting depth, caches, message uses.

The checker is one object (:class:`~mdle.lang.check.Checker`) assembled from one class
per concern: names and arity (:mod:`~mdle.lang.check_names`), dimensions of values,
timers and interrupts (:mod:`~mdle.lang.check_dimensions`), and structure and
reachability of elements (:mod:`~mdle.lang.check_structure`). They share the state
kept here, and call one another through the abstract methods declared here.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from mdle.atoms.registry import LawSpec, Param, SensorSpec
from mdle.core.errors import Diagnostic, Severity, Span
from mdle.core.motion_limits import KnownRobot
from mdle.core.units import Dim
from mdle.lang import conditions as cond
from mdle.lang import syntax as st
from mdle.lang.dimensions import Quantity, Symbol, Value
from mdle.lang.expansion import ExpansionBudget
from mdle.lang.format import format_expr
from mdle.lang.program import Element, Interrupt, MessageUse
from mdle.lang.resolve import Namespace

#: Deepest nesting of elements and interrupts, counting through named definitions.
MAX_NESTING = 120

Env = Mapping[str, Value]
_EMPTY: Env = MappingProxyType({})
_UNKNOWN = Quantity(math.nan, None)
_MISSING = object()  # not in a cache (None there means: failed before)
_NAN_KEY = "NaN"  # every NaN value's place in a cache key


class _Abort(Exception):
    """Stops a branch of the check after its error has been reported."""


@dataclass(frozen=True)
class _Slot:
    """A parameter as the binder sees it: law, sensor function or definition parameter."""

    name: str
    dim: Dim | None  # None: any dimension (a definition parameter without a numeric default)
    default: Any  # a Value, or REQUIRED
    choices: tuple[str, ...] = ()
    symbol: bool = False  # takes a symbol (a law parameter with choices, or a symbol default)
    param: Param | None = None  # a law's or sensor function's declaration (its range)


def _kind_name(target: object) -> str:
    if isinstance(target, LawSpec):
        return "a control law"
    if isinstance(target, SensorSpec):
        return "a sensor function"
    if isinstance(target, st.Definition):
        return {"atom": "an atom", "behavior": "a behavior", "plan": "a plan",
                "interrupt": "an interrupt"}[target.kind.value]
    return "a parameter"


def _frozen_value(v: Value) -> tuple[Any, ...]:
    if isinstance(v, Symbol):
        return (v.name,)
    # NaN (a parameter only a call fixes, or `inf * 0`) is never equal to itself: keyed by
    # value, every NaN would miss the cache and a chain of definitions passing one on
    # (`iK(a) = iK-1(a) or iK-1(a + 1 deg)`) would be checked once per path, 2**K times
    value = _NAN_KEY if v.value != v.value else v.value
    return (value, v.dim, v.bare)


def _freeze(bound: Mapping[str, Value]) -> tuple[tuple[str, Any], ...]:
    if not bound:
        return ()
    if len(bound) == 1:
        ((k, v),) = bound.items()
        return ((k, _frozen_value(v)),)
    return tuple(sorted((k, _frozen_value(v)) for k, v in bound.items()))


def _short(expr: st.Expr) -> str:
    text = format_expr(expr)
    return text if len(text) <= 60 else text[:57] + "..."


class CheckerState(ABC):
    """What every concern of the checker shares (see the module docstring).

    Diagnostics accumulate in :attr:`errors` and :attr:`warnings`; each public method
    returns None for a part that has errors (after reporting them).
    """

    def __init__(self, ns: Namespace, robot: KnownRobot | None = None) -> None:
        self.ns = ns
        # ns.lookup as one dict: definitions over control laws over sensor functions
        # (the namespace does not change while a checker uses it)
        self._lookup = {**ns.registry.sensors, **ns.registry.laws, **ns.definitions}.get
        #: The robot whose speed and turn-rate limits constants are compared with (None:
        #: no comparison).
        self.robot = robot
        #: The scaled atom's own atom while :meth:`_scaled` compiles it: its limits are
        #: checked after scaling, not before.
        self._scaling: st.Expr | None = None
        #: The first item of a triple while :meth:`string` compiles it as an element: an
        #: unknown name there may be a misspelt control law (``(g(1 m/s), never, 5 s)``).
        self._atom_head: st.Expr | None = None
        self.errors: list[Diagnostic] = []
        self.warnings: list[Diagnostic] = []
        self._seen: set[tuple[Span | None, str]] = set()
        self._notes: list[Diagnostic] = []
        self._depth = 0
        self._cache: dict[tuple[Any, ...], Any] = {}
        #: what instances with new argument values add to the program (bounded)
        self._expansion = ExpansionBudget()
        self.broken: set[str] = set()
        self._depths: dict[int, int] = {}
        self._too_deep = False
        self._keep: list[Element] = []
        self._never_memo: dict[int, bool] = {}  # by id: elements stay alive in _keep
        self._pools: dict[tuple[Any, ...], dict[int | str, list[str]]] = {}  # _closest's indexes
        self._readable: list[str] | None = None  # the names any condition may read
        self._element_pools: dict[bool, list[str]] = {}  # element names (True: and laws)
        self._spec_slots: dict[int, list[_Slot]] = {}  # by id of a law or sensor function
        self._def_slots: dict[int, list[_Slot]] = {}  # by id of a definition
        #: Names defined by statements that did not parse: uses of them are not errors
        #: of their own (the syntax error is reported)
        self.unparsed: frozenset[str] = frozenset()
        #: Names of definitions refused (a control law's or sensor function's name): a
        #: use that does not fit what the name really is, is not an error of its own
        self.refused: frozenset[str] = frozenset()
        #: For each definition used as an element: whether each use was scaled, and the
        #: robot-limit warnings of atoms checked on their own, held until every use is
        #: known (an atom used only scaled down is not too fast)
        self.scaled_uses: dict[str, set[bool]] = {}
        self._deferring: list[tuple[Span | None, str, str]] | None = None
        self.deferred: dict[str, list[tuple[Span | None, str, str]]] = {}
        #: While the arguments of a sensor function are bound: those read each tick
        #: (``range(-theta)``), by parameter (None: every argument must be fixed)
        self._live_args: dict[str, Any] | None = None
        #: True inside ``at_start(...)``
        self._remembering = False
        #: id of each reading of a sensor function with declared bounds: (bounds, name)
        self._bounded: dict[int, tuple[Any, str]] = {}
        #: True while a definition is checked with its required parameters unknown (NaN):
        #: a NaN is then no error (each use with arguments is checked again)
        self._partial = False
        #: where the program sends, reads channels and names robots (for team checks)
        self.uses: list[MessageUse] = []
        #: id of each `message(channel)` reading's node: (node, channel, span)
        self._messages: dict[int, tuple[Any, str, Span]] = {}
        # the uses of the instance being checked (innermost last), and of each one checked
        self._use_stack: list[list[MessageUse]] = []
        self._key_uses: dict[tuple[Any, ...], list[MessageUse]] = {}
        #: the uses of each runnable definition, as it runs with its defaults
        self.element_uses: dict[str, tuple[MessageUse, ...]] = {}

    def _use(self, use: MessageUse) -> None:
        self.uses.append(use)
        if self._use_stack:
            self._use_stack[-1].append(use)

    def _replay(self, key: tuple[Any, ...]) -> None:
        """Count a cached instance's uses again, for the instance using it too."""
        if self._use_stack and self._key_uses:
            self._use_stack[-1].extend(self._key_uses.get(key, ()))

    # ------------------------------------------------------------------ diagnostics

    def error(self, span: Span | None, message: str, hint: str | None = None,
              notes: Sequence[Diagnostic] = ()) -> None:
        """Record an error once (the same place and message may be met by several uses)."""
        key = (span, message)
        if key in self._seen:
            return
        self._seen.add(key)
        self.errors.append(Diagnostic(span, message, Severity.ERROR, hint,
                                      tuple(notes) + tuple(self._notes[-1:])))

    def _expand(self, d: st.Definition, call: Span | None) -> None:
        """Account for a new instance of ``d`` before it is made; abort past the budget."""
        budget = self._expansion
        if budget.charge(d):
            return
        if not budget.reported:  # the first refusal says where; later ones abort quietly
            budget.reported = True
            self.error(call or d.name_span, budget.message(d),
                       hint="each different set of argument values makes another copy of a "
                            "definition; pass fewer different values")
        raise _Abort

    def warn(self, span: Span | None, message: str, hint: str | None = None,
             in_use: bool = False) -> None:
        """Record a warning once; ``in_use`` adds the use of a definition being checked."""
        key = (span, "w:" + message)
        if key in self._seen:
            return
        self._seen.add(key)
        notes = tuple(self._notes[-1:]) if in_use else ()
        self.warnings.append(Diagnostic(span, message, Severity.WARNING, hint, notes))

    def _enter(self, span: Span) -> None:
        """One level deeper (the caller leaves with ``self._depth -= 1`` in a finally)."""
        self._depth += 1
        if self._depth > MAX_NESTING:
            self._depth -= 1
            self.error(span, f"elements and interrupts nest more than {MAX_NESTING} levels "
                       "deep here (counting through named definitions)",
                       hint="flatten the plan: fewer levels of behaviors inside behaviors")
            raise _Abort

    @staticmethod
    def _plain(values: Mapping[str, Value]) -> dict[str, float | str]:
        return {k: (v.name if isinstance(v, Symbol) else v.value) for k, v in values.items()}

    # ------------------------------------------------------------------ across concerns

    @abstractmethod
    def value(self, expr: st.Expr, env: Env) -> Value:
        """Evaluate a fixed value (:mod:`~mdle.lang.check_dimensions`)."""

    @abstractmethod
    def timer(self, expr: st.Expr, env: Env) -> float:
        """Return a timer in seconds (:mod:`~mdle.lang.check_dimensions`)."""

    @abstractmethod
    def _factor(self, expr: st.Expr, env: Env, what: str) -> float:
        """Return a scale factor, a plain number (:mod:`~mdle.lang.check_dimensions`)."""

    @abstractmethod
    def condition(self, expr: st.Expr, env: Env) -> cond.Typed:
        """Type and compile a condition (:mod:`~mdle.lang.check_dimensions`)."""

    @abstractmethod
    def interrupt(self, expr: st.Expr, env: Env) -> Interrupt:
        """Return an element's compiled interrupt (:mod:`~mdle.lang.check_dimensions`)."""

    @abstractmethod
    def _within_limits(self, law: LawSpec, args: Mapping[str, Value], call: st.Expr,
                       scale: tuple[float, float] = (1.0, 1.0),
                       span: Span | None = None) -> None:
        """Warn about constants beyond the robot (:mod:`~mdle.lang.check_dimensions`)."""

    @abstractmethod
    def bind(self, callee: str, slots: Sequence[_Slot], args: Sequence[st.Argument],
             env: Env, span: Span) -> dict[str, Value]:
        """Bind call arguments to parameters (:mod:`~mdle.lang.check_names`)."""

    @abstractmethod
    def live_argument(self, callee: str, slot: _Slot, expr: st.Expr, env: Env) -> Value | None:
        """Type an argument read each tick (:mod:`~mdle.lang.check_dimensions`)."""

    @abstractmethod
    def _is_live(self, expr: st.Expr, env: Env) -> bool:
        """Tell whether ``expr`` reads a sensor function (:mod:`~mdle.lang.check_expressions`)."""

    @abstractmethod
    def slots_of(self, d: st.Definition) -> list[_Slot]:
        """Return a definition's parameters (:mod:`~mdle.lang.check_names`)."""

    @abstractmethod
    def _slots_of_spec(self, spec: LawSpec | SensorSpec) -> list[_Slot]:
        """Return a law's or sensor function's parameters (:mod:`~mdle.lang.check_names`)."""

    @abstractmethod
    def _note_names(self, spec: LawSpec | SensorSpec, bound: Mapping[str, Value],
                    span: Span) -> None:
        """Record the channels and robots a call names (:mod:`~mdle.lang.check_names`)."""

    @abstractmethod
    def _unknown(self, name: str, span: Span, what: str, pool: Sequence[str],
                 shared: list[str] | None = None) -> None:
        """Report an unknown name (:mod:`~mdle.lang.check_names`)."""

    @abstractmethod
    def _named_element(self, expr: st.Name | st.Call, env: Env) -> Element:
        """Compile a named element (:mod:`~mdle.lang.check_names`)."""

    @abstractmethod
    def instance(self, d: st.Definition, bound: Mapping[str, Value],
                 call: Span | None = None) -> Element:
        """Return a definition's element (:mod:`~mdle.lang.check_structure`)."""
