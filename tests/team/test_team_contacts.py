"""Two robots of a team driven into each other at speed: the contact at any rate.

A real team run (plans, world file, traces): the collision records give the same time
and places at 10 Hz and at 0.5 Hz, halfway between the starts, as the two robots are
alike. Before the team cut its ticks where robots could meet, the robot moving first in
a tick covered more ground, and a slow rate moved the contact by tenths of a metre.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pytest

from mdle.cli import main
from mdle.record.load import read_trace

#: Two robots facing each other 3 m apart in a walled room
WORLD = (Path(__file__).parent.parent / "data" / "duel.world.yaml").read_text(encoding="utf-8")
AHEAD = "atom ahead = (go(1.2 m/s), stalled, 20 s)\nplan main = ((ahead), never, 30 s)\n"


def _contacts(tmp_path: Path, rate: str) -> dict[str, Mapping[str, Any]]:
    d = tmp_path / rate
    d.mkdir()
    (d / "duel.world.yaml").write_text(WORLD)
    (d / "red.mdle").write_text(AHEAD)
    (d / "blue.mdle").write_text(AHEAD)
    (d / "team.yaml").write_text(f"world: duel.world.yaml\nrate: {rate}\n"
                                 "robots:\n  red: red.mdle\n  blue: blue.mdle\n")
    assert main(["run", "--team", str(d / "team.yaml"), "-q",
                 "--trace", str(d / "t.jsonl")]) == 3
    out = {}
    for name in ("red", "blue"):
        (hit,) = read_trace(d / f"t.{name}.jsonl").collisions()
        out[name] = hit
    return out


def test_robots_driven_into_each_other_meet_halfway_at_any_rate(tmp_path: Path) -> None:
    fast, slow = _contacts(tmp_path, "10"), _contacts(tmp_path, "0.5")
    for hits in (fast, slow):
        assert hits["red"]["obstacle"] == "blue" and hits["blue"]["obstacle"] == "red"
        assert hits["red"]["kind"] == hits["blue"]["kind"] == "robot"
        # pioneer2dx: radius 0.25 m; alike robots from 3 m apart touch at 1.25 and 1.75
        assert hits["red"]["x"] == pytest.approx(1.25, abs=1e-3)
        assert hits["blue"]["x"] == pytest.approx(1.75, abs=1e-3)
        assert hits["red"]["t"] == pytest.approx(hits["blue"]["t"], abs=1e-3)
    assert slow["red"]["t"] == pytest.approx(fast["red"]["t"], abs=1e-3)
