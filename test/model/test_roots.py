"""Root joints chosen at load time (fixed, floating, planar): sizes and layouts of q and v,
integration on the manifold, PoE kinematics and Jacobians, RNEA / ABA / CRBA with friction,
free fall, the command line and the simulator's refusal.

The references are Pinocchio models built straight from the URDF file with
``pin.JointModelFreeFlyer()`` / ``pin.JointModelPlanar()`` as root (Pinocchio's own parser,
continuous joints as its cos/sin joints: our q is mapped onto theirs), our own SE(3)
exponential (model/lie.py) for integration, and closed forms (gravity, planar motion).
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from lxml import etree

from youbot_dynamics.cli import main
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import (bias_torque, forward_dynamics, gravity_torque,
                                                 inverse_dynamics, mass_matrix)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.configuration import difference, integrate, neutral, random_configuration
from youbot_dynamics.model.lie import exp_se3, matrix_from_quaternion
from youbot_dynamics.model.robot import Robot, keep_joints, load_robot
from youbot_dynamics.model.screws import (fkin_body, fkin_space, jacobian_body, jacobian_space,
                                          screw_chain)
from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.sim.simulator import Simulator

YOUBOT = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
G1 = (Path(pin.__file__).resolve().parents[4] / "share" / "example-robot-data"
      / "robots" / "g1_description" / "urdf" / "g1_29dof_rev_1_0.urdf")
TIAGO_PRO = G1.parents[2] / "tiago_pro_description" / "robots" / "tiago_pro.urdf"
ROOT_JOINT_MODELS = {"floating": pin.JointModelFreeFlyer, "planar": pin.JointModelPlanar}
GRAVITY = np.array([0.0, 0.0, -9.81])


class Reference:
    """Pinocchio's model of the file with the root joint, and our q mapped onto its q."""

    def __init__(self, path: Path, root: str) -> None:
        self.model = (pin.buildModelFromUrdf(str(path)) if root == "fixed"
                      else pin.buildModelFromUrdf(str(path), ROOT_JOINT_MODELS[root]()))
        self.data = self.model.createData()

    def q(self, robot: Robot, q: np.ndarray) -> np.ndarray:
        out = np.zeros(self.model.nq)
        for joint_id in range(1, self.model.njoints):
            joint, name = self.model.joints[joint_id], self.model.names[joint_id]
            if name == "root_joint":
                out[:robot.root_nq] = q[:robot.root_nq]
                continue
            value = q[robot.root_nq + robot.joint_index(name)]
            # Pinocchio's continuous joints hold (cos, sin) of the angle.
            out[joint.idx_q:joint.idx_q + joint.nq] = (np.cos(value), np.sin(value)) if joint.nq == 2 else value
        return out

    def v_names(self) -> list[str]:
        names = []
        for joint_id in range(1, self.model.njoints):
            joint = self.model.joints[joint_id]
            names += [self.model.names[joint_id]] * joint.nv
        return names


CASES = [(path, root) for path in (YOUBOT, G1) for root in ("fixed", "floating", "planar")]


def case_id(case: tuple[Path, str]) -> str:
    return f"{case[0].stem[:6]}-{case[1]}"


@pytest.fixture(scope="module", params=CASES, ids=case_id)
def loaded(request: pytest.FixtureRequest) -> tuple[Robot, Reference]:
    path, root = request.param
    return load_robot(path, root=root), Reference(path, root)


# ---- sizes and layouts ------------------------------------------------------------------
@pytest.mark.parametrize("root, root_nq, root_nv", [("fixed", 0, 0), ("floating", 7, 6), ("planar", 4, 3)])
def test_sizes_and_names_follow_the_root(root: str, root_nq: int, root_nv: int) -> None:
    robot = load_robot(YOUBOT, root=root)
    reference = Reference(YOUBOT, root)
    assert (robot.root, robot.root_nq, robot.root_nv) == (root, root_nq, root_nv)
    assert robot.nv == reference.model.nv == 11 + root_nv and robot.nq == 11 + root_nq
    assert len(robot.joints) == len(robot.damping) == len(robot.lower) == 11  # URDF joints only
    assert len(robot.q_names) == robot.nq and len(robot.v_names) == robot.nv
    # v's layout is Pinocchio's: the root's DoFs first, then the joints in its order.
    expected = ["root_joint"] * root_nv + list(robot.joint_names)
    assert reference.v_names() == expected
    assert robot.v_names[root_nv:] == robot.joint_names
    assert any(note.startswith(f"root: {root}") for note in robot.fidelity)


