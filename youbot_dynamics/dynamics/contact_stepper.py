"""Constraint-based time stepping with Pinocchio's contact solvers (no home-made LCP).

It steps the scene's one Pinocchio model (the robot's joints followed by one free-flyer
joint per free body: configuration (p, quaternion x y z w), velocity the body-frame twist)
and reads the contact geometry from the scene's
:class:`~youbot_dynamics.dynamics.contact_model.ContactModel`, as the compliant and impulsive
laws do; the step stays on the manifold through ``pin.integrate``. A step of size h (semi-implicit Euler, velocity
level, Moreau-Jean style):

1. free velocity v_f = v + h ABA(q, v, tau);
2. for every contact point within ``margin`` (coal, dynamics/collision.py) a
   ``PointContactConstraintModel`` between the two owners' joints, its frame's z axis along
   the normal from geometry 1 to geometry 2, with the pair's Coulomb coefficient;
3. the Delassus matrix G = J M^-1 J^T and the drift g = J v_f + b, where the normal part of
   b lets a gap phi > 0 close within the step (phi / h: no tunnelling), pushes an overlap
   out at the rate ``baumgarte`` (-phi) / h; a point approaching faster than
   ``restitution_threshold`` that would close its gap within the step asks instead for
   the rebound v_n+ >= e (-v_n) (Newton's law; the bounce happens up to one step early);
4. impulses lambda from ``pin.PGSConstraintSolver`` or ``pin.ADMMConstraintSolver`` (the
   friction cone as given), v+ = v_f + M^-1 J^T lambda, q+ = integrate(q, h v+).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.collision import BroadPhase
from youbot_dynamics.dynamics.contact_model import ContactModel
from youbot_dynamics.dynamics.rigid_body import symmetrised


@dataclass(frozen=True)
class StepperSettings:
    """Solver (pgs or admm), its iteration cap and tolerance, the look-ahead margin (m),
    the overlap correction rate (per step) and the restitution threshold (m/s)."""

    solver: str = "pgs"
    max_iterations: int = 200
    tolerance: float = 1e-10
    margin: float = 0.01
    baumgarte: float = 0.2
    restitution_threshold: float = 0.05


@dataclass
class StepReport:
    """What one step found: per pair the summed normal impulse (N s), the deepest overlap
    (m) and the solver's iterations."""

    normal_impulse: dict[str, float] = field(default_factory=dict)
    penetration: float = 0.0
    iterations: int = 0


def _contact_rotation(normal: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is ``normal``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, normal)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(normal, x), normal])


class ConstraintStepper:
    """One :meth:`step` of the constraint-based law on ``contact``'s model."""

    def __init__(self, contact: ContactModel, settings: StepperSettings) -> None:
        self.contact, self.model, self.settings = contact, contact.model, settings
        self.broad = BroadPhase([g.shape for g in contact.geometries],
                                [(p.first, p.second) for p in contact.pairs], settings.margin)

    def step(self, data: pin.Data, q: np.ndarray, v: np.ndarray, tau: np.ndarray,
             h: float) -> tuple[np.ndarray, np.ndarray, StepReport]:
        """(q+, v+, report) after one step of h seconds under generalised forces tau (nv,);
        ``data`` is a Data of the model (scratch)."""
        model, settings, contact = self.model, self.settings, self.contact
        report = StepReport()
        v_free = v + h * pin.aba(model, data, q, v, tau)
        pin.framesForwardKinematics(model, data, q)
        poses = contact.poses(data)
        constraints = pin.StdVec_ConstraintModel()
        rows: list[tuple[int, float, str, float]] = []
        for k in self.broad.close_pairs(poses):
            pair = contact.pairs[k]
            name, law = pair.name, pair.law
            points = contact.points(k, poses, settings.margin)
            if points:
                joint1, joint2 = contact.owner_joint(pair.first), contact.owner_joint(pair.second)
                world1, world2 = data.oMi[joint1], data.oMi[joint2]
            for c in points:
                rotation = _contact_rotation(c.normal)
                point = pin.PointContactConstraintModel(
                    model, joint1, world1.actInv(pin.SE3(rotation, c.point1)),
                    joint2, world2.actInv(pin.SE3(rotation, c.point2)))
                point.setFriction(law.friction)
                constraints.append(pin.ConstraintModel(point))
                rows.append((len(rows), -c.depth, name, law.restitution))
                report.penetration = max(report.penetration, c.depth)
        if not rows:
            return pin.integrate(model, q, h * v_free), v_free, report
        datas = pin.StdVec_ConstraintData()
        for constraint in constraints:
            datas.append(constraint.createData())
        pin.computeJointJacobians(model, data, q)
        for constraint, cdata in zip(constraints, datas):
            constraint.calc(model, data, cdata)
        jacobian = pin.getConstraintsJacobian(model, data, constraints, datas)
        inverse_mass = symmetrised(pin.computeMinverse(model, data, q))
        delassus = jacobian @ inverse_mass @ jacobian.T
        drift = jacobian @ v_free
        before = jacobian @ v
        for i, gap, _, restitution in rows:
            n = 3 * i + 2
            if before[n] < -settings.restitution_threshold and gap + h * before[n] < 0:
                drift[n] += restitution * before[n]
            else:
                drift[n] += gap / h if gap > 0 else settings.baumgarte * gap / h
        impulses = self._solve(delassus, drift, constraints, datas, report)
        v_next = v_free + inverse_mass @ jacobian.T @ impulses
        for i, _, name, _ in rows:
            report.normal_impulse[name] = report.normal_impulse.get(name, 0.0) + float(impulses[3 * i + 2])
        return pin.integrate(model, q, h * v_next), v_next, report

    def _solve(self, delassus: np.ndarray, drift: np.ndarray, constraints, datas, report: StepReport) -> np.ndarray:
        size = drift.size
        if self.settings.solver == "pgs":
            solver, options, result = pin.PGSConstraintSolver(size), pin.PGSSolverSettings(), pin.PGSSolverResult()
        else:
            solver, options, result = pin.ADMMConstraintSolver(size), pin.ADMMSolverSettings(), pin.ADMMSolverResult()
            options.lanczos_size = size
        options.max_iterations = self.settings.max_iterations
        options.absolute_feasibility_tol = self.settings.tolerance
        options.absolute_complementarity_tol = self.settings.tolerance
        solver.solve(pin.DelassusOperatorDense(delassus), drift, constraints, datas, options, result)
        report.iterations = int(result.iterations)
        return np.array(result.retrieveConstraintImpulses())
