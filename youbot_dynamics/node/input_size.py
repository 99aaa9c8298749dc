"""The size of an input message judged on its serialized form (CDR, with its 4-byte
encapsulation header, as an rclpy subscription with ``raw=True`` hands it over), before it
is deserialised.

Deserialising costs per element, not per byte: a /joint_trajectory of 40 000 points with
empty arrays is under 1 MiB of CDR (24 bytes a point) and took 0.27 s to deserialise on an
idle machine (about 2 s under load) before its point count could be refused. So
:func:`check_serialized` refuses (``too_large``) a message over its topic's ``max_bytes``,
and reads the counts that deserialisation would loop over from the first bytes: the joint
names of a sensor_msgs/JointState (more than :data:`~youbot_dynamics.node.commands.MAX_NAMES`)
and the joint names and points of a trajectory_msgs/JointTrajectory (more than
:data:`~youbot_dynamics.node.commands.MAX_TRAJECTORY_POINTS`). Reading them walks the header
and at most ``MAX_NAMES`` names: bounded work whatever the message. Bytes too short to hold
what they announce are left to the deserialiser, which refuses them.
"""
from __future__ import annotations

import struct

from youbot_dynamics.node.commands import MAX_NAMES, MAX_TRAJECTORY_POINTS, InputRejected

ENCAPSULATION = 4
"""Bytes of the CDR encapsulation header (its second byte: 0 big endian, 1 little endian)."""
_HEADER_STAMP = 8
"""Bytes of std_msgs/Header's stamp (int32 sec, uint32 nanosec) before its frame_id."""
COUNTED = {"sensor_msgs/msg/JointState": ("joint names",),
           "trajectory_msgs/msg/JointTrajectory": ("joint names", "points")}
"""The counts read from a serialized message of each type, in the order they come (every
other type is judged by its bytes alone)."""
LIMITS = {"joint names": MAX_NAMES, "points": MAX_TRAJECTORY_POINTS}
"""The largest count of each kind a message may carry."""


class _Reader:
    """Aligned reads of uint32s from CDR ``data`` (alignment relative to the end of the
    encapsulation header); :meth:`uint32` returns None past the end."""

    def __init__(self, data: bytes) -> None:
        self.data, self.offset = data, ENCAPSULATION + _HEADER_STAMP
        self.format = "<I" if len(data) > 1 and data[1] & 1 else ">I"

    def uint32(self) -> int | None:
        self.offset += -(self.offset - ENCAPSULATION) % 4
        if self.offset + 4 > len(self.data):
            return None
        (value,) = struct.unpack_from(self.format, self.data, self.offset)
        self.offset += 4
        return value

    def skip_string(self) -> bool:
        """Skip one string (uint32 length with its NUL, then the bytes); False past the end."""
        length = self.uint32()
        if length is None or self.offset + length > len(self.data):
            return False
        self.offset += length
        return True


def leading_counts(data: bytes, msgtype: str) -> dict[str, int]:
    """The counts of :data:`COUNTED` that the serialized ``msgtype`` message ``data``
    announces, read in order (a count over its limit ends the reading: nothing after it is
    walked); those the bytes are too short to reach are missing."""
    counts: dict[str, int] = {}
    kinds = COUNTED.get(msgtype, ())
    if not kinds:
        return counts
    reader = _Reader(data)
    if not reader.skip_string():     # the header's frame_id
        return counts
    for kind in kinds:
        count = reader.uint32()
        if count is None:
            return counts
        counts[kind] = count
        if count > LIMITS[kind] or kind != "joint names":
            return counts
        if not all(reader.skip_string() for _ in range(count)):
            return counts
    return counts


def check_serialized(data: bytes, msgtype: str, max_bytes: int) -> None:
    """Refuse (raise :class:`InputRejected` ``too_large``) the serialized ``msgtype``
    message ``data`` if it has more than ``max_bytes`` bytes or announces more joint names
    or points than :data:`LIMITS` allows, before anything deserialises it."""
    if len(data) > max_bytes:
        raise InputRejected("too_large", f"{len(data)} bytes, more than the {max_bytes} byte limit")
    for kind, count in leading_counts(data, msgtype).items():
        if count > LIMITS[kind]:
            raise InputRejected("too_large", f"{count} {kind}, more than the limit of {LIMITS[kind]}")
