"""The team examples of plans/team/ run end to end, as docs/teams.md says they do."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mdle.runtime import Recorder
from mdle.sim.team import TeamSim
from mdle.team.file import load_team, read_team
from mdle.team.run import TeamRun

TEAM = Path(__file__).resolve().parents[2] / "plans" / "team"


def _run(name: str, until: float | None = None, **changes: Any
         ) -> tuple[TeamRun, dict[str, Recorder]]:
    import dataclasses

    spec = dataclasses.replace(read_team(TEAM / name), **changes)
    team = load_team(spec)
    assert not team.warnings, team.warnings
    sim_team = TeamSim(team.world, team.world.robots, seed=spec.seed or 0, rules=spec.rules)
    recorders = {n: Recorder() for n in team.elements}
    run = TeamRun(sim_team, team.elements, 10.0, until if until is not None else spec.until,
                  {n: [r] for n, r in recorders.items()})
    run.run()
    return run, recorders


def _true_path(r: Recorder) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = [x for x in r.samples if x.true_x is not None]
    return (np.array([x.time for x in s]), np.array([x.true_x for x in s]),
            np.array([x.true_y for x in s]))


def _distance_to_polyline(px: float, py: float, xs: np.ndarray, ys: np.ndarray) -> float:
    a = np.column_stack([xs[:-1], ys[:-1]])
    b = np.column_stack([xs[1:], ys[1:]])
    ab = b - a
    ll = np.maximum((ab * ab).sum(axis=1), 1e-12)
    u = np.clip(((np.array([px, py]) - a) * ab).sum(axis=1) / ll, 0.0, 1.0)
    near = a + ab * u[:, None]
    return float(np.hypot(near[:, 0] - px, near[:, 1] - py).min())


def test_the_follower_keeps_to_the_leader_s_path_for_a_minute_without_collision() -> None:
    run, rec = _run("pair.team.yaml", until=60.0)
    results = run.results
    assert all(not r.collided and r.fault is None for r in results.values())
    assert results["leader"].duration == pytest.approx(60.0, abs=0.11)
    t, lx, ly = _true_path(rec["leader"])
    _, fx, fy = _true_path(rec["follower"])
    # the leader drives its loop round the pillar: most of 18 m in the minute
    assert results["leader"].distance > 15.0
    worst_path = worst_gap = 0.0
    # it starts 1.5 m behind the leader, on the line the leader leaves along: from where
    # the leader started on, it must keep to the leader's path
    on = int(np.flatnonzero(np.hypot(fx - lx[0], fy - ly[0]) < 0.05)[0])
    assert t[on] < 8.0
    for i in range(on, len(t)):
        worst_path = max(worst_path, _distance_to_polyline(fx[i], fy[i], lx[: i + 1],
                                                           ly[: i + 1]))
        if t[i] > 10.0:  # once it has closed up on the leader
            worst_gap = max(worst_gap, math.hypot(fx[i] - lx[i], fy[i] - ly[i]))
    assert worst_path < 0.1, f"the follower strayed {worst_path:.3f} m from the leader's path"
    assert worst_gap < 2.0, f"the follower fell {worst_gap:.2f} m behind"
    assert results["follower"].distance > 14.0


def test_the_waiter_leaves_only_after_the_go_message() -> None:
    run, rec = _run("wait.team.yaml")
    results = run.results
    assert all(r.ok and not r.collided for r in results.values())
    scout_sends = [s.time for s in rec["scout"].samples if s.path.endswith("/signal")]
    t, x, _ = _true_path(rec["waiter"])
    moved = t[np.flatnonzero(np.abs(x - x[0]) > 1e-6)[0]]
    assert scout_sends and moved > scout_sends[0] + 0.05  # the message came a tick later
    hold = next(e for e in results["waiter"].terminations if e.path == "main/hold")
    assert hold.cause.value == "interrupt" and hold.time == pytest.approx(scout_sends[0] + 0.1)
    assert results["waiter"].distance > 1.5


def test_without_the_message_the_waiter_never_leaves() -> None:
    import dataclasses

    spec = read_team(TEAM / "wait.team.yaml")
    alone = dataclasses.replace(spec, members=tuple(m for m in spec.members
                                                    if m.name == "waiter"), until=20.0)
    team = load_team(alone)
    assert any("no robot of the team sends on channel `go`" in w.message
               for w in team.warnings)
    sim_team = TeamSim(team.world, team.world.robots, seed=1)
    run = TeamRun(sim_team, team.elements, 10.0, 20.0)
    result = run.run()["waiter"]
    assert result.distance < 1e-6 and not result.collided


def test_the_relay_passes_the_baton_down_the_line_within_radio_range() -> None:
    run, rec = _run("relay.team.yaml")
    results = run.results
    assert all(r.ok and not r.collided for r in results.values())
    starts = {}
    for name in ("second", "third"):
        wait = next(e for e in results[name].terminations if e.path == "main/wait")
        assert wait.cause.value == "interrupt"
        starts[name] = wait.time
    assert 0.0 < starts["second"] < starts["third"]
    # each runner starts when the one before has run more than a metre and is within
    # 2.5 m (the radio's range)
    for before, after in (("first", "second"), ("second", "third")):
        t, bx, by = _true_path(rec[before])
        _, ax, ay = _true_path(rec[after])
        i = int(np.searchsorted(t, starts[after] - 0.1 - 1e-9))
        assert bx[i] - bx[0] > 1.0
        assert math.hypot(bx[i] - ax[i], by[i] - ay[i]) <= 2.5 + 1e-9
    assert all(r.distance > 2.0 for r in results.values())


def test_with_a_short_radio_the_relay_stops_at_the_first_runner() -> None:
    from mdle.core.messages import DeliveryRules

    run, _ = _run("relay.team.yaml", rules=DeliveryRules(range=1.0), until=30.0)
    results = run.results
    assert results["second"].distance < 1e-6 and results["third"].distance < 1e-6


def test_every_example_runs_from_the_command_line(tmp_path: Path) -> None:
    from mdle.cli import main

    for name in ("pair.team.yaml", "wait.team.yaml", "relay.team.yaml"):
        out = tmp_path / name.replace(".team.yaml", ".png")
        code = main(["run", "--team", str(TEAM / name), "--until", "20", "-q",
                     "--trace", str(tmp_path / "run.jsonl"), "--plot", str(out)])
        assert code == 0 and out.stat().st_size > 0
    assert (tmp_path / "run.first.jsonl").exists() and (tmp_path / "run.third.jsonl").exists()


def test_a_team_run_is_drawn_and_animated_from_its_traces(tmp_path: Path) -> None:
    from mdle.cli import main
    from mdle.record.load import read_trace
    from mdle.view.team_animate import animate_team

    assert main(["run", "--team", str(TEAM / "wait.team.yaml"), "-q",
                 "--trace", str(tmp_path / "w.jsonl")]) == 0
    paths = [str(tmp_path / "w.scout.jsonl"), str(tmp_path / "w.waiter.jsonl")]
    sent = [m for m in read_trace(paths[0]).extra if m.get("type") == "message"]
    heard = [m for m in read_trace(paths[1]).extra if m.get("type") == "message"]
    assert sent and all(m["dir"] == "sent" and m["channel"] == "go" for m in sent)
    assert heard and heard[0]["dir"] == "received" and heard[0]["from"] == "scout"
    assert heard[0]["t"] == pytest.approx(sent[0]["t"] + 0.1)  # the next tick
    assert main(["plot", *paths, "-o", str(tmp_path / "team.png")]) == 0
    out = animate_team([read_trace(p) for p in paths], None, tmp_path / "team.gif",
                       max_frames=4)
    assert Path(out).stat().st_size > 0


def test_rate_comes_from_the_command_line_then_the_team_file_then_10_hz(tmp_path: Path) -> None:
    """--rate wins over the team file's rate: even when it is the default value, 10 Hz."""
    import json

    from mdle.cli import main

    team = tmp_path / "t.team.yaml"
    team.write_text((TEAM / "wait.team.yaml").read_text().replace("robots:", "rate: 20\nrobots:")
                    .replace("wait.world.yaml", str(TEAM / "wait.world.yaml"))
                    .replace(": scout.mdle", f": {TEAM / 'scout.mdle'}")
                    .replace(": waiter.mdle", f": {TEAM / 'waiter.mdle'}"))

    def rate(*args: str) -> float:
        trace = tmp_path / "r.jsonl"
        assert main(["run", "--team", str(team), "--until", "1", "-q", "--trace", str(trace),
                     *args]) == 0
        with open(tmp_path / "r.scout.jsonl") as f:
            return float(json.loads(f.readline())["rate"])

    assert rate() == 20.0
    assert rate("--rate", "10") == 10.0
    assert rate("--rate", "50") == 50.0
