"""The message packages built from interfaces/ (interfaces/build.sh, run by `make`) are ROS 2
Jazzy's: control_msgs' FollowJointTrajectory, GripperCommand and JointTolerance have Jazzy's
fields and RIHS01 type hashes (tf2_msgs' TFMessage too), and a FollowJointTrajectory and a
GripperCommand goal go through an rclpy ActionServer and ActionClient with feedback and result.

Reference hashes: the rosidl_generator_c output of ros-controls/control_msgs in the workspace of
saahu27/aprs (commit 4013b140da197a3dda08b2b4089a2ff77d0627c9, aprs_ws/build/control_msgs/
rosidl_generator_c/control_msgs/action/detail/{follow_joint_trajectory,gripper_command}__description.c),
built against ROS 2 rolling of 2023. No control_msgs release for Jazzy (5.0.0 to 5.10.0) changed
these types' fields, and the referenced types' hashes in that output (std_msgs/Header,
trajectory_msgs/*, builtin_interfaces/*, unique_identifier_msgs/UUID,
service_msgs/ServiceEventInfo) equal the PyPI Jazzy wheels', so a Jazzy install has these hashes.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

control_action = pytest.importorskip(
    "control_msgs.action", reason="control_msgs is not installed: `make` builds it (interfaces/build.sh)")
import control_msgs.msg  # noqa: E402
from rclpy.action import ActionClient, ActionServer, CancelResponse, GoalResponse  # noqa: E402
from rclpy.node import Node  # noqa: E402

from ros_support import WAIT, ros_context, spinning, wait_until  # noqa: E402

REFERENCE_HASHES = {
    "control_msgs/action/FollowJointTrajectory":
        "RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6",
    "control_msgs/action/FollowJointTrajectory_Goal":
        "RIHS01_8a9060704b269608f5a340934cc26e66869dd14bdac29e2e7fd9ec8b9882d205",
    "control_msgs/action/FollowJointTrajectory_Result":
        "RIHS01_8002e99ed2c14c6faa522f2a93c26d744c5982f254f9e98ff9c6f19789bdb220",
    "control_msgs/action/FollowJointTrajectory_Feedback":
        "RIHS01_3fd0aaecf71725121ae1ff7f01098a5e0da581e672be18a6b2c286cb43d96b49",
    "control_msgs/action/FollowJointTrajectory_FeedbackMessage":
        "RIHS01_80398fcb9674a79081a9906e2ccf0c804dd7cb15e22e362e606ee87186beab71",
    "control_msgs/action/GripperCommand":
        "RIHS01_e17c0e644eccf14bea84a0a93e0977182872c2eb7873ca6694900059b46dbc84",
    "control_msgs/action/GripperCommand_Goal":
        "RIHS01_607d9f41eb241e1922e90f02125e87ae6bfb78f7f64a71dc92630263d01f8b6d",
    "control_msgs/action/GripperCommand_Result":
        "RIHS01_bf512d5aa6a0e4fe4d8be22b2ec4a1973c3d250fa1f65e47450322c25c45c0a0",
    "control_msgs/action/GripperCommand_Feedback":
        "RIHS01_8f7c520077bab528bb9161ee3b83c81eee1f8aecadb8922ce82c79d667a819c4",
    "control_msgs/action/GripperCommand_FeedbackMessage":
        "RIHS01_392ff03fcd872f9dc2405cbeb2897fcf011ad9998458b6aa85c603b8a49e431d",
    "control_msgs/msg/GripperCommand": "RIHS01_57eb8f326c9889ca8bb34ead82cc94cc09bf6bc5c3b6c09546dca3a00b589890",
    "control_msgs/msg/JointTolerance": "RIHS01_c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648",
    "control_msgs/msg/JointComponentTolerance":
        "RIHS01_739ea7566931944d33830fa10f1bf5e7a7fbdc3172bce7a7eaac642bd6e3ffa4",
    "tf2_msgs/msg/TFMessage": "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
}
TOLERANCE = {"position": "double", "velocity": "double", "acceleration": "double"}
GRIPPER_STATE = {"position": "double", "effort": "double", "stalled": "boolean", "reached_goal": "boolean"}
FJT = control_action.FollowJointTrajectory
GRIPPER = control_action.GripperCommand


def installed_hashes(package: str) -> dict[str, str]:
    """Every type hash in the type-description files (share/PACKAGE/*/*.json) that rosidl
    generated for PACKAGE, found from where its Python package was imported."""
    module = Path(__import__(package).__file__).resolve()
    share = next(parent / "share" / package for parent in module.parents if (parent / "share" / package).is_dir())
    return {entry["type_name"]: entry["hash_string"] for path in share.glob("*/*.json")
            for entry in json.loads(path.read_text())["type_hashes"]}


