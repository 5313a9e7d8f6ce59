"""Properties over random drives: the body never overlaps an obstacle; scans match ground truth."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mdle import sim
from mdle.core.backend import Command
from mdle.sim.backend import SimBackend

commands = st.lists(st.tuples(st.floats(-3.0, 3.0), st.floats(-6.0, 6.0),
                              st.sampled_from([0.01, 0.05, 0.1, 0.25, 1.0])),
                    min_size=1, max_size=40)


@settings(max_examples=40, deadline=None)
@given(world=st.sampled_from(["office", "corridor", "u-shape", "garden", "default"]),
       robot=st.sampled_from(["pioneer2dx", "ideal"]), drive=commands)
def test_random_drives_never_overlap_obstacles(world: str, robot: str,
                                               drive: list[tuple[float, float, float]]) -> None:
    w = sim.load_world(world)
    b = SimBackend(w, robot=robot, ladar="lms200-ideal")
    radius = b.profile.radius
    for v, omega, dt in drive:
        b.command(Command(v, omega))
        b.advance(dt)
        t = b.observe().truth
        assert t["clearance"] >= 0.0
        # Independent check with the world's own (signed) clearance.
        assert w.clearance((t["x"], t["y"]), radius) >= -1e-9


@settings(max_examples=25, deadline=None)
@given(world=st.sampled_from(sim.list_worlds()), heading=st.floats(-math.pi, math.pi))
def test_noise_free_scans_equal_ground_truth_casts(world: str, heading: float) -> None:
    from mdle.core.pose import Pose

    w = sim.load_world(world)
    b = SimBackend(w, ladar="lms200-ideal")
    s = w.start_pose
    b.reset(Pose(s.x, s.y, heading))
    scan = b.observe().scan
    assert scan is not None
    mx, my, mth = b.profile.ladar_mount
    ox = s.x + math.cos(heading) * mx - math.sin(heading) * my
    oy = s.y + math.sin(heading) * mx + math.cos(heading) * my
    truth = w.cast((ox, oy), heading + mth + np.linspace(-math.pi / 2, math.pi / 2, 181), 10.0)
    assert np.array_equal(scan.valid, truth.hit)
    np.testing.assert_allclose(scan.ranges[scan.valid], truth.ranges[truth.hit], atol=1e-12)
    assert np.all(scan.ranges[~scan.valid] == 10.0)
