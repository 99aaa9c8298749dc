"""The node's ros2_control-style interfaces with a client acting as MoveIt would: its own rclpy
context and node, spun in its own thread, sends FollowJointTrajectory and GripperCommand goals
and Float64MultiArray commands to a dynamics node spun in another context."""
from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from ros_support import WAIT, Collector, ros_context, spinning, stamp_ns, wait_until
from scene_support import write
from wrench_support import (LIFTED_JOINT_4, gripped_sphere_scene, hand_masses, relative_error, sphere_mass,
                            static_load)

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

import rclpy  # noqa: E402
from action_msgs.msg import GoalStatus  # noqa: E402
from builtin_interfaces.msg import Duration  # noqa: E402
from control_msgs.action import FollowJointTrajectory, GripperCommand  # noqa: E402
from control_msgs.msg import GripperCommand as GripperCommandMsg, JointTolerance  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from std_msgs.msg import Float64MultiArray  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
ARM = [f"arm_joint_{k}" for k in range(1, 6)]
CANDLE = np.array([2.9496, 1.1345, -2.5482, 1.7890, 2.9234])
TARGET = CANDLE + np.array([0.3, 0.2, -0.2, 0.2, 0.3])
Result = FollowJointTrajectory.Result
SLOW = 4 * WAIT
"""Wait (s) for about 5 s of contact stepping at time_scale 1 on a loaded machine."""


def frictionless_arm(tmp_path: Path) -> str:
    """arm_ptp without joint friction: computed torque then settles on its target exactly
    (arm_ptp's Stribeck static friction, 0.4 N m, holds joint 3 0.09 rad off under kp 400)."""
    scene = yaml.safe_load((REPO / "config/scenes/arm_ptp.yaml").read_text())
    scene["friction"] = {"default": "none"}
    path = tmp_path / "arm.yaml"
    path.write_text(yaml.safe_dump(scene))
    return str(path)


def make_node(context, **parameters) -> DynamicsNode:
    return DynamicsNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in parameters.items()])


def duration(seconds: float) -> Duration:
    return Duration(sec=int(seconds), nanosec=round(seconds % 1 * 1e9))


@contextmanager
def client_context(domain: int):
    """A second rclpy context in the node's domain: the client's own middleware participant."""
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    try:
        yield context
    finally:
        context.try_shutdown()


class MoveItLike(Collector):
    """An action client as MoveIt's controller manager uses them; keeps every feedback, and
    every message of ``topics`` (name: type)."""

    def __init__(self, context: Context, namespace: str = "/", topics: dict[str, str] | None = None) -> None:
        super().__init__(context, topics or {}, "moveit_like", namespace)
        self.arm = ActionClient(self, FollowJointTrajectory, "arm_controller/follow_joint_trajectory")
        self.gripper = ActionClient(self, GripperCommand, "gripper_controller/gripper_command")
        self.commands = self.create_publisher(Float64MultiArray, "arm_controller/commands", RELIABLE_DEEP)
        self.feedback: list = []

    def send(self, names, points, path=(), goal=(), goal_time=0.0):
        """Send a goal and wait for its acceptance; returns the goal handle."""
        request = FollowJointTrajectory.Goal()
        request.trajectory = JointTrajectory(joint_names=list(names), points=[
            JointTrajectoryPoint(positions=list(map(float, q)), time_from_start=duration(t)) for t, q in points])
        request.path_tolerance = [JointTolerance(name=n, position=p) for n, p in path]
        request.goal_tolerance = [JointTolerance(name=n, position=p) for n, p in goal]
        request.goal_time_tolerance = duration(goal_time)
        return self._accepted(self.arm, request)

    def _accepted(self, client, request):
        assert client.wait_for_server(timeout_sec=WAIT)
        future = client.send_goal_async(request, feedback_callback=lambda m: self.feedback.append(m.feedback))
        wait_until(future.done, what="the goal's acceptance")
        handle = future.result()
        assert handle.accepted
        return handle


def result_of(handle, timeout: float = WAIT):
    future = handle.get_result_async()
    wait_until(future.done, timeout, what="the goal's result")
    return future.result()


