"""The dynamics node with real ROS 2 traffic: what it publishes, bad input on every topic,
services, parameter ranges, and logs finalised on SIGINT / SIGTERM."""
from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
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
from youbot_dynamics.model.lie import matrix_from_quaternion  # noqa: E402
from youbot_dynamics.model.screws import fkin_space, screw_chain  # noqa: E402
from youbot_dynamics.node.interface import TOPIC_TYPES  # noqa: E402
from youbot_dynamics.node.simulate import SimulationSession  # noqa: E402
from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
OUTPUTS = {"/joint_states": "sensor_msgs/msg/JointState", "/ee_pose": "geometry_msgs/msg/PoseStamped",
           "/clock": "rosgraph_msgs/msg/Clock", "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"}


def make_node(context, **parameters) -> DynamicsNode:
    return DynamicsNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in parameters.items()])


def wait_matched(node: DynamicsNode, topic: str = "/joint_states") -> None:
    wait_until(lambda: node.publishers_[topic].get_subscription_count() > 0, what=f"a subscriber on {topic}")


def test_simulate_mode_publishes_the_simulated_motion() -> None:
    """Every /joint_states sample equals the simulator's, /ee_pose the screw FK of its q,
    /clock the sample times; the node stops after `duration` with a last /diagnostics that
    carries CVODE's own counters (error-test failures, Newton iterations)."""
    with ros_context(0) as (context, _):
        node = make_node(context, scene="arm_ptp", publish_rate=100.0, duration=0.5, time_scale=0.0,
                         wait_for_subscribers=1)
        collector = Collector(context, OUTPUTS)
        with spinning(context, node, collector):
            wait_until(lambda: node.finished, what="the node to finish")
            # each topic has its own reader: wait for all three (/clock's last sample has come
            # after /joint_states' in CI) and for the closing /diagnostics, the one at t = 0.5 s
            wait_until(lambda: all(collector.count(topic) == 51 for topic in ("/joint_states", "/ee_pose", "/clock"))
                       and any(abs(float(diagnostic_values(m)["sim_time"]) - 0.5) < 1e-9
                               for m in collector.messages("/diagnostics")),
                       what="51 samples on each topic and the closing /diagnostics")
        states, poses = collector.messages("/joint_states"), collector.messages("/ee_pose")
        clocks = [m.clock.sec * 10**9 + m.clock.nanosec for m in collector.messages("/clock")]
        diagnostics = next(values for values in map(diagnostic_values, collector.messages("/diagnostics"))
                           if abs(float(values["sim_time"]) - 0.5) < 1e-9)
    reference = SimulationSession(load_scene("arm_ptp"), 100.0, samples_per_solve=2)
    expected = [dict(reference.step())["/joint_states"] for _ in range(51)]
    assert [stamp_ns(m) for m in states] == clocks == [10_000_000 * k for k in range(51)]
    for got, want in zip(states, expected):
        assert list(got.name) == list(want.name)
        for field in ("position", "velocity", "effort"):
            assert np.array_equal(getattr(got, field), getattr(want, field))
    assert np.ptp([m.position[0] for m in states]) > 1e-3        # the arm moved
    chain = screw_chain(reference.robot)
    for pose, state in zip(poses, states):
        q = dict(zip(state.name, state.position))
        expected = fkin_space(chain, np.array([q[name] for name in reference.robot.joint_names]))
        p, o = pose.pose.position, pose.pose.orientation
        assert np.allclose([p.x, p.y, p.z], expected[:3, 3], atol=1e-12)
        assert np.allclose(matrix_from_quaternion([o.x, o.y, o.z, o.w]), expected[:3, :3], atol=1e-12)
        assert pose.header.frame_id == "base_footprint"
    assert float(diagnostics["sim_time"]) == pytest.approx(0.5)
    assert int(diagnostics["integrator.steps"]) > 0 and diagnostics["integrator.integrator"] == "cvode_bdf"
    assert math.isfinite(float(diagnostics["real_time_factor"])) and float(diagnostics["energy"]) > 0
    assert int(diagnostics["integrator.rejected_steps"]) >= 0 and int(diagnostics["integrator.nonlinear_iterations"]) > 0
    assert "None" not in diagnostics.values() and "n/a" not in diagnostics.values()


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
        with spinning(context, node, collector, single_threaded=True):
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
    """A command stamped 1 ns, received after t = 0.5 s with a 0.1 s timeout, is rejected as
    stale and never accepted.

    Robust against two races that made it fail once under load: (1) spun by a
    MultiThreadedExecutor, the always-late step timer (time_scale 0) and the subscription
    share the node's mutually exclusive callback group, and the executor skips the
    subscription whenever the timer is running: it starved; the node process spins
    single-threaded, and so does this test now. (2) The publisher may match the node's
    subscription before the subscription has matched the publisher, and a volatile reader
    drops what came before its match: the command is republished until one is counted."""
    with ros_context(2) as (context, _):
        node = make_node(context, scene="arm_swing", publish_rate=200.0, time_scale=0.0, command_timeout=0.1)
        sender = Collector(context, {})
        commands = sender.create_publisher(JointState, "/joint_commands", RELIABLE_DEEP)
        with spinning(context, node, sender, single_threaded=True):
            wait_until(lambda: commands.get_subscription_count() > 0, what="the node's subscription")
            wait_until(lambda: node.session.t > 0.5, what="simulated time")

            def stale_counted() -> bool:
                if node.session.counters.rejected["stale"] == 0:
                    commands.publish(_command(["arm_joint_1"], [1.0], stamp_ns_=1))
                    return False
                return True

            wait_until(stale_counted, what="the stale count")
        counters = node.session.counters
        assert counters.rejected["stale"] >= 1 and sum(counters.rejected.values()) == counters.rejected["stale"]
        assert counters.accepted == 0


