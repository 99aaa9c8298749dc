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
4. impulses lambda from ``pin.PGSConstraintSolver`` (stopped by its fixed-point test, see
   :class:`ContactSet`) or ``pin.ADMMConstraintSolver`` (the friction cone as given),
   v+ = v_f + M^-1 J^T lambda, q+ = integrate(q, h v+).

Nothing of this is rebuilt per step: one ABA pass (world convention) places the joints and
fills the joint Jacobians, ``computeMinverse`` reuses it for M^-1 of the whole step; coal's
geometry model places the geometries on those joints and measures every pair in two C++
calls (:meth:`ContactModel.touching`); and the constraint models, their datas and
the solver with its settings and result are built once per contact SET (which pairs touch
at how many points, a :class:`ContactSet`) and kept, the step only moving the contact
frames in place.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numba import njit, types
from numba.extending import register_jitable

from youbot_dynamics.dynamics.collision import ContactPoint
from youbot_dynamics.dynamics.contact_model import ContactModel
from youbot_dynamics.compiled import unchecked
from youbot_dynamics.dynamics.friction import READ_VECTOR, WRITTEN_VECTOR

#: PGS stops when a sweep moves no impulse by more than this fraction of the largest (see
#: :class:`ContactSet`); ``tolerance`` is ADMM's.
PGS_FIXED_POINT = 1e-14
#: Contact sets kept at once; beyond it the oldest is dropped (a scene cycles through few).
MAX_CONTACT_SETS = 64


@dataclass(frozen=True)
class StepperSettings:
    """Solver (pgs or admm), its iteration cap and (ADMM's) tolerance, the look-ahead margin (m),
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
    (m) and the solver's iterations; per contact point its pair's name (``names``), the point
    (``points``: normal from the pair's first geometry to its second) and its impulse on the
    second geometry (``impulses``, N s, rows 3i, 3i + 1 tangential, 3i + 2 normal in the
    contact frame :func:`contact_rotation` of the normal)."""

    normal_impulse: dict[str, float] = field(default_factory=dict)
    penetration: float = 0.0
    iterations: int = 0
    names: list[str] = field(default_factory=list)
    points: list = field(default_factory=list)
    impulses: np.ndarray | None = None


@njit(types.void(READ_VECTOR, types.Array(types.float64, 2, "A")), cache=True)
def _contact_rotation(normal: np.ndarray, out: np.ndarray) -> None:
    """out = :func:`contact_rotation` of ``normal`` (3,), in place (3 x 3)."""
    if normal.shape[0] != 3 or out.shape[0] != 3 or out.shape[1] != 3:
        raise ValueError("contact rotation: a normal (3,) and a 3 x 3 output")
    n0, n1, n2 = normal[0], normal[1], normal[2]
    if abs(n0) < 0.9:  # helper (1, 0, 0)
        x0, x1, x2 = 0.0, -n2, n1
    else:              # helper (0, 1, 0)
        x0, x1, x2 = n2, 0.0, -n0
    length = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    x0, x1, x2 = x0 / length, x1 / length, x2 / length
    out[0, 0], out[0, 1], out[0, 2] = x0, n1 * x2 - n2 * x1, n0
    out[1, 0], out[1, 1], out[1, 2] = x1, n2 * x0 - n0 * x2, n1
    out[2, 0], out[2, 1], out[2, 2] = x2, n0 * x1 - n1 * x0, n2


