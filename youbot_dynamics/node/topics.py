"""Topic names on the ROS graph and in the logs.

The sessions and the logs name topics as a node in the root namespace publishes them
(``/joint_states``): these are the MCAP's topic names, whatever namespace the node runs in,
and the names its /diagnostics counters use. On the graph, the nodes subscribe and publish
under relative names (``joint_states``), so ``--ros-args -r __ns:=/youbot1`` moves every
topic under /youbot1, except those ROS keeps global (:data:`GLOBAL_TOPICS`).
"""
from __future__ import annotations

GLOBAL_TOPICS = frozenset({"/tf", "/tf_static", "/diagnostics"})
"""Topics published under their absolute names in any namespace: /tf and /tf_static, where
tf2's broadcasters and listeners, RViz and robot_state_publisher meet (two robots keep their
frames apart by a frame prefix, not by namespace), and /diagnostics, where
diagnostic_updater publishes and diagnostic_aggregator listens (each status names its node)."""


def graph_name(topic: str) -> str:
    """The name a node uses on the graph for ``topic`` (a logged name such as
    ``/joint_states``): relative (``joint_states``, resolved in the node's namespace) unless
    it is one of :data:`GLOBAL_TOPICS`. In the root namespace both name the same topic."""
    return topic if topic in GLOBAL_TOPICS else topic.lstrip("/")
