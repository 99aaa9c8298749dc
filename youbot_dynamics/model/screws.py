"""Screw axes from the URDF and product-of-exponentials kinematics (Lynch & Park ch. 4-5).

The screw axes are derived from the kinematic tree exactly as the URDF states it (joint
origins and axes at q = 0, fixed joints folded in), not from Pinocchio, so comparing the two
is an independent check.

Conventions: a screw axis / twist is (omega, v), angular part first; S_i is expressed in
the root-link ("space") frame {s}, B_i = [Ad_{M^-1}] S_i in the frame {b} of the chain's end
link at home. M = T_sb(0), positions in metres. Joint values are rad (revolute, continuous)
or m (prismatic). Functions take the ROBOT's full configuration q (shape (nq,), or (..., nq)
for a batch) and pick the chain's joints with ``chain.joints``; Jacobians have one column per
robot joint that moves the chain, in chain order (root first), after the root joint's
columns for a floating or planar root, and map velocities v (``chain.columns`` of them) to
twists (omega, v). A mimic joint in the chain (theta = multiplier q_primary + offset) has a
screw axis of its own but no column: its column, times the multiplier, adds to its
primary's, as Pinocchio's mimic joints do.

Root joint (see :mod:`youbot_dynamics.model.robot`): with a floating or planar root the
space frame {s} is the world, T_sb(q) = T_root(q_root) T_chain(q_joints), and the Jacobians
get the root's DoFs as their first columns, in the order and convention of Pinocchio's v
(the root link's body twist: (vx, vy, vz, wx, wy, wz) floating, (vx, vy, wz) planar), so
that J_s equals Pinocchio's WORLD frame Jacobian and J_b its LOCAL one (rows reordered) on
the columns ``chain.columns``. With the root's body twist V_r = P v_root (P picks the twist
(omega, v) out of v_root): V_s = [Ad_{T_root}] (V_r + J_s,chain dq) and
V_b = [Ad_{T_chain^-1}] V_r + J_b,chain dq.

Speed: a call costs a fixed number of numpy calls plus one 4x4 product per joint, which is
what matters for one configuration (each numpy call costs ~0.3 us, the arithmetic far less).
exp([S_i] theta) = I + theta A1 + sin(theta) A2 + (1 - cos(theta)) A3 with constant matrices
A_k per joint (Rodrigues for a unit screw axis, Prop. 3.25 of the book), so the exponentials
of all joints are one product of (theta, sin theta, cos theta) with a precomputed
block-diagonal matrix (M folded into the last space / first body exponential); the pose then
costs n - 1 4x4 products. The Jacobian columns [Ad_{T_i}] S_i = (R_i omega_i,
p_i x R_i omega_i + R_i v_i) come from the running products T_i = (R_i, p_i) of the same
pass, for all joints at once.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.lie import adjoint, inverse_transform, matrix_from_quaternion, skew
from youbot_dynamics.model.robot import ROOT_COORDINATES, Robot


class MimicCoupling(NamedTuple):
    """How a chain with mimic joints reads the robot's joint vector: the chain joint i
    (screw axis S_i, named ``names[i]``) turns by theta_i = multiplier[i] q[index[i]] +
    offset[i] (rad or m), and d theta / d q[chain.joints] = ``matrix`` (n, columns)."""

    names: tuple[str, ...]
    index: np.ndarray
    multiplier: np.ndarray
    offset: np.ndarray
    matrix: np.ndarray


class ExponentialMap(NamedTuple):
    """exp([X_i] theta_i) for all joints of a chain as one affine map of the coefficients
    c = (theta_1..theta_n, sin theta_1..sin theta_n, cos theta_1..cos theta_n) (rad or m).

    ``offset + c.dot(matrix).reshape(..., n, 4, 4)`` is the stack of the n 4x4 exponentials;
    ``offset`` is (n, 4, 4), ``matrix`` (3 n, 16 n) is block diagonal: joint i's coefficients
    only reach its own 16 entries (row-major).
    """

    offset: np.ndarray
    matrix: np.ndarray


@dataclass(frozen=True)
class ScrewChain:
    """The chain from a robot's root link to ``link``: S (6, n), M (4, 4), B (6, n).

    ``joints`` are the indices in the robot's configuration q (of length ``nq``) of the
    joints that move the chain (the Jacobians' columns after the root's) and ``joint_names``
    their names, root first; without mimic joints they are the chain's moving joints, one
    per screw axis. ``coupling`` (None without mimic joints) maps q to the n screw axes'
    angles. ``root`` is the robot's root joint. Build it once per (robot, link) with
    :func:`screw_chain` and keep it: it is immutable.
    """

    link: str
    joint_names: tuple[str, ...]
    joints: np.ndarray
    nq: int
    S: np.ndarray
    M: np.ndarray
    coupling: MimicCoupling | None = None
    root: str = "fixed"
    B: np.ndarray = field(init=False)
    _space_pose: ExponentialMap = field(init=False, repr=False)
    _body_pose: ExponentialMap = field(init=False, repr=False)
    _space_factors: ExponentialMap = field(init=False, repr=False)
    _body_factors: ExponentialMap = field(init=False, repr=False)
    _space_axes: np.ndarray = field(init=False, repr=False)
    _body_axes: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        body = adjoint(inverse_transform(self.M)) @ self.S
        space_terms, body_terms = exponential_terms(self.S), exponential_terms(body)
        # M folded into the last space exponential (exp([S_n] q_n) M) and the first body one
        # (M exp([B_1] q_1)): forward kinematics then needs n - 1 matrix products.
        space_pose_terms, body_pose_terms = space_terms.copy(), body_terms.copy()
        if self.n:
            space_pose_terms[-1] = space_terms[-1] @ self.M
            body_pose_terms[0] = self.M @ body_terms[0]
        # J_b is J_s's formula applied to the factors exp([-B_i] q_i) from the tip down (see
        # jacobian_body), so the body factors and axes are in reverse joint order.
        reversed_body = body[:, ::-1]
        derived = {"B": body,
                   "_space_pose": exponential_map(space_pose_terms),
                   "_body_pose": exponential_map(body_pose_terms),
                   "_space_factors": exponential_map(space_terms),
                   "_body_factors": exponential_map(exponential_terms(-reversed_body)),
                   "_space_axes": _axis_pairs(self.S),
                   "_body_axes": _axis_pairs(reversed_body)}
        for name, value in derived.items():
            for array in value if isinstance(value, ExponentialMap) else (value,):
                array.setflags(write=False)
            object.__setattr__(self, name, value)
        for array in (self.joints, self.S, self.M):
            array.setflags(write=False)

    @property
    def n(self) -> int:
        """Number of moving joints (screw axes) in the chain, mimic joints included."""
        return self.S.shape[1]

    @property
    def axis_names(self) -> tuple[str, ...]:
        """The joint of each screw axis (column of S and B), root first."""
        return self.joint_names if self.coupling is None else self.coupling.names

    @property
    def columns(self) -> np.ndarray:
        """Indices in v of the Jacobians' columns: the root's DoFs, then the joints that move
        the chain (equal to ``joints`` for a fixed root)."""
        root_nq, root_nv = (len(names) for names in ROOT_COORDINATES[self.root])
        return np.concatenate([np.arange(root_nv), self.joints - root_nq + root_nv])


def screw_chain(robot: Robot, link: str | None = None) -> ScrewChain:
    """Space-frame screw axes S_i and home configuration M of the chain from the root link
    to ``link`` (default ``robot.end_effector``), from the URDF tree at q = 0.

    Walking down the chain, T accumulates the joint origins; a revolute (or continuous) joint
    with world axis omega through the point p has S = (omega, -omega x p), a prismatic joint
    along the world direction d has S = (0, d), a fixed joint only moves T. M is T at the end.
    A mimic joint (``robot.mimic``) is read from its primary's value.
    """
    link = robot.end_effector if link is None else link
    transform = np.eye(4)
    axes, names = [], []
    for joint in robot.chain_to(link):
        transform = transform @ joint.origin
        if joint.type == "fixed":
            continue
        direction = transform[:3, :3] @ joint.axis
        if joint.type == "prismatic":
            axes.append(np.concatenate([np.zeros(3), direction]))
        else:
            axes.append(np.concatenate([direction, -np.cross(direction, transform[:3, 3])]))
        names.append(joint.name)
    S = np.array(axes, dtype=float).reshape(-1, 6).T
    columns, coupling = mimic_coupling(robot, tuple(names))
    indices = np.array([robot.root_nq + robot.joint_index(name) for name in columns], dtype=int)
    return ScrewChain(link=link, joint_names=columns, joints=indices, nq=robot.nq, S=S,
                      M=transform, coupling=coupling, root=robot.root)


def mimic_coupling(robot: Robot, names: tuple[str, ...]) -> tuple[tuple[str, ...], MimicCoupling | None]:
    """The robot joints that drive the chain joints ``names`` (each once, root first: a joint
    drives itself, a mimic joint is driven by its primary) and their :class:`MimicCoupling`
    (None when no chain joint mimics another); its ``index`` points into q (after the root's
    coordinates)."""
    relations = [robot.mimic.get(name) for name in names]
    drivers = [name if m is None else m.primary for name, m in zip(names, relations)]
    columns = tuple(dict.fromkeys(drivers))
    if not any(relations):
        return columns, None
    multiplier = np.array([1.0 if m is None else m.multiplier for m in relations])
    matrix = np.zeros((len(names), len(columns)))
    matrix[np.arange(len(names)), [columns.index(d) for d in drivers]] = multiplier
    coupling = MimicCoupling(names=names,
                             index=np.array([robot.root_nq + robot.joint_index(d) for d in drivers], dtype=int),
                             multiplier=multiplier,
                             offset=np.array([0.0 if m is None else m.offset for m in relations]),
                             matrix=matrix)
    for array in coupling[1:]:
        array.setflags(write=False)
    return columns, coupling


def exponential_terms(axes: np.ndarray) -> np.ndarray:
    """Constant 4x4 matrices (A0, A1, A2, A3) per unit screw axis (columns (omega, v) of
    ``axes``), shape (n, 4, 4, 4), such that
    exp([S] theta) = A0 + theta A1 + sin(theta) A2 + (1 - cos(theta)) A3 (Prop. 3.25).

    With [omega] = K: A0 = I, A1 = [[0, v + K^2 v]], A2 = [[K, -K^2 v]], A3 = [[K^2, K v]];
    for a prismatic axis (omega = 0) A2 and A3 vanish and A1 = [[0, v]].
    """
    n = axes.shape[1]
    terms = np.zeros((n, 4, 4, 4))
    for i in range(n):
        k = skew(axes[:3, i])
        v = axes[3:, i]
        k2 = k @ k
        terms[i, 0] = np.eye(4)
        terms[i, 1, :3, 3] = v + k2 @ v
        terms[i, 2, :3, :3], terms[i, 2, :3, 3] = k, -k2 @ v
        terms[i, 3, :3, :3], terms[i, 3, :3, 3] = k2, k @ v
    return terms


def exponential_map(terms: np.ndarray) -> ExponentialMap:
    """The :class:`ExponentialMap` of per-joint terms (A0, A1, A2, A3) (shape (n, 4, 4, 4), from
    :func:`exponential_terms`, possibly with constant transforms folded in):
    (1 - cos) A3 = A3 - cos A3, so the offset is A0 + A3 and cos theta multiplies -A3."""
    n = terms.shape[0]
    flat = terms.reshape(n, 4, 16)
    matrix = np.zeros((3, n, n, 16))
    for i in range(n):
        matrix[:, i, i] = flat[i, 1], flat[i, 2], -flat[i, 3]
    return ExponentialMap(terms[:, 0] + terms[:, 3], matrix.reshape(3 * n, n * 16))


def _axis_pairs(axes: np.ndarray) -> np.ndarray:
    """The columns (omega_i, v_i) of ``axes`` as 3x2 matrices [omega_i v_i], shape (n, 3, 2)."""
    return np.ascontiguousarray(axes.reshape(2, 3, -1).transpose(2, 1, 0))


# (a x b)_k = sum over i, j of CROSS[3 i + j, k] a_i b_j (the Levi-Civita symbol).
_CROSS = np.zeros((9, 3))
_CROSS[[5, 6, 1], [0, 1, 2]] = 1.0
_CROSS[[7, 2, 3], [0, 1, 2]] = -1.0
_CROSS.setflags(write=False)


def _exponentials(exponential: ExponentialMap, theta: np.ndarray) -> np.ndarray:
    """exp([X_i] theta_i) (with the folded constants) at theta (..., n): shape (..., n, 4, 4)."""
    coefficients = np.concatenate((theta, np.sin(theta), np.cos(theta)), axis=-1)
    return coefficients.dot(exponential.matrix).reshape(theta.shape + (4, 4)) + exponential.offset


def _joint_values(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """The screw axes' angles theta (..., n) (rad or m) from the robot's joint vector(s)."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 0 or q.shape[-1] != chain.nq:
        raise UserInputError(f"chain to '{chain.link}' needs the robot's configuration q of "
                             f"nq = {chain.nq} values ({chain.root} root); got shape {q.shape}")
    if chain.coupling is None:
        return q.take(chain.joints, axis=-1)
    coupling = chain.coupling
    return q.take(coupling.index, axis=-1) * coupling.multiplier + coupling.offset


