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

Speed: what depends only on the chain is built once in the ScrewChain: per joint the constant
4x4 matrices A_k of exp([S_i] theta) = A0 + theta A1 + sin(theta) A2 + (1 - cos(theta)) A3
(Rodrigues for a unit screw axis, Prop. 3.25 of the book; M folded into the last space / first
body exponential) and the map q -> theta. Forward kinematics and the Jacobians are then one
compiled loop (numba) over the joints: per joint one exponential, one 3x4 product of the
running transform T_i = (R_i, p_i) and, for the Jacobians, the column
[Ad_{T_i}] S_i = (R_i omega_i, p_i x R_i omega_i + R_i v_i). A batch (..., nq) is the same
loop over its rows, so the cost grows linearly with the number of joints and of
configurations. The loops hold T_i as three rows of four numbers (registers, no array), so
they allocate nothing and run without numba's reference counting; one float64 configuration
of a fixed-root chain without mimic joints calls them through their entry points
(:mod:`youbot_dynamics.compiled`) after a dtype and size check in line: about 0.7 us per
Jacobian of the youBot arm, where Pinocchio's frame Jacobian takes 0.5 us
(bench/bench_kinematics.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import register_jitable

from youbot_dynamics.compiled import BORROWED, FLOAT, unchecked
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
    _space_pose: tuple[np.ndarray, np.ndarray] = field(init=False, repr=False)
    _body_pose: tuple[np.ndarray, np.ndarray] = field(init=False, repr=False)
    _space_jacobian: tuple[np.ndarray, np.ndarray, np.ndarray] = field(init=False, repr=False)
    _body_jacobian: tuple[np.ndarray, np.ndarray, np.ndarray] = field(init=False, repr=False)
    _direct: bool = field(init=False, repr=False)
    _columns_shape: tuple[int, int] = field(init=False, repr=False)

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
        # jacobian_body), so the body factors, axes and angles are in reverse joint order.
        # The arrays each compiled loop reads after q, C-ordered: the angle map and the
        # factors' terms (FK), and the axes (Jacobians).
        reversed_body = body[:, ::-1]
        angles = angle_map(self.joints, self.coupling)
        loops = {"_space_pose": (angles, space_pose_terms), "_body_pose": (angles, body_pose_terms),
                 "_space_jacobian": (angles, space_terms, np.ascontiguousarray(self.S)),
                 "_body_jacobian": (np.ascontiguousarray(angles[:, ::-1]), exponential_terms(-reversed_body),
                                    np.ascontiguousarray(reversed_body))}
        for array in (body, *(array for loop in loops.values() for array in loop), self.joints, self.S, self.M):
            array.setflags(write=False)
        derived = {"B": body, **loops, "_direct": self.root == "fixed" and self.coupling is None and self.n > 0,
                   "_columns_shape": (6, self.n)}
        for name, value in derived.items():
            object.__setattr__(self, name, value)

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


def angle_map(joints: np.ndarray, coupling: MimicCoupling | None) -> np.ndarray:
    """The (3, n) table theta_i = multiplier_i q[index_i] + offset_i of a chain's screw axes
    (rows: index into q as a float, multiplier, offset): ``joints`` with multiplier 1 and
    offset 0 without mimic joints (exactly theta = q[joints])."""
    if coupling is None:
        return np.array([joints, np.ones(len(joints)), np.zeros(len(joints))], dtype=float).reshape(3, -1)
    return np.array([coupling.index, coupling.multiplier, coupling.offset], dtype=float)


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


#: The top three rows (R | p) of the identity transform. The compiled loops hold their
#: running transform as such a tuple of rows (numbers in registers, not an array: the loops
#: allocate nothing, see :mod:`youbot_dynamics.compiled`).
_IDENTITY_ROWS = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0))


@register_jitable
def _entry_times_exponential(row: tuple, terms: np.ndarray, theta: float, s: float, c: float, col: int) -> float:
    """Entry ``col`` of (one row (r_0, r_1, r_2, p) of a rigid transform) exp([X] theta):
    (p if col == 3 else 0) + sum_k r_k (A0 + theta A1 + s A2 + c A3)[k, col], the
    exponential from its terms (A0, A1, A2, A3) (4, 4, 4), s = sin(theta), c = 1 - cos(theta)
    (its last row is (0, 0, 0, 1))."""
    total = row[3] if col == 3 else 0.0
    for k in range(3):
        factor = terms[0, k, col] + theta * terms[1, k, col] + s * terms[2, k, col] + c * terms[3, k, col]
        total += row[k] * factor
    return total


