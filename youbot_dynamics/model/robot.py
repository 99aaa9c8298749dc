"""URDF -> Robot: the immutable description of what a robot IS, and :func:`load_robot`.

Loading reads and checks the file (:mod:`youbot_dynamics.model.urdf`), builds the Pinocchio
model (:mod:`youbot_dynamics.model.pinocchio_model`) and the fidelity report
(:mod:`youbot_dynamics.model.fidelity`). A :class:`Robot` holds the Pinocchio model of the URDF (for the rigid-body algorithms), the
kinematic tree as the URDF states it (for the screw axes, independent of Pinocchio), the
moving joints in Pinocchio's order with their limits, damping and friction, and a fidelity
report of what the model ignores or approximates. What the robot is DOING lives elsewhere
(Pinocchio ``Data`` and the simulation state); nothing here changes after loading.

Joint coordinates: one number per moving joint of the URDF (angle in rad for revolute and
continuous joints, displacement in m for prismatic ones), in Pinocchio's joint order.
Continuous joints are given to Pinocchio as revolute joints without position limits (the
angle is not wrapped); the fidelity report says so. A ``<mimic>`` joint is no coordinate of
its own: it follows q_mimic = multiplier q_primary + offset through Pinocchio's mimic joints,
and ``Robot.mimic`` holds those relations.

The root joint, chosen at load time, joins the root link to the world (Pinocchio's layout;
its coordinates come FIRST in q and v, named in :data:`ROOT_COORDINATES`):

- ``fixed`` (default): the root link is welded to the world; q and v hold the joints only,
  nq == nv == number of moving joints (mimic joints excluded).
- ``floating``: Pinocchio's free-flyer. q = (x, y, z, qx, qy, qz, qw, joints): position of
  the root link in the world (m) and its orientation as a unit quaternion (x, y, z, w);
  v = (vx, vy, vz, wx, wy, wz, joint rates): the root link's twist in its own frame (body
  twist, linear part first, m/s and rad/s). nq = nv + 1.
- ``planar``: the root link slides on the world's x-y plane and turns about z (the youBot
  base on the floor). q = (x, y, cos yaw, sin yaw, joints); v = (vx, vy, wz, joint rates),
  velocity in the root link's frame. nq = nv + 1.

Where nq != nv a configuration is not moved by q + v dt: use
:mod:`youbot_dynamics.model.configuration` (``pin.integrate`` on the manifold).

Loading accepts what urdfdom and Pinocchio accept: zero-mass links, point masses (mass > 0,
inertia 0) and principal moments within INERTIA_RTOL of the largest one (or below
INERTIA_ATOL) count as zero. A physically invalid inertia (a negative principal moment, the
triangle inequality violated, a negative mass) is a warning in the fidelity report (every
offending link named); ``strict=True`` makes warnings errors. A malformed file is a
:class:`URDFError` naming file:line, the element and the reason.
"""
from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin
from lxml import etree

from youbot_dynamics.errors import SingularMassMatrixError, URDFError, UserInputError
from youbot_dynamics.model.fidelity import WARNING, fidelity_notes, inertial_warnings, mass_matrix_defect
from youbot_dynamics.model.lie import exp_se3
from youbot_dynamics.model.lenient_urdf import add_point_mass_inertias, reversed_limit_notes
from youbot_dynamics.model.pinocchio_model import ROOT_JOINT_NAME, pinocchio_model, root_joint_name
from youbot_dynamics.model.urdf import (Joint, Mimic, TreeJoint, check_urdf, kinematic_tree, mimic_relations,
                                        moving_joint, parse_urdf, read_source)

#: Names of the root joint's coordinates in q and in v, per root kind (Pinocchio's layout).
ROOT_COORDINATES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "fixed": ((), ()),
    "floating": (("root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz", "root_qw"),
                 ("root_vx", "root_vy", "root_vz", "root_wx", "root_wy", "root_wz")),
    "planar": (("root_x", "root_y", "root_cos", "root_sin"), ("root_vx", "root_vy", "root_wz")),
}
ROOTS = tuple(ROOT_COORDINATES)