def test_unknown_root_is_a_one_line_error() -> None:
    with pytest.raises(UserInputError, match=r"root 'wheeled' is unknown: expected one of fixed, floating, planar$"):
        load_robot(YOUBOT, root="wheeled")


def test_a_urdf_joint_named_like_the_root_joint_leaves_its_name_to_the_file() -> None:
    urdf = """<robot name="clash">
  <link name="base"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <link name="arm"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="root_joint" type="revolute"><parent link="base"/><child link="arm"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""
    assert load_robot(urdf).joint_names == ("root_joint",)
    robot = load_robot(urdf, root="planar")  # the root joint takes another name (test_lenient_urdf)
    assert robot.joint_names == ("root_joint",) and robot.model.names[1] == "root_joint_1"
    assert robot.v_names == ("root_vx", "root_vy", "root_wz", "root_joint")


def test_vector_by_name_fills_the_root_with_its_neutral_pose_and_normalises_it() -> None:
    robot = load_robot(YOUBOT, root="floating")
    q = robot.vector({"root_z": 0.3, "arm_joint_2": 1.0}, of="q")
    np.testing.assert_array_equal(q[:7], [0, 0, 0.3, 0, 0, 0, 1])
    assert q[7 + robot.joint_index("arm_joint_2")] == 1.0
    q = robot.vector([1, 2, 3, 0, 0, 2, 2] + [0] * 11, of="q")
    np.testing.assert_allclose(q[3:7], [0, 0, 2 ** -0.5, 2 ** -0.5], rtol=0, atol=1e-15)  # measured 1.1e-16
    np.testing.assert_array_equal(robot.vector({}, of="v"), np.zeros(17))
    with pytest.raises(UserInputError, match=r"expected 18 values \(nq of a floating root\) in the order root_x"):
        robot.vector(np.zeros(17), of="q")
    with pytest.raises(UserInputError, match=r"expected 17 values \(nv of a floating root\)"):
        robot.vector(np.zeros(18), of="v")
    with pytest.raises(UserInputError, match=r"orientation \(root_qx, root_qy, root_qz, root_qw\) must be"):
        robot.vector({"root_qw": 0.0}, of="q")
    planar = load_robot(YOUBOT, root="planar")
    np.testing.assert_array_equal(planar.vector({"root_x": 1.0}, of="q")[:4], [1, 0, 1, 0])


# ---- configuration: on the manifold -----------------------------------------------------
def _pose(robot: Robot, q: np.ndarray) -> np.ndarray:
    """The root link's pose of q, from our quaternion formula (not Pinocchio)."""
    pose = np.eye(4)
    if robot.root == "floating":
        pose[:3, :3], pose[:3, 3] = matrix_from_quaternion(q[3:7]), q[:3]
    else:
        c, s = q[2], q[3]
        pose[:2, :2], pose[:2, 3] = [[c, -s], [s, c]], q[:2]
    return pose


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_integrate_moves_the_root_along_its_body_twist(root: str) -> None:
    robot = load_robot(YOUBOT, root=root)
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(20):
        # |omega dt| <= 2 sqrt(3) 0.5 < pi: difference takes the shortest way back.
        q, v, dt = random_configuration(robot, rng), rng.uniform(-2.0, 2.0, robot.nv), rng.uniform(0.01, 0.5)
        q1 = integrate(robot, q, v, dt)
        assert q1.shape == (robot.nq,)
        twist = np.zeros(6)  # body twist (omega, v) of the root
        if root == "floating":
            twist[:3], twist[3:] = v[3:6], v[:3]
        else:
            twist[2], twist[3:5] = v[2], v[:2]
        expected = _pose(robot, q) @ exp_se3(twist * dt)
        worst = max(worst, np.abs(_pose(robot, q1) - expected).max())
        np.testing.assert_allclose(q1[robot.root_nq:], q[robot.root_nq:] + v[robot.root_nv:] * dt, rtol=0,
                                   atol=1e-13)  # measured 0; bound 1e-13
        # difference inverts integrate (per unit time): measured 1.4e-13 (planar); bound 1e-9.
        np.testing.assert_allclose(difference(robot, q, q1), v * dt, rtol=0, atol=1e-9)
    assert worst < 1e-12  # measured 1.4e-15; bound 1e-12
    with pytest.raises(UserInputError, match=rf"integrate: q: expected {robot.nq} values"):
        integrate(robot, np.zeros(robot.nv), np.zeros(robot.nv), 0.1)


