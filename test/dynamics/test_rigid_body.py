"""Rigid-body dynamics with friction: ABA and RNEA invert each other, the mass matrix, the
gravity and bias torques, the energies (gradient of V, power balance along a simulated
trajectory), Pinocchio not applying the URDF damping itself, and extreme velocities."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import (bias_torque, forward_dynamics,
                                                 forward_dynamics_batch, gravity_torque,
                                                 inverse_dynamics, inverse_dynamics_batch,
                                                 kinetic_energy, mass_matrix, potential_energy,
                                                 symmetrised)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.model.configuration import random_configuration
from youbot_dynamics.model.robot import Robot, keep_joints, load_robot

URDF = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
ARM = tuple(f"arm_joint_{i}" for i in range(1, 6))
LUGRE = {"law": "lugre", "sigma0": 300.0, "sigma1": 2.0, "sigma2": 0.3, "coulomb": 0.5,
         "static": 0.8, "stribeck_velocity": 0.1}
STRIBECK = {"law": "stribeck", "coulomb": 0.4, "static": 0.7, "stribeck_velocity": 0.1,
            "damping": 0.5, "velocity_scale": 0.02}
#: Rotor inertia times gear ratio squared, kg m^2 (youbot_facts.md section 1).
ARM_ARMATURE = np.array([1.35e-5 + 4.09e-7, 1.35e-5 + 4.09e-7, 1.35e-5 + 7.1e-8, 9.25e-6 + 7.1e-8,
                         3.5e-6 + 7.1e-8]) * np.array([156, 156, 100, 71, 71]) ** 2


@pytest.fixture(scope="module")
def youbot() -> Robot:
    return load_robot(URDF)


@pytest.fixture(scope="module")
def arm(youbot) -> Robot:
    return keep_joints(youbot, ARM)


def with_armature(robot: Robot, armature: np.ndarray) -> Robot:
    model = pin.Model(robot.model)
    model.armature = armature
    return dataclasses.replace(robot, model=model)


def frictions(robot: Robot) -> list[JointFriction]:
    return [JointFriction.from_urdf(robot),
            JointFriction.from_spec(robot, {"arm_joint_2": LUGRE, "arm_joint_3": STRIBECK,
                                            "arm_joint_5": {**LUGRE, "sigma0": 1e3}})]


def random_state(robot: Robot, friction: JointFriction, rng: np.random.Generator):
    n = robot.nv
    return (rng.uniform(-np.pi, np.pi, n), rng.uniform(-2, 2, n), rng.uniform(-5, 5, n),
            rng.normal(0, 2e-3, friction.n_states))


@pytest.mark.parametrize("which", ["youbot", "arm"])
def test_aba_and_rnea_invert_each_other_with_friction(which, request):
    robot = request.getfixturevalue(which)
    data = robot.model.createData()
    rng = np.random.default_rng(3)
    for friction in frictions(robot):
        for _ in range(50):
            q, v, a, z = random_state(robot, friction, rng)
            tau = inverse_dynamics(robot, data, q, v, a, friction, z)
            np.testing.assert_allclose(forward_dynamics(robot, data, q, v, tau, friction, z), a, rtol=0, atol=1e-9)
            np.testing.assert_allclose(tau - friction.torque(v, z), pin.rnea(robot.model, data, q, v, a),
                                       rtol=0, atol=1e-12)


def test_the_unchecked_friction_path_equals_the_checked_one_and_refuses_bad_states(arm):
    """forward/inverse dynamics call the compiled friction loop without numba's type checks
    for float64 vectors: equal (bit for bit) to Pinocchio plus JointFriction.torque (the
    checked call of the same loop) for contiguous, strided and float32 inputs, and a wrong
    bristle state is still the friction's UserInputError, never a wrong read."""
    data = arm.model.createData()
    rng = np.random.default_rng(8)
    for friction in frictions(arm):
        q, v, a, z = random_state(arm, friction, rng)
        tau = pin.rnea(arm.model, data, q, v, a) + friction.torque(v, z)
        np.testing.assert_array_equal(inverse_dynamics(arm, data, q, v, a, friction, z), tau)
        expected = pin.aba(arm.model, data, q, v, tau - friction.torque(v, z))
        strided = np.repeat(v, 2)[::2]
        for velocity in (v, strided):
            np.testing.assert_array_equal(forward_dynamics(arm, data, q, velocity, tau, friction, z), expected)
        # what the in-line type checks send the other way: lists, a float32 torque, a strided z
        np.testing.assert_array_equal(forward_dynamics(arm, data, q, v, list(tau), friction, list(z)), expected)
        np.testing.assert_array_equal(forward_dynamics(arm, data, q, v, tau.astype(np.float32), friction, z),
                                      pin.aba(arm.model, data, q, v, tau.astype(np.float32) - friction.torque(v, z)))
        np.testing.assert_array_equal(inverse_dynamics(arm, data, q, v, a, friction, list(z)), tau)
        np.testing.assert_array_equal(inverse_dynamics(arm, data, q, v, a, friction, np.repeat(z, 2)[::2]), tau)
        v32 = v.astype(np.float32)
        np.testing.assert_array_equal(forward_dynamics(arm, data, q, v32, tau, friction, z),
                                      pin.aba(arm.model, data, q, v32, tau - friction.torque(v32.astype(float), z)))
        for wrong in (np.zeros(friction.n_states + 1), np.zeros((1, friction.n_states)), *([None] if friction.n_states else [])):
            with pytest.raises(UserInputError, match="LuGre bristle states"):
                forward_dynamics(arm, data, q, v, tau, friction, wrong)
            with pytest.raises(UserInputError, match="LuGre bristle states"):
                inverse_dynamics(arm, data, q, v, a, friction, wrong)
        with pytest.raises(UserInputError, match="v: expected 5 values"):
            forward_dynamics(arm, data, q, np.zeros(4), tau, friction, z)


