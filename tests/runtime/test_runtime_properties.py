"""Properties of the scheduler on random element trees and random signal scripts.

Whatever the tree (nesting, repetition, zero-time elements, timers) and whatever the
signals do, the events must nest, every running element must have passed its tests at
every tick it stayed running, every recorded cause must be true at its tick, ancestors
of an element that fired must not have fired (outermost wins), strings must run their
elements in order, and the command must come from the running atom only.
"""

from __future__ import annotations

import itertools
import math
from types import SimpleNamespace
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mdle.core.backend import Command
from mdle.lang import INF, NEVER, AtomNode, Element, StringNode
from mdle.runtime import Cause, EventKind, RunResult, run
from mdle.runtime.scripted import ScriptedBackend

SIGNALS = ("a", "b", "c")
TIMERS = (INF, INF, 0.0, 0.1, 0.2, 0.35)
TICKS = 25
DT = 0.1


def _speed(label: str) -> float:
    """Return the speed atom ``label`` commands: distinct per atom, so commands name it."""
    return float(len(label) + int(label[1:]))


@st.composite
def trees(draw: st.DrawFn, ir: SimpleNamespace, depth: int = 3) -> Element:
    counter = itertools.count()

    def node(d: int) -> Element:
        label = f"n{next(counter)}"
        xi_name = draw(st.sampled_from((None, *SIGNALS)))
        xi = NEVER if xi_name is None else ir.sig(xi_name)
        timer = draw(st.sampled_from(TIMERS))
        if d == 0 or draw(st.integers(0, 2)) == 0:
            return AtomNode(label, ir.const_law(label, _speed(label)), {}, xi, timer)
        n = draw(st.integers(0, 3))
        return StringNode(label, tuple(node(d - 1) for _ in range(n)), xi, timer,
                          draw(st.booleans()))

    return node(depth)


def _index(root: Element) -> tuple[dict[str, Element], dict[str, str | None]]:
    """Path -> node, and path -> parent path."""
    nodes: dict[str, Element] = {}
    parents: dict[str, str | None] = {}

    def walk(n: Element, path: str, parent: str | None) -> None:
        nodes[path] = n
        parents[path] = parent
        for c in getattr(n, "elements", ()):
            walk(c, f"{path}/{c.label}", path)

    walk(root, root.label, None)
    return nodes, parents


def _fires(node: Element, signals: set[str], t_local: float) -> tuple[bool, bool]:
    """(timer expired, interrupt true) for ``node`` at a tick with ``signals``."""
    timer = t_local >= node.timer - 1e-9
    xi = (not node.interrupt.never) and node.interrupt.source in signals
    return timer, xi


def check(root: Element, script: list[dict[str, Any]]) -> RunResult:
    backend = ScriptedBackend(script)
    result = run(root, backend, until=TICKS * DT - DT / 2, stall_timeout=None)
    nodes, parents = _index(root)
    tick_of = lambda t: round(t / DT)  # noqa: E731
    signals = [set(k for k, v in s["truth"].items() if v) for s in script]

    # 1. events nest, and everything started has ended
    stack: list[str] = []
    starts: dict[str, float] = {}
    running_at: dict[int, list[str]] = {}  # tick -> active paths after that tick's events
    by_tick = itertools.groupby(result.events, key=lambda e: tick_of(e.time))
    for k, events in by_tick:
        for e in events:
            if e.kind is EventKind.START:
                assert e.path.rpartition("/")[0] == (stack[-1] if stack else ""), e
                stack.append(e.path)
                starts[e.path] = e.time
            else:
                assert stack and stack[-1] == e.path, (e, stack)
                stack.pop()
                t_local = e.time - starts[e.path]
                timer, xi = _fires(nodes[e.path], signals[k], t_local)
                # 2. the cause recorded holds at that tick
                if e.cause is Cause.TIMER:
                    assert timer, e
                elif e.cause is Cause.INTERRUPT:
                    assert xi and not timer, e
                elif e.cause is Cause.COMPLETED:
                    ended = nodes[e.path]
                    assert isinstance(ended, StringNode) and not ended.repeat
                if e.cause in (Cause.TIMER, Cause.INTERRUPT):
                    # 3. outermost wins: no running ancestor fired at this tick
                    p = parents[e.path]
                    while p is not None:
                        assert not any(_fires(nodes[p], signals[k], e.time - starts[p])), (e, p)
                        p = parents[p]
        running_at[k] = list(stack)
    assert stack == []

    # every tick: the active paths after its events (unchanged on ticks without events)
    for k in range(result.ticks):
        if k not in running_at:
            running_at[k] = running_at[k - 1]

    # 4. an element still running after a tick passed its tests at that tick
    for k, active in running_at.items():
        for path in active:
            assert not any(_fires(nodes[path], signals[k], k * DT - starts_at(result, path, k))
                           ), (k, path)

    # 5. the command is the running atom's, or zero
    for (t, cmd) in backend.commands:
        k = tick_of(t)
        active = running_at[k]
        top = nodes[active[-1]] if active else None
        if isinstance(top, AtomNode):
            assert cmd == Command(_speed(top.label), 0.0), (k, active)
        else:
            assert cmd == Command(), (k, active)

    # 6. strings start their elements in order
    for path, node in nodes.items():
        if not isinstance(node, StringNode) or not node.elements:
            continue
        runs: list[list[str]] = []
        for e in result.events:
            if e.kind is EventKind.START and e.path == path:
                runs.append([])
            elif e.kind is EventKind.START and parents.get(e.path) == path:
                runs[-1].append(e.path.rpartition("/")[2])
        labels = [c.label for c in node.elements]
        for seq in runs:
            expected = itertools.cycle(labels) if node.repeat else iter(labels)
            assert seq == [next(expected) for _ in seq], (path, seq)
    return result


def starts_at(result: RunResult, path: str, k: int) -> float:
    """Start time of the run of ``path`` active at tick ``k``."""
    return max(e.time for e in result.events
               if e.path == path and e.kind is EventKind.START and round(e.time / DT) <= k)


def scripts() -> st.SearchStrategy[list[dict[str, dict[str, bool]]]]:
    tick = st.fixed_dictionaries({"truth": st.fixed_dictionaries(
        {s: st.booleans() for s in SIGNALS})})
    return st.lists(tick, min_size=TICKS + 1, max_size=TICKS + 1)


@settings(max_examples=200, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_random_trees_obey_the_semantics(ir: SimpleNamespace, data: st.DataObject) -> None:
    root = data.draw(trees(ir))
    script = data.draw(scripts())
    result = check(root, script)
    assert result.ticks <= TICKS + 1
    assert math.isfinite(result.duration)
