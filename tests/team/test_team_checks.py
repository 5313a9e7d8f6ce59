"""Bad team input gets clear messages with places: never a traceback."""

from __future__ import annotations

from pathlib import Path

import pytest

from mdle.cli import main

#: Two robots facing each other 3 m apart in a walled room
WORLD = (Path(__file__).parent.parent / "data" / "duel.world.yaml").read_text(encoding="utf-8")


def _files(tmp_path: Path, plans: dict[str, str], team: str | None = None) -> Path:
    (tmp_path / "duel.world.yaml").write_text(WORLD)
    for name, text in plans.items():
        (tmp_path / f"{name}.mdle").write_text(text)
    robots = "".join(f"  {n}: {n}.mdle\n" for n in plans)
    path = tmp_path / "team.yaml"
    path.write_text(team if team is not None else f"world: duel.world.yaml\nrobots:\n{robots}")
    return path


AHEAD = "atom ahead = (go(0.4 m/s), stalled, 20 s)\nplan main = ((ahead), never, 30 s)\n"
STILL = "atom still = (stop, never, 10 s)\nplan main = ((still), never, 12 s)\n"


def test_robots_that_collide_are_reported_with_both_names(tmp_path: Path,
                                                          capsys: pytest.CaptureFixture[str]
                                                          ) -> None:
    team = _files(tmp_path, {"red": AHEAD, "blue": AHEAD})
    assert main(["run", "--team", str(team), "--trace", str(tmp_path / "t.jsonl")]) == 3
    out = capsys.readouterr().out
    assert "red: " in out and "robots `red` and `blue` touched" in out
    assert "robots `blue` and `red` touched" in out
    from mdle.record.load import read_trace

    hits = read_trace(tmp_path / "t.red.jsonl").collisions()
    assert hits and hits[0]["obstacle"] == "blue" and hits[0]["kind"] == "robot"


