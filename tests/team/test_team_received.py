"""`received` counts only messages that arrived after the tick its element started in."""

from __future__ import annotations

from pathlib import Path

from mdle.runtime import Recorder
from mdle.sim.team import TeamSim
from mdle.team.file import load_team, read_team
from mdle.team.run import TeamRun

#: Two robots facing each other 3 m apart in a walled room
WORLD = (Path(__file__).parent.parent / "data" / "duel.world.yaml").read_text(encoding="utf-8")

# red sends `go` at one tick only (its atom runs for exactly one tick at 10 Hz)
ONCE = ("atom tell = (stop, never, 0.1 s, send(go, 1))\n"
        "plan main = ((tell, (stop, never, 8 s)), never, 10 s)\n")
# blue waits three times in a row
WAITS = ("atom hold = (stop, received(go), 2 s)\n"
         "plan main = ((hold, hold, hold), never, 10 s)\n")


def _run(tmp_path: Path, red: str, blue: str) -> dict[str, Recorder]:
    (tmp_path / "duel.world.yaml").write_text(WORLD)
    (tmp_path / "red.mdle").write_text(red)
    (tmp_path / "blue.mdle").write_text(blue)
    team_file = tmp_path / "team.yaml"
    team_file.write_text("world: duel.world.yaml\nrobots:\n  red: red.mdle\n  blue: blue.mdle\n")
    spec = read_team(team_file)
    team = load_team(spec)
    sim_team = TeamSim(team.world, team.world.robots, seed=1, rules=spec.rules)
    recorders = {n: Recorder() for n in team.elements}
    TeamRun(sim_team, team.elements, 10.0, 12.0, {n: [r] for n, r in recorders.items()}).run()
    return recorders


def _hold_ends(rec: Recorder) -> list[tuple[str, str, float]]:
    """(path, cause, time) of every end of a `hold`."""
    return [(e.path, e.cause.value, round(e.time, 6)) for e in rec.events
            if e.kind.value == "end" and e.cause is not None and e.path.startswith("main/hold")]


def test_one_message_ends_one_wait_and_the_next_waits_for_a_new_one(tmp_path: Path) -> None:
    rec = _run(tmp_path, ONCE, WAITS)
    ends = _hold_ends(rec["blue"])
    # sent at tick 0 (t = 0), arrived at tick 1: the first wait ends then, by its
    # interrupt; the two after it started at that tick and see no newer message
    assert ends == [("main/hold", "interrupt", 0.1), ("main/hold#2", "timer", 2.1),
                    ("main/hold#3", "timer", 4.1)]


def test_a_message_each_tick_ends_each_wait_a_tick_apart(tmp_path: Path) -> None:
    often = ("atom tell = (stop, never, 1 s, send(go, 1))\n"
             "plan main = ((tell, (stop, never, 8 s)), never, 10 s)\n")
    rec = _run(tmp_path, often, WAITS)
    ends = _hold_ends(rec["blue"])
    assert ends == [("main/hold", "interrupt", 0.1), ("main/hold#2", "interrupt", 0.2),
                    ("main/hold#3", "interrupt", 0.3)]


def test_a_value_sent_may_remember_where_its_atom_started(tmp_path: Path) -> None:
    # red drives 2 s, then sends how far it has gone since `tell` started: 0 at first,
    # over 0.2 m about 0.4 s later (at 0.5 m/s); blue waits for that
    red = ("atom tell = (go(0.5 m/s), never, 3 s, send(gap, x - at_start(x)))\n"
           "plan main = (((go(0.5 m/s), never, 2 s), tell), never, 10 s)\n")
    blue = "plan main = (((stop, message(gap) > 0.2 m, 8 s)), never, 10 s)\n"
    (end,) = [e for e in _run(tmp_path, red, blue)["blue"].events
              if e.kind.value == "end" and e.path == "main/stop"]
    assert end.cause is not None and end.cause.value == "interrupt" and 2.3 < end.time < 2.8
