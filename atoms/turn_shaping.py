"""Turn-away shaping: on a robot that jumps to turns away, the law ramps them itself.

The steering law's reflexes turn away from the boundary for a tick or two: the front floor
asks for the full turn rate (8.7 rad/s on a Pioneer) when a face comes up ahead; the front
blend and the next face's weight ask for sharp turns at a concave corner. A firmware that
ramps every change smooths such a spike into a small swerve. Some do not: the Stage-based
ARCOS servers (AMRISim, MobileSim) take a positive turn rate commanded negative *at once*
and ramp the other way at 100 deg/s^2. Following on the side where that jump is a turn
away (the left), a one-tick spike becomes a full turn rate that takes seconds to undo
(8.7 rad/s at 1.74 rad/s^2: 5 s), and every swing back towards the boundary, round a tip,
starts from further away and late.

:class:`TurnShaper` shapes the command the safety layer let through. It watches the measured
turn rate: once that has risen away from the boundary faster than the robot's turn
acceleration allows (:data:`JUMP_FACTOR` times it, and by more than :data:`JUMP_MIN`), the
robot is known to jump to turns away, and from then on :func:`limit_turn_away` caps each
command's turn away at one tick of the ramp beyond the rate the robot is predicted to turn at
when the command starts to act (the measured rate ramped through the commands still in
flight: :attr:`atoms.latency.Prediction.omega`). Until then only a spin is capped:
a turn away more than :data:`UNWIND` of the ramp beyond that rate, which a ramping firmware
never reaches within a tick, so for it nothing changes (the P3-DX following on the right, as
before, bit for bit); a jumping one takes its first spike only that far (a second to
unwind, not five), and shows by it that it jumps. Turns towards the boundary pass as the law asks: a
firmware that jumps to them rounds a tip sooner (the P3-DX on the right), and the safety
layer guards them. Without a turn-acceleration limit (the ideal unicycle) nothing is shaped.
Everything is in the law's (right-hand) frame, where a positive turn rate turns away from
the boundary.

>>> round(limit_turn_away(8.7, rate=0.5, accel=1.74, dt=0.1), 6)  # the floor's spike, ramped
0.674
>>> limit_turn_away(-2.0, rate=0.5, accel=1.74, dt=0.1)            # towards: as asked
-2.0
>>> limit_turn_away(8.7, rate=0.5, accel=math.inf, dt=0.1)         # an ideal robot
8.7
>>> s = TurnShaper()
>>> s.observe(0.0, -0.5, accel=1.74)
>>> round(s.limit(8.7, rate=-0.5, accel=1.74, dt=0.1), 6)  # not seen to jump: a spin is capped
1.24
>>> s.observe(0.1, 0.3, accel=1.74)        # +0.8 rad/s in 0.1 s: the ramp allows 0.174
>>> s.jumps, round(s.limit(8.7, rate=0.3, accel=1.74, dt=0.1), 6)
(True, 0.474)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["TurnShaper", "limit_turn_away", "JUMP_MIN", "JUMP_FACTOR", "UNWIND"]

#: A rise of the measured turn rate smaller than this is never taken for a jump (rad/s):
#: odometry's rounding and a report's timing jitter stay below it.
JUMP_MIN = 0.2
#: A rise faster than this many times the robot's turn acceleration is a jump (a report that
#: slipped lets one tick see two cycles' ramp at once; the right side of the lab study, whose
#: firmware ramps every turn away, shows rises of up to twice the ramp's rate).
JUMP_FACTOR = 3.0
#: Before the robot has shown a jump, a turn away is capped only where it would take longer
#: than this to unwind at the robot's turn acceleration (s): a spin, not a swerve.
UNWIND = 1.0


def limit_turn_away(u: float, rate: float, accel: float, dt: float) -> float:
    """Return the turn rate ``u`` with its turn away capped at ``dt`` of the robot's ramp.

    Parameters
    ----------
    u : float, rad/s
        The turn rate asked for (law frame: positive turns away from the boundary).
    rate : float, rad/s
        The turn rate the robot is predicted to have when this command starts to act
        (law frame).
    accel : float, rad/s^2
        The robot's turn acceleration limit (``inf``: none).
    dt : float, s
        How long the robot may ramp towards the command: the tick's length.

    Returns
    -------
    float
        ``min(u, rate + accel dt)``; ``u`` itself without a finite positive acceleration
        limit or a positive ``dt``.
    """
    if not (0.0 < accel < math.inf) or not dt > 0.0:
        return u
    top = rate + accel * dt
    return top if u > top else u


@dataclass
class TurnShaper:
    """What one ``follow_boundary`` atom has seen of its robot's answer to turns away.

    Rates in the law's frame (rad/s, positive away from the boundary), times on the
    backend's clock (s).
    """

    reported: float | None = None
    """The measured turn rate as last changed (None: no report yet)."""
    reported_at: float = 0.0
    """When it last changed."""
    jumps: bool = False
    """The measured rate has risen away from the boundary faster than the robot's ramp."""

    def observe(self, time: float, measured: float, accel: float) -> None:
        """Take this tick's measured turn rate (once per tick, before :meth:`limit`)."""
        if not 0.0 < accel < math.inf:
            return
        before, before_at = self.reported, self.reported_at
        if before is not None and measured == before:
            return  # the same report again: nothing new about the robot
        self.reported, self.reported_at = measured, time
        if before is None or self.jumps:
            return
        rise = measured - before
        if rise > JUMP_MIN and rise > JUMP_FACTOR * accel * (time - before_at):
            self.jumps = True

    def limit(self, u: float, rate: float, accel: float, dt: float) -> float:
        """Return ``u`` with its turn away capped (law frame, rad/s).

        At one tick (``dt``) of the ramp beyond the predicted ``rate`` once the robot has
        jumped to a turn away; before that, only at :data:`UNWIND` of it (a firmware that
        ramps never gets that far in a tick, so it is left as it was).
        """
        return limit_turn_away(u, rate, accel, dt if self.jumps else UNWIND)