def test_integrate_with_a_fixed_root_is_q_plus_v_dt() -> None:
    robot = load_robot(YOUBOT)
    q, v = np.linspace(-1, 1, robot.nq), np.linspace(2, -3, robot.nv)
    np.testing.assert_allclose(integrate(robot, q, v, 0.25), q + 0.25 * v, rtol=0, atol=1e-15)  # measured 0
    np.testing.assert_array_equal(neutral(robot), np.zeros(robot.nq))


# ---- kinematics -------------------------------------------------------------------------
def test_poe_kinematics_and_jacobians_match_pinocchio(loaded: tuple[Robot, Reference]) -> None:
    robot, reference = loaded
    model, data = reference.model, reference.data
    rng = np.random.default_rng(7)
    qs = np.array([random_configuration(robot, rng) for _ in range(6)])
    worst = 0.0
    for link in {robot.end_effector, robot.link_names[-1], robot.link_names[len(robot.link_names) // 2],
                 robot.root_link}:
        chain = screw_chain(robot, link)
        frame = model.getFrameId(link, pin.BODY)
        batch = [fkin_space(chain, qs), fkin_body(chain, qs), jacobian_space(chain, qs), jacobian_body(chain, qs)]
        assert batch[2].shape == (6, 6, robot.root_nv + chain.n)
        for k, q in enumerate(qs):
            pin.computeJointJacobians(model, data, reference.q(robot, q))
            pin.updateFramePlacements(model, data)
            pose = data.oMf[frame].homogeneous
            world, local = (pin.getFrameJacobian(model, data, frame, kind) for kind in (pin.WORLD, pin.LOCAL))
            # Pinocchio's rows are (v, omega), ours (omega, v); our columns are chain.columns of v.
            world, local = (np.vstack([j[3:], j[:3]])[:, chain.columns] for j in (world, local))
            single = [fkin_space(chain, q), fkin_body(chain, q), jacobian_space(chain, q), jacobian_body(chain, q)]
            for ours, theirs in zip((*single, *(b[k] for b in batch)), (pose, pose, world, local) * 2):
                worst = max(worst, np.abs(ours - theirs).max(initial=0.0))
    assert worst <= 1e-12  # measured 2.6e-15 (youBot planar); bound 1e-12


def test_root_columns_are_pinocchio_s_velocity_convention() -> None:
    # A planar root at yaw 90 degrees moving with v = (vx, 0, 0) in its own frame moves the
    # end effector along world +y.
    robot = load_robot(YOUBOT, root="planar")
    chain = screw_chain(robot)
    q = robot.vector({"root_cos": 0.0, "root_sin": 1.0}, of="q")
    j = jacobian_space(chain, q)  # rows (omega, v) of the spatial twist
    position = fkin_space(chain, q)[:3, 3]
    velocity = j[3:, 0] + np.cross(j[:3, 0], position)  # of the end effector's origin
    np.testing.assert_allclose(velocity, [0, 1, 0], rtol=0, atol=1e-15)  # measured 0


# ---- dynamics ---------------------------------------------------------------------------
DYNAMICS_CASES = [(G1, "floating"), (G1, "planar"), (YOUBOT, "planar"), (YOUBOT, "floating")]


@pytest.mark.parametrize("path, root", DYNAMICS_CASES, ids=[case_id(c) for c in DYNAMICS_CASES])
def test_rnea_aba_crba_match_pinocchio_s_own_root_models(path: Path, root: str) -> None:
    robot, reference = load_robot(path, root=root), Reference(path, root)
    data = robot.model.createData()
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(5):
        q = random_configuration(robot, rng)
        v, a, tau = (rng.normal(size=robot.nv) for _ in range(3))
        ref_q = reference.q(robot, q)
        pairs = [(inverse_dynamics(robot, data, q, v, a), pin.rnea(reference.model, reference.data, ref_q, v, a)),
                 (forward_dynamics(robot, data, q, v, tau), pin.aba(reference.model, reference.data, ref_q, v, tau)),
                 (mass_matrix(robot, data, q), pin.crba(reference.model, reference.data, ref_q))]
        for ours, theirs in pairs:
            theirs = np.triu(theirs) + np.triu(theirs, 1).T if theirs.ndim == 2 else theirs
            worst = max(worst, np.abs(ours - theirs).max() / max(1.0, np.abs(theirs).max()))
    # measured 0 (bit-identical: the same algorithms on the same tree, reached through a
    # different parse and q layout); bound 1e-10 relative to max(1, |ref|)
    assert worst <= 1e-10


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_friction_acts_on_the_urdf_joints_only(root: str) -> None:
    robot = load_robot(YOUBOT, root=root)
    friction, data = JointFriction.from_urdf(robot), robot.model.createData()
    rng = np.random.default_rng(5)
    q, v, a = random_configuration(robot, rng), rng.normal(size=robot.nv), rng.normal(size=robot.nv)
    added = inverse_dynamics(robot, data, q, v, a, friction) - inverse_dynamics(robot, data, q, v, a)
    joints = v[robot.root_nv:]
    # The URDF's <dynamics damping friction>: viscous plus Coulomb regularised at 0.01 rad/s.
    expected = robot.damping * joints + robot.friction * np.tanh(joints / 1e-2)
    assert np.any(expected != 0.0)
    np.testing.assert_array_equal(added[:robot.root_nv], 0.0)
    np.testing.assert_allclose(added[robot.root_nv:], expected, rtol=0, atol=1e-12)  # measured 4.4e-16
    tau = inverse_dynamics(robot, data, q, v, a, friction)
    np.testing.assert_allclose(forward_dynamics(robot, data, q, v, tau, friction), a, rtol=0, atol=1e-9)
    # measured 1.4e-13 on the round trip (youBot planar); bound 1e-9


@pytest.mark.parametrize("path", [G1, YOUBOT], ids=lambda p: p.stem[:6])
def test_free_fall_from_rest_accelerates_the_root_by_g(path: Path) -> None:
    robot = load_robot(path, root="floating")
    data = robot.model.createData()
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(5):
        q = random_configuration(robot, rng)
        a = forward_dynamics(robot, data, q, np.zeros(robot.nv), np.zeros(robot.nv))
        rotation = matrix_from_quaternion(q[3:7])
        worst = max(worst, np.abs(rotation @ a[:3] - GRAVITY).max(), np.abs(a[3:]).max())
    assert worst <= 1e-12  # measured 3.0e-14 (g1); bound 1e-12: the base falls at g, nothing turns


def test_gravity_torque_on_a_floating_root_holds_up_the_whole_weight() -> None:
    robot = load_robot(G1, root="floating")
    mass = sum(float(m.get("value")) for m in etree.parse(str(G1)).getroot().iterfind("link/inertial/mass"))
    q = random_configuration(robot, np.random.default_rng(4))
    holding = gravity_torque(robot, robot.model.createData(), q)
    # The root's entries are the body-frame wrench (f, n) that holds the robot: f = -m R^T g.
    weight = mass * 9.81
    np.testing.assert_allclose(matrix_from_quaternion(q[3:7]) @ holding[:3], -mass * GRAVITY, rtol=0,
                               atol=1e-12 * weight)  # measured 7.2e-14 N = 2.2e-16 weight; bound 1e-12 weight


def test_wrong_sizes_name_nq_and_nv() -> None:
    robot = load_robot(YOUBOT, root="floating")
    data = robot.model.createData()
    zeros = np.zeros(robot.nv)
    with pytest.raises(UserInputError, match=r"^q: expected 18 values \(q of robot 'youbot' with a floating root"):
        forward_dynamics(robot, data, zeros, zeros, zeros)
    with pytest.raises(UserInputError, match=r"^a: expected 17 values \(v of robot"):
        inverse_dynamics(robot, data, neutral(robot), zeros, np.zeros(robot.nq))
    with pytest.raises(UserInputError, match=r"^q: expected 18 values"):
        mass_matrix(robot, data, zeros)
    with pytest.raises(UserInputError, match=r"^q: expected 18 values"):
        gravity_torque(robot, data, zeros)
    with pytest.raises(UserInputError, match=r"^v: expected 17 values"):
        bias_torque(robot, data, neutral(robot), np.zeros(robot.nq))
    with pytest.raises(UserInputError, match=r"needs the robot's configuration q of nq = 18"):
        fkin_space(screw_chain(robot), zeros)


def test_locking_joints_keeps_the_root() -> None:
    robot = keep_joints(load_robot(YOUBOT, root="floating"), [f"arm_joint_{i}" for i in range(1, 6)],
                        {"arm_joint_1": 0.0, "gripper_finger_joint_l": 0.01})
    assert (robot.root, robot.nq, robot.nv) == ("floating", 12, 11)
    rng = np.random.default_rng(2)
    q = random_configuration(robot, rng)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    link = "gripper_finger_link_l"
    np.testing.assert_allclose(fkin_space(screw_chain(robot, link), q),
                               data.oMf[robot.model.getFrameId(link, pin.BODY)].homogeneous, rtol=0,
                               atol=1e-12)  # measured 1.0e-15; bound 1e-12


def test_locking_a_mimic_primary_with_a_planar_root_locks_its_mimics_and_keeps_the_root() -> None:
    robot = load_robot(TIAGO_PRO, root="planar")
    locked = keep_joints(robot, [n for n in robot.joint_names if n != "gripper_left_finger_joint"],
                         {"gripper_left_finger_joint": 0.2})
    assert (locked.root, locked.nq, locked.nv) == ("planar", robot.nq - 1, robot.nv - 1)
    assert {m.primary for m in locked.mimic.values()} == {"gripper_right_finger_joint"}
    assert all(locked.locked[name] == pytest.approx(m.multiplier * 0.2 + m.offset)
               for name, m in robot.mimic.items() if m.primary == "gripper_left_finger_joint")
    q = random_configuration(locked, np.random.default_rng(4))
    data = locked.model.createData()
    pin.framesForwardKinematics(locked.model, data, q)
    for link in ("gripper_left_fingertip_left_link", "gripper_right_fingertip_left_link"):
        np.testing.assert_allclose(fkin_space(screw_chain(locked, link), q),
                                   data.oMf[locked.frame_id(link)].homogeneous, rtol=0,
                                   atol=1e-12)  # measured 2.8e-15; bound 1e-12 (360x margin)


# ---- command line -----------------------------------------------------------------------
def _json(capsys: pytest.CaptureFixture[str], argv: list[str]) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_cli_info_fk_jacobian_with_a_root(capsys: pytest.CaptureFixture[str]) -> None:
    record = _json(capsys, ["info", "--root", "planar"])
    assert (record["root"], record["nq"], record["nv"]) == ("planar", 15, 14)
    assert record["q_names"][:4] == ["root_x", "root_y", "root_cos", "root_sin"]
    assert "root: planar; nq = 15, nv = 14" in (main(["info", "--root", "planar"]), capsys.readouterr().out)[1]
    # fk with a planar root at (x, y, yaw) = (1, 2, 90 deg): the fixed-root pose turned and moved.
    fixed = np.array(_json(capsys, ["fk", "--q", "arm_joint_2=0.7"])["position"])
    moved = _json(capsys, ["fk", "--root", "planar", "--q", "root_x=1,root_y=2,root_cos=0,root_sin=1,arm_joint_2=0.7"])
    assert moved["reference_frame"] == "world"
    np.testing.assert_allclose(moved["position"], [1 - fixed[1], 2 + fixed[0], fixed[2]], rtol=0,
                               atol=1e-12)  # measured 0; bound 1e-12
    robot = load_robot(YOUBOT, root="floating")
    jacobian = _json(capsys, ["jacobian", "--root", "floating", "--kind", "world", "--q", "root_qz=1,arm_joint_3=-1"])
    assert jacobian["columns"] == list(robot.v_names)
    q = robot.vector({"root_qz": 1.0, "arm_joint_3": -1.0}, of="q")
    reference = pin.computeFrameJacobian(robot.model, robot.model.createData(), q,
                                         robot.model.getFrameId(robot.end_effector, pin.BODY), pin.WORLD)
    np.testing.assert_allclose(jacobian["matrix"], reference, rtol=0, atol=1e-12)  # measured 0


def test_cli_dynamics_with_a_floating_root(capsys: pytest.CaptureFixture[str]) -> None:
    record = _json(capsys, ["fd", "--root", "floating", "--q", "root_qx=1,root_qw=0"])
    assert list(record["q"])[:7] == ["root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz", "root_qw"]
    # Upside down (180 deg about x) at rest: the body's own z points down, gravity along +z body.
    a = record["a"]
    np.testing.assert_allclose([a["root_vx"], a["root_vy"], a["root_vz"]], [0, 0, 9.81], rtol=0,
                               atol=1e-12)  # measured 1.8e-15; bound 1e-12
    assert len(record["a"]) == 17 and record["root"] == "floating"
    text = (main(["id", "--root", "floating"]), capsys.readouterr().out)[1]
    assert "q (floating root): root_x=0" in text and "root_wz" in text
    assert main(["id", "--root", "floating", "--q", "0,0,0"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "expected 18 values (nq of a floating root)" in lines[0]


# ---- the simulator refuses what it would integrate wrongly --------------------------------
def test_simulator_refuses_a_movable_root() -> None:
    scene = dataclasses.replace(load_scene("arm_swing"), robot=load_robot(YOUBOT, root="planar"))
    with pytest.raises(UserInputError, match=r"arm_swing.yaml: robot 'youbot' has a planar root \(nq = 15, nv = 14\)"):
        Simulator(scene)
