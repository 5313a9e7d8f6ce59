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

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st_h

from mdle.atoms.registry import Args, Context, Param, Registry, sensor
from mdle.core.backend import Observation, RobotLimits
from mdle.core.errors import CheckError
from mdle.core.pose import Pose
from mdle.core.units import LENGTH
from mdle.lang import StringNode, load_text, show_program, structure
from mdle.lang.check import never_ends
from tests.language.conftest import count_instances

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


# ---------------------------------------------------------------- parameterised chains


def parameter_chain(n: int, step: str, default: str = " = 0 m", first: str = "a") -> str:
    """``iK(a) = iK-1(a) or iK-1(<step>)``, one line per level (issue 26's family)."""
    lines = [f"interrupt i0(a{default}) = probe(a) < 1 m"]
    lines += [f"interrupt i{k}(a{default}) = i{k - 1}({first}) or i{k - 1}({step})"
              for k in range(1, n + 1)]
    return "\n".join(lines) + "\n"


def test_a_chain_of_required_parameters_is_checked_once_per_value(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # checked on its own, a definition's required parameter is NaN; NaN != NaN made every
    # lookup miss, so 16 lines made 2**17 instances (29 s at 23 lines, then MemoryError)
    made = count_instances(monkeypatch)
    load_text(parameter_chain(16, "a + 1 cm", default=""), "chain.mdle", _registry())
    assert made[0] < 200, made[0]  # 17 definitions, a few values each


def test_the_doubling_family_at_30_lines_checks_and_runs_in_linear_work(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from mdle import sim
    from mdle.runtime import Scheduler

    made = count_instances(monkeypatch)
    text = parameter_chain(30, "a + 1 cm") + "atom go1 = (go(0.3 m/s), i30, 5 s)\nrun go1\n"
    tracemalloc.start()
    try:
        program = load_text(text, "chain.mdle", _registry())
        sched = Scheduler(program.elements["go1"], sim.SimBackend(sim.load_world("default")))
        CALLS[0] = 0
        for _ in range(5):
            assert sched.tick()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert made[0] < 31 * 32, made[0]  # i_k is made once per value a + j cm, j <= 30 - k
    assert CALLS[0] <= 5 * 31, CALLS[0]  # one reading per distinct argument per tick
    assert peak < 50_000_000, peak


def test_values_that_never_repeat_are_refused_at_the_budget(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from mdle.lang.expansion import MAX_EXPANSION

    made = count_instances(monkeypatch)
    text = (parameter_chain(30, "a + 1 cm", " = 1 m", "a * 3")
            + "atom go1 = (go(0.3 m/s), i30, 5 s)\nrun go1\n")
    with pytest.raises(CheckError) as err:
        load_text(text, "chain.mdle", _registry())
    (d,) = err.value.diagnostics
    assert "expands the program past mdle's limit" in d.message
    assert f"{MAX_EXPANSION:,} syntax nodes" in d.message
    assert d.span is not None and d.span.file == "chain.mdle" and d.span.line > 1
    assert made[0] < MAX_EXPANSION, made[0]  # stopped when the budget ran out, not 2**30


def test_a_program_within_the_budget_is_not_refused() -> None:
    # a hundred different values passed to one small definition: nowhere near the budget
    lines = ["interrupt near(d = 1 m) = probe() < d"]
    lines += [f"atom a{k} = (go(0.3 m/s), near({k + 1} cm), 1 s)" for k in range(100)]
    program = load_text("\n".join(lines) + "\n", "many.mdle", _registry())
    assert len(program.elements) == 100


# ------------------------------------------------------ large expressions, interpreted

_LEAVES = st_h.sampled_from(["probe(1 m)", "probe(2 m)", "x", "y", "1 m", "5 m", "0 m"])


@st_h.composite
def _number(draw: st_h.DrawFn, depth: int = 3) -> str:
    if depth == 0 or draw(st_h.booleans()):
        return draw(_LEAVES)
    op = draw(st_h.sampled_from(["+", "-", "*"]))
    left = draw(_number(depth - 1))
    right = draw(_number(depth - 1)) if op != "*" else "2"
    return f"({left} {op} {right})"


@st_h.composite
def _condition(draw: st_h.DrawFn, depth: int = 3) -> str:
    if depth == 0 or draw(st_h.booleans()):
        op = draw(st_h.sampled_from(["<", "<=", ">", ">=", "==", "!="]))
        return f"{draw(_number())} {op} {draw(_number())}"
    op = draw(st_h.sampled_from(["and", "or", "xor", "not"]))
    if op == "not":
        return f"not ({draw(_condition(depth - 1))})"
    return f"({draw(_condition(depth - 1))}) {op} ({draw(_condition(depth - 1))})"


@settings(max_examples=60, deadline=None)
@given(_condition(), st_h.floats(-3, 3))
def test_interpreted_and_generated_interrupts_agree(text: str, x: float) -> None:
    import mdle.lang.conditions as conditions

    body = f"interrupt c = {text}\natom a = (go(0.3 m/s), c, 1 s)\n"
    ctx = Context(Observation(time=0.0, pose=Pose(x=x)), 0.0, 0.1, RobotLimits(1.0, 1.0, 3.0))
    program = load_text(body, "c.mdle", _registry())
    interrupt = program.elements["a"].interrupt
    node = interrupt.__dict__.get("_node")
    if node is None:  # folded to a constant at check time
        return
    generated = conditions._compile(node, as_bool=True)
    interpreted = conditions._interpret(node, as_bool=True)
    CALLS[0] = 0
    want = generated(ctx)
    generated_reads = CALLS[0]
    CALLS[0] = 0
    assert interpreted(ctx) is want
    assert CALLS[0] == generated_reads  # same short-circuits, same reads


def test_a_large_interrupt_is_interpreted_not_generated() -> None:
    import mdle.lang.conditions as conditions

    text = (parameter_chain(9, "a + 1 cm", " = 1 m", "a * 3")
            + "atom go1 = (go(0.3 m/s), i9, 5 s)\n")
    program = load_text(text, "chain.mdle", _registry())
    interrupt = program.elements["go1"].interrupt
    node = interrupt.__dict__["_node"]
    assert conditions._distinct_nodes(node, 10 ** 9) > conditions._GENERATE_LIMIT
    before = conditions._code.cache_info().misses
    CALLS[0] = 0
    assert interrupt.test(_ctx()) is False
    assert conditions._code.cache_info().misses == before  # no source compiled
    assert 400 < CALLS[0] <= 2 ** 9  # each distinct value read once (a few coincide)