def test_symmetrised_is_the_upper_triangle_mirrored_to_the_bit():
    """Against triu(M) + triu(M, 1)^T, signed zeros included; the input is not modified."""
    rng = np.random.default_rng(2)
    for n in (1, 2, 5, 20):
        upper = rng.normal(size=(n, n))
        upper[rng.random((n, n)) < 0.3] = -0.0
        before = upper.copy()
        full = symmetrised(upper)
        assert full.tobytes() == (np.triu(upper) + np.triu(upper, 1).T).tobytes()
        np.testing.assert_array_equal(full, full.T)
        assert upper.tobytes() == before.tobytes()


@pytest.mark.parametrize("which", ["youbot", "arm", "floating"])
def test_batches_equal_the_per_sample_functions(which, request):
    """inverse_dynamics_batch / forward_dynamics_batch (Pinocchio's C++ loops and the friction
    of all rows at once) against the per-sample functions, row by row, with URDF and mixed
    (LuGre, Stribeck) friction; a floating root keeps friction off its six columns."""
    robot = load_robot(URDF, root="floating") if which == "floating" else request.getfixturevalue(which)
    data, rng = robot.model.createData(), np.random.default_rng(7)
    n = 40
    for friction in [None, *frictions(robot)]:
        q = np.array([random_configuration(robot, rng) for _ in range(n)])
        v, a = rng.uniform(-2, 2, (n, robot.nv)), rng.uniform(-5, 5, (n, robot.nv))
        z = None if friction is None or not friction.n_states else rng.normal(0, 2e-3, (n, friction.n_states))
        row_z = [None if z is None else z[k] for k in range(n)]
        tau = inverse_dynamics_batch(robot, q, v, a, friction, z)
        expected = [inverse_dynamics(robot, data, q[k], v[k], a[k], friction, row_z[k]) for k in range(n)]
        # the same C++ RNEA and friction formulas: measured 0 difference; 1e-12 N m allows a
        # different summation order
        np.testing.assert_allclose(tau, expected, rtol=0, atol=1e-12)
        acc = forward_dynamics_batch(robot, q, v, tau, friction, z)
        expected = [forward_dynamics(robot, data, q[k], v[k], tau[k], friction, row_z[k]) for k in range(n)]
        np.testing.assert_allclose(acc, expected, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(acc, a, rtol=0, atol=1e-8)


def test_batch_sizes_are_checked(arm):
    q = np.zeros((3, arm.nq))
    with pytest.raises(UserInputError, match=r"v: a batch needs shape \(N, nv = 5\)"):
        inverse_dynamics_batch(arm, q, np.zeros((3, 4)), np.zeros((3, 5)))
    with pytest.raises(UserInputError, match="a: 2 samples"):
        inverse_dynamics_batch(arm, q, np.zeros((3, 5)), np.zeros((2, 5)))
    assert forward_dynamics_batch(arm, q[:0], q[:0], q[:0]).shape == (0, 5)


def test_pinocchio_does_not_apply_urdf_damping_or_friction(youbot):
    """The URDF dynamics reach model.damping/friction; rnea and aba must ignore them, or
    friction would be counted twice."""
    assert np.any(youbot.model.damping > 0) and np.any(youbot.model.friction > 0)
    bare = pin.Model(youbot.model)
    bare.damping[:] = 0.0
    bare.friction[:] = 0.0
    data, bare_data = youbot.model.createData(), bare.createData()
    rng = np.random.default_rng(4)
    q, v, a = (rng.uniform(-1, 1, youbot.nv) for _ in range(3))
    np.testing.assert_array_equal(pin.rnea(youbot.model, data, q, v, a), pin.rnea(bare, bare_data, q, v, a))
    np.testing.assert_array_equal(pin.aba(youbot.model, data, q, v, a), pin.aba(bare, bare_data, q, v, a))


@pytest.mark.parametrize("armature", [False, True])
def test_mass_matrix_gravity_and_bias(youbot, armature):
    robot = with_armature(youbot, np.linspace(0.01, 0.3, youbot.nv)) if armature else youbot
    data = robot.model.createData()
    rng = np.random.default_rng(5)
    for _ in range(20):
        q, v, a = (rng.uniform(-2, 2, robot.nv) for _ in range(3))
        mass = mass_matrix(robot, data, q)
        np.testing.assert_array_equal(mass, mass.T)
        assert np.linalg.eigvalsh(mass).min() > 0
        # columns of M from RNEA: M e_i = rnea(q, 0, e_i) - g(q)
        g = gravity_torque(robot, data, q)
        np.testing.assert_allclose(g, pin.rnea(robot.model, data, q, 0 * v, 0 * a), rtol=0, atol=1e-12)
        columns = np.column_stack([pin.rnea(robot.model, data, q, 0 * v, e) for e in np.eye(robot.nv)]) - g[:, None]
        np.testing.assert_allclose(mass, columns, rtol=0, atol=1e-12)
        np.testing.assert_allclose(inverse_dynamics(robot, data, q, v, a),
                                   mass @ a + bias_torque(robot, data, q, v), rtol=0, atol=1e-11)


def test_energies(youbot):
    data = youbot.model.createData()
    rng = np.random.default_rng(6)
    q, v = rng.uniform(-2, 2, youbot.nv), rng.uniform(-2, 2, youbot.nv)
    # without armature, T agrees with Pinocchio's own kinetic energy algorithm
    assert kinetic_energy(youbot, data, q, v) == pytest.approx(
        pin.computeKineticEnergy(youbot.model, data, q, v), rel=1e-13)
    # dV/dq = g(q), by central differences
    h = 1e-6
    gradient = [(potential_energy(youbot, data, q + h * e) - potential_energy(youbot, data, q - h * e)) / (2 * h)
                for e in np.eye(youbot.nv)]
    np.testing.assert_allclose(gradient, gravity_torque(youbot, data, q), rtol=0, atol=1e-7)


def power_balance_error(robot: Robot, friction: JointFriction, integrator: str, rtol: float,
                        count_friction: bool = True) -> float:
    """Simulate x = (q, v, z, W) with W' = v . (tau - tau_friction) under a time-varying torque
    from rest; return |(T + V)(t_end) - (T + V)(0) - W(t_end)| / max |W|. With
    ``count_friction`` False, W leaves the friction out (a deliberately wrong balance)."""
    data = robot.model.createData()
    n, nz = robot.nv, friction.n_states
    amplitude = 0.5 * np.minimum(robot.effort_limit, 5.0)
    frequency = 2.0 * np.arange(1, n + 1)  # rad/s

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, v, z = x[:n], x[n:2 * n], x[2 * n:2 * n + nz]
        tau = gravity_torque(robot, data, q) + amplitude * np.sin(frequency * t)
        a = forward_dynamics(robot, data, q, v, tau, friction, z)
        return np.concatenate([v, a, friction.state_derivative(v, z), [v @ (tau - count_friction * friction.torque(v, z))]])

    def energy(x: np.ndarray) -> float:
        return kinetic_energy(robot, data, x[:n], x[n:2 * n]) + potential_energy(robot, data, x[:n])

    x0 = np.concatenate([np.full(n, 0.5), np.zeros(n), np.zeros(nz), [0.0]])
    solution = integrate(rhs, x0, np.linspace(0.0, 1.5, 31), integrator, rtol=rtol, atol=rtol * 1e-3)
    assert solution.t[-1] == 1.5
    work = solution.x[:, -1]
    assert np.abs(solution.x[:, n:2 * n]).max() > 0.5  # the arm really moves
    return abs(energy(solution.x[-1]) - energy(x0) - work[-1]) / np.abs(work).max()


@pytest.mark.parametrize("armature", [False, True])
def test_power_balance_along_simulated_arm_trajectory(arm, armature):
    """d/dt (T + V) = v . (tau - tau_friction), with the URDF friction, Stribeck and LuGre
    joints; with the youBot's rotor inertias as armature the check covers T's armature term."""
    robot = with_armature(arm, ARM_ARMATURE) if armature else arm
    friction = JointFriction.from_spec(robot, {"arm_joint_2": LUGRE, "arm_joint_3": STRIBECK})
    rtol = 1e-9
    assert power_balance_error(robot, friction, "dop853", rtol) < 100 * rtol


def test_power_balance_fails_without_the_friction_work(arm):
    """The check is sensitive: leaving the friction out of the work integral breaks it."""
    friction = JointFriction.from_spec(arm, {"arm_joint_2": LUGRE})
    assert power_balance_error(arm, friction, "dop853", 1e-9, count_friction=False) > 1e-3


@pytest.mark.parametrize("value", [0.0, 1e-12, -1e-12, 1e3, -1e3])
def test_dynamics_finite_at_extreme_velocities(youbot, value):
    data = youbot.model.createData()
    friction = frictions(youbot)[1]
    q, v, a = np.full(youbot.nv, 0.3), np.full(youbot.nv, value), np.ones(youbot.nv)
    z = friction.steady_state_bristles(v)
    tau = inverse_dynamics(youbot, data, q, v, a, friction, z)
    acceleration = forward_dynamics(youbot, data, q, v, tau, friction, z)
    assert np.all(np.isfinite(tau)) and np.all(np.isfinite(acceleration))
    np.testing.assert_allclose(acceleration, a, rtol=0, atol=1e-9 * max(1.0, np.abs(tau).max()))
    # friction stays within its viscous part plus the largest static level
    viscous = (friction.damping + 0.3 * np.array([law == "lugre" for law in friction.laws])) * v
    assert np.all(np.abs(friction.torque(v, z) - viscous) <= 1.0 + 1e-12)
