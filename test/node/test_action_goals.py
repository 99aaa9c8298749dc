"""The ROS-free logic behind the node's controller interfaces: FollowJointTrajectory goals
(result codes, JTC's tolerance rules), per-group references, forward commands."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.controller_groups import GroupedTrajectory, Hold, Ramp, group_joints
from youbot_dynamics.node.forward_commands import forward_command
from youbot_dynamics.node.gripper_goal import GripperGoal, finger_pairs
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.node.trajectory_goal import (GOAL_TOLERANCE_VIOLATED, INVALID_GOAL, INVALID_JOINTS,
                                                  OLD_HEADER_TIMESTAMP, SUCCESSFUL, GoalRejected, TrajectoryGoal,
                                                  resolve_tolerances)
from youbot_dynamics.scene.schema import load_scene

ARM = tuple(f"arm_joint_{k}" for k in range(1, 6))
S = 1_000_000_000


@pytest.fixture(scope="module")
def scene():
    return load_scene("arm_ptp")


def session_at(scene, seconds: float) -> SimulationSession:
    session = SimulationSession(scene, 100.0)
    for _ in range(round(seconds * 100) + 1):
        session.step()
    return session


def start(session, names, points, stamp_ns=0, goal=(), goal_time_ns=0):
    return TrajectoryGoal.start(session, "arm_controller", ARM, names, points, stamp_ns, [], goal, goal_time_ns)


def test_tolerances_follow_jtc() -> None:
    """0 keeps the default, -1 switches the check off (0), a positive value replaces it;
    another negative value or a foreign joint is INVALID_GOAL."""
    defaults = np.full((2, 3), 0.5)
    got = resolve_tolerances(("a", "b"), defaults, [("b", 0.0, -1.0, 0.2)], "goal_tolerance")
    np.testing.assert_array_equal(got, [[0.5, 0.5, 0.5], [0.5, 0.0, 0.2]])
    for given in ([("a", -0.5, 0, 0)], [("c", 0.1, 0, 0)], [("a", float("nan"), 0, 0)]):
        with pytest.raises(GoalRejected) as error:
            resolve_tolerances(("a", "b"), defaults, given, "goal_tolerance")
        assert error.value.code == INVALID_GOAL


def test_goals_that_cannot_run_carry_jtc_codes(scene) -> None:
    session = session_at(scene, 1.0)
    q = list(session.snapshot.q)
    cases = [(["arm_joint_1", "wrist"], [(S, [3.0, 0.0], [])], 0, INVALID_JOINTS),
             (list(ARM[:3]), [(S, q[:3], [])], 0, INVALID_JOINTS),
             (list(ARM) + ["arm_joint_1"], [(S, q + [3.0], [])], 0, INVALID_JOINTS),
             (list(ARM), [(S, [9.0] + q[1:], [])], 0, INVALID_GOAL),             # beyond joint 1's limit
             (list(ARM), [], 0, INVALID_GOAL),
             (list(ARM), [(S // 2, q, [])], S // 10, OLD_HEADER_TIMESTAMP)]      # ends at 0.6 s, now 1.0 s
    for names, points, stamp, code in cases:
        with pytest.raises(GoalRejected) as error:
            start(session, names, points, stamp)
        assert error.value.code == code, (names, str(error.value))
    start(session, list(ARM), [(S // 2, q, [])], 9 * S // 10)   # ends at 1.4 s: runs


def test_goal_tolerance_violated_after_goal_time(scene) -> None:
    """arm_ptp's Stribeck static friction (0.4 N m) holds joint 3 about 0.09 rad short under
    computed torque without integral action: a 0.01 rad goal tolerance is not met, and the goal
    aborts once the goal time (0.5 s) after the trajectory's end has passed, not before; a
    0.15 rad tolerance is met, SUCCESSFUL."""
    outcomes = {}
    for tolerance in (0.01, 0.15):
        session = session_at(scene, 0.0)
        target = session.snapshot.q + np.array([0.3, 0.2, -0.2, 0.2, 0.3])
        goal = start(session, list(ARM)[::-1], [(S, target[::-1].tolist(), [])],
                     goal=[(n, tolerance, 0.0, 0.0) for n in ARM], goal_time_ns=S // 2)
        for _ in range(300):
            session.step()
            feedback, outcome = goal.update()
            if outcome:
                break
        outcomes[tolerance] = (outcome, session.t, np.abs(feedback[2][0]))
    outcome, t, error = outcomes[0.01]
    assert outcome.code == GOAL_TOLERANCE_VIOLATED and outcome.status == "aborted"
    assert t == pytest.approx(1.51, abs=1e-9) and error.max() > 0.01 and "arm_joint_3" in outcome.message
    outcome, t, error = outcomes[0.15]
    assert outcome.code == SUCCESSFUL and t >= 1.0 and error.max() <= 0.15


def test_grouped_trajectory_keeps_each_group_on_its_own() -> None:
    """Joints of no group hold; each group's columns come from its own trajectory."""
    ramp = Ramp(np.zeros(4), np.array([1.0, 2.0, 3.0, 4.0]), 1.0, np.full(4, -1.0), np.array([1.0, 1.0, 2.0, 1.0]))
    grouped = GroupedTrajectory(np.array([9.0, 9.0, 9.0, 9.0]),
                                (("a", np.array([0]), Hold(np.arange(4.0))), ("b", np.array([2, 3]), ramp)))
    q, v, a = grouped.evaluate(1.4)
    np.testing.assert_allclose(q, [0.0, 9.0, 1.2, 1.0])         # joint 3 stops at its limit
    np.testing.assert_allclose(v, [0.0, 0.0, 3.0, 0.0])
    np.testing.assert_array_equal(a, 0.0)


