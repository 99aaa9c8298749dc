"""Building the robot a scene simulates: several URDFs composed into one (every link and
joint name prefixed, each robot's root link welded to a common ``world`` link at its pose,
link inertials corrected), the empty robot, and another gravity on a model copy.

A robot on a moving base is not welded: its root link (base_footprint) is the composed
robot's root, which the base's planar joint moves and odometry places under ``odom``; a
``world`` link welded to it would be a second parent of base_footprint on /tf (and in
robot_state_publisher's tree of /robot_description). So such a composition holds one robot
at the identity pose (the base's initial pose places it).

Plain data in, URDF text or a :class:`~youbot_dynamics.model.robot.Robot` out; the scene
validator (scene/contacts.py) reads the scene's ``robot: {compose: [...]}`` into
:class:`Placement` values and turns a :class:`CompositionError` into an error naming the
scene's key.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin
from lxml import etree

from youbot_dynamics.errors import URDFError, UserInputError
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.model.urdf import parse_urdf, read_source

#: The URDF of a scene without a robot (``robot: none``): one link, no joint.
EMPTY_ROBOT = '<robot name="none"><link name="world"/></robot>'


@dataclass(frozen=True)
class InertialCorrection:
    """A link's new mass (kg) and/or principal moments of inertia (kg m^2, about the file's
    inertial origin and axes; the products become 0). None keeps the file's value."""

    mass: float | None = None
    moments: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class Placement:
    """One robot of a composition: its URDF file, the prefix of its link and joint names,
    the world pose of its root link (4x4 homogeneous, m) and inertial corrections by the
    file's link names."""

    urdf: Path
    prefix: str = ""
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))
    inertials: Mapping[str, InertialCorrection] = field(default_factory=dict)


class CompositionError(UserInputError):
    """A placement that cannot be composed: ``index`` of the placement, ``part`` (``urdf``
    or ``inertials.<link>``) and the problem."""

    def __init__(self, index: int, part: str, problem: str) -> None:
        self.index, self.part, self.problem = index, part, problem
        super().__init__(f"placement {index}: {part}: {problem}")


def composed_urdf(placements: Sequence[Placement], welded: bool = True) -> str:
    """One URDF (text) from several: every link and joint name prefixed, each robot's root
    link fixed to a common ``world`` link at its pose by a joint ``<prefix>world_joint``;
    ``welded`` False (a moving base): one robot at the identity pose, its own root link the
    root (no ``world`` link), else a CompositionError."""
    if not welded:
        _check_unwelded(placements)
    world = etree.Element("robot", name="composed")
    if welded:
        etree.SubElement(world, "link", name="world")
    for index, placement in enumerate(placements):
        text, label = _read(placement, index)
        try:
            root, _ = parse_urdf(text, label)  # as load_robot reads it: what urdfdom forgives, forgiven
        except URDFError as error:
            raise CompositionError(index, "urdf", f"{placement.urdf} is not valid XML: {error}") from None
        corrected_inertials(root, placement.inertials, index)
        prefix = placement.prefix
        children = {j.find("child").get("link") for j in root.findall("joint")}
        base = next(link.get("name") for link in root.findall("link") if link.get("name") not in children)
        for element in list(root):
            if element.tag in ("link", "joint"):
                element.set("name", prefix + element.get("name"))
                for role in ("parent", "child"):
                    link = element.find(role)
                    if link is not None:
                        link.set("link", prefix + link.get("link"))
                world.append(element)
        if not welded:
            continue
        joint = etree.SubElement(world, "joint", name=f"{prefix}world_joint", type="fixed")
        etree.SubElement(joint, "parent", link="world")
        etree.SubElement(joint, "child", link=prefix + base)
        pose = np.asarray(placement.pose, dtype=float)
        rpy = pin.rpy.matrixToRpy(pose[:3, :3])
        etree.SubElement(joint, "origin", xyz=" ".join(repr(float(x)) for x in pose[:3, 3]),
                         rpy=" ".join(repr(float(x)) for x in rpy))
    return etree.tostring(world, encoding="unicode")


def _check_unwelded(placements: Sequence[Placement]) -> None:
    """A composition a moving base carries: one robot, at the identity pose."""
    if len(placements) != 1:
        raise CompositionError(1, "urdf", "a moving base carries one robot: compose one URDF (or fix the base)")
    if not np.array_equal(np.asarray(placements[0].pose, dtype=float), np.eye(4)):
        raise CompositionError(0, "pose", "a moving base's robot is placed by base.initial.pose: give no pose "
                               "(or the identity)")


def _read(placement: Placement, index: int) -> tuple[str | bytes, str]:
    """The placement's URDF file as bytes, and its label; a missing or oversized file is a
    CompositionError of the placement's ``urdf``."""
    try:
        return read_source(Path(placement.urdf))
    except URDFError as error:
        raise CompositionError(index, "urdf", str(error)) from None


def corrected_inertials(root: etree._Element, corrections: Mapping[str, InertialCorrection],
                        index: int = 0) -> None:
    """Replace, in the URDF tree ``root``, the mass and/or the inertia (principal moments,
    products set to 0) of the named links; ``index`` names the placement in errors."""
    links = {link.get("name"): link for link in root.findall("link")}
    for name, correction in corrections.items():
        inertial = links[name].find("inertial") if name in links else None
        if inertial is None:
            raise CompositionError(index, f"inertials.{name}", "not a link with an <inertial> in the URDF")
        if correction.mass is not None:
            inertial.find("mass").set("value", repr(float(correction.mass)))
        if correction.moments is not None:
            values = dict(zip(("ixx", "iyy", "izz"), correction.moments), ixy=0.0, ixz=0.0, iyz=0.0)
            for attribute, number in values.items():
                inertial.find("inertia").set(attribute, repr(float(number)))


def robot_with_gravity(robot: Robot, gravity: np.ndarray) -> Robot:
    """The same Robot with another gravity vector (m/s^2, root frame) on a model copy."""
    gravity = np.asarray(gravity, dtype=float)
    if np.array_equal(robot.model.gravity.linear, gravity):
        return robot
    model = pin.Model(robot.model)
    model.gravity = pin.Motion(gravity, np.zeros(3))
    return dataclasses.replace(robot, model=model)
