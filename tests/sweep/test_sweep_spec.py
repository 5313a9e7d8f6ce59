"""Study specs: located errors (file:line:col, key path), expansion, keys, start rules."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mdle.sim import load_world
from mdle.sweep import SpecError, expand, parse_study, read_study
from mdle.sweep.tasks import start_poses

PLAN = ("atom follow(rc = 1 m, kf = 0.5) = (follow_boundary(rc = rc, v = 1 m/s, kf = kf), "
        "never, 4 s)\\n")
HEAD = f'plan: {{text: "{PLAN}"}}\nentry: follow\n'


def error(text: str, base: Path | None = None) -> str:
    with pytest.raises(SpecError) as err:
        parse_study(text, file="s.yaml", base=base or Path("."))
    return str(err.value)


@pytest.mark.parametrize(("body", "expected"), [
    ("worlds: [ellipse]\nsensng: [scan]\n", "s.yaml:4:1: error: sensng: unknown key `sensng` "
                                             "(did you mean `sensing`?)"),
    ("rates: [50, -1]\n", "s.yaml:3:13: error: rates[1]: must be positive, got -1"),
    ("sensing: [sonar]\n", "sensing[0]: unknown value 'sonar'; one of: scan, exact"),
    ("parameters: {grid: {kf: []}}\n", "parameters.grid.kf: is empty"),
    ("parameters: {grid: {kf: [1, 1]}}\n", "parameters.grid.kf[1]: repeats an earlier value"),
    ("parameters: {grid: {kff: [1]}}\n", "parameters.grid.kff[0]: no definition"),
    ("parameters: {grid: {rc: [1 s]}}\n", "parameters.grid.rc[0]:"),
    ("parameters: {random: {count: 3, ranges: {kf: [2, 1]}}}\n",
     "parameters.random.ranges.kf: the range [2, 1] is empty"),
    ("worlds: [elipse]\n", "worlds[0]: no reference world or world file `elipse` "
                           "(did you mean `ellipse`?)"),
    ("worlds: []\n", "worlds: is empty"),
    ("seeds: {first: 3}\n", "seeds: missing key `count`"),
    ("starts: {random: {count: 0}}\n", "starts.random.count: must be at least 1, got 0"),
    ("starts: {random: {count: 2, distance: [3, 1]}}\n", "starts.random.distance: the range"),
    ("starts: {grid: {x: [0], y: [1]}}\n", "starts.grid: missing key `theta`"),
    ("starts: [[0, 0]]\n", "starts.fixed[0]: expected [x, y, theta]"),
    ("robots: [wheelchair]\n", "robots[0]: unknown robot profile"),
    ("robots: [{profile: ideal, max_sped: 2}]\n", "robots[0].max_sped: unknown key"),
    ("keep_traces: yes please\n", "keep_traces: expected true or false"),
    # numbers that allocated, overflowed or failed late (issue 26)
    ("rates: [1e309]\n", "rates[0]: expected a finite number, got 1e309"),
    ("rates: [0.0000001]\n", "rates[0]: the rate must be from 0.001 to 1,000 Hz, got 1e-07"),
    ("seeds: {count: 300000000000000000000}\n",
     "seeds.count: must be at most 100000, got 300000000000000000000"),
    ("seeds: {count: 2147483648}\n", "seeds.count: must be at most 100000, got 2147483648"),
    ("seeds: [9223372036854775808]\n",
     "seeds[0]: must be at most 9223372036854775807, got 9223372036854775808"),
    ("seeds: {count: 10, first: 9223372036854775800}\n", "seeds.first: must be at most"),
    ("starts: {random: {count: 10000000000000000000000000000000000000000}}\n",
     "starts.random.count: must be at most 10000000, got a number of 41 digits"),
    ("worlds: [{generated: {seed: 1, count: 10000000000000000000000000000000000000000}}]\n",
     "worlds[0].generated.count: must be at most 100000"),
    ("parameters: {random: {count: 100000000000000000000, ranges: {kf: [1, 2]}}}\n",
     "parameters.random.count: must be at most 100000"),
    ("worlds: [" + "w" * 300 + "]\n", "worlds[0]: no reference world `www"),
])
def test_bad_specs_name_the_key_path(body: str, expected: str) -> None:
    assert expected in error(HEAD + body)


def test_missing_files_are_named(tmp_path: Path) -> None:
    assert "plan: plan file not found: nowhere.mdle" in error("plan: nowhere.mdle\n", tmp_path)
    assert "worlds[1]: no reference world or world file `my.yaml`" in error(
        HEAD + "worlds: [ellipse, my.yaml]\n", tmp_path)
    assert "robots[0]: robot profile file not found: r.yaml" in error(
        HEAD + "robots: [r.yaml]\n", tmp_path)
    with pytest.raises(SpecError, match="study spec not found"):
        read_study(tmp_path / "none.yaml")


def test_plan_errors_keep_their_own_location(tmp_path: Path) -> None:
    (tmp_path / "p.mdle").write_text("atom a = (go(1 m/s), never 2 s)\n")
    msg = error("plan: p.mdle\n", tmp_path)
    assert "p.mdle:1:" in msg


def test_a_world_file_error_is_located_in_the_world_file(tmp_path: Path) -> None:
    (tmp_path / "w.yaml").write_text("obstacles:\n  - {type: circle, center: [3, 0]}\n")
    assert "w.yaml:2:5: error: obstacles[0]: missing key `radius`" in error(
        HEAD + "worlds: [w.yaml]\n", tmp_path)


def test_expansion_counts_and_orders_runs() -> None:
    s = parse_study(HEAD + "worlds: [ellipse, hexagon]\nrobots: [ideal, pioneer2dx]\n"
                    "rates: [10, 50]\nseeds: {count: 3}\nparameters: {grid: {kf: [1, 2]}}\n")
    tasks = list(expand(s))
    assert len(tasks) == s.size() == 2 * 2 * 2 * 3 * 2
    assert [t.index for t in tasks] == list(range(len(tasks)))
    assert len({t.key for t in tasks}) == len(tasks)
    assert {t.labels["world"] for t in tasks[:24]} == {"ellipse"}
    assert [t.seed for t in tasks[:3]] == [0, 1, 2]


def test_keys_hash_content_not_paths(tmp_path: Path) -> None:
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        (tmp_path / d / "common.mdle").write_text("atom halt2 = (stop, never, 1 s)\n")
        (tmp_path / d / f"plan_{d}.mdle").write_text(
            'import "common.mdle"\nplan main = ((halt2), never, inf)\n')
    ka = [t.key for t in expand(parse_study("plan: a/plan_a.mdle\n", base=tmp_path))]
    kb = [t.key for t in expand(parse_study("plan: b/plan_b.mdle\n", base=tmp_path))]
    assert ka == kb
    (tmp_path / "b" / "common.mdle").write_text("atom halt2 = (stop, never, 2 s)\n")
    kc = [t.key for t in expand(parse_study("plan: b/plan_b.mdle\n", base=tmp_path))]
    assert kc != ka          # an imported file's content is part of the key


def test_random_parameters_are_seeded_and_in_range() -> None:
    body = "parameters: {random: {count: 20, seed: 3, ranges: {rc: [0.5 m, 1.5 m]}}}\n"
    a, b = parse_study(HEAD + body), parse_study(HEAD + body)
    assert a.parameters == b.parameters and len(a.parameters) == 20
    values = [float(dict(p)["rc"].split()[0]) for p in a.parameters]
    assert all(0.5 <= v <= 1.5 for v in values) and len(set(values)) == 20


@pytest.mark.parametrize("origin", ["boundary", "centre"])
def test_random_starts_meet_their_rules(origin: str) -> None:
    s = parse_study(HEAD + "worlds: [hexagon]\nstarts: {random: {count: 25, seed: 1, "
                    f"distance: [2, 5], from: {origin}, spread: 20}}}}\n")
    world = load_world("hexagon")
    poses = start_poses(s.starts, s.worlds[0])
    assert len(poses) == 25 and poses == start_poses(s.starts, s.worlds[0])
    for pose in poses:
        assert pose is not None
        x, y, th = pose
        if origin == "boundary":
            d = float(world.nearest_boundary((x, y)).distance)
        else:
            c = world.geometry.centroid
            d = math.hypot(x - c.x, y - c.y)
        assert 2 - 1e-9 <= d <= 5 + 1e-9
        assert world.clearance((x, y), world.robot.radius) > 0
        # a collision course: the ray straight ahead hits the obstacle
        assert bool(world.cast((x, y), np.array([th]), 1e4).hit[0])


def test_random_starts_that_cannot_be_placed_say_so(tmp_path: Path) -> None:
    (tmp_path / "void.yaml").write_text("name: void\n")
    s = parse_study(HEAD + "worlds: [void.yaml]\nstarts: {random: {count: 2}}\n",
                    base=tmp_path)
    with pytest.raises(SpecError, match="no obstacle"):
        list(expand(s))


def test_generated_worlds_expand_and_travel_as_parameters() -> None:
    s = parse_study(HEAD + "worlds: [ellipse, {generated: {seed: 3, count: 3, first: 2}}, "
                    "{generated: {seed: 1, index: 0, family: plate}}]\n")
    assert [w.label for w in s.worlds] == ["ellipse", "rounded-rect-3-2",
                                           "rounded-rect-facets-3-3", "superellipse-3-4",
                                           "plate-1-0"]
    from mdle.sim.generated import generate_shape
    from mdle.sweep.worlds import build_world

    w = build_world(s.worlds[1].text, s.worlds[1].label)
    assert w.obstacles == generate_shape(3, 2).obstacles
    assert "family: unknown value" in error(
        HEAD + "worlds: [{generated: {seed: 1, family: blob}}]\n")
    assert "worlds[0].generated: give `index`" in error(
        HEAD + "worlds: [{generated: {index: 1, count: 2}}]\n")


def test_many_generated_worlds_are_checked_for_repeats_in_linear_work(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # each world was compared with every earlier one: 100,000 worlds took hours
    from mdle.sweep.spec import WorldChoice

    compared = [0]
    eq = WorldChoice.__eq__

    def counted(self: WorldChoice, other: object) -> bool:
        compared[0] += 1
        return eq(self, other)

    monkeypatch.setattr(WorldChoice, "__eq__", counted)
    n = 5000
    study = parse_study(HEAD + f"worlds: [{{generated: {{seed: 1, count: {n}}}}}]\n",
                        file="s.yaml")
    assert len(study.worlds) == n
    assert compared[0] < n, compared[0]  # pairwise: n * (n - 1) / 2
