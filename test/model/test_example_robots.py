"""Acceptance: every non-empty URDF that the PyPI package example-robot-data ships loads, its
PoE kinematics equal Pinocchio's, and its dynamics equal those of a Pinocchio model built
straight from the same file.

The reference model is ``pin.buildModelFromUrdf(path)``: continuous joints as Pinocchio's
(cos, sin) joints, no mimic coupling and a free-flyer for a <floating> joint (locked at its
origin with buildReducedModel, as our loader fixes it). A mimic joint follows
q_m = k q_p + o, so v_m = k v_p and a_m = k a_p: with G = d q_reference / d q (one row per
reference joint), our RNEA is G^T RNEA_ref(q_ref, G v, G a) and our mass matrix G^T M_ref G.

A few robots (the g1 humanoid, tiago_pro with its mimic fingers, the packaged youBot) are
also loaded with a floating or planar root and compared with Pinocchio models built from the
same file with the same root joint (``pin.JointModelFreeFlyer`` / ``pin.JointModelPlanar``):
the one above (G then passes the root's velocities through unchanged) and, for the mimic
robot, Pinocchio's own mimic model (``mimic=True``) with that root.
"""
from __future__ import annotations

import importlib.metadata
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.dynamics.rigid_body import (forward_dynamics, inverse_dynamics, mass_matrix,
                                                 potential_energy)
from youbot_dynamics.errors import SingularMassMatrixError
from youbot_dynamics.model.configuration import random_configuration
from youbot_dynamics.model.robot import Robot, load_robot
from youbot_dynamics.model.screws import fkin_space, jacobian_body, jacobian_space, screw_chain

N_CONFIGURATIONS = 3
ROOT_JOINTS = {"floating": pin.JointModelFreeFlyer, "planar": pin.JointModelPlanar}


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
    """Joints uniform in [-1, 1] (rad or m); a movable root anywhere in a 2 m cube (z = 0
    planar) with a uniformly random orientation."""
    rng = np.random.default_rng(seed)
    joints = rng.uniform(-1.0, 1.0, (N_CONFIGURATIONS, len(robot.joints)))
    roots = [random_configuration(robot, rng)[:robot.root_nq] for _ in range(N_CONFIGURATIONS)]
    return np.hstack([np.reshape(roots, (N_CONFIGURATIONS, robot.root_nq)), joints])


def _kinematics_error(robot: Robot) -> float:
    """Worst difference between our PoE FK and space / body Jacobians and Pinocchio's frame
    placement and WORLD / LOCAL Jacobians (on ``chain.columns``; zero elsewhere) over random
    configurations, for every leaf link (every joint moves one) and every link that shares
    its name with a joint (frame look-up by type)."""
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
            others = np.setdiff1d(np.arange(robot.nv), chain.columns)
            worst = max(worst, np.abs(space[k] - data.oMf[frame].homogeneous).max(),
                        np.abs(j_space[k] - _swap(world)[:, chain.columns]).max(initial=0.0),
                        np.abs(j_body[k] - _swap(local)[:, chain.columns]).max(initial=0.0),
                        np.abs(world[:, others]).max(initial=0.0))
    return worst


@pytest.mark.parametrize("path", URDFS, ids=_id)
def test_poe_kinematics_equal_pinocchio(robots: dict[Path, Robot], path: Path) -> None:
    worst = _kinematics_error(robots[path])
    # Measured at most 2.7e-15 (icub_reduced) over all robots; bound 1e-12 (375x margin).
    assert worst <= 1e-12, f"{path.name}: {worst:.3g}"


def _reference(path: Path, robot: Robot, mimic: bool = False) -> tuple[pin.Model, np.ndarray]:
    """pin.buildModelFromUrdf of the file with the robot's root joint (Pinocchio's mimic
    joints with ``mimic``; <floating> joints locked at their origin) and G = d v_reference /
    d v (nv_ref x nv): the identity on the root's DoFs, a joint's multiplier on its primary."""
    root = () if robot.root == "fixed" else (ROOT_JOINTS[robot.root](),)
    model = pin.buildModelFromUrdf(str(path), *root, mimic=mimic)
    first = 1 + len(root)  # joint 0 is the universe, 1 the root joint if there is one
    floating = [j for j in range(first, model.njoints) if model.names[j] not in robot.joint_names
                and model.names[j] not in robot.mimic]
    if floating:
        model = pin.buildReducedModel(model, floating, pin.neutral(model))
    coupling = np.zeros((model.nv, robot.nv))
    coupling[:robot.root_nv, :robot.root_nv] = np.eye(robot.root_nv)
    for j in range(first, model.njoints):
        name, row = model.names[j], model.joints[j].idx_v
        if not model.joints[j].nv:
            continue  # a mimic joint of the reference: no velocity of its own
        relation = robot.mimic.get(name)
        if relation is None:
            coupling[row, robot.root_nv + robot.joint_index(name)] = 1.0
        else:
            coupling[row, robot.root_nv + robot.joint_index(relation.primary)] = relation.multiplier
    return model, coupling


