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
String = _T["std_msgs/msg/String"]

NS_PER_S = 1_000_000_000
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
