"""URDF -> Robot: the immutable description of what a robot IS.

A :class:`Robot` holds the Pinocchio model of the URDF (for the rigid-body algorithms), the
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
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, Mapping, Sequence

import numpy as np
import pinocchio as pin
from lxml import etree

from youbot_dynamics.errors import SingularMassMatrixError, URDFError, UserInputError
from youbot_dynamics.model import limits
from youbot_dynamics.model.lie import exp_se3

MOVING_JOINT_TYPES = ("revolute", "continuous", "prismatic")
KNOWN_JOINT_TYPES = (*MOVING_JOINT_TYPES, "fixed", "floating", "planar")
UNBOUNDED = 1e10  # position limit handed to Pinocchio for continuous joints, rad
#: A principal moment of inertia counts as zero within this fraction of the link's largest
#: one (round-off such as -2e-22 next to 3e-6 kg m^2 is 7e-17 of it; the smallest physical
#: violation among example-robot-data's files is 1.8e-3 of it) ...
INERTIA_RTOL = 1e-6
#: ... or below this, kg m^2 (iCub's "zero" inertias are 1e-20..4e-18 kg m^2).
INERTIA_ATOL = 1e-12
#: A joint-space mass matrix is singular where a diagonal entry, or its smallest eigenvalue,
#: is below this fraction of the largest one (example-robot-data: the singular ones have 0 and
#: round-off -1e-17, the regular ones 2.2e-7 (tiago_no_hand) and more).
MASS_MATRIX_RTOL = 1e-12
GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))  # rad, for the sample configuration of that test
WARNING = "warning: "  # prefix of the fidelity notes that strict loading turns into errors
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
#: Numeric attributes urdfdom reads, by element, with how many numbers each holds.
NUMERIC_ATTRIBUTES = {
    "origin": {"xyz": 3, "rpy": 3},
    "axis": {"xyz": 3},
    "mass": {"value": 1},
    "inertia": dict.fromkeys(INERTIA_KEYS, 1),
    "limit": dict.fromkeys(("lower", "upper", "effort", "velocity"), 1),
    "dynamics": {"damping": 1, "friction": 1},
    "mimic": {"multiplier": 1, "offset": 1},
    "safety_controller": dict.fromkeys(("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"), 1),
    "calibration": {"rising": 1, "falling": 1},
    "box": {"size": 3},
    "cylinder": {"radius": 1, "length": 1},
    "sphere": {"radius": 1},
    "mesh": {"scale": 3},
}
#: Magnitude bounds (youbot_dynamics.model.limits) on numeric attributes, by element.
ATTRIBUTE_BOUNDS = {
    "origin": {"xyz": limits.LENGTH},
    "mass": {"value": limits.MASS},
    "inertia": dict.fromkeys(INERTIA_KEYS, limits.INERTIA),
    "dynamics": {"damping": limits.DAMPING, "friction": limits.FRICTION},
    "box": {"size": limits.LENGTH},
    "cylinder": {"radius": limits.LENGTH, "length": limits.LENGTH},
    "sphere": {"radius": limits.LENGTH},
}
#: Attributes urdfdom refuses to do without.
REQUIRED_ATTRIBUTES = {"mass": ("value",), "inertia": INERTIA_KEYS, "limit": ("effort", "velocity"),
                       "mimic": ("joint",)}
_XML_DECLARATION = re.compile(r"^\s*<\?xml\b[^>]*\?>")

#: Names of the root joint's coordinates in q and in v, per root kind (Pinocchio's layout).
ROOT_COORDINATES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "fixed": ((), ()),
    "floating": (("root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz", "root_qw"),
                 ("root_vx", "root_vy", "root_vz", "root_wx", "root_wy", "root_wz")),
    "planar": (("root_x", "root_y", "root_cos", "root_sin"), ("root_vx", "root_vy", "root_wz")),
}
ROOTS = tuple(ROOT_COORDINATES)
ROOT_JOINT_NAME = "root_joint"  # the Pinocchio joint of a floating or planar root
_ROOT_JOINT_MODELS = {"floating": pin.JointModelFreeFlyer, "planar": pin.JointModelPlanar}


@dataclass(frozen=True)
class TreeJoint:
    """One URDF joint as an edge of the kinematic tree.

    ``origin`` is the 4x4 pose of the child frame in the parent link frame at zero joint
    value; ``axis`` is the unit joint axis in the child (joint) frame. Locked joints appear
    with ``type == "fixed"`` and their locked value folded into ``origin``.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray


