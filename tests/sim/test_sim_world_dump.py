"""World YAML written from a World loads back as the same world."""

from __future__ import annotations

import math

import numpy as np

from mdle.core.pose import Pose
from mdle.sim.catalog import list_worlds, load_world
from mdle.sim.generated import FAMILIES, generate_shape
from mdle.sim.world import World
from mdle.sim.world_dump import world_to_yaml
from mdle.sim.world_yaml import parse_world


def _same_parts(a: World, b: World) -> None:
    pa, pb = a.parts, b.parts
    for name in ("seg_start", "seg_end", "seg_kappa", "arc_center", "arc_radius", "arc_start",
                 "arc_sweep", "arc_side", "ell_center", "ell_axes", "ell_angle"):
        x, y = getattr(pa, name), getattr(pb, name)
        assert x.shape == y.shape, name
        assert np.allclose(x, y, rtol=0, atol=1e-9), name


def test_every_reference_world_round_trips() -> None:
    for name in list_worlds():
        w = load_world(name)
        back = parse_world(world_to_yaml(w), file="<dump>")
        assert back.name == w.name and back.seed == w.seed and back.extent == w.extent
        assert back.robot.name == w.robot.name and back.ladar.name == w.ladar.name
        assert math.isclose(back.start_pose.theta, w.start_pose.theta, abs_tol=1e-12)
        assert [o.kind for o in back.obstacles] == [o.kind for o in w.obstacles]
        assert [o.name for o in back.obstacles] == [o.name for o in w.obstacles]
        _same_parts(w, back)


def test_generated_worlds_round_trip_with_their_start_and_seed() -> None:
    for i in range(len(FAMILIES)):
        w = generate_shape(4, i).world(Pose(9.0, -1.5, 2.0))
        text = world_to_yaml(w)
        back = parse_world(text, file="<dump>")
        assert back.start_pose.x == 9.0 and back.start_pose.y == -1.5
        assert math.isclose(back.start_pose.theta, 2.0, abs_tol=1e-12)
        _same_parts(w, back)