def test_control_msgs_have_the_jazzy_fields() -> None:
    """Field names, types and order as control_msgs 5.x (ROS 2 Jazzy) defines them."""
    assert control_msgs.msg.JointTolerance.get_fields_and_field_types() == {"name": "string", **TOLERANCE}
    assert control_msgs.msg.JointComponentTolerance.get_fields_and_field_types() == {
        "joint_name": "string", "component": "uint16", **TOLERANCE}
    assert control_msgs.msg.GripperCommand.get_fields_and_field_types() == {
        "position": "double", "max_effort": "double"}
    assert list(FJT.Goal.get_fields_and_field_types().items()) == [
        ("trajectory", "trajectory_msgs/JointTrajectory"),
        ("multi_dof_trajectory", "trajectory_msgs/MultiDOFJointTrajectory"),
        ("path_tolerance", "sequence<control_msgs/JointTolerance>"),
        ("component_path_tolerance", "sequence<control_msgs/JointComponentTolerance>"),
        ("goal_tolerance", "sequence<control_msgs/JointTolerance>"),
        ("component_goal_tolerance", "sequence<control_msgs/JointComponentTolerance>"),
        ("goal_time_tolerance", "builtin_interfaces/Duration")]
    assert FJT.Result.get_fields_and_field_types() == {"error_code": "int32", "error_string": "string"}
    assert (FJT.Result.SUCCESSFUL, FJT.Result.INVALID_GOAL, FJT.Result.INVALID_JOINTS, FJT.Result.OLD_HEADER_TIMESTAMP,
            FJT.Result.PATH_TOLERANCE_VIOLATED, FJT.Result.GOAL_TOLERANCE_VIOLATED) == (0, -1, -2, -3, -4, -5)
    assert list(FJT.Feedback.get_fields_and_field_types().items()) == [
        ("header", "std_msgs/Header"), ("joint_names", "sequence<string>"),
        *((name, "trajectory_msgs/JointTrajectoryPoint") for name in ("desired", "actual", "error")),
        ("multi_dof_joint_names", "sequence<string>"),
        *((f"multi_dof_{name}", "trajectory_msgs/MultiDOFJointTrajectoryPoint")
          for name in ("desired", "actual", "error"))]
    assert (control_msgs.msg.JointComponentTolerance.X_AXIS, control_msgs.msg.JointComponentTolerance.ROTATION) == (1, 5)
    assert GRIPPER.Goal.get_fields_and_field_types() == {"command": "control_msgs/GripperCommand"}
    assert GRIPPER.Result.get_fields_and_field_types() == GRIPPER_STATE
    assert GRIPPER.Feedback.get_fields_and_field_types() == GRIPPER_STATE


def test_type_hashes_equal_the_reference() -> None:
    """The RIHS01 hashes rosidl computed for the built types are the reference's (a Jazzy
    install's: see the module docstring); tf2_msgs' TFMessage's is Jazzy's as well."""
    pytest.importorskip("tf2_msgs.msg", reason="tf2_msgs is not installed: `make` builds it (interfaces/build.sh)")
    installed = installed_hashes("control_msgs") | installed_hashes("tf2_msgs")
    assert {name: installed.get(name) for name in REFERENCE_HASHES} == REFERENCE_HASHES


