"""Builders for the ROS 2 messages the package logs and publishes.

This is the one place that builds messages. Each builder takes plain data and returns an
instance from the rosbags typestore for ROS 2 Jazzy (``TYPESTORE``); ``mcap_log`` serialises
these to CDR, and the ROS layer converts them to rclpy messages by field name.

Conventions: stamps are integer nanoseconds of simulated time (>= 0); lengths in metres,
angles in radians, efforts in N m (revolute) or N (prismatic); quaternions are given and
stored in ROS order (x, y, z, w) and must be unit length. Every numeric field is checked:
a NaN or infinite value raises ``MessageFieldError`` naming the field, so nothing non-finite
is ever logged or published as if it were valid.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
from rosbags.typesys import Stores, get_typestore

from youbot_dynamics.dynamics.collision import Shape
from youbot_dynamics.model.lie import quaternion_from_matrix
from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.io.drawn_shapes import drawn_shape

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
"""The rosbags typestore (ROS 2 Jazzy) every message here comes from."""

_T = TYPESTORE.types
Time = _T["builtin_interfaces/msg/Time"]
Header = _T["std_msgs/msg/Header"]
JointState = _T["sensor_msgs/msg/JointState"]
Point = _T["geometry_msgs/msg/Point"]
Vector3 = _T["geometry_msgs/msg/Vector3"]
Quaternion = _T["geometry_msgs/msg/Quaternion"]
Pose = _T["geometry_msgs/msg/Pose"]
PoseStamped = _T["geometry_msgs/msg/PoseStamped"]
PoseArray = _T["geometry_msgs/msg/PoseArray"]
Transform = _T["geometry_msgs/msg/Transform"]
TransformStamped = _T["geometry_msgs/msg/TransformStamped"]
TFMessage = _T["tf2_msgs/msg/TFMessage"]
Clock = _T["rosgraph_msgs/msg/Clock"]
KeyValue = _T["diagnostic_msgs/msg/KeyValue"]
DiagnosticStatus = _T["diagnostic_msgs/msg/DiagnosticStatus"]
DiagnosticArray = _T["diagnostic_msgs/msg/DiagnosticArray"]
Duration = _T["builtin_interfaces/msg/Duration"]
ColorRGBA = _T["std_msgs/msg/ColorRGBA"]
CompressedImage = _T["sensor_msgs/msg/CompressedImage"]
MeshFile = _T["visualization_msgs/msg/MeshFile"]
Marker = _T["visualization_msgs/msg/Marker"]
MarkerArray = _T["visualization_msgs/msg/MarkerArray"]
String = _T["std_msgs/msg/String"]
Odometry = _T["nav_msgs/msg/Odometry"]
Twist = _T["geometry_msgs/msg/Twist"]
TwistWithCovariance = _T["geometry_msgs/msg/TwistWithCovariance"]
PoseWithCovariance = _T["geometry_msgs/msg/PoseWithCovariance"]
Wrench = _T["geometry_msgs/msg/Wrench"]
WrenchStamped = _T["geometry_msgs/msg/WrenchStamped"]
Imu = _T["sensor_msgs/msg/Imu"]

UNIT_QUATERNION_TOLERANCE = 1e-6
"""Largest accepted | |q| - 1 | for a quaternion in a message."""

DIAGNOSTIC_LEVELS = {"OK": 0, "WARN": 1, "ERROR": 2, "STALE": 3}
"""diagnostic_msgs/DiagnosticStatus levels by name."""


class MessageFieldError(ValueError):
    """A message field would hold an invalid value (NaN, inf, wrong length, bad stamp)."""

    def __init__(self, field_name: str, problem: str) -> None:
        super().__init__(f"{field_name}: {problem}")
        self.field = field_name


def finite_array(values: Iterable[float], field_name: str, length: int | None = None) -> np.ndarray:
    """Return ``values`` as a float64 vector, checking that every entry is finite.

    ``length``, when given, is the required number of entries. Raises ``MessageFieldError``
    naming ``field_name`` (and the index) otherwise. For long vectors; see ``finite_floats``.
    """
    array = np.asarray(values, dtype=np.float64).reshape(-1)
    if length is not None and array.size != length:
        raise MessageFieldError(field_name, f"has {array.size} entries, expected {length}")
    if not np.isfinite(array).all():
        index = int(np.flatnonzero(~np.isfinite(array))[0])
        raise _not_finite(field_name, index, array[index])
    return array


def finite_floats(values: Iterable[float], field_name: str, length: int) -> list[float]:
    """``finite_array`` for short fixed-length fields (xyz, quaternions), without numpy."""
    floats = [float(value) for value in values]
    if len(floats) != length:
        raise MessageFieldError(field_name, f"has {len(floats)} entries, expected {length}")
    for index, value in enumerate(floats):
        if not math.isfinite(value):
            raise _not_finite(field_name, index, value)
    return floats


def stamps_ns(values: Iterable[int], field_name: str) -> np.ndarray:
    """``values`` as an int64 vector of stamps (integer nanoseconds, >= 0). Raises
    ``MessageFieldError`` naming ``field_name`` for a float (even a whole one: times are
    never carried in float seconds here), a bool or a negative stamp."""
    array = np.asarray(values).reshape(-1)
    if array.size and not (np.issubdtype(array.dtype, np.integer) and array.dtype != np.bool_):
        raise MessageFieldError(field_name, f"must be integer nanoseconds, got {array.dtype} values")
    if array.size and array.min() < 0:
        raise MessageFieldError(field_name, f"must be >= 0 ns, got {int(array.min())}")
    return array.astype(np.int64)


def _not_finite(field_name: str, index: int, value: float) -> MessageFieldError:
    return MessageFieldError(f"{field_name}[{index}]", f"is {value}, not finite")


def time(stamp_ns: int) -> Time:
    """builtin_interfaces/Time for ``stamp_ns`` nanoseconds (integer, >= 0)."""
    if isinstance(stamp_ns, bool) or not isinstance(stamp_ns, (int, np.integer)):
        raise MessageFieldError("stamp", f"must be integer nanoseconds, got {stamp_ns!r}")
    if stamp_ns < 0:
        raise MessageFieldError("stamp", f"must be >= 0 ns, got {stamp_ns}")
    sec, nanosec = divmod(int(stamp_ns), NS_PER_S)
    if sec >= 2**31:
        raise MessageFieldError("stamp", f"{stamp_ns} ns does not fit builtin_interfaces/Time")
    return Time(sec=sec, nanosec=nanosec)


def header(stamp_ns: int, frame_id: str) -> Header:
    """std_msgs/Header with stamp ``stamp_ns`` (ns) and frame ``frame_id``."""
    return Header(stamp=time(stamp_ns), frame_id=str(frame_id))


def unit_quaternion(quaternion_xyzw: Sequence[float], field_name: str) -> Quaternion:
    """geometry_msgs/Quaternion from (x, y, z, w), which must be finite and of unit norm."""
    x, y, z, w = finite_floats(quaternion_xyzw, field_name, 4)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if abs(norm - 1.0) > UNIT_QUATERNION_TOLERANCE:
        raise MessageFieldError(field_name, f"has norm {norm}, expected a unit quaternion")
    return Quaternion(x=x, y=y, z=z, w=w)


def joint_state(
    stamp_ns: int,
    names: Sequence[str],
    position: Sequence[float],
    velocity: Sequence[float] = (),
    effort: Sequence[float] = (),
) -> JointState:
    """sensor_msgs/JointState: positions (rad or m), velocities (rad/s or m/s), efforts.

    Each of position, velocity and effort is either empty or has one entry per name, as
    the message definition allows. Names must be unique.
    """
    names = [str(name) for name in names]
    if len(set(names)) != len(names):
        raise MessageFieldError("JointState.name", f"has duplicate joint names {names}")
    arrays = {}
    for label, values in (("position", position), ("velocity", velocity), ("effort", effort)):
        array = finite_array(values, f"JointState.{label}")
        if array.size not in (0, len(names)):
            raise MessageFieldError(
                f"JointState.{label}", f"has {array.size} entries for {len(names)} joints"
            )
        arrays[label] = array
    return JointState(header=header(stamp_ns, ""), name=names, **arrays)


def pose_stamped(
    stamp_ns: int,
    frame_id: str,
    position_xyz: Sequence[float],
    quaternion_xyzw: Sequence[float],
) -> PoseStamped:
    """geometry_msgs/PoseStamped: position (m) and orientation of a frame in ``frame_id``."""
    return PoseStamped(header=header(stamp_ns, frame_id),
                       pose=pose(position_xyz, quaternion_xyzw, "PoseStamped.pose"))


def pose(position_xyz: Sequence[float], quaternion_xyzw: Sequence[float], field_name: str = "Pose") -> Pose:
    """geometry_msgs/Pose: position (m) and unit quaternion (x, y, z, w)."""
    x, y, z = finite_floats(position_xyz, f"{field_name}.position", 3)
    orientation = unit_quaternion(quaternion_xyzw, f"{field_name}.orientation")
    return Pose(position=Point(x=x, y=y, z=z), orientation=orientation)


def pose_array(
    stamp_ns: int,
    frame_id: str,
    poses: Iterable[tuple[Sequence[float], Sequence[float]]],
) -> PoseArray:
    """geometry_msgs/PoseArray: (position (m), quaternion (x, y, z, w)) of several frames in
    ``frame_id``, in the given order (the message carries no names: the publisher documents
    the order)."""
    return PoseArray(header=header(stamp_ns, frame_id),
                     poses=[pose(position, quaternion, f"PoseArray.poses[{index}]")
                            for index, (position, quaternion) in enumerate(poses)])


def transform_stamped(
    stamp_ns: int,
    parent: str,
    child: str,
    translation: Sequence[float],
    quaternion_xyzw: Sequence[float],
) -> TransformStamped:
    """geometry_msgs/TransformStamped: pose (m, unit quaternion) of ``child`` in ``parent``."""
    x, y, z = finite_floats(translation, f"TransformStamped[{child}].translation", 3)
    rotation = unit_quaternion(quaternion_xyzw, f"TransformStamped[{child}].rotation")
    transform = Transform(translation=Vector3(x=x, y=y, z=z), rotation=rotation)
    return TransformStamped(
        header=header(stamp_ns, parent), child_frame_id=str(child), transform=transform
    )


def odometry(stamp_ns: int, frame_id: str, child_frame_id: str, position_xyz: Sequence[float],
             quaternion_xyzw: Sequence[float], twist: Sequence[float], pose_covariance: Sequence[float],
             twist_covariance: Sequence[float]) -> Odometry:
    """nav_msgs/Odometry: the pose (m, unit quaternion) of ``child_frame_id`` in
    ``frame_id``, its twist (vx, vy, vz m/s, wx, wy, wz rad/s) in ``child_frame_id``, the
    row-major 6x6 covariances (x, y, z, rotation about x, y, z)."""
    vx, vy, vz, wx, wy, wz = finite_floats(twist, "Odometry.twist", 6)
    return Odometry(header=header(stamp_ns, frame_id), child_frame_id=str(child_frame_id),
                    pose=PoseWithCovariance(pose=pose(position_xyz, quaternion_xyzw, "Odometry.pose"),
                                            covariance=finite_array(pose_covariance, "Odometry.pose.covariance", 36)),
                    twist=TwistWithCovariance(twist=Twist(linear=Vector3(x=vx, y=vy, z=vz),
                                                          angular=Vector3(x=wx, y=wy, z=wz)),
                                              covariance=finite_array(twist_covariance, "Odometry.twist.covariance",
                                                                      36)))


def wrench_stamped(stamp_ns: int, frame_id: str, force: Sequence[float], torque: Sequence[float]) -> WrenchStamped:
    """geometry_msgs/WrenchStamped: force (N) and torque (N m) about ``frame_id``'s origin, in
    that frame."""
    fx, fy, fz = finite_floats(force, "WrenchStamped.wrench.force", 3)
    tx, ty, tz = finite_floats(torque, "WrenchStamped.wrench.torque", 3)
    return WrenchStamped(header=header(stamp_ns, frame_id),
                         wrench=Wrench(force=Vector3(x=fx, y=fy, z=fz), torque=Vector3(x=tx, y=ty, z=tz)))


def imu(stamp_ns: int, frame_id: str, quaternion_xyzw: Sequence[float], angular_velocity: Sequence[float],
        linear_acceleration: Sequence[float], covariances: Sequence[Sequence[float]]) -> Imu:
    """sensor_msgs/Imu in ``frame_id``: orientation (unit quaternion), angular velocity
    (rad/s), linear acceleration (m/s^2) and their row-major 3x3 ``covariances`` (in that
    order; REP 145: -1 in element 0 for a quantity not provided)."""
    wx, wy, wz = finite_floats(angular_velocity, "Imu.angular_velocity", 3)
    ax, ay, az = finite_floats(linear_acceleration, "Imu.linear_acceleration", 3)
    orientation, angular, linear = (finite_array(c, f"Imu.{name}_covariance", 9) for c, name in
                                    zip(covariances, ("orientation", "angular_velocity", "linear_acceleration")))
    return Imu(header=header(stamp_ns, frame_id), orientation=unit_quaternion(quaternion_xyzw, "Imu.orientation"),
               orientation_covariance=orientation, angular_velocity=Vector3(x=wx, y=wy, z=wz),
               angular_velocity_covariance=angular, linear_acceleration=Vector3(x=ax, y=ay, z=az),
               linear_acceleration_covariance=linear)


def tf_message(transforms: Iterable[TransformStamped]) -> TFMessage:
    """tf2_msgs/TFMessage holding ``transforms`` (for /tf or /tf_static)."""
    return TFMessage(transforms=list(transforms))


def string(text: str) -> String:
    """std_msgs/String holding ``text`` (for /robot_description: the URDF XML)."""
    return String(data=str(text))


def clock(stamp_ns: int) -> Clock:
    """rosgraph_msgs/Clock at ``stamp_ns`` nanoseconds of simulated time."""
    return Clock(clock=time(stamp_ns))


def diagnostic_status(
    name: str,
    level: str | int = "OK",
    message: str = "",
    hardware_id: str = "",
    values: Mapping[str, object] | None = None,
) -> DiagnosticStatus:
    """diagnostic_msgs/DiagnosticStatus.

    ``level`` is a name of ``DIAGNOSTIC_LEVELS`` or its number; ``values`` maps keys to
    strings or numbers (numbers must be finite; floats are written with ``repr``).
    """
    number = DIAGNOSTIC_LEVELS.get(level) if isinstance(level, str) else level
    if number not in DIAGNOSTIC_LEVELS.values():
        raise MessageFieldError(
            f"DiagnosticStatus[{name}].level",
            f"is {level!r}, expected one of {list(DIAGNOSTIC_LEVELS)} or 0..3",
        )
    pairs = [
        KeyValue(key=str(key), value=_diagnostic_value(name, key, value))
        for key, value in (values or {}).items()
    ]
    return DiagnosticStatus(
        level=int(number), name=str(name), message=str(message),
        hardware_id=str(hardware_id), values=pairs,
    )


def _diagnostic_value(status: str, key: str, value: object) -> str:
    """The text of one key/value, refusing non-finite numbers."""
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        if not math.isfinite(value):
            raise MessageFieldError(
                f"DiagnosticStatus[{status}].values[{key}]", f"is {value}, not finite"
            )
        return repr(float(value))
    return str(value)


def diagnostic_array(stamp_ns: int, statuses: Iterable[DiagnosticStatus]) -> DiagnosticArray:
    """diagnostic_msgs/DiagnosticArray at ``stamp_ns`` holding ``statuses``."""
    return DiagnosticArray(header=header(stamp_ns, ""), status=list(statuses))


def marker(stamp_ns: int, frame_id: str, namespace: str, marker_id: int, kind: int,
           pose_in_frame: Pose, scale: Sequence[float], rgba: Sequence[float], *,
           frame_locked: bool = False) -> Marker:
    """visualization_msgs/Marker to ADD (or replace: same ``namespace`` and ``marker_id``) a
    primitive ``kind`` (Marker.CUBE, SPHERE, CYLINDER) at ``pose_in_frame`` in ``frame_id``,
    of ``scale`` (m: the box's edges; the sphere's or cylinder's diameters along x, y and
    its height along z) and colour ``rgba`` (0..1), shown until replaced (zero lifetime).
    ``frame_locked`` asks viewers to move it with its frame (for shapes on robot links)."""
    sx, sy, sz = finite_floats(scale, f"Marker[{namespace}].scale", 3)
    r, g, b, a = finite_floats(rgba, f"Marker[{namespace}].color", 4)
    return Marker(header=header(stamp_ns, frame_id), ns=str(namespace), id=int(marker_id), type=int(kind),
                  action=Marker.ADD, pose=pose_in_frame, scale=Vector3(x=sx, y=sy, z=sz),
                  color=ColorRGBA(r=r, g=g, b=b, a=a), lifetime=Duration(sec=0, nanosec=0),
                  frame_locked=bool(frame_locked), points=[], colors=[], texture_resource="",
                  texture=CompressedImage(header=header(0, ""), format="", data=np.zeros(0, np.uint8)),
                  uv_coordinates=[], text="", mesh_resource="",
                  mesh_file=MeshFile(filename="", data=np.zeros(0, np.uint8)), mesh_use_embedded_materials=False)


def shape_markers(stamp_ns: int, frame_id: str, name: str, shape: Shape, placement: np.ndarray,
                  rgba: Sequence[float], *, frame_locked: bool = False) -> list[Marker]:
    """The markers that draw ``shape`` (m) placed by ``placement`` (4x4) in ``frame_id``,
    in namespace ``name``: a sphere, box or cylinder is one marker (id 0); a capsule (no
    marker type of its own) a cylinder (id 0) and its two end spheres (ids 1, 2); a
    halfspace the plate ``io.drawn_shapes.drawn_shape`` draws."""
    shape, placement = drawn_shape(shape, placement)
    radius, length = shape.radius, shape.length

    def placed(kind: int, marker_id: int, scale: Sequence[float], along_z: float = 0.0) -> Marker:
        position = placement[:3, 3] + along_z * placement[:3, 2]
        where = pose(position, quaternion_from_matrix(placement[:3, :3]), f"Marker[{name}].pose")
        return marker(stamp_ns, frame_id, name, marker_id, kind, where, scale, rgba, frame_locked=frame_locked)

    if shape.kind == "sphere":
        return [placed(Marker.SPHERE, 0, [2 * radius] * 3)]
    if shape.kind == "box":
        return [placed(Marker.CUBE, 0, shape.size)]
    cylinder = placed(Marker.CYLINDER, 0, [2 * radius, 2 * radius, length])
    if shape.kind == "cylinder":
        return [cylinder]
    return [cylinder, *(placed(Marker.SPHERE, k, [2 * radius] * 3, end * 0.5 * length)
                        for k, end in ((1, 1.0), (2, -1.0)))]


def marker_array(markers: Iterable[Marker]) -> MarkerArray:
    """visualization_msgs/MarkerArray holding ``markers``."""
    return MarkerArray(markers=list(markers))