@dataclass(frozen=True)
class Joint:
    """A moving joint: limits (rad or m, rad/s or m/s, N m or N) and URDF dynamics."""

    name: str
    type: str
    lower: float
    upper: float
    velocity_limit: float
    effort_limit: float
    damping: float
    friction: float


@dataclass(frozen=True)
class Mimic:
    """A joint that follows another: q_joint = multiplier q_primary + offset (rad or m), the
    primary an independent moving joint (chains of mimics are resolved to their root)."""

    joint: str
    primary: str
    multiplier: float
    offset: float


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
        object.__setattr__(self, "mass_matrix_defect", _mass_matrix_defect(self.model, self.source))

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
def load_robot(source: str | Path, *, root: str = "fixed", strict: bool = False) -> Robot:
    """Build a Robot from a URDF file path or a URDF XML string (any encoding declaration).

    ``root`` joins the URDF's root link to the world: ``fixed`` (welded), ``floating``
    (Pinocchio free-flyer) or ``planar`` (x, y, yaw on the floor); see the module docstring
    for the q and v layouts. An unknown root is a UserInputError.

    Raises :class:`URDFError` naming the file, the line, the element and the reason for a
    missing file, malformed XML, a ``<robot>`` without a name, a duplicate link or joint name,
    an attribute that is not the numbers urdfdom expects, a missing ``<mass value>``,
    ``<inertia>`` moment or ``<limit>`` effort / velocity, an unknown joint type, a missing
    parent or child link, a lower limit above the upper one, a zero axis on a moving joint, a
    ``<mimic>`` of no moving joint, a kinematic loop, or (with a floating or planar root) a
    URDF joint named ROOT_JOINT_NAME. Physically invalid inertias are warnings in the fidelity
    report (``Robot.warnings``), errors with ``strict=True``; so is a singular joint-space
    mass matrix.
    """
    if root not in ROOTS:
        raise UserInputError(f"root '{root}' is unknown: expected one of {', '.join(ROOTS)}")
    text, label = _read_source(source)
    element = _parse_xml(text, label)
    try:
        fidelity = _check_urdf(element, label)
        joint = element.find(f"joint[@name='{ROOT_JOINT_NAME}']")
        if root != "fixed" and joint is not None:
            raise URDFError(f"{_where(label, joint)}: the name is reserved for the {root} root joint; "
                            "rename the joint or load with root 'fixed'")
        tree, root_link = _kinematic_tree(element)
        relations, mimic_warnings = _mimic_relations(element, label)
        model, mimic, mimic_notes = _pinocchio_model(element, relations, root)
        first = 1 if root == "fixed" else 2  # Pinocchio joint 0 is the universe, 1 the root joint
        by_name = {joint.get("name"): joint for joint in element.findall("joint")}
        joints = tuple(_joint_of(by_name[model.names[i]]) for i in range(first, model.njoints)
                       if model.names[i] not in mimic)
        robot = Robot(name=element.get("name"), source=label, model=model, joints=joints, tree=tree,
                      root_link=root_link,
                      fidelity=(_root_note(root, root_link), *mimic_warnings, *fidelity, *mimic_notes),
                      mimic=mimic, root=root)
        if strict and robot.warnings:
            raise URDFError(f"{label}: strict loading refuses {len(robot.warnings)} warning(s): "
                            + "; ".join(w.removeprefix(WARNING) for w in robot.warnings))
    except (ValueError, TypeError, KeyError, IndexError, AttributeError) as error:  # the parsers' own failures
        if isinstance(error, UserInputError):
            raise
        raise URDFError(f"{label}: cannot read the URDF: {type(error).__name__}: {' '.join(str(error).split())} "
                        "(a malformed attribute or element the checks above do not cover)") from None
    return robot


