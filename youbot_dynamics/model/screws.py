"""Screw axes from the URDF and product-of-exponentials kinematics (Lynch & Park ch. 4-5).

The screw axes are derived from the kinematic tree exactly as the URDF states it (joint
origins and axes at q = 0, fixed joints folded in), not from Pinocchio, so comparing the two
is an independent check.

Conventions: a screw axis / twist is (omega, v), angular part first; S_i is expressed in
the root-link ("space") frame {s}, B_i = [Ad_{M^-1}] S_i in the frame {b} of the chain's end
link at home. M = T_sb(0), positions in metres. Joint values are rad (revolute, continuous)
or m (prismatic). Functions take the ROBOT's full joint vector q (shape (nv,), or (..., nv)
for a batch) and pick the chain's joints with ``chain.joints``; Jacobians have one column per
chain joint, in chain order (root first), and map joint rates to twists (omega, v).

Speed: exp([S_i] theta) = I + theta A1 + sin(theta) A2 + (1 - cos(theta)) A3 with constant
matrices A_k per joint (Rodrigues for a unit screw axis, Prop. 3.25 of the book). They are
precomputed (with M folded into the last space / first body exponential), so the
exponentials of all joints cost one small matrix product and the pose n - 1 more.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.lie import adjoint, inverse_transform, skew
from youbot_dynamics.model.robot import Robot


@dataclass(frozen=True)
class ScrewChain:
    """The chain from a robot's root link to ``link``: S (6, n), M (4, 4), B (6, n).

    ``joints`` are the indices of the chain's moving joints in the robot's joint vector (of
    length ``nv``) and ``joint_names`` their names, root first. Build it once per (robot, link) with
    :func:`screw_chain` and keep it: it is immutable.
    """

    link: str
    joint_names: tuple[str, ...]
    joints: np.ndarray
    nv: int
    S: np.ndarray
    M: np.ndarray
    B: np.ndarray = field(init=False)
    _space_terms: np.ndarray = field(init=False, repr=False)
    _body_terms: np.ndarray = field(init=False, repr=False)
    _space_pose_terms: np.ndarray = field(init=False, repr=False)
    _body_pose_terms: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        body = adjoint(inverse_transform(self.M)) @ self.S
        space_terms, body_terms = exponential_terms(self.S), exponential_terms(body)
        # M folded into the last space exponential (exp([S_n] q_n) M) and the first body one
        # (M exp([B_1] q_1)): forward kinematics then needs n - 1 matrix products.
        space_pose_terms, body_pose_terms = space_terms.copy(), body_terms.copy()
        if self.n:
            space_pose_terms[-1] = (space_terms[-1].reshape(4, 4, 4) @ self.M).reshape(4, 16)
            body_pose_terms[0] = (self.M @ body_terms[0].reshape(4, 4, 4)).reshape(4, 16)
        for name, value in (("B", body), ("_space_terms", space_terms),
                            ("_body_terms", body_terms), ("_space_pose_terms", space_pose_terms),
                            ("_body_pose_terms", body_pose_terms)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        for array in (self.joints, self.S, self.M):
            array.setflags(write=False)

    @property
    def n(self) -> int:
        """Number of moving joints in the chain."""
        return self.S.shape[1]


def screw_chain(robot: Robot, link: str | None = None) -> ScrewChain:
    """Space-frame screw axes S_i and home configuration M of the chain from the root link
    to ``link`` (default ``robot.end_effector``), from the URDF tree at q = 0.

    Walking down the chain, T accumulates the joint origins; a revolute (or continuous) joint
    with world axis omega through the point p has S = (omega, -omega x p), a prismatic joint
    along the world direction d has S = (0, d), a fixed joint only moves T. M is T at the end.
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
    indices = np.array([robot.joint_index(name) for name in names], dtype=int)
    return ScrewChain(link=link, joint_names=tuple(names), joints=indices, nv=robot.nv, S=S,
                      M=transform)


def exponential_terms(axes: np.ndarray) -> np.ndarray:
    """Constant matrices (A0, A1, A2, A3) per unit screw axis, shape (n, 4, 16), such that
    exp([S] theta) = A0 + theta A1 + sin(theta) A2 + (1 - cos(theta)) A3 (flattened 4x4).

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
    return terms.reshape(n, 4, 16)


def _exponentials(terms: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Sum over k of coefficient_k(theta_i) terms[i, k] for every joint i: the matrices
    exp([X_i] theta_i) (times M where it is folded in), shape (..., n, 4, 4)."""
    coefficients = np.empty((*theta.shape, 4))
    coefficients[..., 0] = 1.0
    coefficients[..., 1] = theta
    np.sin(theta, out=coefficients[..., 2])
    coefficients[..., 3] = 1.0 - np.cos(theta)
    return np.einsum("...nk,nkm->...nm", coefficients, terms).reshape(*theta.shape, 4, 4)


