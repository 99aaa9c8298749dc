"""Screw axes from the URDF and product-of-exponentials kinematics against the seed exercise
(youbot_facts.md section 5) and Pinocchio's frame placements and frame Jacobians; the
compiled loops (running transform held in registers, called through their entry points)
against the previous implementation, to the bit, and the direct path (one float64
configuration) against the general one."""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from numba import njit

from youbot_dynamics import default_urdf
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.lie import exp_se3
from youbot_dynamics.model.robot import Robot, keep_joints, load_robot, lock_joints
from youbot_dynamics.model.screws import (ScrewChain, fkin_body, fkin_space, jacobian_body, jacobian_space,
                                          screw_chain)

N_CONFIGURATIONS = 1000
TOLERANCE = 1e-12

# ---- the seed's exercise, written as a URDF ----------------------------------------------
L1, L2, L3, L4, L5 = 1.0, 2.0, 2.0, 1.0, 1.5
W2, W3, W4, W5 = 1.0, 1.0, 1.0, 0.5
SEED_S = np.array([[0, 0, 1, 0, 0, 0],
                   [1, 0, 0, 0, L1, 0],
                   [1, 0, 0, 0, L1 + L2, 0],
                   [1, 0, 0, 0, L1 + L2 + L3, 0],
                   [0, 0, 1, 0, W2 - W3 + W4 - W5, 0],
                   [0, 0, 0, 1, 0, 0]], dtype=float).T
SEED_M = np.array([[1, 0, 0, -W2 + W3 - W4 + W5], [0, 0, -1, 0],
                   [0, 1, 0, L1 + L2 + L3 + L4 + L5], [0, 0, 0, 1]], dtype=float)
SEED_THETA = (math.pi, -math.pi / 4, -math.pi / 4, -1.057, 0.0, 0.0)
SEED_X, SEED_Y = 0.499999999999987, -4.64293092352121  # printed by the seed


def _link(name: str) -> str:
    return (f'<link name="{name}"><inertial><mass value="1"/>'
            '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>')


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, rpy: str = "0 0 0",
           axis: str = "1 0 0") -> str:
    limit = '<limit lower="-10" upper="10" effort="10" velocity="1"/>' if kind in ("revolute", "prismatic") else ""
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>{limit}</joint>')


def seed_urdf() -> str:
    """The seed's 6-joint chain: revolutes about z, x, x, x, z, a prismatic along x; the
    last joint frame is turned +90 degrees about x so that M has the seed's rotation."""
    joints = [("j1", "revolute", "0 0 0", "0 0 0", "0 0 1"),
              ("j2", "revolute", f"0 0 {L1}", "0 0 0", "1 0 0"),
              ("j3", "revolute", f"0 0 {L2}", "0 0 0", "1 0 0"),
              ("j4", "revolute", f"0 0 {L3}", "0 0 0", "1 0 0"),
              ("j5", "revolute", f"{-W2 + W3 - W4 + W5} 0 {L4}", "0 0 0", "0 0 1"),
              ("j6", "prismatic", f"0 0 {L5}", f"{math.pi / 2!r} 0 0", "1 0 0")]
    links = [f"l{i}" for i in range(7)]
    body = [_link(name) for name in links]
    body += [_joint(name, kind, links[i], links[i + 1], xyz, rpy, axis)
             for i, (name, kind, xyz, rpy, axis) in enumerate(joints)]
    return f'<robot name="seed">{"".join(body)}</robot>'


