"""Stamps as integer nanoseconds: the one conversion from builtin_interfaces Time and
Duration (rclpy or rosbags messages alike), for the node, the message builders and the
bag readers."""
from __future__ import annotations

NS_PER_S = 1_000_000_000
"""Nanoseconds per second: sample stamps and trajectory times are integer nanoseconds."""


def stamp_ns_of(stamp: object) -> int:
    """A builtin_interfaces Time or Duration (``sec``, ``nanosec``) as integer nanoseconds."""
    return stamp.sec * NS_PER_S + stamp.nanosec
