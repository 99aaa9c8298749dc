"""Live /tf, /tf_static and /robot_description between processes, as a ROS user sees them:
the dynamics node in its own process, a plain rclpy subscriber here (tf2_msgs built from
interfaces/ by ``make``), and the node without tf2_msgs."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ros_support import WAIT, Collector, ros_context, spinning, stamp_ns, wait_until

pytestmark = pytest.mark.timeout(240)

from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from youbot_dynamics.io.bag_reader import bag_topics, read_bag  # noqa: E402
from youbot_dynamics.io.messages import TYPESTORE  # noqa: E402
from youbot_dynamics.node.simulate import SimulationSession  # noqa: E402
from youbot_dynamics.ros import dynamics_node  # noqa: E402
from youbot_dynamics.ros.conversions import from_rclpy, rclpy_class  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
URDF = REPO / "urdf" / "youbot.urdf"
LATE_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
"""What a late tf2 / robot_description subscriber asks for (as tf2_ros and RViz do)."""


def matrix(transform) -> np.ndarray:
    """4x4 homogeneous matrix of a geometry_msgs/Transform (rosbags object), via scipy."""
    r, p = transform.rotation, transform.translation
    out = np.eye(4)
    out[:3, :3] = Rotation.from_quat([r.x, r.y, r.z, r.w]).as_matrix()
    out[:3, 3] = [p.x, p.y, p.z]
    return out


def compose(transforms: list, root: str, link: str) -> np.ndarray:
    """Pose of ``link`` in ``root`` by walking the parent links of TransformStamped messages."""
    parent_of = {t.child_frame_id: t for t in transforms}
    pose = np.eye(4)
    while link != root:
        step = parent_of[link]
        pose = matrix(step.transform) @ pose
        link = step.header.frame_id
    return pose


@pytest.mark.ros
def test_live_tf_and_late_latched_description_from_another_process(tmp_path: Path) -> None:
    """A subscriber in another process gets /tf at the sample rate with the arm links, and,
    subscribing only after the node has published for a while, still gets the latched
    /tf_static (base links, locked wheels and fingers) and /robot_description (the scene's
    URDF). The palm pose composed along /tf_static and /tf equals /ee_pose to 1e-12 at every
    common stamp (both come from one kinematics pass, the static part from the URDF); the
    MCAP logs the description."""
    pytest.importorskip("tf2_msgs.msg", reason="tf2_msgs is not installed: `make` builds it (interfaces/build.sh)")
    mcap = tmp_path / "live.mcap"
    with ros_context(27) as (context, domain):
        node = subprocess.Popen(
            [sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-p", "scene:=arm_swing",
             "-p", "publish_rate:=100.0", "-p", f"mcap_path:={mcap}"],
            cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain)}, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True)
        try:
            early = Collector(context, {"/tf": "tf2_msgs/msg/TFMessage", "/ee_pose": "geometry_msgs/msg/PoseStamped"},
                              name="early")
            with spinning(context, early):
                wait_until(lambda: early.count("/ee_pose") >= 30 and early.count("/tf") >= 30, what="30 samples")
                late = Node("late", context=context)
                received: dict[str, list] = {"/tf_static": [], "/robot_description": []}
                late.create_subscription(rclpy_class("tf2_msgs/msg/TFMessage"), "/tf_static",
                                         received["/tf_static"].append, LATE_QOS)
                late.create_subscription(String, "/robot_description", received["/robot_description"].append,
                                         LATE_QOS)
                with spinning(context, late):
                    wait_until(lambda: all(received.values()), what="latched /tf_static and /robot_description")
                    (offered,) = late.get_publishers_info_by_topic("/tf")
            node.send_signal(signal.SIGINT)
            node.wait(timeout=WAIT)
        finally:
            if node.poll() is None:
                node.kill()
    assert node.returncode == 0, node.stderr.read()
    # the tf2_msgs built here is ROS 2 Jazzy's type: same hash as the rosbags typestore's (and the MCAP's)
    assert str(offered.topic_type_hash) == TYPESTORE.hash_rihs01("tf2_msgs/msg/TFMessage")
    assert received["/robot_description"][0].data == URDF.read_text(encoding="utf-8")
    static = received["/tf_static"][0].transforms
    assert {"base_link", "arm_link_0", "wheel_link_fl", "gripper_palm_link"} <= {t.child_frame_id for t in static}
    tf = early.messages("/tf")
    assert all({t.child_frame_id for t in m.transforms} == {f"arm_link_{k}" for k in range(1, 6)} for m in tf)
    stamps = [stamp_ns(m.transforms[0]) for m in tf]
    assert set(np.diff(stamps)) == {10_000_000}                 # one /tf per 100 Hz sample, none lost
    by_stamp = dict(zip(stamps, (m.transforms for m in tf)))
    static = [from_rclpy(t) for t in static]
    compared, worst = 0, 0.0
    for pose in early.messages("/ee_pose"):
        if stamp_ns(pose) not in by_stamp:
            continue
        expected = compose(static + list(by_stamp[stamp_ns(pose)]), pose.header.frame_id, "gripper_palm_link")
        p, r = pose.pose.position, pose.pose.orientation
        got = np.eye(4)
        got[:3, :3] = Rotation.from_quat([r.x, r.y, r.z, r.w]).as_matrix()
        got[:3, 3] = [p.x, p.y, p.z]
        worst = max(worst, float(np.abs(got - expected).max()))
        compared += 1
    assert compared >= 25 and worst < 1e-12        # measured 1.1e-15 over 60 samples; bound 1e-12
    topics = {t.topic: t for t in bag_topics(mcap)}
    assert topics["/robot_description"].latched and topics["/robot_description"].message_count == 1
    (logged,) = [m.message for m in read_bag(mcap) if m.topic == "/robot_description"]
    assert logged.data == URDF.read_text(encoding="utf-8")


@pytest.mark.ros
def test_without_tf2_msgs_the_node_says_so_once_and_runs_on(monkeypatch, capfd) -> None:
    """With tf2_msgs not importable, the node warns once, has no /tf or /tf_static
    publisher, and still publishes its samples and the latched /robot_description."""
    real = rclpy_class

    def no_tf2_msgs(msgtype: str) -> type:
        if msgtype.startswith("tf2_msgs/"):
            raise ModuleNotFoundError("No module named 'tf2_msgs'")
        return real(msgtype)

    monkeypatch.setattr(dynamics_node, "rclpy_class", no_tf2_msgs)
    with ros_context(28) as (context, _):
        node = dynamics_node.DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value="arm_swing"), Parameter("publish_rate", value=100.0),
            Parameter("duration", value=0.2), Parameter("time_scale", value=0.0),
            Parameter("wait_for_subscribers", value=1)])
        collector = Collector(context, {"/joint_states": "sensor_msgs/msg/JointState"})
        with spinning(context, node, collector):
            wait_until(lambda: node.finished, what="the node to finish")
            wait_until(lambda: collector.count("/joint_states") == 21, what="21 samples")
        assert "/tf" not in node.publishers_ and "/tf_static" not in node.publishers_
        assert "/robot_description" in node.publishers_
        node.close()
    err = capfd.readouterr().err
    assert err.count("not publishing /tf, /tf_static") == 1, err


def test_composed_scene_describes_the_composed_robot() -> None:
    """gripping composes two youBots: /robot_description is the composed URDF (both robots'
    links, parsed here with the standard library's XML parser), and every frame that /tf and
    /tf_static name is one of its links or a free body, so a tf consumer can draw it."""
    with SimulationSession(load_scene("gripping"), 500.0) as session:
        latched = dict(session.latched)
        sample = dict(session.step())
    links = {link.get("name") for link in ElementTree.fromstring(latched["/robot_description"].data).iter("link")}
    assert {"yb1_arm_link_5", "yb2_arm_link_5", "yb1_gripper_palm_link", "yb2_base_link"} <= links
    frames = {name for message in (latched["/tf_static"], sample["/tf"]) for t in message.transforms
              for name in (t.header.frame_id, t.child_frame_id)}
    bodies = {spec.body.name for spec in session.scene.free_bodies}
    assert bodies and frames - bodies <= links and len(frames - bodies) > 20