@contextmanager
def node_and_client(offset: int, namespace: str = "/", topics: dict[str, str] | None = None, **parameters):
    """A dynamics node (in ``namespace``) and a MoveIt-like client in the same namespace (keeping
    the messages of ``topics``), each in its own context, spun in its own thread."""
    with ros_context(offset) as (context, domain), client_context(domain) as other:
        node = DynamicsNode(context=context, namespace=namespace,
                            parameter_overrides=[Parameter(k, value=v) for k, v in parameters.items()])
        client = MoveItLike(other, namespace, topics)
        with spinning(context, node, single_threaded=True), spinning(other, client):
            yield node, client


def test_follow_joint_trajectory_results(tmp_path) -> None:
    """A valid goal with the joints in reverse order ends SUCCESSFUL within its goal
    tolerance; an unknown joint is INVALID_JOINTS; a move the effort limits cannot follow
    within a 0.01 rad path tolerance is PATH_TOLERANCE_VIOLATED. Feedback comes once per
    published sample (simulated time: consecutive stamps 1/publish_rate apart)."""
    with node_and_client(20, scene=frictionless_arm(tmp_path), publish_rate=100.0, time_scale=1.0) as (node, client):
        order = ARM[::-1]
        handle = client.send(order, [(1.5, TARGET[::-1])], goal=[(n, 0.002) for n in ARM], goal_time=1.0)
        response = result_of(handle)
        assert response.status == GoalStatus.STATUS_SUCCEEDED
        assert response.result.error_code == Result.SUCCESSFUL, response.result.error_string
        final = node.session.snapshot.q
        assert np.all(np.abs(final - TARGET) <= 0.002)
        # the result (a service reply) may overtake the last feedback (a topic): wait for them
        wait_until(lambda: len(client.feedback) >= 150, what="a feedback per sample of the 1.5 s goal")
        stamps = np.array([f.header.stamp.sec * 10**9 + f.header.stamp.nanosec for f in client.feedback])
        assert client.feedback[0].joint_names == ARM and len(stamps) >= 150
        assert np.all(np.diff(stamps) == 10_000_000)     # one per sample at 100 Hz, none missing
        last = client.feedback[-1]
        np.testing.assert_allclose(np.array(last.desired.positions) - last.actual.positions, last.error.positions,
                                   atol=1e-12)

        response = result_of(client.send(["arm_joint_1", "gripper_joint"], [(1.0, [3.0, 0.0])]))
        assert response.status == GoalStatus.STATUS_ABORTED
        assert response.result.error_code == Result.INVALID_JOINTS and "gripper_joint" in response.result.error_string

        fast = TARGET.copy()
        fast[1] += 1.0                       # joint 2 by 1 rad in 0.2 s: beyond its 9.5 N m
        response = result_of(client.send(ARM, [(0.2, fast)], path=[(n, 0.01) for n in ARM]))
        assert response.status == GoalStatus.STATUS_ABORTED
        assert response.result.error_code == Result.PATH_TOLERANCE_VIOLATED, response.result.error_string
        assert "arm_joint_2" in response.result.error_string


def test_cancel_and_preemption(tmp_path) -> None:
    """A goal cancelled mid-way ends CANCELED with the arm held short of its target; a goal
    preempted by a second one ends CANCELED (INVALID_GOAL, as JTC) and the second succeeds; a
    goal whose joints an arm_controller/commands message takes over ends CANCELED too."""
    with node_and_client(21, scene=frictionless_arm(tmp_path), publish_rate=100.0, time_scale=1.0) as (node, client):
        slow = client.send(ARM, [(20.0, TARGET)])
        wait_until(lambda: len(client.feedback) > 20, what="feedback")
        cancel = slow.cancel_goal_async()
        wait_until(cancel.done, what="the cancel response")
        response = result_of(slow)
        assert response.status == GoalStatus.STATUS_CANCELED
        held = node.session.snapshot.q.copy()
        assert np.max(np.abs(held - TARGET)) > 0.2                 # stopped early
        client.feedback.clear()
        first = client.send(ARM, [(20.0, CANDLE)])
        wait_until(lambda: len(client.feedback) > 20, what="feedback of the first goal")
        second = client.send(ARM, [(1.0, TARGET)], goal=[(n, 0.002) for n in ARM], goal_time=1.0)
        response = result_of(first)
        assert response.status == GoalStatus.STATUS_CANCELED
        assert response.result.error_code == Result.INVALID_GOAL
        response = result_of(second)
        assert response.status == GoalStatus.STATUS_SUCCEEDED, response.result.error_string

        third = client.send(ARM, [(20.0, CANDLE)])
        wait_until(lambda: client.commands.get_subscription_count() > 0, what="the node's commands subscription")
        client.commands.publish(Float64MultiArray(data=TARGET.tolist()))
        response = result_of(third)
        assert response.status == GoalStatus.STATUS_CANCELED
        assert "arm_controller/commands" in response.result.error_string


