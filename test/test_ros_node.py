"""The dynamics node with real ROS 2 traffic: what it publishes, bad input on every topic,
services, parameter ranges, and logs finalised on SIGINT / SIGTERM."""
from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ros_support import (WAIT, Collector, diagnostic_values, ros_context, spinning, stamp_ns, wait_until)

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_srvs.srv import SetBool, Trigger  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

from youbot_dynamics.io.bag_reader import bag_topics, read_bag  # noqa: E402
from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402
from youbot_dynamics.ros.session import SimulationSession  # noqa: E402
from youbot_dynamics.sim.frames import LinkFrames  # noqa: E402
from youbot_dynamics.sim.scene import load_scene  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
OUTPUTS = {"/joint_states": "sensor_msgs/msg/JointState", "/ee_pose": "geometry_msgs/msg/PoseStamped",
           "/clock": "rosgraph_msgs/msg/Clock", "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"}


def make_node(context, **parameters) -> DynamicsNode:
    return DynamicsNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in parameters.items()])


def wait_matched(node: DynamicsNode, topic: str = "/joint_states") -> None:
    wait_until(lambda: node.publishers_[topic].get_subscription_count() > 0, what=f"a subscriber on {topic}")


def test_simulate_mode_publishes_the_simulated_motion() -> None:
    """Every /joint_states sample equals the simulator's, /ee_pose the screw FK of its q,
    /clock the sample times; the node stops after `duration` with a last /diagnostics, where
    a counter the integrator does not report (CVODE's rejected steps) reads n/a."""
    with ros_context(0) as (context, _):
        node = make_node(context, scene="arm_ptp", publish_rate=100.0, duration=0.5, time_scale=0.0,
                         wait_for_subscribers=1)
        collector = Collector(context, OUTPUTS)
        with spinning(context, node, collector):
            wait_until(lambda: node.finished, what="the node to finish")
            wait_until(lambda: collector.count("/joint_states") == 51 and collector.count("/diagnostics") > 0,
                       what="51 samples")
        states, poses = collector.messages("/joint_states"), collector.messages("/ee_pose")
        clocks = [m.clock.sec * 10**9 + m.clock.nanosec for m in collector.messages("/clock")]
        diagnostics = diagnostic_values(collector.messages("/diagnostics")[-1])
    reference = SimulationSession(load_scene("arm_ptp"), 100.0, samples_per_solve=2)
    expected = [dict(reference.step())["/joint_states"] for _ in range(51)]
    assert [stamp_ns(m) for m in states] == clocks == [10_000_000 * k for k in range(51)]
    for got, want in zip(states, expected):
        assert list(got.name) == list(want.name)
        for field in ("position", "velocity", "effort"):
            assert np.array_equal(getattr(got, field), getattr(want, field))
    assert np.ptp([m.position[0] for m in states]) > 1e-3        # the arm moved
    frames = LinkFrames(reference.robot)
    for pose, state in zip(poses, states):
        position, quaternion = frames.ee_pose(np.asarray(state.position))
        p, o = pose.pose.position, pose.pose.orientation
        assert np.allclose([p.x, p.y, p.z], position, atol=1e-12)
        assert np.allclose([o.x, o.y, o.z, o.w], quaternion, atol=1e-12)
        assert pose.header.frame_id == "base_footprint"
    assert float(diagnostics["sim_time"]) == pytest.approx(0.5)
    assert int(diagnostics["integrator.steps"]) > 0 and diagnostics["integrator.integrator"] == "cvode_bdf"
    assert math.isfinite(float(diagnostics["real_time_factor"])) and float(diagnostics["energy"]) > 0
    assert diagnostics["integrator.rejected_steps"] == "n/a" and "None" not in diagnostics.values()


