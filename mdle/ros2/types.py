"""The ROS 2 messages mdle sends and receives, as Cyclone DDS IDL types with ROS 2's names.

Each class is a :class:`cyclonedds.idl.IdlStruct` whose DDS type name is the one a ROS 2
node uses (``geometry_msgs::msg::dds_::Twist_``), with the fields of the ROS 2 Humble and
Jazzy definitions in order, so Cyclone's CDR of a message is byte for byte what rclpy
sends (the tests compare it with mdle's recording encoder). :data:`ROS_TYPES` names each
class's ROS type, for topics' type hashes (:mod:`mdle.ros2.typehash`). Importing this
module needs the ``cyclonedds`` package (``pip install 'mdle[ros2]'``).
"""

# No ``from __future__ import annotations``: Cyclone reads the field types from the
# evaluated annotations.
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as t

if TYPE_CHECKING:  # what the IDL types hold, as mypy knows them
    Covariance = list[float]
    Floats = list[float]
    Transforms = list["TransformStamped"]
else:
    Covariance = t.array[t.float64, 36]
    Floats = t.sequence[t.float32]

__all__ = ["ROS_TYPES", "Clock", "Header", "LaserScan", "Odometry", "Pose",
           "PoseWithCovariance", "Quaternion", "TFMessage", "Time", "Transform",
           "TransformStamped", "Twist", "TwistStamped", "TwistWithCovariance", "Vector3",
           "Point"]


def _zero36() -> list[float]:
    return [0.0] * 36


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    """``builtin_interfaces/Time``: seconds and nanoseconds."""

    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    """``std_msgs/Header``: a stamp and a frame id."""

    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    """``geometry_msgs/Vector3``."""

    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    """``geometry_msgs/Point``."""

    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    """``geometry_msgs/Quaternion`` (the identity by default)."""

    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0
    w: t.float64 = 1.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    """``geometry_msgs/Pose``."""

    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    """``geometry_msgs/PoseWithCovariance``."""

    pose: Pose = field(default_factory=Pose)
    covariance: Covariance = field(default_factory=_zero36)


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    """``geometry_msgs/Twist``: linear (m/s) and angular (rad/s) velocity."""

    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    """``geometry_msgs/TwistStamped``."""

    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@dataclass
class TwistWithCovariance(IdlStruct,
                          typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    """``geometry_msgs/TwistWithCovariance``."""

    twist: Twist = field(default_factory=Twist)
    covariance: Covariance = field(default_factory=_zero36)


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    """``nav_msgs/Odometry``: pose in ``header.frame_id``, twist in ``child_frame_id``."""

    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    """``sensor_msgs/LaserScan``."""

    header: Header = field(default_factory=Header)
    angle_min: t.float32 = 0.0
    angle_max: t.float32 = 0.0
    angle_increment: t.float32 = 0.0
    time_increment: t.float32 = 0.0
    scan_time: t.float32 = 0.0
    range_min: t.float32 = 0.0
    range_max: t.float32 = 0.0
    ranges: Floats = field(default_factory=list)
    intensities: Floats = field(default_factory=list)


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    """``geometry_msgs/Transform``."""

    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    """``geometry_msgs/TransformStamped``: ``header.frame_id`` -> ``child_frame_id``."""

    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


if not TYPE_CHECKING:
    Transforms = t.sequence[TransformStamped]


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    """``tf2_msgs/TFMessage``."""

    transforms: Transforms = field(default_factory=list)


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    """``rosgraph_msgs/Clock``: the simulated time."""

    clock: Time = field(default_factory=Time)


#: The ROS type of each message class.
ROS_TYPES: dict[type[IdlStruct], str] = {
    Twist: "geometry_msgs/msg/Twist",
    TwistStamped: "geometry_msgs/msg/TwistStamped",
    Odometry: "nav_msgs/msg/Odometry",
    LaserScan: "sensor_msgs/msg/LaserScan",
    TFMessage: "tf2_msgs/msg/TFMessage",
    Clock: "rosgraph_msgs/msg/Clock",
}
