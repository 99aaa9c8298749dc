"""Configurations on the manifold: neutral pose, integration and difference of q.

A robot's configuration q has ``robot.nq`` entries and its velocity v ``robot.nv``; with a
floating or planar root they differ (nq = nv + 1, see :mod:`youbot_dynamics.model.robot`)
and q + v dt is wrong: the root orientation (a unit quaternion, or cos and sin of the yaw)
must move on its manifold. These functions are Pinocchio's ``neutral``, ``integrate`` and
``difference`` with sizes checked; with a fixed root they reduce to 0, q + v dt and q1 - q0.
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot

Vector = np.ndarray


def sized(robot: Robot, x: Vector, of: str, what: str) -> Vector:
    """``x`` as a float array after checking that it has nq (``of="q"``) or nv (``of="v"``)
    entries; a UserInputError naming ``what`` and the expected size otherwise."""
    x = np.asarray(x, dtype=float)
    expected = robot.nq if of == "q" else robot.nv
    if x.shape != (expected,):
        names = robot.q_names if of == "q" else robot.v_names
        raise UserInputError(f"{what}: expected {expected} values ({of} of robot '{robot.name}' with "
                             f"a {robot.root} root: {', '.join(names)}); got shape {x.shape}")
    return x


def neutral(robot: Robot) -> Vector:
    """The neutral configuration (nq): root at the world origin with identity orientation
    (quaternion (0, 0, 0, 1), or cos = 1, sin = 0), every joint at 0 (rad or m)."""
    return pin.neutral(robot.model)


def integrate(robot: Robot, q: Vector, v: Vector, dt: float = 1.0) -> Vector:
    """q (+) v dt: the configuration (nq) reached from q (nq) by moving at the constant
    velocity v (nv; root twist in the root link's frame, m/s and rad/s) for dt seconds, on the
    manifold (``pin.integrate``): for a fixed root it is q + v dt."""
    q = sized(robot, q, "q", "integrate: q")
    v = sized(robot, v, "v", "integrate: v")
    return pin.integrate(robot.model, q, v * dt)


def difference(robot: Robot, q0: Vector, q1: Vector) -> Vector:
    """q1 (-) q0 (nv): the constant velocity that moves q0 to q1 in one second
    (``pin.difference``), so that integrate(robot, q0, difference(robot, q0, q1)) == q1."""
    q0 = sized(robot, q0, "q", "difference: q0")
    q1 = sized(robot, q1, "q", "difference: q1")
    return pin.difference(robot.model, q0, q1)


def random_configuration(robot: Robot, rng: np.random.Generator, *, span: float = 1.0) -> Vector:
    """A random configuration (nq) from ``rng``: joints uniform within their limits (within
    [-pi, pi] where a limit is infinite), the root position uniform in [-span, span] m per
    axis (z is 0 for a planar root) and its orientation uniform (a normalised Gaussian
    quaternion, or a uniform yaw)."""
    lower = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    upper = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    joints = rng.uniform(lower, upper)
    if robot.root == "floating":
        quaternion = rng.normal(size=4)
        root = np.concatenate([rng.uniform(-span, span, 3), quaternion / np.linalg.norm(quaternion)])
    elif robot.root == "planar":
        yaw = rng.uniform(-np.pi, np.pi)
        root = np.concatenate([rng.uniform(-span, span, 2), [np.cos(yaw), np.sin(yaw)]])
    else:
        root = np.zeros(0)
    return np.concatenate([root, joints])


def require_fixed_root(robot: Robot, where: str) -> None:
    """Refuse a floating or planar root where code moves q by q + v dt (nq == nv assumed):
    a one-line UserInputError naming ``where``."""
    if robot.root != "fixed":
        raise UserInputError(f"{where}: robot '{robot.name}' has a {robot.root} root (nq = "
                             f"{robot.nq}, nv = {robot.nv}), which this simulator does not "
                             "integrate yet; load it with root 'fixed'")
