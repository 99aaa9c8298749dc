"""QoS profiles of the package's topics in their rclpy form, built from the node's interface
table (:data:`youbot_dynamics.node.interface.QOS`, the same entries the MCAP records as its
channels' offered profiles)."""
from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from youbot_dynamics.io.qos import Qos
from youbot_dynamics.node.interface import QOS, SUBSCRIPTION_QOS


def rclpy_profile(qos: Qos) -> QoSProfile:
    """The rclpy profile of a table entry (policies by their rosbag2 names)."""
    return QoSProfile(history=HistoryPolicy[qos.history.upper()], depth=qos.depth,
                      reliability=ReliabilityPolicy[qos.reliability.upper()],
                      durability=DurabilityPolicy[qos.durability.upper()])


PROFILES = {name: rclpy_profile(qos) for name, qos in QOS.items()}
"""Every profile by its name in the node's interface table."""
SUBSCRIPTION_PROFILES = {name: PROFILES[name] for name in SUBSCRIPTION_QOS}
"""The choices of a subscription's QoS parameter (inverse mode's ``joint_states_qos``)."""

RELIABLE_DEEP = PROFILES["reliable"]
"""Reliable, keep the last 1000: a replay or a 1 kHz stream is not thinned out by a slow
reader for up to a second."""
RELIABLE_ALL = PROFILES["keep_all"]
"""Reliable, keep all: nothing is dropped for a slow reader. A reader keeps what it has not
taken (Fast DDS: up to 5000 samples) and acknowledges a sample only once it has room for it;
a writer keeps what is not yet acknowledged and, with its history full, blocks a publish for
100 ms and then refuses it (rclpy raises RCLError), so the writer must retry."""
LATCHED = PROFILES["latched"]
"""Transient local, depth 1 (as /tf_static): late subscribers get the last message."""
BEST_EFFORT = PROFILES["best_effort"]
"""Best effort, keep the last 1000: hears best-effort and reliable publishers alike (a
reliable subscription matches no best-effort publisher), but may lose samples."""


def profile(latched: bool, keep_all: bool = False) -> QoSProfile:
    """The profile to offer a topic with (``keep_all``: :data:`RELIABLE_ALL` unless latched)."""
    if latched:
        return LATCHED
    return RELIABLE_ALL if keep_all else RELIABLE_DEEP