def _reference_q(model: pin.Model, robot: Robot, q: np.ndarray) -> np.ndarray:
    """The reference configuration: the root's coordinates as ours (same layout), each
    joint's angle, (cos, sin) for a continuous one."""
    q_ref = np.empty(model.nq)
    q_ref[:robot.root_nq] = q[:robot.root_nq]
    for j in range(1 + (robot.root != "fixed"), model.njoints):
        name, joint = model.names[j], model.joints[j]
        if not joint.nq:
            continue  # a mimic joint of the reference reads its primary's q
        relation = robot.mimic.get(name)
        joint_q = q[robot.root_nq:]
        angle = joint_q[robot.joint_index(name)] if relation is None else \
            relation.multiplier * joint_q[robot.joint_index(relation.primary)] + relation.offset
        q_ref[joint.idx_q:joint.idx_q + joint.nq] = (np.cos(angle), np.sin(angle)) if joint.nq == 2 else angle
    return q_ref


def _relative(ours: np.ndarray, reference: np.ndarray) -> float:
    return float(np.abs(ours - reference).max(initial=0.0) / max(1.0, np.abs(reference).max(initial=0.0)))


def _dynamics_errors(path: Path, robot: Robot, mimic: bool = False) -> dict[str, float]:
    """Worst relative differences (to max(1, |reference|)) of our RNEA, CRBA, potential
    energy and forward dynamics from the reference of :func:`_reference` over random states;
    a robot with a singular mass matrix must refuse forward dynamics instead. Pinocchio 4.1
    refuses aba and the potential energy of mimic models: with ``mimic`` the reference
    accelerations come from its CRBA and nonLinearEffects, and the energy is not compared."""
    model, G = _reference(path, robot, mimic)
    data, reference = robot.model.createData(), model.createData()
    rng = np.random.default_rng(2)
    errors = dict.fromkeys(("rnea", "crba", "aba") + (() if mimic else ("potential",)), 0.0)
    for q in _configurations(robot, 3):
        v, a, tau = rng.uniform(-1.0, 1.0, (3, robot.nv))
        q_ref = _reference_q(model, robot, q)
        tau_ref = G.T @ pin.rnea(model, reference, q_ref, G @ v, G @ a)
        errors["rnea"] = max(errors["rnea"], _relative(inverse_dynamics(robot, data, q, v, a), tau_ref))
        upper = pin.crba(model, reference, q_ref)
        m_ref = G.T @ (np.triu(upper) + np.triu(upper, 1).T) @ G
        errors["crba"] = max(errors["crba"], _relative(mass_matrix(robot, data, q), m_ref))
        if not mimic:
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
    return errors


@pytest.mark.parametrize("path", URDFS, ids=_id)
def test_dynamics_equal_pinocchio_from_the_file(robots: dict[Path, Robot], path: Path) -> None:
    robot = robots[path]
    if not robot.nv:
        return
    errors = _dynamics_errors(path, robot)
    # Measured (relative to max(1, |reference|)), worst over all robots: rnea 4.9e-18, crba
    # 3.9e-19, aba 6.5e-16 (all tiago_pro, the mimic solve), potential energy 6.8e-16 (romeo,
    # through the centre of mass); bound 1e-10 (1.5e5x margin).
    assert max(errors.values()) <= 1e-10, f"{path.name}: {errors}"


G1 = ROOT / "g1_description" / "urdf" / "g1_29dof_rev_1_0.urdf"
TIAGO_PRO = ROOT / "tiago_pro_description" / "robots" / "tiago_pro.urdf"
ROOTED = [(G1, "floating"), (G1, "planar"), (TIAGO_PRO, "planar"), (TIAGO_PRO, "floating"),
          (default_urdf(), "planar")]