def _joint_values(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.ndim == 0 or q.shape[-1] != chain.nv:
        raise UserInputError(f"chain to '{chain.link}' needs the robot's joint vector of "
                             f"{chain.nv} values; got shape {q.shape}")
    return q[..., chain.joints]


def _product(matrices: np.ndarray) -> np.ndarray:
    """matrices[..., 0, :, :] @ ... @ matrices[..., n-1, :, :] for n >= 1."""
    multiply = np.dot if matrices.ndim == 3 else np.matmul  # np.dot: less overhead for 4x4
    out = matrices[..., 0, :, :]
    for i in range(1, matrices.shape[-3]):
        out = multiply(out, matrices[..., i, :, :])
    return out


def _home(chain: ScrewChain, theta: np.ndarray) -> np.ndarray:
    """M for every configuration of a batch: the pose of a chain without moving joints."""
    return np.broadcast_to(chain.M, (*theta.shape[:-1], 4, 4)).copy()


def fkin_space(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """T_sb(q) = exp([S_1] q_1) ... exp([S_n] q_n) M, the pose of the chain's end link in the
    root frame (4x4, m) (FKinSpace). q: robot joint vector(s), shape (nv,) or (..., nv)."""
    theta = _joint_values(chain, q)
    return _product(_exponentials(chain._space_pose_terms, theta)) if chain.n else _home(chain, theta)


def fkin_body(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """T_sb(q) = M exp([B_1] q_1) ... exp([B_n] q_n) (4x4, m) (FKinBody)."""
    theta = _joint_values(chain, q)
    return _product(_exponentials(chain._body_pose_terms, theta)) if chain.n else _home(chain, theta)


def _adjoint_columns(transforms: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """[Ad_{T_i}] X_i for transforms (..., n, 4, 4) and axes (6, n): shape (..., 6, n)."""
    rotations, positions = transforms[..., :3, :3], transforms[..., :3, 3]
    omega = (rotations @ axes[:3].T[..., None])[..., 0]
    v = np.cross(positions, omega) + (rotations @ axes[3:].T[..., None])[..., 0]
    return np.swapaxes(np.concatenate([omega, v], axis=-1), -1, -2)


def jacobian_space(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """Space Jacobian J_s(q), shape (6, n) (or (..., 6, n)): rows (omega, v) of the end
    link's spatial twist in the root frame (JacobianSpace). Column i is
    [Ad_{exp([S_1] q_1) ... exp([S_{i-1}] q_{i-1})}] S_i."""
    exponentials = _exponentials(chain._space_terms, _joint_values(chain, q))
    prefix = np.empty_like(exponentials)
    if chain.n:
        prefix[..., 0, :, :] = np.eye(4)
    for i in range(1, chain.n):
        prefix[..., i, :, :] = prefix[..., i - 1, :, :] @ exponentials[..., i - 1, :, :]
    return _adjoint_columns(prefix, chain.S)


def jacobian_body(chain: ScrewChain, q: np.ndarray) -> np.ndarray:
    """Body Jacobian J_b(q), shape (6, n) (or (..., 6, n)): rows (omega, v) of the end link's
    body twist (JacobianBody). Column i is [Ad_{(exp([B_{i+1}] q_{i+1}) ... exp([B_n] q_n))^-1}] B_i."""
    exponentials = _exponentials(chain._body_terms, _joint_values(chain, q))
    suffix = np.empty_like(exponentials)
    if chain.n:
        suffix[..., -1, :, :] = np.eye(4)
    for i in range(chain.n - 2, -1, -1):
        suffix[..., i, :, :] = exponentials[..., i + 1, :, :] @ suffix[..., i + 1, :, :]
    inverse = np.zeros_like(suffix)
    rotations_t = np.swapaxes(suffix[..., :3, :3], -1, -2)
    inverse[..., :3, :3] = rotations_t
    inverse[..., :3, 3] = -(rotations_t @ suffix[..., :3, 3, None])[..., 0]
    inverse[..., 3, 3] = 1.0
    return _adjoint_columns(inverse, chain.B)
