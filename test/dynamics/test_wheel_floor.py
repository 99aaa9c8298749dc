"""Wheel-floor pieces of the youBot base: normal loads against hand cases and the equilibrium
equations, the centre of mass through Pinocchio, the roller friction law against its hand
formula and the kinematics (pure rolling slips nowhere)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.dynamics.mobile.mecanum import mecanum_base_from_robot, wheel_speeds, youbot_base
from youbot_dynamics.dynamics.mobile.wheel_floor import (TipOverError, centre_of_mass_in_base,
                                                         contact_slip_velocities, roller_forces,
                                                         roller_friction, support_loads,
                                                         wheel_normal_forces, wheel_spin_torques)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import load_robot

URDF = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
BASE = youbot_base()  # lx = 0.235, ly = 0.15 m; wheels fl, fr, bl, br
LX, LY = 0.235, 0.15
MASS, G = 30.0, 9.81
W = MASS * G
RNG = np.random.default_rng(5)


def equilibrium_residual(loads, centre):
    """(sum N - W, sum N x - W x_c, sum N y - W y_c) in N and N m."""
    return np.array([loads.sum() - W, loads @ BASE.positions[:, 0] - W * centre[0],
                     loads @ BASE.positions[:, 1] - W * centre[1]])


def test_centre_of_mass_at_the_centre_gives_a_quarter_each():
    assert np.allclose(wheel_normal_forces(BASE, MASS, [0.0, 0.0]), W / 4, rtol=0, atol=1e-12)


def test_centre_of_mass_forward_loads_the_front_wheels():
    centre = np.array([0.05, 0.0])
    loads = wheel_normal_forces(BASE, MASS, centre)
    # Hand: N = W (1/4 +- x_c / (4 lx)) = 73.575 (1 +- 0.05 / 0.235) on the front / back pair.
    front, back = W / 4 * (1 + 0.05 / LX), W / 4 * (1 - 0.05 / LX)
    assert np.allclose(loads, [front, front, back, back], rtol=0, atol=1e-12)
    assert np.allclose(equilibrium_residual(loads, centre), 0.0, atol=1e-12)


def test_loads_balance_for_random_centres_inside_the_diamond():
    for centre in RNG.uniform(-1, 1, size=(20, 2)) * [LX, LY] * 0.45:
        loads = wheel_normal_forces(BASE, MASS, centre)
        assert np.all(loads > 0)
        assert np.allclose(equilibrium_residual(loads, centre), 0.0, atol=1e-11)
        # Least norm: loads linear in the wheel position, W (1/4 + x_c x_i / (4 lx^2) + y_c y_i / (4 ly^2)).
        linear = W * (0.25 + centre[0] * BASE.positions[:, 0] / (4 * LX**2)
                      + centre[1] * BASE.positions[:, 1] / (4 * LY**2))
        assert np.allclose(loads, linear, rtol=0, atol=1e-11)


def test_a_wheel_lifts_when_the_linear_rule_would_pull_it():
    """x_c = 0.8 lx, y_c = 0.8 ly: the linear rule gives br W (1/4 - 0.2 - 0.2) < 0, so br
    carries 0 and fl + fr + bl = W, lx (fl + fr - bl) = 0.8 W, ly (fl - fr + bl) = 0.8 W:
    fl = 0.8 W, fr = bl = 0.1 W."""
    centre = np.array([0.8 * LX, 0.8 * LY])
    loads = wheel_normal_forces(BASE, MASS, centre)
    assert np.allclose(loads, [0.8 * W, 0.1 * W, 0.1 * W, 0.0], rtol=0, atol=1e-10)
    assert np.allclose(equilibrium_residual(loads, centre), 0.0, atol=1e-10)


def test_centre_of_mass_outside_the_wheels_tips_over():
    with pytest.raises(TipOverError, match="outside the support polygon"):
        wheel_normal_forces(BASE, MASS, [1.01 * LX, 0.0])
    with pytest.raises(UserInputError, match="one line"):
        support_loads(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]]), [0.5, 0.0], W)
    with pytest.raises(UserInputError, match="mass"):
        wheel_normal_forces(BASE, 0.0, [0.0, 0.0])


def test_acceleration_shifts_the_load_backwards_and_moments_balance():
    """Accelerating at a with the centre of mass h above the floor: floor forces m a at the
    floor, h below it. Moments about the centre of mass: sum N_i (x_i - x_c) = -h m a_x,
    sum N_i (y_i - y_c) = -h m a_y."""
    h, a, centre = 0.25, np.array([2.0, -0.5]), np.array([0.02, 0.01])
    loads = wheel_normal_forces(BASE, MASS, centre, com_height=h, com_acceleration=a)
    assert loads[2] > loads[0] and loads[3] > loads[1]  # forward acceleration loads the back wheels
    assert math.isclose(loads.sum(), W, rel_tol=1e-14)
    assert np.allclose(loads @ (BASE.positions - centre), -h * MASS * a, rtol=0, atol=1e-11)


@pytest.fixture(scope="module")
def robot():
    return load_robot(URDF, root="planar")


def test_youbot_centre_of_mass_moves_the_loads(robot):
    data = robot.model.createData()
    q = pin.neutral(robot.model)
    mass, com = centre_of_mass_in_base(robot, data, q)
    links = {"base_link": 22.0, "plate_link": 2.397, "arm_link_0": 0.961, "arm_link_1": 1.390,
             "arm_link_2": 1.318, "arm_link_3": 0.821, "arm_link_4": 0.769, "arm_link_5": 0.687,
             "gripper_palm_link": 0.1, "gripper_finger_link_l": 0.01, "gripper_finger_link_r": 0.01}
    assert math.isclose(mass, sum(links.values()) + 4 * 1.4, rel_tol=1e-12)  # youbot_facts.md masses
    # The same configuration of the body elsewhere on the floor: the same centre in the base frame.
    moved = q.copy()
    moved[:4] = [1.5, -2.0, math.cos(0.7), math.sin(0.7)]
    assert np.allclose(centre_of_mass_in_base(robot, data, moved)[1], com, atol=1e-12)
    # The arm leaning forward over the front wheels (arm_joint_1 2.95, 2 at 2.0, 3 at -1: the
    # centre of mass measured at x = +0.0385 m) and the same lean turned backwards (arm_joint_1 0:
    # x = -0.0042 m): the loads follow the centre of mass.
    base = mecanum_base_from_robot(robot)
    index = {name: robot.model.joints[robot.model.getJointId(name)].idx_q
             for name in ("arm_joint_1", "arm_joint_2", "arm_joint_3")}
    ends = []
    for joint_1 in (2.95, 0.0):
        pose = q.copy()
        pose[[index["arm_joint_1"], index["arm_joint_2"], index["arm_joint_3"]]] = [joint_1, 2.0, -1.0]
        _, centre = centre_of_mass_in_base(robot, data, pose)
        loads = wheel_normal_forces(base, mass, centre)
        assert math.isclose(loads.sum(), mass * 9.81, rel_tol=1e-13)
        assert np.allclose(loads @ base.positions, mass * 9.81 * centre[:2], rtol=0, atol=1e-10)
        ends.append((centre[0], loads[:2].sum() - loads[2:].sum()))  # (x_c, front minus back load)
    (x_forward, excess_forward), (x_back, excess_back) = ends
    assert x_forward > 0.03 and x_back < 0.0
    assert excess_forward > 0.0 > excess_back
    # Front minus back = W x_c / lx (linear rule): 15.5 N per 0.01 m for the 36.06 kg youBot.
    assert math.isclose(excess_forward, mass * 9.81 * x_forward / 0.228, rel_tol=1e-12)


def test_pure_rolling_slips_nowhere_and_feels_no_force():
    loads = wheel_normal_forces(BASE, MASS, [0.0, 0.0])
    for twist in RNG.uniform(-1, 1, size=(10, 3)):
        slips = contact_slip_velocities(BASE, twist, wheel_speeds(BASE, twist))
        normals = np.column_stack([-BASE.roller_axes[:, 1], BASE.roller_axes[:, 0]])
        assert np.allclose(np.einsum("ij,ij->i", slips, normals), 0.0, atol=1e-14)
        assert np.allclose(roller_forces(BASE, slips, loads, 0.6, 1e-3), 0.0, atol=1e-9)


def test_roller_friction_is_free_along_the_roller_and_coulomb_across():
    axis = np.array([1.0, 1.0]) / math.sqrt(2.0)
    across = np.array([-1.0, 1.0]) / math.sqrt(2.0)
    n_force, mu, vs = 80.0, 0.5, 1e-3
    assert np.allclose(roller_friction(0.3 * axis, axis, n_force, mu, vs), 0.0, atol=1e-15)
    # Hand: slip 0.02 m/s across plus 0.3 along: F = -mu N 0.02 / sqrt(0.02^2 + vs^2) n.
    force = roller_friction(0.02 * across + 0.3 * axis, axis, n_force, mu, vs)
    assert np.allclose(force, -mu * n_force * 0.02 / math.hypot(0.02, vs) * across, rtol=1e-14, atol=0)
    fast = roller_friction(-5.0 * across, axis, n_force, mu, vs)
    assert math.isclose(np.linalg.norm(fast), mu * n_force, rel_tol=1e-7)  # saturates at mu N
    assert fast @ across > 0  # opposes the slip


def test_contact_power_splits_into_hub_and_spin_and_dissipates():
    """F . u = F . v_hub + tau omega with tau = -r F . d: the contact's power, never positive."""
    loads = wheel_normal_forces(BASE, MASS, [0.03, -0.02])
    for _ in range(10):
        twist, speeds = RNG.uniform(-1, 1, 3), RNG.uniform(-20, 20, 4)
        slips = contact_slip_velocities(BASE, twist, speeds)
        forces = roller_forces(BASE, slips, loads, 0.6, 1e-3)
        power = np.einsum("ij,ij->i", forces, slips)
        hubs = np.einsum("ij,ij->i", forces, BASE.hub_velocities(twist))
        assert np.allclose(power, hubs + wheel_spin_torques(BASE, forces) * speeds, rtol=0, atol=1e-10)
        assert np.all(power <= 0.0)
