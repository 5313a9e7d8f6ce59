"""Worlds of many circles (issues 26 and 27): the obstacle budgets, circles as arrays.

Circles are kept as arrays of centres and radii: :attr:`World.parts` must be the very
arrays one concatenation of every shape's parts gives, :meth:`World.inside` tests them
in closed form (no union of polygons), and :attr:`World.bounds` reads them directly.
The load times are measured in ``benchmarks/circles.py``, not here.
"""

from __future__ import annotations

import gc

import numpy as np
import pytest
import yaml

from mdle.core.errors import WorldError
from mdle.sim import world_obstacles, world_yaml
from mdle.sim.shapes import Arc, Circle, Curve, Ellipse, Parts, Rectangle
from mdle.sim.world import World
from mdle.sim.world_yaml import parse_world
from mdle.sim.yaml_doc import _Doc, _yaml_value

_CIRCLE = "{type: circle, center: [5, 5], radius: 1}"
_BOX = "{type: rectangle, center: [-5, 5], size: [1, 1]}"


def _world(*entries: str) -> str:
    return "name: many\nobstacles: [" + ", ".join(entries) + "]\n"


def _never(*_: object) -> None:
    raise AssertionError("an obstacle was built")


@pytest.fixture
def small_budgets(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(world_obstacles, "MAX_OBSTACLES", 5)
    monkeypatch.setattr(world_obstacles, "MAX_SHAPES", 2)


@pytest.mark.usefixtures("small_budgets")
def test_too_many_obstacles_are_refused_at_their_key_before_any_is_built(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(world_yaml, "_obstacle", _never)
    with pytest.raises(WorldError) as err:
        parse_world(_world(*[_CIRCLE] * 6), file="many.yaml")
    assert str(err.value).startswith(
        "many.yaml:2:12: error: obstacles: lists 6 obstacles; a world holds at most 5 (")


@pytest.mark.usefixtures("small_budgets")
def test_too_many_obstacles_other_than_circles_are_refused(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(world_yaml, "_obstacle", _never)
    with pytest.raises(WorldError) as err:
        parse_world(_world(_CIRCLE, _BOX, _CIRCLE, _BOX, _BOX), file="many.yaml")
    assert ("many.yaml:2:12: error: obstacles: lists 3 obstacles other than circles; a world "
            "holds at most 2 (") in str(err.value)


@pytest.mark.usefixtures("small_budgets")
def test_a_world_at_both_budgets_loads() -> None:
    w = parse_world(_world(_CIRCLE, _BOX, "{type: circle, center: [9, 0], radius: 1}", _BOX,
                           "{type: circle, center: [0, -9], radius: 2}"))
    assert len(w.obstacles) == 5


def _mixed() -> tuple[object, ...]:
    return (Rectangle((0.0, 5.0), (1.0, 1.0)), Circle((3.0, 0.0), 1.0),
            Arc((0.0, 0.0), 10.0, 0.0, 1.0, 0.2), Circle((-3.0, 0.0), 0.5),
            Ellipse((0.0, -6.0), (2.0, 1.0), 0.3),
            Curve(((5.0, 5.0), (7.0, 6.0), (9.0, 5.0)), 0.2), Circle((0.0, 20.0), 2.0))


def test_circles_as_arrays_make_the_parts_one_concatenation_makes() -> None:
    obstacles = _mixed()
    w = World("mixed", obstacles=obstacles)  # type: ignore[arg-type]
    fast = w.parts
    plain = Parts.concat([o.parts() for o in obstacles])  # type: ignore[attr-defined]
    for name in Parts.__dataclass_fields__:
        a, b = getattr(fast, name), getattr(plain, name)
        assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b), name


def test_inside_a_circle_is_exact_and_nothing_is_unioned_for_circles_alone() -> None:
    w = World("discs", obstacles=(Circle((0.0, 0.0), 1.0), Circle((3.0, 0.0), 1.0)))
    pts = np.array([[0.0, 0.0], [1.0 - 1e-9, 0.0], [1.0, 0.0], [2.0, 0.0],
                    # between the circle and a 256-sided polygon inscribed in it
                    [np.cos(np.pi / 256) * (1.0 - 1e-6), np.sin(np.pi / 256) * (1.0 - 1e-6)],
                    [3.0, 0.999]])
    assert np.asarray(w.inside(pts)).tolist() == [True, True, False, False, True, True]
    assert w._prepared is None
    assert float(w.clearance((0.0, 0.0))) == -1.0


def test_inside_a_mixed_world_matches_the_union_of_its_shapes() -> None:
    import shapely

    obstacles = _mixed()
    w = World("mixed", obstacles=obstacles)  # type: ignore[arg-type]
    rng = np.random.default_rng(3)
    pts = rng.uniform(-12.0, 22.0, size=(4000, 2))
    union = shapely.union_all([o.geometry() for o in obstacles])  # type: ignore[attr-defined]
    expect = shapely.contains_xy(union, pts[:, 0], pts[:, 1])
    got = np.asarray(w.inside(pts))
    # only a point between a circle and its polygon could differ: none is drawn here
    assert np.array_equal(got, expect)


def test_bounds_of_circles_come_from_their_arrays() -> None:
    w = World("mixed", obstacles=_mixed())  # type: ignore[arg-type]
    x0, y0, x1, y1 = w.geometry.bounds
    assert w.bounds == (x0 - 1.0, y0 - 1.0, x1 + 1.0, y1 + 1.0)


def test_plain_text_is_read_as_yaml_reads_it() -> None:
    text = ("a: circle\nb: yes\nc: null\nd: ~\ne: 0x1f\nf: 1e3\ng: 2001-12-14\nh: .inf\n"
            "i: 'quoted'\nj: !!str 12\nk: [x, 'y', No, 3.5]\nl: 1_000\n")
    assert _yaml_value(_Doc("t.yaml", text)) == yaml.safe_load(text)


def test_the_cycle_collector_is_back_as_it_was_after_a_document() -> None:
    assert gc.isenabled()
    _yaml_value(_Doc("t.yaml", "a: [1, 2]\n"))
    assert gc.isenabled()
    with pytest.raises(WorldError):
        _yaml_value(_Doc("t.yaml", "a: [1, 2\n"))
    assert gc.isenabled()
    gc.disable()
    try:
        _yaml_value(_Doc("t.yaml", "a: [1, 2]\n"))
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_reading_a_world_s_robot_parses_but_does_not_build_the_other_keys() -> None:
    text = "robot: pioneer2dx\nobstacles: [{type: circle, center: [1, 2], radius: 1}]\n"
    assert _yaml_value(_Doc("w.yaml", text), only=frozenset({"robot"})) == {
        "robot": "pioneer2dx", "obstacles": None}
    assert world_yaml.parse_world_robot(text).name == "pioneer2dx"


def test_a_robot_that_is_an_alias_into_a_value_not_built_is_still_read() -> None:
    text = "description: &p pioneer2dx\nobstacles: [&q {a: 1}]\nrobot: *p\n"
    assert world_yaml.parse_world_robot(text).name == "pioneer2dx"


@pytest.mark.parametrize(("text", "where", "words"), [
    ("obstacles: [{type: circle, center: [1, 2}]\nrobot: pioneer2dx\n", "w.yaml:1:",
     "not valid YAML"),
    ("obstacles: " + "[" * 70 + "]" * 70 + "\n", "w.yaml:1:", "nests more than 64 levels"),
    ("robot: pioneer2dx\nobstacles: []\nrobot: pioneer2dx\n", "w.yaml:3:", "key given twice"),
])
def test_the_values_not_built_are_still_checked_as_yaml(text: str, where: str, words: str) -> None:
    with pytest.raises(WorldError) as err:
        world_yaml.parse_world_robot(text, file="w.yaml")
    assert str(err.value).startswith(where) and words in str(err.value)


def test_a_world_read_is_frozen_out_of_the_collectors_passes() -> None:
    # 200,000 circles are millions of objects: a full pass of the cycle collector over
    # them held Ctrl-C for a quarter of a second, each time one came during the build
    text = "obstacles:\n" + "".join(
        f"  - {{type: circle, center: [{3 + i}, 5], radius: 0.2}}\n" for i in range(50))
    world = parse_world(text, "w.yaml")
    walked = {id(o) for o in gc.get_objects()}
    assert len(world.obstacles) == 50
    assert not [o for o in (world, *world.obstacles) if id(o) in walked]