def offset_arm_urdf() -> str:
    """A second robot unlike the youBot: 6 moving joints with offsets, a prismatic joint, a
    continuous joint, a skew axis, non-trivial rpy origins, fixed joints in between and a
    side branch."""
    links = ["base", "a1", "a2", "a3", "a3b", "a4", "a5", "a6", "tool", "side"]
    joints = [
        ("q1", "revolute", "base", "a1", "0.05 -0.02 0.3", "0.1 -0.2 0.3", "0 0 1"),
        ("q2", "revolute", "a1", "a2", "0.1 0.07 0.02", "1.2 0.4 -0.7", "0 1 0"),
        ("q3", "prismatic", "a2", "a3", "0.4 -0.05 0.1", "-0.3 0.8 0.2", "0.6 0 0.8"),
        ("fix", "fixed", "a3", "a3b", "0.02 0.03 -0.04", "0.5 -1.1 2.0", "1 0 0"),
        ("q4", "revolute", "a3b", "a4", "0.3 0.01 -0.06", "-1.4 0.2 0.9", "1 0 0"),
        ("q5", "continuous", "a4", "a5", "0 0.12 0.25", "0.7 0.7 -0.7", "0 0 1"),
        ("q6", "revolute", "a5", "a6", "0.08 0 0.05", "2.5 -0.3 1.0", "1 1 1"),
        ("tool_joint", "fixed", "a6", "tool", "0.01 0.02 0.15", "0.3 0.2 0.1", "1 0 0"),
        ("side_joint", "revolute", "a2", "side", "0 0.2 0", "0 0 0.5", "0 0 1"),
    ]
    body = [_link(name) for name in links]
    body += [_joint(*joint) for joint in joints]
    return f'<robot name="offset_arm">{"".join(body)}</robot>'


# ---- helpers -----------------------------------------------------------------------------
def _swap(jacobian: np.ndarray) -> np.ndarray:
    """Pinocchio rows (v, omega) -> ours (omega, v)."""
    return np.vstack([jacobian[3:], jacobian[:3]])


def _max_errors(robot: Robot, link: str, configurations: np.ndarray) -> dict[str, float]:
    """Largest deviations of our FK and Jacobians from Pinocchio's over the configurations."""
    chain = screw_chain(robot, link)
    data = robot.model.createData()
    frame = robot.frame_id(link)
    space, body = fkin_space(chain, configurations), fkin_body(chain, configurations)
    j_space, j_body = jacobian_space(chain, configurations), jacobian_body(chain, configurations)
    others = np.setdiff1d(np.arange(robot.nv), chain.joints)
    errors = dict.fromkeys(("fkin_space", "fkin_body", "jacobian_space", "jacobian_body", "others"), 0.0)
    for k, q in enumerate(configurations):
        pin.framesForwardKinematics(robot.model, data, q)
        placement = data.oMf[frame].homogeneous
        world = _swap(pin.computeFrameJacobian(robot.model, data, q, frame, pin.WORLD))
        local = _swap(pin.computeFrameJacobian(robot.model, data, q, frame, pin.LOCAL))
        for key, ours, reference in (("fkin_space", space[k], placement), ("fkin_body", body[k], placement),
                                     ("jacobian_space", j_space[k], world[:, chain.joints]),
                                     ("jacobian_body", j_body[k], local[:, chain.joints])):
            errors[key] = max(errors[key], float(np.abs(ours - reference).max(initial=0.0)))
        # Joints outside the chain do not move the link.
        errors["others"] = max(errors["others"], float(np.abs(world[:, others]).max(initial=0.0)))
    return errors


def _random_configurations(robot: Robot, seed: int) -> np.ndarray:
    """Uniform in [-pi, pi] rad for rotating joints, [-0.5, 0.5] m for prismatic ones."""
    scale = np.array([0.5 if j.type == "prismatic" else math.pi for j in robot.joints])
    return np.random.default_rng(seed).uniform(-1.0, 1.0, (N_CONFIGURATIONS, robot.nv)) * scale


@pytest.fixture(scope="module")
def youbot() -> Robot:
    return load_robot(default_urdf())


# ---- the seed exercise -------------------------------------------------------------------
def test_seed_exercise_screw_axes_and_home() -> None:
    robot = load_robot(seed_urdf())
    chain = screw_chain(robot)
    assert chain.link == "l6" and chain.joint_names == ("j1", "j2", "j3", "j4", "j5", "j6")
    np.testing.assert_allclose(chain.S, SEED_S, rtol=0, atol=1e-15)
    np.testing.assert_allclose(chain.M, SEED_M, rtol=0, atol=1e-15)