def contact_rotation(normal: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is the unit ``normal``: x = helper x normal normalised (helper
    the world x axis, or y when the normal is near x), y = normal x x. Compiled scalar
    arithmetic (np.cross costs tens of microseconds), the same roundings as the vector
    formulas."""
    rotation = np.empty((3, 3))
    _contact_rotation(np.asarray(normal, dtype=float), rotation)
    return rotation


_READ_MATRIX, _WRITTEN_MATRIX = types.Array(types.float64, 2, "A", readonly=True), types.Array(types.float64, 2, "A")
_TREES = types.Array(types.int64, 1, "C", readonly=True)


@njit(types.void(READ_VECTOR, READ_VECTOR, READ_VECTOR, _READ_MATRIX, READ_VECTOR, _READ_MATRIX, READ_VECTOR,
                 _WRITTEN_MATRIX, WRITTEN_VECTOR, _WRITTEN_MATRIX, WRITTEN_VECTOR), cache=True)
def _contact_placements(normal: np.ndarray, point1: np.ndarray, point2: np.ndarray, rotation1: np.ndarray,
                        translation1: np.ndarray, rotation2: np.ndarray, translation2: np.ndarray,
                        out_rotation1: np.ndarray, out_translation1: np.ndarray, out_rotation2: np.ndarray,
                        out_translation2: np.ndarray) -> None:
    """A contact point's frame in its two joints' frames, in place: the contact frame (z along
    the ``normal``, :func:`contact_rotation`) at ``point1`` seen from joint 1, placed in the
    world at (``rotation1``, ``translation1``), and at ``point2`` seen from joint 2 (world,
    m): Pinocchio's SE3 actInv, R^T R_c and R^T (c - p), its sums in its order (to the
    bit)."""
    if (normal.shape[0] != 3 or point1.shape[0] != 3 or point2.shape[0] != 3 or translation1.shape[0] != 3
            or translation2.shape[0] != 3 or out_translation1.shape[0] != 3 or out_translation2.shape[0] != 3
            or rotation1.shape != (3, 3) or rotation2.shape != (3, 3) or out_rotation1.shape != (3, 3)
            or out_rotation2.shape != (3, 3)):
        raise ValueError("contact placements: a normal and points (3,), joint placements (3 x 3, 3) and "
                         "outputs of the same sizes")
    contact = np.empty((3, 3))
    _contact_rotation(normal, contact)
    for rotation, translation, point, out_rotation, out_translation in (
            (rotation1, translation1, point1, out_rotation1, out_translation1),
            (rotation2, translation2, point2, out_rotation2, out_translation2)):
        for i in range(3):
            for j in range(3):
                out_rotation[i, j] = (rotation[0, i] * contact[0, j] + rotation[1, i] * contact[1, j]
                                      + rotation[2, i] * contact[2, j])
        d0, d1, d2 = point[0] - translation[0], point[1] - translation[1], point[2] - translation[2]
        for i in range(3):
            out_translation[i] = rotation[0, i] * d0 + rotation[1, i] * d1 + rotation[2, i] * d2


# The parts of _delassus_and_drift, inlined there (numba IR inlining: no call). Each sum runs
# over the columns where the constraint's row of J is non-zero, in increasing order: a term
# of a zero column is +-0 times a finite number, which leaves every partial sum as it was,
# so the result is bit for bit that of the dense sums (for a finite M^-1), at a cost that
# grows with the dofs a contact touches rather than with the whole model's. And M^-1 is
# zero between two subtrees of the universe (two robots, a robot and a free body:
# computeMinverse writes an exact +0 there, whatever the Data held), so an entry of M^-1 J^T
# or J M^-1 J^T between two contact components (trees joined by the rows that touch them,
# :func:`_components`) is a sum of +-0 terms, +0: written as such without its sum (N robots
# with a contact each: linear in N, not quadratic).
@register_jitable(inline="always")
def _support(jacobian: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(columns, counts): row i of J (3p x nv) is non-zero in columns[i, :counts[i]], in
    increasing order."""
    rows, nv = jacobian.shape
    columns = np.empty((rows, nv), np.int64)
    counts = np.zeros(rows, np.int64)
    for i in range(rows):
        count = 0
        for b in range(nv):
            if jacobian[i, b] != 0.0:
                columns[i, count] = b
                count += 1
        counts[i] = count
    return columns, counts


@register_jitable
def _root(parent: np.ndarray, tree: int) -> int:
    """The representative of ``tree`` in the union-find forest ``parent``."""
    root = tree
    while parent[root] != root:
        root = parent[root]
    return root


