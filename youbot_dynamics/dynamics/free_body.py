"""Free bodies: six-degree-of-freedom rigid objects, as Pinocchio free-flyer joints.

Mass and inertia come from the shape and a density (Pinocchio's ``Inertia.From*`` and
coal's volume) or are given; the inertia is about the centre of mass in the body frame,
whose origin is the centre of mass.

A body's dynamics are Pinocchio's: :func:`add_free_flyer` appends it to the scene's one
model as a free-flyer joint (configuration (p, quaternion x y z w), velocity the body-frame
twist (v, w)), so ABA, the mass matrix, the energies and ``pin.integrate`` cover it with the
robot's joints. Nothing here integrates Newton-Euler by hand.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.collision import Shape
from youbot_dynamics.errors import UserInputError


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

    def spatial_inertia(self) -> pin.Inertia:
        """Pinocchio's spatial inertia (centre of mass at the body origin)."""
        return pin.Inertia(self.mass, np.zeros(3), self.inertia)


def add_free_flyer(model: pin.Model, body: FreeBody) -> tuple[int, int]:
    """Append ``body`` to ``model`` (in place) as a free-flyer joint under the universe;
    returns (joint id, body frame id). Pinocchio's configuration is (p, quaternion x y z w),
    its velocity the body-frame (linear, angular) twist."""
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), body.name)
    model.appendBodyToJoint(joint, body.spatial_inertia(), pin.SE3.Identity())
    frame = model.addBodyFrame(body.name, joint, pin.SE3.Identity(), 0)
    return joint, frame
