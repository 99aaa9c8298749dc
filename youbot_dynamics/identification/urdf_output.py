"""A URDF with identified parameters: the source file with each identified body's inertial
and each identified joint's ``<dynamics damping friction>`` replaced, and a header comment.

A Pinocchio body is the joint's child link plus every link welded to it (and, with joints
locked, their links too), expressed in the joint frame, which is the child link's frame. The
identified body differs from the URDF's by delta (ten dynamic parameters, linear); that
delta goes onto the child link's own inertial, so the welded links keep theirs and the
reloaded robot has exactly the identified bodies. The link's ``<inertial>`` is rewritten
with its centre of mass as origin, rpy 0, and the inertia about the centre of mass in the
link frame. Viscous and Coulomb coefficients become damping and friction; a constant
offset has no URDF field and is listed in the header only.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
from lxml import etree

from youbot_dynamics.identification.regressor import RegressorLayout


def _link_inertia(inertial: etree._Element | None) -> pin.Inertia:
    """A link's URDF inertial as a Pinocchio Inertia in the link frame (zero if absent)."""
    if inertial is None:
        return pin.Inertia.Zero()
    origin = inertial.find("origin")
    xyz = np.array((origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split(), float)
    rpy = np.array((origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split(), float)
    element = inertial.find("inertia")
    ixx, ixy, ixz, iyy, iyz, izz = (float(element.get(k, 0.0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"))
    rotation = pin.rpy.rpyToMatrix(rpy)
    central = rotation @ np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]) @ rotation.T
    return pin.Inertia(float(inertial.find("mass").get("value")), xyz, central)


def _write_inertial(link: etree._Element, inertia: pin.Inertia) -> None:
    inertial = link.find("inertial")
    if inertial is None:
        inertial = etree.SubElement(link, "inertial")
    inertial.clear()
    text = " ".join(f"{x:.12g}" for x in inertia.lever)
    etree.SubElement(inertial, "origin", xyz=text, rpy="0 0 0")
    etree.SubElement(inertial, "mass", value=f"{inertia.mass:.12g}")
    i = inertia.inertia
    etree.SubElement(inertial, "inertia", **{key: f"{i[a, b]:.12g}" for key, (a, b) in
                                             {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1),
                                              "iyz": (1, 2), "izz": (2, 2)}.items()})


def identified_urdf(source: str | Path, layout: RegressorLayout, theta: np.ndarray, header: str) -> str:
    """The URDF at ``source`` with the standard parameters ``theta`` (layout's order) written
    in (see the module docstring) and ``header`` as a comment before the first element."""
    tree = etree.parse(str(source))
    root = tree.getroot()
    robot = layout.robot
    children = {joint.name: joint.child for joint in robot.tree}
    for i, body in enumerate(layout.body_names):
        nominal = robot.model.inertias[i + 1].toDynamicParameters()
        link = root.find(f"link[@name='{children[body]}']")
        own = _link_inertia(link.find("inertial")).toDynamicParameters()
        _write_inertial(link, pin.Inertia.FromDynamicParameters(own + theta[10 * i:10 * i + 10] - nominal))
    named = dict(zip(layout.names, theta))
    for joint_name in robot.joint_names:
        joint = root.find(f"joint[@name='{joint_name}']")
        dynamics = joint.find("dynamics")
        if dynamics is None:
            dynamics = etree.SubElement(joint, "dynamics")
        for term, attribute in (("viscous", "damping"), ("coulomb", "friction")):
            if f"{joint_name}.{term}" in named:
                dynamics.set(attribute, f"{named[f'{joint_name}.{term}']:.12g}")
    comment = etree.Comment(" " + header.replace("--", "- -") + " ")
    comment.tail = "\n  "
    root.insert(0, comment)
    return etree.tostring(tree, encoding="unicode")
