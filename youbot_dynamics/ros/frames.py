"""Frames a running simulation reports, from one forward-kinematics pass per sample: the
pose of every moving link relative to its parent link (/tf), every end effector's pose in
the root link's frame (/ee_pose, /ee_poses), plus the constant transforms across fixed
joints (/tf_static) and the free bodies' poses in the world frame (/tf, /free_bodies).

Each URDF joint of the Robot's tree is an edge parent -> child. A fixed joint (locked ones
included, with their value folded into the origin) gives a constant transform, taken once
from the URDF tree. The moving ones come from Pinocchio (``framesForwardKinematics``, the
robot's model: mimic joints follow their primaries): parent -> child is
oMf[parent]^-1 oMf[child]. The screw-axis kinematics of ``model/screws.py`` are independent
of this pass, and the tests hold it to them. Poses are 4x4 homogeneous matrices (m);
quaternions are (x, y, z, w) with w >= 0.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from youbot_dynamics.model.robot import Robot


class LinkTransform(NamedTuple):
    """Pose of ``child`` in ``parent``: translation (3,) m and quaternion (x, y, z, w)."""

    parent: str
    child: str
    translation: np.ndarray
    quaternion_xyzw: np.ndarray


class SampleFrames(NamedTuple):
    """One sample's kinematics: ``moving`` (parent -> child across every moving joint, URDF
    tree order), ``ee_poses`` (position (3,) m and quaternion (x, y, z, w) of every link of
    ``LinkFrames.ee_links`` in the root link's frame, in that order) and ``ee_pose`` (the
    same for ``LinkFrames.ee_link``)."""

    moving: tuple[LinkTransform, ...]
    ee_poses: tuple[tuple[np.ndarray, np.ndarray], ...]
    ee_pose: tuple[np.ndarray, np.ndarray]


def _position_quaternion(placement: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    """Translation (3,) m and quaternion (x, y, z, w), w >= 0, of ``placement``."""
    xyz_quaternion = pin.SE3ToXYZQUAT(placement)
    quaternion = xyz_quaternion[3:]
    return xyz_quaternion[:3], -quaternion if quaternion[3] < 0.0 else quaternion


def _link_transform(parent: str, child: str, transform: np.ndarray) -> LinkTransform:
    """``transform`` (4x4, m) as the pose of ``child`` in ``parent``."""
    return LinkTransform(parent, child, *_position_quaternion(pin.SE3(transform)))


def body_transforms(world_frame: str, poses: Mapping[str, np.ndarray]) -> list[LinkTransform]:
    """``world_frame`` -> body transforms of free bodies from their world poses (4x4, m) by
    body name, in the mapping's order; the child frame is the body's name."""
    return [_link_transform(world_frame, name, pose) for name, pose in poses.items()]


class LinkFrames:
    """Parent -> child transforms of every link of ``robot``, the pose of ``ee_link``
    (default: the first of ``robot.end_effectors``, the robot's end effector or, for
    several robots composed into one model, the first robot's) and the poses of every
    robot's end effector (``ee_links``), all in the root link's frame. ``at(q)`` runs the
    one kinematics pass of a sample (its own Pinocchio Data). An unknown ``ee_link`` is a
    UserInputError listing the links."""

    def __init__(self, robot: Robot, ee_link: str | None = None) -> None:
        self.robot = robot
        self.root_link = robot.root_link
        self.ee_links = robot.end_effectors
        self.ee_link = ee_link or self.ee_links[0]
        self._data = robot.model.createData()
        self._root = robot.frame_id(self.root_link)
        links = self.ee_links if self.ee_link in self.ee_links else (*self.ee_links, self.ee_link)
        self._ee = tuple(robot.frame_id(link) for link in links)
        self._ee_index = links.index(self.ee_link)
        self.static = tuple(_link_transform(j.parent, j.child, j.origin) for j in robot.tree if j.type == "fixed")
        self._moving = tuple((j.parent, j.child, robot.frame_id(j.parent), robot.frame_id(j.child))
                             for j in robot.tree if j.type != "fixed")

    def at(self, q: np.ndarray) -> SampleFrames:
        """The frames at joint positions q (the robot's configuration, Pinocchio order)."""
        pin.framesForwardKinematics(self.robot.model, self._data, np.asarray(q, dtype=float))
        placements = self._data.oMf
        moving = tuple(LinkTransform(parent, child, *_position_quaternion(placements[p].actInv(placements[c])))
                       for parent, child, p, c in self._moving)
        root = placements[self._root]
        poses = tuple(_position_quaternion(root.actInv(placements[e])) for e in self._ee)
        return SampleFrames(moving, poses[:len(self.ee_links)], poses[self._ee_index])
