"""Rigid-body dynamics of a Robot with joint friction, over Pinocchio.

Equations of motion, joint coordinates in Pinocchio's order (rad, m; SI units throughout):

    M(q) a + C(q, v) v + g(q) = tau - tau_friction(v, z),

tau the applied joint torques (N m) or forces (N), tau_friction from
:class:`~youbot_dynamics.dynamics.friction.JointFriction` (positive along v, it resists),
z the friction's extra states (LuGre bristles; None without LuGre joints). Gravity is the
model's (``model.gravity``, default 9.81 m/s^2 along -z of the root frame). M includes the
model's ``armature`` (rotor inertia seen at the joint), as Pinocchio's algorithms do.

Friction is applied here and only here: Pinocchio 4.1 stores the URDF's
``<dynamics damping friction>`` in ``model.damping`` and ``model.friction`` but its rnea,
aba, crba and nonLinearEffects do not use them (test_rigid_body checks that), so nothing is
counted twice and the Robot's model needs no change.

Root joint (see :mod:`youbot_dynamics.model.robot`): q has ``robot.nq`` entries, v, a and tau
``robot.nv``, root coordinates first. The root's entries of tau are the generalised force on
the root link (its body wrench (f, n) for a floating root, (fx, fy, nz) planar); the root
has no friction: tau_friction acts on the URDF joints, v[robot.root_nv:], only. The root's
entries of a are the time derivative of its body twist (Pinocchio's convention), so a
floating robot at rest falls with a = (R^T g, 0, 0, ...), R the root link's orientation.
A wrong size is a UserInputError naming nq or nv.

``data`` is a Pinocchio Data of ``robot.model`` (``robot.model.createData()``), the caller's
scratch space; each call overwrites it. Returned arrays are fresh (not views of ``data``).

Speed: with a fixed root and float64 vectors the friction is the compiled loop called
without numba's type dispatch or reference counting (:mod:`youbot_dynamics.compiled`; the
types are checked in line, the loop checks the sizes); anything else takes
JointFriction.add_torque, which converts or names what is wrong. About 0.3 us over pin.rnea
and 0.6 us over pin.aba on the youBot arm (bench/bench_dynamics.py).

Batches: :func:`inverse_dynamics_batch` and :func:`forward_dynamics_batch` take N samples as
rows (q (N, nq), v, a, tau (N, nv), z (N, n_states)) and run Pinocchio's C++ loops
(``rneaInParallel`` / ``abaInParallel``) plus the friction of all rows in one compiled call:
no Python per sample. ``pool`` is their scratch space (``pin.ModelPool(robot.model, threads)``,
about 60 us to build: pass one to reuse it), ``threads`` the C++ threads (OpenMP) to use.
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit, types

from youbot_dynamics.dynamics.friction import (FLOAT, NO_BRISTLES, JointFriction, add_friction_torque_unchecked,
                                               subtract_friction_torque_unchecked)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.configuration import sized
from youbot_dynamics.model.robot import Robot

Vector = np.ndarray
#: np.ndarray under one global name: the in-line type checks below are on the hot path, where
#: ``np.ndarray`` costs a global and an attribute lookup per check (together 0.03 us a call).
_ARRAY = np.ndarray


def inverse_dynamics(robot: Robot, data: pin.Data, q: Vector, v: Vector, a: Vector,
                     friction: JointFriction | None = None, z: Vector | None = None) -> Vector:
    """tau = RNEA(q, v, a) + tau_friction(v, z) (nv): joint torques (N m) or forces (N)
    giving accelerations a (nv; rad/s^2, m/s^2) at positions q (nq) and velocities v (nv)."""
    try:
        tau = pin.rnea(robot.model, data, q, v, a)  # a fresh float64 vector; q, v and a are arrays
        if friction is not None:
            states = NO_BRISTLES if z is None else z
            if robot.root == "fixed" and v.dtype is FLOAT and v.ndim == 1 \
                    and type(states) is _ARRAY and states.dtype is FLOAT and states.ndim == 1:
                add_friction_torque_unchecked(v, states, friction.table, tau)
            else:
                friction.add_torque(tau[robot.root_nv:], v[robot.root_nv:], z)
    except (ValueError, TypeError):
        _check_sizes(robot, q, v=v, a=a)
        _check_friction(robot, friction, v, z)
        raise
    return tau


def forward_dynamics(robot: Robot, data: pin.Data, q: Vector, v: Vector, tau: Vector,
                     friction: JointFriction | None = None, z: Vector | None = None) -> Vector:
    """a = ABA(q, v, tau - tau_friction(v, z)) (nv): accelerations (rad/s^2, m/s^2) at
    positions q (nq) and velocities v (nv) under applied torques tau (nv; N m, N).

    Raises :class:`~youbot_dynamics.errors.SingularMassMatrixError` (naming the massless
    joints) when the robot's mass matrix is singular, instead of returning inf or NaN. With
    mimic joints, a = M(q)^-1 (tau - C(q, v) v - g(q)): Pinocchio 4.1's aba refuses them.
    """
    if robot.mass_matrix_defect:
        robot.require_regular_mass_matrix()
    try:
        if friction is not None:
            states = NO_BRISTLES if z is None else z
            if robot.root == "fixed" and type(v) is _ARRAY and v.dtype is FLOAT and v.ndim == 1 \
                    and type(tau) is _ARRAY and tau.dtype is FLOAT and tau.ndim == 1 \
                    and type(states) is _ARRAY and states.dtype is FLOAT and states.ndim == 1:
                tau = tau.copy()
                subtract_friction_torque_unchecked(v, states, friction.table, tau)
            else:
                tau = tau.astype(float) if type(tau) is np.ndarray else np.array(tau, dtype=float)  # a copy
                friction.add_torque(tau[robot.root_nv:], v[robot.root_nv:], z, -1.0)
        if robot.mimic:
            return np.linalg.solve(mass_matrix(robot, data, q), tau - bias_torque(robot, data, q, v))
        return pin.aba(robot.model, data, q, v, tau)
    except (ValueError, TypeError):
        _check_sizes(robot, q, v=v, tau=tau)
        _check_friction(robot, friction, v, z)
        raise


def inverse_dynamics_batch(robot: Robot, q: np.ndarray, v: np.ndarray, a: np.ndarray,
                           friction: JointFriction | None = None, z: np.ndarray | None = None, *,
                           pool: pin.ModelPool | None = None, threads: int = 1) -> np.ndarray:
    """:func:`inverse_dynamics` of every row: tau (N, nv; N m, N) for q (N, nq), v and a
    (N, nv; rad/s, rad/s^2), z (N, n_states) with LuGre joints."""
    q, v, a = _batch(robot, q, "q", "nq"), _batch(robot, v, "v", "nv"), _batch(robot, a, "a", "nv")
    _same_rows(q, v=v, a=a)
    pool = pin.ModelPool(robot.model, threads) if pool is None else pool
    tau = np.empty(v.shape)
    if len(tau):
        pin.rneaInParallel(threads, pool, q.T, v.T, a.T, tau.T)
    if friction is not None:
        root = robot.root_nv
        friction.add_torque(tau[:, root:], v[:, root:], z)
    return tau


def forward_dynamics_batch(robot: Robot, q: np.ndarray, v: np.ndarray, tau: np.ndarray,
                           friction: JointFriction | None = None, z: np.ndarray | None = None, *,
                           pool: pin.ModelPool | None = None, threads: int = 1) -> np.ndarray:
    """:func:`forward_dynamics` of every row: a (N, nv; rad/s^2, m/s^2) for q (N, nq), v and
    tau (N, nv; rad/s, N m), z (N, n_states) with LuGre joints. With mimic joints (which
    abaInParallel refuses) it is the per-sample function row by row."""
    q, v, tau = _batch(robot, q, "q", "nq"), _batch(robot, v, "v", "nv"), _batch(robot, tau, "tau", "nv")
    _same_rows(q, v=v, tau=tau)
    robot.require_regular_mass_matrix()
    if robot.mimic:
        data = robot.model.createData()
        return np.array([forward_dynamics(robot, data, q[k], v[k], tau[k], friction, None if z is None else z[k])
                         for k in range(len(q))]).reshape(v.shape)
    tau = tau.copy()
    if friction is not None:
        root = robot.root_nv
        friction.add_torque(tau[:, root:], v[:, root:], z, -1.0)
    pool = pin.ModelPool(robot.model, threads) if pool is None else pool
    a = np.empty(v.shape)
    if len(a):
        pin.abaInParallel(threads, pool, q.T, v.T, tau.T, a.T)
    return a


def _batch(robot: Robot, x: np.ndarray, name: str, size: str) -> np.ndarray:
    """x as a C-ordered float array of rows of ``size`` (nq or nv) values, or a UserInputError
    naming it."""
    x = np.ascontiguousarray(x, dtype=float)
    n = getattr(robot, size)
    if x.ndim != 2 or x.shape[1] != n:
        raise UserInputError(f"{name}: a batch needs shape (N, {size} = {n}) (one sample per row); "
                             f"got {x.shape}")
    return x


def _same_rows(q: np.ndarray, **others: np.ndarray) -> None:
    for name, x in others.items():
        if len(x) != len(q):
            raise UserInputError(f"{name}: {len(x)} samples (rows) against {len(q)} in q")


def _check_friction(robot: Robot, friction: JointFriction | None, v: Vector, z: Vector | None) -> None:
    """After the compiled friction loop refused its input (sizes checked by
    :func:`_check_sizes` first): the friction's own UserInputError naming the bristle
    states z expected, if they are what was wrong."""
    if friction is not None:
        friction.torque(np.asarray(v, dtype=float)[robot.root_nv:], z)


def _check_sizes(robot: Robot, q: Vector, **velocity_sized: Vector) -> None:
    """After Pinocchio refused its input: a UserInputError naming the vector whose size is
    not nq (q) or nv (the keyword arguments, by name), if one is; checked only then, so that
    a call with the right sizes pays nothing."""
    sized(robot, q, "q", "q")
    for name, x in velocity_sized.items():
        sized(robot, x, "v", name)


def symmetrised(upper: np.ndarray) -> np.ndarray:
    """The full symmetric matrix of one of which only the upper triangle is reliable (what
    Pinocchio's crba and computeMinverse fill); a fresh array in the input's memory order.
    Each entry is upper[i, j] + 0.0 (i <= j), mirrored: the same to the bit (signed zeros
    included) as triu(M) + triu(M, 1)^T, in one compiled pass (1 us for 20 x 20, where
    numpy's fancy indexing took 15)."""
    upper = np.asarray(upper, dtype=float)
    full = np.empty_like(upper)
    _mirror_upper(upper, full)
    return full


@njit(types.void(types.Array(types.float64, 2, "A", readonly=True), types.Array(types.float64, 2, "A")),
      cache=True)
def _mirror_upper(upper: np.ndarray, full: np.ndarray) -> None:
    """full[i, j] = full[j, i] = upper[i, j] + 0.0 for i <= j (square matrices)."""
    n = upper.shape[0]
    if upper.shape[1] != n or full.shape[0] != n or full.shape[1] != n:
        raise ValueError("symmetrised: the matrix must be square")
    for j in range(n):
        for i in range(j + 1):
            value = upper[i, j] + 0.0
            full[i, j] = value
            full[j, i] = value


def mass_matrix(robot: Robot, data: pin.Data, q: Vector) -> Vector:
    """Joint-space mass matrix M(q) (nv x nv; kg m^2, kg), full and symmetric, armature
    included, at positions q (nq)."""
    try:
        return symmetrised(pin.crba(robot.model, data, q))
    except (ValueError, TypeError):
        _check_sizes(robot, q)
        raise


def gravity_torque(robot: Robot, data: pin.Data, q: Vector) -> Vector:
    """g(q) (nv; N m, N) at positions q (nq): the torques that hold the robot still against
    gravity (for a floating root, the root's entries are the wrench that would hold it up)."""
    try:
        return pin.computeGeneralizedGravity(robot.model, data, q)
    except (ValueError, TypeError):
        _check_sizes(robot, q)
        raise


def bias_torque(robot: Robot, data: pin.Data, q: Vector, v: Vector) -> Vector:
    """C(q, v) v + g(q) (nv; N m, N) at positions q (nq) and velocities v (nv): Coriolis,
    centrifugal and gravity torques."""
    try:
        return pin.nonLinearEffects(robot.model, data, q, v)
    except (ValueError, TypeError):
        _check_sizes(robot, q, v=v)
        raise


def kinetic_energy(robot: Robot, data: pin.Data, q: Vector, v: Vector) -> float:
    """T = v . M(q) v / 2 (J) at positions q (nq) and velocities v (nv), armature included.

    Not pin.computeKineticEnergy: in Pinocchio 4.1 it leaves out the armature of
    RevoluteUnaligned joints (such as the youBot's arm_joint_1, axis -z).
    """
    return 0.5 * float(v @ mass_matrix(robot, data, q) @ v)


def potential_energy(robot: Robot, data: pin.Data, q: Vector) -> float:
    """V(q) = -sum_i m_i gravity . c_i (J) at positions q (nq), c_i the centre of mass of link
    i in the world (the root link's frame for a fixed root); zero with every centre of mass at
    the world origin's height (gravity along -z). With mimic joints (which Pinocchio 4.1's
    computePotentialEnergy refuses): -m gravity . c of the whole robot, the same sum."""
    try:
        if robot.mimic:
            com = pin.centerOfMass(robot.model, data, q)  # fills data.mass[0], the total mass (kg)
            return float(-data.mass[0] * robot.model.gravity.linear @ com)
        return float(pin.computePotentialEnergy(robot.model, data, q))
    except (ValueError, TypeError):
        _check_sizes(robot, q)
        raise