@pytest.mark.parametrize(("path", "root"), ROOTED, ids=[f"{p.stem}-{r}" for p, r in ROOTED])
def test_rooted_variants_equal_pinocchio_with_the_same_root(path: Path, root: str) -> None:
    robot = load_robot(path, root=root)
    fixed = load_robot(path)
    assert (robot.nq, robot.nv) == (fixed.nq + robot.root_nq, fixed.nv + robot.root_nv)
    assert robot.mimic == fixed.mimic and robot.joint_names == fixed.joint_names
    kinematics = _kinematics_error(robot)
    errors = _dynamics_errors(path, robot)
    if robot.mimic:  # tiago_pro: also Pinocchio's own mimic model with the same root
        errors |= {f"{name} (pin mimic)": e for name, e in _dynamics_errors(path, robot, mimic=True).items()}
    # Measured: kinematics at most 3.2e-15 (tiago_pro planar; bound 1e-12, 310x margin);
    # dynamics at most 8.5e-16 (tiago_pro floating, potential energy through the centre of
    # mass; bound 1e-10, 1.2e5x margin). g1, the youBot and Pinocchio's own mimic model give
    # 0: the same Pinocchio algorithms on the same tree, so these check the root's q and v
    # layout and the mimic coupling (a quaternion stored (w, x, y, z) gives 2.2 in RNEA).
    assert kinematics <= 1e-12, f"{path.name} {root}: {kinematics:.3g}"
    assert max(errors.values()) <= 1e-10, f"{path.name} {root}: {errors}"


def _yourdfpy_joint(joint) -> tuple:
    """(name, type, parent, child, origin, axis) of a yourdfpy joint, with the loader's
    conventions: floating and planar joints are fixed; a missing origin is the identity, a
    missing or zero axis is x."""
    axis = np.array([1.0, 0.0, 0.0]) if joint.axis is None else np.asarray(joint.axis, float)
    axis = axis / np.linalg.norm(axis) if np.linalg.norm(axis) > 0 else np.array([1.0, 0.0, 0.0])
    kind = "fixed" if joint.type in ("floating", "planar") else joint.type
    origin = np.eye(4) if joint.origin is None else np.asarray(joint.origin, float)
    return joint.name, kind, joint.parent, joint.child, origin, axis


def _yourdfpy_limits(joint) -> tuple:
    """(lower, upper, velocity, effort, damping, friction) as the loader reads them: a bound
    the file leaves out is infinite, a continuous joint unbounded, damping and friction 0."""
    limit, dynamics = joint.limit, joint.dynamics

    def value(element, attribute: str, default: float) -> float:
        got = None if element is None else getattr(element, attribute)
        return default if got is None else float(got)

    unbounded = joint.type == "continuous"
    return (-np.inf if unbounded else value(limit, "lower", -np.inf),
            np.inf if unbounded else value(limit, "upper", np.inf),
            value(limit, "velocity", np.inf), value(limit, "effort", np.inf),
            value(dynamics, "damping", 0.0), value(dynamics, "friction", 0.0))


@pytest.mark.parametrize("path", [Path(default_urdf())] + URDFS, ids=lambda p: "youbot" if p == Path(default_urdf())
                         else _id(p))
def test_tree_and_limits_equal_yourdfpys_reading(robots: dict[Path, Robot], path: Path) -> None:
    """The loader reads the kinematic tree and the joint limits from the XML it checks
    (lxml), not through yourdfpy (whose trimesh import cost 0.9 s of every start-up);
    yourdfpy's reading of the same file is the independent reference."""
    import yourdfpy
    robot = robots[path] if path in robots else load_robot(path)
    urdf = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False,
                              build_collision_scene_graph=False, load_collision_meshes=False)
    theirs = {j.name: _yourdfpy_joint(j) for j in urdf.robot.joints}
    assert {j.name for j in robot.tree} == set(theirs)
    for ours in robot.tree:
        name, kind, parent, child, origin, axis = theirs[ours.name]
        assert (ours.type, ours.parent, ours.child) == (kind, parent, child), ours.name
        # measured at most 6.7e-16 (rpy -> matrix by Pinocchio against yourdfpy's); bound 1e-12
        np.testing.assert_allclose(ours.origin, origin, atol=1e-12, err_msg=ours.name)
        np.testing.assert_allclose(ours.axis, axis, atol=1e-12, err_msg=ours.name)
    for joint in robot.joints:
        limits = (joint.lower, joint.upper, joint.velocity_limit, joint.effort_limit, joint.damping, joint.friction)
        assert limits == _yourdfpy_limits(urdf.joint_map[joint.name]), joint.name