def _root_note(root: str, root_link: str) -> str:
    """The fidelity report's line on the root joint."""
    if root == "fixed":
        return (f"root: fixed: link '{root_link}' is welded to the world "
                "(load with root 'floating' or 'planar' to free it)")
    q_names, v_names = ROOT_COORDINATES[root]
    return (f"root: {root}: joint '{ROOT_JOINT_NAME}' between the world and link '{root_link}' "
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


# ---------------------------------------------------------------------------------------
# Helpers: reading, checking, converting
# ---------------------------------------------------------------------------------------
def _read_source(source: str | Path) -> tuple[str | bytes, str]:
    """The URDF text and a label for messages: a string as given, a file as bytes (so that
    the XML parser honours its encoding declaration)."""
    if isinstance(source, str) and source.lstrip().startswith("<"):
        return source, "<URDF string>"
    path = Path(source)
    if not path.is_file():
        raise URDFError(f"URDF file not found: {path}")
    size = path.stat().st_size
    if size > limits.MAX_URDF_BYTES:
        raise URDFError(f"{path}: {size} bytes is beyond the bound of {limits.MAX_URDF_BYTES} bytes on a URDF file")
    return path.read_bytes(), str(path)


def _parse_xml(text: str | bytes, label: str) -> etree._Element:
    """The XML tree. A str is already decoded, so its encoding declaration (which lxml
    refuses in a str) is dropped; the lines keep their numbers."""
    if isinstance(text, str):
        text = _XML_DECLARATION.sub("", text, count=1)
    try:
        root = etree.fromstring(text)
    except etree.XMLSyntaxError as error:
        raise URDFError(f"{label}: malformed XML: {error}") from None
    if root.tag != "robot":
        raise URDFError(f"{label}:{root.sourceline}: root element is <{root.tag}>, expected <robot>")
    if not root.get("name"):
        raise URDFError(f"{label}:{root.sourceline}: <robot> has no name attribute")
    return root


def _where(label: str, element: etree._Element) -> str:
    return f"{label}:{element.sourceline}: {element.tag} '{element.get('name')}'"


def _floats(element: etree._Element | None, attribute: str, default: str) -> np.ndarray:
    return np.array([float(x) for x in (element.get(attribute, default) if element is not None else default).split()])


def _urdf_elements(root: etree._Element) -> Iterator[tuple[etree._Element, etree._Element]]:
    """(owner, element) for every element whose attributes urdfdom reads: a joint's children,
    and the children of a link's <inertial>, <visual> and <collision> with their shapes."""
    for joint in root.findall("joint"):
        for child in joint:
            yield joint, child
    for link in root.findall("link"):
        for part in link:
            if part.tag not in ("inertial", "visual", "collision"):
                continue
            for child in part:
                yield link, child
                if child.tag == "geometry":
                    yield from ((link, shape) for shape in child)


def _check_numbers(owner: etree._Element, element: etree._Element, label: str) -> None:
    """Every numeric attribute of ``element`` holds as many finite numbers as urdfdom reads,
    and the attributes urdfdom requires are there."""
    spec = NUMERIC_ATTRIBUTES.get(element.tag)
    if spec is None:
        return
    where = f"{label}:{element.sourceline}: {owner.tag} '{owner.get('name')}': <{element.tag}>"
    for attribute in REQUIRED_ATTRIBUTES.get(element.tag, ()):
        if element.get(attribute) is None:
            raise URDFError(f"{where}: missing attribute '{attribute}'")
    for attribute, count in spec.items():
        text = element.get(attribute)
        if text is None:
            continue
        parts = text.split()
        if len(parts) != count:
            raise URDFError(f"{where}: {attribute}=\"{text}\" is not {count} number(s)")
        for part in parts:
            try:
                value = float(part)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise URDFError(f"{where}: {attribute}=\"{text}\": '{part}' is not a finite number")
            bound = ATTRIBUTE_BOUNDS.get(element.tag, {}).get(attribute)
            problem = bound.problem(value) if bound is not None else ""
            if problem:
                raise URDFError(f"{where}: {attribute}=\"{text}\": {problem}")


def _check_urdf(root: etree._Element, label: str) -> list[str]:
    """Validate the URDF; returns the fidelity notes: warnings first, then what the model
    ignores."""
    sizes = {"<link> elements": (limits.MAX_LINKS, sum(1 for e in root if e.tag == "link")),
             "<joint> elements": (limits.MAX_LINKS, sum(1 for e in root if e.tag == "joint")),
             "moving joints": (limits.MAX_MOVING_JOINTS, sum(1 for e in root if e.tag == "joint"
                                                             and e.get("type") in MOVING_JOINT_TYPES))}
    for what, (most, count) in sizes.items():
        if count > most:
            raise URDFError(f"{label}: {count} {what}, beyond the bound of {most} (see "
                            "youbot_dynamics.model.limits; the largest example robot has 130 links, 101 moving joints)")
    first_line: dict[tuple[str, str], int] = {}  # (tag, name) -> line
    for element in root:
        if element.tag in ("link", "joint"):
            key = (element.tag, element.get("name"))
            if key in first_line:
                raise URDFError(f"{_where(label, element)}: the name is already used by the "
                                f"{element.tag} at line {first_line[key]}")
            first_line[key] = element.sourceline
    links = {link.get("name"): link for link in root.findall("link")}
    if not links:
        raise URDFError(f"{label}: the robot has no <link>")
    for owner, element in _urdf_elements(root):
        _check_numbers(owner, element, label)
    parent_of: dict[str, str] = {}  # child link -> its joint's name
    parent_link: dict[str, str] = {}  # child link -> parent link
    for joint in root.findall("joint"):
        where = _where(label, joint)
        kind = joint.get("type")
        if kind not in KNOWN_JOINT_TYPES:
            raise URDFError(f"{where}: unknown joint type '{kind}' (expected one of {', '.join(KNOWN_JOINT_TYPES)})")
        for role in ("parent", "child"):
            element = joint.find(role)
            name = element.get("link") if element is not None else None
            if name is None:
                raise URDFError(f"{where}: missing <{role} link=...>")
            if name not in links:
                raise URDFError(f"{where}: {role} link '{name}' is not defined")
        child = joint.find("child").get("link")
        if child in parent_of:
            raise URDFError(f"{where}: kinematic loop: link '{child}' is already the child of "
                            f"joint '{parent_of[child]}' (closed chains are not supported in URDF)")
        parent_of[child] = joint.get("name")
        parent_link[child] = joint.find("parent").get("link")
        limit = joint.find("limit")
        if kind in ("revolute", "prismatic"):
            if limit is None:
                raise URDFError(f"{where}: a {kind} joint needs a <limit>")
            lower, upper = float(limit.get("lower", 0)), float(limit.get("upper", 0))
            if lower > upper:
                raise URDFError(f"{where}: lower limit {lower} is above upper limit {upper}")
        if kind in MOVING_JOINT_TYPES:
            axis = _floats(joint.find("axis"), "xyz", "1 0 0")
            if np.linalg.norm(axis) < 1e-12:
                raise URDFError(f"{where}: axis {axis.tolist()} is not a non-zero 3-vector")
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        raise URDFError(f"{label}: the links form {'no tree (kinematic loop)' if not roots else 'several trees'}; "
                        f"links without a parent joint: {', '.join(roots) or 'none'}")
    # A cycle with one root elsewhere: walk up from every link.
    for start in links:
        seen, link = set(), start
        while link in parent_of:
            if link in seen:
                raise URDFError(f"{label}: kinematic loop through link '{link}'")
            seen.add(link)
            link = parent_link[link]
    warnings = [warning for link in links.values() for warning in _inertial_warnings(link, label)]
    return warnings + _fidelity_notes(root)


def _inertial_warnings(link: etree._Element, label: str) -> list[str]:
    """Warnings for a physically invalid <inertial> (a negative mass, a negative principal
    moment, the triangle inequality violated), each naming the link and its line. Zero mass
    and point masses are valid; principal moments within INERTIA_RTOL of the largest (or
    below INERTIA_ATOL) count as zero."""
    inertial = link.find("inertial")
    if inertial is None:
        return []
    if inertial.find("mass") is None or inertial.find("inertia") is None:
        raise URDFError(f"{_where(label, link)}: <inertial> needs a <mass> and an <inertia>")
    mass = float(inertial.find("mass").get("value"))
    c = {k: float(inertial.find("inertia").get(k)) for k in INERTIA_KEYS}
    inertia = np.array([[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]], [c["ixz"], c["iyz"], c["izz"]]])
    principal = np.linalg.eigvalsh(inertia)
    tolerance = max(INERTIA_RTOL * float(np.abs(principal).max()), INERTIA_ATOL)
    at = f"{WARNING}link '{link.get('name')}' (line {link.sourceline})"
    moments = f"principal moments {np.array2string(principal, precision=6)} kg m^2"
    warnings = [f"{at}: negative mass {mass:g} kg"] if mass < 0.0 else []
    a, b, c3 = principal
    if a < -tolerance:
        warnings.append(f"{at}: inertia has a negative principal moment ({moments})")
    elif a + b < c3 - tolerance:
        warnings.append(f"{at}: inertia violates the triangle inequality ({moments}: "
                        f"{a:.6g} + {b:.6g} < {c3:.6g}; no rigid body has it)")
    return warnings