def test_simulated_time_waits_for_the_subscribers() -> None:
    """With wait_for_subscribers 2 the node holds simulated time at 0 while one subscriber
    listens, and starts once a second one comes: both get every sample from t = 0."""
    with ros_context(8) as (context, _):
        node = make_node(context, scene="arm_swing", publish_rate=100.0, duration=0.2, time_scale=0.0,
                         wait_for_subscribers=2, wait_timeout=WAIT, diagnostics_period=0.05)
        first = Collector(context, {"/joint_states": OUTPUTS["/joint_states"], "/diagnostics": OUTPUTS["/diagnostics"]})
        with spinning(context, node, first) as executor:
            wait_until(lambda: first.count("/diagnostics") >= 3, what="/diagnostics while waiting")
            assert first.count("/joint_states") == 0 and node.session.t == 0.0
            assert all(diagnostic_values(m)["sim_time"] == "0.0" for m in first.messages("/diagnostics"))
            second = Collector(context, {"/joint_states": OUTPUTS["/joint_states"]}, name="second")
            executor.add_node(second)
            wait_until(lambda: node.finished, what="the node to finish")
            wait_until(lambda: first.count("/joint_states") == second.count("/joint_states") == 21,
                       what="21 samples on both subscribers")
        stamps = [[stamp_ns(m) for m in c.messages("/joint_states")] for c in (first, second)]
        second.destroy_node()
    assert stamps[0] == stamps[1] == [10_000_000 * k for k in range(21)]


def _command(names, efforts, stamp_ns_: int = 0) -> JointState:
    msg = JointState(name=list(names), effort=[float(e) for e in efforts])
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns_, 10**9)
    return msg


def test_bad_input_is_counted_warned_and_never_published() -> None:
    """Each kind of bad command is rejected and counted in /diagnostics; a command beyond the
    effort limit is clamped; the node keeps publishing finite states throughout."""
    with ros_context(1) as (context, _):
        node = make_node(context, scene="arm_ptp", publish_rate=100.0, diagnostics_period=0.1,
                         on_timeout="zero_torque", command_timeout=5.0)
        collector = Collector(context, OUTPUTS)
        commands = collector.create_publisher(JointState, "/joint_commands", RELIABLE_DEEP)
        trajectories = collector.create_publisher(JointTrajectory, "/joint_trajectory", RELIABLE_DEEP)
        wait_matched(node)
        with spinning(context, node, collector):
            wait_until(lambda: commands.get_subscription_count() > 0 and trajectories.get_subscription_count() > 0,
                       what="the node's subscriptions")
            bad = [(["arm_joint_1"], [math.nan]), (["arm_joint_1"], [math.inf]),
                   (["arm_joint_1", "arm_joint_2"], [1.0]), (["no_such_joint"], [1.0]),
                   (["arm_joint_1", "arm_joint_1"], [1.0, 1.0])]
            for names, efforts in bad:
                commands.publish(_command(names, efforts))
            late = JointTrajectory(joint_names=["arm_joint_1"])
            late.points = [JointTrajectoryPoint(positions=[3.0]), JointTrajectoryPoint(positions=[3.1])]
            trajectories.publish(late)                                                 # equal times
            commands.publish(_command(["arm_joint_2", "arm_joint_4"], [-100.0, 100.0]))   # clamped
            limits = node.session.robot.effort_limit

            def clamped_effort_seen() -> bool:
                states = collector.messages("/joint_states")
                return bool(states) and states[-1].effort[1] == -limits[1] and states[-1].effort[3] == limits[3]

            wait_until(clamped_effort_seen, what="the clamped command on /joint_states")

            def counted() -> dict[str, str]:
                diagnostics = collector.messages("/diagnostics")
                return diagnostic_values(diagnostics[-1]) if diagnostics else {}

            wait_until(lambda: counted().get("clamped") == "1", what="the counters in /diagnostics")
        values = counted()
        states = collector.messages("/joint_states")
    assert values["rejected.non_finite"] == "2"
    assert values["rejected.length_mismatch"] == "1"
    assert values["rejected.unknown_joint"] == "1"
    assert values["rejected.duplicate_joint"] == "1"
    assert values["rejected.bad_timing"] == "1"
    assert values["accepted"] == "1"
    assert values["command"] == "effort_command"
    assert all(np.isfinite(s.position).all() and np.isfinite(s.effort).all() for s in states)
    # joints the command does not name get no effort: the rejected commands left no trace
    assert states[-1].effort[0] == 0.0 and states[-1].effort[2] == 0.0


