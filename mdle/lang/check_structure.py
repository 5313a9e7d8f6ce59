"""The checker's structure and reachability: what each tuple is, and what can run.

How a tuple ``(a, b, c)`` in an element position is read:

* ``a`` is a control law (``go(0.3 m/s)``, ``stop``): an atom (U, xi, T);
* ``a`` is a number, a parameter or ``[av, aw]``: a scaled atom (alpha, beta, sigma);
* ``a`` is a parenthesised string or a named element: an element ((a...), xi, T).

A definition's element is built once per distinct set of arguments (cached); nesting
is bounded (:data:`~mdle.lang.check_state.MAX_NESTING`), and an element after one that
never ends is reported as never reached.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Any, TypeVar

from mdle.atoms.registry import LawSpec
from mdle.core.errors import Diagnostic, Severity, Span
from mdle.core.messages import POSE_CHANNEL
from mdle.lang import conditions as cond
from mdle.lang import syntax as st
from mdle.lang.check_state import _MISSING, MAX_NESTING, CheckerState, Env, _Abort, _freeze, _short
from mdle.lang.dimensions import Quantity, Symbol, Value, show_value
from mdle.lang.format import format_expr
from mdle.lang.program import (
    AtomNode,
    Element,
    Interrupt,
    LiveArg,
    LiveArgs,
    MessageUse,
    Send,
    StringKind,
    StringNode,
)

_E = TypeVar("_E", AtomNode, StringNode)


def _replaced(node: _E, **changes: Any) -> _E:
    """Return a copy of ``node`` with some fields changed (a misspelt field is a TypeError)."""
    return dataclasses.replace(node, **changes)


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


class StructureChecks(CheckerState):
    """Structure: atoms, scaled atoms, strings, definitions, reachability."""

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
            if isinstance(self._lookup(head.name), LawSpec) and head.name not in self.refused:
                return "atom"  # (a refused definition of a law's name was meant as one)
            return "string"
        return "scaled"

    def _atom(self, expr: st.Group, env: Env) -> AtomNode:
        u, xi, timer = expr.items[:3]
        assert isinstance(u, (st.Name, st.Call))
        law = self._lookup(u.name)
        assert isinstance(law, LawSpec)
        failed = False
        given = u.args if isinstance(u, st.Call) else ()
        read: dict[str, cond.Typed] = {}  # the arguments read while the atom runs
        outer, self._live_args = self._live_args, (
            read if any(self._is_live(a.value, env) for a in given) else None)
        try:
            args = self.bind(u.name, self._slots_of_spec(law), given, env, u.span)
            self._note_names(law, args, u.span)
        except _Abort:
            failed = True
        else:
            if self._scaling is not expr:  # a scaled atom is checked once scaled
                self._within_limits(law, args, u)
        finally:
            self._live_args = outer
        sends: list[Send] = []
        sent: list[cond.Typed] = []  # the values sent, for what they remember
        for item in expr.items[3:]:
            assert isinstance(item, st.Call)
            try:
                sends.append(self._send(item, env, sent))
            except _Abort:
                failed = True
        interrupt, t = self._ending(xi, timer, env, failed)
        live = None if failed or not (read or sent) else self._live(law, read, given, env,
                                                                    sent)
        return AtomNode(law.name, law, MappingProxyType(self._plain(args)), interrupt, t,
                        (1.0, 1.0), expr.span, tuple(sends), live)

    def _live(self, law: LawSpec, read: dict[str, cond.Typed], given: Sequence[st.Argument],
              env: Env, sent: list[cond.Typed]) -> LiveArgs | None:
        """Compile the arguments of ``law`` read while the atom runs (constants stay fixed).

        What they and the values the atom sends remember (``send(gap, x - at_start(x))``)
        is kept with them, for each run of the atom.
        """
        shown = {k: show_value(v) for k, v in env.items()
                 if not (isinstance(v, Quantity) and math.isnan(v.value))}
        texts = {}
        for i, a in enumerate(given):
            name = a.name if a.name is not None else (
                law.params[i].name if i < len(law.params) else None)
            if name is not None:
                texts[name] = format_expr(a.value, shown)
        # all of them, a constant too (`lowest(1 m/s)`): its place in the args is a NaN
        parts = dict(read)
        memory = cond.all_memories([*parts.values(), *sent])
        if not parts and not memory:
            return None
        return LiveArgs(
            tuple(LiveArg(name, texts.get(name, name), t.call(), law.param(name))
                  for name, t in parts.items()),
            tuple((m.key, m.read) for m in memory),
            tuple((m.key, m.read, m.fold) for m in memory if m.fold is not None))

    def _send(self, call: st.Call, env: Env, sent: list[cond.Typed]) -> Send:
        """Check ``send(channel, value)`` or ``send(pose)``, an atom's fourth part on.

        The value's typed expression is appended to ``sent``.
        """
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
        sent.append(t)
        return Send(channel, t.call(), t.dim, f"send({channel}, {format_expr(args[1].value)})",
                    call.span)

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
        node = StringNode(label, tuple(elements), interrupt, t, repeat, kind, expr.span)
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
        self._expand(d, call)
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


def _is_send(expr: st.Expr) -> bool:
    return isinstance(expr, st.Call) and expr.name == "send"


def _called(expr: st.Expr) -> str:
    """How a message names an element: its text if short, else where it starts."""
    text = format_expr(expr)
    if len(text) <= 40:
        return f"`{text}`"
    return f"the element at line {expr.span.line}, column {expr.span.column}"


def _after(expr: st.Group) -> Span:
    s = expr.span
    return Span(s.file, s.end_line, max(1, s.end_column - 1), s.end_line, s.end_column)