def _fidelity_notes(root: etree._Element) -> list[str]:
    """What of the URDF the model ignores or approximates."""
    notes = []
    for joint in root.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        if joint.find("safety_controller") is not None:
            notes.append(f"joint '{name}': <safety_controller> ignored (soft limits not enforced)")
        if joint.find("calibration") is not None:
            notes.append(f"joint '{name}': <calibration> ignored")
        if kind == "continuous":
            notes.append(f"joint '{name}': continuous, modelled as revolute without position limits (angle not wrapped)")
        if kind in ("floating", "planar"):
            notes.append(f"joint '{name}': {kind} joint treated as fixed at its origin (free bodies are scene objects)")
    for link in root.findall("link"):
        contact = link.find("contact")
        if contact is not None:
            values = ", ".join(f"{c.tag} {c.get('value')}" for c in contact if isinstance(c.tag, str))
            notes.append(f"link '{link.get('name')}': <contact> ({values}) ignored; "
                         "contact laws and friction come from the scene")
    controls = root.findall("ros2_control")
    if controls:
        notes.append(f"{len(controls)} <ros2_control> element(s) ignored: "
                     + ", ".join(f"'{c.get('name')}'" for c in controls))
    for tag in ("transmission", "gazebo"):
        count = len(root.findall(tag))
        if count:
            notes.append(f"{count} <{tag}> element(s) ignored")
    sensors = len(list(root.iter("sensor")))
    if sensors:
        notes.append(f"{sensors} <sensor> element(s) ignored (no sensors are simulated)")
    shapes = Counter(shape.tag for shape in root.iterfind("link/collision/geometry/*") if isinstance(shape.tag, str))
    if shapes:
        notes.append("<collision> geometry not used (contact shapes come from the scene): "
                     + ", ".join(f"{count} {kind}" for kind, count in sorted(shapes.items())))
    meshes = root.findall(".//mesh")
    if meshes:
        notes.append(f"{len(meshes)} mesh geometries not loaded (inertia comes from <inertial> only)")
    for link in root.findall("link"):
        if link.find("inertial") is None:
            notes.append(f"link '{link.get('name')}': no <inertial>, massless")
    return notes