def test_seed_exercise_end_effector_position() -> None:
    robot = load_robot(seed_urdf())
    chain = screw_chain(robot)
    q = np.array(SEED_THETA)
    for transform in (fkin_space(chain, q), fkin_body(chain, q)):
        # The seed prints 15 significant digits of its own (rounded) computation.
        assert abs(transform[0, 3] - SEED_X) < 1e-13
        assert abs(transform[1, 3] - SEED_Y) < 1e-13
    # The seed's own formula with the seed's S and M, through exp_se3.
    reference = SEED_M
    for i in reversed(range(6)):
        reference = exp_se3(SEED_S[:, i] * SEED_THETA[i]) @ reference
    np.testing.assert_allclose(fkin_space(chain, q), reference, rtol=0, atol=1e-14)
    assert abs(fkin_space(chain, q)[0, 3] - 0.5) < 1e-14  # exact: -W2+W3-W4+W5 rotated by pi


def test_seed_exercise_matches_pinocchio() -> None:
    robot = load_robot(seed_urdf())
    errors = _max_errors(robot, "l6", _random_configurations(robot, 1))
    assert max(errors.values()) < TOLERANCE, errors


# ---- agreement with Pinocchio ------------------------------------------------------------
@pytest.mark.parametrize("link", ["gripper_palm_link", "arm_link_3", "gripper_finger_link_l",
                                  "gripper_finger_link_r", "wheel_link_fl", "wheel_link_br"])
def test_youbot_matches_pinocchio(youbot: Robot, link: str) -> None:
    errors = _max_errors(youbot, link, _random_configurations(youbot, 2))
    assert max(errors.values()) < TOLERANCE, errors


@pytest.mark.parametrize("link", ["tool", "a3b", "side"])
def test_offset_arm_matches_pinocchio(link: str) -> None:
    robot = load_robot(offset_arm_urdf())
    errors = _max_errors(robot, link, _random_configurations(robot, 3))
    assert max(errors.values()) < TOLERANCE, errors


def test_offset_arm_chain_structure() -> None:
    robot = load_robot(offset_arm_urdf())
    chain = screw_chain(robot, "tool")
    assert chain.joint_names == ("q1", "q2", "q3", "q4", "q5", "q6")
    assert [robot.joint_names[i] for i in chain.joints] == list(chain.joint_names)
    np.testing.assert_allclose(np.linalg.norm(chain.S[:3, 2]), 0.0)  # prismatic: omega = 0
    np.testing.assert_allclose(np.linalg.norm(chain.S[3:, 2]), 1.0)
    np.testing.assert_allclose(np.linalg.norm(chain.S[:3, [0, 1, 3, 4, 5]], axis=0), 1.0)
    # Side branch: only q1, q2 and its own joint.
    assert screw_chain(robot, "side").joint_names == ("q1", "q2", "side_joint")


def test_root_link_has_no_joints(youbot: Robot) -> None:
    chain = screw_chain(youbot, youbot.root_link)
    q = np.zeros((3, youbot.nv))
    np.testing.assert_array_equal(fkin_space(chain, q), np.broadcast_to(np.eye(4), (3, 4, 4)))
    assert jacobian_space(chain, q).shape == (3, 6, 0)


def test_body_axes_and_single_configuration(youbot: Robot) -> None:
    chain = screw_chain(youbot)
    assert chain.link == "gripper_palm_link"
    assert chain.joint_names == tuple(f"arm_joint_{i}" for i in range(1, 6))
    q = _random_configurations(youbot, 4)[:5]
    for k in range(5):  # one configuration at a time gives the batch's values
        np.testing.assert_allclose(fkin_space(chain, q[k]), fkin_space(chain, q)[k], rtol=0, atol=1e-15)
        np.testing.assert_allclose(jacobian_body(chain, q[k]), jacobian_body(chain, q)[k], rtol=0, atol=1e-15)
    with pytest.raises(UserInputError, match="11 values"):
        fkin_space(chain, np.zeros(5))


def test_locked_robot_keeps_screw_kinematics(youbot: Robot) -> None:
    """Locked joints are folded into the fixed part: same pose as the full robot."""
    locked_values = {"arm_joint_1": 0.7, "arm_joint_4": 1.1, "gripper_finger_joint_l": 0.004}
    moving = [n for n in youbot.joint_names if n not in locked_values]
    reduced = keep_joints(youbot, moving, locked_values)
    q_reduced = _random_configurations(reduced, 5)[:50]
    q_full = np.zeros((50, youbot.nv))
    for i, name in enumerate(reduced.joint_names):
        q_full[:, youbot.joint_index(name)] = q_reduced[:, i]
    for name, value in locked_values.items():
        q_full[:, youbot.joint_index(name)] = value
    for link in ("gripper_palm_link", "gripper_finger_link_l"):
        np.testing.assert_allclose(fkin_space(screw_chain(reduced, link), q_reduced),
                                   fkin_space(screw_chain(youbot, link), q_full), rtol=0, atol=1e-14)
        assert max(_max_errors(reduced, link, q_reduced).values()) < TOLERANCE


