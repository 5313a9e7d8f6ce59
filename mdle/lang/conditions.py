"""Interrupt expressions compiled once into flat closures.

Over 500 lines: the code generator and the closure interpreter of huge expressions
(:func:`_interpret`) evaluate the same node kinds the same way, and stay side by side.

The checker types each sub-expression (:class:`Typed`: a condition, or a number of
some dimension) and combines them bottom-up into an expression tree; constant parts are
folded at check time. :func:`to_interrupt` then turns the tree into ONE Python function:
``range(0 deg) < 2 * 0.5 m or stalled`` becomes
``lambda ctx: (True if s0(a0, ctx) < k0 else False) or (True if s1(a1, ctx) else False)``
with the sensor functions, their arguments and the constants bound as names, so a tick
pays one call plus the sensor calls, not a closure per operator (interrupts are most of
the interpreter's per-tick work). The generated code evaluates exactly what nested
closures would: the same operations in the same order, ``and``/``or`` short-circuiting,
every condition normalised to a Python bool. The runtime calls ``Interrupt.test(ctx)``
and nothing else.
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import CodeType, MappingProxyType
from typing import Any

from mdle.atoms.registry import BOOL, Context, SensorSpec
from mdle.core.units import Dim
from mdle.lang.program import NEVER, Interrupt

__all__ = ["Typed", "constant", "sensor_reading", "sensor_call", "negate", "logic", "compare",
           "arith", "apply", "remembered", "tracked", "to_interrupt", "BUILTINS", "FOLDS"]

#: Functions of numbers a condition may call, by name: how many arguments each takes
#: (low, high). ``at_start(e)`` is the value ``e`` had when the element started;
#: ``lowest(e)``, ``highest(e)`` and ``ever(c)`` what ``e`` or ``c`` has been over the
#: element's run so far (:data:`FOLDS`).
BUILTINS: Mapping[str, tuple[int, float]] = {
    "abs": (1, 1), "min": (2, math.inf), "max": (2, math.inf), "at_start": (1, 1),
    "lowest": (1, 1), "highest": (1, 1), "ever": (1, 1)}


def _lower(held: Any, new: Any) -> Any:
    """Return the lesser of the two; a NaN held so far gives way to any reading."""
    return new if new < held or held != held else held


def _higher(held: Any, new: Any) -> Any:
    """Return the greater of the two; a NaN held so far gives way to any reading."""
    return new if new > held or held != held else held


def _either(held: Any, new: Any) -> bool:
    """Return True once either has held."""
    return bool(held or new)


#: The running memories: how each folds this tick's reading into the value it holds.
FOLDS: Mapping[str, Callable[[Any, Any], Any]] = MappingProxyType(
    {"lowest": _lower, "highest": _higher, "ever": _either})

Kind = Any  # Dim (a number), None (a number of unknown dimension) or BOOL (a condition)
Fn = Callable[[Context], Any]

_COMPARE: dict[str, Callable[[Any, Any], bool]] = {
    "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge,
    "==": operator.eq, "!=": operator.ne,
}
_ARITH: dict[str, Callable[[Any, Any], Any]] = {
    "+": operator.add, "-": operator.sub, "*": operator.mul,
}
#: Nodes whose value is always a Python bool: no normalisation needed around them.
_BOOL_NODES = frozenset({"not", "cmp", "and", "or", "xor"})


@dataclass(frozen=True)
class Node:
    """A node of an expression read at run time: ``op`` applied to ``parts``.

    ``op`` is ``sensor`` (parts: function, arguments), ``sensor_call`` (function, fixed
    arguments, names of the arguments read each tick, then their nodes), ``const``
    (value), ``not`` or ``neg`` (operand), ``cmp`` or ``arith`` (operator, left, right),
    ``and``, ``or``, ``xor`` (left, right), ``fn`` (a Python function of numbers, then its
    operands), ``start`` (a :class:`Remembered` key, the node it remembers) or ``track``
    (a :class:`Remembered` key, the fold of :data:`FOLDS`, the node it follows).
    """

    op: str
    parts: tuple[Any, ...]


@dataclass(frozen=True)
class Typed:
    """A typed expression: its kind, and either a constant or a tree read at run time."""

    kind: Kind
    node: Node | None = None
    const: Any = None

    @property
    def is_bool(self) -> bool:
        """True for a condition."""
        return self.kind is BOOL

    @property
    def is_const(self) -> bool:
        """True when the value is known at check time."""
        return self.node is None

    @property
    def dim(self) -> Dim | None:
        """The dimension of a number (None when unknown)."""
        return None if self.kind is BOOL else self.kind

    @property
    def fn(self) -> Fn | None:
        """The expression compiled to ``fn(ctx)`` (None for a constant)."""
        return None if self.node is None else _compile(self.node, as_bool=False)

    def call(self) -> Fn:
        """Return a function of ``ctx`` for this expression (constants return themselves)."""
        if self.node is not None:
            return _compile(self.node, as_bool=False)
        value = self.const
        return lambda ctx: value



def _operand(t: Typed) -> Node:
    return Node("const", (t.const,)) if t.node is None else t.node


def constant(kind: Kind, value: Any) -> Typed:
    """Return a value known at check time."""
    return Typed(kind, None, value)


def sensor_reading(spec: SensorSpec, args: Mapping[str, Any]) -> Typed:
    """Return a sensor function read each time the interrupt is tested."""
    return Typed(spec.result, Node("sensor", (spec.fn, args)), None)


def sensor_call(spec: SensorSpec, fixed: Mapping[str, Any],
                read: tuple[tuple[str, Typed], ...]) -> Typed:
    """Return a sensor function whose arguments ``read`` are expressions read each tick.

    ``range(bearing_to(8 m, 0 m))``: the bearing is computed, then the range read along
    it, at every test. Constant arguments among ``read`` join the fixed ones.
    """
    args = dict(fixed)
    live = []
    for name, t in read:
        if t.node is None:
            args[name] = t.const
        else:
            live.append((name, t.node))
    if not live:
        return sensor_reading(spec, MappingProxyType(args))
    return Typed(spec.result, Node("sensor_call", (
        spec.fn, MappingProxyType(args), tuple(n for n, _ in live), *(n for _, n in live))),
        None)


def apply(fn: Callable[..., Any], args: list[Typed], kind: Kind) -> Typed:
    """Return ``fn(*args)`` (abs, min, max): folded when every argument is constant."""
    if all(a.node is None for a in args):
        return constant(kind, fn(*(a.const for a in args)))
    return Typed(kind, Node("fn", (fn, *(_operand(a) for a in args))), None)


class Remembered:
    """The key of one ``at_start``, ``lowest``, ``highest`` or ``ever``.

    Where an element keeps the value it remembers.
    """

    __slots__ = ()


def remembered(t: Typed) -> Typed:
    """Return ``at_start(t)``: ``t`` as it was when the element started (a constant stays)."""
    if t.node is None:
        return t
    return Typed(t.kind, Node("start", (Remembered(), t.node)), None)


def tracked(name: str, t: Typed) -> Typed:
    """Return ``lowest(t)``, ``highest(t)`` or ``ever(t)`` (a constant stays)."""
    if t.node is None:
        return t
    return Typed(t.kind, Node("track", (Remembered(), FOLDS[name], t.node)), None)


@dataclass(frozen=True)
class Memory:
    """One value an element remembers: evaluated at its start, and folded each tick.

    ``read(ctx)`` evaluates the expression remembered; ``fold`` is None for
    ``at_start`` (kept as it was at the start), else how this tick's reading joins the
    value held (:data:`FOLDS`).
    """

    key: Remembered
    read: Fn
    fold: Callable[[Any, Any], Any] | None


def memories(t: Typed) -> tuple[Memory, ...]:
    """Return what a condition remembers, inner before outer.

    ``lowest(dist_to(at_start(x), at_start(y)))`` needs the two start values before its
    first reading: the order is the order of evaluation, at the start and each tick.
    """
    if t.node is None:
        return ()
    found: list[Memory] = []
    seen: set[int] = set()
    stack: list[tuple[Node, bool]] = [(t.node, False)]
    while stack:
        n, parts_done = stack.pop()
        if parts_done:
            if n.op == "start":
                found.append(Memory(n.parts[0], _compile(n.parts[1], as_bool=False), None))
            elif n.op == "track":
                inner = n.parts[2]
                found.append(Memory(n.parts[0], _compile(inner, as_bool=n.parts[1] is _either),
                                    n.parts[1]))
            continue
        if id(n) in seen:
            continue
        seen.add(id(n))
        stack.append((n, True))
        stack.extend((p, False) for p in reversed(n.parts) if isinstance(p, Node))
    return tuple(found)


def all_memories(parts: list[Typed]) -> tuple[Memory, ...]:
    """Return what several expressions remember (a node they share, once), inner first."""
    found: dict[int, Memory] = {}
    for t in parts:
        for m in memories(t):
            found.setdefault(id(m.key), m)
    return tuple(found.values())


def remembers(t: Typed) -> tuple[tuple[Remembered, Fn], ...]:
    """Return each value a condition remembers at the start: its key and its function."""
    return tuple((m.key, m.read) for m in memories(t))


def negate(op: str, a: Typed) -> Typed:
    """Apply ``not a``, ``-a`` or ``+a`` (already type-checked)."""
    if op == "not":
        if a.node is None:
            return constant(BOOL, not a.const)
        return Typed(BOOL, Node("not", (_operand(a),)), None)
    if op == "+":
        return a
    if a.node is None:
        return constant(a.kind, -a.const)
    return Typed(a.kind, Node("neg", (_operand(a),)), None)


def logic(op: str, a: Typed, b: Typed) -> Typed:
    """Combine conditions with ``and``, ``or``, ``xor``, short-circuiting where it can."""
    if a.node is None and b.node is None:
        value = {"and": a.const and b.const, "or": a.const or b.const,
                 "xor": bool(a.const) != bool(b.const)}[op]
        return constant(BOOL, bool(value))
    for fixed, other in ((a, b), (b, a)):
        if fixed.node is None:
            if op == "and":
                return other if fixed.const else constant(BOOL, False)
            if op == "or":
                return constant(BOOL, True) if fixed.const else other
            return negate("not", other) if fixed.const else other
    if op not in ("and", "or"):
        op = "xor"
    return Typed(BOOL, Node(op, (_operand(a), _operand(b))), None)


def _divide(x: float, y: float) -> float:
    if y == 0:
        return math.copysign(math.inf, x) if x else math.nan
    return x / y


def compare(op: str, a: Typed, b: Typed) -> Typed:
    """Return a comparison of two numbers of the same dimension."""
    if a.node is None and b.node is None:
        return constant(BOOL, bool(_COMPARE[op](a.const, b.const)))
    return Typed(BOOL, Node("cmp", (op, _operand(a), _operand(b))), None)


def arith(op: str, a: Typed, b: Typed, kind: Kind) -> Typed:
    """Apply ``a + b`` and friends; division by zero gives inf (or nan), never an exception."""
    if a.node is None and b.node is None:
        fn = _divide if op == "/" else _ARITH[op]
        return constant(kind, fn(a.const, b.const))
    return Typed(kind, Node("arith", (op, _operand(a), _operand(b))), None)


#: Nesting depth of one generated function: deeper subtrees (a chain of named interrupts,
#: say) become functions of their own, since Python's parser allows 200 parentheses.
_SPLIT_DEPTH = 24

#: Marks a shared sub-expression not yet evaluated during the current test.
_UNSET = object()


def _shared(root: Node) -> set[int]:
    """Return the ids of the nodes reached from more than one place (the DAG's joins).

    A named interrupt used twice is one node with two parents; generated inline it would
    double at every level of a chain (``interrupt iN = iN-1 or iN-1``).
    """
    refs: dict[int, int] = {}
    seen = {id(root)}
    stack = [root]
    while stack:
        n = stack.pop()
        for part in n.parts:
            if isinstance(part, Node) and part.op != "const":
                refs[id(part)] = refs.get(id(part), 0) + 1
                if id(part) not in seen:
                    seen.add(id(part))
                    stack.append(part)
    return {k for k, count in refs.items() if count > 1}


class _Source:
    """Python source of one expression DAG, and the objects it names.

    A node reached from several places is generated once, as a function of its own
    whose value is kept for the rest of the test (``_m``, one slot per such node); a
    subtree nested deeper than :data:`_SPLIT_DEPTH` becomes a function of its own too.
    The code therefore grows with the number of distinct nodes, and a test evaluates
    each of them at most once.
    """

    def __init__(self, shared: set[int]) -> None:
        self.names: dict[str, Any] = {}
        self.depth = 0
        self.shared = shared
        self.slots: dict[int, int] = {}
        self.functions: list[str] = []

    def bind(self, prefix: str, value: Any) -> str:
        name = f"{prefix}{len(self.names)}"
        self.names[name] = value
        return name

    def value(self, n: Node) -> str:
        """Return source evaluating ``n`` exactly as nested closures would."""
        if id(n) in self.shared:
            return self._memo(n)
        if self.depth >= _SPLIT_DEPTH and n.op not in ("const", "sensor"):
            name = f"_h{len(self.functions)}"
            self.functions.append("")  # reserve the name before generating the body
            index = len(self.functions) - 1
            self.functions[index] = f"def {name}(ctx, _m):\n    return {self._body(n)}\n"
            return f"{name}(ctx, _m)"
        self.depth += 1
        try:
            return self._value(n)
        finally:
            self.depth -= 1

    def _body(self, n: Node) -> str:
        """Return the source of ``n`` as the whole body of a new function."""
        saved, self.depth = self.depth, 1
        try:
            return self._value(n)
        finally:
            self.depth = saved

    def _memo(self, n: Node) -> str:
        index = self.slots.get(id(n))
        if index is None:
            index = self.slots[id(n)] = len(self.slots)
            self.functions.append(f"def _g{index}(ctx, _m):\n    v = _m[{index}] = "
                                  f"{self._body(n)}\n    return v\n")
        return f"(_m[{index}] if _m[{index}] is not _U else _g{index}(ctx, _m))"

    def _value(self, n: Node) -> str:
        op, p = n.op, n.parts
        if op == "const":
            return self.bind("k", p[0])
        if op == "sensor":
            return f"{self.bind('s', p[0])}({self.bind('a', p[1])}, ctx)"
        if op == "sensor_call":  # the fixed arguments, and those read now, in one dict
            read = ", ".join(f"{name!r}: {self.value(node)}"
                             for name, node in zip(p[2], p[3:], strict=True))
            return f"{self.bind('s', p[0])}({{**{self.bind('a', p[1])}, {read}}}, ctx)"
        if op == "fn":
            return f"{self.bind('f', p[0])}({', '.join(self.value(x) for x in p[1:])})"
        if op in ("start", "track"):  # kept by the element (Interrupt.remember, .track)
            return f"ctx.memory[{self.bind('r', p[0])}]"
        if op == "not":
            return f"(not {self.value(p[0])})"
        if op == "neg":
            return f"(-{self.value(p[0])})"
        if op == "cmp":  # operator.lt(x, y) is x < y; bool() of it is `True if .. else False`
            return f"(True if {self.value(p[1])} {p[0]} {self.value(p[2])} else False)"
        if op == "arith":
            left, right = self.value(p[1]), self.value(p[2])
            if p[0] == "/":
                return f"{self.bind('d', _divide)}({left}, {right})"
            return f"({left} {p[0]} {right})"
        x, y = self.truth(p[0]), self.truth(p[1])
        return f"({x} != {y})" if op == "xor" else f"({x} {op} {y})"

    def truth(self, n: Node) -> str:
        """Return source for ``bool(n)``."""
        code = self.value(n)
        return code if n.op in _BOOL_NODES else f"(True if {code} else False)"


#: Distinct nodes above which an expression is evaluated by closures rather than by
#: generated code: Python's ``compile`` of one huge function takes seconds, cannot be
#: interrupted and holds the tick loop meanwhile, while closures are made in a Python
#: loop (a signal is answered between two nodes) in time linear in the nodes.
_GENERATE_LIMIT = 1000


def _distinct_nodes(root: Node, limit: int) -> int:
    """Return the number of distinct non-constant nodes under ``root`` (stops past ``limit``)."""
    seen = {id(root)}
    stack = [root]
    while stack and len(seen) <= limit:
        for part in stack.pop().parts:
            if isinstance(part, Node) and part.op != "const" and id(part) not in seen:
                seen.add(id(part))
                stack.append(part)
    return len(seen)


MFn = Callable[[Context, list[Any]], Any]  # a node's closure: (ctx, the test's memo slots)


def _node_closure(n: Node, made: Mapping[int, MFn]) -> MFn:
    """Return the closure of one node whose parts' closures are already ``made``."""
    op, p = n.op, n.parts

    def part(x: Any) -> MFn:
        if isinstance(x, Node) and x.op != "const":
            return made[id(x)]
        value = x.parts[0] if isinstance(x, Node) else x
        return lambda ctx, m: value

    def truth(x: Any) -> MFn:  # bool(x) without a call where x is a bool already
        f = part(x)
        if isinstance(x, Node) and x.op in _BOOL_NODES:
            return f
        return lambda ctx, m: True if f(ctx, m) else False

    if op == "const":
        return part(n)
    if op == "sensor":
        fn, args = p
        return lambda ctx, m: fn(args, ctx)
    if op == "sensor_call":  # the fixed arguments, and those read now, in one dict
        fn, fixed, names = p[0], p[1], p[2]
        reads = [part(x) for x in p[3:]]
        return lambda ctx, m: fn({**fixed, **{k: r(ctx, m) for k, r in zip(names, reads,
                                                                          strict=True)}},
                                 ctx)
    if op == "fn":
        f0, operands = p[0], [part(x) for x in p[1:]]
        return lambda ctx, m: f0(*(o(ctx, m) for o in operands))
    if op in ("start", "track"):  # kept by the element (Interrupt.remember, .track)
        key = p[0]
        return lambda ctx, m: ctx.memory[key]
    if op == "not":
        f = part(p[0])
        return lambda ctx, m: not f(ctx, m)
    if op == "neg":
        f = part(p[0])
        return lambda ctx, m: -f(ctx, m)
    if op == "cmp":
        test, left, right = _COMPARE[p[0]], part(p[1]), part(p[2])
        return lambda ctx, m: True if test(left(ctx, m), right(ctx, m)) else False
    if op == "arith":
        fa = _divide if p[0] == "/" else _ARITH[p[0]]
        left, right = part(p[1]), part(p[2])
        return lambda ctx, m: fa(left(ctx, m), right(ctx, m))
    x, y = truth(p[0]), truth(p[1])
    if op == "and":
        return lambda ctx, m: x(ctx, m) and y(ctx, m)
    if op == "or":
        return lambda ctx, m: x(ctx, m) or y(ctx, m)
    return lambda ctx, m: x(ctx, m) != y(ctx, m)


def _memoised(f: MFn, slot: int) -> MFn:
    """Return ``f`` whose value is kept in ``m[slot]`` for the rest of one test."""
    def g(ctx: Context, m: list[Any]) -> Any:
        v = m[slot]
        if v is _UNSET:
            v = m[slot] = f(ctx, m)
        return v
    return g


def _interpret(root: Node, as_bool: bool) -> Fn:
    """Return a function of ``ctx`` evaluating ``root`` through one closure per node.

    It evaluates what the generated code does, in the same order, each shared node at
    most once per test; the closures are made bottom-up without recursion.
    """
    shared = _shared(root)
    slots = {key: i for i, key in enumerate(shared)}
    made: dict[int, MFn] = {}
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        n, parts_made = stack.pop()
        if id(n) in made:
            continue
        if not parts_made:
            stack.append((n, True))
            stack.extend((x, False) for x in n.parts if isinstance(x, Node) and id(x) not in made)
            continue
        f = _node_closure(n, made)
        made[id(n)] = _memoised(f, slots[id(n)]) if id(n) in slots else f
    top = made[id(root)]
    if as_bool and root.op not in _BOOL_NODES:
        inner = top
        top = lambda ctx, m: True if inner(ctx, m) else False  # noqa: E731
    count = len(slots)

    def test(ctx: Context) -> Any:
        return top(ctx, [_UNSET] * count)
    return test


def _compile(node: Node, as_bool: bool) -> Fn:
    """Return one function of ``ctx`` evaluating ``node`` (as a bool when ``as_bool``)."""
    if _distinct_nodes(node, _GENERATE_LIMIT) > _GENERATE_LIMIT:
        return _interpret(node, as_bool)
    src = _Source(_shared(node))
    body = src.truth(node) if as_bool else src.value(node)
    params = ", ".join(src.names)
    if not src.functions:
        # the bound objects become closure cells of the lambda: the fastest lookups there are
        code = f"def make({params}):\n    return lambda ctx: {body}\n"
    else:
        inner = "".join("    " + line + "\n" for f in src.functions for line in f.splitlines())
        memo = f"[_U] * {len(src.slots)}" if src.slots else "None"
        code = (f"def make(_U, {params}):\n{inner}"
                f"    def test(ctx):\n        _m = {memo}\n        return {body}\n"
                "    return test\n")
        src.names["_U"] = _UNSET
    namespace: dict[str, Any] = {"__builtins__": {}}
    exec(_code(code), namespace)
    fn: Fn = namespace["make"](**src.names)
    return fn


@functools.lru_cache(maxsize=1024)
def _code(source: str) -> CodeType:
    """Compile generated source once per shape.

    The bound objects are parameters of ``make``, so interrupts of the same shape
    (``range(0 deg) < 1 m`` and ``range(90 deg) < 2 m``) share one source text; a plan
    of thousands of definitions pays for a handful of compilations.
    """
    return compile(source, "<interrupt>", "exec")


def to_interrupt(t: Typed, source: str | Callable[[], str],
                 parts: tuple[tuple[Callable[[], str], Typed], ...] = ()) -> Interrupt:
    """Return the runtime's :class:`~mdle.lang.program.Interrupt` for a checked condition.

    ``source`` is the interrupt's text, or a function making it when first read;
    ``parts`` the conditions of a top-level ``or``, each with a function making its text.
    """
    if t.is_const:
        text = source if isinstance(source, str) else source()
        if not t.const:
            return NEVER if text == "never" else Interrupt(NEVER.test, text, never=True)
        return Interrupt(lambda ctx: True, text)
    assert t.node is not None
    return _Deferred(t.node, source, parts)


def _always(ctx: Context) -> bool:
    return True


class _Deferred(Interrupt):
    """An interrupt compiled when its ``test`` is first read, its text made likewise.

    ``mdle check`` reads neither, so a plan of thousands of interrupts is checked
    without generating their code; the runtime reads ``test`` once per string start and
    gets the compiled function itself (no wrapper per call).
    """

    def __init__(self, node: Node, source: str | Callable[[], str],
                 parts: tuple[tuple[Callable[[], str], Typed], ...] = ()) -> None:
        fields = self.__dict__  # as object.__setattr__ would, one call fewer each
        fields["never"] = False
        fields["_node"] = node
        fields["_source"] = source
        fields["_parts"] = parts

    @functools.cached_property
    def parts(self) -> tuple[tuple[str, Fn], ...]:
        """The conditions of a top-level ``or``, each with its text and test (compiled now)."""
        out = []
        for text, t in self.__dict__["_parts"]:
            if t.node is not None:
                out.append((text(), _compile(t.node, as_bool=True)))
            elif t.const:
                out.append((text(), _always))
        return tuple(out)

    @functools.cached_property
    def test(self) -> Fn:
        """The compiled function of ``ctx``."""
        return _compile(self.__dict__["_node"], as_bool=True)

    @functools.cached_property
    def _memories(self) -> tuple[Memory, ...]:
        return memories(Typed(BOOL, self.__dict__["_node"]))

    @functools.cached_property
    def remember(self) -> tuple[tuple[Any, Fn], ...]:
        """What the condition remembers, compiled, as read at the start (:class:`Interrupt`)."""
        return tuple((m.key, m.read) for m in self._memories)

    @functools.cached_property
    def track(self) -> tuple[tuple[Any, Fn, Callable[[Any, Any], Any]], ...]:
        """The running memories (``lowest``...), with their folds (:class:`Interrupt`)."""
        return tuple((m.key, m.read, m.fold) for m in self._memories if m.fold is not None)

    @functools.cached_property
    def source(self) -> str:
        """The canonical text of the interrupt."""
        made = self.__dict__["_source"]
        return made if isinstance(made, str) else made()