def _mimic_relations(root: etree._Element, label: str) -> tuple[dict[str, Mimic], list[str]]:
    """The <mimic> of every moving joint, chains (a mimic of a mimic) resolved to their
    independent primary: q_a = m1 q_b + o1 and q_b = m2 q_c + o2 give q_a = m1 m2 q_c + m1 o2 + o1.
    A <mimic> of no other moving joint is ignored with a warning (urdfdom loads it)."""
    joints = {joint.get("name"): joint for joint in root.findall("joint")}
    direct: dict[str, tuple[str, float, float]] = {}
    warnings = []
    for name, joint in joints.items():
        element = joint.find("mimic")
        if element is None or joint.get("type") not in MOVING_JOINT_TYPES:
            continue
        primary = element.get("joint")
        if primary == name or joints.get(primary) is None or joints[primary].get("type") not in MOVING_JOINT_TYPES:
            warnings.append(f"{WARNING}joint '{name}' (line {element.sourceline}): <mimic joint=\"{primary}\"> "
                            "names no other moving joint; ignored, the joint moves independently")
            continue
        direct[name] = (primary, float(element.get("multiplier", 1.0)), float(element.get("offset", 0.0)))
    relations = {}
    for name, (primary, multiplier, offset) in direct.items():
        seen = {name}
        while primary in direct:
            if primary in seen:
                raise URDFError(f"{_where(label, joints[name])}: <mimic> joints form a cycle through '{primary}'")
            seen.add(primary)
            primary, factor, shift = direct[primary]
            multiplier, offset = multiplier * factor, multiplier * shift + offset
        relations[name] = Mimic(name, primary, multiplier, offset)
    return relations, warnings