@dataclass(frozen=True)
class Robot:
    """Immutable robot description. Do not mutate ``model``; make Data with ``model.createData()``.

    ``root`` is the root joint (``fixed``, ``floating`` or ``planar``, see the module
    docstring). The per-joint arrays (``lower``, ``upper``, ``velocity_limit``,
    ``effort_limit``, ``damping``, ``friction``) and ``joint_names`` cover the URDF's
    independent moving joints only (no mimic joints): joint i sits at q[root_nq + i] and
    v[root_nv + i].

    ``mass_matrix_defect`` is computed at construction: empty when the joint-space mass matrix
    (root DoFs included) is positive definite at a sample configuration, else the reason
    forward dynamics refuses.
    """

    name: str
    source: str
    model: pin.Model
    joints: tuple[Joint, ...]
    tree: tuple[TreeJoint, ...]
    root_link: str
    fidelity: tuple[str, ...]
    locked: Mapping[str, float] = field(default_factory=dict)
    mimic: Mapping[str, Mimic] = field(default_factory=dict)
    root: str = "fixed"
    mass_matrix_defect: str = field(init=False, default="")

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass_matrix_defect", mass_matrix_defect(self.model, self.source))

    @property
    def warnings(self) -> tuple[str, ...]:
        """The fidelity notes that are warnings (physically invalid inertias, a singular mass
        matrix): what ``strict=True`` refuses."""
        notes = tuple(note for note in self.fidelity if note.startswith(WARNING))
        return notes + ((WARNING + self.mass_matrix_defect,) if self.mass_matrix_defect else ())

    def require_regular_mass_matrix(self) -> None:
        """Raise :class:`SingularMassMatrixError` when forward dynamics is undefined."""
        if self.mass_matrix_defect:
            raise SingularMassMatrixError(self.mass_matrix_defect)

    # ---- joint-indexed arrays (Pinocchio order) -------------------------------------
    @property
    def joint_names(self) -> tuple[str, ...]:
        """Moving joints' names in Pinocchio's order (the order of every joint array)."""
        return tuple(j.name for j in self.joints)

    @property
    def nq(self) -> int:
        """Size of a configuration q: root coordinates plus one per moving joint."""
        return self.model.nq

    @property
    def nv(self) -> int:
        """Size of a velocity v (and of a, tau): root DoFs plus one per moving joint; equal to
        the number of moving joints for a fixed root."""
        return self.model.nv

    @property
    def root_nq(self) -> int:
        """Number of root coordinates at the head of q (7 floating, 4 planar, 0 fixed)."""
        return len(ROOT_COORDINATES[self.root][0])

    @property
    def root_nv(self) -> int:
        """Number of root DoFs at the head of v (6 floating, 3 planar, 0 fixed)."""
        return len(ROOT_COORDINATES[self.root][1])

    @property
    def q_names(self) -> tuple[str, ...]:
        """Names of the entries of q: root coordinates, then the moving joints."""
        return ROOT_COORDINATES[self.root][0] + self.joint_names

    @property
    def v_names(self) -> tuple[str, ...]:
        """Names of the entries of v (and a, tau): root DoFs, then the moving joints."""
        return ROOT_COORDINATES[self.root][1] + self.joint_names

    def _array(self, attribute: str) -> np.ndarray:
        values = np.array([getattr(j, attribute) for j in self.joints], dtype=float)
        values.setflags(write=False)
        return values

    @property
    def lower(self) -> np.ndarray:
        """Lower position limits (rad or m; -inf for continuous joints), read-only."""
        return self._array("lower")

    @property
    def upper(self) -> np.ndarray:
        """Upper position limits (rad or m; +inf for continuous joints), read-only."""
        return self._array("upper")

    @property
    def velocity_limit(self) -> np.ndarray:
        """Velocity limits (rad/s or m/s; inf where the URDF gives none), read-only."""
        return self._array("velocity_limit")

    @property
    def effort_limit(self) -> np.ndarray:
        """Effort limits (N m or N; inf where the URDF gives none), read-only."""
        return self._array("effort_limit")

    @property
    def damping(self) -> np.ndarray:
        """URDF viscous damping (N m s/rad or N s/m), read-only."""
        return self._array("damping")

    @property
    def friction(self) -> np.ndarray:
        """URDF Coulomb friction level (N m or N), read-only."""
        return self._array("friction")

    @property
    def link_names(self) -> tuple[str, ...]:
        """Every link of the URDF tree, root first, parents before children."""
        return (self.root_link, *(j.child for j in self.tree))

    # ---- look-ups ---------------------------------------------------------------------
    def joint_index(self, name: str) -> int:
        """Index of a moving joint in the joint arrays (q[root_nq + i], v[root_nv + i])."""
        try:
            return self.joint_names.index(name)
        except ValueError:
            if name in self.mimic:
                m = self.mimic[name]
                raise UserInputError(f"joint '{name}' of robot '{self.name}' mimics '{m.primary}' "
                                     f"(q = {m.multiplier:g} q_{m.primary} + {m.offset:g}): it is no "
                                     f"coordinate of its own; use '{m.primary}'") from None
            raise UserInputError(
                f"unknown joint '{name}' in robot '{self.name}' ({self.source}); "
                f"moving joints: {', '.join(self.joint_names)}"
            ) from None

    def frame_id(self, name: str, kind: str = "link") -> int:
        """Pinocchio frame id of a link frame (``kind="link"``, pin.FrameType.BODY) or of a
        joint frame (``kind="joint"``: a moving joint's or a fixed joint's), with a clear error
        if unknown. Looking up by type keeps a link and a joint of the same name apart."""
        types = {"link": pin.FrameType.BODY,
                 "joint": pin.FrameType(int(pin.FrameType.JOINT) | int(pin.FrameType.FIXED_JOINT))}
        if kind not in types:
            raise UserInputError(f"frame kind '{kind}': expected 'link' or 'joint'")
        if not self.model.existFrame(name, types[kind]):
            names = self.link_names if kind == "link" else tuple(j.name for j in self.tree)
            raise UserInputError(
                f"unknown frame '{name}': no {kind} of that name in robot '{self.name}' "
                f"({self.source}); {kind}s: {', '.join(names)}"
            )
        return self.model.getFrameId(name, types[kind])

    def chain_to(self, link: str) -> list[TreeJoint]:
        """URDF joints from the root link to ``link``, root first."""
        by_child = {j.child: j for j in self.tree}
        if link != self.root_link and link not in by_child:
            raise UserInputError(
                f"unknown link '{link}' in robot '{self.name}' ({self.source}); "
                f"links: {', '.join(self.link_names)}"
            )
        chain: list[TreeJoint] = []
        while link != self.root_link:
            joint = by_child[link]
            chain.append(joint)
            link = joint.parent
        return chain[::-1]

    @property
    def end_effector(self) -> str:
        """Default end-effector link: the common ancestor of the links with the most joints
        above them (the gripper palm of the youBot, locked fingers or not; the last link of a
        serial arm)."""
        return self._deepest_common_link(self.link_names)

    @property
    def end_effectors(self) -> tuple[str, ...]:
        """One end-effector link per robot of a composed model (several robots fixed to a
        common root link): for each child of the root link whose subtree has a moving joint,
        the ``end_effector`` rule applied to that subtree (the youBots' gripper palms), in
        the order of the subtrees' first moving joints (Pinocchio's joint order, the URDF's).
        A single robot (the root has at most one such child): its ``end_effector``."""
        first_joint = {}
        for top in (j.child for j in self.tree if j.parent == self.root_link):
            links = [link for link in self.link_names if top in (j.child for j in self.chain_to(link))]
            moving = {j.name for link in links for j in self.chain_to(link) if j.type != "fixed"}
            if moving:
                first_joint[min(self.joint_names.index(name) for name in moving)] = links
        if len(first_joint) < 2:
            return (self.end_effector,)
        return tuple(self._deepest_common_link(first_joint[k]) for k in sorted(first_joint))

    def _deepest_common_link(self, links: Sequence[str]) -> str:
        """The common ancestor of those of ``links`` with the most joints above them."""
        depth = {link: len(self.chain_to(link)) for link in links}
        deepest = [link for link, d in depth.items() if d == max(depth.values())]
        chains = [[self.root_link, *(j.child for j in self.chain_to(link))] for link in deepest]
        common = self.root_link
        for tiers in zip(*chains):
            if len(set(tiers)) != 1:
                break
            common = tiers[0]
        return common

    def vector(self, values: Mapping[str, float] | Sequence[float] | np.ndarray, *,
               default: float | None = 0.0, what: str = "joint values", of: str = "v") -> np.ndarray:
        """A configuration (``of="q"``, nq values) or a velocity-sized vector (``of="v"``, nv
        values: v, a, tau) from a sequence in model order (root coordinates first, see
        ``q_names`` / ``v_names``) or a mapping by coordinate name.

        Joints missing from a mapping take ``default`` (an error when ``default`` is None);
        root coordinates missing from it take the neutral pose (origin, identity orientation)
        or zero velocity. A configuration's root quaternion (x, y, z, w) or (cos, sin) pair is
        normalised; a zero or non-finite one is an error.
        """
        if of not in ("q", "v"):
            raise ValueError(f"vector: of must be 'q' or 'v', got {of!r}")
        names = self.q_names if of == "q" else self.v_names
        offset = self.root_nq if of == "q" else self.root_nv
        if isinstance(values, Mapping):
            out = np.full(len(names), np.nan if default is None else default)
            out[:offset] = pin.neutral(self.model)[:offset] if of == "q" else 0.0
            for name, value in values.items():
                if name in names[:offset]:
                    out[names.index(name)] = float(value)
                else:
                    out[offset + self.joint_index(name)] = float(value)
            missing = [n for n, v in zip(names, out) if np.isnan(v)]
            if missing:
                raise UserInputError(f"{what}: no value for joint(s) {', '.join(missing)}")
        else:
            out = np.asarray(values, dtype=float).reshape(-1)
            if out.size != len(names):
                raise UserInputError(
                    f"{what}: expected {len(names)} values ({'nq' if of == 'q' else 'nv'} of a "
                    f"{self.root} root) in the order {', '.join(names)}; got {out.size}"
                )
        if of == "q" and self.root != "fixed":
            out = self._normalised_root(out, what)
        return out

    def _normalised_root(self, q: np.ndarray, what: str) -> np.ndarray:
        """q with its root orientation (quaternion or cos, sin) scaled to unit norm."""
        rotation = slice(3, 7) if self.root == "floating" else slice(2, 4)
        largest = float(np.abs(q[rotation]).max())
        if not (math.isfinite(largest) and largest > 0.0):
            names = ", ".join(self.q_names[rotation])
            raise UserInputError(f"{what}: the {self.root} root's orientation ({names}) must be "
                                 f"finite and non-zero; got {q[rotation].tolist()}")
        q = q.copy()
        q[rotation] /= largest  # first, so that the norm cannot overflow (1e308 components)
        q[rotation] /= np.linalg.norm(q[rotation])
        return q