def test_pause_and_reset_services() -> None:
    with ros_context(3) as (context, _):
        node = make_node(context, scene="arm_swing", publish_rate=100.0, diagnostics_period=0.05)
        client_node = Collector(context, OUTPUTS)
        pause = client_node.create_client(SetBool, "/dynamics_node/pause")
        reset = client_node.create_client(Trigger, "/dynamics_node/reset")
        with spinning(context, node, client_node, single_threaded=True):
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
            # the scene restarts; node time goes on one increment after the last sample
            assert future.result().success and node.session.scene_time == 0.0
            assert node.session.stamp_ns == round(frozen * 1e9) + 10_000_000 == node.session.last_reset_ns
            future = pause.call_async(SetBool.Request(data=False))
            wait_until(future.done, what="resume")
            wait_until(lambda: node.session.scene_time > 0.1, what="the simulation to run again")
            wait_until(lambda: any(diagnostic_values(m)["resets"] == "1" for m in client_node.messages("/diagnostics")),
                       what="the reset in /diagnostics")
        clocks = [m.clock.sec * 10**9 + m.clock.nanosec for m in client_node.messages("/clock")]
        states = client_node.messages("/joint_states")
    assert clocks == sorted(set(clocks))                      # /clock never went back, no stamp twice
    restart = next(m for m in states if stamp_ns(m) == node.session.last_reset_ns)
    first = SimulationSession(load_scene("arm_swing"), 100.0).step()
    assert np.array_equal(restart.position, dict(first)["/joint_states"].position)   # the initial state again


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


