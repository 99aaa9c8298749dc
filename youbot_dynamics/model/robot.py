"""URDF -> Robot: the immutable description of what a robot IS.

A :class:`Robot` holds the Pinocchio model of the URDF (for the rigid-body algorithms), the
kinematic tree as the URDF states it (for the screw axes, independent of Pinocchio), the
moving joints in Pinocchio's order with their limits, damping and friction, and a fidelity
report of what the model ignores or approximates. What the robot is DOING lives elsewhere
(Pinocchio ``Data`` and the simulation state); nothing here changes after loading.

Joint coordinates: one number per moving joint (angle in rad for revolute and continuous
joints, displacement in m for prismatic ones), in Pinocchio's joint order, so nq == nv.
Continuous joints are given to Pinocchio as revolute joints without position limits (the
angle is not wrapped); the fidelity report says so.
"""
from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin
import yourdfpy
from lxml import etree

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.lie import exp_se3

MOVING_JOINT_TYPES = ("revolute", "continuous", "prismatic")
KNOWN_JOINT_TYPES = (*MOVING_JOINT_TYPES, "fixed", "floating", "planar")
UNBOUNDED = 1e10  # position limit handed to Pinocchio for continuous joints, rad


class URDFError(UserInputError):
    """A URDF that cannot be loaded: the message names the file, the element and the reason."""


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
class Robot:
    """Immutable robot description. Do not mutate ``model``; make Data with ``model.createData()``."""

    name: str
    source: str
    model: pin.Model
    joints: tuple[Joint, ...]
    tree: tuple[TreeJoint, ...]
    root_link: str
    fidelity: tuple[str, ...]
    locked: Mapping[str, float] = field(default_factory=dict)

    # ---- joint-indexed arrays (Pinocchio order) -------------------------------------
    @property
    def joint_names(self) -> tuple[str, ...]:
        """Moving joints' names in Pinocchio's order (the order of every joint vector)."""
        return tuple(j.name for j in self.joints)

    @property
    def nv(self) -> int:
        """Number of moving joints (== model.nq == model.nv)."""
        return len(self.joints)

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
        """Index of a moving joint in the joint-coordinate vector."""
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise UserInputError(
                f"unknown joint '{name}' in robot '{self.name}' ({self.source}); "
                f"moving joints: {', '.join(self.joint_names)}"
            ) from None

    def frame_id(self, name: str) -> int:
        """Pinocchio frame id of a link (or joint) frame, with a clear error if unknown."""
        if not self.model.existFrame(name):
            raise UserInputError(
                f"unknown frame '{name}' in robot '{self.name}' ({self.source}); "
                f"links: {', '.join(self.link_names)}"
            )
        return self.model.getFrameId(name)

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
        depth = {link: len(self.chain_to(link)) for link in self.link_names}
        deepest = [link for link, d in depth.items() if d == max(depth.values())]
        chains = [[self.root_link, *(j.child for j in self.chain_to(link))] for link in deepest]
        common = self.root_link
        for links in zip(*chains):
            if len(set(links)) != 1:
                break
            common = links[0]
        return common

    def vector(self, values: Mapping[str, float] | Sequence[float] | np.ndarray, *,
               default: float | None = 0.0, what: str = "joint values") -> np.ndarray:
        """Joint-coordinate vector from a sequence in model order or a mapping by joint name.

        Joints missing from a mapping take ``default`` (an error when ``default`` is None).
        """
        if isinstance(values, Mapping):
            out = np.full(self.nv, np.nan if default is None else default)
            for name, value in values.items():
                out[self.joint_index(name)] = float(value)
            missing = [n for n, v in zip(self.joint_names, out) if np.isnan(v)]
            if missing:
                raise UserInputError(f"{what}: no value for joint(s) {', '.join(missing)}")
            return out
        out = np.asarray(values, dtype=float).reshape(-1)
        if out.size != self.nv:
            raise UserInputError(
                f"{what}: expected {self.nv} values in joint order "
                f"({', '.join(self.joint_names)}), got {out.size}"
            )
        return out


