"""The URDF side of identification: the links that make up each identified body, and the
URDF with identified parameters written in.

A Pinocchio body is the joint's child link plus every link welded to it (and, with joints
locked, their links too), in the joint frame, which is the child link's frame.
:func:`body_links` lists those links with their placement in the body frame and their URDF
inertial (the prior of :func:`~youbot_dynamics.identification.consistency.consistent_fit`,
which fits every link on its own). :func:`identified_urdf` writes the source file with each
fitted link's ``<inertial>`` replaced (centre of mass as origin, rpy 0, the inertia about
the centre of mass in the link frame) and each identified joint's ``<dynamics damping
friction>``, and a header comment. A constant torque offset has no URDF field and is listed
in the header only.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
from lxml import etree

from youbot_dynamics.identification.consistency import BodyLink, ConsistentFit
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


def body_links(source: str | Path, layout: RegressorLayout) -> tuple[BodyLink, ...]:
    """The links of every moving body of ``layout`` (the URDF at ``source``, a path or the
    text), in Pinocchio's frame order, with their URDF inertials; links without mass carry
    nothing and are left out."""
    root = etree.fromstring(Path(source).read_bytes()) if not str(source).lstrip().startswith("<") \
        else etree.fromstring(str(source).encode())
    model, links = layout.robot.model, []
    for frame in model.frames:
        if frame.type != pin.FrameType.BODY or frame.parentJoint == 0:
            continue
        element = root.find(f"link[@name='{frame.name}']")
        inertia = _link_inertia(element.find("inertial") if element is not None else None)
        if inertia.mass > 0.0:
            links.append(BodyLink(frame.name, frame.parentJoint - 1, frame.placement.homogeneous, inertia))
    return tuple(links)


def identified_urdf(source: str | Path, layout: RegressorLayout, fit: ConsistentFit, header: str) -> str:
    """The URDF at ``source`` with the fit's link inertials and joint friction written in (see
    the module docstring) and ``header`` as a comment before the first element."""
    tree = etree.parse(str(source))
    root = tree.getroot()
    for name, inertia in fit.inertias.items():
        _write_inertial(root.find(f"link[@name='{name}']"), inertia)
    named = dict(zip(layout.names, fit.theta))
    for joint_name in layout.robot.joint_names:
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