@register_jitable(inline="always")
def _components(trees: np.ndarray, columns: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(per dof, per row of J) its contact component: the subtrees of the universe
    (``trees``: per dof its subtree, numbered from 0) joined where one row of J moves dofs of
    several; a row that moves none is in component -1, with no dof."""
    parent = np.arange(trees.max() + 1 if trees.shape[0] else 0)
    for i in range(counts.shape[0]):
        if counts[i]:
            first = _root(parent, trees[columns[i, 0]])
            for k in range(1, counts[i]):
                other = _root(parent, trees[columns[i, k]])
                if other != first:
                    parent[other] = first
    dof_component = np.empty(trees.shape[0], np.int64)
    for a in range(trees.shape[0]):
        dof_component[a] = _root(parent, trees[a])
    row_component = np.full(counts.shape[0], -1, np.int64)
    for i in range(counts.shape[0]):
        if counts[i]:
            row_component[i] = dof_component[columns[i, 0]]
    return dof_component, row_component


@register_jitable(inline="always")
def _inverse_mass_jt(upper: np.ndarray, jacobian: np.ndarray, columns: np.ndarray, counts: np.ndarray,
                     dof_component: np.ndarray, row_component: np.ndarray, mass_jt: np.ndarray) -> None:
    """mass_jt = M^-1 J^T (nv x 3p) from the upper triangle of M^-1 (nv x nv) and J (3p x nv)
    on J's support (:func:`_support`), +0 between components (:func:`_components`)."""
    rows, nv = jacobian.shape
    for a in range(nv):
        for i in range(rows):
            total = 0.0
            if dof_component[a] == row_component[i]:
                for k in range(counts[i]):
                    b = columns[i, k]  # M^-1[a, b] = upper[b, a] below the diagonal
                    total += (upper[b, a] if b < a else upper[a, b]) * jacobian[i, b]
            mass_jt[a, i] = total


@register_jitable(inline="always")
def _delassus_and_free_drift(jacobian: np.ndarray, mass_jt: np.ndarray, v_free: np.ndarray, columns: np.ndarray,
                             counts: np.ndarray, row_component: np.ndarray, delassus: np.ndarray,
                             drift: np.ndarray) -> None:
    """delassus = J M^-1 J^T (3p x 3p, symmetric to the bit; +0 between components) and
    drift = J v_free (m/s), on J's support."""
    rows = jacobian.shape[0]
    for i in range(rows):
        for j in range(i, rows):
            total = 0.0
            if row_component[i] == row_component[j]:
                for k in range(counts[i]):
                    a = columns[i, k]
                    total += jacobian[i, a] * mass_jt[a, j]
            delassus[i, j] = total
            delassus[j, i] = total
        total = 0.0
        for k in range(counts[i]):
            a = columns[i, k]
            total += jacobian[i, a] * v_free[a]
        drift[i] = total


@register_jitable(inline="always")
def _add_gap_drift(jacobian: np.ndarray, v: np.ndarray, gaps: np.ndarray, restitutions: np.ndarray, h: float,
                   threshold: float, baumgarte: float, columns: np.ndarray, counts: np.ndarray,
                   drift: np.ndarray) -> None:
    """Add to each point's normal row (3i + 2) of the drift: the rebound restitution J_n v if
    J_n v < ``threshold`` (m/s, negative) and the gap closes within h, else gap / h for a
    gap, ``baumgarte`` gap / h for an overlap (gap < 0, m); J_n v on J's support."""
    for point in range(gaps.shape[0]):
        row, gap = 3 * point + 2, gaps[point]
        before = 0.0
        for k in range(counts[row]):
            a = columns[row, k]
            before += jacobian[row, a] * v[a]
        if before < threshold and gap + h * before < 0.0:
            drift[row] += restitutions[point] * before
        elif gap > 0.0:
            drift[row] += gap / h
        else:
            drift[row] += baumgarte * gap / h


@njit(types.void(_READ_MATRIX, _READ_MATRIX, _TREES, READ_VECTOR, READ_VECTOR, READ_VECTOR, READ_VECTOR,
                 types.float64, types.float64, types.float64, _WRITTEN_MATRIX, _WRITTEN_MATRIX, WRITTEN_VECTOR),
      cache=True)
def _delassus_and_drift(upper: np.ndarray, jacobian: np.ndarray, trees: np.ndarray, v_free: np.ndarray,
                        v: np.ndarray, gaps: np.ndarray, restitutions: np.ndarray, h: float, threshold: float,
                        baumgarte: float, mass_jt: np.ndarray, delassus: np.ndarray, drift: np.ndarray) -> None:
    """Step 3 of the module docstring in one compiled pass. From the upper triangle of M^-1
    (nv x nv, what computeMinverse fills: zero between the universe's subtrees, per dof its
    subtree in ``trees``, numbered from 0) and the constraints' Jacobian J (3p x nv; point
    i's normal row 3i + 2): mass_jt = M^-1 J^T (nv x 3p), delassus = J M^-1 J^T (3p x 3p,
    symmetric to the bit), drift = J v_free (m/s) plus per point, with its gap (m, < 0
    overlapping), restitution and approach speed J_n v before the step: the rebound
    restitution J_n v if J_n v < ``threshold`` (m/s, negative) and the gap closes within h
    (s), else gap / h for a gap, ``baumgarte`` gap / h for an overlap."""
    rows, nv = jacobian.shape
    if (upper.shape[0] != nv or upper.shape[1] != nv or trees.shape[0] != nv or v_free.shape[0] != nv
            or v.shape[0] != nv or rows != 3 * gaps.shape[0] or restitutions.shape[0] != gaps.shape[0]
            or mass_jt.shape[0] != nv or mass_jt.shape[1] != rows or delassus.shape[0] != rows or delassus.shape[1] != rows
            or drift.shape[0] != rows):
        raise ValueError("contact step: M^-1 (nv x nv), J (3p x nv), subtrees and velocities (nv,), gaps and "
                         "restitutions (p,) and outputs of matching sizes")
    if trees.shape[0] and (trees.min() < 0 or trees.max() >= nv):
        raise ValueError("contact step: subtrees numbered from 0, fewer than the dofs")
    columns, counts = _support(jacobian)
    dof_component, row_component = _components(trees, columns, counts)
    _inverse_mass_jt(upper, jacobian, columns, counts, dof_component, row_component, mass_jt)
    _delassus_and_free_drift(jacobian, mass_jt, v_free, columns, counts, row_component, delassus, drift)
    _add_gap_drift(jacobian, v, gaps, restitutions, h, threshold, baumgarte, columns, counts, drift)


@njit(types.void(READ_VECTOR, READ_VECTOR, types.float64, WRITTEN_VECTOR), cache=True)
def _free_velocity(v: np.ndarray, a: np.ndarray, h: float, out: np.ndarray) -> None:
    """out = v + h a (m/s, rad/s): step 1's free velocity from the accelerations a and the
    step h (s), numpy's two operations per entry."""
    if a.shape[0] != v.shape[0] or out.shape[0] != v.shape[0]:
        raise ValueError("contact step: v, a and out (nv,)")
    for i in range(v.shape[0]):
        out[i] = v[i] + h * a[i]


@njit(types.void(READ_VECTOR, _READ_MATRIX, READ_VECTOR, types.float64, WRITTEN_VECTOR, WRITTEN_VECTOR),
      cache=True)
def _velocity_after(v_free: np.ndarray, mass_jt: np.ndarray, impulses: np.ndarray, h: float, out: np.ndarray,
                    displacement: np.ndarray) -> None:
    """out = v_free + M^-1 J^T lambda (m/s, rad/s) from mass_jt = M^-1 J^T and the impulses,
    and displacement = h out (what ``pin.integrate`` moves q by over the step h, s)."""
    nv, rows = mass_jt.shape
    if v_free.shape[0] != nv or impulses.shape[0] != rows or out.shape[0] != nv or displacement.shape[0] != nv:
        raise ValueError("contact step: v_free (nv,), M^-1 J^T (nv x 3p), impulses (3p,), outputs (nv,)")
    for a in range(nv):
        total = 0.0
        for i in range(rows):
            total += mass_jt[a, i] * impulses[i]
        out[a] = v_free[a] + total
        displacement[a] = h * out[a]


#: The step's kernels without numba's type dispatch (about 1.5 us of a step): the step hands
#: them float64 arrays only (coal's points and normals, Pinocchio's matrices and vectors, the
#: stepper's own scratch; v checked by :meth:`ConstraintStepper.step`), the kernels check sizes.
_contact_placements_unchecked = unchecked(_contact_placements)
_delassus_and_drift_unchecked = unchecked(_delassus_and_drift)
_free_velocity_unchecked = unchecked(_free_velocity)
_velocity_after_unchecked = unchecked(_velocity_after)


def subtrees(model: pin.Model) -> np.ndarray:
    """Per dof of ``model`` its subtree of the universe (a robot, a free body), numbered from
    0 in joint order (int64, read-only): what :func:`_delassus_and_drift` reads."""
    roots = []
    for joint in range(1, model.njoints):
        root = joint
        while model.parents[root] != 0:
            root = model.parents[root]
        roots += [root] * model.joints[joint].nv
    trees = np.unique(np.array(roots, dtype=np.int64), return_inverse=True)[1].astype(np.int64).reshape(-1)
    trees.setflags(write=False)
    return trees


class ContactSet:
    """What the solve of one contact set needs, built once and updated in place: a
    ``PointContactConstraintModel`` per point (pair k's owners' joints, its friction), their
    datas, the solver with its settings and result, and per point the pair's name and
    restitution (point i's rows: 3i, 3i + 1 tangential, 3i + 2 normal). ``key`` is
    ((pair, number of points), ...) in the order the points come.

    Scratch space like the coal requests of the contact model: a step sets every frame it
    reads, and the solvers start cold (no warm start is set), so one set serves any state."""

    def __init__(self, contact: ContactModel, key: tuple[tuple[int, int], ...], settings: StepperSettings) -> None:
        model = contact.model
        self.key = key
        self.constraints = pin.StdVec_ConstraintModel()
        self.datas = pin.StdVec_ConstraintData()
        self.names: list[str] = []
        restitutions: list[float] = []
        for k, count in key:
            pair = contact.pairs[k]
            joint1, joint2 = contact.owner_joint(pair.first), contact.owner_joint(pair.second)
            for _ in range(count):
                point = pin.PointContactConstraintModel(model, joint1, pin.SE3.Identity(), joint2, pin.SE3.Identity())
                point.setFriction(pair.law.friction)
                self.constraints.append(pin.ConstraintModel(point))
                self.names.append(pair.name)
                restitutions.append(pair.law.restitution)
        for constraint in self.constraints:
            self.datas.append(constraint.createData())
        #: References into the vectors: moving a contact frame here moves the solver's.
        self.points = [constraint.extract() for constraint in self.constraints]
        #: per point, views of its frame's rotation and translation in joint 1's and joint 2's
        #: frames (what :func:`_contact_placements` writes)
        self.placements = [(point.joint1_placement.rotation, point.joint1_placement.translation,
                            point.joint2_placement.rotation, point.joint2_placement.translation)
                           for point in self.points]
        self.pairs = list(zip(self.constraints, self.datas))
        size = 3 * len(self.points)
        self.restitutions = np.array(restitutions, dtype=float)
        #: per point its gap (m, < 0 overlapping), written by :meth:`place`
        self.gaps = np.empty(len(self.points))
        #: scratch for M^-1 J^T, the Delassus matrix and the drift (see :func:`_delassus_and_drift`)
        self.mass_jt, self.delassus, self.drift = np.empty((model.nv, size)), np.empty((size, size)), np.empty(size)
        if settings.solver == "pgs":
            self.solver, self.options, self.result = (pin.PGSConstraintSolver(size), pin.PGSSolverSettings(),
                                                      pin.PGSSolverResult())
        else:
            self.solver, self.options, self.result = (pin.ADMMConstraintSolver(size), pin.ADMMSolverSettings(),
                                                      pin.ADMMSolverResult())
            self.options.lanczos_size = size
        self.options.max_iterations = settings.max_iterations
        if settings.solver == "pgs":
            # PGS judges its absolute criteria block by block during a sweep, each block on the
            # velocities before the later blocks moved (Pinocchio 4.1, pgs-solver.hxx): after
            # the first sweep of a two-sided grasp every block looks solved while the first
            # pad's contact still approaches at 30 mm/s, and the sphere slid 2.8 mm in 0.75 s
            # (test/sim/test_grasp.py). So PGS stops on its fixed-point test alone, at rounding
            # level: it creeps where contacts are redundant, and at 1e-10 a box landing on a
            # 0.25 rad incline (4 corners) stopped after 50 sweeps with 0.9 mm/s of slip left.
            self.options.absolute_feasibility_tol = 0.0
            self.options.absolute_complementarity_tol = 0.0
            self.options.relative_feasibility_tol = PGS_FIXED_POINT
        else:
            self.options.absolute_feasibility_tol = settings.tolerance
            self.options.absolute_complementarity_tol = settings.tolerance

    def place(self, touching: list[tuple[int, list[ContactPoint]]],
              joints: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]) -> tuple[list[ContactPoint], float]:
        """Move every point's contact frame to its ``touching`` point (pair k's points, in the
        set's order) in its joints' frames (per pair the world rotations and translations of
        its owner joints, :meth:`ConstraintStepper.joint_placements`) and write its gap:
        (the points in order, the deepest overlap (m, >= 0))."""
        placements, gaps, placed, deepest, i = self.placements, self.gaps, [], 0.0, 0
        for k, points in touching:
            rotation1, translation1, rotation2, translation2 = joints[k]
            placed += points
            for c in points:
                placed1, at1, placed2, at2 = placements[i]
                _contact_placements_unchecked(c.normal, c.point1, c.point2, rotation1, translation1, rotation2,
                                              translation2, placed1, at1, placed2, at2)
                gaps[i] = -c.depth
                deepest = max(deepest, c.depth)
                i += 1
        return placed, deepest

    def normal_impulses(self, impulses: np.ndarray) -> dict[str, float]:
        """Per pair name the sum of its points' normal impulses (N s; rows 3i + 2), added in
        point order from 0."""
        totals = dict.fromkeys(self.names, 0.0)
        for name, impulse in zip(self.names, impulses[2::3].tolist()):
            totals[name] += impulse
        return totals

    def solve(self, delassus: np.ndarray, drift: np.ndarray) -> tuple[np.ndarray, int]:
        """Impulses (N s, 3 per point: tangential x, y and normal along the contact frames)
        and the solver's iterations for the Delassus matrix and drift (m/s)."""
        self.solver.solve(pin.DelassusOperatorDense(delassus), drift, self.constraints, self.datas, self.options,
                          self.result)
        return self.result.retrieveConstraintImpulses(), int(self.result.iterations)  # a fresh array


