"""A topic's QoS profile as plain data, without rclpy: what the node's interface table names
(:data:`youbot_dynamics.node.interface.QOS`), what its rclpy publishers offer
(:mod:`youbot_dynamics.ros.qos` builds them from it) and what the MCAP records as a channel's
``offered_qos_profiles`` (:mod:`youbot_dynamics.io.mcap_log`): one entry, three uses."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Qos:
    """The policies of a profile in rosbag2's (Jazzy) spelling: ``reliability`` "reliable" |
    "best_effort", ``durability`` "volatile" | "transient_local", ``history`` "keep_last" |
    "keep_all", and ``depth`` (samples kept; 0 with keep_all). Deadline, lifespan and
    liveliness are the defaults (infinite, automatic)."""

    reliability: str
    durability: str
    history: str
    depth: int

    def describe(self) -> str:
        """The profile in words: ``reliable, volatile, keep last 1000``."""
        kept = "keep all" if self.history == "keep_all" else f"keep last {self.depth}"
        return f"{self.reliability.replace('_', ' ')}, {self.durability.replace('_', ' ')}, {kept}"


DEFAULT = Qos("reliable", "volatile", "keep_last", 10)
"""rclpy's default publisher profile with the usual depth 10: what an MCAP channel offers
unless its writer names another."""
