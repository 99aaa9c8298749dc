"""The node's interface table (node/interface.py): docs/node.md and the README's table are
what it generates, and the names it uses for QoS profiles are those ros/qos.py defines."""
from __future__ import annotations

from pathlib import Path

import pytest

from youbot_dynamics.node.interface import (CHOICES, PARAMETERS, QOS, SUBSCRIPTION_QOS, TOPICS, markdown,
                                            stack_table)

DOCS = Path(__file__).resolve().parents[2] / "docs" / "node.md"
README = Path(__file__).resolve().parents[2] / "README.md"


def test_docs_node_md_is_what_the_table_generates() -> None:
    assert DOCS.read_text(encoding="utf-8") == markdown(), \
        "docs/node.md is stale: python -m youbot_dynamics.node.interface > docs/node.md"


def test_the_readme_holds_the_generated_stack_table() -> None:
    text = README.read_text(encoding="utf-8")
    section = text[text.index("## Use it from your ROS stack"):]
    assert stack_table() in section, f"README's table is stale; it should read:\n{stack_table()}"


def test_every_topic_names_a_known_qos_and_subscriptions_a_size_bound() -> None:
    for topic in TOPICS:
        assert topic.qos in QOS or topic.qos in PARAMETERS, topic
        assert (topic.max_bytes is not None) == (topic.direction == "sub"), topic
    assert set(CHOICES) <= set(PARAMETERS) and set(SUBSCRIPTION_QOS) <= set(QOS)


def test_the_qos_names_are_the_rclpy_profiles() -> None:
    pytest.importorskip("rclpy")
    from youbot_dynamics.ros.qos import PROFILES, SUBSCRIPTION_PROFILES

    assert set(PROFILES) == set(QOS) and tuple(SUBSCRIPTION_PROFILES) == SUBSCRIPTION_QOS
