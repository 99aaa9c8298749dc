"""The moving base's limits through the ROS-free session: a /cmd_vel command is reached
within the scene's a_max (kinematic and dynamic), and wheel slip shows in /diagnostics."""
from __future__ import annotations

import numpy as np
import yaml

from youbot_dynamics.dynamics.mobile.ramp import DEFAULT_A_MAX
from youbot_dynamics.node.mobile_base import SLIP_WARN
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import Scene, load_scene, scene_dir

RATE = 100.0


def spin_arm(mu: float) -> Scene:
    """base_spin_arm (dynamic base, no path: the default a_max) on a floor of Coulomb ``mu``."""
    data = yaml.safe_load((scene_dir() / "base_spin_arm.yaml").read_text())
    data["base"]["floor"]["mu"] = mu
    return Scene.from_dict(data, source="base_spin_arm")


def drive(session: SimulationSession, linear, angular, samples: int) -> tuple[np.ndarray, list]:
    """The true twists (vx, vy, wz) of ``samples`` samples under a /cmd_vel stream at the
    publish rate, and the /diagnostics status after each 0.5 s."""
    twists, statuses = [], []
    for k in range(samples):
        session.base_command(linear, angular)
        twist = dict(session.step())["/base_pose_ground_truth"].twist.twist
        twists.append((twist.linear.x, twist.linear.y, twist.angular.z))
        if k % 50 == 49:
            statuses.append(dict(session.diagnostics(1.0))["/diagnostics"].status[0])
    return np.array(twists), statuses


def slip_of(status) -> float:
    return float(next(kv.value for kv in status.values if kv.key == "base.slip"))


def test_kinematic_base_reaches_a_command_within_a_max():
    """base_square's a_max is 1 m/s^2 and 1 rad/s^2: a 5 m/s, 10 rad/s command (the largest
    /cmd_vel takes) changes the twist by at most a_max / rate per sample, on a straight line
    in (vx, vy, wz) (the slower axis paced by the faster), and reaches it after 10 s."""
    with SimulationSession(load_scene(scene_dir() / "base_square.yaml"), RATE, samples_per_solve=5,
                           command_timeout=0.3) as session:
        twists, statuses = drive(session, (5.0, 0.0, 0.0), (0.0, 0.0, 10.0), 150)
    steps = np.diff(twists, axis=0)
    assert np.all(np.abs(steps) <= np.array([1.0, 1.0, 1.0]) / RATE + 1e-12)
    assert np.abs(steps[:, 2]).max() >= 0.99 / RATE  # the turn rate paces the ramp at its limit
    np.testing.assert_allclose(twists[:, 0], twists[:, 2] / 2.0, atol=1e-12)  # direction kept
    assert 1.3 <= twists[-1, 2] <= 1.5  # 1.49 s of 1 rad/s^2 from the first block (0 to 0.05 s)
    assert all(status.level == 0 and slip_of(status) < 1e-12 for status in statuses)  # rolls, no slip


def test_dynamic_base_accelerates_within_a_max_without_slip():
    """base_spin_arm, mu 0.5: a 5 m/s command is reached at the default a_max (2.5 m/s^2;
    the floor would allow mu g = 4.9): the true acceleration stays within the PI's overshoot
    (measured 2.69 m/s^2), the rollers creep (measured 0.023 m/s), /diagnostics stays OK."""
    with SimulationSession(spin_arm(0.5), RATE, samples_per_solve=5, command_timeout=0.3) as session:
        twists, statuses = drive(session, (5.0, 0.0, 0.0), (0.0, 0.0, 0.0), 150)
    acceleration = np.abs(np.diff(twists[:, 0])) * RATE
    assert acceleration.max() <= 1.1 * DEFAULT_A_MAX[0]
    assert 3.3 <= twists[-1, 0] <= 3.8  # still accelerating at 2.5 m/s^2 after 1.5 s
    assert all(status.level == 0 and 0.0 < slip_of(status) < SLIP_WARN for status in statuses)


def test_wheel_slip_is_reported_in_diagnostics():
    """On a floor of mu 0.05 the base can accelerate at 0.49 m/s^2 at most, the wheels at
    2.5: they spin ahead of the base; /odom's twist is the wheels' and /diagnostics warns
    with the slip at a hub (the odometry's speed beyond the truth's, about 0.5 m/s)."""
    with SimulationSession(spin_arm(0.05), RATE, samples_per_solve=5, command_timeout=0.3) as session:
        twists, statuses = drive(session, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0), 100)
    assert np.abs(np.diff(twists[:, 0])).max() * RATE <= 0.05 * 9.81 * 1.1
    assert [status.level for status in statuses] == [1, 1]
    assert all(slip_of(status) > 0.3 for status in statuses)
    assert "slip" in statuses[-1].message