@register_jitable
def _row_times_exponential(row: tuple, terms: np.ndarray, theta: float, s: float, c: float) -> tuple:
    """One row (4 numbers) of T exp([X] theta) (see :func:`_entry_times_exponential`)."""
    return (_entry_times_exponential(row, terms, theta, s, c, 0), _entry_times_exponential(row, terms, theta, s, c, 1),
            _entry_times_exponential(row, terms, theta, s, c, 2), _entry_times_exponential(row, terms, theta, s, c, 3))


@register_jitable
def _times_exponential(rows: tuple, terms: np.ndarray, theta: float) -> tuple:
    """The top rows of T exp([X] theta) for the top rows of a rigid transform T, the
    exponential A0 + theta A1 + sin(theta) A2 + (1 - cos(theta)) A3 from its terms (4, 4, 4)."""
    s, c = np.sin(theta), 1.0 - np.cos(theta)
    return (_row_times_exponential(rows[0], terms, theta, s, c), _row_times_exponential(rows[1], terms, theta, s, c),
            _row_times_exponential(rows[2], terms, theta, s, c))


@register_jitable
def _angle(q: np.ndarray, angles: np.ndarray, i: int) -> float:
    """theta_i = multiplier_i q[index_i] + offset_i of the angle map ``angles`` (3, n)."""
    return angles[1, i] * q[int(angles[0, i])] + angles[2, i]


@register_jitable
def _product_of_exponentials(q: np.ndarray, angles: np.ndarray, terms: np.ndarray, out: np.ndarray) -> None:
    """out = exp([X_1] theta_1) ... exp([X_n] theta_n) (4, 4), theta from q (nq) by the
    angle map ``angles`` (3, n), the exponentials' terms (n, 4, 4, 4)."""
    rows = _IDENTITY_ROWS
    for i in range(terms.shape[0]):
        rows = _times_exponential(rows, terms[i], _angle(q, angles, i))
    for r in range(3):
        for col in range(4):
            out[r, col] = rows[r][col]
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = 0.0, 0.0, 0.0, 1.0


@register_jitable
def _adjoint_columns(q: np.ndarray, angles: np.ndarray, terms: np.ndarray, axes: np.ndarray,
                     out: np.ndarray) -> None:
    """out[:, i] = [Ad_{T_i}] X_i = (R_i omega_i, p_i x R_i omega_i + R_i v_i) (6, n) for
    T_i = F_1 ... F_{i-1} = (R_i, p_i), the factors F_j = exp([X_j] theta_j) from their terms
    (n, 4, 4, 4), the axes X_j = (omega_j, v_j) the columns of ``axes`` (6, n)."""
    rows = _IDENTITY_ROWS
    for i in range(terms.shape[0]):
        for r in range(3):
            row = rows[r]
            omega = row[0] * axes[0, i] + row[1] * axes[1, i] + row[2] * axes[2, i]
            out[r, i] = omega
            out[r + 3, i] = row[0] * axes[3, i] + row[1] * axes[4, i] + row[2] * axes[5, i]
        w0, w1, w2 = out[0, i], out[1, i], out[2, i]
        p0, p1, p2 = rows[0][3], rows[1][3], rows[2][3]
        out[3, i] += p1 * w2 - p2 * w1
        out[4, i] += p2 * w0 - p0 * w2
        out[5, i] += p0 * w1 - p1 * w0
        if i + 1 < terms.shape[0]:
            rows = _times_exponential(rows, terms[i], _angle(q, angles, i))


# The compiled entry points, each for one explicit signature and without reference counting
# (see youbot_dynamics.compiled): one configuration q (nq,) of float64 (any stride) read, the
# chain's constant arrays (its angle map (3, n), terms (n, 4, 4, 4), axes (6, n)) read, out
# written. They trust the sizes: q has the chain's nq values (checked by the caller).
_Q, _TABLE, _TERMS = (types.Array(types.float64, 1, "A", readonly=True), types.Array(types.float64, 2, "C", readonly=True),
                      types.Array(types.float64, 4, "C", readonly=True))
_OUT = types.Array(types.float64, 2, "C")


