"""Simulate-mode time semantics and commands, in-process: a reset while logging
keeps log time monotonic; wall-clock stamped trajectories run from their arrival; far-future
and past stamps are rejected and never latched; an empty command is rejected; efforts on
joints without a URDF effort limit are clamped to a finite default."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from youbot_dynamics.io.stamps import NS_PER_S as NS
from youbot_dynamics.model.robot import keep_joints, load_robot
from youbot_dynamics.node.commands import (DEFAULT_EFFORT_LIMIT, FUTURE_LIMIT_NS, MAX_NAMES,
                                           MAX_TRAJECTORY_POINTS, EffortCommands, InputRejected,
                                           joint_trajectory)
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene

SCENE = load_scene("arm_ptp")
ROBOT = SCENE.robot
NAMES = list(ROBOT.joint_names)
WALL_NS = 1_763_900_000 * NS          # a wall-clock time (Nov 2025), passed explicitly


def test_reset_while_logging_keeps_log_time_monotonic(tmp_path: Path) -> None:
    """After a reset node time goes on (log time never runs backwards, no /joint_states
    stamp repeats), the scene restarts (the first sample after the reset holds the initial
    q) and /diagnostics records the reset."""
    path = tmp_path / "reset.mcap"
    session = SimulationSession(SCENE, 100.0, samples_per_solve=2, mcap_path=path)
    first = [session.step() for _ in range(15)]
    session.reset()
    after = [session.step() for _ in range(15)]
    session.diagnostics(1.0)
    session.close()
    q0 = dict(first[0])["/joint_states"].position
    restart = dict(after[0])["/joint_states"]
    assert np.array_equal(restart.position, q0)
    stamps, log_times, diagnostics = [], [], []
    with AnyReader([path]) as reader:
        for connection, log_time, raw in reader.messages():
            log_times.append(log_time)
            message = reader.deserialize(raw, connection.msgtype)
            if connection.topic == "/joint_states":
                stamps.append(message.header.stamp.sec * NS + message.header.stamp.nanosec)
            elif connection.topic == "/diagnostics":
                diagnostics.append({v.key: v.value for v in message.status[0].values})
    assert log_times == sorted(log_times)
    assert stamps == [10_000_000 * k for k in range(30)]          # no stamp twice, one increment apart
    assert diagnostics[-1]["resets"] == "1" and float(diagnostics[-1]["last_reset_at"]) == pytest.approx(0.15)


def test_wall_clock_stamped_trajectory_runs_from_its_arrival() -> None:
    """A two-point trajectory stamped with the wall clock (1.76e9 s) while simulated time is
    0.1 s starts on arrival (not 1.76e9 s ahead) and reaches its last point 0.5 s later, as
    an unstamped one does."""
    def final_reference(stamp_ns: int) -> np.ndarray:
        session = SimulationSession(SCENE, 100.0, samples_per_solve=2)
        for _ in range(11):
            session.step()
        target = np.array(SCENE.q0) + 0.05
        session.trajectory(NAMES, [(250_000_000, list(target - 0.025), []), (500_000_000, list(target), [])],
                           stamp_ns, wall_ns=WALL_NS)
        trajectory = session.simulator.state.reference.trajectory
        return trajectory.evaluate(session.scene_time + 0.5)[0], trajectory.start_ns
    unstamped, start = final_reference(0)
    wall, wall_start = final_reference(WALL_NS - 20_000_000)       # sent 20 ms ago by the wall clock
    assert start == 100_000_000 and wall_start == start            # a past stamp within the timeout: now
    np.testing.assert_array_equal(wall, unstamped)
    np.testing.assert_allclose(wall, np.array(SCENE.q0) + 0.05, atol=1e-12)


@pytest.mark.parametrize(("stamp_ns", "kind"), [
    (FUTURE_LIMIT_NS + 200_000_000, "bad_timing"),     # 60 s ahead of now (0.1 s) and more
    (10**6 * NS, "bad_timing"),                         # 1e6 s
    (WALL_NS + 3600 * NS, "bad_timing"),                # an hour ahead of the wall clock
    (WALL_NS - 5 * NS, "stale"),                        # 5 s old by the wall clock, timeout 0.5 s
])
@pytest.mark.parametrize("what", ["trajectory", "command"])
def test_far_future_and_past_stamps_are_rejected_and_never_latched(stamp_ns: int, kind: str, what: str) -> None:
    session = SimulationSession(SCENE, 100.0, samples_per_solve=2)
    for _ in range(11):
        session.step()
    reference = session.simulator.state.reference
    with pytest.raises(InputRejected) as error:
        if what == "trajectory":
            session.trajectory(NAMES, [(100_000_000, list(SCENE.q0), [])], stamp_ns, wall_ns=WALL_NS)
        else:
            session.effort_command(NAMES, [0.1] * 5, stamp_ns, wall_ns=WALL_NS)
    assert error.value.kind == kind and session.counters.rejected[kind] == 1
    assert session.simulator.state.reference is reference and session.commands.received_at is None
    # a good message right after is accepted: nothing was latched
    session.effort_command(NAMES, [0.1] * 5, 0, wall_ns=WALL_NS)
    assert session.commands.active(session.t)


def test_empty_command_is_rejected_not_zero_torque() -> None:
    """An empty JointState is rejected: taken as a command, it would switch the scene
    controller off (zero torque on every joint: the arm falls 2.64 rad in 2 s)."""
    commands = EffortCommands(ROBOT, 0.5, "hold")
    with pytest.raises(InputRejected) as error:
        commands.accept([], [], 0, 1.0)
    assert error.value.kind == "empty" and commands.counters.rejected["empty"] == 1
    assert commands.torque(1.0) is None            # the scene's controller stays in charge


def test_efforts_on_continuous_joints_are_clamped_to_a_finite_limit() -> None:
    robot = keep_joints(load_robot(SCENE.urdf_path), ["wheel_joint_fl", "arm_joint_1"])
    assert np.isinf(robot.effort_limit[robot.joint_index("wheel_joint_fl")])   # the premise
    commands = EffortCommands(robot, 0.5, "hold")
    out = commands.accept(["wheel_joint_fl", "arm_joint_1"], [1e150, -1e150], 0, 1.0)
    limit_arm = robot.effort_limit[robot.joint_index("arm_joint_1")]
    assert out[robot.joint_index("wheel_joint_fl")] == DEFAULT_EFFORT_LIMIT
    assert out[robot.joint_index("arm_joint_1")] == -limit_arm and commands.counters.clamped == 1
    custom = EffortCommands(robot, 0.5, "hold", default_limit=3.0)
    assert custom.accept(["wheel_joint_fl"], [-1e150], 0, 1.0)[robot.joint_index("wheel_joint_fl")] == -3.0


def test_oversized_messages_are_rejected_in_linear_time() -> None:
    """20 000 names took 4.7 s in the quadratic duplicate check; now more than MAX_NAMES are
    refused at once, and a check at the limit is linear (no timing asserted: the counts)."""
    commands = EffortCommands(ROBOT, 0.5, "hold")
    with pytest.raises(InputRejected) as error:
        commands.accept([f"j{k}" for k in range(20_000)], [0.0] * 20_000, 0, 1.0)
    assert error.value.kind == "too_large"
    with pytest.raises(InputRejected) as error:   # at the limit: reaches the name check
        commands.accept([f"j{k}" for k in range(MAX_NAMES)], [0.0] * MAX_NAMES, 0, 1.0)
    assert error.value.kind == "unknown_joint"
    point = (0, list(SCENE.q0), [])
    with pytest.raises(InputRejected) as error:
        joint_trajectory(ROBOT, NAMES, [point] * (MAX_TRAJECTORY_POINTS + 1), 0, np.array(SCENE.q0))
    assert error.value.kind == "too_large"
    assert commands.counters.rejected["too_large"] == 1
