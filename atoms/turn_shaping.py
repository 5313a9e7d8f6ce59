"""Turn-away shaping: on a robot seen to jump to turns away, the law ramps them itself.

The steering law's reflexes turn away from the boundary for a tick or two: the front floor
asks for the full turn rate (8.7 rad/s on a Pioneer) when a face comes up ahead, the front
blend and the next face's weight ask for sharp turns at a concave corner. A firmware that
ramps every change smooths such a spike into a small swerve. Some do not: the Stage-based
ARCOS servers (AMRISim, MobileSim) take a positive turn rate commanded negative *at once*
and ramp the other way at 100 deg/s^2. Following on the side where that jump is a turn away,
a one-tick spike becomes a full turn rate that takes seconds to undo (8.7 rad/s at
1.74 rad/s^2: 5 s), and each swing back towards the boundary round a tip starts late.

:class:`TurnShaper` watches the measured turn rate. Once it has risen away from the boundary
faster than the robot's turn acceleration allows (twice the ramp's step, and by more than
:data:`JUMP_MIN`), the robot is known to jump that way, and from then on each command's turn
away is capped at one tick of the ramp from the rate the robot turns at now: the larger
(further away) of the last command and the measured rate, so the cap never holds it back
behind what a ramping firmware does anyway. Turns towards the boundary pass as the law asks:
a firmware that jumps to them rounds a tip sooner, and the safety layer guards them. A robot
that ramps every change, or has no turn-acceleration limit (the ideal unicycle), is never
shaped. Everything is in the law's (right-hand) frame, where a positive turn rate turns away
from the boundary.

>>> s = TurnShaper()
>>> s.observe(0.0, 0.3, accel=1.74)
>>> s.observe(0.1, -0.2, accel=1.74)       # towards the boundary at once: not a jump away
>>> s.jumps
False
>>> s.observe(0.2, 0.5, accel=1.74)        # +0.7 rad/s in 0.1 s, the ramp allows 0.17
>>> s.jumps
True
>>> s.sent(0.5)
>>> round(s.limit(8.7, measured=0.3, accel=1.74, dt=0.1), 6)   # the floor's spike, ramped
0.674
>>> s.limit(-2.0, measured=0.3, accel=1.74, dt=0.1)            # towards: as asked
-2.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["TurnShaper", "JUMP_MIN", "JUMP_FACTOR"]

#: A rise of the measured turn rate smaller than this is never taken for a jump (rad/s):
#: odometry's rounding and a report's timing jitter stay below it.
JUMP_MIN = 0.2
#: A rise faster than this many times the robot's turn acceleration is a jump (the reports'
#: instants jitter, so one cycle's ramp can show as up to about 1.5 cycles' worth).
JUMP_FACTOR = 2.0


@dataclass
class TurnShaper:
    """What one ``follow_boundary`` atom knows of its robot's turn-rate response.

    Rates are in the law's frame (rad/s, positive away from the boundary), times in the
    backend's clock (s).
    """

    last: float | None = None
    """The turn rate last commanded; None before the first command."""
    report: tuple[float, float] | None = None
    """When the measured turn rate last changed, and to what."""
    jumps: bool = False
    """The robot has been seen to take a turn away faster than its ramp."""

    def observe(self, time: float, measured: float, accel: float) -> None:
        """Take this tick's measured turn rate (once per tick, before :meth:`limit`).

        Parameters
        ----------
        time : float, s
            The tick's time.
        measured : float, rad/s
            The turn rate measured now (odometry, law frame).
        accel : float, rad/s^2
            The robot's turn acceleration limit (``inf``: none, nothing is ever shaped).
        """
        if not 0.0 < accel < math.inf:
            return
        prev = self.report
        if prev is not None and measured == prev[1]:
            return  # the same report again: nothing new about the robot
        self.report = (time, measured)
        if prev is None or self.jumps:
            return
        rise = measured - prev[1]
        if rise > JUMP_MIN and rise > JUMP_FACTOR * accel * (time - prev[0]):
            self.jumps = True

    def limit(self, u: float, measured: float, accel: float, dt: float) -> float:
        """Return the turn rate ``u`` with its turn away capped at one tick of the ramp.

        Parameters
        ----------
        u : float, rad/s
            The turn rate asked for (law frame: positive turns away from the boundary).
        measured : float, rad/s
            The turn rate measured now (law frame).
        accel : float, rad/s^2
            The robot's turn acceleration limit.
        dt : float, s
            The tick's length.

        Returns
        -------
        float
            ``min(u, max(last, measured) + accel dt)`` once the robot is known to jump to
            turns away; ``u`` itself before that, before the first command, or without a
            finite acceleration limit or a positive tick.
        """
        last = self.last
        if not self.jumps or last is None or not (0.0 < accel < math.inf) or not dt > 0.0:
            return u
        top = max(last, measured) + accel * dt
        return top if u > top else u

    def sent(self, u: float) -> None:
        """Remember the turn rate commanded this tick (law frame, rad/s)."""
        self.last = u