def _pinocchio_model(element: etree._Element, mimic: dict[str, Mimic],
                     root: str) -> tuple[pin.Model, dict[str, Mimic], list[str]]:
    """Pinocchio's model with the chosen root joint (named ROOT_JOINT_NAME) and its mimic
    joints, the relations it holds and the fidelity notes.

    Pinocchio 4.1 adds a mimic joint only after its primary in its depth-first joint order; a
    mimic joint above its primary moves independently (noted).
    """
    order = _pinocchio_build(_pinocchio_xml(element, {}), root, mimic=False)
    if not mimic:
        return order, {}, []
    kept = {name: m for name, m in mimic.items() if order.getJointId(m.primary) < order.getJointId(name)}
    notes = [f"joint '{name}': <mimic> of '{m.primary}' ignored (Pinocchio needs the primary "
             "before it in the tree); the joint moves independently"
             for name, m in mimic.items() if name not in kept]
    notes += [f"joint '{name}': mimics '{m.primary}' (q = {m.multiplier:g} q_{m.primary} + {m.offset:g}); "
              "no coordinate of its own, its <limit> and <dynamics> unused" for name, m in kept.items()]
    return _pinocchio_build(_pinocchio_xml(element, kept), root, mimic=True), kept, notes


def _pinocchio_build(xml: str, root: str, *, mimic: bool) -> pin.Model:
    """pin.buildModelFromXML of the URDF text with the chosen root joint."""
    if root == "fixed":
        return pin.buildModelFromXML(xml, mimic=mimic)
    return pin.buildModelFromXML(xml, _ROOT_JOINT_MODELS[root](), ROOT_JOINT_NAME, mimic=mimic)


def _mass_matrix_defect(model: pin.Model, source: str) -> str:
    """Why forward dynamics is undefined for ``model`` ('' when the joint-space mass matrix is
    positive definite at a sample configuration: neutral moved by a fixed pseudo-random
    displacement). Joints whose diagonal entry is below MASS_MATRIX_RTOL of the largest have
    no mass (or no inertia about their axis) in their subtree."""
    if model.nv == 0:
        return ""
    # A fixed displacement spread over [-1, 1] (sines of multiples of the golden angle, rad):
    # generic like a random one, without importing numpy.random (start-up of `info`).
    q = pin.integrate(model, pin.neutral(model), np.sin(1.0 + GOLDEN_ANGLE * np.arange(model.nv)))
    upper = pin.crba(model, model.createData(), q)
    mass = np.triu(upper) + np.triu(upper, 1).T
    diagonal = np.diag(mass)
    threshold = MASS_MATRIX_RTOL * diagonal.max()
    massless = [f"'{model.names[j]}'" for j in range(1, model.njoints) if model.joints[j].nv
                and np.any(diagonal[model.joints[j].idx_v:model.joints[j].idx_v + model.joints[j].nv] <= threshold)]
    eigenvalues = np.linalg.eigvalsh(mass)
    if not massless and eigenvalues[0] > MASS_MATRIX_RTOL * eigenvalues[-1]:
        return ""
    if massless:
        return (f"{source}: the mass matrix is singular: no mass moves with joint(s) {', '.join(massless)} "
                "(their subtrees carry no mass, or no inertia about the joint axis), so forward "
                "dynamics is undefined; give those links an <inertial> or lock the joints")
    return (f"{source}: the mass matrix is not positive definite (eigenvalues {eigenvalues[0]:.3g} to "
            f"{eigenvalues[-1]:.3g}), so forward dynamics is undefined; see the inertia warnings")