# ---------------------------------------------------------------------------------------
# Loading
# ---------------------------------------------------------------------------------------
def load_robot(source: str | Path) -> Robot:
    """Build a Robot from a URDF file path or a URDF XML string.

    Raises :class:`URDFError` naming the file, the element (with its line) and the reason for
    a missing file, malformed XML, an unknown joint type, a missing parent or child link, a
    non-positive mass, an inertia that is not positive definite or violates the triangle
    inequality, a lower limit above the upper one, or a kinematic loop.
    """
    text, label = _read_source(source)
    root = _parse_xml(text, label)
    try:
        fidelity = _check_urdf(root, label)
        urdf = yourdfpy.URDF.load(io.StringIO(text), build_scene_graph=False, load_meshes=False)
        tree, root_link = _kinematic_tree(urdf)
        model = pin.buildModelFromXML(_pinocchio_xml(root))
        joints = tuple(_joint_of(urdf.joint_map[model.names[i]]) for i in range(1, model.njoints))
    except (ValueError, TypeError, KeyError, IndexError, AttributeError) as error:  # the parsers' own failures
        if isinstance(error, URDFError):
            raise
        raise URDFError(f"{label}: cannot read the URDF: {type(error).__name__}: {' '.join(str(error).split())} "
                        "(a malformed attribute or element the checks above do not cover)") from None
    return Robot(name=root.get("name", "robot"), source=label, model=model, joints=joints,
                 tree=tree, root_link=root_link, fidelity=tuple(fidelity))


def lock_joints(robot: Robot, positions: Mapping[str, float]) -> Robot:
    """Reduced Robot with the named joints locked at the given values (rad or m).

    The locked joints become fixed joints of the tree with their value folded into the
    origin, and Pinocchio's buildReducedModel removes them from the rigid-body model.
    """
    if not positions:
        return robot
    indices = [robot.joint_index(name) for name in positions]
    q_ref = np.zeros(robot.nv)
    for i, value in zip(indices, positions.values()):
        q_ref[i] = float(value)
    joint_ids = [robot.model.getJointId(name) for name in positions]
    model = pin.buildReducedModel(robot.model, joint_ids, q_ref)
    tree = tuple(_locked(j, positions[j.name]) if j.name in positions else j for j in robot.tree)
    kept = tuple(j for j in robot.joints if j.name not in positions)
    return Robot(name=robot.name, source=robot.source, model=model, joints=kept, tree=tree,
                 root_link=robot.root_link, fidelity=robot.fidelity,
                 locked={**robot.locked, **{k: float(v) for k, v in positions.items()}})


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
def _read_source(source: str | Path) -> tuple[str, str]:
    if isinstance(source, str) and source.lstrip().startswith("<"):
        return source, "<URDF string>"
    path = Path(source)
    if not path.is_file():
        raise URDFError(f"URDF file not found: {path}")
    return path.read_text(encoding="utf-8"), str(path)


def _parse_xml(text: str, label: str) -> etree._Element:
    try:
        root = etree.fromstring(text.encode("utf-8"))
    except etree.XMLSyntaxError as error:
        raise URDFError(f"{label}: malformed XML: {error}") from None
    if root.tag != "robot":
        raise URDFError(f"{label}:{root.sourceline}: root element is <{root.tag}>, expected <robot>")
    return root


def _where(label: str, element: etree._Element) -> str:
    return f"{label}:{element.sourceline}: {element.tag} '{element.get('name')}'"


def _floats(element: etree._Element | None, attribute: str, default: str) -> np.ndarray:
    return np.array([float(x) for x in (element.get(attribute, default) if element is not None else default).split()])


def _check_urdf(root: etree._Element, label: str) -> list[str]:
    """Validate the URDF; returns the fidelity notes of what the model ignores."""
    links = {link.get("name"): link for link in root.findall("link")}
    if not links:
        raise URDFError(f"{label}: the robot has no <link>")
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
            if axis.shape != (3,) or np.linalg.norm(axis) < 1e-12:
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
    for link in links.values():
        _check_inertial(link, label)
    return _fidelity_notes(root)