def test_stale_command_is_rejected() -> None:
    with ros_context(2) as (context, _):
        node = make_node(context, scene="arm_swing", publish_rate=200.0, time_scale=0.0, command_timeout=0.1)
        sender = Collector(context, {})
        commands = sender.create_publisher(JointState, "/joint_commands", RELIABLE_DEEP)
        with spinning(context, node, sender):
            wait_until(lambda: commands.get_subscription_count() > 0, what="the node's subscription")
            wait_until(lambda: node.session.t > 0.5, what="simulated time")
            commands.publish(_command(["arm_joint_1"], [1.0], stamp_ns_=1))
            wait_until(lambda: node.session.counters.rejected["stale"] == 1, what="the stale count")
        assert node.session.counters.accepted == 0


def test_pause_and_reset_services() -> None:
    with ros_context(3) as (context, _):
        node = make_node(context, scene="arm_swing", publish_rate=100.0, diagnostics_period=0.05)
        client_node = Collector(context, OUTPUTS)
        pause = client_node.create_client(SetBool, "/dynamics_node/pause")
        reset = client_node.create_client(Trigger, "/dynamics_node/reset")
        with spinning(context, node, client_node):
            assert pause.wait_for_service(timeout_sec=WAIT) and reset.wait_for_service(timeout_sec=WAIT)
            wait_until(lambda: node.session.t > 0.3, what="simulated time")
            future = pause.call_async(SetBool.Request(data=True))
            wait_until(future.done, what="pause")
            assert future.result().success
            frozen = node.session.t

            def paused_reports() -> int:
                return sum(diagnostic_values(m)["paused"] == "True" for m in client_node.messages("/diagnostics"))
            wait_until(lambda: paused_reports() >= 5, what="/diagnostics while paused")   # the timers ran
            assert node.session.t == frozen
            future = reset.call_async(Trigger.Request())
            wait_until(future.done, what="reset")
            assert future.result().success and node.session.t == 0.0
            future = pause.call_async(SetBool.Request(data=False))
            wait_until(future.done, what="resume")
            wait_until(lambda: 0.0 < node.session.t, what="the simulation to run again")

            def clock_went_back() -> bool:  # /clock after its maximum shows a time before the pause
                clocks = [m.clock.sec + m.clock.nanosec * 1e-9 for m in client_node.messages("/clock")]
                return bool(clocks) and min(clocks[clocks.index(max(clocks)):]) < frozen
            wait_until(clock_went_back, what="/clock to go back after the reset")


def test_parameter_ranges_and_choices_are_enforced() -> None:
    with ros_context(4) as (context, _):
        node = make_node(context, scene="arm_swing", publish_rate=100.0)
        try:
            results = node.set_parameters([Parameter("command_timeout", value=100.0),
                                           Parameter("on_timeout", value="explode"),
                                           Parameter("publish_rate", value=200.0),
                                           Parameter("on_timeout", value="zero_torque")])
            assert [r.successful for r in results] == [False, False, False, True]
            assert node.session.commands.on_timeout == "zero_torque"
            assert node.get_parameter("command_timeout").value == 0.5
            assert node.describe_parameter("publish_rate").floating_point_range[0].to_value == 2000.0
            assert node.describe_parameter("wait_for_subscribers").integer_range[0].to_value == 100
        finally:
            node.close()
            node.destroy_node()
    env = {**os.environ, "ROS_DOMAIN_ID": "231"}
    bad = subprocess.run([sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args",
                          "-p", "mode:=dance"], capture_output=True, text=True, timeout=120, env=env, cwd=REPO)
    assert bad.returncode == 2 and "mode" in bad.stderr and "dance" in bad.stderr


