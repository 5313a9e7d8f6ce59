import pytest

from mdle.core.errors import BackendError
from mdle.ros2.names import dds_topic, dds_type, frame_id, namespace, ros_topic
from mdle.ros2.typehash import type_description, type_hash

# What a ROS 2 Jazzy (rmw_cyclonedds) announced in its endpoints' USER_DATA, measured
# (design notes): mdle derives them from the message definitions.
JAZZY = {
    "geometry_msgs/msg/Twist":
        "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a",
    "sensor_msgs/msg/LaserScan":
        "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828",
    "nav_msgs/msg/Odometry":
        "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
    "tf2_msgs/msg/TFMessage":
        "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
}


@pytest.mark.parametrize("name", sorted(JAZZY))
def test_type_hashes_are_those_ros2_jazzy_announces(name: str) -> None:
    assert type_hash(name) == JAZZY[name]


def test_a_type_description_lists_every_used_type_once_sorted_without_defaults() -> None:
    d = type_description("nav_msgs/msg/Odometry")
    names = [t["type_name"] for t in d["referenced_type_descriptions"]]
    assert names == sorted(set(names))
    assert "geometry_msgs/msg/Quaternion" in names and "builtin_interfaces/msg/Time" in names
    quat = next(t for t in d["referenced_type_descriptions"]
                if t["type_name"] == "geometry_msgs/msg/Quaternion")
    assert all("default_value" not in f for f in quat["fields"])  # `float64 w 1` has one
    cov = d["referenced_type_descriptions"][names.index("geometry_msgs/msg/PoseWithCovariance")]
    assert cov["fields"][1]["type"] == {"type_id": 11 + 48, "capacity": 36,
                                        "string_capacity": 0, "nested_type_name": ""}


def test_ros_names_map_to_dds_names() -> None:
    assert dds_type("geometry_msgs/msg/Twist") == "geometry_msgs::msg::dds_::Twist_"
    assert dds_topic(ros_topic("", "cmd_vel")) == "rt/cmd_vel"
    assert dds_topic(ros_topic("/robot1", "cmd_vel")) == "rt/robot1/cmd_vel"
    assert ros_topic("/robot1", "/clock") == "/clock"
    assert frame_id("/lab/robot1", "odom") == "lab/robot1/odom"
    assert frame_id("", "odom") == "odom"


@pytest.mark.parametrize(("text", "canonical"), [
    (None, ""), ("", ""), ("/", ""), ("robot1", "/robot1"), ("/lab/robot_1/", "/lab/robot_1")])
def test_namespaces_are_made_canonical(text: str | None, canonical: str) -> None:
    assert namespace(text) == canonical


@pytest.mark.parametrize("bad", ["1robot", "ro-bot", "a//b", "a__b", "robot 1"])
def test_a_bad_namespace_is_refused_naming_the_part(bad: str) -> None:
    with pytest.raises(BackendError, match="--ns .*is not a ROS name part"):
        namespace(bad)
