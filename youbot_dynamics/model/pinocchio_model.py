"""The Pinocchio model of a checked URDF tree, with the chosen root joint and its mimic joints.

The URDF is rewritten as Pinocchio should see it (:func:`pinocchio_urdf`): links with their
<inertial> only and joints, nothing else (no visual, collision, material or other tool's
element reaches urdfdom, so none of its complaints about them is printed on stderr: the
fidelity report names what is ignored), continuous joints and joints with reversed limits as
revolute or prismatic joints with position limits of +-UNBOUNDED (one coordinate, angle not
wrapped), floating and planar joints fixed at their origin, ``<mimic>`` only where Pinocchio
can honour it. A floating or planar root is Pinocchio's free-flyer or planar joint between the
world and the root link, named :data:`ROOT_JOINT_NAME` unless the file has a joint of that
name (:func:`root_joint_name`).
"""
from __future__ import annotations

from typing import Mapping

import pinocchio as pin
from lxml import etree

from youbot_dynamics.model.lenient_urdf import reversed_limits
from youbot_dynamics.model.urdf import Mimic

UNBOUNDED = 1e10  # position limit handed to Pinocchio for continuous joints, rad
ROOT_JOINT_NAME = "root_joint"  # the Pinocchio joint of a floating or planar root
_ROOT_JOINT_MODELS = {"floating": pin.JointModelFreeFlyer, "planar": pin.JointModelPlanar}


def root_joint_name(element: etree._Element) -> str:
    """ROOT_JOINT_NAME, or when a joint of the URDF has that name (ARMAR-4's fixed joint to
    its world) the first of ROOT_JOINT_NAME_1, _2, ... that none has."""
    taken = {joint.get("name") for joint in element.findall("joint")}
    name, k = ROOT_JOINT_NAME, 0
    while name in taken:
        k += 1
        name = f"{ROOT_JOINT_NAME}_{k}"
    return name


def pinocchio_model(element: etree._Element, mimic: dict[str, Mimic], root: str,
                    root_joint: str = ROOT_JOINT_NAME) -> tuple[pin.Model, dict[str, Mimic], list[str]]:
    """Pinocchio's model with the chosen root joint (named ``root_joint``) and its mimic
    joints, the relations it holds and the fidelity notes.

    Pinocchio 4.1 adds a mimic joint only after its primary in its depth-first joint order; a
    mimic joint above its primary moves independently (noted).
    """
    order = _build(pinocchio_urdf(element, {}), root, root_joint, mimic=False)
    if not mimic:
        return order, {}, []
    kept = {name: m for name, m in mimic.items() if order.getJointId(m.primary) < order.getJointId(name)}
    notes = [f"joint '{name}': <mimic> of '{m.primary}' ignored (Pinocchio needs the primary "
             "before it in the tree); the joint moves independently"
             for name, m in mimic.items() if name not in kept]
    notes += [f"joint '{name}': mimics '{m.primary}' (q = {m.multiplier:g} q_{m.primary} + {m.offset:g}); "
              "no coordinate of its own, its <limit> and <dynamics> unused" for name, m in kept.items()]
    return _build(pinocchio_urdf(element, kept), root, root_joint, mimic=True), kept, notes


def _build(xml: str, root: str, root_joint: str, *, mimic: bool) -> pin.Model:
    """pin.buildModelFromXML of the URDF text with the chosen root joint."""
    if root == "fixed":
        return pin.buildModelFromXML(xml, mimic=mimic)
    return pin.buildModelFromXML(xml, _ROOT_JOINT_MODELS[root](), root_joint, mimic=mimic)


def pinocchio_urdf(root: etree._Element, mimic: Mapping[str, Mimic]) -> str:
    """The URDF as Pinocchio should see it: links with their <inertial> only, joints, continuous
    or with reversed limits -> unbounded, floating and planar -> fixed, <mimic> only for the
    joints in ``mimic`` (naming their resolved primary)."""
    root = etree.fromstring(etree.tostring(root))
    for element in list(root):
        if element.tag not in ("link", "joint"):
            root.remove(element)
    for link in root.findall("link"):
        for element in list(link):
            if element.tag != "inertial":
                link.remove(element)
    for joint in root.findall("joint"):
        kind = joint.get("type")
        for element in joint.findall("mimic"):
            joint.remove(element)
        relation = mimic.get(joint.get("name"))
        if relation is not None:
            etree.SubElement(joint, "mimic", joint=relation.primary, multiplier=repr(relation.multiplier),
                             offset=repr(relation.offset))
        if kind == "continuous" or reversed_limits(joint):
            joint.set("type", "revolute" if kind == "continuous" else kind)
            limit = joint.find("limit")
            if limit is None:
                limit = etree.SubElement(joint, "limit", effort="0", velocity="0")
            limit.set("lower", str(-UNBOUNDED))
            limit.set("upper", str(UNBOUNDED))
        elif kind in ("floating", "planar"):
            joint.set("type", "fixed")
    return etree.tostring(root, encoding="unicode")
