"""What urdfdom forgives in a URDF and a strict reader would refuse, forgiven here the same way.

urdfdom reads URDF with tinyxml, which checks neither the XML declaration nor namespaces, and
Pinocchio loads what urdfdom loads; real files (pybullet_data, ARMAR, Drake's) rely on it. So:

- :func:`lenient_xml`, a pre-pass over the text, only when the strict XML parse fails: a
  declaration after blank lines or spaces moves to the start, a declared version other than
  1.x (``<?xml version="0.0"?>``) reads as 1.0, and a namespace prefix used without a
  declaration (``drake:``) is declared on ``<robot>`` (its attributes and elements are not
  URDF and stay unread). Line numbers are kept.
- :func:`add_point_mass_inertias`: an ``<inertial>`` with a ``<mass>`` and no ``<inertia>`` is a
  point mass (zero rotational inertia about the inertial origin), as urdfdom reads it.
- :func:`reversed_limits`: a ``<limit>`` with lower > upper (pybullet's way of writing "no
  limit") means no position limits.
- (in :func:`youbot_dynamics.model.urdf.check_urdf`) malformed numbers in a ``<visual>`` or
  ``<collision>`` (a mesh ``scale`` of 1 or 4 numbers), which urdfdom drops and the dynamics
  never use; and (in :mod:`youbot_dynamics.model.pinocchio_model`) geometry, materials and
  other tools' elements never reach urdfdom, so its complaints stay off stderr.

Each forgiveness is a line of the fidelity report.
"""
from __future__ import annotations

import math
import re

from lxml import etree

from youbot_dynamics.model.fidelity import INERTIA_KEYS

UNDECLARED_NAMESPACE = "urn:youbot-dynamics:undeclared:"  # + prefix: the URI an undeclared prefix gets
_DECLARATION = r"^(\s+)(<\?xml\b[^>]*\?>)"
_DECLARATION_AT_START = r"^<\?xml\b[^>]*\?>"
_VERSION = r"""(\bversion\s*=\s*["'])([^"']*)(["'])"""
_PREFIXED_NAME = r"""(?:</?|\s)([A-Za-z_][\w.\-]*):[A-Za-z_][\w.\-]*(?=[\s=/>])"""
_DECLARED_PREFIX = r"""\bxmlns:([A-Za-z_][\w.\-]*)\s*="""
_ROBOT_START = r"<robot(?=[\s/>])"


def lenient_xml(text: str | bytes) -> tuple[str | bytes, list[str]]:
    """The text with urdfdom's forgiven XML faults mended (same line numbers), and a note for
    each mend. ``bytes`` stay bytes (the declaration's encoding is kept)."""
    binary = isinstance(text, bytes)

    def pattern(regex: str) -> re.Pattern:
        return re.compile(regex.encode() if binary else regex)

    def string(value: str | bytes) -> str:
        return value.decode("latin-1") if binary else value

    notes = []
    declaration = pattern(_DECLARATION).match(text)
    if declaration:  # blank lines first, then the declaration: swapped, lines keep their numbers
        text = declaration.group(2) + declaration.group(1) + text[declaration.end():]
        notes.append("XML: blank lines or spaces before the <?xml ...?> declaration ignored (as urdfdom does)")
    head = pattern(_DECLARATION_AT_START).match(text)
    version = pattern(_VERSION).search(text, 0, head.end()) if head else None
    if version and not re.fullmatch(r"1\.\d+", string(version.group(2))):
        one = b"1.0" if binary else "1.0"
        text = text[:version.start(2)] + one + text[version.end(2):]
        notes.append(f"XML: declared version '{string(version.group(2))}' read as 1.0 (urdfdom ignores it)")
    used = {string(m.group(1)) for m in pattern(_PREFIXED_NAME).finditer(text)}
    declared = {string(m.group(1)) for m in pattern(_DECLARED_PREFIX).finditer(text)}
    undeclared = sorted(used - declared - {"xml", "xmlns"})
    robot = pattern(_ROBOT_START).search(text)
    if undeclared and robot:
        declarations = "".join(f' xmlns:{prefix}="{UNDECLARED_NAMESPACE}{prefix}"' for prefix in undeclared)
        text = text[:robot.end()] + (declarations.encode() if binary else declarations) + text[robot.end():]
        notes.append(f"XML: namespace prefix(es) {', '.join(repr(p) for p in undeclared)} used without a "
                     "declaration (urdfdom reads no namespaces): their attributes and elements are not URDF, ignored")
    return text, notes


def add_point_mass_inertias(root: etree._Element) -> list[str]:
    """Give every <inertial> that has a <mass> and no <inertia> a zero <inertia> (a point mass,
    as urdfdom reads it); a note per link."""
    notes = []
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None or inertial.find("mass") is None or inertial.find("inertia") is not None:
            continue
        etree.SubElement(inertial, "inertia", dict.fromkeys(INERTIA_KEYS, "0"))
        notes.append(f"link '{link.get('name')}' (line {link.sourceline}): <inertial> has a <mass> and no "
                     "<inertia>: a point mass (zero rotational inertia), as urdfdom reads it")
    return notes


def reversed_limits(joint: etree._Element) -> bool:
    """Whether a revolute or prismatic joint's <limit> gives lower > upper (finite numbers):
    pybullet's way of saying the joint has no position limits."""
    limit = joint.find("limit")
    if joint.get("type") not in ("revolute", "prismatic") or limit is None:
        return False
    try:
        lower, upper = float(limit.get("lower", 0)), float(limit.get("upper", 0))
    except ValueError:
        return False
    return math.isfinite(lower) and math.isfinite(upper) and lower > upper


def reversed_limit_notes(root: etree._Element) -> list[str]:
    """A note per joint whose limits are reversed (read as none)."""
    return [f"joint '{joint.get('name')}' (line {joint.sourceline}): <limit> lower {joint.find('limit').get('lower')} "
            f"> upper {joint.find('limit').get('upper')}, pybullet's way of saying no limit: no position limits"
            for joint in root.findall("joint") if reversed_limits(joint)]
