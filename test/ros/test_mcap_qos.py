"""The MCAP records every channel as offered with the QoS that the live publisher offers.

For every published topic of the interface table (scenes that together have each one, and
inverse mode), a dynamics node is built with an MCAP log; its publishers' profiles are read
from the ROS graph (reliability, durability, liveliness: what DDS discovery reports, an
independent reading of the writer) and from the rclpy publisher (history and depth, which
discovery does not carry), and compared with the channel's ``offered_qos_profiles``."""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader

pytest.importorskip("rclpy")
from ros_support import ros_context, wait_until  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, ReliabilityPolicy  # noqa: E402

from youbot_dynamics.node.interface import QOS, TOPIC_QOS, table_topic, topic_qos  # noqa: E402
from youbot_dynamics.node.topics import graph_name  # noqa: E402
from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402

RUNS = {"gripping": ("gripping", "simulate"), "base_square": ("base_square", "simulate"),
        "inverse": ("arm_ptp", "inverse")}
"""Node set-ups that together publish every topic of the table (composed robots, free bodies,
static geometry; a moving base; inverse mode)."""



def named(policy: type, value: int) -> str:
    """rosbag2's name of a policy value (``ReliabilityPolicy.BEST_EFFORT`` -> best_effort)."""
    return policy(value).name.lower()


def channel_profiles(path: Path) -> dict[str, dict]:
    with path.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    profiles = {}
    for channel in summary.channels.values():
        (profiles[channel.topic],) = yaml.safe_load(channel.metadata["offered_qos_profiles"])
    return profiles


@pytest.fixture(scope="module")
def live_and_recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[dict, dict]]:
    """Per topic: (the live publisher's profile, the MCAP channel's profile)."""
    found: dict[str, tuple[dict, dict]] = {}
    for offset, (label, (scene, mode)) in enumerate(RUNS.items()):
        mcap = tmp_path_factory.mktemp(label) / "run.mcap"
        with ros_context(5 + offset) as (context, _):
            node = DynamicsNode(context=context, parameter_overrides=[
                Parameter("scene", value=scene), Parameter("mode", value=mode), Parameter("mcap_path", value=str(mcap))])
            try:
                for topic, publisher in node.publishers_.items():
                    resolved = node.resolve_topic_name(graph_name(topic))
                    wait_until(lambda name=resolved: node.get_publishers_info_by_topic(name),
                               what=f"{resolved} on the graph")
                    (info,) = node.get_publishers_info_by_topic(resolved)
                    live = {"reliability": named(ReliabilityPolicy, info.qos_profile.reliability),
                            "durability": named(DurabilityPolicy, info.qos_profile.durability),
                            "liveliness": named(LivelinessPolicy, info.qos_profile.liveliness),
                            "history": named(HistoryPolicy, publisher.qos_profile.history),
                            "depth": publisher.qos_profile.depth}
                    found[topic] = (live, {})
            finally:
                node.close()
                node.destroy_node()
        for topic, profile in channel_profiles(mcap).items():
            if topic in found:
                found[topic] = (found[topic][0], profile)
    return found


def test_every_published_topic_is_covered(live_and_recorded) -> None:
    assert {table_topic(topic) for topic in live_and_recorded} == set(TOPIC_QOS)


def test_the_mcap_records_what_the_live_publishers_offer(live_and_recorded) -> None:
    for topic, (live, recorded) in live_and_recorded.items():
        assert {key: recorded[key] for key in live} == live, topic


def test_the_recorded_profiles_are_the_table_entries(live_and_recorded) -> None:
    for topic, (_, recorded) in live_and_recorded.items():
        qos = topic_qos(topic)
        assert (recorded["reliability"], recorded["durability"], recorded["history"], recorded["depth"]) == \
            (qos.reliability, qos.durability, qos.history, qos.depth), topic
    assert live_and_recorded["/joint_states"][1]["depth"] == QOS["reliable"].depth == 1000
    assert (live_and_recorded["/tf_static"][1]["durability"], live_and_recorded["/tf_static"][1]["depth"]) == \
        ("transient_local", 1)
