"""Shared definitions stay shared: no exponential expansion in check, show or run.

A chain ``interrupt iN = iN-1 or iN-1`` and a chain of behaviors each holding the
previous one twice describe trees with 2**N leaves but only N distinct definitions.
The checker, ``show`` and the scheduler must work on the definitions (a DAG), so their
cost grows with N, not 2**N. Costs are pinned by operation counts and sizes, never by
wall-clock time.
"""

from __future__ import annotations

import tracemalloc
import types

from mdle.atoms.registry import Args, Context, Param, Registry, sensor
from mdle.backend import Observation, Pose, RobotLimits
from mdle.lang import StringNode, load_text, show_program, structure
from mdle.lang.check import never_ends
from mdle.units import LENGTH

CALLS: list[int] = [0]


@sensor(Param("angle", LENGTH, 0.0), result=LENGTH)
def probe(args: Args, ctx: Context) -> float:
    """Count each reading (the tests bound how many a tick makes)."""
    CALLS[0] += 1
    return 5.0


def _registry() -> Registry:
    from mdle.atoms import default_registry

    return default_registry().merged(Registry.from_modules(types.SimpleNamespace(probe=probe)))


def interrupt_chain(n: int) -> str:
    lines = ["interrupt i0 = probe() < 1 m"]
    lines += [f"interrupt i{k} = i{k - 1} or i{k - 1}" for k in range(1, n + 1)]
    lines.append(f"atom a = (go(0.3 m/s), i{n}, 10 s)")
    return "\n".join(lines) + "\nrun a\n"


def behavior_chain(n: int, timer: str = "1 s") -> str:
    lines = [f"atom b0 = (go(0.3 m/s), never, {timer})"]
    lines += [f"behavior b{k} = ((b{k - 1}, b{k - 1}), never, inf)" for k in range(1, n + 1)]
    return "\n".join(lines) + f"\nrun b{n}\n"


def _ctx() -> Context:
    return Context(Observation(time=0.0, pose=Pose()), 0.0, 0.1, RobotLimits(1.0, 1.0, 3.0))


def test_interrupt_chain_of_30_compiles_once_per_definition_and_reads_each_once() -> None:
    program = load_text(interrupt_chain(30), "chain.mdle", _registry())
    test = program.elements["a"].interrupt.test
    CALLS[0] = 0
    assert test(_ctx()) is False  # every branch false: a tree would read 2**30 times
    assert CALLS[0] == 1


def test_interrupt_chain_still_short_circuits_and_fires() -> None:
    text = interrupt_chain(20).replace("probe() < 1 m", "probe() < 10 m")
    program = load_text(text, "chain.mdle", _registry())
    CALLS[0] = 0
    assert program.elements["a"].interrupt.test(_ctx()) is True
    assert CALLS[0] == 1


def test_behavior_chain_figures_are_exact_and_cheap() -> None:
    program = load_text(behavior_chain(30), "beh.mdle", _registry())
    e = program.elements["b30"]
    s = structure(e)
    assert (s.atoms, s.depth, s.duration, s.laws) == (2 ** 30, 31, float(2 ** 30), ("go",))
    assert not never_ends(e)


def test_never_ends_on_a_shared_chain_is_linear() -> None:
    text = behavior_chain(40, timer="inf")
    program = load_text(text, "beh.mdle", _registry())
    assert never_ends(program.elements["b40"])  # 2**40 paths: only memoised recursion ends


def test_show_prints_a_shared_definition_once() -> None:
    program = load_text(behavior_chain(25), "beh.mdle", _registry())
    text = show_program(program)
    lines = text.splitlines()
    assert len(lines) < 100, len(lines)
    assert "atoms: 33554432" in text
    assert "(as above)" in text


def test_scheduler_builds_slots_lazily() -> None:
    from mdle import sim
    from mdle.runtime import Scheduler

    program = load_text(behavior_chain(30), "beh.mdle", _registry())
    backend = sim.SimBackend(sim.load_world("ellipse"), sensing="exact")
    tracemalloc.start()
    try:
        sched = Scheduler(program.elements["b30"], backend)
        for _ in range(50):  # five 1 s atoms: the first of 2**30
            assert sched.tick()
        size, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 20_000_000, peak  # eager slots for 2**31 elements would never fit
    assert sched.path_str.count("/") == 30
    assert isinstance(program.elements["b30"], StringNode)
