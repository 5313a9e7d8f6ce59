"""Hostile world files: every one is refused (or loaded) with a located message, quickly.

Deep nesting, aliases that refer to themselves or expand exponentially ("billion
laughs"), numbers too large for a float, names too long for a file system, absurd rates
and coordinates, and a start pose touching an obstacle. Each must end in a
:class:`~mdle.core.errors.WorldError` naming the place, never a RecursionError,
OverflowError, OSError or a hang. Costs are pinned by sizes, not wall-clock time.
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

import pytest

from mdle.core.errors import WorldError
from mdle.core.pose import Pose
from mdle.sim import load_world
from mdle.sim.world_yaml import MAX_YAML_DEPTH, parse_world


def refused(text: str) -> str:
    """Return the rendered message of the world error ``text`` must raise."""
    with pytest.raises(WorldError) as err:
        parse_world(text, file="w.yaml")
    (d,) = err.value.diagnostics
    assert d.span is not None and d.span.file == "w.yaml", d
    return str(err.value)


def test_nesting_500_deep_is_refused_at_its_place() -> None:
    msg = refused("obstacles: " + "[" * 500 + "]" * 500 + "\n")
    assert f"nests more than {MAX_YAML_DEPTH} levels" in msg and "w.yaml:1:" in msg


def test_nesting_of_block_mappings_is_refused_too() -> None:
    text = "".join("  " * i + f"k{i}:\n" for i in range(300)) + "  " * 300 + "x: 1\n"
    assert f"nests more than {MAX_YAML_DEPTH} levels" in refused(text)


def test_a_self_referencing_anchor_is_refused() -> None:
    msg = refused("obstacles: &a\n  - *a\n")
    assert "refers to itself" in msg and "obstacles[0]" in msg
    msg = refused("start: &s {x: 0, y: 0, theta: *s}\n")
    assert "refers to itself" in msg


def laughs(levels: int) -> str:
    """Anchors of ten aliases of the previous anchor: 10**levels values if expanded."""
    lines = ["x0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"]
    lines += [f"x{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]"
              for i in range(1, levels)]
    return "\n".join(lines) + "\n"


def test_billion_laughs_is_never_expanded() -> None:
    # aliases share their anchor's value: the unknown keys are found, nothing expands
    msg = refused(laughs(12).replace("x0:", "obstacles:"))
    assert "x1: unknown key" in msg and "w.yaml:2:1" in msg


def test_an_alias_bomb_as_a_key_is_shown_short() -> None:
    msg = refused(laughs(12).split("\nx")[0] + "\n? *a0\n: 1\n")
    assert "keys must be names" in msg and len(msg) < 400
    lines = laughs(12).splitlines()
    msg = refused("\n".join(lines).replace("x11:", "? *a10\n:") + "\n")
    assert "keys must be names" in msg and len(msg) < 400


@pytest.mark.parametrize("value", ["1" * 400, "1" * 5000, "-" + "9" * 400])
def test_huge_numbers_are_refused_with_the_key(value: str) -> None:
    msg = refused(f"obstacles:\n  - {{type: circle, center: [{value}, 0], radius: 1}}\n")
    assert "obstacles[0].center[0]" in msg and "w.yaml:2:" in msg


def test_huge_seed_is_refused() -> None:
    assert "seed" in refused("seed: " + "7" * 400 + "\n")


def test_absurd_ladar_rate_is_refused() -> None:
    msg = refused("ladar: {rate: 1e308}\n")
    assert "ladar.rate" in msg and "at most" in msg


@pytest.mark.parametrize("where", ["obstacles:\n  - {type: circle, center: [1e300, 0], "
                                   "radius: 1}\n",
                                   "start: {x: 1e300, y: 0}\n",
                                   "extent: [-1e300, -1, 1e300, 1]\n"])
def test_coordinates_far_beyond_any_world_are_refused(where: str) -> None:
    assert "must be within" in refused(where)


@pytest.mark.parametrize(("where", "key"), [("start: {x: 0, y: 0, theta: 1e308}\n", "start.theta"),
                                            ("start: [0, 0, -400]\n", "start[2]")])
def test_absurd_start_headings_are_refused_at_their_key(where: str, key: str) -> None:
    msg = refused(where)
    assert key in msg and "a heading must be from -360 to 360 deg" in msg and "w.yaml:1:" in msg


def test_start_pose_touching_an_obstacle_is_refused() -> None:
    # Pioneer radius 0.26 m: a wall face exactly 0.26 m away touches the body.
    text = ("robot: {radius: 0.26}\nstart: {x: 0, y: 0}\nobstacles:\n"
            "  - {type: rectangle, center: [1.26, 0], size: [2, 2]}\n")
    msg = refused(text)
    assert "touches" in msg and "obstacles[0]" in msg
    # A hair further away is fine.
    parse_world(text.replace("1.26", "1.27"), file="w.yaml")


def test_a_polygon_of_100k_vertices_loads(tmp_path: Path) -> None:
    n = 100_000
    pts = ", ".join(f"[{10 + 5 * math.cos(2 * math.pi * i / n):.9f}, "
                    f"{5 * math.sin(2 * math.pi * i / n):.9f}]" for i in range(n))
    w = parse_world(f"obstacles:\n  - {{type: polygon, points: [{pts}]}}\n", file="w.yaml")
    assert len(w.obstacles) == 1


def test_a_5000_character_world_name_is_a_message(tmp_path: Path, mdle_command: list[str],
                                                   repo: Path) -> None:
    name = "w" * 5000
    with pytest.raises(WorldError) as err:
        load_world(name)
    assert "unknown world" in str(err.value) and len(str(err.value)) < 1000
    with pytest.raises(WorldError):
        load_world(name + ".yaml")
    plan = repo / "plans" / "language" / "tour.mdle"
    r = subprocess.run([*mdle_command, "run", str(plan), "--world", name, "--until", "1"],
                       capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert r.returncode == 1 and "unknown world" in r.stderr, r.stderr


def test_worlds_show_of_a_far_obstacle_is_a_message(tmp_path: Path,
                                                    mdle_command: list[str]) -> None:
    world = tmp_path / "far.yaml"
    world.write_text("obstacles:\n  - {type: circle, center: [1e300, 0], radius: 1}\n",
                     encoding="utf-8")
    r = subprocess.run([*mdle_command, "worlds", "show", str(world), "-o",
                        str(tmp_path / "far.png")], capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and "far.yaml:2:" in r.stderr and "must be within" in r.stderr, \
        r.stderr


def test_worlds_show_without_an_extension_says_what_it_needs(tmp_path: Path,
                                                             mdle_command: list[str]) -> None:
    out = tmp_path / "picture"
    r = subprocess.run([*mdle_command, "worlds", "show", "ellipse", "-o", str(out)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and ".png, .svg or .pdf" in r.stderr, r.stderr
    assert not out.exists() and not (tmp_path / "picture.png").exists()
    r = subprocess.run([*mdle_command, "worlds", "show", "ellipse", "-o", str(out) + ".svg"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and f"world drawn to {out}.svg" in r.stdout, r.stderr
    assert (tmp_path / "picture.svg").stat().st_size > 0


def test_point_tests_join_no_shapes(monkeypatch: pytest.MonkeyPatch) -> None:
    # The union of 20,000 rectangles was 1.6 s of CPU in one GEOS call that Ctrl-C could
    # not cut: the point tests now ask each shape near the point, as the union would.
    import numpy as np
    import shapely

    from mdle.sim.shapes import Rectangle
    from mdle.sim.world import World

    shapes = tuple(Rectangle((float(i % 30), float(i // 30)), (0.8, 0.5)) for i in range(300))
    union = shapely.union_all([s.geometry() for s in shapes])

    def refused(*args: object, **kwargs: object) -> None:
        raise AssertionError("no union is needed to test points")

    monkeypatch.setattr(shapely, "union_all", refused)
    world = World("grid", obstacles=shapes, start_pose=Pose(-5.0, -5.0, 0.0))
    pts = np.random.default_rng(3).uniform(-1.0, 31.0, size=(2000, 2))
    got = np.asarray(world.inside(pts))
    assert got.tolist() == shapely.contains_xy(union, pts[:, 0], pts[:, 1]).tolist()
    assert got.any() and not got.all()