def _kinematic_tree(root: etree._Element) -> tuple[tuple[TreeJoint, ...], str]:
    """URDF joints ordered root first (parents before children), children in file order;
    read from the checked XML (:func:`_check_urdf`): one root link, no loop."""
    joints = root.findall("joint")
    children: dict[str, list[etree._Element]] = {}
    for j in joints:
        children.setdefault(j.find("parent").get("link"), []).append(j)
    child_links = {j.find("child").get("link") for j in joints}
    root_link = next(l.get("name") for l in root.findall("link") if l.get("name") not in child_links)
    ordered, stack = [], [root_link]
    while stack:
        link = stack.pop()
        for j in reversed(children.get(link, [])):
            kind, child = j.get("type"), j.find("child").get("link")
            origin = _origin(j.find("origin"))
            origin.setflags(write=False)
            # Moving joints have a non-zero axis (checked); a fixed joint's axis is unused and
            # may be zero in the file (tiago_pro, Talos): it stays the URDF default x.
            axis = _floats(j.find("axis"), "xyz", "1 0 0")
            norm = np.linalg.norm(axis)
            axis = axis / norm if norm > 0.0 else np.array([1.0, 0.0, 0.0])
            axis.setflags(write=False)
            ordered.append(TreeJoint(j.get("name"), "fixed" if kind in ("floating", "planar") else kind,
                                     link, child, origin, axis))
            stack.append(child)
    return tuple(ordered), root_link


def _origin(element: etree._Element | None) -> np.ndarray:
    """The 4x4 pose of an ``<origin xyz rpy>`` (identity without one): translation xyz (m),
    rotation Rz(yaw) Ry(pitch) Rx(roll) (URDF's fixed-axis roll, pitch, yaw; rad)."""
    pose = np.eye(4)
    if element is not None:
        pose[:3, :3] = pin.rpy.rpyToMatrix(_floats(element, "rpy", "0 0 0"))
        pose[:3, 3] = _floats(element, "xyz", "0 0 0")
    return pose


def _pinocchio_xml(root: etree._Element, mimic: Mapping[str, Mimic]) -> str:
    """The URDF as Pinocchio should see it: continuous -> unbounded revolute, floating and
    planar -> fixed, <mimic> only for the joints in ``mimic`` (naming their resolved primary)."""
    root = etree.fromstring(etree.tostring(root))
    for joint in root.findall("joint"):
        kind = joint.get("type")
        for element in joint.findall("mimic"):
            joint.remove(element)
        relation = mimic.get(joint.get("name"))
        if relation is not None:
            etree.SubElement(joint, "mimic", joint=relation.primary, multiplier=repr(relation.multiplier),
                             offset=repr(relation.offset))
        if kind == "continuous":
            joint.set("type", "revolute")
            limit = joint.find("limit")
            if limit is None:
                limit = etree.SubElement(joint, "limit", effort="0", velocity="0")
            limit.set("lower", str(-UNBOUNDED))
            limit.set("upper", str(UNBOUNDED))
        elif kind in ("floating", "planar"):
            joint.set("type", "fixed")
    return etree.tostring(root, encoding="unicode")


def _joint_of(joint: etree._Element) -> Joint:
    """A moving joint's limits and dynamics from its checked XML; a bound the file leaves
    out is infinite (a continuous joint has no position limits), damping and friction 0."""
    limit, dynamics = joint.find("limit"), joint.find("dynamics")
    kind = joint.get("type")

    def value(element: etree._Element | None, attribute: str, default: float) -> float:
        text = None if element is None else element.get(attribute)
        return default if text is None else float(text)

    unbounded = kind == "continuous"
    lower = -math.inf if unbounded else value(limit, "lower", -math.inf)
    upper = math.inf if unbounded else value(limit, "upper", math.inf)
    return Joint(joint.get("name"), kind, lower, upper, value(limit, "velocity", math.inf),
                 value(limit, "effort", math.inf), value(dynamics, "damping", 0.0),
                 value(dynamics, "friction", 0.0))


def _locked(joint: TreeJoint, value: float) -> TreeJoint:
    """The joint as a fixed one: its origin times exp([X] value), X = (0, axis) for a
    prismatic joint and (axis, 0) for a revolute or continuous one (joint frame)."""
    zero = np.zeros(3)
    screw = np.concatenate((zero, joint.axis) if joint.type == "prismatic" else (joint.axis, zero))
    origin = joint.origin @ exp_se3(screw * value)
    origin.setflags(write=False)
    return TreeJoint(joint.name, "fixed", joint.parent, joint.child, origin, joint.axis)
