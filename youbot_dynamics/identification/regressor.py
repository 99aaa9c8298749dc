"""The joint-torque regressor with friction: tau = Y(q, v, a) theta.

Standard parameters, per moving body in Pinocchio's order (``model.inertias[1:]``), ten
each, in Pinocchio 4.1's ``Inertia.toDynamicParameters`` order:

    m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz

(kg, kg m, kg m^2), the first moments and the inertia about the ORIGIN of the body's
joint frame (not about the centre of mass), in that frame. Then per joint, for the friction
terms chosen (:data:`FRICTION_TERMS`, in this order): viscous b (N m s/rad), Coulomb F_c
(N m; the column is the simulator's regularised law ``friction.coulomb(v, 1, v_s)``, so
tanh(v / v_s)) and a constant offset (N m). Prismatic joints read N for N m and m for rad.

Y's inertial part is Pinocchio's ``computeJointTorqueRegressor``; tau = Y theta equals
``inverse_dynamics(robot, data, q, v, a, JointFriction.from_urdf(robot))`` for the URDF's
own parameters (offset 0), which test_identification checks to 1e-10.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics import friction
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot

#: Names of the ten inertial parameters of a body, Pinocchio's toDynamicParameters order.
INERTIAL_PARAMETERS = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
#: Friction terms a regressor can carry per joint, in column order.
FRICTION_TERMS = ("viscous", "coulomb", "offset")


@dataclass(frozen=True)
class RegressorLayout:
    """What the columns of Y stand for: a robot with a fixed root, the friction terms per
    joint and the Coulomb regularisation scale v_s (rad/s). ``names`` gives every column,
    ``<body>.<parameter>`` for inertial ones, ``<joint>.<term>`` for friction ones."""

    robot: Robot
    friction_terms: tuple[str, ...] = FRICTION_TERMS
    velocity_scale: float = friction.DEFAULT_VELOCITY_SCALE

    def __post_init__(self) -> None:
        if self.robot.root != "fixed":
            raise UserInputError(f"identification: robot '{self.robot.name}' needs a fixed root, "
                                 f"got '{self.robot.root}'")
        unknown = [t for t in self.friction_terms if t not in FRICTION_TERMS]
        if unknown:
            raise UserInputError(f"identification: unknown friction term(s) {', '.join(unknown)}; "
                                 f"known: {', '.join(FRICTION_TERMS)}")
        ordered = tuple(t for t in FRICTION_TERMS if t in self.friction_terms)
        object.__setattr__(self, "friction_terms", ordered)

    @property
    def body_names(self) -> tuple[str, ...]:
        """The moving bodies, named by the joint that carries each (Pinocchio's order)."""
        return tuple(self.robot.model.names[1:])

    @property
    def n_inertial(self) -> int:
        """Number of inertial columns: 10 per moving body."""
        return 10 * (self.robot.model.njoints - 1)

    @property
    def names(self) -> tuple[str, ...]:
        """Column names: inertial first (body by body), then friction (joint by joint)."""
        inertial = [f"{body}.{p}" for body in self.body_names for p in INERTIAL_PARAMETERS]
        return (*inertial, *(f"{j}.{t}" for j in self.robot.joint_names for t in self.friction_terms))

    def standard_parameters(self, offsets: Sequence[float] | None = None) -> np.ndarray:
        """theta of the robot's own model: inertias from the URDF, viscous b = damping and
        Coulomb F_c = friction from ``<dynamics>``, offsets (N m) default 0."""
        model = self.robot.model
        inertial = [model.inertias[i].toDynamicParameters() for i in range(1, model.njoints)]
        values = {"viscous": self.robot.damping, "coulomb": self.robot.friction,
                  "offset": np.zeros(self.robot.nv) if offsets is None else np.asarray(offsets, float)}
        per_joint = np.column_stack([values[t] for t in self.friction_terms]).ravel() \
            if self.friction_terms else np.zeros(0)
        return np.concatenate([*inertial, per_joint])

    def regressor(self, data: pin.Data, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Y(q, v, a), nv x (10 bodies + terms per joint): q in rad or m, v in rad/s, a in
        rad/s^2 (Pinocchio's joint order)."""
        inertial = pin.computeJointTorqueRegressor(self.robot.model, data, q, v, a)
        return np.hstack([inertial, self.friction_columns(v)])

    def friction_columns(self, v: np.ndarray) -> np.ndarray:
        """The friction block at velocities v (..., nv): (..., nv, nv terms), joint i's
        columns nonzero on row i only."""
        v = np.asarray(v, float)
        n, k = v.shape[-1], len(self.friction_terms)
        columns = {"viscous": lambda: friction.viscous(v, 1.0),
                   "coulomb": lambda: friction.coulomb(v, 1.0, self.velocity_scale),
                   "offset": lambda: np.ones_like(v)}
        block = np.zeros((*v.shape, n * k))
        for t, term in enumerate(self.friction_terms):
            block[..., np.arange(n), np.arange(n) * k + t] = columns[term]()
        return block

    def stacked(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Y over N samples (rows (N, nv) each), stacked sample by sample: (N nv) x p."""
        model, data = self.robot.model, self.robot.model.createData()
        inertial = np.stack([pin.computeJointTorqueRegressor(model, data, qk, vk, ak)
                             for qk, vk, ak in zip(q, v, a)])
        return np.concatenate([inertial, self.friction_columns(v)], axis=2).reshape(-1, len(self.names))


def random_samples(robot: Robot, count: int, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """``count`` random (q, v, a): q uniform within the position limits (continuous joints
    in [-pi, pi]), v and a standard normal (rad/s, rad/s^2)."""
    lower = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    upper = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    q = rng.uniform(lower, upper, size=(count, robot.nv))
    return q, rng.standard_normal((count, robot.nv)), rng.standard_normal((count, robot.nv))