def test_group_joints_by_pattern_or_parameter(scene) -> None:
    robot = scene.robot
    assert group_joints(robot, "arm_controller", "") == ARM
    assert group_joints(robot, "gripper_controller", "") == ()          # arm_ptp locks the fingers
    assert group_joints(robot, "arm_controller", "arm_joint_2, arm_joint_1") == ("arm_joint_2", "arm_joint_1")
    with pytest.raises(Exception, match="gripper_finger_joint_l"):
        group_joints(robot, "gripper_controller", "gripper_finger_joint_l")
    gripping = load_scene("gripping")          # two youBots: the first one's joints
    fingers = group_joints(gripping.robot, "gripper_controller", "")
    assert fingers == ("yb1_gripper_finger_joint_l", "yb1_gripper_finger_joint_r")
    assert group_joints(gripping.robot, "arm_controller", "") == tuple(f"yb1_{name}" for name in ARM)
    assert finger_pairs(gripping, ["yb1_gripper_finger_link_l", "yb1_gripper_finger_link_r"]) == {
        "yb1_pad_l/sphere", "yb1_pad_r/sphere"}


def test_forward_commands_are_checked_and_counted(scene) -> None:
    session = session_at(scene, 0.0)
    q = session.snapshot.q
    for data, kind in (([1.0] * 4, "length_mismatch"), ([float("inf")] + list(q[1:]), "non_finite"),
                       ([9.0] + list(q[1:]), "out_of_limits")):
        with pytest.raises(InputRejected) as error:
            forward_command(session, "arm_controller", ARM, data, "position")
        assert error.value.kind == kind and session.counters.rejected[kind] == 1
    forward_command(session, "arm_controller", ARM, [0.1, 0, 0, 0, 0], "velocity")
    t0 = session.scene_time
    for _ in range(50):
        session.step()
    q_d, v_d, _ = session.simulator.state.reference.at(session.scene_time)
    assert session.counters.accepted == 1
    assert q_d[0] == pytest.approx(q[0] + 0.1 * (session.scene_time - t0)) and v_d[0] == 0.1
    np.testing.assert_allclose(q_d[1:], q[1:])


def test_gripper_goal_caps_the_force_and_stalls_on_the_sphere() -> None:
    """grasp: the scene's servo presses each pad with kp * 1 mm = 1.5 N; a goal 3 mm into
    the sphere with max_effort 1 N leaves each pad at exactly 1 N (the cap, not the URDF's
    10 N), blocked by the sphere: stalled after stall_timeout (0.3 s) of contact at rest, not
    reached; without allow_stalling it aborts. The sphere is held: 2 mu F = 0.6 N > m g = 0.449 N."""
    session = SimulationSession(load_scene("grasp"), 100.0)
    for _ in range(21):
        session.step()
    np.testing.assert_allclose(session.snapshot.tau, 1500.0 * 0.001, rtol=1e-5)
    joints = group_joints(session.robot, "gripper_controller", "pad_l_joint,pad_r_joint")
    goal = GripperGoal.start(session, "gripper_controller", joints, 0.003, 1.0, 0.0005, 0.3, False)
    t0 = session.t
    for _ in range(200):
        session.step()
        state, status = goal.update()
        if status:
            break
    assert status == "aborted" and state.stalled and not state.reached_goal
    assert session.t - t0 >= 0.3 and state.effort == 1.0
    np.testing.assert_array_equal(np.abs(session.snapshot.tau), 1.0)
    assert abs(session.snapshot.bodies["sphere"][2, 3]) < 1e-4
