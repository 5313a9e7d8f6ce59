"""Messages between the robots of a team: what one sends, what another has received.

A robot sends a value on a named *channel* (``send(gap, 1 m)`` in an atom); the team's
radio delivers it to the other robots at the next tick, within range and unless it is
lost (:class:`DeliveryRules`). Each robot's :class:`Inbox` keeps, per channel, the last
message that arrived, and per robot the last pose it reported (``send(pose)``), which
``range_to`` and ``bearing_to`` read. Poses travel in the *team frame* (the world's
coordinates): a robot reports its odometry composed with its start pose, so its drift
travels with it, as it would on real robots that share a map.

Pure Python, no numpy: sensor functions read inboxes at every tick.

>>> box = Inbox(Pose(1.0, 0.0, 0.0))
>>> box.put(Message("go", 1.0, "leader", 0.0, 0.1))
>>> box.since("go", 0.0), box.since("go", 0.1), box.value("go")
(True, False, 1.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from mdle.core.pose import Pose

__all__ = ["POSE_CHANNEL", "Message", "Inbox", "DeliveryRules", "compose", "relative"]

#: The channel ``send(pose)`` uses; its values are poses, not numbers.
POSE_CHANNEL = "pose"
_EPS = 1e-9


@dataclass(frozen=True)
class Message:
    """One message: ``value`` (SI number, or a team-frame :class:`Pose` on ``pose``).

    ``sent`` and ``arrived`` are simulated times, s.
    """

    channel: str
    value: float | Pose
    sender: str
    sent: float
    arrived: float


@dataclass(frozen=True)
class DeliveryRules:
    """How the team's radio delivers: always at the next tick, then these.

    ``range`` (m): only robots within it (true distance when sent) receive (``inf``:
    everyone). ``loss``: the probability that a message is lost for one receiver, drawn
    from a generator seeded with ``seed`` (None: from the run's seed).
    """

    range: float = math.inf
    loss: float = 0.0
    seed: int | None = None


def compose(origin: Pose, local: Pose) -> Pose:
    """Return ``local`` (odometry, relative to ``origin``) in the team frame."""
    c, s = math.cos(origin.theta), math.sin(origin.theta)
    th = origin.theta + local.theta
    return Pose(origin.x + c * local.x - s * local.y, origin.y + s * local.x + c * local.y,
                math.atan2(math.sin(th), math.cos(th)))


def relative(me: Pose, other: Pose) -> tuple[float, float]:
    """Return (range, bearing) of ``other`` seen from ``me``: m, and rad in (-pi, pi]."""
    dx, dy = other.x - me.x, other.y - me.y
    b = math.atan2(dy, dx) - me.theta
    return math.hypot(dx, dy), math.atan2(math.sin(b), math.cos(b))


@dataclass
class Inbox:
    """What one robot has received. ``origin`` is its start pose in the team frame."""

    origin: Pose
    _last: dict[str, Message] = field(default_factory=dict)
    _poses: dict[str, Message] = field(default_factory=dict)

    def put(self, msg: Message) -> None:
        """Keep ``msg`` as the newest on its channel (and its sender's pose)."""
        self._last[msg.channel] = msg
        if isinstance(msg.value, Pose):
            self._poses[msg.sender] = msg

    def since(self, channel: str, t: float) -> bool:
        """Tell whether a message on ``channel`` arrived after the tick at time ``t``.

        Strictly after: a message that arrived at the tick ``t`` was in that tick's
        observation, before anything started in it, so it is older than an element
        started at ``t`` (one message cannot end a chain of waits in one tick).
        """
        m = self._last.get(channel)
        return m is not None and m.arrived > t + _EPS

    def value(self, channel: str) -> float:
        """Return the last number received on ``channel`` (NaN: none yet, or a pose)."""
        m = self._last.get(channel)
        if m is None or isinstance(m.value, Pose):
            return math.nan
        return m.value

    def pose_of(self, robot: str) -> Pose | None:
        """Return the last pose ``robot`` reported (None: none received yet)."""
        m = self._poses.get(robot)
        return m.value if m is not None and isinstance(m.value, Pose) else None

    def me(self, odometry: Pose) -> Pose:
        """Return this robot's own pose in the team frame, from its odometry."""
        return compose(self.origin, odometry)
