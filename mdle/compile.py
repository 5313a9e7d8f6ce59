"""The checker: syntax tree to the runnable program of :mod:`mdle.program`.

It resolves every name against the namespace (definitions, control laws, sensor
functions), binds arguments to parameters (arity, keywords, symbols, dimensions),
classifies each tuple by where it stands, compiles interrupts into closures
(:mod:`mdle.conditions`), evaluates timers, and warns about elements that can never be
reached. Errors are collected, not raised one at a time: :func:`check_program` raises
one :class:`~mdle.errors.CheckError` with all of them.

How a tuple ``(a, b, c)`` in an element position is read:

* ``a`` is a control law (``go(0.3 m/s)``, ``stop``): an atom (U, xi, T);
* ``a`` is a number, a parameter or ``[av, aw]``: a scaled atom (alpha, beta, sigma);
* ``a`` is a parenthesised string or a named element: an element ((a...), xi, T).

A definition with parameters is checked once on its own (parameters without a
default may be anything) and again for each distinct use with arguments, so a
dimension that only a call fixes is still checked; results are cached per arguments.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, TypeVar

from mdle import conditions as cond
from mdle import syntax as st
from mdle.atoms.registry import BOOL, REQUIRED, LawSpec, Param, Registry, SensorSpec
from mdle.dimensions import (
    Quantity,
    Symbol,
    Value,
    dim_example,
    dim_words,
    fits,
    same_kind,
    show_value,
    unit_for,
)
from mdle.errors import CheckError, Diagnostic, Severity, Span
from mdle.format import format_expr
from mdle.messages import POSE_CHANNEL
from mdle.motion_limits import KnownRobot, excess
from mdle.program import (
    INF,
    AtomNode,
    Element,
    Interrupt,
    MessageUse,
    Program,
    Send,
    StringKind,
    StringNode,
)
from mdle.resolve import Namespace, build_namespace, find_cycles, uses_of
from mdle.treebuild import builder
from mdle.units import NONE, TIME, TURN_RATE, Dim

__all__ = ["Checker", "check_program", "MAX_NESTING", "missing_entry", "never_ends"]

#: Deepest nesting of elements and interrupts, counting through named definitions.
MAX_NESTING = 120
#: Most names one "did you mean" compares an unknown name with.
_MAX_CANDIDATES = 200

Env = Mapping[str, Value]
_EMPTY: Env = MappingProxyType({})
_UNKNOWN = Quantity(math.nan, None)
_MISSING = object()  # not in a cache (None there means: failed before)


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


def _own_never(e: Element) -> bool:
    return e.interrupt.never and math.isinf(e.timer)


def never_ends(e: Element, memo: dict[int, bool] | None = None) -> bool:
    """Whether an element can only be ended by an enclosing interrupt or timer.

    That is: its own interrupt never fires, its timer is ``inf``, and it is an atom, a
    repeated string, or a string holding an element that never ends. Shared elements
    are visited once (``memo``, by identity, may be kept across calls), so a chain of
    behaviors each holding the previous one twice costs its length, not 2**length.
    """
    memo = {} if memo is None else memo
    if not _own_never(e):
        return False
    # Post-order without recursion: (node, children pushed?).
    stack: list[tuple[Element, bool]] = [(e, False)]
    while stack:
        x, expanded = stack.pop()
        if id(x) in memo:
            continue
        if isinstance(x, AtomNode) or x.repeat:
            memo[id(x)] = True
            continue
        kids = [c for c in x.elements if _own_never(c)]
        if not expanded:
            stack.append((x, True))
            stack.extend((c, False) for c in kids if id(c) not in memo)
            continue
        memo[id(x)] = any(memo[id(c)] for c in kids)
    return memo[id(e)]


class Checker:
    """Checks definitions and compiles elements against one namespace.

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
        self.broken: set[str] = set()
        self._depths: dict[int, int] = {}
        self._too_deep = False
        self._keep: list[Element] = []
        self._never_memo: dict[int, bool] = {}  # by id: elements stay alive in _keep
        self._pools: dict[tuple[Any, ...], dict[int, list[str]]] = {}  # _closest's indexes
        self._spec_slots: dict[int, list[_Slot]] = {}  # by id of a law or sensor function
        self._def_slots: dict[int, list[_Slot]] = {}  # by id of a definition
        #: Names defined by statements that did not parse: uses of them are not errors
        #: of their own (the syntax error is reported)
        self.unparsed: frozenset[str] = frozenset()
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

    def _closest(self, name: str, pool: Sequence[str]) -> str | None:
        """Return the name in ``pool`` closest to ``name`` (difflib, cutoff 0.6), if any.

        The pool is indexed by length once per checker: a ratio of 0.6 needs lengths
        within a factor of two, and at most :data:`_MAX_CANDIDATES` of those (sharing the
        first letter first) are compared, so 4,000 unknown names among 4,000 definitions
        cost a few comparisons each instead of 4,000.
        """
        key = (len(pool), tuple(pool[:3]), tuple(pool[-3:]))
        index = self._pools.get(key)
        if index is None:
            index = {}
            for c in dict.fromkeys(pool):
                index.setdefault(len(c), []).append(c)
            self._pools[key] = index
        n = len(name)
        near = [c for size in range(max(1, n // 2), 2 * n + 2) for c in index.get(size, ())]
        if len(near) > _MAX_CANDIDATES:
            near = ([c for c in near if c[:1] == name[:1]] + near)[:_MAX_CANDIDATES]
        close = difflib.get_close_matches(name, near, n=1, cutoff=0.6)
        return close[0] if close else None

    def _unknown(self, name: str, span: Span, what: str, pool: Sequence[str]) -> None:
        if name in self.unparsed:
            return  # its statement has a syntax error, reported already
        found = self._closest(name, list(pool))
        close = [found] if found else []
        self.error(span, f"unknown {what} `{name}`",
                   hint=f"did you mean `{close[0]}`?" if close else None)

    # ------------------------------------------------------------------ fixed values

    def value(self, expr: st.Expr, env: Env) -> Value:
        """Evaluate a fixed value: numbers with units, parameters, arithmetic.

        A bare unknown name is a symbol (its use decides whether that is right). Raises
        _Abort after an error.
        """
        if self._depth >= MAX_NESTING:
            self._enter(expr.span)  # reports, raises
        if type(expr) is st.Number:  # the common case, with nothing nested to count
            return _new_quantity(expr.value, expr.dim, not expr.unit)
        self._depth += 1
        try:
            return self._value(expr, env)
        finally:
            self._depth -= 1

    def _value(self, expr: st.Expr, env: Env) -> Value:
        if isinstance(expr, st.Number):
            return _new_quantity(expr.value, expr.dim, not expr.unit)
        if isinstance(expr, st.Name):
            if expr.name in env:
                return env[expr.name]
            target = self._lookup(expr.name)
            if target is not None:
                self.error(expr.span, f"expected a fixed value, but `{expr.name}` is "
                           f"{_kind_name(target)}",
                           hint="arguments and timers are fixed when an element starts; "
                                "sensor readings belong in interrupts")
                raise _Abort
            return Symbol(expr.name)
        if isinstance(expr, st.Inf):
            return Quantity(INF, None)
        if isinstance(expr, st.Group) and len(expr.items) == 1 and not expr.repeat:
            return self.value(expr.items[0], env)
        if isinstance(expr, st.Unary) and expr.op in "+-":
            q = self._number(expr.operand, env)
            return q if expr.op == "+" else Quantity(-q.value, q.dim, q.bare)
        if isinstance(expr, st.Binary) and expr.op in ("+", "-", "*", "/"):
            a, b = self._number(expr.left, env), self._number(expr.right, env)
            if expr.op in "+-":
                if not (fits(a, b.dim) and fits(b, a.dim)):
                    self.error(expr.op_span, f"cannot {'add' if expr.op == '+' else 'subtract'}"
                               f" {dim_words(b.dim)} and {dim_words(a.dim)}")
                    raise _Abort
                dim = a.dim if not a.zero else b.dim
                v = a.value + b.value if expr.op == "+" else a.value - b.value
                return Quantity(v, dim, a.bare and b.bare)
            dim = None if a.dim is None or b.dim is None else (
                a.dim * b.dim if expr.op == "*" else a.dim / b.dim)
            if expr.op == "*":
                return Quantity(a.value * b.value, dim, a.bare and b.bare)
            if b.value == 0:
                self.error(expr.span, "division by zero")
                raise _Abort
            return Quantity(a.value / b.value, dim, a.bare and b.bare)
        self.error(expr.span, f"expected a fixed value such as `1 m` or `10 s`, "
                   f"found `{_short(expr)}`")
        raise _Abort

    def _number(self, expr: st.Expr, env: Env) -> Quantity:
        v = self.value(expr, env)
        if isinstance(v, Symbol):
            self._unknown(v.name, expr.span, "name", list(env))  # only parameters fit here
            raise _Abort
        return v

    def timer(self, expr: st.Expr, env: Env) -> float:
        """Return a timer in seconds: `inf`, a time, or a plain number (seconds)."""
        if isinstance(expr, st.Never):
            self.error(expr.span, "expected a timer such as `10 s` or `inf`, found `never`",
                       hint="`never` is the interrupt that never fires; the timer that never "
                            "expires is `inf`")
            raise _Abort
        if isinstance(expr, (st.Binary, st.Unary)) and expr.op in (
                "and", "or", "xor", "not", "<", "<=", ">", ">=", "==", "!="):
            self.error(expr.span, "expected a timer such as `10 s` or `inf`, found a condition",
                       hint="an element is (…, interrupt, timer): the condition goes second")
            raise _Abort
        q = self._number(expr, env)
        if not (q.dim is None or q.dim is TIME or q.dim == TIME or q.dim == NONE or q.zero):
            self.error(expr.span, f"expected a timer such as `10 s` or `inf`, found "
                       f"{dim_words(q.dim)} (`{_short(expr)}`)")
            raise _Abort
        if math.isnan(q.value) and not self._partial:
            self.error(expr.span, f"the timer `{_short(expr)}` is not a number (NaN)",
                       hint="`inf * 0` and `inf - inf` have no value; write `inf` or a time")
            raise _Abort
        if q.value < 0:
            self.error(expr.span, "a timer cannot be negative")
            raise _Abort
        return q.value

    # ------------------------------------------------------------------ arguments

    def bind(self, callee: str, slots: Sequence[_Slot], args: Sequence[st.Argument],
             env: Env, span: Span) -> dict[str, Value]:
        """Bind call arguments to parameters; checks arity, keywords, symbols, dimensions."""
        bound: dict[str, Value] = {}
        given: dict[str, st.Argument] = {}
        ok = True
        positional_done = False
        for i, a in enumerate(args):
            if a.name is None:
                if positional_done:
                    self.error(a.span, "a positional argument cannot follow a keyword argument")
                    ok = False
                    continue
                if i >= len(slots):
                    names = [s.name for s in slots]
                    takes = (f"takes {len(slots)} argument{'s' * (len(slots) != 1)}"
                             + (f" ({', '.join(names)})" if names else ""))
                    self.error(a.span, f"too many arguments: `{callee}` {takes}, "
                               f"found {len(args)}")
                    ok = False
                    break
                slot = slots[i]
            else:
                positional_done = True
                found = next((s for s in slots if s.name == a.name), None)
                if found is None:
                    names = [s.name for s in slots]
                    close = difflib.get_close_matches(a.name, names, n=1)
                    hint = (f"did you mean `{close[0]}`?" if close else
                            f"`{callee}` takes {', '.join(f'`{n}`' for n in names)}" if names
                            else f"`{callee}` takes no arguments")
                    self.error(a.span, f"`{callee}` has no parameter `{a.name}`", hint=hint)
                    ok = False
                    continue
                slot = found
            if slot.name in given:
                self.error(a.span, f"`{slot.name}` of `{callee}` is given twice",
                           notes=(Diagnostic(given[slot.name].span, "first given here",
                                             Severity.NOTE),))
                ok = False
                continue
            given[slot.name] = a
            try:
                bound[slot.name] = self._argument(callee, slot, a.value, env)
            except _Abort:
                ok = False
        if len(given) < len(slots):  # defaults, or what is missing
            missing = []
            for s in slots:
                if s.name not in bound and s.name not in given:
                    if s.default is REQUIRED:
                        missing.append(s)
                    else:
                        bound[s.name] = s.default
            for s in missing:
                self.error(span, f"`{callee}` needs `{s.name}`"
                           + ("" if s.symbol else f" ({dim_example(s.dim)})"),
                           hint=f"write it as `{_completed(callee, args, missing)}`")
                ok = False
        if not ok:
            raise _Abort
        return bound

    def _argument(self, callee: str, slot: _Slot, expr: st.Expr, env: Env) -> Value:
        if (isinstance(expr, st.Name) and expr.name in slot.choices
                and expr.name not in env):
            return Symbol(expr.name)  # a declared symbol wins over a definition's name
        if (slot.param is not None and slot.param.any_name and isinstance(expr, st.Name)
                and expr.name not in env):
            return Symbol(expr.name)  # a channel or robot: any name
        v = self.value(expr, env)
        if slot.choices:
            if not isinstance(v, Symbol) or v.name not in slot.choices:
                options = " or ".join(f"`{c}`" for c in slot.choices)
                got = v.name if isinstance(v, Symbol) else _short(expr)
                close = difflib.get_close_matches(got, list(slot.choices), n=1)
                self.error(expr.span, f"`{slot.name}` of `{callee}` is one of {options}, "
                           f"found `{got}`", hint=f"did you mean `{close[0]}`?" if close else None)
                raise _Abort
            return v
        if isinstance(v, Symbol):
            if slot.symbol:
                return v
            self._unknown(v.name, expr.span, "name", list(env))  # only parameters fit here
            raise _Abort
        if slot.symbol:
            what = (f"a {slot.param.any_name} name" if slot.param and slot.param.any_name
                    else "a symbol such as `right`")
            self.error(expr.span, f"`{slot.name}` of `{callee}` takes {what}, "
                       f"found {dim_words(v.dim)}")
            raise _Abort
        if not fits(v, slot.dim):
            assert slot.dim is not None
            if v.dim == NONE and unit_for(slot.dim):
                hint = f"add a unit: `{_short(expr)} {unit_for(slot.dim)}`"
            else:
                hint = None
            self.error(expr.span, f"`{slot.name}` of `{callee}` is {dim_example(slot.dim)}, "
                       f"found {dim_words(v.dim)} (`{_short(expr)}`)", hint=hint)
            raise _Abort
        p = slot.param
        if p is not None and not (self._partial and math.isnan(v.value)) \
                and not p.accepts(v.value):
            unit = f" ({p.dim.symbol()})" if p.dim != NONE else ""
            self.error(expr.span, f"`{slot.name}` of `{callee}` must be {p.range_words()}{unit}, "
                       f"found {show_value(v) if not math.isnan(v.value) else 'NaN'}"
                       + (f" (`{_short(expr)}`)" if not isinstance(expr, st.Number) else ""),
                       hint=p.doc or None)
            raise _Abort
        return v

    def _slots_of_spec(self, spec: LawSpec | SensorSpec) -> list[_Slot]:
        slots = self._spec_slots.get(id(spec))  # specs live in the registry: ids stay unique
        if slots is None:
            slots = self._spec_slots[id(spec)] = self._make_slots(spec)
        return slots

    @staticmethod
    def _make_slots(spec: LawSpec | SensorSpec) -> list[_Slot]:
        return [_Slot(p.name, None if p.is_symbol else p.dim,
                      REQUIRED if p.default is REQUIRED else (
                          Symbol(p.default) if isinstance(p.default, str) else
                          Quantity(float(p.default), p.dim)),
                      tuple(p.choices), p.is_symbol, p) for p in spec.params]

    def _note_names(self, spec: LawSpec | SensorSpec, bound: Mapping[str, Value],
                    span: Span) -> None:
        """Record the channels and robots a call names (see :class:`MessageUse`)."""
        for p in spec.params:
            if not p.any_name:
                continue
            v = bound.get(p.name)
            if isinstance(v, Symbol):
                kind = "read" if p.any_name == "channel" else "robot"
                self._use(MessageUse(kind, v.name, None, span, spec.name))

    def _note_message_dim(self, a: cond.Typed, b: cond.Typed) -> None:
        """Record the dimension a `message(channel)` is used with (known from the other side)."""
        for m, other in ((a, b), (b, a)):
            hit = self._messages.get(id(m.node)) if m.node is not None else None
            if hit is not None and other.dim is not None:
                self._use(MessageUse("read", hit[1], other.dim, hit[2], "message"))

    def slots_of(self, d: st.Definition) -> list[_Slot]:
        """Return the parameters of a definition; a parameter's dimension is its default's."""
        key = id(d)  # definitions live in the namespace: ids stay unique
        known = self._def_slots.get(key)
        if known is not None:
            return known
        slots: list[_Slot] = []
        seen: dict[str, st.Param] = {}
        for p in d.param_list:
            if p.name in seen:
                self.error(p.span, f"parameter `{p.name}` of `{d.name}` is declared twice")
                continue
            seen[p.name] = p
            if p.default is None:
                slots.append(_Slot(p.name, None, REQUIRED))
                continue
            try:
                v = self.value(p.default, _EMPTY)
            except _Abort:
                slots.append(_Slot(p.name, None, REQUIRED))
                continue
            if isinstance(v, Symbol):
                slots.append(_Slot(p.name, None, v, symbol=True))
            else:
                slots.append(_Slot(p.name, None if v.bare else v.dim, v))
        self._def_slots[key] = slots
        return slots

    @staticmethod
    def _plain(values: Mapping[str, Value]) -> dict[str, float | str]:
        return {k: (v.name if isinstance(v, Symbol) else v.value) for k, v in values.items()}

    # ------------------------------------------------------------------ interrupts

    def condition(self, expr: st.Expr, env: Env) -> cond.Typed:
        """Type and compile an interrupt expression (or a part of one)."""
        if self._depth >= MAX_NESTING:
            self._enter(expr.span)  # reports, raises
        self._depth += 1
        try:
            kind = type(expr)  # the common nodes first (the syntax tree has no subclasses)
            if kind is st.Binary:
                return self._binary_condition(expr, env)  # type: ignore[arg-type]
            if kind is st.Name or kind is st.Call:
                return self._reading(expr, env)  # type: ignore[arg-type]
            return self._condition(expr, env)
        finally:
            self._depth -= 1

    def _condition(self, expr: st.Expr, env: Env) -> cond.Typed:
        if isinstance(expr, st.Number):
            return cond.constant(None if (not expr.unit and expr.value == 0) else expr.dim,
                                 expr.value)
        if isinstance(expr, st.Never):
            return cond.constant(BOOL, False)
        if isinstance(expr, st.Inf):
            self.error(expr.span, "`inf` is the timer that never expires; the interrupt that "
                       "never fires is `never`")
            raise _Abort
        if isinstance(expr, st.Group):
            if len(expr.items) == 1 and not expr.repeat:
                return self.condition(expr.items[0], env)
            self.error(expr.span, "expected an interrupt such as `stalled` or "
                       "`range(0 deg) < 1 m`, found a tuple")
            raise _Abort
        if isinstance(expr, st.Vector):
            self.error(expr.span, "`[...]` is only the per-channel scale of a scaled atom")
            raise _Abort
        if isinstance(expr, (st.Name, st.Call)):
            return self._reading(expr, env)
        if isinstance(expr, st.Unary):
            a = self.condition(expr.operand, env)
            if expr.op == "not":
                if not a.is_bool:
                    self.error(expr.operand.span, f"`not` needs a condition, found "
                               f"{dim_words(a.dim)}")
                    raise _Abort
            elif a.is_bool:
                self.error(expr.span, f"`{expr.op}` needs a number, found a condition")
                raise _Abort
            return cond.negate(expr.op, a)
        assert isinstance(expr, st.Binary)
        return self._binary_condition(expr, env)

    def _binary_condition(self, expr: st.Binary, env: Env) -> cond.Typed:
        a = self.condition(expr.left, env)
        b = self.condition(expr.right, env)
        op = expr.op
        if op in ("and", "or", "xor"):
            if a.kind is BOOL and b.kind is BOOL:
                return cond.logic(op, a, b)
            for side, t in ((expr.left, a), (expr.right, b)):
                if not t.is_bool:
                    self.error(side.span, f"`{op}` joins conditions, but this is "
                               f"{dim_words(t.dim)}",
                               hint="compare it with something: `range(0 deg) < 1 m`")
                    raise _Abort
            return cond.logic(op, a, b)
        if a.kind is BOOL or b.kind is BOOL:
            side = expr.left if a.kind is BOOL else expr.right
            self.error(side.span, f"`{op}` needs numbers, found a condition")
            raise _Abort
        if op in ("<", "<=", ">", ">=", "==", "!="):
            if not _same_dim(a, b):
                self.error(expr.op_span, f"cannot compare {dim_words(a.dim)} with "
                           f"{dim_words(b.dim)}", hint=_unit_hint(expr, a, b))
                raise _Abort
            if self._messages:
                self._note_message_dim(a, b)
            return cond.compare(op, a, b)
        if op in ("+", "-"):
            if not _same_dim(a, b):
                self.error(expr.op_span, f"cannot {'add' if op == '+' else 'subtract'} "
                           f"{dim_words(b.dim)} and {dim_words(a.dim)}",
                           hint=_unit_hint(expr, a, b))
                raise _Abort
            if self._messages:
                self._note_message_dim(a, b)
            return cond.arith(op, a, b, a.dim if a.dim is not None else b.dim)
        kind = None if a.dim is None or b.dim is None else (
            a.dim * b.dim if op == "*" else a.dim / b.dim)
        return cond.arith(op, a, b, kind)

    def _reading(self, expr: st.Name | st.Call, env: Env) -> cond.Typed:
        name = expr.name
        args = expr.args if isinstance(expr, st.Call) else ()
        if isinstance(expr, st.Name) and name in env:
            v = env[name]
            if isinstance(v, Symbol):
                self.error(expr.span, f"`{name}` is the symbol `{v.name}` here; an interrupt "
                           "needs a condition or a number")
                raise _Abort
            return cond.constant(None if v.zero else v.dim, v.value)
        target = self._lookup(name)
        if isinstance(target, SensorSpec):
            bound = self.bind(name, self._slots_of_spec(target), args, env, expr.span)
            self._note_names(target, bound, expr.span)
            t = cond.sensor_reading(target, MappingProxyType(self._plain(bound)))
            if target.result is None and "channel" in bound:
                channel = bound["channel"]
                if isinstance(channel, Symbol):
                    self._messages[id(t.node)] = (t.node, channel.name, expr.span)
            return t
        if isinstance(target, st.Definition) and target.kind is st.DefKind.INTERRUPT:
            if name in self.broken:
                raise _Abort
            slots = self.slots_of(target)
            bound = self.bind(name, slots, args, env, expr.span)
            return self._interrupt_body(target, bound, expr.span if args else None)
        if target is None:
            # what a condition can read: numeric parameters, interrupts, sensor functions
            pool = [*(k for k, v in env.items() if not isinstance(v, Symbol)),
                    *(n for n, d in self.ns.definitions.items()
                      if d.kind is st.DefKind.INTERRUPT),
                    *self.ns.registry.sensors, "never"]
            self._unknown(name, getattr(expr, "name_span", expr.span), "name", pool)
            raise _Abort
        self.error(expr.span, f"expected an interrupt such as `stalled` or `range(0 deg) < 1 m`; "
                   f"`{name}` is {_kind_name(target)}",
                   hint=("to run elements one after another, put them in a string with its own "
                         "interrupt and timer: `((a, b), never, inf)`")
                   if isinstance(target, st.Definition) else None)
        raise _Abort

    def _interrupt_body(self, d: st.Definition, bound: Mapping[str, Value],
                        call: Span | None) -> cond.Typed:
        key = ("interrupt", d.name, _freeze(bound))
        if key in self._cache:
            self._replay(key)
            return self._cache[key]
        if call is not None:
            self._notes.append(Diagnostic(call, f"in this use of `{d.name}`", Severity.NOTE))
        self._use_stack.append([])
        try:
            t = self.condition(d.body, MappingProxyType(dict(bound)))
        finally:
            uses = self._use_stack.pop()
            if uses:  # most instances name no channel or robot: nothing to keep
                self._key_uses[key] = uses
                self._replay(key)
            if call is not None:
                self._notes.pop()
        if not t.is_bool:
            self.error(d.body.span, f"an interrupt is a condition such as `range(0 deg) < 1 m`; "
                       f"`{d.name}` is {dim_words(t.dim)}")
            raise _Abort
        self._cache[key] = t
        return t

    def interrupt(self, expr: st.Expr, env: Env) -> Interrupt:
        """Return the compiled interrupt of an element."""
        t = self.condition(expr, env)
        if not t.is_bool:
            self.error(expr.span, "expected an interrupt such as `stalled` or "
                       f"`range(0 deg) < 1 m`, found {dim_words(t.dim)}",
                       hint="compare it with something, as in `range(0 deg) < 1 m`")
            raise _Abort
        if t.is_const and t.const and not any(
                isinstance(v, Quantity) and math.isnan(v.value) for v in env.values()):
            self.warn(expr.span, f"the interrupt `{_short(expr)}` is always true: the element "
                      "ends as soon as it starts", hint="did you mean `never`?")
        if isinstance(expr, st.Never):
            return cond.to_interrupt(t, "never")

        def source() -> str:  # the text `show` and traces print, made when first read
            shown = {k: show_value(v) for k, v in env.items()
                     if not (isinstance(v, Quantity) and math.isnan(v.value))}
            return format_expr(expr, shown)

        return cond.to_interrupt(t, source)

    # ------------------------------------------------------------------ elements

    def element(self, expr: st.Expr, env: Env) -> Element:
        """Compile an expression standing where an element is expected."""
        if self._depth >= MAX_NESTING:
            self._enter(expr.span)  # reports, raises
        self._depth += 1
        try:
            return self._element(expr, env)
        finally:
            self._depth -= 1

    def _element(self, expr: st.Expr, env: Env) -> Element:
        if isinstance(expr, (st.Name, st.Call)):
            return self._named_element(expr, env)
        if isinstance(expr, st.Group):
            if expr.repeat:
                self.error(expr.span, "`...` repeats the string of a behavior or plan; here it "
                           "stands for an element",
                           hint="write the repeated string with its interrupt and timer: "
                                "`((a, b)..., x > 10 m, inf)`")
                raise _Abort
            if len(expr.items) == 1:
                return self.element(expr.items[0], env)
            return self._triple(expr, env)
        self.error(expr.span, "expected an element: an atom such as `(go(0.3 m/s), stalled, "
                   f"10 s)`, a named atom, behavior or plan, found `{_short(expr)}`")
        raise _Abort

    def _named_element(self, expr: st.Name | st.Call, env: Env) -> Element:
        name = expr.name
        if isinstance(expr, st.Name) and name in env:
            self.error(expr.span, f"`{name}` is a parameter, not an element")
            raise _Abort
        target = self._lookup(name)
        if isinstance(target, st.Definition) and target.kind is not st.DefKind.INTERRUPT:
            if name in self.broken:
                raise _Abort
            args = expr.args if isinstance(expr, st.Call) else ()
            bound = self.bind(name, self.slots_of(target), args, env, expr.span)
            return self.instance(target, bound, expr.span if args else None)
        if isinstance(target, LawSpec):
            self.error(expr.span, f"`{name}` is a control law; an atom needs an interrupt and a "
                       "timer too", hint=f"write `({_short(expr)}, never, 10 s)`")
            raise _Abort
        if target is not None:
            self.error(expr.span, f"expected an element (an atom, behavior or plan); `{name}` is "
                       f"{_kind_name(target)}")
            raise _Abort
        if name in self.unparsed:
            raise _Abort  # its statement has a syntax error, reported already
        pool = [n for n, d in self.ns.definitions.items() if d.kind is not st.DefKind.INTERRUPT]
        if expr is self._atom_head:  # `(g(1 m/s), never, 5 s)`: a control law fits here too
            pool += list(self.ns.registry.laws)
        found = self._closest(name, pool)
        close = [found] if found else []
        span = getattr(expr, "name_span", expr.span)
        self.error(span, f"unknown name `{name}`: not a control law, atom, behavior or plan",
                   hint=f"did you mean `{close[0]}`?" if close else None)
        raise _Abort

    def _triple(self, expr: st.Group, env: Env) -> Element:
        head = expr.items[0]
        n = len(expr.items)
        kind = self._head_kind(head, env)
        if n > 3 and kind == "atom" and all(_is_send(i) for i in expr.items[3:]):
            return self._atom(expr, env)
        if n != 3:
            what = {"atom": "an atom is (control law, interrupt, timer)",
                    "scaled": "a scaled atom is (alpha, beta, atom)",
                    "string": "an element is ((elements), interrupt, timer)"}[kind]
            if n == 2 and kind != "scaled":
                self.error(_after(expr), "expected a timer such as `10 s` or `inf` after the "
                           f"interrupt: {what}", hint="add `, inf` to run until the interrupt "
                                                      "fires")
            elif n == 2:
                self.error(expr.span, f"{what}; this has 2 parts")
            else:
                self.error(expr.items[3].span, f"{what}; this has {n} parts",
                           hint="to run elements one after another, wrap them in a string: "
                                "`((a, b, c, d), never, inf)`" if kind == "string" else None)
            raise _Abort
        if kind == "atom":
            return self._atom(expr, env)
        if kind == "scaled":
            return self._scaled(expr, env)
        return self.string(expr, env, "group", StringKind.GROUP)

    def _head_kind(self, head: st.Expr, env: Env) -> str:
        while isinstance(head, st.Group) and len(head.items) == 1 and not head.repeat:
            inner = head.items[0]
            if not isinstance(inner, (st.Name, st.Call)):
                head = inner
                continue
            return "string"  # `((cruise), never, 10 s)`: a string of one element
        if isinstance(head, st.Group):
            return "string"
        if isinstance(head, (st.Name, st.Call)):
            if isinstance(head, st.Name) and head.name in env:
                return "scaled"
            if isinstance(self._lookup(head.name), LawSpec):
                return "atom"
            return "string"
        return "scaled"

    def _atom(self, expr: st.Group, env: Env) -> AtomNode:
        u, xi, timer = expr.items[:3]
        assert isinstance(u, (st.Name, st.Call))
        law = self._lookup(u.name)
        assert isinstance(law, LawSpec)
        failed = False
        try:
            args = self.bind(u.name, self._slots_of_spec(law), u.args if isinstance(u, st.Call)
                             else (), env, u.span)
            self._note_names(law, args, u.span)
        except _Abort:
            failed = True
        else:
            if self._scaling is not expr:  # a scaled atom is checked once scaled
                self._within_limits(law, args, u)
        sends: list[Send] = []
        for item in expr.items[3:]:
            assert isinstance(item, st.Call)
            try:
                sends.append(self._send(item, env))
            except _Abort:
                failed = True
        interrupt, t = self._ending(xi, timer, env, failed)
        return _new_atom(law.name, law, MappingProxyType(self._plain(args)), interrupt, t,
                         (1.0, 1.0), expr.span, tuple(sends))

    def _send(self, call: st.Call, env: Env) -> Send:
        """Check ``send(channel, value)`` or ``send(pose)``, an atom's fourth part on."""
        args = call.args
        if not args or args[0].name is not None or not isinstance(args[0].value, st.Name) \
                or any(a.name is not None for a in args):
            self.error(call.span, "expected `send(channel, value)` or `send(pose)`: a channel "
                       "name, then the number to send", hint="for example `send(gap, 1 m)`")
            raise _Abort
        channel = args[0].value.name
        held = env.get(channel)
        if isinstance(held, Symbol):
            channel = held.name  # a parameter holding a channel name
        if len(args) == 1:
            if channel != POSE_CHANNEL:
                self.error(call.span, f"`send({channel})` needs a value to send",
                           hint=f"write `send({channel}, 1)`, or `send(pose)` to send the "
                                "robot's pose")
                raise _Abort
            self._use(MessageUse("send", channel, "pose", call.span))
            return Send(channel, None, None, "send(pose)", call.span)
        if len(args) > 2:
            self.error(args[2].span, f"`send` takes a channel and one value, found {len(args)} "
                       "arguments")
            raise _Abort
        if channel == POSE_CHANNEL:
            self.error(args[1].span, "the channel `pose` carries the robot's pose: write "
                       "`send(pose)`", hint="send numbers on a channel of another name")
            raise _Abort
        t = self.condition(args[1].value, env)
        if t.is_bool:
            self.error(args[1].span, f"`send` sends a number, found a condition "
                       f"(`{_short(args[1].value)}`)", hint="send 1 and test "
                       f"`received({channel})`, or send a number such as `range(0 deg)`")
            raise _Abort
        self._use(MessageUse("send", channel, t.dim, call.span))
        return Send(channel, t.call(), t.dim, f"send({channel}, {format_expr(args[1].value)})",
                    call.span)

    def _within_limits(self, law: LawSpec, args: Mapping[str, Value], call: st.Expr,
                       scale: tuple[float, float] = (1.0, 1.0),
                       span: Span | None = None) -> None:
        """Warn about a constant speed or turn rate the robot cannot reach.

        ``call`` is the law's call (each argument is pointed at where it is written; a
        default, at the call); ``scale`` the scaled atom's (alpha_v, alpha_omega) and
        ``span`` its place, when the values are scaled.
        """
        if self.robot is None:
            return
        given = call.args if isinstance(call, st.Call) else ()
        for i, p in enumerate(law.params):
            v = args.get(p.name)
            if not p.commanded or not isinstance(v, Quantity) or math.isnan(v.value):
                continue
            factor = scale[1] if p.dim == TURN_RATE else scale[0]
            why = excess(self.robot, p.dim, v.value * factor)
            if why is None:
                continue
            arg = next((a for j, a in enumerate(given)
                        if a.name == p.name or (a.name is None and j == i)), None)
            where = span or (arg.span if arg is not None else call.span)
            value = show_value(Quantity(v.value * factor, p.dim))
            scaled = f" (scaled by {factor:g})" if span is not None else ""
            self.warn(where, f"`{p.name}` of `{law.name}` is {value}{scaled}, more than the "
                      f"robot can do: {why}", hint="the robot clamps the command to its "
                      "limit, so the plan does not move as written; use a value within the "
                      "limit, or name the robot meant (--robot, --world)", in_use=True)

    def _ending(self, xi: st.Expr, timer: st.Expr, env: Env,
                failed: bool) -> tuple[Interrupt, float]:
        """Check how an element ends: its interrupt and its timer, both reported.

        ``failed`` says an earlier part of the element had an error. Raises _Abort when it
        or either of these did, once all of them have been checked.
        """
        interrupt: Interrupt | None = None
        t: float | None = None
        try:
            interrupt = self.interrupt(xi, env)
        except _Abort:
            failed = True
        try:
            t = self.timer(timer, env)
        except _Abort:
            failed = True
        if failed or interrupt is None or t is None:
            raise _Abort
        return interrupt, t

    def _scaled(self, expr: st.Group, env: Env) -> AtomNode:
        alpha_e, beta_e, sigma_e = expr.items
        failed = False
        alpha = (1.0, 1.0)
        try:
            if isinstance(alpha_e, st.Vector):
                if len(alpha_e.items) != 2:
                    self.error(alpha_e.span, "a per-channel scale is `[alpha_v, alpha_omega]`: two "
                               f"factors, found {len(alpha_e.items)}")
                    raise _Abort
                alpha = (self._factor(alpha_e.items[0], env, "alpha_v"),
                         self._factor(alpha_e.items[1], env, "alpha_omega"))
            else:
                a = self._factor(alpha_e, env, "alpha")
                alpha = (a, a)
        except _Abort:
            failed = True
        beta = 1.0
        try:
            beta = self._factor(beta_e, env, "beta")
            if not beta > 0 and not (self._partial and math.isnan(beta)):
                self.error(beta_e.span, "beta scales the timer and must be positive")
                failed = True
        except _Abort:
            failed = True
        outer, self._scaling = self._scaling, sigma_e
        try:
            sigma = self.element(sigma_e, env)
        except _Abort:
            raise _Abort from None
        finally:
            self._scaling = outer
        if not isinstance(sigma, AtomNode):
            self.error(sigma_e.span, f"only atoms can be scaled; `{_short(sigma_e)}` is a string "
                       "of elements", hint="scale each of its atoms instead")
            raise _Abort
        if failed:
            raise _Abort
        scale = (sigma.scale[0] * alpha[0], sigma.scale[1] * alpha[1])
        if isinstance(sigma.law, LawSpec):
            values = {k: Quantity(float(v), None) for k, v in sigma.args.items()
                      if isinstance(v, (int, float))}
            self._within_limits(sigma.law, values, sigma_e, scale, expr.span)
        return _replaced(sigma, timer=sigma.timer * beta, scale=scale, span=expr.span)

    def _factor(self, expr: st.Expr, env: Env, what: str) -> float:
        q = self._number(expr, env)
        if not (q.dim is None or q.dim == NONE or q.zero):
            self.error(expr.span, f"{what} is a plain number such as `0.5`, found "
                       f"{dim_words(q.dim)}")
            raise _Abort
        if not math.isfinite(q.value) and not (self._partial and math.isnan(q.value)):
            self.error(expr.span, f"{what} must be a finite number, found `{_short(expr)}`"
                       + (" (NaN)" if math.isnan(q.value) else ""))
            raise _Abort
        return q.value

    def string(self, expr: st.Group, env: Env, label: str, kind: StringKind) -> StringNode:
        """Return a string element ((e1, ..., en), xi, T); the first item may be one element."""
        head, xi, timer = expr.items
        repeat = False
        items: tuple[st.Expr, ...]
        if isinstance(head, st.Group) and len(head.items) > 1 and \
                self._head_kind(head.items[0], env) in ("atom", "scaled"):
            # `((go(1 m/s), never, 5 s)..., x > 1 m, inf)`: a law or a number cannot be an
            # element, so the tuple is one atom, not a string of three elements.
            items, repeat = (dataclasses.replace(head, repeat=False),), head.repeat
        elif isinstance(head, st.Group):
            items, repeat = head.items, head.repeat
        else:
            items = (head,)
        elements: list[Element] = []
        failed = False
        outer, self._atom_head = self._atom_head, (None if isinstance(head, st.Group) else head)
        try:
            for item in items:
                try:
                    elements.append(self.element(item, env))
                except _Abort:
                    failed = True
        finally:
            self._atom_head = outer
        interrupt, t = self._ending(xi, timer, env, failed)
        for i in range(len(elements) - 1):
            if never_ends(elements[i], self._never_memo):
                self.warn(items[i + 1].span,
                          f"{_called(items[i + 1])} is never reached: "
                          f"{_called(items[i])} before it never ends (its interrupt is `never` "
                          "and its timer `inf`)",
                          hint="give the element before it an interrupt or a finite timer")
                break
        depth = 1 + max(self._depths.get(id(e), 1) for e in elements)
        if depth > MAX_NESTING:
            if not self._too_deep:  # once: every enclosing definition would repeat it
                self._too_deep = True
                self.error(expr.span, f"elements nest {depth} levels deep here; mdle allows at "
                           f"most {MAX_NESTING}", hint="flatten the plan: fewer levels of "
                                                       "strings inside strings")
            raise _Abort
        node = _new_string(label, tuple(elements), interrupt, t, repeat, kind, expr.span)
        self._depths[id(node)] = depth
        self._keep.append(node)  # ids stay unique while the checker lives
        return node

    def instance(self, d: st.Definition, bound: Mapping[str, Value],
                 call: Span | None = None) -> Element:
        """Return the element a definition makes with these parameter values (cached)."""
        key = ("element", d.name, _freeze(bound))
        cached = self._cache.get(key, _MISSING)
        if cached is not _MISSING:
            if cached is None:  # failed before; its errors are already reported
                raise _Abort
            self._replay(key)
            return cached
        env = MappingProxyType(dict(bound))
        if call is not None:
            self._notes.append(Diagnostic(call, f"in this use of `{d.name}`", Severity.NOTE))
        self._use_stack.append([])
        try:
            if self._depth >= MAX_NESTING:
                self._enter(d.span)  # reports, raises
            self._depth += 1
            try:
                result = self._definition_body(d, env)
            finally:
                self._depth -= 1
                uses = self._use_stack.pop()
                if uses:
                    self._key_uses[key] = uses
                    self._replay(key)
        except _Abort:
            self._cache[key] = None
            raise
        finally:
            if call is not None:
                self._notes.pop()
        self._cache[key] = result
        return result

    def _definition_body(self, d: st.Definition, env: Env) -> Element:
        body = d.body
        while isinstance(body, st.Group) and len(body.items) == 1 and not body.repeat:
            body = body.items[0]
        if d.kind is st.DefKind.ATOM:
            e = self.element(body, env)
            if not isinstance(e, AtomNode):
                self.error(d.body.span, f"`{d.name}` is declared an atom but is a string of "
                           "elements", hint=f"declare it with `behavior {d.name} = ...`")
                raise _Abort
            return _replaced(e, label=d.name, span=d.span)
        kind = StringKind.PLAN if d.kind is st.DefKind.PLAN else StringKind.BEHAVIOR
        if isinstance(body, st.Group) and len(body.items) == 3 and \
                self._head_kind(body.items[0], env) == "string":
            return self.string(body, env, d.name, kind)
        e = self.element(body, env)  # reports what is wrong with the body, if anything
        if isinstance(e, StringNode):
            node = _replaced(e, label=d.name, kind=kind, span=d.span)
            self._depths[id(node)] = self._depths.get(id(e), 1)
            self._keep.append(node)
            return node
        self.error(d.body.span, f"`{d.name}` is declared a {d.kind.value} but is an atom: "
                   f"a {d.kind.value} is ((elements), interrupt, timer)",
                   hint=f"declare it with `atom {d.name} = ...`, or write "
                        f"`(({_short(d.body)}), never, inf)`")
        raise _Abort

    # ------------------------------------------------------------------ whole programs

    def check_definition(self, d: st.Definition) -> Element | None:
        """Check a definition on its own; returns its element if it can run as it stands."""
        if d.name in self.broken:
            return None
        slots = self.slots_of(d)
        if slots:
            runnable = all(s.default is not REQUIRED for s in slots)
            bound = {s.name: (_UNKNOWN if s.default is REQUIRED else s.default) for s in slots}
        else:
            runnable, bound = True, {}
        self._partial = not runnable
        try:
            if d.kind is st.DefKind.INTERRUPT:
                self._interrupt_body(d, bound, None)
                return None
            e = self.instance(d, bound)
        except _Abort:
            return None
        finally:
            self._partial = False
        if runnable:
            key = ("element", d.name, _freeze(bound))
            self.element_uses[d.name] = tuple(dict.fromkeys(self._key_uses.get(key, ())))
        return e if runnable else None


_E = TypeVar("_E", AtomNode, StringNode)
#: Constructors of the program's nodes taking every field in order (see builder).
_new_atom = builder(AtomNode)
_new_string = builder(StringNode)
_new_quantity = builder(Quantity)


def _replaced(node: _E, **changes: Any) -> _E:
    """Return ``dataclasses.replace(node, **changes)`` without calling ``__init__``.

    The program's nodes are plain frozen dataclasses (no ``__post_init__``, no slots), so
    a copy of the fields with some changed is the same node; ``__init__`` would set each
    field through ``object.__setattr__``, and a large plan makes thousands of them.
    """
    new = object.__new__(type(node))
    fields = new.__dict__
    fields.update(node.__dict__)
    fields.update(changes)
    return new


def _freeze(bound: Mapping[str, Value]) -> tuple[tuple[str, Any], ...]:
    if not bound:
        return ()
    if len(bound) == 1:
        ((k, v),) = bound.items()
        return ((k, (v.name,) if isinstance(v, Symbol) else (v.value, v.dim, v.bare)),)
    return tuple(sorted((k, (v.name,) if isinstance(v, Symbol) else (v.value, v.dim, v.bare))
                        for k, v in bound.items()))


def _is_send(expr: st.Expr) -> bool:
    return isinstance(expr, st.Call) and expr.name == "send"


def _same_dim(a: cond.Typed, b: cond.Typed) -> bool:
    x, y = a.dim, b.dim
    return x is None or y is None or x is y or same_kind(x, y)


def _unit_hint(expr: st.Binary, a: cond.Typed, b: cond.Typed) -> str | None:
    for side, other in ((expr.right, a), (expr.left, b)):
        if isinstance(side, st.Number) and not side.unit and other.dim is not None:
            unit = unit_for(other.dim)
            if unit:
                return f"add a unit: `{side.text} {unit}`"
    return None


def _short(expr: st.Expr) -> str:
    text = format_expr(expr)
    return text if len(text) <= 60 else text[:57] + "..."


def _completed(callee: str, args: Sequence[st.Argument], missing: Sequence[_Slot]) -> str:
    """Return the call as written with the missing parameters added.

    ``arc(0.3 m/s)`` missing ``omega`` gives ``arc(0.3 m/s, omega = ...)``.
    """
    parts = [(f"{a.name} = " if a.name else "") + format_expr(a.value) for a in args]
    parts += [f"{s.name} = ..." for s in missing]
    return f"{callee}({', '.join(parts)})"


def _called(expr: st.Expr) -> str:
    """How a message names an element: its text if short, else where it starts."""
    text = format_expr(expr)
    if len(text) <= 40:
        return f"`{text}`"
    return f"the element at line {expr.span.line}, column {expr.span.column}"


def _after(expr: st.Group) -> Span:
    s = expr.span
    return Span(s.file, s.end_line, max(1, s.end_column - 1), s.end_line, s.end_column)


def check_program(modules: Sequence[st.Module], registry: Registry, *,
                  sources: Mapping[str, str] | None = None, main: st.Module | None = None,
                  replace: bool = False, unparsed: frozenset[str] = frozenset(),
                  robot: KnownRobot | None = None) -> Program:
    """Check the modules of a program (the main file last) and build its :class:`Program`.

    Parameters
    ----------
    modules : sequence of Module
        Every file of the program, imports first, each once.
    registry : Registry
        The control laws and sensor functions names resolve to.
    sources : mapping, optional
        File texts by name (kept in the program and the error, for messages).
    main : Module, optional
        The file whose ``run`` names the entry (default: the last module).
    replace : bool
        Later definitions replace earlier ones of the same name (the REPL).
    unparsed : frozenset of str
        Names defined by statements with syntax errors (left out of ``modules``): using
        one is not reported again.
    robot : KnownRobot, optional
        The robot the plan is meant for: a constant speed or turn rate beyond its limits
        is a warning. None: no comparison.

    Raises
    ------
    CheckError
        With every error found (warnings are in ``Program.warnings``).
    """
    srcs = dict(sources or {})
    checker, errors, uses = _checker(modules, registry, replace, robot)
    checker.unparsed = unparsed
    main = main if main is not None else (modules[-1] if modules else None)
    elements: dict[str, Element] = {}
    for d in _dependency_order(checker.ns, checker.broken, uses):
        try:
            e = checker.check_definition(d)
        except RecursionError:  # a last guard: the nesting limits should prevent this
            checker.error(d.span, f"`{d.name}` nests too deeply to check",
                          hint="flatten it: fewer levels of elements or interrupts inside "
                               "each other")
            checker.broken.add(d.name)
            continue
        if e is not None:
            elements[d.name] = e
    try:
        entry = _entry(checker, main, elements)
    except RecursionError:
        checker.error(None, "the program nests too deeply to check")
        entry = None
    errors.extend(checker.errors)
    if errors:
        raise CheckError(_ordered(errors), srcs)
    return Program(MappingProxyType(elements), entry, MappingProxyType(srcs),
                   tuple(_ordered(checker.warnings)), tuple(dict.fromkeys(checker.uses)),
                   MappingProxyType({n: u for n, u in checker.element_uses.items()
                                     if n in elements}))


def _dependency_order(ns: Namespace, broken: set[str],
                      uses: Mapping[str, list[st.Name | st.Call]]) -> list[st.Definition]:
    """Order definitions so that what each uses comes first.

    A long chain of definitions is then checked one link at a time (each use finds its
    element already built).
    """
    order: list[st.Definition] = []
    done: set[str] = set()
    for root in ns.definitions:
        if root in done:
            continue
        stack = [(root, False)]
        while stack:
            name, expanded = stack.pop()
            if expanded:
                order.append(ns.definitions[name])
                continue
            if name in done:
                continue
            done.add(name)
            stack.append((name, True))
            if name not in broken:
                stack.extend((r.name, False) for r in uses[name] if r.name not in done)
    return order


def _checker(modules: Sequence[st.Module], registry: Registry, replace: bool,
             robot: KnownRobot | None = None
             ) -> tuple[Checker, list[Diagnostic], dict[str, list[st.Name | st.Call]]]:
    defs = [d for m in modules for d in m.definitions]
    ns, errors = build_namespace(defs, registry, replace=replace)
    uses = uses_of(ns)
    broken, cycle_errors = find_cycles(ns, uses)
    checker = Checker(ns, robot)
    checker.broken = broken
    return checker, errors + cycle_errors, uses


def _entry(checker: Checker, main: st.Module | None, elements: Mapping[str, Element]) -> str | None:
    runs = [s for s in main.statements if isinstance(s, st.Run)] if main else []
    if len(runs) > 1:
        checker.error(runs[1].span, f"`run` is given twice: {runs[0].span} and {runs[1].span}",
                      notes=(Diagnostic(runs[0].span, "first `run` here", Severity.NOTE),))
    if not runs:
        return "main" if "main" in elements else None
    run = runs[-1]
    target = checker.ns.lookup(run.name)
    if isinstance(target, st.Definition) and target.kind is not st.DefKind.INTERRUPT:
        if run.name in elements:
            return run.name
        missing = [s.name for s in checker.slots_of(target) if s.default is REQUIRED]
        if missing:
            checker.error(run.name_span, f"`{run.name}` cannot run as it stands: it needs "
                          + ", ".join(f"`{m}`" for m in missing),
                          hint="give those parameters defaults, or define a plan that calls "
                               f"`{run.name}(...)` with arguments")
        return None
    if target is None:
        pool = [n for n, d in checker.ns.definitions.items() if d.kind is not st.DefKind.INTERRUPT]
        checker._unknown(run.name, run.name_span, "element", pool)
    else:
        checker.error(run.name_span, f"`run` takes an atom, behavior or plan; `{run.name}` is "
                      f"{_kind_name(target)}")
    return None


def missing_entry(program: Program, file: str) -> Diagnostic | None:
    """Return the warning for a file ``mdle run`` cannot run: no ``run`` and no ``main``.

    None when the program has an entry. The warning points at the line after the file's
    last, where a ``run`` line would go.
    """
    if program.entry is not None:
        return None
    text = program.sources.get(file, "")
    end = text.rstrip().count("\n") + 2 if text.strip() else 1
    span = Span(file, end, 1, end, 2)
    names = sorted(program.elements)
    hint = (f"add `run {names[-1] if len(names) == 1 else 'NAME'}` (runnable here: "
            f"{', '.join(names)}); a file that other plans only import needs none" if names
            else "nothing here runs as it stands: define an atom, behavior or plan whose "
                 "parameters all have defaults (or that calls others with arguments), and "
                 "`run` it")
    return Diagnostic(span, "nothing to run: the file has no `run NAME` line and no plan "
                      "named `main`, so `mdle run` cannot run it", Severity.WARNING, hint)


def _ordered(diags: list[Diagnostic]) -> list[Diagnostic]:
    return sorted(diags, key=lambda d: (d.span.file, d.span.line, d.span.column)
                  if d.span else ("", 0, 0))