def test_a_robot_standing_still_is_hit_and_says_by_whom(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    team = _files(tmp_path, {"red": AHEAD, "blue": STILL})
    assert main(["run", "--team", str(team)]) == 3
    out = capsys.readouterr().out
    assert "robots `red` and `blue` touched" in out and "robots `blue` and `red` touched" in out


def test_a_team_file_naming_a_robot_the_world_lacks(tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    team = _files(tmp_path, {"red": STILL, "green": STILL})
    assert main(["run", "--team", str(team)]) == 1
    err = capsys.readouterr().err
    assert "robot `green` is not in world `duel`" in err and "red, blue" in err


def test_robots_placed_overlapping_by_the_team_file(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    team = _files(tmp_path, {"red": STILL, "blue": STILL},
                  "world: duel.world.yaml\nrobots:\n  red: red.mdle\n"
                  "  blue: {plan: blue.mdle, start: [0.2, 0.1, 0]}\n")
    assert main(["run", "--team", str(team)]) == 1
    err = capsys.readouterr().err
    assert "robots `red` and `blue` overlap at their starts" in err
    assert "Traceback" not in err


def test_a_channel_no_one_sends_on_is_a_warning(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    waits = "atom hold = (stop, received(go), 2 s)\nplan main = ((hold), never, 5 s)\n"
    team = _files(tmp_path, {"red": waits, "blue": STILL})
    assert main(["run", "--team", str(team)]) == 0
    err = capsys.readouterr().err
    assert "red.mdle:1:20: warning: no robot of the team sends on channel `go`" in err


def test_a_message_of_the_wrong_unit_is_an_error_at_both_places(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    sends = "atom tell = (stop, never, 1 s, send(gap, 2 s))\nplan main = ((tell), never, 5 s)\n"
    reads = ("atom hold = (stop, message(gap) < 1 m, 2 s)\n"
             "plan main = ((hold), never, 5 s)\n")
    team = _files(tmp_path, {"red": sends, "blue": reads})
    assert main(["run", "--team", str(team)]) == 1
    err = capsys.readouterr().err
    assert "blue.mdle:1:20: error: `message(gap)` is used as a length here, but robot `red` " \
           "sends a time on `gap` (" in err and "red.mdle:1:32" in err


def test_two_senders_of_different_units_and_message_of_pose(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a = ("atom tell = (stop, never, 1 s, send(gap, 2 s), send(pose))\n"
         "plan main = ((tell), never, 5 s)\n")
    b = ("atom tell = (stop, message(pose) > 1 m, 1 s, send(gap, 2 m))\n"
         "plan main = ((tell), never, 5 s)\n")
    team = _files(tmp_path, {"red": a, "blue": b})
    assert main(["run", "--team", str(team)]) == 1
    err = capsys.readouterr().err
    assert "robot `blue` sends a length on `gap`, but robot `red` sends a time there" in err
    assert "channel `pose` carries poses, not numbers" in err


def test_a_robot_the_team_lacks_named_by_range_to(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    near = "atom hold = (stop, range_to(green) < 1 m, 2 s)\nplan main = ((hold), never, 5 s)\n"
    team = _files(tmp_path, {"red": near, "blue": STILL})
    assert main(["run", "--team", str(team)]) == 1
    err = capsys.readouterr().err
    assert "red.mdle:1:20: error: `range_to` names robot `green`, which is not in the team" in err
    assert "the robots: `red`, `blue`" in err


@pytest.mark.parametrize(("team", "message"), [
    ("world: duel.world.yaml\n", "a team file needs `robots:`"),
    ("world: duel.world.yaml\nrobots: {red: {plan: red.mdle, sett: []}}\n",
     "unknown key `sett` (did you mean `set`?)"),
    ("world: duel.world.yaml\nmessages: {loss: 2}\nrobots: {red: red.mdle}\n",
     "messages.loss: a probability is at most 1"),
    ("world: duel.world.yaml\nrobots: {red: {element: main}}\n", "missing key `plan`"),
    ("world: default\nrobots: {red: red.mdle}\n", "world `default` has no `robots:` list"),
    # checked as --rate is: 1e308 never ended (t + 1e-308 == t), 1e6 over-ran
    ("world: duel.world.yaml\nrate: 1e308\nrobots: {red: red.mdle}\n",
     "rate: the rate must be from 0.001 to 1,000 Hz, got 1e308"),
    ("world: duel.world.yaml\nrate: 1e6\nrobots: {red: red.mdle}\n",
     "rate: the rate must be from 0.001 to 1,000 Hz, got 1e6"),
])
def test_team_file_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str], team: str,
                          message: str) -> None:
    path = _files(tmp_path, {"red": STILL}, team)
    assert main(["run", "--team", str(path)]) == 1
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_robot_plan_options_with_a_world(tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    _files(tmp_path, {"red": STILL, "blue": STILL})
    world = str(tmp_path / "duel.world.yaml")
    assert main(["run", "--world", world, "--robot-plan", f"red={tmp_path / 'red.mdle'}",
                 "--robot-plan", f"blue={tmp_path / 'blue.mdle'}"]) == 0
    assert "red: main ended (completed)" in capsys.readouterr().out
    assert main(["run", "--world", world, "--robot-plan", "red"]) == 1
    assert "--robot-plan takes NAME=PLAN.mdle" in capsys.readouterr().err
    assert main(["run"]) == 2
    assert main(["run", "--robot-plan", f"red={tmp_path / 'red.mdle'}"]) == 1
    assert "a team needs a world with robots" in capsys.readouterr().err


@pytest.mark.parametrize(("atom", "message"), [
    ("(stop, never, 1 s, send(pose, 1 m))", "the channel `pose` carries the robot's pose"),
    ("(stop, never, 1 s, send(gap))", "`send(gap)` needs a value to send"),
    ("(stop, never, 1 s, send(gap, stalled))", "`send` sends a number, found a condition"),
    ("(stop, never, 1 s, send(1, 2))", "expected `send(channel, value)` or `send(pose)`"),
    ("(stop, never, 1 s, send(a, 1, 2))", "`send` takes a channel and one value"),
    ("(stop, received(1 m), 1 s)", "`channel` of `received` takes a channel name"),
    ("(stop, never, 1 s, 3)", "an atom is (control law, interrupt, timer); this has 4 parts"),
])
def test_send_and_receive_errors_in_a_plan(atom: str, message: str) -> None:
    from mdle.core.errors import MdleError
    from mdle.lang import load_text

    with pytest.raises(MdleError, match=message.replace("(", r"\(").replace(")", r"\)")):
        load_text(f"atom a = {atom}\n")


def test_a_plan_that_talks_runs_alone_too() -> None:
    from mdle import sim
    from mdle.lang import load_text
    from mdle.runtime import run_named

    program = load_text("atom tell = (go(0.2 m/s), received(go), 2 s, send(pose), send(go, 1))\n"
                        "atom near = (stop, range_to(other) < 1 m, 1 s)\n"
                        "plan main = ((tell, near), never, 10 s)\n")
    result = run_named(program, None, sim.SimBackend(sim.load_world("default")))
    assert result.ok and [t.cause.value for t in result.terminations][:2] == ["timer", "timer"]


def test_show_lists_what_an_atom_sends(capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.lang import load_text, show_program

    program = load_text("atom tell(ch = leg) = (stop, never, 1 s, send(ch, 2 * x), send(pose))\n"
                        "plan main = ((tell(leg2)), never, 5 s)\n")
    assert "[never | 1 s]  send(leg2, 2 * x), send(pose)" in show_program(program, "main")


def test_a_robot_without_a_plan_stands_where_it_starts(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    team = _files(tmp_path, {"red": AHEAD})  # blue has no plan: an obstacle
    assert main(["run", "--team", str(team)]) == 3
    out = capsys.readouterr().out
    assert "robots `red` and `blue` touched at x 2.50 m" in out and "blue:" not in out


def test_mdle_check_checks_a_team_file_whole(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    near = "atom hold = (stop, range_to(green) < 1 m, 2 s)\nplan main = ((hold), never, 5 s)\n"
    team = _files(tmp_path, {"red": near, "blue": STILL})
    assert main(["check", str(team)]) == 1
    assert "`range_to` names robot `green`, which is not in the team" in capsys.readouterr().out
    waits = "atom hold = (stop, received(go), 2 s)\nplan main = ((hold), never, 5 s)\n"
    team = _files(tmp_path, {"red": waits, "blue": STILL})
    assert main(["check", str(team)]) == 0
    assert "checked 1 file: 0 errors, 1 warning" in capsys.readouterr().out
    assert main(["check", "--strict", str(team)]) == 1


def test_worlds_show_draws_a_team_world_s_robots(tmp_path: Path) -> None:
    _files(tmp_path, {})
    out = tmp_path / "duel.png"
    # the world has no `start:`; its robots are drawn where they start, each with its scan
    assert main(["worlds", "show", str(tmp_path / "duel.world.yaml"), "-o", str(out)]) == 0
    assert out.stat().st_size > 0


def test_a_point_robot_in_a_team_is_a_warning_naming_it(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    team = _files(tmp_path, {"red": STILL, "blue": STILL})
    world = tmp_path / "duel.world.yaml"
    world.write_text(WORLD.replace("robot: pioneer2dx", "robot: ideal"))
    assert main(["check", str(team)]) == 0
    out = capsys.readouterr().out
    assert "warning: robot `red` of world `duel` is a point (profile `ideal`, radius 0 m)" in out
    assert "robot `blue`" in out and "1 file: 0 errors, 2 warnings" in out
    world.write_text(WORLD)
    assert main(["check", str(team)]) == 0
    assert "is a point" not in capsys.readouterr().out
