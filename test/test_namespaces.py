"""Two youBots side by side: two dynamics node processes in the namespaces /youbot1 and
/youbot2, heard by one plain rclpy subscriber, as a ROS user runs them."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from ros_support import WAIT, Collector, ros_context, spinning, wait_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402

from youbot_dynamics.ros.conversions import from_rclpy, rclpy_class  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
ARM_LINKS = {f"arm_link_{k}" for k in range(1, 6)}


def start_node(namespace: str, domain: int, *remaps: str) -> subprocess.Popen:
    """A dynamics node process simulating arm_swing at 50 Hz in ``namespace``."""
    command = [sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-r", f"__ns:={namespace}",
               "-p", "scene:=arm_swing", "-p", "publish_rate:=50.0"]
    for remap in remaps:
        command += ["-r", remap]
    return subprocess.Popen(command, cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain)},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_two_nodes_in_two_namespaces_publish_apart() -> None:
    """Every topic of each node lies under its namespace (/youbot1/joint_states,
    /youbot2/joint_states, ...) but /tf, /tf_static and /diagnostics, which stay global; on
    /tf and /tf_static the frames of the two robots carry their namespace as prefix and none
    is named twice; each /diagnostics status names its node. The remap ``clock:=/clock``
    gives one node the global /clock (as use_sim_time listeners need) and leaves the other's
    under its namespace."""
    pytest.importorskip("tf2_msgs.msg", reason="tf2_msgs is not installed: `make` builds it (interfaces/build.sh)")
    with ros_context(17) as (context, domain):
        nodes = [start_node("/youbot1", domain, "clock:=/clock"), start_node("/youbot2", domain)]
        try:
            collector = Collector(context, {"/youbot1/joint_states": "sensor_msgs/msg/JointState",
                                            "/youbot2/joint_states": "sensor_msgs/msg/JointState",
                                            "/tf": "tf2_msgs/msg/TFMessage",
                                            "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
            static: list = []
            collector.create_subscription(rclpy_class("tf2_msgs/msg/TFMessage"), "/tf_static",
                                          lambda message: static.append(from_rclpy(message)), LATCHED)
            with spinning(context, collector):
                def heard_both() -> bool:
                    names = {s.name for m in collector.messages("/diagnostics") for s in m.status}
                    return (collector.count("/youbot1/joint_states") >= 20
                            and collector.count("/youbot2/joint_states") >= 20 and len(static) >= 2
                            and len({n.split(":")[0] for n in names}) == 2)
                wait_until(heard_both, what="both nodes' joint states, /tf_static and /diagnostics")
                topics = dict(collector.get_topic_names_and_types())
                subscribed = {name for name, _ in collector.get_subscriber_names_and_types_by_node(
                    "dynamics_node", "/youbot2")}
            for node in nodes:
                node.send_signal(signal.SIGINT)
            for node in nodes:
                node.wait(timeout=WAIT)
        finally:
            for node in nodes:
                if node.poll() is None:
                    node.kill()
    assert [node.returncode for node in nodes] == [0, 0], [node.stderr.read() for node in nodes]
    for ns in ("/youbot1", "/youbot2"):
        assert {f"{ns}/joint_states", f"{ns}/ee_pose", f"{ns}/robot_description"} <= set(topics)
        states = collector.messages(f"{ns}/joint_states")
        assert "arm_joint_1" in states[0].name
    assert {"/tf", "/tf_static", "/diagnostics", "/clock", "/youbot2/clock"} <= set(topics)
    assert not {"/joint_states", "/ee_pose", "/youbot1/clock", "/youbot1/tf", "/youbot2/diagnostics"} & set(topics)
    assert {"/youbot2/joint_commands", "/youbot2/joint_trajectory"} <= subscribed
    moving = {t.child_frame_id for m in collector.messages("/tf") for t in m.transforms}
    assert moving == {f"{ns}/{link}" for ns in ("youbot1", "youbot2") for link in ARM_LINKS}
    fixed = [[(t.header.frame_id, t.child_frame_id) for t in m.transforms] for m in static]
    by_robot = {frames[0][0].split("/")[0]: frames for frames in fixed}
    assert set(by_robot) == {"youbot1", "youbot2"}
    for prefix, frames in by_robot.items():
        assert all(parent.startswith(prefix + "/") and child.startswith(prefix + "/") for parent, child in frames)
    assert len({child for frames in fixed for _, child in frames}) == sum(len(frames) for frames in fixed)
    names = {s.name.split(":")[0] for m in collector.messages("/diagnostics") for s in m.status}
    assert names == {"/youbot1/dynamics_node", "/youbot2/dynamics_node"}