@njit(types.void(_Q, _TABLE, _TERMS, _OUT), **BORROWED)
def _pose(q: np.ndarray, angles: np.ndarray, terms: np.ndarray, out: np.ndarray) -> None:
    """out (4, 4) = :func:`_product_of_exponentials` at one configuration."""
    _product_of_exponentials(q, angles, terms, out)


@njit(types.void(_Q, _TABLE, _TERMS, _TABLE, _OUT), **BORROWED)
def _space_columns(q: np.ndarray, angles: np.ndarray, terms: np.ndarray, axes: np.ndarray, out: np.ndarray) -> None:
    """out (6, n) = :func:`_adjoint_columns` at one configuration."""
    _adjoint_columns(q, angles, terms, axes, out)


@njit(types.void(_Q, _TABLE, _TERMS, _TABLE, _OUT), **BORROWED)
def _body_columns(q: np.ndarray, angles: np.ndarray, terms: np.ndarray, axes: np.ndarray, out: np.ndarray) -> None:
    """out (6, n) = :func:`_adjoint_columns` at one configuration, columns in reverse order
    (the body Jacobian's factors, axes and angles are stored tip first)."""
    _adjoint_columns(q, angles, terms, axes, out[:, ::-1])


_pose_unchecked, _space_columns_unchecked, _body_columns_unchecked = (
    unchecked(_pose), unchecked(_space_columns), unchecked(_body_columns))


@njit(**BORROWED)
def _product_of_exponentials_rows(q: np.ndarray, angles: np.ndarray, terms: np.ndarray, out: np.ndarray) -> None:
    """:func:`_product_of_exponentials` of each row of q (N, nq) into out (N, 4, 4)."""
    for row in range(q.shape[0]):
        _product_of_exponentials(q[row], angles, terms, out[row])


@njit(**BORROWED)
def _adjoint_columns_rows(q: np.ndarray, angles: np.ndarray, terms: np.ndarray, axes: np.ndarray,
                          out: np.ndarray) -> None:
    """:func:`_adjoint_columns` of each row of q (N, nq) into out (N, 6, n) (or a view of it
    with its columns reversed)."""
    for row in range(q.shape[0]):
        _adjoint_columns(q[row], angles, terms, axes, out[row])