@pytest.mark.parametrize(("signum", "offset"), [(signal.SIGINT, 5), (signal.SIGTERM, 6)])
def test_signal_finalises_the_logs(tmp_path: Path, signum: int, offset: int) -> None:
    """A node process killed by SIGINT / SIGTERM leaves an MCAP that rosbags and mcap_ros2
    read to the end, and a Rerun file with its samples; a subscriber here (another process),
    waited for by the node, received its /joint_states from t = 0 on."""
    mcap, rrd = tmp_path / "run.mcap", tmp_path / "run.rrd"
    with ros_context(offset) as (context, domain):
        collector = Collector(context, {"/joint_states": OUTPUTS["/joint_states"]})
        process = subprocess.Popen(
            [sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-p", "scene:=arm_swing",
             "-p", "publish_rate:=100.0", "-p", f"mcap_path:={mcap}", "-p", f"rrd_path:={rrd}",
             "-p", "wait_for_subscribers:=1"],
            cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain)}, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True)
        try:
            with spinning(context, collector):
                wait_until(lambda: collector.count("/joint_states") >= 20 or process.poll() is not None,
                           what="samples from the node process")
                process.send_signal(signum)
                process.wait(timeout=WAIT)
        finally:
            if process.poll() is None:
                process.kill()
        received = collector.messages("/joint_states")
    assert process.returncode == 0, process.stderr.read()
    assert [stamp_ns(m) for m in received] == [10_000_000 * k for k in range(len(received))]
    topics = {t.topic: t for t in bag_topics(mcap)}
    assert set(topics) == {"/clock", "/joint_states", "/ee_pose", "/diagnostics", "/tf", "/tf_static",
                           "/robot_description"}
    assert topics["/tf_static"].latched and topics["/tf_static"].message_count == 1
    logged = [m.message for m in read_bag(mcap) if m.topic == "/joint_states"]
    assert len(logged) >= len(received) >= 20
    by_stamp = {stamp_ns(m): m for m in logged}
    assert all(np.array_equal(by_stamp[stamp_ns(m)].position, m.position) for m in received)
    tf = [m.message for m in read_bag(mcap) if m.topic == "/tf"]
    assert len(tf) == len(logged) and {t.child_frame_id for t in tf[0].transforms} >= {"arm_link_1", "arm_link_5"}

    from mcap_ros2.reader import read_ros2_messages
    assert sum(1 for m in read_ros2_messages(str(mcap), topics=["/joint_states"])) == len(logged)

    from rerun.chunk import RrdReader
    entities = {chunk.entity_path for chunk in RrdReader(str(rrd)).stream()}
    assert "/joints/q" in entities and "/energy" in entities


def test_inverse_mode_rejects_bad_joint_states_and_publishes_only_finite_torques() -> None:
    with ros_context(7) as (context, _):
        node = make_node(context, scene="arm_ptp", mode="inverse", diagnostics_period=0.1)
        collector = Collector(context, {"/computed_torques": "sensor_msgs/msg/JointState",
                                        "/diagnostics": OUTPUTS["/diagnostics"]})
        states = collector.create_publisher(JointState, "/joint_states", RELIABLE_DEEP)
        names = list(node.session.robot.joint_names)
        q0 = load_scene("arm_ptp").q0
        with spinning(context, node, collector):
            wait_until(lambda: states.get_subscription_count() > 0, what="the node's subscription")
            wait_matched(node, "/computed_torques")
            for k in range(4):
                msg = JointState(name=names, position=list(q0), velocity=[0.1 * k] * 5)
                msg.header.stamp.nanosec = 10_000_000 * (k + 1)
                states.publish(msg)
                if k == 1:
                    broken = JointState(name=names, position=[math.nan] * 5, velocity=[0.0] * 5)
                    broken.header.stamp.nanosec = 15_000_000
                    states.publish(broken)
                    states.publish(JointState(name=names[:3], position=[0.0] * 3, velocity=[0.0] * 3))
            wait_until(lambda: collector.count("/computed_torques") == 2, what="two torque samples")
            wait_until(lambda: collector.count("/diagnostics") > 0 and
                       diagnostic_values(collector.messages("/diagnostics")[-1])["rejected.total"] == "2",
                       what="the rejection counts")
        torques = collector.messages("/computed_torques")
    for k, torque in enumerate(torques):
        assert stamp_ns(torque) == 10_000_000 * (k + 2)
        expected = node.session.dynamics.torque(q0, np.full(5, 0.1 * (k + 1)), np.full(5, 10.0))
        assert np.allclose(torque.effort, expected, rtol=1e-12, atol=1e-12)