# ---- the singular, fully stretched youBot --------------------------------------------------
def test_stretched_youbot_jacobians_rank_four(youbot: Robot) -> None:
    """Arm straight up (joints 2, 3, 4 undo the origin pitches 65, 146, -102.5 degrees): the
    three pitch axes lie in one plane through one vertical line, so they span only 2 twist
    directions; with joints 1 and 5 (vertical, parallel, not collinear) the 5-joint
    Jacobian has rank 4 of 5, and the finger's 6-joint chain too (its slide is horizontal,
    already spanned)."""
    stretched = youbot.vector({"arm_joint_1": 2.9496, "arm_joint_2": math.radians(65),
                               "arm_joint_3": math.radians(-146), "arm_joint_4": math.radians(102.5),
                               "arm_joint_5": 2.9234})
    chain = screw_chain(youbot)
    pose = fkin_space(chain, stretched)
    np.testing.assert_allclose(pose[:3, 2], [0, 0, 1], atol=1e-15)  # palm z straight up
    for link, n in (("gripper_palm_link", 5), ("gripper_finger_link_l", 6)):
        chain = screw_chain(youbot, link)
        for jacobian in (jacobian_space(chain, stretched), jacobian_body(chain, stretched)):
            assert jacobian.shape == (6, n) and np.all(np.isfinite(jacobian))
            singular = np.linalg.svd(jacobian, compute_uv=False)
            assert singular[3] > 1e-2 and singular[4] < 1e-12, singular
        assert max(_max_errors(youbot, link, stretched[None, :]).values()) < TOLERANCE
    generic = np.linalg.svd(jacobian_space(screw_chain(youbot), stretched + 0.3), compute_uv=False)
    assert generic[4] > 1e-3


# ---- mimic joints --------------------------------------------------------------------------
MIMIC = {"q4": ("q2", -2.0, 0.3), "q6": ("q1", 0.5, -0.1), "side_joint": ("q5", 1.5, 0.2)}


def mimic_arm_urdf() -> str:
    """The offset arm with q4 and q6 mimicking joints of their own chain and the side branch's
    joint mimicking q5, which is not in the side chain."""
    text = offset_arm_urdf()
    for joint, (primary, multiplier, offset) in MIMIC.items():
        start = text.index(f'<joint name="{joint}"')
        end = text.index("</joint>", start)
        text = text[:end] + f'<mimic joint="{primary}" multiplier="{multiplier}" offset="{offset}"/>' + text[end:]
    return text


def test_mimic_chains_follow_their_primaries() -> None:
    robot = load_robot(mimic_arm_urdf())
    assert robot.joint_names == ("q1", "q2", "q3", "q5")
    assert {name: (m.primary, m.multiplier, m.offset) for name, m in robot.mimic.items()} == MIMIC
    tool, side = screw_chain(robot, "tool"), screw_chain(robot, "side")
    assert tool.joint_names == ("q1", "q2", "q3", "q5") and tool.n == 6
    assert tool.axis_names == ("q1", "q2", "q3", "q4", "q5", "q6")
    assert side.joint_names == ("q1", "q2", "q5") and side.axis_names == ("q1", "q2", "side_joint")
    with pytest.raises(UserInputError, match="'q4' .* mimics 'q2'"):
        robot.joint_index("q4")


