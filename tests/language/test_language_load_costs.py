"""What keeps a large check cheap: no collector walks, no code generated, shared code."""

from __future__ import annotations

import gc

import pytest

from mdle.core.errors import CheckError
from mdle.lang import StringNode, conditions, load_text

PLAN = """
atom a(d = 1 m) = (go(1 m/s), range(0 deg) < d, 2 s)
atom b = (go(1 m/s), range(90 deg) < 2 m and not stalled, 3 s)
behavior main = ((a, a(2 m), b), never, inf)
run main
"""


def test_collector_state_is_restored() -> None:
    assert gc.isenabled()
    load_text(PLAN)
    assert gc.isenabled()
    with pytest.raises(CheckError):
        load_text("atom a = (go(1 m/s), nowhere, 1 s)")
    assert gc.isenabled()
    gc.disable()
    try:
        load_text(PLAN)
        assert not gc.isenabled()  # a caller's choice is kept
    finally:
        gc.enable()


def _walked() -> set[int]:
    """The ids of the objects the cycle collector's passes walk (frozen ones are not)."""
    return {id(o) for o in gc.get_objects()}


def test_a_loaded_program_is_frozen_out_of_the_collectors_passes() -> None:
    # A plan of 200,000 lines is millions of objects: walking them again on every full
    # pass held Ctrl-C for a quarter of a second each time
    program = load_text(PLAN)
    walked = _walked()
    nodes = [program, *program.elements.values()]
    assert nodes and not [n for n in nodes if id(n) in walked]


def test_checking_generates_no_interrupt_code() -> None:
    program = load_text(PLAN)
    xi = program.elements["a"].interrupt
    assert "test" not in xi.__dict__ and "source" not in xi.__dict__
    assert xi.source == "range(0 deg) < 1 m"
    assert callable(xi.test) and xi.test is xi.test  # compiled once, on first read


def test_interrupts_of_one_shape_share_their_code() -> None:
    conditions._code.cache_clear()
    program = load_text(PLAN)
    main = program.elements["main"]
    assert isinstance(main, StringNode)
    tests = [e.interrupt.test for e in main.elements]
    assert tests[0] is not tests[1]  # each has its own constants...
    assert tests[0].__code__ is tests[1].__code__  # ...in one compiled shape
    assert conditions._code.cache_info().misses == 2  # `< d` and `< 2 m and not stalled`


def _lines_run(text: str) -> int:
    """Return the lines of mdle's language package executed checking ``text`` (a count)."""
    import sys

    count = [0]

    def trace(frame, event, arg):  # type: ignore[no-untyped-def]
        if "mdle/lang/" not in frame.f_code.co_filename:
            return None
        if event == "line":
            count[0] += 1
        return trace

    sys.settrace(trace)
    try:
        with pytest.raises(CheckError):
            load_text(text)
    finally:
        sys.settrace(None)
    return count[0]


@pytest.mark.parametrize("line", [
    "atom a{k} = (go(0.3 m/s), unknown{k} < 1 m, 1 s)",   # a name in a condition
    "behavior a{k} = ((unknown{k}, a0), never, 1 s)",       # a name as an element
])
def test_unknown_names_cost_work_linear_in_the_file(line: str) -> None:
    # each unknown name used to rebuild the list of every name the file defines (and walk
    # it): 1k/2k/4k/8k lines took 0.76/2.05/7.3/29 s
    small, large = (_lines_run("\n".join(line.format(k=k) for k in range(n)))
                    for n in (300, 1200))
    assert large < 5 * small, (small, large)  # 4x the lines; quadratic work is 16x
