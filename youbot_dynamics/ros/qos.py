"""QoS profiles of the package's topics, by the names of
:data:`youbot_dynamics.node.interface.QOS`."""
from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from youbot_dynamics.node.interface import SUBSCRIPTION_QOS

RELIABLE_DEEP = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.VOLATILE)
"""Reliable, keep the last 1000: a replay or a 1 kHz stream is not thinned out by a slow
reader for up to a second."""

RELIABLE_ALL = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
"""Reliable, keep all: nothing is dropped for a slow reader. A reader keeps what it has not
taken (Fast DDS: up to 5000 samples) and acknowledges a sample only once it has room for it;
a writer keeps what is not yet acknowledged and, with its history full, blocks a publish for
100 ms and then refuses it (rclpy raises RCLError), so the writer must retry."""

LATCHED = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
"""Transient local, depth 1 (as /tf_static): late subscribers get the last message."""

BEST_EFFORT = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT,
                         durability=DurabilityPolicy.VOLATILE)
"""Best effort, keep the last 1000: hears best-effort and reliable publishers alike (a
reliable subscription matches no best-effort publisher), but may lose samples."""

PROFILES = {"reliable": RELIABLE_DEEP, "latched": LATCHED, "best_effort": BEST_EFFORT, "keep_all": RELIABLE_ALL}
"""Every profile by its name in the node's interface table."""
SUBSCRIPTION_PROFILES = {name: PROFILES[name] for name in SUBSCRIPTION_QOS}
"""The choices of a subscription's QoS parameter (inverse mode's ``joint_states_qos``)."""


def profile(latched: bool, keep_all: bool = False) -> QoSProfile:
    """The profile to offer a topic with (``keep_all``: :data:`RELIABLE_ALL` unless latched)."""
    if latched:
        return LATCHED
    return RELIABLE_ALL if keep_all else RELIABLE_DEEP
