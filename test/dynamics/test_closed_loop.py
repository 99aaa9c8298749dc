"""Closed loops from Pinocchio constraint models (dynamics.closed_loop) on the planar
four-bar (systems.four_bar), against independent references: finite differences of g and
of G v, the closed-form position analysis of the four-bar (Freudenstein's equation),
energy conservation, and Pinocchio's own constraintDynamics."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.dynamics.closed_loop import (LoopClosure, holonomic_system_from_robot,
                                                  point_anchor)
from youbot_dynamics.dynamics.constraints import (HolonomicSystem, accelerations_and_multipliers,
                                                  consistent_initial_values)
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import kinetic_energy, potential_energy
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.constrained import ConstrainedRun, simulate_holonomic
from youbot_dynamics.model.robot import Robot, load_robot
from youbot_dynamics.studies.four_bar import (COUPLER, CRANK, FOUR_BAR_URDF, GROUND,
                                              PLANAR_COMPONENTS, ROCKER, four_bar_system)

STEP = 1e-6  # central-difference step (rad, rad/s)
#: Initial guess (rad) and crank rate (rad/s): enough energy for the crank to turn round.
Q_GUESS, CRANK_RATE = np.array([0.6, 0.1, 1.5]), 12.0
T_END = 1.0  # s


@pytest.fixture(scope="module")
def robot() -> Robot:
    return load_robot(FOUR_BAR_URDF)


@pytest.fixture(scope="module")
def closure(robot: Robot) -> LoopClosure:
    return point_anchor(robot, "coupler_tip", "rocker_tip", PLANAR_COMPONENTS)


@pytest.fixture(scope="module")
def system() -> HolonomicSystem:
    return four_bar_system()


@pytest.fixture(scope="module")
def initial(system: HolonomicSystem) -> tuple[np.ndarray, np.ndarray]:
    q0, v0, *_ = consistent_initial_values(system, Q_GUESS, [CRANK_RATE, 0.0, 0.0], fixed=[0])
    return q0, v0


@pytest.fixture(scope="module")
def runs(system: HolonomicSystem, initial) -> dict[str, ConstrainedRun]:
    t = np.linspace(0.0, T_END, 101)
    return {formulation: simulate_holonomic(system, formulation, "dop853", *initial, t,
                                            rtol=1e-11, atol=1e-12, baumgarte_rate=50.0)
            for formulation in ("index1-projection", "index1-baumgarte")}


def energy(robot: Robot, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """(T, T + V) in J."""
    data = robot.model.createData()
    kinetic = kinetic_energy(robot, data, q, v)
    return kinetic, kinetic + potential_energy(robot, data, q)


def freudenstein_rocker_angles(crank: float) -> np.ndarray:
    """Both rocker angles theta4 (rad) for crank angle theta2 from Freudenstein's equation
    K1 cos theta4 - K2 cos theta2 + K3 = cos(theta2 - theta4), K1 = d/a, K2 = d/c,
    K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c), solved with t = tan(theta4 / 2)."""
    a, b, c, d = CRANK, COUPLER, ROCKER, GROUND
    k1, k2, k3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    p, s, r = k1 - np.cos(crank), -np.sin(crank), k3 - k2 * np.cos(crank)
    root = np.sqrt(p * p + s * s - r * r)
    return 2.0 * np.arctan2(-s + np.array([1.0, -1.0]) * root, r - p)


def wrapped(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def test_jacobian_and_curvature_match_finite_differences(system: HolonomicSystem) -> None:
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, v = rng.uniform(-np.pi, np.pi, 3), rng.uniform(-3.0, 3.0, 3)
        columns = [(system.constraint(q + STEP * e) - system.constraint(q - STEP * e))
                   / (2 * STEP) for e in np.eye(3)]
        assert np.abs(system.jacobian(q) - np.column_stack(columns)).max() < 1e-7
        rate = ((system.jacobian(q + STEP * v) - system.jacobian(q - STEP * v)) @ v
                / (2 * STEP))
        assert np.abs(system.curvature(q, v) - rate).max() < 1e-7


def test_frame_anchor_derivatives(robot: Robot, system: HolonomicSystem, initial) -> None:
    """A frame anchor welding rocker_tip to coupler_tip at an assembled configuration:
    G = dg/dq where g = 0 (log6 at the identity), g_qq = d/dt(G v) everywhere."""
    q0, _ = initial
    model, data = robot.model, robot.model.createData()
    first, second = (model.frames[robot.frame_id(n)] for n in ("coupler_tip", "rocker_tip"))
    pin.framesForwardKinematics(model, data, q0)
    tip1, tip2 = (data.oMf[robot.frame_id(n)] for n in ("coupler_tip", "rocker_tip"))
    weld = pin.FrameAnchorConstraintModel(model, first.parentJoint, first.placement,
                                          second.parentJoint,
                                          second.placement * tip2.actInv(tip1))
    welded = holonomic_system_from_robot(robot, [LoopClosure(weld, (0, 2, 4))])
    assert np.abs(welded.constraint(q0)).max() < 1e-12
    columns = [(welded.constraint(q0 + STEP * e) - welded.constraint(q0 - STEP * e))
               / (2 * STEP) for e in np.eye(3)]
    assert np.abs(welded.jacobian(q0) - np.column_stack(columns)).max() < 1e-8
    v = np.array([0.4, -1.2, 2.0])
    for q in (q0, q0 + 0.3):
        rate = ((welded.jacobian(q + STEP * v) - welded.jacobian(q - STEP * v)) @ v
                / (2 * STEP))
        assert np.abs(welded.curvature(q, v) - rate).max() < 1e-7


@pytest.mark.parametrize("formulation", ["index1-projection", "index1-baumgarte"])
def test_constraints_hold_and_energy_is_conserved(robot: Robot, runs, formulation: str
                                                  ) -> None:
    run = runs[formulation]
    assert np.ptp(run.q[:, 0]) > 2 * np.pi  # the crank turns round
    assert np.abs(run.position_residual).max() < 1e-9
    assert np.abs(run.velocity_residual).max() < 1e-8
    energies = np.array([energy(robot, q, v) for q, v in zip(run.q, run.v)])
    drift = np.abs(energies[:, 1] - energies[0, 1]).max() / energies[:, 0].max()
    assert drift < 1e-6


def test_positions_follow_freudenstein(runs) -> None:
    """Rocker angle theta4 = q[2] against the closed form on the run's branch, and the
    coupler angle theta3 = q[0] + q[1] against the direction from B to C."""
    q = runs["index1-projection"].q
    branch = int(np.argmin(np.abs(wrapped(freudenstein_rocker_angles(q[0, 0]) - q[0, 2]))))
    rocker = np.array([freudenstein_rocker_angles(crank)[branch] for crank in q[:, 0]])
    assert np.abs(wrapped(rocker - q[:, 2])).max() < 1e-8
    joint_b = CRANK * np.column_stack((np.cos(q[:, 0]), np.sin(q[:, 0])))
    joint_c = np.column_stack((GROUND + ROCKER * np.cos(rocker), ROCKER * np.sin(rocker)))
    coupler = np.arctan2(*(joint_c - joint_b).T[::-1])
    assert np.abs(wrapped(coupler - q[:, 0] - q[:, 1])).max() < 1e-8


def test_multipliers_match_pinocchio_constraint_dynamics(robot: Robot, closure: LoopClosure,
                                                         system: HolonomicSystem, runs) -> None:
    """pin.constraintDynamics with the same point anchor as a legacy RigidConstraintModel
    (CONTACT_3D, LOCAL; its out-of-plane row is zero, so a proximal mu > 0 regularises
    the singular Delassus matrix): same accelerations, Jacobian -G and contact force
    lambda in the imposed components."""
    model = robot.model
    rigid = pin.convertToRigidConstraintModel(model, closure.constraint, pin.LOCAL)
    models = pin.StdVec_RigidConstraintModel()
    models.append(rigid)
    datas = pin.StdVec_RigidConstraintData()
    datas.append(rigid.createData())
    data = model.createData()
    pin.initConstraintDynamics(model, data, models, datas)
    run = runs["index1-projection"]
    components = list(PLANAR_COMPONENTS)
    for k in (0, 37, 74, 100):
        q, v = run.q[k], run.v[k]
        w, lam = accelerations_and_multipliers(system, q, v)
        settings = pin.ProximalSettings(1e-14, 1e-10, 200)
        acceleration = pin.constraintDynamics(model, data, q, v, np.zeros(model.nv), models,
                                              datas, settings)
        jacobian = pin.getConstraintsJacobian(model, data, models, datas)
        assert np.abs(acceleration - w).max() < 1e-9 * np.abs(w).max()
        assert np.abs(jacobian[components] + system.jacobian(q)).max() < 1e-10
        assert np.abs(data.lambda_c[components] - lam).max() < 1e-9 * np.abs(lam).max()


def test_friction_dissipates(robot: Robot, closure: LoopClosure, initial) -> None:
    friction = JointFriction.from_spec(
        robot, {name: {"law": "viscous", "damping": 0.02} for name in robot.joint_names})
    damped = holonomic_system_from_robot(robot, [closure], friction=friction)
    run = simulate_holonomic(damped, "index1-projection", "dop853", *initial,
                             np.linspace(0.0, T_END, 51), rtol=1e-10, atol=1e-12)
    total = np.array([energy(robot, q, v)[1] for q, v in zip(run.q, run.v)])
    assert np.all(np.diff(total) < 0.0)


def test_bad_closures_are_refused(robot: Robot, closure: LoopClosure) -> None:
    with pytest.raises(UserInputError, match="components"):
        holonomic_system_from_robot(robot, [LoopClosure(closure.constraint, (0, 3))])
    with pytest.raises(UserInputError, match="not supported"):
        holonomic_system_from_robot(robot, [LoopClosure(
            pin.convertToRigidConstraintModel(robot.model, closure.constraint), (0,))])
    with pytest.raises(UserInputError, match="unknown frame"):
        point_anchor(robot, "coupler_tip", "no_such_link")
