"""The computed-torque controller's compiled path (desired motion, commanded acceleration,
RNEA, friction feedforward and clip in two compiled calls) against its numpy formula, bit for
bit: with and without friction, a compiled and a sampled trajectory, and an effort limit
below the URDF's on one joint, above it on another. The same for the gravity-compensated PD
(its law in one compiled call), with a held set point too."""
from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.scene.schema import load_scene, scene_dir
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim.controllers import ComputedTorque, GravityCompensatedPD, Reference
from youbot_dynamics.sim.engine import initial_state


class _Sampled:
    """A trajectory without a compiled form (as a /joint_trajectory's): rest at ``q``."""

    def __init__(self, q: np.ndarray) -> None:
        self.q = q

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.q, np.zeros_like(self.q), np.zeros_like(self.q)


class _Plain(np.ndarray):
    """An ndarray subclass: the controllers take numpy's path for it."""


def numpy_torque(controller: ComputedTorque, t: float, q: np.ndarray, v: np.ndarray,
                 reference: Reference) -> np.ndarray:
    """tau = clip(RNEA(q, v, a_d + Kp e + Kd e') + tau_f(v_d), -limit, limit) in numpy."""
    q_d, v_d, a_d = reference.at(t)
    a = a_d + controller.kp * (q_d - q) + controller.kd * (v_d - v)
    tau = pin.rnea(controller.robot.model, controller.robot.model.createData(), q, v, a)
    if controller.friction is not None:
        tau = tau + controller.friction.torque(v_d, controller.friction.steady_state_bristles(v_d))
    limit = reference.limit(controller.limit)
    return np.clip(tau, -limit, limit)


@pytest.mark.parametrize("with_friction", [True, False])
def test_compiled_computed_torque_equals_the_numpy_formula(with_friction):
    model = compile(load_scene(scene_dir() / "arm_ptp.yaml"))
    state = initial_state(model)
    robot = model.robot
    controller = ComputedTorque(robot, model.control.controller.kp, model.control.controller.kd,
                                model.friction if with_friction else None)
    effort = np.array(robot.effort_limit, dtype=float)
    effort[[0, 2]] = [0.5, np.inf]  # below the URDF's on joint 1, above it on joint 3
    references = [state.reference, dataclasses.replace(state.reference, effort_limit=effort),
                  Reference(state.x[model.slices["q"]] + 0.1, _Sampled(state.x[model.slices["q"]] + 0.1))]
    rng = np.random.default_rng(7)
    clipped = lowered = 0
    for reference in references:
        for t in np.linspace(-0.5, 13.0, 19):
            q = state.x[model.slices["q"]] + rng.normal(0.0, 0.2, robot.nv)
            v = rng.normal(0.0, 1.0, robot.nv)
            expected = numpy_torque(controller, t, q, v, reference)
            np.testing.assert_array_equal(controller.torque(t, q, v, reference), expected)
            clipped += int(np.any(np.abs(expected) == reference.limit(controller.limit)))
            lowered += int(abs(expected[0]) == 0.5)
    assert clipped and lowered  # the clip and the lowered limit are exercised


def test_compiled_pd_equals_the_numpy_formula():
    model = compile(load_scene(scene_dir() / "arm_ptp.yaml"))
    state = initial_state(model)
    robot, hold = model.robot, state.x[model.slices["q"]]
    kp, kd = np.linspace(20.0, 60.0, robot.nv), 3.0  # per joint and one for all
    controller, data = GravityCompensatedPD(robot, kp, kd), robot.model.createData()
    effort = np.array(robot.effort_limit, dtype=float)
    effort[[0, 2]] = [0.5, np.inf]  # below the URDF's on joint 1, above it on joint 3
    references = [state.reference, dataclasses.replace(state.reference, effort_limit=effort),
                  Reference(hold + 0.1), Reference(hold + 0.1, _Sampled(hold + 0.1))]
    rng = np.random.default_rng(11)
    clipped = lowered = 0
    for reference in references:
        for t in np.linspace(-0.5, 13.0, 19):
            q, v = hold + rng.normal(0.0, 0.2, robot.nv), rng.normal(0.0, 1.0, robot.nv)
            q_d, v_d, _ = reference.at(t)
            limit = robot.effort_limit if reference.effort_limit is None else \
                np.minimum(robot.effort_limit, reference.effort_limit)
            gravity = pin.computeGeneralizedGravity(robot.model, data, q)
            expected = np.clip(gravity + kp * (q_d - q) + kd * (v_d - v), -limit, limit)
            np.testing.assert_array_equal(controller.torque(t, q, v, reference), expected)
            np.testing.assert_array_equal(controller.torque(t, q.view(_Plain), v, reference), expected)  # numpy's path
            np.testing.assert_array_equal(controller.torque(t, np.repeat(q, 2)[::2], v, reference), expected)  # strided
            clipped += int(np.any(np.abs(expected) == limit))
            lowered += int(abs(expected[0]) == 0.5)
    assert clipped and lowered  # the clip and the lowered limit are exercised