def settled_after(node: DynamicsNode, publisher, message, seconds: float = 2.0) -> np.ndarray:
    """Publish ``message`` until the node has accepted it, then the arm's q once ``seconds``
    of simulated time have passed."""
    def accepted() -> bool:
        if node.session.counters.accepted == 0:
            publisher.publish(message)
            return False
        return True

    wait_until(lambda: publisher.get_subscription_count() > 0, what="the node's subscription")
    wait_until(accepted, what="the command to be accepted")
    start = node.session.t
    wait_until(lambda: node.session.t > start + seconds, what="simulated time")
    return node.session.snapshot.q.copy()


def test_forward_position_commands_move_the_arm_like_a_joint_trajectory(tmp_path) -> None:
    """arm_controller/commands (position) holding TARGET leaves the arm where a
    /joint_trajectory to TARGET does; a command of the wrong length or with a NaN is refused
    and counted."""
    scene = frictionless_arm(tmp_path)
    finals = {}
    for offset, (topic, kind, message) in enumerate((
            ("joint_trajectory", JointTrajectory, JointTrajectory(joint_names=ARM, points=[
                JointTrajectoryPoint(positions=TARGET.tolist(), time_from_start=Duration())])),
            ("arm_controller/commands", Float64MultiArray, Float64MultiArray(data=TARGET.tolist())))):
        with ros_context(22 + offset) as (context, _):
            node = make_node(context, scene=scene, publish_rate=100.0, time_scale=0.0)
            sender = Collector(context, {})
            publisher = sender.create_publisher(kind, topic, RELIABLE_DEEP)
            with spinning(context, node, sender, single_threaded=True):
                finals[topic] = settled_after(node, publisher, message)
                if kind is Float64MultiArray:
                    publisher.publish(Float64MultiArray(data=TARGET[:4].tolist()))
                    publisher.publish(Float64MultiArray(data=[float("nan"), *TARGET[1:]]))
                    counters = node.session.counters
                    rejected = counters.rejected
                    wait_until(lambda: (rejected["length_mismatch"], rejected["non_finite"]) == (1, 1),
                               what="the two bad commands counted")
                    assert np.all(np.isfinite(node.session.snapshot.q))
    np.testing.assert_allclose(finals["arm_controller/commands"], finals["joint_trajectory"], atol=1e-6)
    np.testing.assert_allclose(finals["arm_controller/commands"], TARGET, atol=1e-6)


def test_gripper_closes_on_the_sphere(tmp_path) -> None:
    """grasp: the pads (gripper_joints) squeeze the sphere at the scene's 1.5 N; a goal 3 mm
    into the sphere with max_effort 1 N stalls on it (contact, the pads still) with each pad's
    force capped at 1 N, and aborts, as gripper_action_controller does without
    allow_stalling; the sphere stays held (it sinks less than 0.1 mm). The node and the client
    run in /youbot1: the action's name is relative."""
    with node_and_client(24, "/youbot1", scene="grasp", publish_rate=100.0, time_scale=1.0,
                         gripper_joints="pad_l_joint,pad_r_joint", stall_timeout=0.3) as (node, client):
        wait_until(lambda: node.session.t > 0.2, what="the grasp to settle")
        assert np.allclose(node.session.snapshot.tau, 1.5)          # the scene's servo force, above the cap
        handle = client._accepted(client.gripper, GripperCommand.Goal(
            command=GripperCommandMsg(position=0.003, max_effort=1.0)))
        response = result_of(handle)
        result = response.result
        assert response.status == GoalStatus.STATUS_ABORTED
        assert result.stalled and not result.reached_goal
        assert 0.9 <= result.effort <= 1.0 + 1e-12
        assert np.all(np.abs(node.session.snapshot.tau) <= 1.0 + 1e-12)
        assert abs(node.session.snapshot.bodies["sphere"][2, 3]) < 1e-4