# ---------------------------------------------------------------------------------------
# Loading
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class URDFDocument:
    """A URDF read and checked once, from which a Robot is built for any root joint
    (:func:`robot_from_urdf`): ``label`` (the file or "<string>"), the parsed ``element``
    (lxml; read-only from here on), the ``forgiven`` notes of what urdfdom forgives, the
    kinematic ``tree`` and ``root_link``, the ``mimic`` relations and their warnings.
    ``source`` is what it was read from (a path or the XML text): a pickled document (a
    scene sent to a sweep's worker) is read again from it."""

    source: str | Path
    label: str
    element: etree._Element
    forgiven: tuple[str, ...]
    tree: tuple[TreeJoint, ...]
    root_link: str
    relations: Mapping[str, Mimic]
    mimic_warnings: tuple[str, ...]

    def __reduce__(self) -> tuple:
        return read_urdf, (self.source,)


@contextmanager
def _reading(label: str) -> Iterator[None]:
    """The parsers' own failures on a malformed attribute or element as one URDFError."""
    try:
        yield
    except (ValueError, TypeError, KeyError, IndexError, AttributeError) as error:
        if isinstance(error, UserInputError):
            raise
        raise URDFError(f"{label}: cannot read the URDF: {type(error).__name__}: {' '.join(str(error).split())} "
                        "(a malformed attribute or element the checks above do not cover)") from None


