"""A robot profile's numbers on hardware: what ``--robot PROFILE`` means with ``--backend pioneer``.

On a robot the motion comes from the robot itself, so a profile (``mdle robots``) does not
change how it moves. It says what the robot is like where the driver cannot measure it:

* the law's lag prediction: :attr:`~mdle.core.backend.RobotLimits.command_latency` (a
  ``follow_boundary`` with ``latency = inf``, its default, predicts over it) and the
  typical scan age :attr:`~mdle.core.backend.RobotLimits.scan_latency`, as the profile's
  timing model has them in simulation;
* the ladar's mount and scan period, which recordings use for their ``base_link ->
  laser`` transform and ``LaserScan`` timing.

Without a profile the backend keeps its own: the ARCOS server loop's mean delay
(:data:`mdle.drivers.pioneer.SERVER_LOOP_LATENCY`) and an unknown mount.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mdle.drivers.pioneer import PioneerBackend
    from mdle.sim.robot import RobotProfile

__all__ = ["apply_robot_profile"]


def apply_robot_profile(backend: PioneerBackend, profile: RobotProfile) -> None:
    """Give a connected Pioneer a profile's latencies, ladar mount and scan period.

    The speed and acceleration limits stay the robot's (from its model and ``--connect``
    options): the profile's are the simulated robot's.
    """
    timing = profile.limits  # the latencies the simulator's laws see with this profile
    backend.limits = replace(backend.limits, command_latency=timing.command_latency,
                             scan_latency=timing.scan_latency)
    x, y, th = profile.ladar_mount
    backend.laser_mount = (float(x), float(y), float(th))
    if profile.scan_period is not None:
        backend.laser_timing = (profile.scan_period, 0.0)
