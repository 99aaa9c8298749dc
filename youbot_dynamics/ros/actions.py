"""The ros2_control-style controllers of the dynamics node on rclpy: the action servers of
:data:`~youbot_dynamics.node.interface.ACTIONS` and the ``<controller>/commands``
subscriptions (relative names: a namespace moves them). The logic is ROS-free
(:mod:`~youbot_dynamics.node.trajectory_goal`, :mod:`~youbot_dynamics.node.gripper_goal`,
:mod:`~youbot_dynamics.node.forward_commands`); this module carries goals, feedback and
results.

Every goal is accepted; one that cannot run ends at once ABORTED with its result code and
error string (rclpy's rejection carries no result, and a MoveIt client reads the code). A
newer goal preempts the running one of its controller: the older ends CANCELED with
``INVALID_GOAL`` "Current goal cancelled due to new incoming action." (JTC's words); so does
a running goal when a ``<controller>/commands`` message takes its joints over, the
simulation fails (diverges) or ``~/reset`` restarts the scene (with that reason). A cancel
request holds the joints where they are and ends the goal CANCELED (``SUCCESSFUL``).

Feedback goes out once per published sample, from the node's step timer
(:meth:`Controllers.on_sample`), with the node's topic QoS (reliable, keep last 1000).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.task import Future

from youbot_dynamics.io.stamps import NS_PER_S, stamp_ns_of
from youbot_dynamics.node.controller_groups import group_joints
from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.forward_commands import forward_command
from youbot_dynamics.node.gripper_goal import GripperGoal, GripperState
from youbot_dynamics.node.interface import ACTIONS, TOPICS
from youbot_dynamics.node.trajectory_goal import INVALID_GOAL, SUCCESSFUL, GoalRejected, Outcome, TrajectoryGoal
from youbot_dynamics.ros.conversions import rclpy_class
from youbot_dynamics.ros.qos import RELIABLE_DEEP

PREEMPTED = "Current goal cancelled due to new incoming action."
"""The error string of a preempted FollowJointTrajectory goal (joint_trajectory_controller's)."""


@dataclass
class _Running:
    """A goal under way: its handle, its ROS-free goal and the future its execute callback
    awaits (resolved with the outcome)."""

    handle: object
    goal: object
    done: Future


def _tolerances(entries) -> list[tuple[str, float, float, float]]:
    return [(t.name, t.position, t.velocity, t.acceleration) for t in entries]


def _point(point_class, values: np.ndarray):
    return point_class(positions=values[0].tolist(), velocities=values[1].tolist())


class Controllers:
    """The arm and gripper controllers of a simulate-mode node: ``subscribe(topic,
    callback)`` is the node's guarded subscription maker."""

    def __init__(self, node: Node, session, params: dict, subscribe: Callable) -> None:
        self.node, self.session, self.params = node, session, params
        robot = session.robot
        self.joints = {name: group_joints(robot, name, params[key]) for name, key in
                       (("arm_controller", "arm_joints"), ("gripper_controller", "gripper_joints"))}
        self.running: dict[str, _Running | None] = dict.fromkeys(self.joints)
        executes = {"arm_controller": self._execute_trajectory, "gripper_controller": self._execute_gripper}
        self.servers = []
        for action in ACTIONS:
            if self.joints[action.when]:
                self.servers.append(ActionServer(
                    node, rclpy_class(action.type), action.name, execute_callback=executes[action.when],
                    goal_callback=lambda request: GoalResponse.ACCEPT,
                    cancel_callback=lambda handle: CancelResponse.ACCEPT, feedback_pub_qos_profile=RELIABLE_DEEP))
        for topic in TOPICS:
            group = topic.when
            if topic.direction == "sub" and group in self.joints and self.joints[group]:
                subscribe(topic, lambda msg, group=group: self._forward(group, msg.data))

    def _forward(self, group: str, data) -> None:
        """A ``<group>/commands`` message: applied, then the group's running goal ends."""
        forward_command(self.session, group, self.joints[group], data, self.params["commands_interface"])
        self.interrupt(group, f"Current goal cancelled by a command on {group}/commands.")

    def interrupt(self, group: str | None, why: str) -> None:
        """End the running goal of ``group`` (None: every group) CANCELED, saying ``why``."""
        for name, running in self.running.items():
            if running is not None and group in (None, name):
                self._end(name, running, Outcome("canceled", INVALID_GOAL, why) if name == "arm_controller"
                          else "canceled")

    # ---- goals -----------------------------------------------------------------------
    def _begin(self, group: str, handle, goal) -> Future:
        """Make ``goal`` its controller's running goal (preempting the older one)."""
        self.interrupt(group, PREEMPTED)
        running = _Running(handle, goal, Future())
        self.running[group] = running
        return running.done

    def _end(self, group: str, running: _Running, outcome) -> None:
        if self.running[group] is running:
            self.running[group] = None
        if not running.done.done():
            running.done.set_result(outcome)

    async def _execute_trajectory(self, handle):
        result_class = rclpy_class("control_msgs/action/FollowJointTrajectory").Result
        goal = handle.request
        points = [(stamp_ns_of(p.time_from_start), p.positions, p.velocities) for p in goal.trajectory.points]
        p = self.params
        try:
            running = TrajectoryGoal.start(
                self.session, "arm_controller", self.joints["arm_controller"], list(goal.trajectory.joint_names),
                points, stamp_ns_of(goal.trajectory.header.stamp), _tolerances(goal.path_tolerance),
                _tolerances(goal.goal_tolerance), stamp_ns_of(goal.goal_time_tolerance),
                round(p["goal_time_tolerance"] * NS_PER_S), p["stopped_velocity_tolerance"])
        except GoalRejected as error:
            handle.abort()
            self.node.get_logger().warning(f"follow_joint_trajectory: goal aborted ({error.code}: {error})")
            return result_class(error_code=error.code, error_string=str(error))
        outcome = await self._begin("arm_controller", handle, running)
        _finish(handle, outcome.status)
        return result_class(error_code=outcome.code, error_string=outcome.message)

    async def _execute_gripper(self, handle):
        result_class = rclpy_class("control_msgs/action/GripperCommand").Result
        command, p = handle.request.command, self.params
        try:
            running = GripperGoal.start(self.session, "gripper_controller", self.joints["gripper_controller"],
                                        command.position, command.max_effort, p["gripper_goal_tolerance"],
                                        p["stall_timeout"], p["allow_stalling"])
        except InputRejected as error:
            handle.abort()
            self.node.get_logger().warning(f"gripper_command: goal aborted ({error})")
            return result_class()
        outcome = await self._begin("gripper_controller", handle, running)
        status, state = outcome if isinstance(outcome, tuple) else (outcome, None)
        _finish(handle, status)
        return result_class() if state is None else _gripper_message(result_class, state)

    # ---- per sample ------------------------------------------------------------------
    def on_sample(self) -> None:
        """After each published sample: feedback of the running goals, their cancel
        requests and their outcomes."""
        arm = self.running["arm_controller"]
        if arm is not None:
            self._trajectory_sample(arm)
        gripper = self.running["gripper_controller"]
        if gripper is not None:
            state, status = gripper.goal.update()
            if gripper.handle.is_cancel_requested:
                gripper.goal.hold()
                self._end("gripper_controller", gripper, ("canceled", state))
                return
            gripper.handle.publish_feedback(_gripper_message(
                rclpy_class("control_msgs/action/GripperCommand").Feedback, state))
            if status is not None:
                self._end("gripper_controller", gripper, (status, state))

    def _trajectory_sample(self, arm: _Running) -> None:
        if arm.handle.is_cancel_requested:
            arm.goal.hold()
            self._end("arm_controller", arm, Outcome("canceled", SUCCESSFUL))
            return
        (desired, actual, error), outcome = arm.goal.update()
        action = rclpy_class("control_msgs/action/FollowJointTrajectory")
        feedback = action.Feedback(joint_names=list(arm.goal.joints))
        feedback.header.stamp.sec, feedback.header.stamp.nanosec = divmod(self.session.stamp_ns, NS_PER_S)
        point = rclpy_class("trajectory_msgs/msg/JointTrajectoryPoint")
        feedback.desired, feedback.actual, feedback.error = (_point(point, values)
                                                             for values in (desired, actual, error))
        arm.handle.publish_feedback(feedback)
        if outcome is not None:
            self._end("arm_controller", arm, outcome)


def _gripper_message(message_class, state: GripperState):
    return message_class(position=state.position, effort=state.effort, stalled=state.stalled,
                         reached_goal=state.reached_goal)


def _finish(handle, status: str) -> None:
    """End a goal's handle with ``status`` (succeeded, aborted, canceled). A goal that no
    cancel request moved to CANCELING (a preempted one) is moved there first, as rclpy's own
    cancel handling does, since only a cancelling goal can end CANCELED."""
    if status == "succeeded":
        handle.succeed()
    elif status == "aborted":
        handle.abort()
    else:
        if not handle.is_cancel_requested:
            handle._update_state(_rclpy.GoalEvent.CANCEL_GOAL)
        handle.canceled()
