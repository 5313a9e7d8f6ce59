"""Running a team: one scheduler per robot, one tick loop, one simulated clock.

Each tick every robot's scheduler ticks in turn (observe, test interrupts, compute its
control and what it sends, command): none of them moves yet. Then
:meth:`sim.team.TeamSim.step` moves every robot by the tick and the radio delivers the
messages of the tick, which the robots see at the next one. A robot whose plan has ended
stays where it stopped, an obstacle to the others. The run ends when every plan has
ended (or at ``until``); a failure or a stop request ends every robot's run.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from mdle.core.messages import Message
from mdle.core.pose import Pose
from mdle.lang import Element
from mdle.runtime import RunResult, Scheduler
from mdle.runtime.events import Observer
from mdle.runtime.pacing import Pacer

__all__ = ["TeamRun", "message_record"]


def message_record(direction: str, robot: str, msg: Message) -> dict[str, Any]:
    """Return the trace record of a message ``robot`` sent or received (``direction``)."""
    value: Any = msg.value
    if isinstance(value, Pose):
        value = {"x": value.x, "y": value.y, "theta": value.theta}
    rec = {"type": "message", "dir": direction, "t": msg.arrived if direction == "received"
           else msg.sent, "channel": msg.channel, "value": value, "from": msg.sender}
    if direction == "received":
        rec["to"] = robot
    return rec


@dataclass
class TeamRun:
    """The robots of a :class:`sim.team.TeamSim` running their elements.

    ``observers`` maps a robot's name to its observers (traces); those with an
    ``on_message(record)`` method also get the messages it sends and receives.
    """

    team: Any  # sim.team.TeamSim
    elements: Mapping[str, Element]
    rate: float = 10.0
    until: float | None = None
    observers: Mapping[str, Sequence[Observer]] | None = None
    pose_records: bool = False
    #: pace the ticks to the wall clock (``--realtime``: a live view to watch)
    realtime: bool = False

    def __post_init__(self) -> None:
        obs = self.observers or {}
        self.schedulers: dict[str, Scheduler] = {}
        for m in self.team.members:
            if m.name in self.elements:
                self.schedulers[m.name] = Scheduler(self.elements[m.name], m, self.rate,
                                                    tuple(obs.get(m.name, ())), until=self.until)
        self.team.radio.log = bool(obs)

    # a Stoppable, for the signal guard
    @property
    def ending(self) -> bool:
        """True once every robot's run has begun to end."""
        return all(s.ending for s in self.schedulers.values())

    def request_stop(self, reason: str | None = None) -> None:
        """Ask every robot's run to stop at its next tick."""
        for s in self.schedulers.values():
            s.request_stop(reason)

    def stop(self) -> None:
        """End every robot's run now (robots stopped, traces ended)."""
        for s in self.schedulers.values():
            if s.result is None:
                s.stop()

    @property
    def results(self) -> dict[str, RunResult]:
        """Each robot's result (once its run has ended)."""
        return {n: s.result for n, s in self.schedulers.items() if s.result is not None}

    def tick(self) -> bool:
        """Run one tick of every robot and move them; False once every run has ended."""
        running = False
        try:
            for s in self.schedulers.values():
                if s.result is None:
                    s.tick()
                    running = running or s.result is None
        except BaseException:
            self.stop()
            raise
        if not running:
            return False
        dt = 1.0 / self.rate
        self.team.step(dt)
        self._route_messages()
        return True

    def run(self) -> dict[str, RunResult]:
        """Run to the end; returns each robot's result."""
        for s in self.schedulers.values():
            s.start()
        pacer = Pacer() if self.realtime else None
        ticks = 0
        while self.tick():
            ticks += 1
            if pacer is not None:
                pacer.wait(ticks / self.rate)
        return self.results

    def _route_messages(self) -> None:
        radio = self.team.radio
        sent, delivered = radio.sent, radio.delivered
        radio.sent, radio.delivered = [], []
        obs = self.observers
        if not obs:
            return
        for sender, msg in sent:
            if not self.pose_records and isinstance(msg.value, Pose):
                continue
            self._tell(sender, message_record("sent", sender, msg))
        for receiver, msg in delivered:
            if not self.pose_records and isinstance(msg.value, Pose):
                continue
            self._tell(receiver, message_record("received", receiver, msg))

    def _tell(self, robot: str, record: dict[str, Any]) -> None:
        assert self.observers is not None
        for o in self.observers.get(robot, ()):
            hook = getattr(o, "on_message", None)
            if hook is not None:
                hook(record)
