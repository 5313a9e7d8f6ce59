"""`:save` writes the world beside the plan, so that `mdle run FILE` runs the same thing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mdle.cli import main
from mdle.repl.session import Session
from mdle.sim.world_yaml import read_world


def test_save_writes_the_world_beside_the_plan_and_mdle_run_uses_it(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    session = Session("ellipse")
    session.define("atom hug = (follow_boundary(side = right, rc = 1 m, v = 0.5 m/s), never, 5 s)")
    session.define("run hug")
    plan = tmp_path / "hug.mdle"
    session.save(plan)
    world_file = tmp_path / "hug.world.yaml"
    assert world_file.is_file()
    saved = read_world(world_file)
    assert saved.name == session.world.name == "ellipse"
    assert saved.start_pose == pytest.approx(session.world.start_pose)
    assert saved.robot.name == session.world.robot.name
    assert len(saved.obstacles) == len(session.world.obstacles)
    # the saved plan runs in the saved world: no collision with the default room's walls
    trace = tmp_path / "t.jsonl"
    assert main(["run", str(plan), "--trace", str(trace)]) == 0
    assert "collided: no" in capsys.readouterr().out
    header = json.loads(trace.read_text().splitlines()[0])
    assert header["world"]["name"] == "ellipse"


def test_the_world_file_is_named_after_the_plan() -> None:
    assert Session.world_path("a/hug.mdle") == "a/hug.world.yaml"
    assert Session.world_path("plan") == "plan.world.yaml"