def test_a_gripper_goal_holds_the_sphere_the_arm_lifts_it_and_the_wrist_reads_its_load(tmp_path) -> None:
    """gripping with youBot 1's open hand around the sphere on its plate, through the action
    servers: GripperCommand (4 mm, 1 mm into the sphere; max_effort 1 N) stalls on the sphere
    and succeeds (allow_stalling), the effort within max_effort; FollowJointTrajectory lifts
    the arm; 1 s later the /wrist_wrench heard equals the static load of palm, fingers and
    sphere computed by hand from the /joint_states and /free_bodies of its stamp (the URDF's
    masses and the sphere's density), in the palm's frame (frame_id), to 1 %."""
    path = write(tmp_path, gripped_sphere_scene(), "gripped_sphere.yaml")
    topics = {"/wrist_wrench": "geometry_msgs/msg/WrenchStamped", "/joint_states": "sensor_msgs/msg/JointState",
              "/free_bodies": "geometry_msgs/msg/PoseArray"}
    arm = [f"yb1_{name}" for name in ARM]
    with node_and_client(6, topics=topics, scene=str(path), publish_rate=100.0, time_scale=1.0, stall_timeout=0.3,
                         allow_stalling=True) as (node, client):
        response = result_of(client._accepted(client.gripper, GripperCommand.Goal(
            command=GripperCommandMsg(position=0.004, max_effort=1.0))), SLOW)
        assert response.status == GoalStatus.STATUS_SUCCEEDED
        assert response.result.stalled and not response.result.reached_goal
        assert 0.85 <= response.result.effort <= 1.0                  # measured 0.900: kp m e, 1 mm
        state = client.messages("/joint_states")[-1]
        target = [state.position[list(state.name).index(name)] for name in arm]
        target[3] = LIFTED_JOINT_4
        response = result_of(client.send(arm, [(2.0, target)]), SLOW)
        assert response.result.error_code == Result.SUCCESSFUL, response.result.error_string
        lifted_at = node.session.t

        def latest_heard() -> int:
            """The stamp (ns) of the latest sample the client heard on all three topics."""
            common = set.intersection(*({stamp_ns(m) for m in client.messages(topic)} for topic in topics))
            return max(common, default=0)

        # the client's own reception, not the node's clock: messages still in flight when the
        # node stops would be lost (a loaded machine heard only 0.76 s of the hold)
        wait_until(lambda: latest_heard() > lifted_at * 1e9 + 1e9, SLOW, what="1 s of holding the sphere, heard")
    heard = {topic: {stamp_ns(m): m for m in client.messages(topic)} for topic in topics}
    stamp = max(set.intersection(*(set(by_stamp) for by_stamp in heard.values())))     # the latest sample of all three
    assert stamp > lifted_at * 1e9 + 0.9e9
    wrench, state, bodies = (heard[topic][stamp] for topic in ("/wrist_wrench", "/joint_states", "/free_bodies"))
    robot = load_scene(path).robot
    q = np.array([state.position[list(state.name).index(name)] for name in robot.joint_names])
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    assert wrench.header.frame_id == "yb1_gripper_palm_link" and bodies.header.frame_id == "world"
    sphere = bodies.poses[0].position
    centre = np.array([sphere.x, sphere.y, sphere.z])
    assert centre[2] - 0.025 - 0.135 > 0.05                                # off the plate
    expected = static_load(data.oMf[robot.frame_id("yb1_gripper_palm_link")],
                           hand_masses(robot.model, data, load_scene(path).urdf, "yb1_") + [(sphere_mass(), centre)])
    force, torque = wrench.wrench.force, wrench.wrench.torque
    reading = (np.array([force.x, force.y, force.z]), np.array([torque.x, torque.y, torque.z]))
    # measured 1.3e-5 relative in the ROS-free test of this motion; bound 1 %
    assert relative_error(reading, expected) <= 0.01, (reading, expected)