@pytest.mark.parametrize("link", ["tool", "a3b", "side"])
def test_mimic_arm_matches_pinocchio_mimic_joints(link: str) -> None:
    """PoE with q_mimic = multiplier q_primary + offset equals Pinocchio's mimic joints, and
    the free offset arm (every joint independent) at the expanded configuration."""
    robot, free = load_robot(mimic_arm_urdf()), load_robot(offset_arm_urdf())
    configurations = _random_configurations(robot, 6)
    errors = _max_errors(robot, link, configurations)
    assert max(errors.values()) < TOLERANCE, errors
    expanded = np.zeros((len(configurations), free.nv))
    for name in free.joint_names:
        primary, multiplier, offset = MIMIC.get(name, (name, 1.0, 0.0))
        expanded[:, free.joint_index(name)] = multiplier * configurations[:, robot.joint_index(primary)] + offset
    # Measured 0 (the same arithmetic on the same angles); bound 1e-12.
    np.testing.assert_allclose(fkin_space(screw_chain(robot, link), configurations),
                               fkin_space(screw_chain(free, link), expanded), rtol=0, atol=TOLERANCE)


def test_locking_a_primary_locks_its_mimic_joints() -> None:
    """Pinocchio refuses to remove a primary and keep its mimic joint: q4 is locked with q2,
    at -2 q2 + 0.3, and the poses stay those of the full robot."""
    robot = load_robot(mimic_arm_urdf())
    reduced = lock_joints(robot, {"q2": 0.4})
    assert reduced.joint_names == ("q1", "q3", "q5") and reduced.model.nv == 3
    assert reduced.locked == pytest.approx({"q2": 0.4, "q4": -0.5})
    assert set(reduced.mimic) == {"q6", "side_joint"}
    q_reduced = _random_configurations(reduced, 7)[:20]
    q_full = np.insert(q_reduced, 1, 0.4, axis=1)
    for link in ("tool", "side"):
        # Measured 5.6e-16 (locked vs full) and 1.5e-15 (vs Pinocchio); bounds 1e-14, 1e-12.
        np.testing.assert_allclose(fkin_space(screw_chain(reduced, link), q_reduced),
                                   fkin_space(screw_chain(robot, link), q_full), rtol=0, atol=1e-14)
        assert max(_max_errors(reduced, link, q_reduced).values()) < TOLERANCE


# ---- the compiled loops ------------------------------------------------------------------
FUNCTIONS = (fkin_space, fkin_body, jacobian_space, jacobian_body)
BY_NAME = {f.__name__: f for f in FUNCTIONS}


# ---- the previous implementation (4x4 arrays, the exponential by its own call), kept as the
# ---- reference the loops must equal to the bit ---------------------------------------------
@njit
def _multiply_exponential(transform, terms, theta, out):
    s, c = np.sin(theta), 1.0 - np.cos(theta)
    for r in range(3):
        for col in range(4):
            total = transform[r, 3] if col == 3 else 0.0
            for k in range(3):
                factor = terms[0, k, col] + theta * terms[1, k, col] + s * terms[2, k, col] + c * terms[3, k, col]
                total += transform[r, k] * factor
            out[r, col] = total
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = 0.0, 0.0, 0.0, 1.0


@njit
def _previous_pose(q, angles, terms, out):
    running, scratch = np.eye(4), np.empty((4, 4))
    for i in range(terms.shape[0]):
        theta = angles[1, i] * q[int(angles[0, i])] + angles[2, i]
        _multiply_exponential(running, terms[i], theta, scratch)
        running, scratch = scratch, running
    out[:, :] = running


@njit
def _previous_columns(q, angles, terms, axes, out):
    running, scratch = np.eye(4), np.empty((4, 4))
    for i in range(terms.shape[0]):
        for r in range(3):
            omega = running[r, 0] * axes[0, i] + running[r, 1] * axes[1, i] + running[r, 2] * axes[2, i]
            out[r, i] = omega
            out[r + 3, i] = running[r, 0] * axes[3, i] + running[r, 1] * axes[4, i] + running[r, 2] * axes[5, i]
        w0, w1, w2 = out[0, i], out[1, i], out[2, i]
        p0, p1, p2 = running[0, 3], running[1, 3], running[2, 3]
        out[3, i] += p1 * w2 - p2 * w1
        out[4, i] += p2 * w0 - p0 * w2
        out[5, i] += p0 * w1 - p1 * w0
        if i + 1 < terms.shape[0]:
            theta = angles[1, i] * q[int(angles[0, i])] + angles[2, i]
            _multiply_exponential(running, terms[i], theta, scratch)
            running, scratch = scratch, running


