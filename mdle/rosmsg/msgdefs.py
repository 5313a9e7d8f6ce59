"""ROS 2 message definitions (``ros2msg`` text) for the MCAP schemas mdle writes.

An MCAP schema of encoding ``ros2msg`` holds the message's own definition followed by
every type it uses, each after a line of 80 ``=`` and a ``MSG: package/Type`` line, as
``ros2 bag record`` writes them. The fields below are those of ROS 2 Humble and Jazzy
(identical for these types; Jazzy only adds a Marker constant, ``ARROW_STRIP``); comments
are left out.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

__all__ = ["DEFINITIONS", "DIAGNOSTICS", "diagnostics_definition", "schema_text"]

#: mdle's own message type for a control law's diagnostics (one float64 field each).
DIAGNOSTICS = "mdle_msgs/msg/Diagnostics"

#: Each type's own fields, by its full name (``package/msg/Type``).
DEFINITIONS: dict[str, str] = {
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/msg/Duration": "int32 sec\nuint32 nanosec\n",
    "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "std_msgs/msg/String": "string data\n",
    "std_msgs/msg/ColorRGBA": "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n",
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Quaternion": (
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"),
    "geometry_msgs/msg/Point32": "float32 x\nfloat32 y\nfloat32 z\n",
    "geometry_msgs/msg/Polygon": "Point32[] points\n",
    "geometry_msgs/msg/PolygonStamped": "std_msgs/Header header\nPolygon polygon\n",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose\n",
    "geometry_msgs/msg/PoseWithCovariance": "Pose pose\nfloat64[36] covariance\n",
    "geometry_msgs/msg/Twist": "Vector3 linear\nVector3 angular\n",
    "geometry_msgs/msg/TwistWithCovariance": "Twist twist\nfloat64[36] covariance\n",
    "geometry_msgs/msg/Transform": "Vector3 translation\nQuaternion rotation\n",
    "geometry_msgs/msg/TransformStamped": (
        "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"),
    "tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    "nav_msgs/msg/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n"),
    "nav_msgs/msg/MapMetaData": (
        "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\n"
        "uint32 height\ngeometry_msgs/Pose origin\n"),
    "nav_msgs/msg/OccupancyGrid": (
        "std_msgs/Header header\nMapMetaData info\nint8[] data\n"),
    "sensor_msgs/msg/LaserScan": (
        "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n"
        "float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n"
        "float32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n"),
    "sensor_msgs/msg/CompressedImage": (
        "std_msgs/Header header\nstring format\nuint8[] data\n"),
    "visualization_msgs/msg/UVCoordinate": "float32 u\nfloat32 v\n",
    "visualization_msgs/msg/MeshFile": "string filename\nuint8[] data\n",
    "visualization_msgs/msg/Marker": (
        "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\n"
        "int32 LINE_STRIP=4\nint32 LINE_LIST=5\nint32 CUBE_LIST=6\nint32 SPHERE_LIST=7\n"
        "int32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\n"
        "int32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\n"
        "int32 DELETEALL=3\n"
        "std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\n"
        "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\n"
        "builtin_interfaces/Duration lifetime\nbool frame_locked\n"
        "geometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\n"
        "string texture_resource\nsensor_msgs/CompressedImage texture\n"
        "UVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n"
        "MeshFile mesh_file\nbool mesh_use_embedded_materials\n"),
    "visualization_msgs/msg/MarkerArray": "Marker[] markers\n",
}

_PRIMITIVES = frozenset({"bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32",
                         "uint32", "int64", "uint64", "float32", "float64", "string"})


def diagnostics_definition(names: Sequence[str]) -> str:
    """Return the definition of :data:`DIAGNOSTICS` with a float64 field per name.

    A header (the tick's time, frame ``base_link``), then one number per diagnostic, NaN
    when the running law does not record it: typed fields that plotting tools (Foxglove's
    Plot panel, PlotJuggler) show by name.
    """
    return "std_msgs/Header header\n" + "".join(f"float64 {n}\n" for n in names)


def _dependencies(name: str, definitions: Mapping[str, str]) -> list[str]:
    """Every type ``name`` uses, depth first, each once (full names)."""
    seen: list[str] = []

    def visit(full: str) -> None:
        package = full.partition("/")[0]
        for line in definitions[full].splitlines():
            words = line.split()
            if not words or "=" in line:
                continue
            base = words[0].split("[")[0]
            if base in _PRIMITIVES:
                continue
            pkg, _, typ = base.rpartition("/")
            dep = f"{pkg or package}/msg/{typ}"
            if dep not in seen and dep != name:
                seen.append(dep)
                visit(dep)

    visit(name)
    return seen


def schema_text(name: str, extra: Mapping[str, str] | None = None) -> str:
    """Return the ``ros2msg`` schema of the type ``name`` with every type it uses.

    ``extra`` adds definitions (mdle's :data:`DIAGNOSTICS`, whose fields depend on the
    laws). Raises KeyError for a type not in :data:`DEFINITIONS` or ``extra``.
    """
    definitions = {**DEFINITIONS, **extra} if extra else DEFINITIONS
    parts = [definitions[name]]
    for dep in _dependencies(name, definitions):
        pkg, _, typ = dep.split("/", 2)
        parts.append("=" * 80 + f"\nMSG: {pkg}/{typ}\n" + definitions[dep])
    return "\n".join(parts)