def read_urdf(source: str | Path) -> URDFDocument:
    """Read and check a URDF file path or XML string (any encoding declaration) once.

    Raises :class:`URDFError` naming the file, the line, the element and the reason for a
    missing file, malformed XML, a ``<robot>`` without a name, a duplicate link or joint name,
    an attribute that is not the numbers urdfdom expects, a missing ``<mass value>``,
    ``<inertia>`` moment or ``<limit>`` effort / velocity, an unknown joint type, a missing
    parent or child link, a zero axis on a moving joint, a ``<mimic>`` of no moving joint or a
    kinematic loop. What urdfdom forgives is forgiven and noted
    (:mod:`youbot_dynamics.model.lenient_urdf`: an XML declaration after blank lines or of
    version 0.0, undeclared namespace prefixes, a point-mass <inertial>, reversed limits; a
    malformed <visual>)."""
    text, label = read_source(source)
    element, forgiven = parse_urdf(text, label)
    with _reading(label):
        forgiven += add_point_mass_inertias(element)
        forgiven += check_urdf(element, label)
        forgiven += reversed_limit_notes(element)
        tree, root_link = kinematic_tree(element)
        relations, mimic_warnings = mimic_relations(element, label)
    return URDFDocument(source, label, element, tuple(forgiven), tree, root_link, relations,
                        tuple(mimic_warnings))