def _check_inertial(link: etree._Element, label: str) -> None:
    inertial = link.find("inertial")
    if inertial is None:
        return
    where = _where(label, link)
    mass_element = inertial.find("mass")
    mass = float(mass_element.get("value")) if mass_element is not None else 0.0
    if not mass > 0.0 or not math.isfinite(mass):
        raise URDFError(f"{where}: mass must be positive and finite, got {mass}")
    element = inertial.find("inertia")
    if element is None:
        raise URDFError(f"{where}: <inertial> has a mass but no <inertia>")
    c = {k: float(element.get(k, 0.0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    inertia = np.array([[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]], [c["ixz"], c["iyz"], c["izz"]]])
    principal = np.linalg.eigvalsh(inertia)
    if not np.all(np.isfinite(principal)) or principal[0] <= 0.0:
        raise URDFError(f"{where}: inertia is not positive definite (principal moments "
                        f"{np.array2string(principal, precision=6)} kg m^2)")
    a, b, c3 = principal
    if a + b < c3 * (1.0 - 1e-9):
        raise URDFError(f"{where}: inertia violates the triangle inequality: principal moments "
                        f"{a:.6g} + {b:.6g} < {c3:.6g} kg m^2 (no rigid body has it)")


def _fidelity_notes(root: etree._Element) -> list[str]:
    """What of the URDF the model ignores or approximates."""
    notes = []
    for joint in root.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        if joint.find("mimic") is not None:
            notes.append(f"joint '{name}': <mimic> ignored; the joint moves independently")
        if joint.find("safety_controller") is not None:
            notes.append(f"joint '{name}': <safety_controller> ignored (soft limits not enforced)")
        if joint.find("calibration") is not None:
            notes.append(f"joint '{name}': <calibration> ignored")
        if kind == "continuous":
            notes.append(f"joint '{name}': continuous, modelled as revolute without position limits (angle not wrapped)")
        if kind in ("floating", "planar"):
            notes.append(f"joint '{name}': {kind} joint treated as fixed at its origin (free bodies are scene objects)")
    for tag in ("transmission", "gazebo"):
        count = len(root.findall(tag))
        if count:
            notes.append(f"{count} <{tag}> element(s) ignored")
    meshes = root.findall(".//mesh")
    if meshes:
        notes.append(f"{len(meshes)} mesh geometries not loaded (inertia comes from <inertial> only)")
    for link in root.findall("link"):
        if link.find("inertial") is None:
            notes.append(f"link '{link.get('name')}': no <inertial>, massless")
    return notes


def _kinematic_tree(urdf: yourdfpy.URDF) -> tuple[tuple[TreeJoint, ...], str]:
    """URDF joints ordered root first (parents before children)."""
    joints = {j.name: j for j in urdf.robot.joints}
    children: dict[str, list[str]] = {}
    for j in urdf.robot.joints:
        children.setdefault(j.parent, []).append(j.name)
    root_link = next(l.name for l in urdf.robot.links if l.name not in {j.child for j in urdf.robot.joints})
    ordered, stack = [], [root_link]
    while stack:
        link = stack.pop()
        for name in reversed(children.get(link, [])):
            j = joints[name]
            origin = np.eye(4) if j.origin is None else np.array(j.origin, dtype=float)
            axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else np.array(j.axis, dtype=float)
            kind = "fixed" if j.type in ("floating", "planar") else j.type
            origin.setflags(write=False)
            axis = axis / np.linalg.norm(axis)
            axis.setflags(write=False)
            ordered.append(TreeJoint(j.name, kind, j.parent, j.child, origin, axis))
            stack.append(j.child)
    return tuple(ordered), root_link


def _pinocchio_xml(root: etree._Element) -> str:
    """The URDF as Pinocchio should see it: continuous -> unbounded revolute, floating and
    planar -> fixed, mimic removed (see the fidelity report)."""
    root = etree.fromstring(etree.tostring(root))
    for joint in root.findall("joint"):
        kind = joint.get("type")
        for mimic in joint.findall("mimic"):
            joint.remove(mimic)
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


def _joint_of(j: yourdfpy.Joint) -> Joint:
    limit, dynamics = j.limit, j.dynamics
    unbounded = j.type == "continuous"
    lower = -math.inf if unbounded or limit is None or limit.lower is None else float(limit.lower)
    upper = math.inf if unbounded or limit is None or limit.upper is None else float(limit.upper)
    velocity = math.inf if limit is None or limit.velocity is None else float(limit.velocity)
    effort = math.inf if limit is None or limit.effort is None else float(limit.effort)
    damping = 0.0 if dynamics is None or dynamics.damping is None else float(dynamics.damping)
    friction = 0.0 if dynamics is None or dynamics.friction is None else float(dynamics.friction)
    return Joint(j.name, j.type, lower, upper, velocity, effort, damping, friction)


def _locked(joint: TreeJoint, value: float) -> TreeJoint:
    """The joint as a fixed one: its origin times exp([X] value), X = (0, axis) for a
    prismatic joint and (axis, 0) for a revolute or continuous one (joint frame)."""
    zero = np.zeros(3)
    screw = np.concatenate((zero, joint.axis) if joint.type == "prismatic" else (joint.axis, zero))
    origin = joint.origin @ exp_se3(screw * value)
    origin.setflags(write=False)
    return TreeJoint(joint.name, "fixed", joint.parent, joint.child, origin, joint.axis)
