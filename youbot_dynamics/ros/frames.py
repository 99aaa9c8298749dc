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

from collections.abc import Sequence
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
    """One sample's kinematics as arrays of poses, each row a translation (3,) m and a
    quaternion (x, y, z, w), w >= 0: ``link_poses`` (k, 7), child in parent across every
    moving joint (URDF tree order, ``edges`` names them (parent, child)); ``ee`` the links of
    ``LinkFrames.ee_links`` in the root link's frame, in that order, then ``ee_link`` if it
    is not among them; ``ee_index`` the row of ``ee_link``. ``moving``, ``ee_poses`` and
    ``ee_pose`` give the same as (translation, quaternion) pairs."""

    edges: tuple[tuple[str, str], ...]
    link_poses: np.ndarray
    ee: np.ndarray
    ee_count: int
    ee_index: int

    @property
    def moving(self) -> tuple[LinkTransform, ...]:
        """parent -> child across every moving joint, URDF tree order."""
        return tuple(LinkTransform(parent, child, pose[:3], pose[3:])
                     for (parent, child), pose in zip(self.edges, self.link_poses))

    @property
    def ee_poses(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """(position, quaternion) of every link of ``LinkFrames.ee_links``, in that order."""
        return tuple((pose[:3], pose[3:]) for pose in self.ee[:self.ee_count])

    @property
    def ee_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """(position, quaternion) of ``LinkFrames.ee_link``."""
        pose = self.ee[self.ee_index]
        return pose[:3], pose[3:]


def pose_rows(poses: Sequence[np.ndarray]) -> np.ndarray:
    """(k, 7) rows of translation (m) and quaternion (x, y, z, w), w >= 0, of k poses (4x4, m)."""
    rows = np.array([pin.SE3ToXYZQUAT(pin.SE3(pose)) for pose in poses]).reshape(-1, 7)
    rows[rows[:, 6] < 0.0, 3:] *= -1.0
    return rows


def _link_transform(parent: str, child: str, transform: np.ndarray) -> LinkTransform:
    """``transform`` (4x4, m) as the pose of ``child`` in ``parent``."""
    row = pose_rows([transform])[0]
    return LinkTransform(parent, child, row[:3], row[3:])


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
        moving = [j for j in robot.tree if j.type != "fixed"]
        self._edges = tuple((j.parent, j.child) for j in moving)
        self._moving_ids = tuple((robot.frame_id(j.parent), robot.frame_id(j.child)) for j in moving)

    def at(self, q: np.ndarray) -> SampleFrames:
        """The frames at joint positions q (the robot's configuration, Pinocchio order)."""
        pin.framesForwardKinematics(self.robot.model, self._data, np.asarray(q, dtype=float))
        placements = self._data.oMf
        root = placements[self._root]
        poses = np.array([*(pin.SE3ToXYZQUAT(placements[p].actInv(placements[c])) for p, c in self._moving_ids),
                          *(pin.SE3ToXYZQUAT(root.actInv(placements[e])) for e in self._ee)])
        poses[poses[:, 6] < 0.0, 3:] *= -1.0
        moving = len(self._moving_ids)
        return SampleFrames(self._edges, poses[:moving], poses[moving:], len(self.ee_links), self._ee_index)
