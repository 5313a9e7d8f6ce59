"""The cycle collector around large builds (mdle/core/collector.py)."""

from __future__ import annotations

import gc
import weakref

import pytest

from mdle.core import collector
from mdle.core.collector import collector_paused, release_in_slices


class Node:
    """A tracked object of its own (the collector walks instances of plain classes)."""


def test_the_collector_is_paused_in_the_block_and_what_it_built_is_frozen() -> None:
    assert gc.isenabled()
    with collector_paused():
        assert not gc.isenabled()
        built = [Node() for _ in range(100)]
    assert gc.isenabled()
    walked = {id(o) for o in gc.get_objects()}
    assert not [n for n in built if id(n) in walked]
    gc.disable()
    try:
        with collector_paused():
            inner = [Node() for _ in range(10)]
        assert not gc.isenabled()  # a caller's choice is kept: nothing frozen
        assert all(id(n) in {id(o) for o in gc.get_objects()} for n in inner)
    finally:
        gc.enable()


def test_garbage_made_before_the_block_is_collected_not_frozen() -> None:
    # a long-lived process (a sweep's worker, the REPL) loads plan after plan: a cycle
    # left by the last run must not be frozen with the next plan, never to be freed
    cycle = Node()
    cycle.me = cycle  # type: ignore[attr-defined]
    gone = weakref.ref(cycle)
    del cycle
    with collector_paused():
        pass
    assert gone() is None


def test_an_interruption_in_the_block_freezes_too() -> None:
    with pytest.raises(KeyboardInterrupt), collector_paused():
        built = [Node() for _ in range(10)]
        raise KeyboardInterrupt
    assert gc.isenabled()
    walked = {id(o) for o in gc.get_objects()}
    assert not [n for n in built if id(n) in walked]


@pytest.mark.parametrize("size", [0, 1, 4, 5, 13])
def test_release_in_slices_empties_lists_and_dicts_and_frees_what_only_they_held(
        monkeypatch: pytest.MonkeyPatch, size: int) -> None:
    monkeypatch.setattr(collector, "RELEASE_SLICE", 4)  # several slices for 5 and 13
    kept = Node()
    items = [Node() for _ in range(size)]
    refs = [weakref.ref(n) for n in items]
    listed = [*items, kept]
    table = {i: n for i, n in enumerate(listed)}
    del items
    release_in_slices(table)
    assert table == {}
    assert all(r() is not None for r in refs)  # the list still holds them
    release_in_slices(listed)
    assert listed == []
    assert [r() for r in refs] == [None] * size  # freed as their last holder let go
    assert isinstance(kept, Node)
