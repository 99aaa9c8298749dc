"""Helpers for tests that read the logs back (no ROS needed)."""
from __future__ import annotations

from pathlib import Path

from rosbags.highlevel import AnyReader


def read_mcap(path: Path) -> dict[str, list]:
    """Messages per topic of an MCAP, decoded by rosbags' AnyReader."""
    by_topic: dict[str, list] = {}
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            by_topic.setdefault(connection.topic, []).append(reader.deserialize(raw, connection.msgtype))
    return by_topic
