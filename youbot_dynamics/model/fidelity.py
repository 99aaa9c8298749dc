"""The fidelity report of a loaded URDF: what the file declares that the dynamics do not use
or approximate, and the warnings about physically invalid data.

Every note is one line of text. Warnings (a physically invalid inertia, a singular joint-space
mass matrix, a ``<mimic>`` of no moving joint) start with :data:`WARNING`; ``strict`` loading
(:func:`youbot_dynamics.model.robot.load_robot`) turns them into errors. The other notes say
what is ignored (soft limits, calibration, collision shapes, meshes, shapes of no URDF type, sensors, ``<contact>``,
``<ros2_control>``, ``<transmission>``, ``<gazebo>``) or approximated (continuous joints as
unbounded revolute ones, floating and planar joints fixed at their origin, massless links).

Inertias are in kg m^2, masses in kg, both in the link's inertial frame as the URDF gives them.
"""
from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pinocchio as pin
from lxml import etree

WARNING = "warning: "  # prefix of the fidelity notes that strict loading turns into errors
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
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
#: The geometry types urdfdom reads; another one is "Unknown geometry type" to it.
URDF_SHAPES = ("box", "cylinder", "sphere", "mesh")
GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))  # rad, for the sample configuration of that test


def inertial_warnings(root: etree._Element) -> list[str]:
    """Warnings for every link's physically invalid <inertial> (checked to hold a <mass> and
    an <inertia>), in file order."""
    return [warning for link in root.findall("link") for warning in _link_inertial_warnings(link)]


def _link_inertial_warnings(link: etree._Element) -> list[str]:
    """Warnings for a physically invalid <inertial> (a negative mass, a negative principal
    moment, the triangle inequality violated), each naming the link and its line. Zero mass
    and point masses are valid; principal moments within INERTIA_RTOL of the largest (or
    below INERTIA_ATOL) count as zero."""
    inertial = link.find("inertial")
    if inertial is None:
        return []
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


def fidelity_notes(root: etree._Element) -> list[str]:
    """What of the URDF the model ignores or approximates: joints, link contacts, the
    elements of other tools, geometry, then massless links."""
    return (_joint_notes(root) + _contact_notes(root) + _ignored_element_notes(root)
            + _geometry_notes(root) + _massless_notes(root))


def _joint_notes(root: etree._Element) -> list[str]:
    """Per joint: soft limits and calibration ignored, continuous and free joints approximated."""
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
    return notes


def _contact_notes(root: etree._Element) -> list[str]:
    """A link's <contact> coefficients (Bullet's): contact comes from the scene."""
    notes = []
    for link in root.findall("link"):
        contact = link.find("contact")
        if contact is not None:
            values = ", ".join(f"{c.tag} {c.get('value')}" for c in contact if isinstance(c.tag, str))
            notes.append(f"link '{link.get('name')}': <contact> ({values}) ignored; "
                         "contact laws and friction come from the scene")
    return notes


def _ignored_element_notes(root: etree._Element) -> list[str]:
    """Elements for other tools: <ros2_control>, <transmission>, <gazebo>, <sensor>."""
    notes = []
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
    return notes


def _geometry_notes(root: etree._Element) -> list[str]:
    """Collision shapes and meshes: neither enters the dynamics; shapes of no URDF type."""
    notes = []
    for link in root.findall("link"):
        for shape in link.iterfind("*/geometry/*"):
            if isinstance(shape.tag, str) and shape.tag not in URDF_SHAPES:
                notes.append(f"link '{link.get('name')}' (line {shape.sourceline}): <{shape.getparent().getparent().tag}> "
                             f"geometry <{shape.tag}> is no URDF shape (urdfdom: \"Unknown geometry type\"), ignored")
    shapes = Counter(shape.tag for shape in root.iterfind("link/collision/geometry/*") if isinstance(shape.tag, str))
    if shapes:
        notes.append("<collision> geometry not used (contact shapes come from the scene): "
                     + ", ".join(f"{count} {kind}" for kind, count in sorted(shapes.items())))
    meshes = root.findall(".//mesh")
    if meshes:
        notes.append(f"{len(meshes)} mesh geometries not loaded (inertia comes from <inertial> only)")
    return notes


def _massless_notes(root: etree._Element) -> list[str]:
    """Links without an <inertial>."""
    return [f"link '{link.get('name')}': no <inertial>, massless"
            for link in root.findall("link") if link.find("inertial") is None]


def mass_matrix_defect(model: pin.Model, source: str) -> str:
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
