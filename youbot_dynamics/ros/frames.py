"""Frames a running simulation reports: the pose of every link relative to its parent (for
/tf and /tf_static), the end-effector pose from the screw-axis kinematics (for /ee_pose) and
the pose of every free body in the world frame (for /tf and /free_bodies).

Each URDF joint of the Robot's tree is an edge parent -> child. A fixed joint (locked ones
included, with their value folded into the origin) gives a constant transform (/tf_static);
a moving joint gives origin @ motion(q): a rotation of q (rad) about the joint axis for
revolute and continuous joints, a translation of q (m) along it for prismatic joints
(computed on quaternions: this runs for every link at every published sample).
Poses are 4x4 homogeneous matrices (m); quaternions are (x, y, z, w).
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from youbot_dynamics.model.lie import quaternion_from_matrix
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.model.screws import fkin_space, screw_chain


class LinkTransform(NamedTuple):
    """Pose of ``child`` in ``parent``: translation (3,) m and quaternion (x, y, z, w)."""

    parent: str
    child: str
    translation: np.ndarray
    quaternion_xyzw: np.ndarray


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a b of quaternions (x, y, z, w): the rotation b, then a."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


def _link_transform(parent: str, child: str, transform: np.ndarray) -> LinkTransform:
    return LinkTransform(parent, child, transform[:3, 3].copy(), quaternion_from_matrix(transform[:3, :3]))


def body_transforms(world_frame: str, poses: Mapping[str, np.ndarray]) -> list[LinkTransform]:
    """``world_frame`` -> body transforms of free bodies from their world poses (4x4, m) by
    body name, in the mapping's order; the child frame is the body's name."""
    return [_link_transform(world_frame, name, pose) for name, pose in poses.items()]


class LinkFrames:
    """Parent -> child transforms of every link of ``robot``, the pose of ``ee_link``
    (default: the first of ``robot.end_effectors``, the robot's end effector or, for
    several robots composed into one model, the first robot's) and the poses of every
    robot's end effector (``ee_links``), all in the root link's frame."""

    def __init__(self, robot: Robot, ee_link: str | None = None) -> None:
        self.robot = robot
        self.root_link = robot.root_link
        self.ee_links = robot.end_effectors
        self.chain = screw_chain(robot, ee_link or self.ee_links[0])
        self.ee_link = self.chain.link
        self._ee_chains = tuple(self.chain if link == self.ee_link else screw_chain(robot, link)
                                for link in self.ee_links)
        self.static = tuple(_link_transform(j.parent, j.child, j.origin) for j in robot.tree if j.type == "fixed")
        self._moving = tuple((j, robot.joint_index(j.name), quaternion_from_matrix(j.origin[:3, :3]))
                             for j in robot.tree if j.type != "fixed")

    def moving(self, q: np.ndarray) -> list[LinkTransform]:
        """Transforms across the moving joints at joint positions q (joint order).

        Revolute: the child origin stays at the joint origin and the rotation is the
        origin's quaternion times (axis sin(q/2), cos(q/2)); prismatic: the child moves by
        q along the axis (rotated into the parent frame) and keeps the origin's rotation."""
        out = []
        for joint, index, origin_xyzw in self._moving:
            value = float(q[index])
            if joint.type == "prismatic":
                translation = joint.origin[:3, 3] + joint.origin[:3, :3] @ (joint.axis * value)
                out.append(LinkTransform(joint.parent, joint.child, translation, origin_xyzw))
            else:
                half = 0.5 * value
                turn = np.array([*(joint.axis * math.sin(half)), math.cos(half)])
                out.append(LinkTransform(joint.parent, joint.child, joint.origin[:3, 3],
                                         quaternion_product(origin_xyzw, turn)))
        return out

    def ee_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position (3,) m and quaternion (x, y, z, w) of ``ee_link`` in the root link frame."""
        return _position_quaternion(fkin_space(self.chain, q))

    def ee_poses(self, q: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """``ee_pose`` of every link of ``ee_links``, in that order."""
        return [_position_quaternion(fkin_space(chain, q)) for chain in self._ee_chains]


def _position_quaternion(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return pose[:3, 3].copy(), quaternion_from_matrix(pose[:3, :3])