def robot_from_urdf(document: URDFDocument, root: str = "fixed", *, strict: bool = False) -> Robot:
    """The Robot of a read URDF with the root joint ``root``: ``fixed`` (welded),
    ``floating`` (Pinocchio free-flyer) or ``planar`` (x, y, yaw on the floor); see the
    module docstring for the q and v layouts. An unknown root is a UserInputError.

    Physically invalid inertias are warnings in the fidelity report (``Robot.warnings``),
    errors with ``strict=True``; so is a singular joint-space mass matrix. A URDF joint named
    ROOT_JOINT_NAME makes a floating or planar root joint take the next free name
    (:func:`~youbot_dynamics.model.pinocchio_model.root_joint_name`)."""
    if root not in ROOTS:
        raise UserInputError(f"root '{root}' is unknown: expected one of {', '.join(ROOTS)}")
    element, label = document.element, document.label
    with _reading(label):
        root_joint = ROOT_JOINT_NAME if root == "fixed" else root_joint_name(element)
        model, mimic, mimic_notes = pinocchio_model(element, document.relations, root, root_joint)
        first = 1 if root == "fixed" else 2  # Pinocchio joint 0 is the universe, 1 the root joint
        by_name = {joint.get("name"): joint for joint in element.findall("joint")}
        joints = tuple(moving_joint(by_name[model.names[i]]) for i in range(first, model.njoints)
                       if model.names[i] not in mimic)
        robot = Robot(name=element.get("name"), source=label, model=model, joints=joints, tree=document.tree,
                      root_link=document.root_link,
                      fidelity=(_root_note(root, document.root_link, root_joint), *document.forgiven,
                                *document.mimic_warnings, *inertial_warnings(element),
                                *fidelity_notes(element), *mimic_notes),
                      mimic=mimic, root=root)
    if strict and robot.warnings:
        raise URDFError(f"{label}: strict loading refuses {len(robot.warnings)} warning(s): "
                        + "; ".join(w.removeprefix(WARNING) for w in robot.warnings))
    return robot


