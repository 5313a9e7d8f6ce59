"""The checker's names and arity: what a name stands for, and binding arguments.

Every name is resolved against the namespace (definitions, control laws, sensor
functions); an unknown one gets a "did you mean" from the names that fit where it
stands. A call's arguments are bound to the parameters of what it calls: arity,
keywords, symbols, each argument's dimension and range.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence

from mdle.atoms.registry import REQUIRED, LawSpec, SensorSpec
from mdle.core.errors import Diagnostic, Severity, Span
from mdle.core.units import NONE
from mdle.lang import syntax as st
from mdle.lang.check_state import _EMPTY, CheckerState, Env, _Abort, _kind_name, _short, _Slot
from mdle.lang.dimensions import (
    Quantity,
    Symbol,
    Value,
    dim_example,
    dim_words,
    fits,
    show_value,
    unit_for,
)
from mdle.lang.format import format_expr
from mdle.lang.program import Element, MessageUse

#: Most names one "did you mean" compares an unknown name with.
_MAX_CANDIDATES = 200


class NameChecks(CheckerState):
    """Names and arity: resolving names, binding arguments to parameters."""

    def _closest(self, name: str, pool: Sequence[str]) -> str | None:
        """Return the name in ``pool`` closest to ``name`` (difflib, cutoff 0.6), if any.

        The pool is indexed by length once per checker: a ratio of 0.6 needs lengths
        within a factor of two, and at most :data:`_MAX_CANDIDATES` of those (sharing the
        first letter first) are compared, so 4,000 unknown names among 4,000 definitions
        cost a few comparisons each instead of 4,000.
        """
        key = (len(pool), tuple(pool[:3]), tuple(pool[-3:]))
        index = self._pools.get(key)
        if index is None:  # by length, and by length and first letter (key "<len> <letter>")
            index = {}
            for c in dict.fromkeys(pool):
                index.setdefault(len(c), []).append(c)
                index.setdefault(f"{len(c)} {c[:1]}", []).append(c)
            self._pools[key] = index
        n = len(name)
        sizes = range(max(1, n // 2), 2 * n + 2)
        # names sharing the first letter first; the lists are walked only until enough are
        # found, so one lookup never passes over the whole pool
        near: dict[str, None] = {}  # ordered, without repeats
        keys: list[int | str] = [f"{size} {name[:1]}" for size in sizes]
        for k in [*keys, *sizes]:
            near.update(dict.fromkeys(index.get(k, ())[:_MAX_CANDIDATES]))
            if len(near) >= _MAX_CANDIDATES:
                break
        close = difflib.get_close_matches(name, list(near)[:_MAX_CANDIDATES], n=1, cutoff=0.6)
        return close[0] if close else None

    def _unknown(self, name: str, span: Span, what: str, pool: Sequence[str],
                 shared: list[str] | None = None) -> None:
        if name in self.unparsed:
            return  # its statement has a syntax error, reported already
        found = self._closest(name, list(pool))
        if shared is not None:
            # ``shared`` is the same list at every call (names the whole program offers):
            # indexed once, so N unknown names cost N lookups, not N passes over the file
            near = [c for c in (found, self._closest(name, shared)) if c]
            close_all = difflib.get_close_matches(name, near, n=1, cutoff=0.6)
            found = close_all[0] if close_all else None
        close = [found] if found else []
        self.error(span, f"unknown {what} `{name}`",
                   hint=f"did you mean `{close[0]}`?" if close else None)

    def bind(self, callee: str, slots: Sequence[_Slot], args: Sequence[st.Argument],
             env: Env, span: Span) -> dict[str, Value]:
        """Bind call arguments to parameters; checks arity, keywords, symbols, dimensions."""
        bound: dict[str, Value] = {}
        given: dict[str, st.Argument] = {}
        ok = True
        positional_done = False
        late = _late_positionals(slots, args)
        for i, a in enumerate(args):
            if a.name is None:
                if positional_done:
                    fix = late.get(i)
                    self.error(a.span, "a positional argument cannot follow a keyword argument",
                               hint=None if fix is None else
                               f"name it: `{_renamed(callee, args, late)}`")
                    ok = False
                    if fix is not None:
                        given[fix] = a  # the slot it was meant for is not missing too
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
        live = self.live_argument(callee, slot, expr, env)
        if live is not None:
            return live  # read each tick: typed and kept aside
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

    def _named_element(self, expr: st.Name | st.Call, env: Env) -> Element:
        name = expr.name
        if isinstance(expr, st.Name) and name in env:
            self.error(expr.span, f"`{name}` is a parameter, not an element")
            raise _Abort
        target = self._lookup(name)
        if name in self.refused and not isinstance(target, st.Definition):
            raise _Abort  # its definition was refused, with the reason
        if isinstance(target, st.Definition) and target.kind is not st.DefKind.INTERRUPT:
            self.scaled_uses.setdefault(name, set()).add(self._scaling is expr)
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
        with_laws = expr is self._atom_head  # `(g(1 m/s), never, 5 s)`: a law fits here too
        pool = self._element_pools.get(with_laws)
        if pool is None:  # made once per checker, so N unknown names cost N lookups
            pool = [n for n, d in self.ns.definitions.items()
                    if d.kind is not st.DefKind.INTERRUPT]
            if with_laws:
                pool += list(self.ns.registry.laws)
            self._element_pools[with_laws] = pool
        found = self._closest(name, pool)
        close = [found] if found else []
        span = getattr(expr, "name_span", expr.span)
        self.error(span, f"unknown name `{name}`: not a control law, atom, behavior or plan",
                   hint=f"did you mean `{close[0]}`?" if close else None)
        raise _Abort


def _late_positionals(slots: Sequence[_Slot], args: Sequence[st.Argument]) -> dict[int, str]:
    """Return the parameter each positional argument after a keyword was meant for, by index.

    In ``arc(v = 0.2 m/s, 10 deg/s)`` the ``10 deg/s`` fills the first parameter not
    given otherwise: ``omega``.
    """
    named = {a.name for a in args if a.name is not None}
    first_kw = next((i for i, a in enumerate(args) if a.name is not None), len(args))
    taken = {s.name for s in slots[:first_kw]} | named
    free = [s.name for s in slots if s.name not in taken]
    late = [i for i in range(first_kw, len(args)) if args[i].name is None]
    return dict(zip(late, free[:len(late)], strict=False))


def _renamed(callee: str, args: Sequence[st.Argument], late: Mapping[int, str]) -> str:
    """Return the call with each late positional argument named (see above)."""
    parts = []
    for i, a in enumerate(args):
        name = a.name if a.name is not None else late.get(i)
        parts.append((f"{name} = " if name else "") + format_expr(a.value))
    return f"{callee}({', '.join(parts)})"


def _completed(callee: str, args: Sequence[st.Argument], missing: Sequence[_Slot]) -> str:
    """Return the call as written with the missing parameters added.

    ``arc(0.3 m/s)`` missing ``omega`` gives ``arc(0.3 m/s, omega = ...)``.
    """
    parts = [(f"{a.name} = " if a.name else "") + format_expr(a.value) for a in args]
    parts += [f"{s.name} = ..." for s in missing]
    return f"{callee}({', '.join(parts)})"

