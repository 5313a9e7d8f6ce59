"""Several simulated robots in one world, advanced together in simulated time.

Over 500 lines: one simulation step of several robots, whose parts (moving in pieces
where robots could meet, their contacts, the scans that see each other, the radio)
share the team's arrays and the order of one tick; split, each part would reach into
the others' state.

:class:`TeamSim` holds one :class:`Member` per robot. Each member is a full
:class:`sim.backend.SimBackend` (its own profile, ladar, noise and seed) that also sees
the others: its ladar's rays meet their discs (:func:`sim.crowd.cast_discs`, one
(beams, robots) array per scan) and its body stops at them as at a wall
(:class:`sim.crowd.CrowdCollider`). A member is driven through the ordinary backend
protocol by its own scheduler, but its ``advance`` only marks the tick done:
:meth:`TeamSim.step` moves every robot, one after the other, each seeing the others where
they are at that moment (so two robots never overlap), then the radio delivers what was
sent during the tick (at the next tick, so the order of the robots never matters).

A robot that touches another stalls, like at a wall; both records name the other
robot (obstacle kind ``robot``). Robots moving one after the other would meet late, or
pass through each other's paths unseen, when both move far in one tick: so a step is cut
where two robots could first meet (their gap over the sum of bounds of their speeds:
conservative advancement), and the robots move together piece by piece. Where no two
robots can meet within the tick (the usual case) the step is one piece.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mdle.core.backend import Scan, TickClock, plain_scan
from mdle.core.errors import BackendError, WorldError
from mdle.core.messages import POSE_CHANNEL, DeliveryRules, Inbox, Message
from mdle.core.pose import Pose
from mdle.sim.backend import SimBackend, SimEvent
from mdle.sim.collision import Clearance
from mdle.sim.crowd import NO_DISCS, CrowdCollider, Discs, cast_discs, occlude, occlusions
from mdle.sim.ladar import settle_rows
from mdle.sim.raycast import RayHits
from mdle.sim.world import RobotPlace, World

__all__ = ["RobotPlace", "Member", "Radio", "TeamSim", "TOUCHING", "MAX_PIECES"]

#: Robots whose bodies are closer than this (m) are in contact: their sweeps meet each
#: other, and the step is no longer cut for them. A contact is found within this distance
#: of where it happens, so its time within TOUCHING / (closing speed).
TOUCHING = 1e-3
#: At most this many pieces in one tick; the rest of a tick is then one piece (robots
#: grazing each other at slightly more than TOUCHING would cut a tick very fine).
MAX_PIECES = 200

#: The arrays of a scan whose casting waits for the end of the team's step (never read:
#: the team replaces the scan before anyone observes it).
_LATER = np.zeros(0)
_LATER.setflags(write=False)
_LATER_VALID = np.zeros(0, dtype=bool)
_LATER_VALID.setflags(write=False)


@dataclass(frozen=True)
class FanShape:
    """A ladar's even fan of beams, as the team's one-pass casts take it."""

    step: float       # between beams, rad
    beams: int
    max_range: float  # m
    own: int          # the robot's own disc in the team's discs


@dataclass(frozen=True)
class PendingScan:
    """A scan taken during the team's step, finished once every robot has moved.

    ``ox``, ``oy``: the ladar's origin (m); ``first``: the world angle of its first beam.
    """

    member: "Member"
    scan: Scan
    ox: float
    oy: float
    first: float
    fan: FanShape


@dataclass(frozen=True)
class Outgoing:
    """A message on its way: sent during a tick, delivered at the next."""

    sender: int
    channel: str
    value: float | Pose
    sent: float
    x: float
    y: float


class Radio:
    """The team's radio: collects what the robots send, delivers at the next tick.

    With :attr:`log` on (a team run with traces), :attr:`sent` keeps every message sent
    and :attr:`delivered` every delivery, ``(robot name, message)``, until drained.
    """

    def __init__(self, names: Sequence[str], rules: DeliveryRules) -> None:
        self.names = tuple(names)
        self.rules = rules
        self._rng = np.random.default_rng(rules.seed)
        self._out: list[Outgoing] = []
        self.log = False
        self.sent: list[tuple[str, Message]] = []  # (sender, message) since last drained
        self.delivered: list[tuple[str, Message]] = []  # (receiver, message)

    def post(self, msg: Outgoing) -> None:
        """Queue a message for the next delivery."""
        self._out.append(msg)

    def deliver(self, now: float, inboxes: Sequence[Inbox], positions: np.ndarray) -> None:
        """Deliver the queued messages at time ``now`` (``positions``: (N, 2) when sent)."""
        out, self._out = self._out, []
        rules = self.rules
        n = len(inboxes)
        everyone = list(range(n))
        for o in out:
            msg = Message(o.channel, o.value, self.names[o.sender], o.sent, now)
            if self.log:
                self.sent.append((msg.sender, msg))
            if math.isinf(rules.range) and rules.loss == 0.0:
                receivers = everyone
            else:  # one draw per robot and message, whether in range or not: reproducible
                ok = np.ones(n, dtype=bool)
                if math.isfinite(rules.range):
                    ok &= np.hypot(positions[:, 0] - o.x, positions[:, 1] - o.y) <= rules.range
                if rules.loss > 0.0:
                    ok &= self._rng.random(n) >= rules.loss
                receivers = np.flatnonzero(ok).tolist()
            for j in receivers:
                if j != o.sender:
                    inboxes[j].put(msg)
                    if self.log:
                        self.delivered.append((self.names[j], msg))


class Member(SimBackend):
    """One robot of a :class:`TeamSim`: a SimBackend that sees and meets the others.

    Driven by a scheduler like any backend; :meth:`advance` only marks the tick, the team
    moves it. :attr:`radio` takes what its plan sends.
    """

    # The team folds the other robots into every clearance once all have moved (TeamSim
    # step): a step ends with the walls' exact clearance, never a bound.
    _lazy_clearance = False

    def __init__(self, team: "TeamSim", index: int, world: World, place: RobotPlace,
                 seed: int, sensing: str) -> None:
        self.team = team
        self.index = index
        self.name = place.name
        self._batched = False
        self._cast_later = False  # the team casts its scans (see TeamSim._settle_scans)
        self._crowd = False  # are there others to see?
        self.discs = NO_DISCS  # every robot's disc (its own skipped), from the team
        self.box = Inbox(place.start)  # what its radio receives (the observation's inbox)
        self.inbox = self.box
        super().__init__(world, seed=seed, robot=place.profile, ladar=place.ladar,
                         sensing=sensing, start=place.start)

    def _make_collider(self) -> CrowdCollider:
        return CrowdCollider(self.world.parts, self.profile.radius, len(self.world.obstacles))

    # the scheduler's side
    def advance(self, dt: float) -> float:
        """Mark this robot's tick done; :meth:`TeamSim.step` moves every robot."""
        if not (dt >= 0.0 and math.isfinite(dt)):
            raise BackendError(f"advance(dt) needs a finite dt >= 0, got {dt}")
        return 0.0

    @property
    def radio(self) -> "Member":
        """The robot's transmitter (itself): see :meth:`send`."""
        return self

    def send(self, channel: str, value: float | None, now: float) -> None:
        """Send ``value`` on ``channel`` (None: this robot's pose, on ``pose``)."""
        if value is None:
            odo = self.observe_pose()
            self.team.radio.post(Outgoing(self.index, POSE_CHANNEL, self.box.me(odo), now,
                                          self._x, self._y))
        else:
            self.team.radio.post(Outgoing(self.index, channel, float(value), now,
                                          self._x, self._y))

    def observe_pose(self) -> Pose:
        """Return the odometry pose the robot reports now."""
        if self.profile.sip_cycle > 0:
            ox, oy, oth = self._report[:3]
        else:
            ox, oy, oth = self._ox, self._oy, self._oth
        return Pose(ox, oy, oth)

    # the team's side
    def join(self, discs: Discs) -> None:
        """See and meet the team's robots at ``discs`` (a live view of where they are).

        From now on a scan is finished by the team once every robot has moved
        (:meth:`TeamSim.step`), with the others in it, unless the ladar is an oracle.
        """
        self.discs = discs
        self._crowd = len(discs) > 1
        assert isinstance(self._collider, CrowdCollider)
        self._collider.join(discs, self.index)
        self._clear = self._collider.clearance(self._x, self._y)
        self._scan = self._take_scan(self._x, self._y, self._th, self._t)
        lad = self._ladar
        self._fan_shape = FanShape(float(lad.bearings[1] - lad.bearings[0])
                                   if len(lad.bearings) > 1 else 1.0, len(lad.bearings),
                                   lad.profile.max_range, self.index)
        self._batched = self._fan is not None
        self._cast_later = self._fan is not None and self._fan.batchable()

    def begin_tick(self, dt: float) -> float:
        """Count a tick of ``dt`` on this robot's clock; return the time the tick ends."""
        return self._ticks.advance(dt)

    def move_to(self, t1: float, others_moved: float, last: bool) -> None:
        """Move to time ``t1`` (``last``: the tick's end), the others standing where they are.

        ``others_moved`` bounds how far any other robot has moved since this one's last
        step: its clearance then is at least the last one less that (the walls stay), and
        the exact clearance is measured only if that bound does not cover the step.
        """
        self._clear = Clearance(self._clear.distance - others_moved, self._clear.obstacle)
        self._clear_bound = True
        self._advance_to(t1, last)

    def speed_bound(self) -> float:
        """Return a bound of the body's speed (m/s) until the tick ends.

        The speed ramps between the speed now and the commands held or queued (the
        commands of the tick are all given before it moves), never beyond them.
        """
        bound = max(abs(self._v), abs(self._cmd.v))
        if self._cycled:
            bound = max(bound, abs(self._desired.v))
        for _, cmd in self._pending:
            bound = max(bound, abs(cmd.v))
        return bound

    def _settled_clearance(self, x: float, y: float) -> Clearance:
        # the walls only: the team adds the others, for every robot at once, once all
        # have moved (TeamSim.step)
        assert isinstance(self._collider, CrowdCollider)
        return self._collider.static_clearance(x, y)

    def replace_scan(self, old: Scan, new: Scan) -> None:
        """Put ``new`` wherever this robot keeps ``old`` (readable, or waiting its latency)."""
        if self._scan is old:
            self._scan = new
        self._scan_queue = [(due, new if s is old else s) for due, s in self._scan_queue]

    def touched_by(self, event: SimEvent, name: str, index: int) -> None:
        """Record that robot ``name`` ran into this one (a collision; not stalled).

        A contact this robot already recorded at that moment (both drove into each
        other) is not recorded twice.
        """
        if self.events and _same_contact(self.events[-1], event, name):
            return
        self.events.append(SimEvent("collision", event.time, self._x, self._y, index, name))
        self._collided = True

    def _obstacle(self, index: int) -> tuple[str, str]:
        base = len(self.world.obstacles)
        if index >= base:
            return self.team.places[index - base].name, "robot"
        return super()._obstacle(index)

    def _take_scan(self, x: float, y: float, th: float, stamp: float) -> Scan:
        if not self._crowd:
            return super()._take_scan(x, y, th, stamp)
        discs = self.discs
        lad = self._ladar
        ox, oy = lad.origin(x, y, th)
        if self._batched and self._fan is not None:
            first = th + float(lad.bearings[0])
            if self._cast_later and self.team.stepping:
                # cast with the others' scans at the end of the step, in one pass
                scan = plain_scan(_LATER, lad.bearings, _LATER_VALID, stamp,
                                  lad.profile.max_range)
            else:
                ranges, hit = self._fan.cast(ox, oy, first)
                scan = plain_scan(ranges, lad.bearings, hit, stamp, lad.profile.max_range)
            self.team.pending.append(PendingScan(self, scan, ox, oy, first, self._fan_shape))
            return scan  # its ranges are final once the team has occluded and settled it
        angles = lad.world_angles(th)
        t, which = cast_discs(ox, oy, angles, discs, self.index, which=self._oracle)
        if self._fan is not None:
            ranges, hit = self._fan.cast(ox, oy, th + float(lad.bearings[0]))
            closer = t < np.where(hit, ranges, math.inf)
            closer &= t <= lad.profile.max_range
            ranges[closer] = t[closer]
            hit |= closer
            return lad.finish(ranges, hit, stamp)
        hits = self.world.caster.cast(np.array((ox, oy)), angles, lad.profile.max_range,
                                      detail=self._oracle, rel=lad.rel)
        return lad.measure(_occluded(hits, ox, oy, angles, t, which, discs), th, stamp)


