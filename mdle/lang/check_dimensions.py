"""The checker's dimensions: fixed values, timers and interrupts, typed by unit.

Arguments and timers are fixed values evaluated when the program is checked
(:class:`~mdle.lang.dimensions.Quantity` or a symbol); an interrupt is typed piece by
piece (a condition, or a number of some dimension) and compiled into one closure
(:mod:`~mdle.lang.conditions`). Constant speeds and turn rates are compared with the
robot's limits when the robot is known.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType

from mdle.atoms.registry import BOOL, LawSpec, SensorSpec
from mdle.core.errors import Diagnostic, Severity, Span
from mdle.core.motion_limits import excess
from mdle.core.units import NONE, TIME, TURN_RATE
from mdle.lang import conditions as cond
from mdle.lang import syntax as st
from mdle.lang.check_expressions import ExpressionChecks, disjuncts, overload
from mdle.lang.check_state import (
    MAX_NESTING,
    Env,
    _Abort,
    _freeze,
    _kind_name,
    _short,
)
from mdle.lang.dimensions import (
    Quantity,
    Symbol,
    Value,
    dim_words,
    fits,
    same_kind,
    show_value,
    unit_for,
)
from mdle.lang.format import format_expr
from mdle.lang.program import INF, Interrupt, MessageUse


class DimensionChecks(ExpressionChecks):
    """Dimensions: values, timers, conditions and interrupts."""

    def value(self, expr: st.Expr, env: Env) -> Value:
        """Evaluate a fixed value: numbers with units, parameters, arithmetic.

        A bare unknown name is a symbol (its use decides whether that is right). Raises
        _Abort after an error.
        """
        if self._depth >= MAX_NESTING:
            self._enter(expr.span)  # reports, raises
        if type(expr) is st.Number:  # the common case, with nothing nested to count
            return Quantity(expr.value, expr.dim, not expr.unit)
        self._depth += 1
        try:
            return self._value(expr, env)
        finally:
            self._depth -= 1

    def _value(self, expr: st.Expr, env: Env) -> Value:
        if isinstance(expr, st.Number):
            return Quantity(expr.value, expr.dim, not expr.unit)
        if isinstance(expr, st.Name):
            if expr.name in env:
                return env[expr.name]
            target = self._lookup(expr.name)
            if target is not None and expr.name in self.refused:
                raise _Abort  # its definition was refused, with the reason
            if target is not None:
                self.error(expr.span, f"expected a fixed value, but `{expr.name}` is "
                           f"{_kind_name(target)}",
                           hint="a definition's arguments and timers are fixed when an "
                                "element starts; sensor readings belong in interrupts and in "
                                "a control law's arguments")
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
            if self._bounded:
                self._never_holds(expr, a, b)
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
        if isinstance(expr, st.Call) and name in cond.BUILTINS and name not in env:
            return self._builtin(expr, env)
        if isinstance(expr, st.Name) and name in env:
            v = env[name]
            if isinstance(v, Symbol):
                self.error(expr.span, f"`{name}` is the symbol `{v.name}` here; an interrupt "
                           "needs a condition or a number")
                raise _Abort
            return cond.constant(None if v.zero else v.dim, v.value)
        target = self._lookup(name)
        if name in self.refused:
            raise _Abort  # meant as the refused definition: that refusal says it all
        if isinstance(target, SensorSpec):
            target = overload(target, args)
            read: dict[str, cond.Typed] = {}  # the arguments read each tick
            outer, self._live_args = self._live_args, (
                read if any(self._is_live(a.value, env) for a in args) else None)
            try:
                bound = self.bind(name, self._slots_of_spec(target), args, env, expr.span)
            finally:
                self._live_args = outer
            self._note_names(target, bound, expr.span)
            if read:
                fixed = {k: v for k, v in self._plain(bound).items() if k not in read}
                return cond.sensor_call(target, fixed, tuple(read.items()))
            t = cond.sensor_reading(target, MappingProxyType(self._plain(bound)))
            if target.bounds is not None:
                self._bounded[id(t.node)] = (target.bounds, name)
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
            if self._readable is None:  # made once: the namespace does not change
                self._readable = [*(n for n, d in self.ns.definitions.items()
                                    if d.kind is st.DefKind.INTERRUPT),
                                  *self.ns.registry.sensors, "never"]
            params = [k for k, v in env.items() if not isinstance(v, Symbol)]
            self._unknown(name, getattr(expr, "name_span", expr.span), "name", params,
                          self._readable)
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
        self._expand(d, call)
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

        shown: dict[str, str] = {}

        def text(part: st.Expr) -> Callable[[], str]:
            def made() -> str:  # the text `show` and traces print, made when first read
                if not shown:
                    shown.update({k: show_value(v) for k, v in env.items()
                                  if not (isinstance(v, Quantity) and math.isnan(v.value))})
                return format_expr(part, shown)
            return made

        parts_of = disjuncts(expr)
        parts = tuple((text(d), self.condition(d, env)) for d in parts_of) \
            if len(parts_of) > 1 else ()
        return cond.to_interrupt(t, text(expr), parts)

    def _note_message_dim(self, a: cond.Typed, b: cond.Typed) -> None:
        """Record the dimension a `message(channel)` is used with (known from the other side)."""
        for m, other in ((a, b), (b, a)):
            hit = self._messages.get(id(m.node)) if m.node is not None else None
            if hit is not None and other.dim is not None:
                self._use(MessageUse("read", hit[1], other.dim, hit[2], "message"))

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
            message = (f"`{p.name}` of `{law.name}` is {value}{scaled}, more than the "
                       f"robot can do: {why}")
            hint = ("the robot clamps the command to its limit, so the plan does not move "
                    "as written; use a value within the limit, or name the robot meant "
                    "(--robot, --world)")
            if self._deferring is not None and span is None:
                self._deferring.append((where, message, hint))  # known once every use is
            else:
                self.warn(where, message, hint=hint, in_use=True)


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
