"""Mecanum kinematics of the youBot base and wheel odometry on SE(2): against a hand
calculation, the youBot driver's own formulas, a no-slip derivation through Pinocchio on the
URDF, the closed-form SE(2) exponential and Pinocchio's SE(2) group."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.dynamics.mobile.mecanum import (WHEEL_JOINTS, base_twist, mecanum_base_from_robot,
                                                      wheel_speeds, youbot_base)
from youbot_dynamics.dynamics.mobile.odometry import odometry_step, se2_step
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import load_robot

URDF = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
RNG = np.random.default_rng(11)
R = 0.0475  # youbot-base.cfg WheelRadius
HALF_SUM = 0.47 / 2 + 0.3 / 2  # (front-rear + left-right) / 2 of youbot-base.cfg = 0.385 m


@pytest.fixture(scope="module")
def robot():
    return load_robot(URDF, root="planar")


def test_inverse_then_forward_is_the_identity():
    base = youbot_base()
    for twist in RNG.uniform(-2.0, 2.0, size=(50, 3)):
        assert np.allclose(base_twist(base, wheel_speeds(base, twist)), twist, rtol=0, atol=1e-12)


def test_wheel_speeds_of_pure_motions_match_a_hand_calculation():
    base = youbot_base()
    # vx = 0.5 m/s: every wheel rolls forward at 0.5 / 0.0475 = 10.526315789... rad/s.
    assert np.allclose(wheel_speeds(base, [0.5, 0.0, 0.0]), [10.526315789473685] * 4, atol=1e-12)
    # vy = 0.5 m/s (to the left): fl and br turn backwards, fr and bl forwards, same magnitude.
    assert np.allclose(wheel_speeds(base, [0.0, 0.5, 0.0]),
                       [-10.526315789473685, 10.526315789473685, 10.526315789473685, -10.526315789473685],
                       atol=1e-12)
    # wz = 1 rad/s (counter-clockwise): the left wheels back, the right ones forward, each at
    # (0.235 + 0.15) / 0.0475 = 8.105263157894736 rad/s.
    assert np.allclose(wheel_speeds(base, [0.0, 0.0, 1.0]),
                       [-8.105263157894736, 8.105263157894736, -8.105263157894736, 8.105263157894736],
                       atol=1e-12)


def test_matches_the_youbot_driver_kinematics():
    """youbot_driver FourSwedishWheelOmniBaseKinematic, motors in the driver's directions
    (left wheels counted backwards): w = (-X + Y + T, X + Y + T, -X - Y + T, X - Y + T) with
    X = vx / r, Y = vy / r, T = wz (L + W) / (2 r); back: vx = (-w1 + w2 - w3 + w4) r / 4,
    vy = (w1 + w2 - w3 - w4) r / 4, wz = (w1 + w2 + w3 + w4) r / (4 (L + W) / 2)."""
    base = youbot_base()
    driver_sign = np.array([-1.0, 1.0, -1.0, 1.0])
    for vx, vy, wz in RNG.uniform(-1.0, 1.0, size=(20, 3)):
        x, y, t = vx / R, vy / R, wz * HALF_SUM / R
        driver = np.array([-x + y + t, x + y + t, -x - y + t, x - y + t])
        assert np.allclose(driver_sign * wheel_speeds(base, [vx, vy, wz]), driver, rtol=0, atol=1e-12)
        w1, w2, w3, w4 = driver
        back = [(-w1 + w2 - w3 + w4) * R / 4, (w1 + w2 - w3 - w4) * R / 4,
                (w1 + w2 + w3 + w4) * R / 4 / HALF_SUM]
        assert np.allclose(base_twist(base, driver_sign * driver), back, rtol=0, atol=1e-12)


def test_least_squares_forward_kinematics_of_inconsistent_wheel_speeds():
    """A slipping wheel: H^+ u is the twist that minimises |H V - u| (normal equations)."""
    base = youbot_base()
    speeds = np.array([3.0, 1.0, -2.0, 0.5])
    twist = base_twist(base, speeds)
    h = base.jacobian
    assert np.allclose(h.T @ (h @ twist - speeds), 0.0, atol=1e-12)
    assert np.linalg.norm(h @ twist - speeds) > 1.0  # the speeds agree with no single twist


def no_slip_matrix_through_pinocchio(robot) -> np.ndarray:
    """H derived on the URDF with Pinocchio alone: the velocity of each wheel's contact point
    (radius R below the hub, on the wheel link) for each unit base twist and for a unit wheel
    speed; the wheel speed that cancels its component across the contact roller."""
    model, data = robot.model, robot.model.createData()
    q = pin.neutral(model)
    normals = {"wheel_joint_fl": (-1.0, 1.0), "wheel_joint_fr": (1.0, 1.0),  # z x roller axis,
               "wheel_joint_bl": (1.0, 1.0), "wheel_joint_br": (-1.0, 1.0)}  # fl/br along (1, 1)

    def contact_velocity(v: np.ndarray, joint: str) -> np.ndarray:
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        frame = model.getFrameId(joint.replace("joint", "link"))
        twist = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
        return (twist.linear + np.cross(twist.angular, [0.0, 0.0, -R]))[:2]

    rows = []
    for joint in WHEEL_JOINTS:
        n = np.array(normals[joint]) / math.sqrt(2.0)
        spin = np.zeros(model.nv)
        spin[model.joints[model.getJointId(joint)].idx_v] = 1.0
        per_speed = n @ contact_velocity(spin, joint)
        row = []
        for k in range(3):  # planar root: v = (vx, vy, wz, joints...)
            unit = np.zeros(model.nv)
            unit[k] = 1.0
            row.append(-(n @ contact_velocity(unit, joint)) / per_speed)
        rows.append(row)
    return np.array(rows)


def test_urdf_wheel_joints_give_the_same_matrix(robot):
    assert set(WHEEL_JOINTS) <= set(robot.joint_names)
    from_urdf = mecanum_base_from_robot(robot)
    assert np.allclose(from_urdf.positions, [[0.228, 0.158], [0.228, -0.158], [-0.228, 0.158], [-0.228, -0.158]],
                       atol=1e-15)
    assert np.allclose(from_urdf.drive_directions, [[1.0, 0.0]] * 4, atol=1e-15)  # axis +y: u > 0 rolls forward
    reference = no_slip_matrix_through_pinocchio(robot)
    assert np.allclose(from_urdf.jacobian, reference, rtol=0, atol=1e-12)
    assert np.allclose(youbot_base(2 * 0.228, 2 * 0.158).jacobian, reference, rtol=0, atol=1e-12)
    # The driver's figures: lx + ly = 0.385 m against the URDF's 0.386 m; only wz's column differs.
    difference = youbot_base().jacobian - reference
    assert np.allclose(difference[:, :2], 0.0, atol=1e-12)
    assert np.allclose(np.abs(difference[:, 2]), 0.001 / R, atol=1e-12)


def test_bad_inputs_name_what_was_wrong(robot):
    with pytest.raises(UserInputError, match="3 values"):
        wheel_speeds(youbot_base(), [1.0, 2.0])
    with pytest.raises(UserInputError, match="4 values"):
        base_twist(youbot_base(), [1.0, 2.0, 3.0])
    with pytest.raises(UserInputError, match="wheel_joint_xx"):
        mecanum_base_from_robot(robot, names=("wheel_joint_fl", "wheel_joint_xx"))
    with pytest.raises(UserInputError, match="radius"):
        youbot_base(radius=0.0)


def closed_form_pose(twist, t):
    """Pose at t from the origin at constant body twist: x = (vx sin wt - vy (1 - cos wt)) / w,
    y = (vx (1 - cos wt) + vy sin wt) / w, theta = w t."""
    vx, vy, w = twist
    return np.array([(vx * math.sin(w * t) - vy * (1 - math.cos(w * t))) / w,
                     (vx * (1 - math.cos(w * t)) + vy * math.sin(w * t)) / w, w * t])


def test_odometry_of_a_constant_twist_matches_the_closed_form_exponential():
    base, twist = youbot_base(), np.array([0.4, -0.15, 0.3])
    speeds = wheel_speeds(base, twist)
    one_step = odometry_step(base, np.zeros(3), speeds, 10.0)
    assert np.allclose(one_step, closed_form_pose(twist, 10.0), rtol=0, atol=1e-9)
    pose = np.zeros(3)
    for _ in range(1000):
        pose = odometry_step(base, pose, speeds, 0.01)
    assert np.allclose(pose, one_step, rtol=0, atol=1e-9)  # measured 4.3e-14 (1000 steps of rounding)
    # Pinocchio's SE(2) group (x, y, cos, sin), an independent implementation.
    q = pin.liegroups.SE2().integrate(np.array([0.0, 0.0, 1.0, 0.0]), twist * 10.0)
    assert np.allclose([q[0], q[1], math.atan2(q[3], q[2])],
                       [one_step[0], one_step[1], math.remainder(one_step[2], 2 * math.pi)], atol=1e-12)
    # Euler on the same steps misses the circle: the test above can fail.
    euler = np.zeros(3)
    for _ in range(1000):
        c, s = math.cos(euler[2]), math.sin(euler[2])
        euler = euler + 0.01 * np.array([c * twist[0] - s * twist[1], s * twist[0] + c * twist[1], twist[2]])
    assert np.linalg.norm(euler[:2] - one_step[:2]) > 1e-3


def test_odometry_from_a_start_pose_and_in_pure_translation():
    start = np.array([1.0, -2.0, 0.7])
    c, s = math.cos(0.7), math.sin(0.7)
    moved = se2_step(start, [0.3, 0.2, 0.0], 5.0)  # no rotation: a straight line in the body axes
    assert np.allclose(moved, [1.0 + 5 * (0.3 * c - 0.2 * s), -2.0 + 5 * (0.3 * s + 0.2 * c), 0.7], atol=1e-14)
    twist = np.array([0.1, 0.3, -0.8])
    local = closed_form_pose(twist, 2.5)
    assert np.allclose(se2_step(start, twist, 2.5),
                       [1.0 + c * local[0] - s * local[1], -2.0 + s * local[0] + c * local[1], 0.7 - 2.0],
                       rtol=0, atol=1e-12)
    with pytest.raises(UserInputError, match="dt"):
        odometry_step(youbot_base(), start, np.zeros(4), -0.1)
