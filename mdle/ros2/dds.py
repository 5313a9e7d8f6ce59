"""A DDS participant that looks like a ROS 2 node on the wire (Cyclone DDS).

:class:`Node` makes readers and writers with ROS 2's topic and type names
(:mod:`mdle.ros2.names`), ROS 2's usual QoS (:data:`SENSOR`, :data:`RELIABLE`,
:data:`LATCHED`, :data:`CLOCK`) and the type hash that rmw_cyclonedds puts in each
endpoint's USER_DATA (``typehash=RIHS01_...;``), so ``ros2 topic info -v`` shows the
real hash. The domain id is ROS's (``ROS_DOMAIN_ID``); Cyclone's own settings come from
``CYCLONEDDS_URI`` as for any ROS 2 node. :func:`loopback_config` writes the settings
that keep all traffic on 127.0.0.1 (the tests use it).
"""

from __future__ import annotations

import enum
import os
from typing import Any

from mdle.core.errors import BackendError
from mdle.ros2.names import dds_topic, ros_topic

__all__ = ["Node", "QosKind", "domain_id", "loopback_config", "require", "take"]

INSTALL_HINT = "install the extra: pip install 'mdle[ros2]' (the cyclonedds package)"
#: Cyclone's default port mapping reaches domain ids 0..232.
MAX_DOMAIN_ID = 232


def require(what: str) -> None:
    """Check that Cyclone DDS imports; raise :class:`BackendError` saying how if not."""
    try:
        import cyclonedds.domain  # noqa: F401
    except ImportError as exc:
        raise BackendError(f"{what} needs the cyclonedds package, which is not installed "
                           f"or does not load ({exc}); {INSTALL_HINT}") from None


def domain_id(given: int | None) -> int:
    """Return the DDS domain: ``given``, else ``ROS_DOMAIN_ID``, else 0 (ROS's rule).

    Raises BackendError for a value outside 0..232.
    """
    where = "--domain-id"
    value: Any = given
    if value is None:
        where = "ROS_DOMAIN_ID"
        value = os.environ.get("ROS_DOMAIN_ID", "").strip() or 0
    try:
        number = int(value)
    except ValueError:
        raise BackendError(f"{where} `{value}` is not a whole number") from None
    if not 0 <= number <= MAX_DOMAIN_ID:
        raise BackendError(f"{where} {number} is outside 0..{MAX_DOMAIN_ID}")
    return number


def loopback_config(max_participants: int = 30) -> str:
    """Return a Cyclone configuration (XML) that keeps every packet on 127.0.0.1.

    The loopback interface only, no multicast, 127.0.0.1 as the one unicast peer, and
    participant indices from 0 (their ports are probed) up to ``max_participants``. Put
    it in ``CYCLONEDDS_URI`` (the text itself, or ``file://`` a file holding it).
    """
    return ("<CycloneDDS><Domain Id=\"any\"><General><Interfaces>"
            "<NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
            "<AllowMulticast>false</AllowMulticast></General>"
            "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
            f"<MaxAutoParticipantIndex>{max_participants}</MaxAutoParticipantIndex>"
            "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
            "</Domain></CycloneDDS>")


def take(reader: Any, n: int) -> list[Any]:
    """Take up to ``n`` samples from ``reader``: the messages only.

    A writer that leaves (its node ended) makes a sample without data, an
    ``InvalidSample``, which says so; it carries no message.
    """
    return [s for s in reader.take(n) if getattr(s, "sample_info", None) is not None
            and s.sample_info.valid_data]


class QosKind(enum.Enum):
    """The QoS profiles of ROS 2 that mdle's endpoints use."""

    SENSOR = "sensor"
    """rclcpp's SensorDataQoS: best effort, volatile, keep last 5 (scans, odometry
    readers: a best-effort reader also matches a reliable writer)."""
    RELIABLE = "reliable"
    """ROS 2's default: reliable, volatile, keep last 10 (``cmd_vel``, ``tf``)."""
    LATCHED = "latched"
    """``tf_static``: reliable, transient local, keep last 1 (late joiners get it)."""
    CLOCK = "clock"
    """``/clock``: reliable, volatile, keep last 1 (rclcpp's ClockQoS readers are best
    effort, which matches)."""


def _qos(kind: QosKind, typehash: str) -> Any:
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration

    reliable = Policy.Reliability.Reliable(duration(milliseconds=100))
    policies: list[Any] = {
        QosKind.SENSOR: [Policy.Reliability.BestEffort, Policy.Durability.Volatile,
                         Policy.History.KeepLast(5)],
        QosKind.RELIABLE: [reliable, Policy.Durability.Volatile, Policy.History.KeepLast(10)],
        QosKind.LATCHED: [reliable, Policy.Durability.TransientLocal,
                          Policy.History.KeepLast(1)],
        QosKind.CLOCK: [reliable, Policy.Durability.Volatile, Policy.History.KeepLast(1)],
    }[kind]
    return Qos(*policies, Policy.Userdata(f"typehash={typehash};".encode("ascii")))


class Node:
    """One DDS participant for one process, with ROS 2's names, in namespace ``ns``.

    Parameters
    ----------
    domain : int
        The DDS domain (ROS_DOMAIN_ID).
    ns : str
        A canonical namespace (:func:`mdle.ros2.names.namespace`): relative topics are
        made in it.

    Raises
    ------
    BackendError
        Cyclone is missing, or cannot make the participant (its configuration is bad).
    """

    def __init__(self, domain: int, ns: str = "") -> None:
        require("ROS 2")
        from cyclonedds.core import DDSException
        from cyclonedds.domain import DomainParticipant

        self.ns = ns
        self.domain = domain
        try:
            self.participant = DomainParticipant(domain)
        except DDSException as exc:
            raise BackendError(f"cannot join DDS domain {domain}: {exc} (check "
                               f"CYCLONEDDS_URI)") from None
        self._topics: dict[str, Any] = {}

    def _topic(self, name: str, cls: type[Any]) -> tuple[str, Any]:
        from cyclonedds.topic import Topic

        full = ros_topic(self.ns, name)
        topic = self._topics.get(full)
        if topic is None:
            topic = self._topics[full] = Topic(self.participant, dds_topic(full), cls)
        return full, topic

    def writer(self, name: str, cls: type[Any], kind: QosKind) -> Any:
        """Return a DataWriter of ``cls`` messages on topic ``name`` (relative or absolute)."""
        from cyclonedds.pub import DataWriter

        from mdle.ros2.typehash import type_hash
        from mdle.ros2.types import ROS_TYPES

        _, topic = self._topic(name, cls)
        return DataWriter(self.participant, topic, qos=_qos(kind, type_hash(ROS_TYPES[cls])))

    def reader(self, name: str, cls: type[Any], kind: QosKind) -> Any:
        """Return a DataReader of ``cls`` messages on topic ``name`` (relative or absolute)."""
        from cyclonedds.sub import DataReader

        from mdle.ros2.typehash import type_hash
        from mdle.ros2.types import ROS_TYPES

        _, topic = self._topic(name, cls)
        return DataReader(self.participant, topic, qos=_qos(kind, type_hash(ROS_TYPES[cls])))

    def topic_name(self, name: str) -> str:
        """Return the full ROS name of topic ``name`` in this node's namespace."""
        return ros_topic(self.ns, name)
