"""Acceptance: every non-empty URDF that the PyPI package example-robot-data ships loads, its
PoE kinematics equal Pinocchio's, and its dynamics equal those of a Pinocchio model built
straight from the same file (issue 9).

The reference model is ``pin.buildModelFromUrdf(path)``: continuous joints as Pinocchio's
(cos, sin) joints, no mimic coupling and a free-flyer for a <floating> joint (locked at its
origin with buildReducedModel, as our loader fixes it). A mimic joint follows
q_m = k q_p + o, so v_m = k v_p and a_m = k a_p: with G = d q_reference / d q (one row per
reference joint), our RNEA is G^T RNEA_ref(q_ref, G v, G a) and our mass matrix G^T M_ref G.
"""
from __future__ import annotations

import importlib.metadata
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.dynamics.rigid_body import (forward_dynamics, inverse_dynamics, mass_matrix,
                                                 potential_energy)
from youbot_dynamics.errors import SingularMassMatrixError
from youbot_dynamics.model.robot import Robot, load_robot
from youbot_dynamics.model.screws import fkin_space, jacobian_body, jacobian_space, screw_chain

N_CONFIGURATIONS = 3


def _example_urdfs() -> list[Path]:
    try:
        distribution = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return []
    files = (Path(distribution.locate_file(f)) for f in distribution.files or () if f.suffix == ".urdf")
    return sorted(f for f in files if "<link" in f.read_text(errors="replace"))


URDFS = _example_urdfs()
ROOT = URDFS[0].parents[2] if URDFS else Path()


def _id(path: Path) -> str:
    return path.stem if path.parent.parent.parent == ROOT else str(path.relative_to(ROOT))


def test_example_robot_data_ships_the_robots() -> None:
    # example-robot-data 6.0.0: 69 .urdf files, one (ur3.urdf) without any link or name.
    assert len(URDFS) >= 68, "pip install -r requirements-test.txt (example-robot-data)"


@pytest.fixture(scope="module")
def robots() -> dict[Path, Robot]:
    return {path: load_robot(path) for path in URDFS}


def _swap(jacobian: np.ndarray) -> np.ndarray:
    """Pinocchio rows (v, omega) -> ours (omega, v)."""
    return np.vstack([jacobian[3:], jacobian[:3]])


def _configurations(robot: Robot, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1.0, 1.0, (N_CONFIGURATIONS, robot.nv))


@pytest.mark.parametrize("path", URDFS, ids=_id)
def test_poe_kinematics_equal_pinocchio(robots: dict[Path, Robot], path: Path) -> None:
    """FK and space / body Jacobians of every leaf link (every joint moves one) and of every
    link that shares its name with a joint (frame look-up by type)."""
    robot = robots[path]
    parents = {j.parent for j in robot.tree}
    joint_names = {j.name for j in robot.tree}
    links = [link for link in robot.link_names if link not in parents or link in joint_names]
    data = robot.model.createData()
    configurations = _configurations(robot, 1)
    worst = 0.0
    for link in links:
        chain, frame = screw_chain(robot, link), robot.frame_id(link)
        assert robot.model.frames[frame].name == link
        assert robot.model.frames[frame].type == pin.FrameType.BODY
        space, j_space, j_body = (f(chain, configurations) for f in (fkin_space, jacobian_space, jacobian_body))
        for k, q in enumerate(configurations):
            pin.framesForwardKinematics(robot.model, data, q)
            world = pin.computeFrameJacobian(robot.model, data, q, frame, pin.WORLD).reshape(6, robot.nv)
            local = pin.computeFrameJacobian(robot.model, data, q, frame, pin.LOCAL).reshape(6, robot.nv)
            others = np.setdiff1d(np.arange(robot.nv), chain.joints)
            worst = max(worst, np.abs(space[k] - data.oMf[frame].homogeneous).max(),
                        np.abs(j_space[k] - _swap(world)[:, chain.joints]).max(initial=0.0),
                        np.abs(j_body[k] - _swap(local)[:, chain.joints]).max(initial=0.0),
                        np.abs(world[:, others]).max(initial=0.0))
    # Measured at most 2.7e-15 (icub_reduced) over all robots; bound 1e-12 (375x margin).
    assert worst <= 1e-12, f"{path.name}: {worst:.3g}"


