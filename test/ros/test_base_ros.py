"""The moving base through the ROS session (no rclpy): /cmd_vel in; /odom, odom ->
base_footprint on /tf and the ground truth out, every sample (REP-105)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from youbot_dynamics.dynamics.mobile.odometry import se2_step
from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene, scene_dir

RATE = 100.0


def yaw_of(q) -> float:
    return 2.0 * math.atan2(q.z, q.w)


@pytest.fixture
def session():
    with SimulationSession(load_scene(scene_dir() / "base_square.yaml"), RATE, samples_per_solve=5,
                           command_timeout=0.3) as session:
        yield session


def by_topic(outputs):
    return {topic: message for topic, message in outputs}


def test_odom_every_sample_and_tf_agrees(session):
    assert {"/odom", "/base_pose_ground_truth"} <= set(session.topics)
    static = session.latched[0][1]
    assert all(t.child_frame_id != "base_footprint" for t in static.transforms)  # odom -> base_footprint moves
    stamps, twists = [], []
    for _ in range(60):
        session.base_command((0.2, 0.1, 0.0), (0.0, 0.0, 0.4))  # a /cmd_vel stream at the publish rate
        out = by_topic(session.step())
        odom, tf = out["/odom"], out["/tf"]
        stamps.append(odom.header.stamp.sec * 10**9 + odom.header.stamp.nanosec)
        base = next(t for t in tf.transforms if t.child_frame_id == "base_footprint")
        assert (base.header.frame_id, odom.header.frame_id, odom.child_frame_id) == ("odom", "odom", "base_footprint")
        assert base.header.stamp == odom.header.stamp
        p, r = odom.pose.pose.position, odom.pose.pose.orientation
        t, q = base.transform.translation, base.transform.rotation
        np.testing.assert_allclose([t.x, t.y, t.z, q.x, q.y, q.z, q.w], [p.x, p.y, p.z, r.x, r.y, r.z, r.w],
                                   atol=1e-12, rtol=0)
        assert np.all(np.diag(odom.pose.covariance.reshape(6, 6)) > 0.0)
        truth_twist = out["/base_pose_ground_truth"].twist.twist
        twists.append((truth_twist.linear.x, truth_twist.linear.y, truth_twist.angular.z))
    assert np.all(np.diff(stamps) == round(1e9 / RATE))  # one /odom per sample, at the publish rate
    # a kinematic base follows the twist command, reached at base_square's a_max (1 per axis)
    # in 0.4 s: the ground truth on an independent integration of the pose rates
    truth = out["/base_pose_ground_truth"].pose.pose
    ramp = lambda t: min(t / 0.4, 1.0) * np.array([0.2, 0.1, 0.4])  # noqa: E731
    rates = lambda t, pose: [*(rotation(pose[2]) @ ramp(t)[:2]), ramp(t)[2]]  # noqa: E731
    expected = solve_ivp(rates, (0.0, 59 / RATE), np.zeros(3), rtol=1e-12, atol=1e-12, max_step=0.01).y[:, -1]
    np.testing.assert_allclose([truth.position.x, truth.position.y, yaw_of(truth.orientation)], expected, atol=1e-6)
    # the odometry holds each sample's wheel speeds (the true twist: no slip) over the next increment
    pose = np.zeros(3)
    for twist in twists[:-1]:
        pose = se2_step(pose, twist, 1 / RATE)
    np.testing.assert_allclose([p.x, p.y, yaw_of(r)], pose, atol=1e-12)


def rotation(yaw: float) -> np.ndarray:
    return np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])


def test_cmd_vel_timeout_stops_the_base(session):
    session.base_command((0.3, 0.0, 0.0), (0.0, 0.0, 0.0))
    for _ in range(80):  # 0.8 s, beyond the 0.3 s timeout
        out = by_topic(session.step())
    twist = out["/base_pose_ground_truth"].twist.twist
    assert (twist.linear.x, twist.linear.y, twist.angular.z) == (0.0, 0.0, 0.0)
    x = out["/base_pose_ground_truth"].pose.pose.position.x
    assert 0.3 * 0.3 <= x <= 0.3 * (0.3 + 5 / RATE) + 1e-9  # ran for the timeout (+ one solve block)


@pytest.mark.parametrize("linear, angular, kind", [
    ((math.nan, 0.0, 0.0), (0.0, 0.0, 0.0), "non_finite"),
    ((0.0, 0.0, 0.1), (0.0, 0.0, 0.0), "out_of_limits"),
    ((9.0, 0.0, 0.0), (0.0, 0.0, 0.0), "out_of_limits"),
    ((0.0, 0.0, 0.0), (0.0, 0.0, 50.0), "out_of_limits"),
])
def test_bad_cmd_vel_is_counted_and_rejected(session, linear, angular, kind):
    with pytest.raises(InputRejected):
        session.base_command(linear, angular)
    assert session.counters.rejected[kind] == 1
    assert session.moving_base.twist(0.0) is None  # nothing taken: the scene's path goes on


def test_fixed_base_rejects_cmd_vel():
    with SimulationSession(load_scene("arm_swing"), RATE) as session:
        assert "/odom" not in session.topics
        with pytest.raises(InputRejected):
            session.base_command((0.1, 0.0, 0.0), (0.0, 0.0, 0.0))
        assert session.counters.rejected["no_controller"] == 1


def test_wheel_joints_are_in_joint_states(session):
    names = by_topic(session.step())["/joint_states"].name
    assert {"wheel_joint_fl", "wheel_joint_fr", "wheel_joint_bl", "wheel_joint_br"} <= set(names)


@pytest.mark.ros
def test_live_cmd_vel_moves_the_base_and_odom_matches_tf():
    """The node with base_square: a /cmd_vel publisher moves the base; /odom arrives at the
    publish rate and the odom -> base_footprint transform on /tf carries its pose (1e-12)."""
    pytest.importorskip("tf2_msgs.msg", reason="tf2_msgs is not installed: `make` builds it (interfaces/build.sh)")
    from geometry_msgs.msg import Twist
    from rclpy.parameter import Parameter
    from ros_support import Collector, ros_context, spinning, stamp_ns, wait_until

    from youbot_dynamics.ros import dynamics_node

    with ros_context(29) as (context, _):
        node = dynamics_node.DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value=str(scene_dir() / "base_square.yaml")), Parameter("publish_rate", value=100.0),
            # paced to the wall clock: as fast as possible, a reader slower than the node loses
            # samples from the publisher's keep-last history, and this test counts them all
            Parameter("time_scale", value=1.0), Parameter("wait_for_subscribers", value=1)])
        collector = Collector(context, {"/odom": "nav_msgs/msg/Odometry", "/tf": "tf2_msgs/msg/TFMessage"})
        publisher = collector.create_publisher(Twist, "cmd_vel", 10)
        command = Twist()
        command.linear.x, command.angular.z = 0.3, 0.2
        collector.create_timer(0.01, lambda: publisher.publish(command))
        # the node on its own single-threaded executor, as its process runs it (a multi-threaded
        # one starves its /cmd_vel and the collector while the step timer is due)
        with spinning(context, node, single_threaded=True), spinning(context, collector):
            wait_until(lambda: collector.count("/odom") >= 150, what="150 /odom samples")
        node.close()
    odom = collector.messages("/odom")
    stamps = [stamp_ns(m) for m in odom]
    assert set(np.diff(stamps)) == {10_000_000}  # one per 100 Hz sample, none lost
    bases = {stamp_ns(t): t for m in collector.messages("/tf") for t in m.transforms
             if t.child_frame_id == "base_footprint"}
    compared = 0
    for m in odom:
        t = bases.get(stamp_ns(m))
        if t is None:
            continue
        p, r = m.pose.pose.position, m.pose.pose.orientation
        a, q = t.transform.translation, t.transform.rotation
        assert np.abs(np.array([a.x - p.x, a.y - p.y, a.z - p.z, q.x - r.x, q.y - r.y, q.z - r.z, q.w - r.w])).max() \
            < 1e-12
        compared += 1
    assert compared >= 100
    # the node runs as fast as it can (time_scale 0), so a command may time out between two
    # wall-clock publications: the base moved, and at the commanded turn rate while commanded
    assert odom[-1].pose.pose.position.x > 0.05
    assert max(m.twist.twist.angular.z for m in odom) == pytest.approx(0.2, abs=1e-9)
