"""QoS profiles of the package's topics."""
from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

RELIABLE_DEEP = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.VOLATILE)
"""Reliable, keep the last 1000: a replay or a 1 kHz stream is not thinned out by a slow
reader for up to a second."""

LATCHED = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
"""Transient local, depth 1 (as /tf_static): late subscribers get the last message."""


def profile(latched: bool) -> QoSProfile:
    """The profile to offer a topic with."""
    return LATCHED if latched else RELIABLE_DEEP