def _same_contact(a: SimEvent, b: SimEvent, label: str | None = None) -> bool:
    """Whether two records are one contact: the same robot touched within half a second."""
    return a.label == (b.label if label is None else label) and abs(a.time - b.time) < 0.5


def _occluded(hits: Any, ox: float, oy: float, angles: np.ndarray, t: np.ndarray,
              which: np.ndarray | None, discs: Discs) -> Any:
    """Return ray hits with the discs in front of the walls (tangents, curvature too)."""
    closer = t < hits.ranges
    if not closer.any():
        return hits
    ranges = np.where(closer, t, hits.ranges)
    hit = hits.hit | closer
    tangents, curvatures = hits.tangents, hits.curvatures
    if tangents is not None and curvatures is not None and which is not None:
        px = ox + t * np.cos(angles)
        py = oy + t * np.sin(angles)
        k = which.clip(min=0)
        nx, ny = px - discs.cx[k], py - discs.cy[k]
        # the boundary runs clockwise round an obstacle: the outward normal turned right
        tangents = np.where(closer, np.arctan2(-nx, ny), tangents)
        curvatures = np.where(closer, -1.0 / discs.r[k], curvatures)
    owner = hits.owner
    return RayHits(ranges, hit, tangents, curvatures, owner)


class TeamSim:
    """The robots of a team in one world.

    Parameters
    ----------
    world : World
    places : sequence of RobotPlace
        The robots, each with a name unique in the team.
    seed : int
        Each robot's generators are seeded from it and the robot's position in the team.
    sensing : {"scan", "exact"}
    rules : DeliveryRules

    Raises
    ------
    WorldError
        A robot overlaps an obstacle or another robot at its start.
    """

    def __init__(self, world: World, places: Sequence[RobotPlace], *, seed: int = 0,
                 sensing: str = "scan", rules: DeliveryRules | None = None) -> None:
        self.world = world
        self.places = tuple(places)
        self.time = 0.0
        self._ticks = TickClock()   # the team's time in whole ticks, as each member's
        n = len(self.places)
        for i in range(n):
            for j in range(i):
                a, b = self.places[j], self.places[i]
                gap = math.hypot(a.start.x - b.start.x, a.start.y - b.start.y)
                if gap < a.profile.radius + b.profile.radius:
                    raise WorldError(f"robots `{a.name}` and `{b.name}` overlap at their "
                                     f"starts ({a.start.x:g}, {a.start.y:g}) and "
                                     f"({b.start.x:g}, {b.start.y:g}): their centres are "
                                     f"{gap:.3g} m apart, their radii add up to "
                                     f"{a.profile.radius + b.profile.radius:.3g} m")
        self.members: list[Member] = []
        ss = np.random.SeedSequence(seed)
        seeds = ss.generate_state(n + 1)
        for i, p in enumerate(self.places):
            try:
                self.members.append(Member(self, i, world, p, int(seeds[i]), sensing))
            except WorldError as err:
                raise WorldError(f"robot `{p.name}`: {err.diagnostics[0].message}") from None
        rules = rules if rules is not None else DeliveryRules()
        if rules.seed is None:
            rules = dataclasses.replace(rules, seed=int(seeds[n]))
        self.radio = Radio([p.name for p in self.places], rules)
        # x and y as rows (contiguous, for the compiled occlusions); _pos is its (N, 2) view
        self._xy = np.array([[m._x for m in self.members], [m._y for m in self.members]],
                            dtype=float).reshape(2, n)
        self._pos = self._xy.T
        # one set of discs for all, their centres views of _xy, which moves in place
        self._z = self._pos[:, 0] + 1j * self._pos[:, 1]
        self.discs = Discs(self._xy[0], self._xy[1],
                           np.array([p.profile.radius for p in self.places]), np.arange(n),
                           self._z)
        self._moved = [0.0] * n  # how far each robot moved in its last step, m
        r = self.discs.r
        self._touch = r[:, None] + r[None, :]   # centre distance at which two robots touch
        self._rows = np.arange(n)
        #: scans taken during a step, finished at its end
        self.pending: list[PendingScan] = []
        #: True during :meth:`step`: scans are then cast at its end, all in one pass
        self.stepping = False
        for m in self.members:  # the first scans see the others too
            m.join(self.discs)

    def positions(self) -> np.ndarray:
        """Return the true positions (N, 2), metres."""
        return self._pos

    def step(self, dt: float) -> None:
        """Move every robot by ``dt``, then deliver the messages sent during the tick."""
        sent_at = self._pos.copy()
        self.stepping = True
        try:
            self._move_all(dt)
        finally:
            self.stepping = False
        self.time = self._ticks.advance(dt)
        self._add_others_to_clearances()
        self._settle_scans()
        self.radio.deliver(self.time, [m.box for m in self.members], sent_at)

    def _move_all(self, dt: float) -> None:
        """Move the robots through the tick, in pieces where two of them could meet.

        Each piece ends before any two robots not yet in contact could touch (their gap
        over the sum of their speed bounds), so moving them one after the other within a
        piece never misses a contact or finds it late; robots in contact meet in their
        sweeps, as at a wall.
        """
        ends = [m.begin_tick(dt) for m in self.members]
        t = self.time
        for piece in range(MAX_PIECES + 1):
            horizon = self._horizon()
            last = piece == MAX_PIECES or t + horizon >= ends[0]
            self._move_piece(ends if last else [t + horizon] * len(ends), last)
            if last:
                return
            t += horizon

    def _horizon(self) -> float:
        """Return how long (s) every robot can move before two not in contact could touch."""
        n = len(self.members)
        if n < 2:
            return math.inf
        speed = np.array([m.speed_bound() for m in self.members])
        gaps = np.abs(self._z[:, None] - self._z)
        gaps -= self._touch                   # the sums of the radii, pair by pair
        closing = speed[:, None] + speed[None, :]
        apart = (gaps >= TOUCHING) & (closing > 0.0)
        apart.flat[::n + 1] = False           # not oneself
        if not apart.any():
            return math.inf
        return float((gaps[apart] / closing[apart]).min())

    def _move_piece(self, ends: list[float], last: bool) -> None:
        """Move the robots one after the other to ``ends``, each seeing the others there."""
        pos = self._pos
        moved = self._moved
        for i, m in enumerate(self.members):
            before = len(m.events)
            x0, y0 = m._x, m._y
            # its own last step too in the bound: a bound, not the least one
            m.move_to(ends[i], max(moved), last)
            moved[i] = math.hypot(m._x - x0, m._y - y0)
            pos[i, 0], pos[i, 1] = m._x, m._y
            self._z[i] = complex(m._x, m._y)
            new = m.events[before:]
            if new and before and _same_contact(m.events[before - 1], new[0]):
                del m.events[before]  # it was run into, and drove on into the same robot
                new = new[1:]
            for e in new:
                if e.obstacle >= len(self.world.obstacles):  # it touched another robot
                    j = e.obstacle - len(self.world.obstacles)
                    self.members[j].touched_by(e, m.name, len(self.world.obstacles) + i)

    def _add_others_to_clearances(self) -> None:
        """Fold the other robots into every robot's clearance, all pairs at once."""
        n = len(self.members)
        if n < 2:
            return
        z = self._z
        gaps = np.abs(z[:, None] - z)
        gaps -= self._touch                   # the sums of the radii, pair by pair
        gaps.flat[::n + 1] = np.inf           # not oneself (np.fill_diagonal, without its checks)
        near = gaps.argmin(axis=1)
        least = gaps[self._rows, near].tolist()
        base = len(self.world.obstacles)
        for m, gap, j in zip(self.members, least, near.tolist(), strict=True):
            if gap < m._clear.distance:
                m._clear = Clearance(gap, base + j)

    def _settle_scans(self) -> None:
        """Cast the scans taken during the step, put the robots into them, add their noise.

        The scans of robots with the same ladar are cast in one pass
        (:meth:`sim.raycast.FanCaster.cast_many`), and occluded and settled as one block
        (:func:`sim.ladar.settle_rows`); a scan cast at once (a world the batch does not
        take) is finished alone.
        """
        pending, self.pending = self.pending, []
        if not pending:
            return
        # One contiguous array per field of the pending scans
        ox = np.array([p.ox for p in pending])
        oy = np.array([p.oy for p in pending])
        first_angle = np.array([p.first for p in pending])
        step = np.array([p.fan.step for p in pending])
        beams_n = np.array([p.fan.beams for p in pending], dtype=np.intp)
        max_range = np.array([p.fan.max_range for p in pending])
        own = np.array([p.fan.own for p in pending], dtype=np.intp)
        scans = (ox, oy, first_angle, step, beams_n, max_range, own, self.discs)
        groups: dict[tuple[Any, ...], list[int]] = {}
        alone = []
        for k, p in enumerate(pending):
            m = p.member
            if p.scan.ranges is _LATER:
                # one profile object and mount per group (an id: no dataclass hash per scan)
                groups.setdefault((id(m._ladar.profile), m._ladar.mount), []).append(k)
            else:
                alone.append(k)
        cuts = None     # every scan's cuts, found when a group or a lone scan needs them
        for ks in groups.values():
            first = pending[ks[0]].member
            assert first._fan is not None
            if len(ks) == len(pending):     # every scan (the usual case): rows are scans
                ranges, valid = first._fan.cast_many(ox, oy, first_angle)
                occlude(*scans, ranges, valid)
            else:
                ranges, valid = first._fan.cast_many(ox[ks], oy[ks], first_angle[ks])
                scan_i, beam, t = cuts = cuts or occlusions(*scans)
                row = np.full(len(pending), -1)
                row[ks] = np.arange(len(ks))
                r = row[scan_i]
                mine = r >= 0
                rows, beams = r[mine], beam[mine]
                np.minimum.at(ranges, (rows, beams), t[mine])
                valid[rows, beams] = True
            settle_rows([pending[k].member._ladar for k in ks], ranges, valid)
            for j, k in enumerate(ks):
                m, old = pending[k].member, pending[k].scan
                m.replace_scan(old, plain_scan(ranges[j], old.bearings, valid[j], old.stamp,
                                               old.max_range))
        if alone:
            scan_i, beam, t = cuts = cuts or occlusions(*scans)
            bounds = np.searchsorted(scan_i, np.arange(len(pending) + 1))
            for k in alone:
                m, scan = pending[k].member, pending[k].scan
                a, b = int(bounds[k]), int(bounds[k + 1])
                if b > a:
                    np.minimum.at(scan.ranges, beam[a:b], t[a:b])
                    scan.valid[beam[a:b]] = True
                m._ladar.settle(scan.ranges, scan.valid)