class ConstraintStepper:
    """One :meth:`step` of the constraint-based law on ``contact``'s model."""

    def __init__(self, contact: ContactModel, settings: StepperSettings) -> None:
        self.contact, self.model, self.settings = contact, contact.model, settings
        self.owners = [(contact.owner_joint(p.first), contact.owner_joint(p.second)) for p in contact.pairs]
        self.trees = subtrees(self.model)
        self.sets: dict[tuple[tuple[int, int], ...], ContactSet] = {}
        self._placed_in: pin.Data | None = None  # the Data whose joint placements _joint_views shows
        self._joint_views: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []

    def contact_set(self, key: tuple[tuple[int, int], ...]) -> ContactSet:
        """The kept :class:`ContactSet` of ``key``, built on its first use."""
        found = self.sets.get(key)
        if found is None:
            if len(self.sets) >= MAX_CONTACT_SETS:
                del self.sets[next(iter(self.sets))]
            found = self.sets[key] = ContactSet(self.contact, key, self.settings)
        return found

    def joint_placements(self, data: pin.Data) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """Per pair, views of its owner joints' world rotations and translations in ``data``
        (data.oMi; the universe's, the identity, for world geometry): read where the
        kinematics pass writes them, made once per Data (which is kept alive with them)."""
        if self._placed_in is not data:
            placed = data.oMi
            self._joint_views = [(placed[joint1].rotation, placed[joint1].translation, placed[joint2].rotation,
                                  placed[joint2].translation) for joint1, joint2 in self.owners]
            self._placed_in = data
        return self._joint_views

    def step(self, data: pin.Data, q: np.ndarray, v: np.ndarray, tau: np.ndarray,
             h: float) -> tuple[np.ndarray, np.ndarray, StepReport]:
        """(q+, v+, report) after one step of h seconds under generalised forces tau (nv,);
        ``data`` is a Data of the model (scratch); v a vector (ValueError otherwise: the
        compiled kernels read it as float64 unchecked)."""
        model, settings = self.model, self.settings
        v = np.asarray(v, dtype=float)
        if v.ndim != 1:
            raise ValueError(f"contact step: v must be a vector, got shape {v.shape}")
        # ABA in the world convention places the joints and fills the joint Jacobians, and
        # computeMinverse(model, data) takes the upper triangle of M^-1 from that same pass
        # (only when a pair touches: the contact search reads the placements alone)
        v_free = np.empty(v.shape[0])
        _free_velocity_unchecked(v, pin.aba(model, data, q, v, tau, pin.Convention.WORLD), h, v_free)
        touching = self.contact.touching(data, settings.margin)
        if not touching:
            return pin.integrate(model, q, h * v_free), v_free, StepReport()
        inverse_mass = pin.computeMinverse(model, data)
        active = self.contact_set(tuple([(k, len(points)) for k, points in touching]))
        points, deepest = active.place(touching, self.joint_placements(data))
        report = StepReport(penetration=deepest, names=active.names, points=points)
        for constraint, cdata in active.pairs:
            constraint.calc(model, data, cdata)
        jacobian = pin.getConstraintsJacobian(model, data, active.constraints, active.datas)
        _delassus_and_drift_unchecked(inverse_mass, jacobian, self.trees, v_free, v, active.gaps,
                                      active.restitutions, h, -settings.restitution_threshold, settings.baumgarte,
                                      active.mass_jt, active.delassus, active.drift)
        report.impulses, report.iterations = active.solve(active.delassus, active.drift)
        v_next, displacement = np.empty(v_free.shape[0]), np.empty(v_free.shape[0])
        _velocity_after_unchecked(v_free, active.mass_jt, report.impulses, h, v_next, displacement)
        report.normal_impulse = active.normal_impulses(report.impulses)
        return pin.integrate(model, q, displacement), v_next, report
