"""Stamps as integer nanoseconds: the one conversion from builtin_interfaces Time and
Duration (rclpy or rosbags messages alike), for the node, the message builders and the
bag readers."""
from __future__ import annotations

NS_PER_S = 1_000_000_000
"""Nanoseconds per second: sample stamps and trajectory times are integer nanoseconds."""

STAMP_LIMIT_NS = 2**31 * NS_PER_S
"""Stamps (ns) must lie in [0, STAMP_LIMIT_NS): the range of builtin_interfaces/Time."""


MALFORMED_STAMP_NS = -(2**63)
"""What :func:`stamp_ns_of` gives for a nanosec of 1e9 or more: negative, so that every stamp
check refuses it (carried over, it would read as a valid later stamp)."""


def stamp_ns_of(stamp: object) -> int:
    """A builtin_interfaces Time or Duration (``sec``, ``nanosec``) as integer nanoseconds;
    ``MALFORMED_STAMP_NS`` when ``nanosec`` is not below 1e9 (builtin_interfaces' rule)."""
    if stamp.nanosec >= NS_PER_S:
        return MALFORMED_STAMP_NS
    return stamp.sec * NS_PER_S + stamp.nanosec
