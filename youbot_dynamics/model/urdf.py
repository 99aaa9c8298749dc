"""Reading URDF text into the kinematic tree and its elements, checked as urdfdom checks it.

:func:`read_source` and :func:`parse_urdf` give the XML tree of a file or a string;
:func:`check_urdf` refuses what urdfdom refuses (and what the limits of
:mod:`youbot_dynamics.model.limits` bound) with a :class:`URDFError` naming file:line, the
element and the reason; from the checked tree, :func:`kinematic_tree` gives the joints as
edges (:class:`TreeJoint`, root first), :func:`moving_joint` a joint's limits and dynamics
(:class:`Joint`) and :func:`mimic_relations` the ``<mimic>`` couplings (:class:`Mimic`).

Units are the URDF's: lengths in m, angles in rad, masses in kg, inertias in kg m^2; poses are
4x4 homogeneous matrices of the child frame in the parent link's frame.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np
import pinocchio as pin
from lxml import etree

from youbot_dynamics.errors import URDFError
from youbot_dynamics.model import limits
from youbot_dynamics.model.fidelity import INERTIA_KEYS, WARNING
from youbot_dynamics.model.lenient_urdf import lenient_xml, reversed_limits

MOVING_JOINT_TYPES = ("revolute", "continuous", "prismatic")
KNOWN_JOINT_TYPES = (*MOVING_JOINT_TYPES, "fixed", "floating", "planar")
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
#: The parts of a link whose malformed numbers urdfdom drops with the part (never used here).
FORGIVING_PARTS = ("visual", "collision")
_XML_DECLARATION = re.compile(r"^\s*<\?xml\b[^>]*\?>")


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


# ---------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------
def read_source(source: str | Path) -> tuple[str | bytes, str]:
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


def parse_urdf(text: str | bytes, label: str) -> tuple[etree._Element, list[str]]:
    """The XML tree of a <robot> with a name, and the notes of what was forgiven to read it.

    A str is already decoded, so its encoding declaration (which lxml refuses in a str) is
    dropped. Text the strict parser refuses is read again after the pre-pass of
    :func:`~youbot_dynamics.model.lenient_urdf.lenient_xml` (what urdfdom forgives); the lines
    keep their numbers either way."""
    if isinstance(text, str):
        text = _XML_DECLARATION.sub("", text, count=1)
    try:
        root, notes = etree.fromstring(text), []
    except etree.XMLSyntaxError:
        mended, notes = lenient_xml(text)
        try:
            root = etree.fromstring(mended)
        except etree.XMLSyntaxError as error:
            raise URDFError(f"{label}: malformed XML: {error}") from None
    if root.tag != "robot":
        raise URDFError(f"{label}:{root.sourceline}: root element is <{root.tag}>, expected <robot>")
    if not root.get("name"):
        raise URDFError(f"{label}:{root.sourceline}: <robot> has no name attribute")
    return root, notes


def where(label: str, element: etree._Element) -> str:
    """``file:line: tag 'name'`` of an element, the head of an error message."""
    return f"{label}:{element.sourceline}: {element.tag} '{element.get('name')}'"


def _floats(element: etree._Element | None, attribute: str, default: str) -> np.ndarray:
    return np.array([float(x) for x in (element.get(attribute, default) if element is not None else default).split()])


# ---------------------------------------------------------------------------------------
# Checking
# ---------------------------------------------------------------------------------------
def check_urdf(root: etree._Element, label: str) -> list[str]:
    """Refuse, as urdfdom does, a URDF beyond the size bounds, with duplicate names, no link,
    malformed numbers, a malformed joint, links that form no single tree or an <inertial>
    without <mass> and <inertia>. Malformed numbers in a <visual> or <collision> (which the
    dynamics never use and urdfdom drops) are notes instead, returned; numbers beyond their
    bounds are errors there too."""
    _check_sizes(root, label)
    _check_unique_names(root, label)
    links = {link.get("name"): link for link in root.findall("link")}
    if not links:
        raise URDFError(f"{label}: the robot has no <link>")
    notes = [note for owner, part, element in _urdf_elements(root)
             for note in _check_numbers(owner, element, label, part)]
    parent_link: dict[str, str] = {}  # child link -> parent link
    parent_of: dict[str, str] = {}  # child link -> its joint's name
    for joint in root.findall("joint"):
        _check_joint(joint, links, parent_of, label)
        parent_of[joint.find("child").get("link")] = joint.get("name")
        parent_link[joint.find("child").get("link")] = joint.find("parent").get("link")
    _check_single_tree(links, parent_link, label)
    for link in links.values():
        inertial = link.find("inertial")
        if inertial is not None and (inertial.find("mass") is None or inertial.find("inertia") is None):
            raise URDFError(f"{where(label, link)}: <inertial> needs a <mass> and an <inertia>")
    return notes


def _check_sizes(root: etree._Element, label: str) -> None:
    """The counts of links, joints and moving joints within youbot_dynamics.model.limits."""
    sizes = {"<link> elements": (limits.MAX_LINKS, sum(1 for e in root if e.tag == "link")),
             "<joint> elements": (limits.MAX_LINKS, sum(1 for e in root if e.tag == "joint")),
             "moving joints": (limits.MAX_MOVING_JOINTS, sum(1 for e in root if e.tag == "joint"
                                                             and e.get("type") in MOVING_JOINT_TYPES))}
    for what, (most, count) in sizes.items():
        if count > most:
            raise URDFError(f"{label}: {count} {what}, beyond the bound of {most} (see "
                            "youbot_dynamics.model.limits; the largest example robot has 130 links, 101 moving joints)")


def _check_unique_names(root: etree._Element, label: str) -> None:
    """No two links, and no two joints, of one name."""
    first_line: dict[tuple[str, str], int] = {}  # (tag, name) -> line
    for element in root:
        if element.tag in ("link", "joint"):
            key = (element.tag, element.get("name"))
            if key in first_line:
                raise URDFError(f"{where(label, element)}: the name is already used by the "
                                f"{element.tag} at line {first_line[key]}")
            first_line[key] = element.sourceline


def _check_joint(joint: etree._Element, links: dict[str, etree._Element], parent_of: dict[str, str],
                 label: str) -> None:
    """A known type, defined parent and child links, a child no other joint has (``parent_of``:
    child link -> joint, of the joints before), a <limit> on a revolute or prismatic joint
    (lower > upper means no limit: :func:`~youbot_dynamics.model.lenient_urdf.reversed_limits`)
    and a non-zero axis on a moving one."""
    at = where(label, joint)
    kind = joint.get("type")
    if kind not in KNOWN_JOINT_TYPES:
        raise URDFError(f"{at}: unknown joint type '{kind}' (expected one of {', '.join(KNOWN_JOINT_TYPES)})")
    for role in ("parent", "child"):
        element = joint.find(role)
        name = element.get("link") if element is not None else None
        if name is None:
            raise URDFError(f"{at}: missing <{role} link=...>")
        if name not in links:
            raise URDFError(f"{at}: {role} link '{name}' is not defined")
    child = joint.find("child").get("link")
    if child in parent_of:
        raise URDFError(f"{at}: kinematic loop: link '{child}' is already the child of "
                        f"joint '{parent_of[child]}' (closed chains are not supported in URDF)")
    if kind in ("revolute", "prismatic") and joint.find("limit") is None:
        raise URDFError(f"{at}: a {kind} joint needs a <limit>")
    if kind in MOVING_JOINT_TYPES:
        axis = _floats(joint.find("axis"), "xyz", "1 0 0")
        if np.linalg.norm(axis) < 1e-12:
            raise URDFError(f"{at}: axis {axis.tolist()} is not a non-zero 3-vector")


def _check_single_tree(links: dict[str, etree._Element], parent_link: dict[str, str], label: str) -> None:
    """Exactly one link without a parent joint, and no loop (``parent_link``: child -> parent)."""
    roots = [name for name in links if name not in parent_link]
    if len(roots) != 1:
        raise URDFError(f"{label}: the links form {'no tree (kinematic loop)' if not roots else 'several trees'}; "
                        f"links without a parent joint: {', '.join(roots) or 'none'}")
    # A cycle with one root elsewhere: walk up from every link.
    for start in links:
        seen, link = set(), start
        while link in parent_link:
            if link in seen:
                raise URDFError(f"{label}: kinematic loop through link '{link}'")
            seen.add(link)
            link = parent_link[link]


def _urdf_elements(root: etree._Element) -> Iterator[tuple[etree._Element, str, etree._Element]]:
    """(owner, part, element) for every element whose attributes urdfdom reads: a joint's
    children (part ``"joint"``), and the children of a link's <inertial>, <visual> and
    <collision> (the part) with their shapes."""
    for joint in root.findall("joint"):
        for child in joint:
            yield joint, "joint", child
    for link in root.findall("link"):
        for part in link:
            if part.tag not in ("inertial", "visual", "collision"):
                continue
            for child in part:
                yield link, part.tag, child
                if child.tag == "geometry":
                    yield from ((link, part.tag, shape) for shape in child)


def _check_numbers(owner: etree._Element, element: etree._Element, label: str, part: str) -> list[str]:
    """Every numeric attribute of ``element`` holds as many finite numbers as urdfdom reads,
    within the bounds of youbot_dynamics.model.limits, and the attributes urdfdom requires are
    there. In a <visual> or <collision> (``part``, the owner's element that holds ``element``:
    FORGIVING_PARTS) a wrong count or a non-number is a returned note, not an error; a number
    beyond its bound stays an error."""
    spec = NUMERIC_ATTRIBUTES.get(element.tag)
    if spec is None:
        return []
    at = f"{label}:{element.sourceline}: {owner.tag} '{owner.get('name')}': <{element.tag}>"
    for attribute in REQUIRED_ATTRIBUTES.get(element.tag, ()):
        if element.get(attribute) is None:
            raise URDFError(f"{at}: missing attribute '{attribute}'")
    notes = []
    for attribute, count in spec.items():
        text = element.get(attribute)
        if text is None:
            continue
        parts = text.split()
        malformed = f" is not {count} number(s)" if len(parts) != count else ""
        for part in parts if not malformed else ():
            value = _finite_or_nan(part)
            if not math.isfinite(value):
                malformed = f": '{part}' is not a finite number"
                break
            bound = ATTRIBUTE_BOUNDS.get(element.tag, {}).get(attribute)
            problem = bound.problem(value) if bound is not None else ""
            if problem:
                raise URDFError(f"{at}: {attribute}=\"{text}\": {problem}")
        if malformed and part not in FORGIVING_PARTS:
            raise URDFError(f"{at}: {attribute}=\"{text}\"{malformed}")
        if malformed:
            notes.append(f"{at}: {attribute}=\"{text}\"{malformed} (in a <{part}>, which urdfdom drops "
                         "and the dynamics never use: ignored)")
    return notes


def _finite_or_nan(text: str) -> float:
    """float(text), NaN when it is no number."""
    try:
        return float(text)
    except ValueError:
        return math.nan


# ---------------------------------------------------------------------------------------
# The checked tree's elements
# ---------------------------------------------------------------------------------------
def kinematic_tree(root: etree._Element) -> tuple[tuple[TreeJoint, ...], str]:
    """URDF joints ordered root first (parents before children), children in file order, and
    the root link; read from the checked XML (:func:`check_urdf`): one root link, no loop."""
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


def moving_joint(joint: etree._Element) -> Joint:
    """A moving joint's limits and dynamics from its checked XML; a bound the file leaves
    out is infinite (a continuous joint, or one whose limits are reversed, has no position
    limits), damping and friction 0."""
    limit, dynamics = joint.find("limit"), joint.find("dynamics")
    kind = joint.get("type")

    def value(element: etree._Element | None, attribute: str, default: float) -> float:
        text = None if element is None else element.get(attribute)
        return default if text is None else float(text)

    unbounded = kind == "continuous" or reversed_limits(joint)
    lower = -math.inf if unbounded else value(limit, "lower", -math.inf)
    upper = math.inf if unbounded else value(limit, "upper", math.inf)
    return Joint(joint.get("name"), kind, lower, upper, value(limit, "velocity", math.inf),
                 value(limit, "effort", math.inf), value(dynamics, "damping", 0.0),
                 value(dynamics, "friction", 0.0))


def mimic_relations(root: etree._Element, label: str) -> tuple[dict[str, Mimic], list[str]]:
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
                raise URDFError(f"{where(label, joints[name])}: <mimic> joints form a cycle through '{primary}'")
            seen.add(primary)
            primary, factor, shift = direct[primary]
            multiplier, offset = multiplier * factor, multiplier * shift + offset
        relations[name] = Mimic(name, primary, multiplier, offset)
    return relations, warnings