def test_a_refused_parameter_set_changes_nothing_and_an_accepted_one_takes_effect() -> None:
    """Parameters are checked on-set (all or nothing) and applied post-set: a set with one bad
    choice leaves every value and the command handling as they were; an accepted set changes
    how a held effort command times out. Inverse mode takes a time_scale without acting on it."""
    with ros_context(14) as (context, _):
        node = make_node(context, scene="arm_swing", publish_rate=100.0)
        try:
            commands = node.session.commands
            node.session.effort_command(["arm_joint_1"], [1.0], 0)         # held from t = 0
            refused = node.set_parameters_atomically([Parameter("command_timeout", value=2.0),
                                                      Parameter("time_scale", value=0.0),
                                                      Parameter("on_timeout", value="explode")])
            assert not refused.successful and "explode" in refused.reason
            assert (commands.timeout, commands.on_timeout) == (0.5, "hold")
            assert [node.get_parameter(n).value for n in ("command_timeout", "time_scale")] == [0.5, 1.0]
            assert (node.params["command_timeout"], node.params["time_scale"]) == (0.5, 1.0)
            assert commands.torque(1.0) is None                             # stale after 0.5 s: the controller
            accepted = node.set_parameters_atomically([Parameter("command_timeout", value=2.0),
                                                       Parameter("time_scale", value=0.0),
                                                       Parameter("on_timeout", value="zero_torque")])
            assert accepted.successful and node.params["time_scale"] == 0.0
            assert commands.torque(1.0)[0] == 1.0                          # still held at 1 s
            assert np.array_equal(commands.torque(2.5), np.zeros(node.session.robot.nv))   # then zero torque
        finally:
            node.close()
            node.destroy_node()
        inverse = make_node(context, scene="arm_swing", mode="inverse")
        try:
            assert inverse.set_parameters([Parameter("time_scale", value=2.0)])[0].successful
        finally:
            inverse.close()
            inverse.destroy_node()


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
    assert set(topics) == {"/clock", "/joint_states", "/ee_pose", "/wrist_wrench", "/diagnostics", "/tf",
                           "/tf_static", "/robot_description"}
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
            for k in range(6):
                msg = JointState(name=names, position=list(q0), velocity=[0.1 * k] * 5)
                msg.header.stamp.nanosec = 10_000_000 * (k + 1)
                states.publish(msg)
                if k == 1:
                    broken = JointState(name=names, position=[math.nan] * 5, velocity=[0.0] * 5)
                    broken.header.stamp.nanosec = 25_000_000
                    states.publish(broken)
                    states.publish(JointState(name=names[:3], position=[0.0] * 3, velocity=[0.0] * 3))
            wait_until(lambda: collector.count("/computed_torques") == 2, what="two torque samples")
            wait_until(lambda: collector.count("/diagnostics") > 0 and
                       diagnostic_values(collector.messages("/diagnostics")[-1])["rejected.total"] == "2",
                       what="the rejection counts")
        torques = collector.messages("/computed_torques")
    # the rejected samples (after 20 ms) break the stencil: the first torque needs 30, 40, 50 ms
    assert [stamp_ns(torque) for torque in torques] == [40_000_000, 50_000_000]
    for torque in torques:               # v = 0.1 k at (k + 1) 10 ms
        v = 0.1 * (stamp_ns(torque) // 10_000_000 - 1)
        expected = node.session.dynamics.torque(q0, np.full(5, v), np.full(5, 10.0))
        assert np.allclose(torque.effort, expected, rtol=1e-12, atol=1e-12)


def test_inverse_mode_hears_a_best_effort_publisher(capfd: pytest.CaptureFixture) -> None:
    """With the default joint_states_qos (keep_all, reliable) a best-effort /joint_states
    publisher (as many drivers are) is not matched, and the node says which parameter to
    set; with joint_states_qos best_effort it is heard. Torques equal RNEA at a = 10 rad/s^2
    (the central difference of v = 10 t is exact to ~1e-15; tolerance 1e-12)."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    with ros_context(9) as (context, _):
        collector = Collector(context, {"/computed_torques": "sensor_msgs/msg/JointState"})
        states = collector.create_publisher(JointState, "/joint_states",
                                            QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT))
        reliable = make_node(context, scene="arm_ptp", mode="inverse")
        log = []

        def warned() -> bool:
            log.append(capfd.readouterr().err)
            return "joint_states_qos:=best_effort" in "".join(log)

        with spinning(context, reliable, single_threaded=True):
            wait_until(warned, what="the incompatible-QoS warning")
        assert states.get_subscription_count() == 0
        node = make_node(context, scene="arm_ptp", mode="inverse", joint_states_qos="best_effort")
        names, q0 = list(node.session.robot.joint_names), load_scene("arm_ptp").q0
        with spinning(context, node, collector, single_threaded=True):
            wait_until(lambda: states.get_subscription_count() > 0, what="the node's best-effort subscription")
            wait_matched(node, "/computed_torques")
            k = 0

            def torques_arrived() -> bool:       # best effort may drop a sample: keep sending
                nonlocal k
                k += 1
                msg = JointState(name=names, position=list(q0), velocity=[0.1 * k] * 5)
                msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(10_000_000 * k, 10**9)
                states.publish(msg)
                return collector.count("/computed_torques") >= 3

            wait_until(torques_arrived, what="torques from best-effort joint states")
        torques = collector.messages("/computed_torques")
    for torque in torques:
        expected = node.session.dynamics.torque(q0, np.full(5, 10.0 * stamp_ns(torque) * 1e-9), np.full(5, 10.0))
        assert np.allclose(torque.effort, expected, rtol=1e-12, atol=1e-12)


def _urdf_movable_joints(urdf: str) -> list[str]:
    """Names of the non-fixed joints of a URDF (file path or text), parsed independently."""
    from lxml import etree
    root = etree.fromstring(urdf.encode()) if urdf.lstrip().startswith("<") else etree.parse(urdf).getroot()
    return [j.get("name") for j in root.iter("joint") if j.get("type") != "fixed"]


@pytest.mark.parametrize(("mode", "offset"), [("simulate", 10), ("inverse", 11)])
def test_every_published_message_passes_the_strict_field_check(mode: str, offset: int) -> None:
    """Under ROS_PYTHON_CHECK_FIELDS=1 (test/conftest.py) the node publishes on every one of
    its topics and no callback fails (a /diagnostics level built as an int instead of bytes
    raises "The 'level' field must be of type 'bytes'" here). Simulate mode's
    /joint_states names every movable joint of the scene's URDF, locked ones at their value."""
    assert os.environ["ROS_PYTHON_CHECK_FIELDS"] == "1"
    scene = load_scene("arm_ptp")
    with ros_context(offset) as (context, _):
        node = make_node(context, scene="arm_ptp", mode=mode, publish_rate=100.0, diagnostics_period=0.05)
        topics = {topic: TOPIC_TYPES[topic] for topic in node.session.topics}
        collector = Collector(context, topics)
        states = collector.create_publisher(JointState, "/joint_states", RELIABLE_DEEP) if mode == "inverse" else None
        with spinning(context, node, collector, single_threaded=True):
            for topic in topics:
                wait_matched(node, topic)
            k = 0

            def every_topic_heard() -> bool:
                nonlocal k
                if states is not None:        # inverse mode: feed joint states until it answers
                    k += 1
                    msg = JointState(name=list(scene.robot.joint_names), position=list(scene.q0),
                                     velocity=[0.01 * k] * 5)
                    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(10_000_000 * k, 10**9)
                    states.publish(msg)
                return all(collector.count(topic) > 0 for topic in topics)

            wait_until(every_topic_heard, what=f"a message on each of {sorted(topics)}")
        diagnostics = collector.messages("/diagnostics")
        joint_states = collector.messages("/joint_states") if mode == "simulate" else []
    assert node.session.counters.failed == {}
    assert {status.level for array in diagnostics for status in array.status} == {0}
    assert diagnostic_values(diagnostics[-1])["failed.total"] == "0"
    if joint_states:
        movable = _urdf_movable_joints(scene.urdf)
        assert sorted(joint_states[0].name) == sorted(movable) and len(movable) == 11
        robot = scene.robot
        by_name = dict(zip(joint_states[-1].name, joint_states[-1].position))
        assert robot.locked and all(by_name[name] == value for name, value in robot.locked.items())


def test_composed_scene_joint_states_and_field_check() -> None:
    """The two-robot gripping scene (URDF composed in memory, a free sphere): /joint_states
    carries every non-fixed joint of that URDF (moving ones, then the locked wheels at 0),
    and every message of its topics (/free_bodies included) converts to rclpy under
    ROS_PYTHON_CHECK_FIELDS=1."""
    from youbot_dynamics.ros.conversions import to_rclpy
    scene = load_scene("gripping")
    session = SimulationSession(scene, 100.0, samples_per_solve=1)
    outputs = [*session.step(), *session.step(), *session.diagnostics(1.0)]
    assert {topic for topic, _ in outputs} == set(session.topics) >= {"/free_bodies", "/joint_states"}
    for _, message in outputs:
        to_rclpy(message)
    message = dict(outputs)["/joint_states"]
    assert sorted(message.name) == sorted(_urdf_movable_joints(scene.urdf))
    assert len(message.name) == len(message.position) == len(message.velocity) == len(message.effort) == 22
    assert all(message.position[list(message.name).index(name)] == value for name, value in scene.robot.locked.items())


def test_no_callback_failure_stops_the_node(capfd: pytest.CaptureFixture) -> None:
    """Faults injected into a subscription (/joint_commands, twice), the step timer (once)
    and a service (~/reset): each is counted in /diagnostics under its cause, logged once
    with the message that caused it, the service answers success false, and the node goes
    on publishing. A one-point /joint_trajectory stamped with wall-clock time (now, about
    1.8e9 s), which killed the node before (ValueError from CubicSpline), is accepted."""
    with ros_context(12) as (context, _):
        node = make_node(context, scene="arm_ptp", publish_rate=100.0, diagnostics_period=0.05,
                         command_timeout=5.0)   # the wall-clock stamp ages while queued behind the commands
        collector = Collector(context, OUTPUTS)
        commands = collector.create_publisher(JointState, "/joint_commands", RELIABLE_DEEP)
        trajectories = collector.create_publisher(JointTrajectory, "/joint_trajectory", RELIABLE_DEEP)
        reset = collector.create_client(Trigger, "/dynamics_node/reset")
        session, step = node.session, node.session.step
        step_faults = [ZeroDivisionError("injected step fault")]

        def broken(*args) -> None:
            raise RuntimeError("injected fault")

        def step_failing_once():
            if step_faults:
                raise step_faults.pop()
            return step()

        session.effort_command, session.reset, session.step = broken, broken, step_failing_once
        wall_clock = JointTrajectory(joint_names=["arm_joint_1"], points=[JointTrajectoryPoint(positions=[2.0])])
        wall_clock.header.stamp.sec, wall_clock.header.stamp.nanosec = divmod(time.time_ns(), 10**9)
        with spinning(context, node, collector, single_threaded=True):
            wait_until(lambda: commands.get_subscription_count() > 0 and trajectories.get_subscription_count() > 0,
                       what="the node's subscriptions")
            assert reset.wait_for_service(timeout_sec=WAIT)

            def failed(cause: str, count: int) -> bool:
                if session.counters.failed.get(cause, 0) < count:
                    commands.publish(_command(["arm_joint_1"], [0.5]))
                    return False
                return True

            wait_until(lambda: failed("/joint_commands: RuntimeError", 2), what="two failed commands")

            def trajectory_accepted() -> bool:
                if session.counters.accepted == 0:
                    wall_clock.header.stamp.sec, wall_clock.header.stamp.nanosec = divmod(time.time_ns(), 10**9)
                    trajectories.publish(wall_clock)
                    return False
                return True

            wait_until(trajectory_accepted, what="the wall-clock stamped trajectory")
            future = reset.call_async(Trigger.Request())
            wait_until(future.done, what="the reset answer")
            samples = collector.count("/joint_states")
            wait_until(lambda: collector.count("/joint_states") > samples + 10, what="publishing after the faults")

            def reported() -> dict[str, str]:
                diagnostics = collector.messages("/diagnostics")
                return diagnostic_values(diagnostics[-1]) if diagnostics else {}

            failures = session.counters.failed      # final: nothing is published any more

            def all_reported() -> bool:
                values = reported()
                return values.get("failed.total") == str(sum(failures.values())) and \
                    values.get("accepted") == str(session.counters.accepted)

            wait_until(all_reported, what="the counts in /diagnostics")
        values = reported()
        states = collector.messages("/joint_states")
    assert not future.result().success and "RuntimeError: injected fault" in future.result().message
    assert values["failed.step timer: ZeroDivisionError"] == "1" and values["failed.~/reset: RuntimeError"] == "1"
    assert int(values["failed./joint_commands: RuntimeError"]) >= 2 and set(failures) == {
        "/joint_commands: RuntimeError", "step timer: ZeroDivisionError", "~/reset: RuntimeError"}
    assert values["rejected.total"] == "0" and int(values["accepted"]) >= 1, values     # the trajectory (maybe resent)
    assert all(np.isfinite(s.position).all() for s in states)
    assert [stamp_ns(m) for m in states] == [10_000_000 * k for k in range(len(states))]   # none skipped
    log = capfd.readouterr().err
    assert log.count("/joint_commands: RuntimeError: injected fault") == 1         # logged once, failed twice
    assert "message: sensor_msgs.msg.JointState(" in log and "injected step fault" in log


def test_oversized_empty_and_slow_input_is_bounded_counted_and_reported() -> None:
    """A /joint_commands message of 10 000 names (170 kB, over the 64 KiB limit) is
    rejected before it is deserialised, an empty one is rejected (not zero torque), both
    counted; a callback slower than ``callback_budget`` (a command handler made to take
    20 ms against a 5 ms budget) is counted in /diagnostics, level WARN; the node keeps
    publishing consecutive samples throughout."""
    with ros_context(13) as (context, _):
        node = make_node(context, scene="arm_ptp", publish_rate=100.0, diagnostics_period=0.05,
                         callback_budget=0.005)
        collector = Collector(context, OUTPUTS)
        commands = collector.create_publisher(JointState, "/joint_commands", RELIABLE_DEEP)
        session, accept = node.session, node.session.effort_command

        def slow_command(*args, **kwargs) -> None:
            if args[0] == ["arm_joint_2"]:
                time.sleep(0.02)
            return accept(*args, **kwargs)

        session.effort_command = slow_command
        huge = _command([f"joint_{k}" for k in range(10_000)], [0.0] * 10_000)
        with spinning(context, node, collector, single_threaded=True):
            wait_until(lambda: commands.get_subscription_count() > 0, what="the node's subscription")
            for message in (huge, _command([], []), _command(["arm_joint_2"], [0.1])):
                commands.publish(message)

            def reported() -> dict[str, str]:
                diagnostics = collector.messages("/diagnostics")
                return diagnostic_values(diagnostics[-1]) if diagnostics else {}

            wait_until(lambda: reported().get("rejected.too_large") == "1" and reported().get("rejected.empty") == "1"
                       and int(reported().get("overruns./joint_commands", "0")) >= 1, what="the counts")
            levels = [m.status[0].level for m in collector.messages("/diagnostics")]
        states = collector.messages("/joint_states")
    assert session.counters.accepted == 1 and sum(session.counters.rejected.values()) == 2
    assert b"\x01" in levels or 1 in levels                        # WARN after the overrun
    assert float(reported()["worst_callback_s"]) >= 0.02
    assert [stamp_ns(m) for m in states] == [10_000_000 * k for k in range(len(states))]