def load_robot(source: str | Path, *, root: str = "fixed", strict: bool = False) -> Robot:
    """Build a Robot from a URDF file path or a URDF XML string: :func:`read_urdf` then
    :func:`robot_from_urdf` (their docstrings say what is refused, forgiven and warned)."""
    if root not in ROOTS:
        raise UserInputError(f"root '{root}' is unknown: expected one of {', '.join(ROOTS)}")
    return robot_from_urdf(read_urdf(source), root, strict=strict)


def _root_note(root: str, root_link: str, root_joint: str) -> str:
    """The fidelity report's line on the root joint (named ``root_joint`` in Pinocchio's model)."""
    if root == "fixed":
        return (f"root: fixed: link '{root_link}' is welded to the world "
                "(load with root 'floating' or 'planar' to free it)")
    q_names, v_names = ROOT_COORDINATES[root]
    renamed = (f" (not '{ROOT_JOINT_NAME}': the URDF has a joint of that name)"
               if root_joint != ROOT_JOINT_NAME else "")
    return (f"root: {root}: joint '{root_joint}'{renamed} between the world and link '{root_link}' "
            f"(q starts {', '.join(q_names)}; v starts {', '.join(v_names)}, in the link's frame)")


def lock_joints(robot: Robot, positions: Mapping[str, float]) -> Robot:
    """Reduced Robot with the named joints locked at the given values (rad or m).

    The locked joints (and the joints that mimic them, at their mimic values) become fixed
    joints of the tree with their value folded into the origin, and Pinocchio's
    buildReducedModel removes them from the rigid-body model.
    """
    if not positions:
        return robot
    for name in positions:
        robot.joint_index(name)  # only independent moving joints can be locked, never the root
    q_ref = robot.vector(dict(positions), of="q", what="locked joint positions")
    values = {name: float(value) for name, value in positions.items()}
    values.update({name: m.multiplier * values[m.primary] + m.offset
                   for name, m in robot.mimic.items() if m.primary in values})
    joint_ids = sorted(robot.model.getJointId(name) for name in values)
    model = pin.buildReducedModel(robot.model, joint_ids, q_ref)
    tree = tuple(_locked(j, values[j.name]) if j.name in values else j for j in robot.tree)
    kept = tuple(j for j in robot.joints if j.name not in positions)
    return Robot(name=robot.name, source=robot.source, model=model, joints=kept, tree=tree,
                 root_link=robot.root_link, fidelity=robot.fidelity,
                 locked={**robot.locked, **values},
                 mimic={name: m for name, m in robot.mimic.items() if name not in values},
                 root=robot.root)


def keep_joints(robot: Robot, moving: Sequence[str], positions: Mapping[str, float] | None = None) -> Robot:
    """Reduced Robot in which only ``moving`` joints move; the others are locked at
    ``positions`` (default 0)."""
    for name in moving:
        robot.joint_index(name)
    positions = positions or {}
    return lock_joints(robot, {n: float(positions.get(n, 0.0)) for n in robot.joint_names if n not in moving})



def _locked(joint: TreeJoint, value: float) -> TreeJoint:
    """The joint as a fixed one: its origin times exp([X] value), X = (0, axis) for a
    prismatic joint and (axis, 0) for a revolute or continuous one (joint frame)."""
    zero = np.zeros(3)
    screw = np.concatenate((zero, joint.axis) if joint.type == "prismatic" else (joint.axis, zero))
    origin = joint.origin @ exp_se3(screw * value)
    origin.setflags(write=False)
    return TreeJoint(joint.name, "fixed", joint.parent, joint.child, origin, joint.axis)

