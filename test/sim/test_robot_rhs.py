"""The compiled paths of a robot's right-hand side (SimModel.robot_derivative for a robot
alone, the computed-torque controller) against the same formulas written with Pinocchio and
JointFriction: equal bit for bit (the same operations in the same order), at random states of
arm_friction (LuGre + Stribeck), arm_ptp (computed torque + Stribeck) and arm_swing."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.scene.reader import read_yaml
from youbot_dynamics.scene.schema import Scene, load_scene, scene_dir
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim.controllers import Reference
from youbot_dynamics.sim.engine import initial_state, right_hand_side


class Plain(np.ndarray):
    """An ndarray subclass: the compiled paths' type checks refuse it (the general path)."""


@pytest.fixture(scope="module", params=["arm_friction", "arm_ptp", "arm_swing"])
def scene(request):
    model = compile(load_scene(scene_dir() / f"{request.param}.yaml"))
    return request.param, model, initial_state(model)


def test_robot_derivative_equals_aba_with_friction_and_the_bristle_rates(scene):
    name, model, state = scene
    assert model.robot_alone
    if name != "arm_swing":  # arm_swing has no friction: always the general path
        assert model._compiled_derivative is not None
    rng = np.random.default_rng(4)
    robot, friction, data = model.robot, model.friction, state.data
    q_block, v_block, z_block = model.slices["q"], model.slices["v"], model.slices["z"]
    for _ in range(20):
        x = state.x + rng.normal(0.0, 0.3, state.x.shape)
        x[z_block] = rng.normal(0.0, 1e-3, z_block.stop - z_block.start)
        tau = rng.uniform(-5.0, 5.0, robot.nv)
        dx = model.robot_derivative(data, x, tau)
        q, v, z = x[q_block], x[v_block], x[z_block]
        left = tau - (0.0 if friction is None else friction.torque(v, z))
        np.testing.assert_array_equal(dx[q_block], v)
        np.testing.assert_array_equal(dx[v_block], pin.aba(robot.model, robot.model.createData(), q, v, left))
        if friction is not None:
            np.testing.assert_array_equal(dx[z_block], friction.state_derivative(v, z))
        np.testing.assert_array_equal(model.robot_derivative(data, x.view(Plain), tau.view(Plain)), dx)


def test_a_wrong_torque_size_still_names_it(scene):
    name, model, state = scene
    with pytest.raises(Exception, match="tau"):
        model.robot_derivative(state.data, state.x, np.zeros(model.robot.nv + 1))


def test_computed_torque_equals_its_formula():
    model = compile(load_scene(scene_dir() / "arm_ptp.yaml"))
    state = initial_state(model)
    controller, friction, robot = model.control.controller, model.friction, model.robot
    assert controller.kind == "computed_torque" and friction is not None
    data = robot.model.createData()
    torque, rhs = right_hand_side(model, state.data, state.reference)
    rng = np.random.default_rng(5)
    limit = robot.effort_limit
    clipped = 0
    for t in np.linspace(0.0, 13.0, 27):
        q = state.x[model.slices["q"]] + rng.normal(0.0, 0.2, robot.nv)
        v = rng.normal(0.0, 1.0, robot.nv)
        q_d, v_d, a_d = state.reference.at(t)
        a = a_d + controller.kp * (q_d - q) + controller.kd * (v_d - v)
        expected = np.clip(pin.rnea(robot.model, data, q, v, a) + friction.torque(v_d, friction.steady_state_bristles(v_d)),
                           -limit, limit)
        clipped += int(np.any(np.abs(expected) == limit))
        np.testing.assert_array_equal(controller.torque(t, q, v, state.reference), expected)
        np.testing.assert_array_equal(controller.torque(t, q.view(Plain), v.view(Plain), state.reference), expected)
    assert clipped  # some samples hit an effort limit (the clipping is exercised)


def _computed_torque_scene(lugre: bool):
    """arm_ptp as it is, or with LuGre friction on joints 2 and 3 (the feedforward then
    needs the steady-state bristles at v_d)."""
    path = scene_dir() / "arm_ptp.yaml"
    data = read_yaml(path.read_bytes(), str(path))
    if lugre:
        for joint in ("arm_joint_2", "arm_joint_3"):
            data["friction"]["joints"][joint] = {"law": "lugre", "sigma0": 1000.0, "sigma1": 5.0, "sigma2": 1.0,
                                                 "coulomb": 0.3, "static": 0.4, "stribeck_velocity": 0.1}
    return compile(Scene.from_dict(data, str(path), path.parent))


class _Sampled:
    """A trajectory without a compiled form (as a /joint_trajectory's): rest at ``q``."""

    def __init__(self, q: np.ndarray) -> None:
        self.q = q

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.q, np.zeros_like(self.q), np.zeros_like(self.q)


@pytest.mark.parametrize("lugre", [False, True])
def test_the_fused_computed_torque_rhs_equals_the_controller_then_robot_derivative(lugre):
    model = _computed_torque_scene(lugre)
    state = initial_state(model)
    controller, robot = model.control.controller, model.robot
    q_block, v_block, z_block = model.slices["q"], model.slices["v"], model.slices["z"]
    assert (z_block.stop - z_block.start == 2) == lugre
    rng = np.random.default_rng(6)
    held = Reference(state.x[q_block] + 0.1)
    for reference in (state.reference, held):
        assert model.computed_torque_derivative(state.data, reference, None) is not None  # fused
        rhs = right_hand_side(model, state.data, reference)[1]
        clipped = 0
        for t in np.linspace(-0.5, 14.5, 31):
            x = state.x + rng.normal(0.0, 0.2, state.x.shape)
            x[v_block] = rng.normal(0.0, 1.0, robot.nv)
            x[z_block] = rng.normal(0.0, 1e-3, z_block.stop - z_block.start)
            tau = controller.torque(t, x[q_block], x[v_block], reference)
            clipped += int(np.any(np.abs(tau) == robot.effort_limit))
            expected = model.robot_derivative(robot.model.createData(), x, tau)
            np.testing.assert_array_equal(rhs(t, x), expected)
            np.testing.assert_array_equal(rhs(t, x.view(Plain)), expected)  # the general path
        assert clipped
    assert model.computed_torque_derivative(state.data, Reference(held.hold, _Sampled(held.hold)), rhs) is None
    with pytest.raises(ValueError, match="one value per joint"):  # the general path names a size the fused refuses
        rhs(0.1, np.zeros(2 * robot.nv - 1))