class TrajectoryServer(Node):
    """FollowJointTrajectory and GripperCommand servers that answer every goal with one
    feedback (echoing the goal) and a result."""

    def __init__(self, context: object) -> None:
        super().__init__("interfaces_server", context=context)
        self.trajectory = ActionServer(self, FJT, "arm_controller/follow_joint_trajectory", self.follow,
                                       goal_callback=lambda _: GoalResponse.ACCEPT,
                                       cancel_callback=lambda _: CancelResponse.ACCEPT)
        self.gripper = ActionServer(self, GRIPPER, "gripper_controller/gripper_command", self.grip)

    def feedback_heard(self, action: str) -> None:
        """Wait until the client's feedback subscription is discovered (feedback is volatile)."""
        wait_until(lambda: self.count_subscribers(f"/{action}/_action/feedback") > 0, what=f"{action}'s client")

    def follow(self, handle: object) -> object:
        goal = handle.request
        self.feedback_heard("arm_controller/follow_joint_trajectory")
        handle.publish_feedback(FJT.Feedback(joint_names=goal.trajectory.joint_names,
                                             desired=goal.trajectory.points[-1]))
        handle.succeed()
        return FJT.Result(error_code=FJT.Result.SUCCESSFUL, error_string=f"{len(goal.goal_tolerance)} tolerances")

    def grip(self, handle: object) -> object:
        command = handle.request.command
        self.feedback_heard("gripper_controller/gripper_command")
        handle.publish_feedback(GRIPPER.Feedback(position=command.position, effort=0.5 * command.max_effort))
        handle.succeed()
        return GRIPPER.Result(position=command.position, effort=command.max_effort, stalled=True, reached_goal=False)


def send(client: ActionClient, goal: object) -> tuple[list, object]:
    """Send ``goal``; the feedback messages and the result response once the result is in."""
    feedback: list = []
    assert client.wait_for_server(timeout_sec=WAIT), "no action server"
    sent = client.send_goal_async(goal, feedback_callback=feedback.append)
    wait_until(sent.done, what="the goal response")
    handle = sent.result()
    assert handle.accepted
    result = handle.get_result_async()
    wait_until(lambda: result.done() and feedback, what="the result and the feedback")
    return feedback, result.result()


@pytest.mark.ros
def test_action_round_trip_through_rclpy() -> None:
    """A client node sends a FollowJointTrajectory goal (joint names, two points, a goal
    tolerance) and a GripperCommand goal; the server node's feedback and results arrive intact,
    and the feedback topic is offered with the reference type hash."""
    from builtin_interfaces.msg import Duration
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    names = [f"arm_joint_{i}" for i in range(1, 6)]
    goal = FJT.Goal(
        trajectory=JointTrajectory(joint_names=names, points=[
            JointTrajectoryPoint(positions=[0.0] * 5, time_from_start=Duration(sec=0)),
            JointTrajectoryPoint(positions=[0.1, 0.2, -0.3, 0.4, 0.5], time_from_start=Duration(sec=2))]),
        goal_tolerance=[control_msgs.msg.JointTolerance(name=name, position=0.01) for name in names],
        goal_time_tolerance=Duration(nanosec=500_000_000))
    with ros_context(22) as (context, _):
        server = TrajectoryServer(context)
        client_node = Node("interfaces_client", context=context)
        trajectory = ActionClient(client_node, FJT, "arm_controller/follow_joint_trajectory")
        gripper = ActionClient(client_node, GRIPPER, "gripper_controller/gripper_command")
        with spinning(context, server, client_node):
            feedback, response = send(trajectory, goal)
            grip_feedback, grip_response = send(
                gripper, GRIPPER.Goal(command=control_msgs.msg.GripperCommand(position=0.01, max_effort=20.0)))
            (offered,) = client_node.get_publishers_info_by_topic(
                "/arm_controller/follow_joint_trajectory/_action/feedback")
    assert response.result.error_code == FJT.Result.SUCCESSFUL and response.result.error_string == "5 tolerances"
    (message,) = feedback
    assert list(message.feedback.joint_names) == names
    assert list(message.feedback.desired.positions) == [0.1, 0.2, -0.3, 0.4, 0.5]
    assert str(offered.topic_type_hash) == REFERENCE_HASHES["control_msgs/action/FollowJointTrajectory_FeedbackMessage"]
    (grip,) = grip_feedback
    assert (grip.feedback.position, grip.feedback.effort) == (0.01, 10.0)
    result = grip_response.result
    assert (result.position, result.effort, result.stalled, result.reached_goal) == (0.01, 20.0, True, False)