def _joint_columns(chain: ScrewChain, columns: np.ndarray) -> np.ndarray:
    """Jacobian columns per screw axis (..., 6, n) -> per driving joint (..., 6, len(joints)):
    a mimic joint's column, times its multiplier, adds to its primary's."""
    return columns if chain.coupling is None else columns @ chain.coupling.matrix


#: P of each movable root: its columns are the root link's body twist (omega, v) per unit
#: of each root DoF of Pinocchio's v ((vx, vy, vz, wx, wy, wz) floating, (vx, vy, wz) planar).
ROOT_TWISTS = {"floating": np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]]),
               "planar": np.zeros((6, 3))}
ROOT_TWISTS["planar"][[3, 4, 2], [0, 1, 2]] = 1.0
for _twists in ROOT_TWISTS.values():
    _twists.setflags(write=False)


def root_pose(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """T_root(q): pose of the robot's root link in the world (4x4, m), shape (..., 4, 4) for
    q of shape (..., nq). Floating: translation q[0:3], rotation of the quaternion q[3:7]
    (x, y, z, w); planar: translation (q[0], q[1], 0), rotation about z with cos q[2] and
    sin q[3]; fixed: the identity."""
    q = np.asarray(q, dtype=float)
    _joint_values(chain, q)  # size check
    pose = np.broadcast_to(np.eye(4), (*q.shape[:-1], 4, 4)).copy()
    if chain.root == "floating":
        pose[..., :3, 3] = q[..., :3]
        pose[..., :3, :3] = matrix_from_quaternion(q[..., 3:7])
    elif chain.root == "planar":
        pose[..., :2, 3] = q[..., :2]
        c, s = q[..., 2], q[..., 3]
        pose[..., 0, 0], pose[..., 0, 1], pose[..., 1, 0], pose[..., 1, 1] = c, -s, s, c
    return pose


def _adjoint_apply(rotation: np.ndarray, position: np.ndarray, twists: np.ndarray) -> np.ndarray:
    """[Ad_T] X for T = (R, p): (R omega, p x R omega + R v) for the columns (omega, v) of X
    (..., 6, k); R (..., 3, 3), p (..., 3)."""
    omega = rotation @ twists[..., :3, :]
    linear = rotation @ twists[..., 3:, :] + np.cross(position[..., None, :], omega.swapaxes(-1, -2)).swapaxes(-1, -2)
    return np.concatenate((omega, linear), axis=-2)


def _running_products(factors: np.ndarray) -> list[np.ndarray]:
    """[F_1, F_1 F_2, ..., F_1 ... F_n] for factors F_i = factors[..., i - 1, :, :] (n >= 1)."""
    # One configuration: ndarray.dot, the 4x4 product with the least call overhead.
    multiply = np.ndarray.dot if factors.ndim == 3 else np.matmul
    products = [factors[..., 0, :, :]]
    for i in range(1, factors.shape[-3]):
        products.append(multiply(products[-1], factors[..., i, :, :]))
    return products


def _home(chain: ScrewChain, theta: np.ndarray) -> np.ndarray:
    """M for every configuration of a batch: the pose of a chain without moving joints."""
    return np.broadcast_to(chain.M, (*theta.shape[:-1], 4, 4)).copy()


def _with_root(chain: ScrewChain, q: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """T_root(q) pose: the chain's pose carried into the world by a movable root."""
    return pose if chain.root == "fixed" else np.matmul(root_pose(chain, q), pose)


def _chain_pose(chain: ScrewChain, theta: np.ndarray) -> np.ndarray:
    """exp([S_1] theta_1) ... exp([S_n] theta_n) M: the end link in the root link's frame."""
    if not chain.n:
        return _home(chain, theta)
    return _running_products(_exponentials(chain._space_pose, theta))[-1]


def fkin_space(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """T_sb(q) = T_root(q) exp([S_1] q_1) ... exp([S_n] q_n) M, the pose of the chain's end
    link in the world (the root link's frame for a fixed root) (4x4, m) (FKinSpace).
    q: robot configuration(s), shape (nq,) or (..., nq)."""
    return _with_root(chain, q, _chain_pose(chain, _joint_values(chain, q)))


def fkin_body(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """T_sb(q) = T_root(q) M exp([B_1] q_1) ... exp([B_n] q_n) (4x4, m) (FKinBody)."""
    theta = _joint_values(chain, q)
    if not chain.n:
        return _with_root(chain, q, _home(chain, theta))
    return _with_root(chain, q, _running_products(_exponentials(chain._body_pose, theta))[-1])


def _adjoint_columns(factors: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """[Ad_{T_i}] X_i = (R_i omega_i, p_i x R_i omega_i + R_i v_i) for T_i = F_1 ... F_i =
    (R_i, p_i), shape (..., 6, n), from factors F_i = exp([X_i] theta_i) (..., n, 4, 4) and
    axes [omega_i v_i] (n, 3, 2). F_i leaves X_i unchanged ([Ad_{exp([X] theta)}] X = X), so
    this is [Ad_{F_1 ... F_{i-1}}] X_i; n = 0 gives shape (..., 6, 0)."""
    n = axes.shape[0]
    if not n:
        return np.zeros((*factors.shape[:-3], 6, 0))
    transforms = np.array(_running_products(factors))  # joint axis first: (n, ..., 4, 4)
    moved = np.matmul(transforms[..., :3, :3], axes.reshape(n, *(1,) * (factors.ndim - 3), 3, 2))
    omega, position = moved[..., 0], transforms[..., :3, 3]
    outer = (position[..., :, None] * omega[..., None, :]).reshape(*omega.shape[:-1], 9)
    columns = np.concatenate((omega, outer.dot(_CROSS) + moved[..., 1]), axis=-1)
    return columns.transpose(*range(1, columns.ndim), 0)


def jacobian_space(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """Space Jacobian J_s(q), shape (6, k) (or (..., 6, k)), k = len(chain.columns): rows
    (omega, v) of the end link's spatial twist in the world (root link frame for a fixed
    root) (JacobianSpace); columns ``chain.columns`` of v. Chain column i is
    [Ad_{exp([S_1] q_1) ... exp([S_{i-1}] q_{i-1})}] S_i; with a movable root every column
    is carried by [Ad_{T_root}] and the root's columns P come first."""
    theta = _joint_values(chain, q)
    chain_columns = _joint_columns(chain, _adjoint_columns(_exponentials(chain._space_factors, theta),
                                                           chain._space_axes))
    if chain.root == "fixed":
        return chain_columns
    root = root_pose(chain, q)
    twists = np.broadcast_to(ROOT_TWISTS[chain.root], (*theta.shape[:-1], *ROOT_TWISTS[chain.root].shape))
    return _adjoint_apply(root[..., :3, :3], root[..., :3, 3],
                          np.concatenate((twists, chain_columns), axis=-1))


def jacobian_body(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """Body Jacobian J_b(q), shape (6, k) (or (..., 6, k)), k = len(chain.columns): rows
    (omega, v) of the end link's body twist (JacobianBody); columns ``chain.columns`` of v.
    Chain column i is [Ad_{exp(-[B_n] q_n) ... exp(-[B_{i+1}] q_{i+1})}] B_i: J_s's formula
    for the factors exp([-B_j] q_j) from j = n down, columns reversed. With a movable root
    the root's columns [Ad_{T_chain^-1}] P come first (T_chain the end link's pose in the
    root link's frame)."""
    theta = _joint_values(chain, q)
    chain_columns = _joint_columns(chain, _adjoint_columns(_exponentials(chain._body_factors, theta[..., ::-1]),
                                                           chain._body_axes)[..., ::-1])
    if chain.root == "fixed":
        return chain_columns
    pose = _chain_pose(chain, theta)
    rotation_t = pose[..., :3, :3].swapaxes(-1, -2)
    position = -(rotation_t @ pose[..., :3, 3:])[..., 0]
    twists = np.broadcast_to(ROOT_TWISTS[chain.root], (*theta.shape[:-1], *ROOT_TWISTS[chain.root].shape))
    return np.concatenate((_adjoint_apply(rotation_t, position, twists), chain_columns), axis=-1)
