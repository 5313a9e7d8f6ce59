"""Worlds of many obstacles: the budget on their number (issues 26 and 27)."""

from __future__ import annotations

import pytest

from mdle.errors import WorldError
from mdle.sim import world_yaml
from mdle.sim.world_obstacles import MAX_OBSTACLES
from mdle.sim.world_yaml import parse_world


def _world(n: int) -> str:
    """A world of ``n`` circles, each an alias of the first (cheap to parse)."""
    rest = ", *c" * (n - 1)
    return ("name: many\n"
            "obstacles: [&c {type: circle, center: [5, 5], radius: 1}" + rest + "]\n")


def test_a_world_past_the_budget_is_refused_at_its_obstacles_before_any_is_built(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def never(*_: object) -> None:
        raise AssertionError("an obstacle was built")

    monkeypatch.setattr(world_yaml, "_obstacle", never)
    with pytest.raises(WorldError) as err:
        parse_world(_world(MAX_OBSTACLES + 1), file="many.yaml")
    msg = str(err.value)
    assert msg.startswith("many.yaml:2:12: error: obstacles: ")
    assert f"lists {MAX_OBSTACLES + 1:,} obstacles; a world holds at most {MAX_OBSTACLES:,}" in msg


def test_a_world_at_the_budget_passes_it(monkeypatch: pytest.MonkeyPatch) -> None:
    class Built(Exception):
        pass

    def first(*_: object) -> None:
        raise Built

    monkeypatch.setattr(world_yaml, "_obstacle", first)
    with pytest.raises(Built):
        parse_world(_world(MAX_OBSTACLES))