def _reference(path: Path, robot: Robot) -> tuple[pin.Model, np.ndarray]:
    """pin.buildModelFromUrdf of the file (floating joints locked at their origin) and
    G = d v_reference / d v (nv_ref x nv)."""
    model = pin.buildModelFromUrdf(str(path))
    floating = [j for j in range(1, model.njoints) if model.names[j] not in robot.joint_names
                and model.names[j] not in robot.mimic]
    if floating:
        model = pin.buildReducedModel(model, floating, pin.neutral(model))
    coupling = np.zeros((model.nv, robot.nv))
    for j in range(1, model.njoints):
        name, row = model.names[j], model.joints[j].idx_v
        relation = robot.mimic.get(name)
        if relation is None:
            coupling[row, robot.joint_index(name)] = 1.0
        else:
            coupling[row, robot.joint_index(relation.primary)] = relation.multiplier
    return model, coupling


def _reference_q(model: pin.Model, robot: Robot, q: np.ndarray) -> np.ndarray:
    """The reference configuration: each joint's angle, (cos, sin) for a continuous one."""
    q_ref = np.empty(model.nq)
    for j in range(1, model.njoints):
        name, joint = model.names[j], model.joints[j]
        relation = robot.mimic.get(name)
        angle = q[robot.joint_index(name)] if relation is None else \
            relation.multiplier * q[robot.joint_index(relation.primary)] + relation.offset
        q_ref[joint.idx_q:joint.idx_q + joint.nq] = (np.cos(angle), np.sin(angle)) if joint.nq == 2 else angle
    return q_ref


def _relative(ours: np.ndarray, reference: np.ndarray) -> float:
    return float(np.abs(ours - reference).max(initial=0.0) / max(1.0, np.abs(reference).max(initial=0.0)))


@pytest.mark.parametrize("path", URDFS, ids=_id)
def test_dynamics_equal_pinocchio_from_the_file(robots: dict[Path, Robot], path: Path) -> None:
    robot = robots[path]
    if not robot.nv:
        return
    model, G = _reference(path, robot)
    data, reference = robot.model.createData(), model.createData()
    rng = np.random.default_rng(2)
    errors = dict.fromkeys(("rnea", "crba", "potential", "aba"), 0.0)
    for q in _configurations(robot, 3):
        v, a, tau = rng.uniform(-1.0, 1.0, (3, robot.nv))
        q_ref = _reference_q(model, robot, q)
        tau_ref = G.T @ pin.rnea(model, reference, q_ref, G @ v, G @ a)
        errors["rnea"] = max(errors["rnea"], _relative(inverse_dynamics(robot, data, q, v, a), tau_ref))
        upper = pin.crba(model, reference, q_ref)
        m_ref = G.T @ (np.triu(upper) + np.triu(upper, 1).T) @ G
        errors["crba"] = max(errors["crba"], _relative(mass_matrix(robot, data, q), m_ref))
        energy = np.array([potential_energy(robot, data, q)])
        errors["potential"] = max(errors["potential"],
                                  _relative(energy, np.array([pin.computePotentialEnergy(model, reference, q_ref)])))
        if robot.mass_matrix_defect:
            with pytest.raises(SingularMassMatrixError, match="no mass moves with joint"):
                forward_dynamics(robot, data, q, v, tau)
            continue
        if robot.mimic:
            a_ref = np.linalg.solve(m_ref, tau - G.T @ pin.nonLinearEffects(model, reference, q_ref, G @ v))
        else:
            a_ref = pin.aba(model, reference, q_ref, v, tau)
        errors["aba"] = max(errors["aba"], _relative(forward_dynamics(robot, data, q, v, tau), a_ref))
    # Measured (relative to max(1, |reference|)), worst over all robots: rnea 4.9e-18, crba
    # 3.9e-19, aba 6.5e-16 (all tiago_pro, the mimic solve), potential energy 6.8e-16 (romeo,
    # through the centre of mass); bound 1e-10 (1.5e5x margin).
    assert max(errors.values()) <= 1e-10, f"{path.name}: {errors}"
