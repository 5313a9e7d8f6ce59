r"""Which frame plan-visible poses are in, and whether a program reads them.

In every backend the sensors ``x``, ``y``, ``theta`` and ``dist_to`` and the laws ``goto``
and ``heading`` read odometry in the REP-105 ``odom`` frame: (0, 0, 0) where the robot
stands when the run starts, x forward and y left of that pose. The simulator's world
coordinates are ground truth only (plots, traces' ``true_x``, collisions).

>>> from mdle.lang import load_text
>>> reads_pose(load_text("atom a = (go(0.2 m/s), x > 1 m, 5 s)\nrun a\n"))
True
>>> reads_pose(load_text("atom a = (go(0.2 m/s), range(0 deg) < 1 m, 5 s)\nrun a\n"))
False
"""

from __future__ import annotations

import re

from mdle.lang import Program

__all__ = ["FRAME_NOTE", "POSE_NAMES", "reads_pose"]

#: Sensors and control laws that read the pose.
POSE_NAMES = ("x", "y", "theta", "dist_to", "goto", "heading")

#: What ``mdle check`` and ``mdle run`` say about the frame.
FRAME_NOTE = ("x, y, theta and dist_to are odometry (REP-105 odom frame): (0, 0, 0) where "
              "the robot stands when the run starts, x forward, y to its left; the same in "
              "simulation and on the robot")

_USE = re.compile(r"(?<![\w.])(" + "|".join(POSE_NAMES) + r")(?![\w])")
_COMMENT = re.compile(r"#[^\n]*")


def reads_pose(program: Program) -> bool:
    """Tell whether the program's text names a pose sensor or law (comments ignored)."""
    return any(_USE.search(_COMMENT.sub("", text)) for text in program.sources.values())
