"""What the simulator's tests share: seeded worlds of boxes."""

from __future__ import annotations

import numpy as np

from mdle.sim.shapes import Rectangle, Wall
from mdle.sim.world import World


def boxes_world(n: int, half: float, seed: int) -> World:
    """``n`` seeded boxes (0.2-1 m, any heading) in a square of side ``2 half``, walled in."""
    rng = np.random.default_rng(seed)
    boxes = [Rectangle(tuple(rng.uniform(-half, half, 2)), tuple(rng.uniform(0.2, 1.0, 2)),
                       float(rng.uniform(0, 3))) for _ in range(n)]
    wall = Wall(((-half - 1, -half - 1), (half + 1, -half - 1), (half + 1, half + 1),
                 (-half - 1, half + 1)), 0.2, True)
    return World(f"boxes{n}", obstacles=(wall, *boxes))