def _configurations(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """q as a float array of the robot's configuration(s) (..., nq), or a UserInputError."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 0 or q.shape[-1] != chain.nq:
        raise UserInputError(f"chain to '{chain.link}' needs the robot's configuration q of "
                             f"nq = {chain.nq} values ({chain.root} root); got shape {q.shape}")
    return q


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
    q = _configurations(chain, q)
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


def _products(chain: ScrewChain, q: np.ndarray, loop: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """exp([X_1] theta_1) ... exp([X_n] theta_n) (..., 4, 4) at q (..., nq, float), the
    angle map and the factors' terms ``loop`` (the space or body pose terms, constants folded
    in); M without moving joints."""
    if not chain.n:
        return np.broadcast_to(chain.M, (*q.shape[:-1], 4, 4)).copy()
    if q.ndim == 1:
        out = np.empty((4, 4))
        _pose_unchecked(q, *loop, out)
        return out
    rows = np.ascontiguousarray(q.reshape(math.prod(q.shape[:-1]), chain.nq))
    out = np.empty((len(rows), 4, 4))
    _product_of_exponentials_rows(rows, *loop, out)
    return out.reshape(*q.shape[:-1], 4, 4)


def _columns(chain: ScrewChain, q: np.ndarray, body: bool) -> np.ndarray:
    """The chain's columns (..., 6, n) at q (..., nq, float): [Ad_{F_1 ... F_{i-1}}] X_i of
    the space Jacobian's factors and axes, or (``body``) of the body Jacobian's (stored tip
    first, written back in joint order); see :func:`_adjoint_columns`."""
    angles, terms, axes = chain._body_jacobian if body else chain._space_jacobian
    if q.ndim == 1:
        out = np.empty(chain._columns_shape)
        (_body_columns_unchecked if body else _space_columns_unchecked)(q, angles, terms, axes, out)
        return out
    rows = np.ascontiguousarray(q.reshape(math.prod(q.shape[:-1]), chain.nq))
    out = np.empty((len(rows), 6, chain.n))
    _adjoint_columns_rows(rows, angles, terms, axes, out[..., ::-1] if body else out)
    return out.reshape(*q.shape[:-1], 6, chain.n)


def _direct_call(chain: ScrewChain, q: object, loop: Any, arrays: tuple[np.ndarray, ...],
                 shape: tuple[int, int]) -> np.ndarray | None:
    """loop(q, *arrays, out) into a fresh out of ``shape`` when that is the answer as it
    stands: a chain with a fixed root, no mimic joints and at least one joint, and q one
    configuration the loop may read as it is (a float64 vector of nq values); else None.
    (Beside the loop, these checks are most of a call's cost: written in line.)"""
    if chain._direct and type(q) is np.ndarray and q.dtype is FLOAT and q.ndim == 1 and len(q) == chain.nq:
        out = np.empty(shape)
        loop(q, *arrays, out)
        return out
    return None


def _with_root(chain: ScrewChain, q: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """T_root(q) pose: the chain's pose carried into the world by a movable root."""
    return pose if chain.root == "fixed" else np.matmul(root_pose(chain, q), pose)


def fkin_space(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """T_sb(q) = T_root(q) exp([S_1] q_1) ... exp([S_n] q_n) M, the pose of the chain's end
    link in the world (the root link's frame for a fixed root) (4x4, m) (FKinSpace).
    q: robot configuration(s), shape (nq,) or (..., nq)."""
    pose = _direct_call(chain, q, _pose_unchecked, chain._space_pose, (4, 4))
    if pose is not None:
        return pose
    q = _configurations(chain, q)
    return _with_root(chain, q, _products(chain, q, chain._space_pose))


def fkin_body(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """T_sb(q) = T_root(q) M exp([B_1] q_1) ... exp([B_n] q_n) (4x4, m) (FKinBody)."""
    pose = _direct_call(chain, q, _pose_unchecked, chain._body_pose, (4, 4))
    if pose is not None:
        return pose
    q = _configurations(chain, q)
    return _with_root(chain, q, _products(chain, q, chain._body_pose))


def jacobian_space(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """Space Jacobian J_s(q), shape (6, k) (or (..., 6, k)), k = len(chain.columns): rows
    (omega, v) of the end link's spatial twist in the world (root link frame for a fixed
    root) (JacobianSpace); columns ``chain.columns`` of v. Chain column i is
    [Ad_{exp([S_1] q_1) ... exp([S_{i-1}] q_{i-1})}] S_i; with a movable root every column
    is carried by [Ad_{T_root}] and the root's columns P come first."""
    columns = _direct_call(chain, q, _space_columns_unchecked, chain._space_jacobian, chain._columns_shape)
    if columns is not None:
        return columns
    q = _configurations(chain, q)
    chain_columns = _joint_columns(chain, _columns(chain, q, False))
    if chain.root == "fixed":
        return chain_columns
    root = root_pose(chain, q)
    twists = np.broadcast_to(ROOT_TWISTS[chain.root], (*q.shape[:-1], *ROOT_TWISTS[chain.root].shape))
    return _adjoint_apply(root[..., :3, :3], root[..., :3, 3],
                          np.concatenate((twists, chain_columns), axis=-1))


def jacobian_body(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """Body Jacobian J_b(q), shape (6, k) (or (..., 6, k)), k = len(chain.columns): rows
    (omega, v) of the end link's body twist (JacobianBody); columns ``chain.columns`` of v.
    Chain column i is [Ad_{exp(-[B_n] q_n) ... exp(-[B_{i+1}] q_{i+1})}] B_i: J_s's formula
    for the factors exp([-B_j] q_j) from j = n down, columns reversed. With a movable root
    the root's columns [Ad_{T_chain^-1}] P come first (T_chain the end link's pose in the
    root link's frame)."""
    columns = _direct_call(chain, q, _body_columns_unchecked, chain._body_jacobian, chain._columns_shape)
    if columns is not None:
        return columns
    q = _configurations(chain, q)
    chain_columns = _joint_columns(chain, _columns(chain, q, True))
    if chain.root == "fixed":
        return chain_columns
    pose = _products(chain, q, chain._space_pose)
    rotation_t = pose[..., :3, :3].swapaxes(-1, -2)
    position = -(rotation_t @ pose[..., :3, 3:])[..., 0]
    twists = np.broadcast_to(ROOT_TWISTS[chain.root], (*q.shape[:-1], *ROOT_TWISTS[chain.root].shape))
    return np.concatenate((_adjoint_apply(rotation_t, position, twists), chain_columns), axis=-1)
