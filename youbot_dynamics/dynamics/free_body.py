"""Free bodies: six-degree-of-freedom rigid objects and their Newton-Euler equations.

Mass and inertia come from the shape and a density (Pinocchio's ``Inertia.From*`` and
coal's volume) or are given; the inertia is about the centre of mass in the body frame,
whose origin is the centre of mass.

State of one body (13 + 3 numbers, world frame unless said otherwise):
``p`` position of the centre of mass (m), ``r`` reference orientation as a unit quaternion
(x, y, z, w), ``phi`` rotation vector (rad) of the local coordinates about it, ``u`` linear
velocity (m/s), ``w`` angular velocity (rad/s). The orientation is R = R(r) exp([phi]).
Within a segment ``r`` is constant (zero derivative) and ``phi`` obeys
d phi/dt = Jr^-1(phi) R^T w (Jr^-1 = Pinocchio's Jlog3), so any ODE integrator keeps R on
SO(3) exactly; :func:`recentred` folds phi into r (re-normalised) when |phi| grows, at
segment boundaries (an event at |phi| = ``RECENTRE_ANGLE``).

For the constraint stepper the same body is a Pinocchio free-flyer joint
(:func:`add_free_flyer`), integrated with ``pin.integrate``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.collision import Shape
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.lie import exp_so3, matrix_from_quaternion, quaternion_from_matrix

#: |phi| (rad) beyond which the local coordinates are re-centred.
RECENTRE_ANGLE = 1.0
#: Components of one body's state, in order, with their sizes.
BODY_BLOCKS = (("p", 3), ("r", 4), ("phi", 3), ("u", 3), ("w", 3))


@dataclass(frozen=True)
class FreeBody:
    """A rigid object: mass (kg), inertia (3x3 kg m^2, body frame about the centre of mass)."""

    name: str
    mass: float
    inertia: np.ndarray

    @classmethod
    def from_shape(cls, name: str, shape: Shape, density: float) -> FreeBody:
        """Uniform body of the given shape and density (kg/m^3)."""
        if shape.kind == "halfspace":
            raise UserInputError(f"free body {name!r}: a half-space has no finite mass")
        mass = density * shape.coal_geometry().computeVolume()
        if shape.kind == "sphere":
            inertia = pin.Inertia.FromSphere(mass, shape.radius)
        elif shape.kind == "box":
            inertia = pin.Inertia.FromBox(mass, *shape.size)
        elif shape.kind == "cylinder":
            inertia = pin.Inertia.FromCylinder(mass, shape.radius, shape.length)
        else:
            inertia = pin.Inertia.FromCapsule(mass, shape.radius, shape.length)
        return cls(name, mass, inertia.inertia.copy())

    def world_inertia(self, rotation: np.ndarray) -> np.ndarray:
        """I_w = R I R^T (kg m^2): the inertia about the centre of mass in world axes, for
        the orientation R (3x3, body axes in the world frame)."""
        return rotation @ self.inertia @ rotation.T

    def spatial_inertia(self) -> pin.Inertia:
        """Pinocchio's spatial inertia (centre of mass at the body origin)."""
        return pin.Inertia(self.mass, np.zeros(3), self.inertia)


def orientation(reference: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """R = R(reference quaternion x, y, z, w) exp([phi]) (phi in rad): the body's axes in
    the world frame (3x3)."""
    return matrix_from_quaternion(reference) @ exp_so3(phi)


def recentred(reference: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """The reference quaternion (x, y, z, w, unit, w >= 0) of R(reference) exp([phi])."""
    return quaternion_from_matrix(orientation(reference, phi))


def phi_rate(phi: np.ndarray, rotation: np.ndarray, omega_world: np.ndarray) -> np.ndarray:
    """d phi/dt = Jr^-1(phi) R^T w (rad/s), w the world-frame angular velocity (rad/s) and
    R the body's orientation (3x3, body axes in the world frame)."""
    return pin.Jlog3(exp_so3(phi)) @ (rotation.T @ omega_world)


def newton_euler(body: FreeBody, rotation: np.ndarray, omega_world: np.ndarray, force: np.ndarray,
                 torque: np.ndarray, gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear and angular accelerations (world frame) under the total force (N) and torque
    about the centre of mass (N m), both world frame: m a = f + m g,
    I_w dw/dt = tau - w x I_w w with I_w = R I R^T."""
    inertia_world = body.world_inertia(rotation)
    gyroscopic = np.cross(omega_world, inertia_world @ omega_world)
    return force / body.mass + gravity, np.linalg.solve(inertia_world, torque - gyroscopic)


def kinetic_energy(body: FreeBody, rotation: np.ndarray, u: np.ndarray, omega_world: np.ndarray) -> float:
    """Translational plus rotational kinetic energy (J)."""
    inertia_world = body.world_inertia(rotation)
    return 0.5 * body.mass * float(u @ u) + 0.5 * float(omega_world @ inertia_world @ omega_world)


def add_free_flyer(model: pin.Model, body: FreeBody) -> int:
    """Append ``body`` to ``model`` as a free-flyer joint under the universe; its joint id.
    Pinocchio's configuration is (p, quaternion x y z w), its velocity the body-frame
    (linear, angular) twist."""
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), body.name)
    model.appendBodyToJoint(joint, body.spatial_inertia(), pin.SE3.Identity())
    model.addBodyFrame(body.name, joint, pin.SE3.Identity(), 0)
    return joint
