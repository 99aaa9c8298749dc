"""Input checks of the node without ROS: effort commands, joint samples, trajectories; the
inverse-mode acceleration estimate; link frames against the URDF tree and the screw
kinematics."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builtin_interfaces.msg import Duration, Time

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.stamps import NS_PER_S as NS, stamp_ns_of
from youbot_dynamics.model.lie import exp_so3, matrix_from_quaternion
from youbot_dynamics.model.screws import fkin_space, screw_chain
from youbot_dynamics.node.commands import (EffortCommands, InputCounters, InputRejected,
                                           JointSample, follow, joint_sample, joint_trajectory)
from youbot_dynamics.node.frames import LinkFrames
from youbot_dynamics.node.inverse import AccelerationEstimator
from youbot_dynamics.node.inverse_session import InverseSession
from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.sim.simulator import Simulator


@pytest.fixture(scope="module")
def simulator() -> Simulator:
    return Simulator(load_scene("arm_ptp"))


@pytest.fixture()
def commands(simulator: Simulator) -> EffortCommands:
    return EffortCommands(simulator.robot, timeout=0.5, on_timeout="zero_torque")


def test_effort_command_by_name_is_put_in_joint_order(commands: EffortCommands, simulator: Simulator) -> None:
    names = list(simulator.joint_names)
    out = commands.accept(names[::-1], [0.5, 0.4, 0.3, 0.2, 0.1], stamp_ns=0, now=1.0)
    assert out.tolist() == [0.1, 0.2, 0.3, 0.4, 0.5]
    # a partial command changes only the named joint
    out = commands.accept([names[2]], [-0.7], stamp_ns=0, now=1.1)
    assert out.tolist() == [0.1, 0.2, -0.7, 0.4, 0.5]
    assert commands.counters.accepted == 2 and sum(commands.counters.rejected.values()) == 0


@pytest.mark.parametrize(("names", "efforts", "stamp", "kind"), [
    (["arm_joint_1"], [math.nan], 0, "non_finite"),
    (["arm_joint_1"], [math.inf], 0, "non_finite"),
    (["arm_joint_1", "arm_joint_2"], [1.0], 0, "length_mismatch"),
    (["arm_joint_9"], [1.0], 0, "unknown_joint"),
    (["wheel_joint_fl"], [1.0], 0, "unknown_joint"),   # in the URDF but locked in the scene
    (["arm_joint_1", "arm_joint_1"], [1.0, 2.0], 0, "duplicate_joint"),
    (["arm_joint_1"], [1.0], 3 * NS, "stale"),          # stamped 7 s before now, timeout 0.5 s
    (["arm_joint_1"], [1.0], -1, "bad_timing"),          # no builtin_interfaces/Time is negative
    (["arm_joint_1"], [1.0], 2**31 * NS, "bad_timing"),  # sec 2^31 (nanosec >= 1e9 carried over)
])
def test_bad_effort_commands_are_rejected_counted_and_change_nothing(
        commands: EffortCommands, names, efforts, stamp, kind) -> None:
    commands.accept(["arm_joint_3"], [0.25], stamp_ns=0, now=10.0)
    with pytest.raises(InputRejected) as error:
        commands.accept(names, efforts, stamp_ns=stamp, now=10.0)
    assert error.value.kind == kind
    assert commands.counters.rejected[kind] == 1
    assert commands.torque(10.0).tolist() == [0.0, 0.0, 0.25, 0.0, 0.0]


@pytest.mark.parametrize(("sec", "kind"), [(5, "bad_timing"), (9, "bad_timing"), (5, "stale")])
def test_a_nanosec_of_1e9_or_more_is_bad_timing_not_carried(commands: EffortCommands, sec, kind) -> None:
    """builtin_interfaces/Time wants nanosec < 1e9: sec 5 with nanosec 1.5e9 is no stamp (carried
    over it would read as 6.5 s, stale at now 10 s; sec 9 as 10.5 s, taken); sec 5 with
    nanosec 0.5e9 is a valid stamp 5.5 s, stale."""
    nanosec = 500_000_000 if kind == "stale" else 1_500_000_000
    with pytest.raises(InputRejected) as error:
        commands.accept(["arm_joint_1"], [1.0], stamp_ns=stamp_ns_of(Time(sec=sec, nanosec=nanosec)), now=10.0)
    assert error.value.kind == kind
    assert commands.counters.rejected[kind] == 1


def test_efforts_beyond_the_urdf_limit_are_clamped_and_counted(commands: EffortCommands, simulator: Simulator) -> None:
    limit = np.asarray(simulator.robot.effort_limit)
    out = commands.accept(["arm_joint_1", "arm_joint_4"], [1e3, -1e3], stamp_ns=0, now=0.0)
    assert out[0] == limit[0] and out[3] == -limit[3]
    assert commands.counters.clamped == 1


@pytest.mark.parametrize(("on_timeout", "after"), [("zero_torque", [0.0] * 5), ("hold", None)])
def test_timeout_action(simulator: Simulator, on_timeout: str, after) -> None:
    commands = EffortCommands(simulator.robot, timeout=0.5, on_timeout=on_timeout)
    assert commands.torque(0.0) is None            # nothing received: the scene's controller
    commands.accept(["arm_joint_2"], [1.0], stamp_ns=0, now=1.0)
    assert commands.torque(1.5).tolist() == [0.0, 1.0, 0.0, 0.0, 0.0]
    result = commands.torque(1.51)
    assert (result is None and after is None) or result.tolist() == after


def test_joint_sample_reorders_ignores_locked_joints_and_rejects_missing(simulator: Simulator) -> None:
    robot = simulator.robot
    known = [j.name for j in robot.tree]
    names = ["wheel_joint_fl", *robot.joint_names[::-1]]
    sample = joint_sample(robot, known, names, [9.0, 5, 4, 3, 2, 1], [9.0, 50, 40, 30, 20, 10], stamp_ns=NS // 10)
    assert sample.q.tolist() == [1, 2, 3, 4, 5] and sample.v.tolist() == [10, 20, 30, 40, 50]
    with pytest.raises(InputRejected, match="missing_joint"):
        joint_sample(robot, known, robot.joint_names[:4], [0.0] * 4, [0.0] * 4, stamp_ns=NS // 10)
    with pytest.raises(InputRejected, match="length_mismatch"):
        joint_sample(robot, known, robot.joint_names, [0.0] * 5, [0.0] * 4, stamp_ns=NS // 10)


def test_trajectory_is_followed_through_its_points(simulator: Simulator) -> None:
    robot, q0 = simulator.robot, simulator.scene.q0
    target = q0 + np.array([0.3, -0.2, 0.1, 0.0, 0.0])
    points = [(500_000_000, target[:3], ()), (1_000_000_000, target[:3] + 0.1, ())]
    trajectory = joint_trajectory(robot, robot.joint_names[:3], points, start_ns=2 * NS, q_now=q0)
    q, v, a = trajectory.evaluate(2.5)
    assert np.allclose(q, target) and np.all(np.isfinite(a))
    assert np.allclose(trajectory.evaluate(2.0)[0], q0)          # starts where the robot is
    assert np.allclose(trajectory.evaluate(9.0)[0][:3], target[:3] + 0.1) and not trajectory.evaluate(9.0)[1].any()
    with pytest.raises(InputRejected, match="bad_timing"):
        joint_trajectory(robot, robot.joint_names[:1], [(NS // 2, [3.0], ()), (NS // 2, [3.1], ())], 0, q0)
    with pytest.raises(InputRejected, match="bad_timing"):
        joint_trajectory(robot, robot.joint_names[:1], [(-1, [3.0], ())], 0, q0)
    with pytest.raises(InputRejected, match="bad_timing"):  # a Duration with nanosec 1.5e9 is no time
        joint_trajectory(robot, robot.joint_names[:1],
                         [(stamp_ns_of(Duration(sec=0, nanosec=1_500_000_000)), [3.0], ())], 0, q0)
    with pytest.raises(InputRejected, match="out_of_limits"):
        joint_trajectory(robot, robot.joint_names[:1], [(NS // 2, [100.0], ())], 0, q0)
    # a joint not named holds where it is, even a hair beyond its stop (a finger resting on
    # it at -3e-23 m in gripping): the command is not blamed for it
    beyond = q0.copy()
    beyond[4] = robot.lower[4] - 1e-12
    held = joint_trajectory(robot, robot.joint_names[:1], [(NS // 2, [q0[0] + 0.1], ())], 0, beyond)
    assert held.evaluate(1.0)[0][4] == beyond[4]
    with pytest.raises(InputRejected, match=f"out_of_limits.*{robot.joint_names[4]}"):
        joint_trajectory(robot, robot.joint_names[4:], [(NS // 2, [beyond[4]], ())], 0, q0)
    scene_free = Simulator(load_scene("arm_swing"))
    with pytest.raises(InputRejected, match="no_controller"):
        follow(scene_free, trajectory)


@pytest.mark.parametrize("start_ns", [0, 1_700_000_000 * NS, 2**31 * NS + NS - 1])
def test_trajectory_times_are_relative_integer_nanoseconds(simulator: Simulator, start_ns: int) -> None:
    """Stamps of any magnitude (up to the largest builtin_interfaces/Time): a one-point
    trajectory holds its point from the start (at a wall-clock stamp of 1.7e9 s, float
    seconds would lose a 1e-9 s spacing to rounding and CubicSpline would raise ValueError);
    points 1 ns apart stay distinct; the reference matches the same trajectory started at 0."""
    robot, q0 = simulator.robot, simulator.scene.q0
    single = joint_trajectory(robot, robot.joint_names[:1], [(0, [0.5], ())], start_ns, q0)
    assert single.evaluate(start_ns / NS + 1.0)[0][0] == 0.5
    points = [(1, [0.4], ()), (2, [0.41], ()), (250_000_000, [0.6], ())]
    moved = joint_trajectory(robot, robot.joint_names[:1], points, start_ns, q0)
    reference = joint_trajectory(robot, robot.joint_names[:1], points, 0, q0)
    assert moved.offsets_ns == reference.offsets_ns == (0, 1, 2, 250_000_000)
    t = start_ns / NS + 0.125                  # float seconds: ulp 2.4e-7 s near 1.7e9 s, 4.8e-7 near 2.1e9 s
    relative = (round(t * NS) - start_ns) / NS
    assert abs(relative - 0.125) <= 1e-6       # measured 6.4e-8 s at 1.7e9 s; bound 1e-6 s
    for got, want in zip(moved.evaluate(t), reference.evaluate(relative)):
        np.testing.assert_array_equal(got, want)


def test_central_difference_is_the_window_mean_of_the_acceleration() -> None:
    """v(t) = sin(t): a_hat(t) = cos(t) sin(h)/h exactly (the mean of cos over [t-h, t+h]),
    and its error stays below the variation of a over the window (the bound the node uses)."""
    estimator, h = AccelerationEstimator(), 0.01
    for k, t in enumerate(np.arange(0.0, 1.0, h)):
        result = estimator.push(JointSample(round(t * NS), np.zeros(1), np.array([math.sin(t)])))
        if result is None:
            assert k < 2
            continue
        middle, a_hat = result
        assert middle.t == pytest.approx(t - h)
        assert a_hat[0] == pytest.approx(math.cos(middle.t) * math.sin(h) / h, rel=1e-9)
        window = np.linspace(middle.t - h, middle.t + h, 41)
        assert abs(a_hat[0] - math.cos(middle.t)) <= np.max(np.abs(np.cos(window) - math.cos(middle.t)))
    # a sample back in time restarts the stencil (a replay that restarts): no estimate until two more
    assert estimator.push(JointSample(NS // 2, np.zeros(1), np.zeros(1))) is None
    assert len(estimator.samples) == 1 and estimator.restarts["backwards"] == 1


@pytest.mark.parametrize("scene", ["arm_ptp", "gripping"])
def test_link_frames_match_the_urdf_tree_and_the_screw_kinematics(scene: str) -> None:
    """The one kinematics pass (Pinocchio) against references that do not use Pinocchio:
    each moving link against its URDF joint origin times the joint motion (rotation exp(axis
    q) or translation axis q), each end effector against the product of exponentials of
    model/screws.py. Measured worst differences 6.7e-16 (arm) and 1.3e-15 (two youBots); bound
    1e-12."""
    robot = load_scene(scene).robot
    frames = LinkFrames(robot)
    q = np.random.default_rng(1).uniform(robot.lower, robot.upper)
    sample = frames.at(q)
    assert {t.child for t in (*sample.moving, *frames.static)} == set(robot.link_names) - {robot.root_link}
    joints = {j.child: j for j in robot.tree}
    for t in sample.moving:
        joint = joints[t.child]
        assert t.parent == joint.parent
        motion, value = np.eye(4), q[robot.joint_index(joint.name)]
        if joint.type == "prismatic":
            motion[:3, 3] = joint.axis * value
        else:
            motion[:3, :3] = exp_so3(joint.axis * value)
        expected = joint.origin @ motion
        np.testing.assert_allclose(t.translation, expected[:3, 3], rtol=0, atol=1e-12)
        np.testing.assert_allclose(matrix_from_quaternion(t.quaternion_xyzw), expected[:3, :3], rtol=0, atol=1e-12)
        assert t.quaternion_xyzw[3] >= 0.0
    assert len(sample.ee_poses) == len(frames.ee_links) == (2 if scene == "gripping" else 1)
    for link, (position, quaternion) in zip((frames.ee_link, *frames.ee_links), (sample.ee_pose, *sample.ee_poses)):
        expected = fkin_space(screw_chain(robot, link), q)
        np.testing.assert_allclose(position, expected[:3, 3], rtol=0, atol=1e-12)
        np.testing.assert_allclose(matrix_from_quaternion(quaternion), expected[:3, :3], rtol=0, atol=1e-12)


def test_link_frames_name_an_unknown_end_effector() -> None:
    robot = load_scene("arm_ptp").robot
    with pytest.raises(UserInputError, match="unknown frame 'palm'.*links: base_footprint"):
        LinkFrames(robot, "palm")


def test_counters_flatten_for_diagnostics() -> None:
    counters = InputCounters()
    counters.reject(InputRejected("stale", "old"))
    values = counters.as_values()
    assert values["rejected.stale"] == 1 and values["rejected.total"] == 1 and values["accepted"] == 0


@pytest.mark.parametrize("base_ns", [0, 1_700_000_000 * NS + 123_456_789])
def test_a_rejected_joint_state_breaks_the_difference_stencil(base_ns: int) -> None:
    """Inverse mode: samples at base + 10, 20, 30, ... ms with v = 10 (t - base) (a = 10
    rad/s^2) and a NaN sample at 25 ms. No torque is computed across the rejected sample
    (none at 20 or 30 ms): the first after it is at 40 ms (three good samples 30, 40, 50
    ms). Torques carry their sample's stamp exactly and equal RNEA at
    a = 10, also at a wall-clock base (1.7e9 s; float seconds there lose 2.4e-7 s, a 1e-5
    relative error in a): tolerance 1e-12, measured difference 0.0."""
    scene = load_scene("arm_ptp")
    session = InverseSession(scene)
    names, q0 = list(session.robot.joint_names), scene.q0
    published = []
    for stamp_ms in (10, 20, 25, 30, 40, 50, 60):
        position = [math.nan] * 5 if stamp_ms == 25 else list(q0)
        try:
            outputs = session.joint_state(names, position, [0.01 * stamp_ms] * 5, base_ns + stamp_ms * 1_000_000)
        except InputRejected as error:
            assert error.kind == "non_finite" and stamp_ms == 25
            continue
        published += [message for topic, message in outputs if topic == "/computed_torques"]
    stamps = [m.header.stamp.sec * NS + m.header.stamp.nanosec - base_ns for m in published]
    assert stamps == [40_000_000, 50_000_000]
    for stamp, message in zip(stamps, published):
        expected = session.dynamics.torque(q0, np.full(5, 10.0 * stamp / NS), np.full(5, 10.0))
        np.testing.assert_allclose(message.effort, expected, rtol=1e-12, atol=1e-12)
    assert session.counters.rejected["non_finite"] == 1 and session.counters.accepted == 6
