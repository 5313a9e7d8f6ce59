"""Names: the one namespace of a program, clashes, and recursive definitions.

Every file of a program (the main file and its imports) shares one namespace. A name
defined twice is an error naming both places; a definition may not take the name of a
control law or sensor function, nor be defined in terms of itself (directly or
through others). The walks here use explicit stacks, so a 10,000-definition chain
cannot exhaust Python's recursion limit.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from mdle.atoms.registry import LawSpec, Registry, SensorSpec
from mdle.core.errors import Diagnostic, Severity
from mdle.lang import syntax as st
from mdle.lang.conditions import BUILTINS

__all__ = ["Namespace", "build_namespace", "symbol_argument", "references", "uses_of",
           "find_cycles"]


@dataclass(frozen=True)
class Namespace:
    """Definitions by name, over the registry of control laws and sensor functions."""

    definitions: Mapping[str, st.Definition]
    registry: Registry

    def lookup(self, name: str) -> st.Definition | LawSpec | SensorSpec | None:
        """Return what a name refers to: a definition, law, sensor function or nothing."""
        found = self.definitions.get(name)
        if found is not None:
            return found
        return self.registry.laws.get(name) or self.registry.sensors.get(name)

    def names(self) -> list[str]:
        """Every name a plan may use: definitions, control laws, sensor functions."""
        return sorted({*self.definitions, *self.registry.laws, *self.registry.sensors})


def build_namespace(definitions: Iterable[st.Definition], registry: Registry, *,
                    replace: bool = False) -> tuple[Namespace, list[Diagnostic]]:
    """Gather definitions into one namespace.

    With ``replace`` (the REPL), a later definition replaces an earlier one of the same
    name; otherwise that is an error naming both places.
    """
    defs: dict[str, st.Definition] = {}
    errors: list[Diagnostic] = []
    for d in definitions:
        kind = ("control law" if d.name in registry.laws else
                "sensor function" if d.name in registry.sensors else
                "built-in function" if d.name in BUILTINS else None)
        if kind is not None:
            errors.append(Diagnostic(
                d.name_span, f"`{d.name}` is already a {kind}; a definition cannot take its name",
                hint=f"pick another name, such as `my_{d.name}`"))
            continue
        prior = defs.get(d.name)
        if prior is not None and not replace:
            if prior is d:
                continue  # the same file reached twice through imports
            errors.append(Diagnostic(
                d.name_span,
                f"`{d.name}` is defined twice: {prior.name_span} and {d.name_span}",
                notes=(Diagnostic(prior.name_span, f"`{d.name}` is first defined here",
                                  Severity.NOTE),)))
            continue
        defs[d.name] = d
    return Namespace(MappingProxyType(defs), registry), errors


def symbol_argument(spec: LawSpec | SensorSpec | None, index: int, arg: st.Argument) -> bool:
    """Whether ``arg``, the ``index``-th argument of a call to ``spec``, is a declared symbol.

    That is, one of the symbols its parameter declares, such as ``left`` in
    ``follow_boundary(side = left)``.

    A declared symbol wins over a definition of the same name: a plan called ``left``
    does not change what ``side = left`` means.
    """
    if spec is None or not isinstance(arg.value, st.Name):
        return False
    if arg.name is not None:
        param = spec.param(arg.name)
    else:
        param = spec.params[index] if index < len(spec.params) else None
    return param is not None and (arg.value.name in param.choices or bool(param.any_name))


def references(definition: st.Definition, names: Mapping[str, st.Definition],
               registry: Registry | None = None) -> list[st.Name | st.Call]:
    """Return the uses of other definitions in a definition's body and defaults.

    Parameters shadow; with a ``registry``, symbols that a control law or sensor function
    declares do too.
    """
    found: list[st.Name | st.Call] = []
    stack: list[st.Expr] = [definition.body]
    shadow: frozenset[str] | set[str] = _NO_NAMES
    if definition.params:
        shadow = {p.name for p in definition.params}
        stack.extend(p.default for p in definition.params if p.default is not None)
    specs = (registry.laws, registry.sensors) if registry is not None else None
    pop, push, extend = stack.pop, stack.append, stack.extend
    # Dispatch on the exact node type (the syntax tree has no subclasses): one test for
    # the common nodes instead of a chain of isinstance calls. Children are pushed left
    # to right, as st.children gives them.
    while stack:
        e: Any = pop()
        kind = type(e)
        if kind is _NAME:
            if e.name in names and e.name not in shadow:
                found.append(e)
        elif kind is _CALL:
            name = e.name
            if name in names:
                if name not in shadow:
                    found.append(e)
                for a in e.args:
                    push(a.value)
            elif name == "send":
                for a in e.args[1:]:  # the channel names no definition
                    push(a.value)
            elif specs is not None:
                spec = specs[0].get(name) or specs[1].get(name)
                for i, a in enumerate(e.args):
                    # (only a name can be a declared symbol)
                    if type(a.value) is not _NAME or not symbol_argument(spec, i, a):
                        push(a.value)
            else:
                for a in e.args:
                    push(a.value)
        elif kind is _BINARY:
            push(e.left)
            push(e.right)
        elif kind is _GROUP or kind is _VECTOR:
            extend(e.items)
        elif kind is _UNARY:
            push(e.operand)
    return found


_NO_NAMES: frozenset[str] = frozenset()
_NAME, _CALL, _BINARY, _UNARY, _GROUP, _VECTOR = (st.Name, st.Call, st.Binary, st.Unary,
                                                  st.Group, st.Vector)


def uses_of(ns: Namespace) -> dict[str, list[st.Name | st.Call]]:
    """Return :func:`references` of every definition, by name (one walk of each body)."""
    defs = ns.definitions
    return {name: references(d, defs, ns.registry) for name, d in defs.items()}


def find_cycles(ns: Namespace, uses: Mapping[str, list[st.Name | st.Call]] | None = None
                ) -> tuple[set[str], list[Diagnostic]]:
    """Definitions defined in terms of themselves; one error per cycle, at each member.

    ``uses`` is :func:`uses_of` ``(ns)``, if the caller has it already.
    """
    defs = ns.definitions
    if uses is None:
        uses = uses_of(ns)
    color: dict[str, int] = {}  # 1: on the current path, 2: done
    in_cycle: set[str] = set()
    errors: list[Diagnostic] = []
    for root in defs:
        if color.get(root):
            continue
        path: list[str] = [root]
        iters = [iter(uses[root])]
        color[root] = 1
        while iters:
            use = next(iters[-1], None)
            if use is None:
                color[path.pop()] = 2
                iters.pop()
                continue
            target = use.name
            c = color.get(target)
            if c == 1:
                cycle = path[path.index(target):] + [target]
                if not set(cycle[:-1]) & in_cycle:
                    route = " \u2192 ".join(cycle)
                    errors.append(Diagnostic(
                        use.span, f"`{target}` is defined in terms of itself: {route}",
                        hint="MDLe elements cannot contain themselves; to repeat a string, "
                             "write `...` after it, as in `((a, b)..., never, inf)`"))
                in_cycle.update(cycle)
            elif c is None:
                color[target] = 1
                path.append(target)
                iters.append(iter(uses[target]))
    return in_cycle, errors