def previous(chain: ScrewChain, q: np.ndarray) -> dict[str, np.ndarray]:
    """The four results of the previous loops at one configuration (fixed root, no mimic)."""
    poses = {}
    for name, (angles, terms) in (("fkin_space", chain._space_pose), ("fkin_body", chain._body_pose)):
        poses[name] = np.empty((4, 4))
        _previous_pose(q, angles, terms, poses[name])
    for name, loop in (("jacobian_space", chain._space_jacobian), ("jacobian_body", chain._body_jacobian)):
        poses[name] = np.empty((6, chain.n))
        _previous_columns(q, *loop, poses[name])
    poses["jacobian_body"] = poses["jacobian_body"][:, ::-1]
    return poses


def robots() -> dict[str, Robot]:
    return {"youbot": load_robot(default_urdf()), "seed": load_robot(seed_urdf()),
            "offset_arm": load_robot(offset_arm_urdf())}


@pytest.mark.parametrize("name", ["youbot", "seed", "offset_arm"])
def test_loops_equal_the_previous_implementation_to_the_bit(name: str) -> None:
    """Every link's chain, 200 configurations (wide angles, signed zeros, prismatic joints):
    the same operations in the same order, so the same bits (signed zeros included)."""
    robot = robots()[name]
    rng = np.random.default_rng(11)
    configurations = rng.uniform(-4.0, 4.0, (200, robot.nq))
    configurations[::7] = 0.0
    configurations[1::7] = -0.0
    for link in robot.link_names:
        chain = screw_chain(robot, link)
        if not chain.n:
            continue
        batch = {f.__name__: f(chain, configurations) for f in FUNCTIONS}
        for k, q in enumerate(configurations):
            for key, reference in previous(chain, q).items():
                ours = BY_NAME[key](chain, q)
                assert ours.tobytes() == np.ascontiguousarray(reference).tobytes(), (link, key, k)
                assert batch[key][k].tobytes() == ours.tobytes(), (link, key, k)


def test_direct_path_equals_the_general_one_and_checks_sizes() -> None:
    """A float64 vector takes the direct path; a list, float32 values (converted), a strided
    view and a (1, nq) batch take the general one: the same values. The results are fresh
    arrays; a wrong size is the UserInputError naming nq, whichever path."""
    robot = robots()["youbot"]
    chain = screw_chain(robot)
    q = np.random.default_rng(4).uniform(-3.0, 3.0, robot.nq)
    for f in FUNCTIONS:
        direct = f(chain, q)
        assert direct.flags.c_contiguous and direct.flags.writeable
        assert f(chain, q) is not direct
        np.testing.assert_array_equal(f(chain, list(q)), direct)
        np.testing.assert_array_equal(f(chain, np.repeat(q, 2)[::2]), direct)
        np.testing.assert_array_equal(f(chain, q[None])[0], direct)
        q32 = q.astype(np.float32)
        np.testing.assert_array_equal(f(chain, q32), f(chain, q32.astype(float)))
        for wrong in (q[:-1], np.append(q, 0.0), np.float64(1.0), q.reshape(1, 1, -1)[..., :-1]):
            with pytest.raises(UserInputError, match=f"nq = {robot.nq}"):
                f(chain, wrong)


def test_mimic_chains_and_movable_roots_keep_the_general_path() -> None:
    """A chain with mimic joints or a movable root is not answered by the loop alone: its
    Jacobian maps the screw columns to the robot's joints (and root); against the batch of
    one configuration, which never takes the direct path."""
    floating = load_robot(default_urdf(), root="floating")
    for robot in (load_robot(mimic_arm_urdf()), floating):
        chain = screw_chain(robot)
        assert not chain._direct
        q = np.zeros(robot.nq)
        q[robot.root_nq:] = np.random.default_rng(5).uniform(-1.0, 1.0, robot.nv - robot.root_nv)
        if robot.root == "floating":
            q[3:7] = (0.1, -0.2, 0.3, 0.9) / np.linalg.norm((0.1, -0.2, 0.3, 0.9))
        for f in FUNCTIONS:
            np.testing.assert_array_equal(f(chain, q), f(chain, q[None])[0])
