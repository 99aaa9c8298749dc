"""The Pinocchio model of a checked URDF tree, with the chosen root joint and its mimic joints.

The URDF is rewritten as Pinocchio should see it (:func:`pinocchio_urdf`): continuous joints as
revolute joints with position limits of +-UNBOUNDED rad (one coordinate, angle not wrapped),
floating and planar joints fixed at their origin, ``<mimic>`` only where Pinocchio can honour
it. A floating or planar root is Pinocchio's free-flyer or planar joint, named
:data:`ROOT_JOINT_NAME`, between the world and the root link.
"""
from __future__ import annotations

from typing import Mapping

import pinocchio as pin
from lxml import etree

from youbot_dynamics.model.urdf import Mimic

UNBOUNDED = 1e10  # position limit handed to Pinocchio for continuous joints, rad
ROOT_JOINT_NAME = "root_joint"  # the Pinocchio joint of a floating or planar root
_ROOT_JOINT_MODELS = {"floating": pin.JointModelFreeFlyer, "planar": pin.JointModelPlanar}


def pinocchio_model(element: etree._Element, mimic: dict[str, Mimic],
                    root: str) -> tuple[pin.Model, dict[str, Mimic], list[str]]:
    """Pinocchio's model with the chosen root joint (named ROOT_JOINT_NAME) and its mimic
    joints, the relations it holds and the fidelity notes.

    Pinocchio 4.1 adds a mimic joint only after its primary in its depth-first joint order; a
    mimic joint above its primary moves independently (noted).
    """
    order = _build(pinocchio_urdf(element, {}), root, mimic=False)
    if not mimic:
        return order, {}, []
    kept = {name: m for name, m in mimic.items() if order.getJointId(m.primary) < order.getJointId(name)}
    notes = [f"joint '{name}': <mimic> of '{m.primary}' ignored (Pinocchio needs the primary "
             "before it in the tree); the joint moves independently"
             for name, m in mimic.items() if name not in kept]
    notes += [f"joint '{name}': mimics '{m.primary}' (q = {m.multiplier:g} q_{m.primary} + {m.offset:g}); "
              "no coordinate of its own, its <limit> and <dynamics> unused" for name, m in kept.items()]
    return _build(pinocchio_urdf(element, kept), root, mimic=True), kept, notes


def _build(xml: str, root: str, *, mimic: bool) -> pin.Model:
    """pin.buildModelFromXML of the URDF text with the chosen root joint."""
    if root == "fixed":
        return pin.buildModelFromXML(xml, mimic=mimic)
    return pin.buildModelFromXML(xml, _ROOT_JOINT_MODELS[root](), ROOT_JOINT_NAME, mimic=mimic)


def pinocchio_urdf(root: etree._Element, mimic: Mapping[str, Mimic]) -> str:
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
