"""Closed kinematic loops of a robot model as a HolonomicSystem (dynamics.constraints).

URDF describes trees only, so a closed mechanism is given as the URDF of a spanning tree
(a :class:`~youbot_dynamics.model.robot.Robot`) plus loop-closure constraints, each a
Pinocchio 4 constraint model between two joints of that tree, of which some or all
residual components are imposed (:class:`LoopClosure`; a planar loop imposes two of a
point anchor's three). :func:`holonomic_system_from_robot` turns them into the
HolonomicSystem that every formulation of dynamics.constraints integrates:

- M(q): Pinocchio's crba (dynamics.rigid_body.mass_matrix), armature included.
- f(q, v) = -(C(q, v) v + g(q)) - tau_friction(v): nonLinearEffects
  (dynamics.rigid_body.bias_torque) and optionally a memoryless JointFriction.
- g(q): the constraint data's ``constraint_position_error`` after forwardKinematics.
  Point anchor (``pin.PointAnchorConstraintModel``): e = R1^T (p2 - p1) - offset (m), the
  anchor point c2 on joint 2's side seen from the anchor point c1 on joint 1's side, in
  c1's axes (c_k = oMi[joint k] * joint k placement). Frame anchor
  (``pin.FrameAnchorConstraintModel``): log6(c1Mc2) (m, rad; linear part first).
- G(q): ``pin.getConstraintJacobian`` after computeJointJacobians (world-frame data.J);
  same rows and sign as g. For the point anchor it is exactly dg/dq everywhere (columns
  +R1^T v_c2 - v_c1 - omega_1 x e in c1's axes). For the frame anchor it maps v to the
  twist of c2 relative to c1 in c1, which is d(log6)/dt only where g = 0 (Jlog6 = I):
  exact on the constraint manifold, so the formulations hold, and Newton on g (projection,
  consistent initial values) converges, linearly away from it.
- g_qq(v, v): the constraint data's ``constraint_acceleration_error`` after
  forwardKinematics(q, v, a = 0): the relative acceleration of c2 with respect to c1
  (classical, i.e. d^2 e/dt^2, for the point anchor) at zero joint acceleration, which is
  (dG/dt) v. The constraints' desired velocity and acceleration must stay zero (their
  defaults); a desired offset shifts g only.

Multipliers follow dynamics.constraints: M v' = f - G^T lambda, so lambda is minus the
force (N; N m for frame-anchor rotations) that the loop exerts on joint 2's side at c2,
in c1's axes. Pinocchio's constraintDynamics (legacy RigidConstraintModel, made by
``pin.convertToRigidConstraintModel(model, point_anchor, pin.LOCAL)``) writes
M a = tau - b + J^T f_c with J = -G on the constraint manifold, so its ``data.lambda_c``
equals lambda in the imposed components (test_closed_loop checks both). For a planar loop
its 3D Delassus matrix is singular (zero out-of-plane row): the default ProximalSettings
(mu = 0) give NaN, a small proximal mu (e.g. ``pin.ProximalSettings(1e-14, 1e-10, 200)``)
gives the solution.

No second derivatives are given, so IDA differences the DAE residual for its iteration
matrix. One Pinocchio Data and one constraint data per loop are the system's scratch
space: the system is not for concurrent use from several threads.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.constraints import HolonomicSystem
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import bias_torque, mass_matrix
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot

Vector = np.ndarray
ConstraintModel = pin.PointAnchorConstraintModel | pin.FrameAnchorConstraintModel
SUPPORTED_CONSTRAINTS: tuple[type, ...] = (pin.PointAnchorConstraintModel,
                                           pin.FrameAnchorConstraintModel)

__all__ = ["LoopClosure", "holonomic_system_from_robot", "point_anchor"]


@dataclass(frozen=True)
class LoopClosure:
    """A loop-closure constraint: a Pinocchio constraint model of the robot's model and the
    indices of its residual components that are imposed (in the constraint's own order:
    x, y, z of c1's axes for a point anchor; linear then angular for a frame anchor)."""

    constraint: ConstraintModel
    components: tuple[int, ...]

    @property
    def name(self) -> str:
        return self.constraint.name or type(self.constraint).__name__


def point_anchor(robot: Robot, frame1: str, frame2: str,
                 components: Sequence[int] = (0, 1, 2)) -> LoopClosure:
    """Coincidence of the origins of two frames (links or joints) of ``robot``: a
    PointAnchorConstraintModel between their parent joints at the frames' placements,
    imposing ``components`` of the error R1^T (p2 - p1) (axes of ``frame1``; for a planar
    loop the two in-plane ones)."""
    model = robot.model
    first, second = (model.frames[robot.frame_id(name)] for name in (frame1, frame2))
    constraint = pin.PointAnchorConstraintModel(model, first.parentJoint, first.placement,
                                                second.parentJoint, second.placement)
    constraint.name = f"{frame1}=={frame2}"
    return LoopClosure(constraint, tuple(int(i) for i in components))


def _checked(robot: Robot, closures: Sequence[LoopClosure]) -> tuple[LoopClosure, ...]:
    """The closures, each of a supported type, on joints of the robot's model, with
    distinct components inside its residual; UserInputError naming the loop otherwise."""
    for closure in closures:
        constraint = closure.constraint
        where = f"robot '{robot.name}': loop closure '{closure.name}'"
        if not isinstance(constraint, SUPPORTED_CONSTRAINTS):
            raise UserInputError(f"{where}: {type(constraint).__name__} is not supported; use "
                                 + " or ".join(c.__name__ for c in SUPPORTED_CONSTRAINTS))
        joints = (constraint.joint1_id, constraint.joint2_id)
        if max(joints) >= robot.model.njoints or joints[0] == joints[1]:
            raise UserInputError(f"{where}: joints {joints} must be two distinct joints of "
                                 f"the model (0..{robot.model.njoints - 1})")
        size = constraint.residualSize()
        components = closure.components
        if not components or len(set(components)) != len(components) or any(
                not 0 <= i < size for i in components):
            raise UserInputError(f"{where}: components {list(components)} must be distinct "
                                 f"indices in 0..{size - 1}")
        if np.any(constraint.desired_constraint_velocity) or np.any(
                constraint.desired_constraint_acceleration):
            raise UserInputError(f"{where}: a holonomic loop needs zero desired constraint "
                                 "velocity and acceleration")
    return tuple(closures)


def holonomic_system_from_robot(robot: Robot, constraints: Sequence[LoopClosure], *,
                                friction: JointFriction | None = None,
                                name: str | None = None) -> HolonomicSystem:
    """The HolonomicSystem of ``robot`` (the spanning tree, joint coordinates in Pinocchio's
    order) closed by ``constraints``; formulas and conventions in the module docstring.

    ``friction`` adds a memoryless joint friction law to f (LuGre joints carry states a
    HolonomicSystem has no room for and are refused).
    """
    closures = _checked(robot, constraints)
    if friction is not None and friction.n_states:
        raise UserInputError(f"robot '{robot.name}': LuGre friction on "
                             f"{', '.join(friction.state_names)} has states; a closed-loop "
                             "system takes memoryless friction laws only")
    model = robot.model
    data = model.createData()
    constraint_datas = [closure.constraint.createData() for closure in closures]
    imposed = [np.array(closure.components) for closure in closures]
    zero_acceleration = np.zeros(model.nv)

    def stacked(attribute: str) -> Vector:
        """The imposed components of ``attribute`` of every loop, after calc on ``data``."""
        blocks = []
        for closure, constraint_data, components in zip(closures, constraint_datas, imposed):
            closure.constraint.calc(model, data, constraint_data)
            blocks.append(getattr(constraint_data, attribute)[components])
        return np.concatenate(blocks)

    def constraint(q: Vector) -> Vector:
        pin.forwardKinematics(model, data, q)
        return stacked("constraint_position_error")

    def jacobian(q: Vector) -> np.ndarray:
        pin.computeJointJacobians(model, data, q)
        blocks = []
        for closure, constraint_data, components in zip(closures, constraint_datas, imposed):
            closure.constraint.calc(model, data, constraint_data)
            rows = pin.getConstraintJacobian(model, data, closure.constraint, constraint_data)
            blocks.append(rows[components])
        return np.vstack(blocks)

    def curvature(q: Vector, v: Vector) -> Vector:
        pin.forwardKinematics(model, data, q, v, zero_acceleration)
        return stacked("constraint_acceleration_error")

    def forces(q: Vector, v: Vector) -> Vector:
        f = -bias_torque(robot, data, q, v)
        if friction is not None:
            f -= friction.torque(v)
        return f

    return HolonomicSystem(
        name=name or robot.name, position_names=robot.joint_names,
        n_constraints=sum(len(closure.components) for closure in closures),
        mass=lambda q: mass_matrix(robot, data, q), forces=forces, constraint=constraint,
        jacobian=jacobian, curvature=curvature)
