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

The tree the node publishes (:func:`frame_tree`, REP 105) has one root and one parent per
frame. A fixed base: the root is ``frame_id`` or the robot's root link (a static root ->
root link joins them if they differ), and the free bodies and the world geometry are in the
root frame (the robot's root link is the world's origin). A moving base (simulate mode):
the root is ``frame_id`` or ``odom`` (a static root -> odom joins them: a user's
``frame_id: map`` asks for it); odom -> root link is the wheel odometry (/odom), and the
ground-truth frame ``world`` hangs under odom, odom -> world being the odometry's drift
(the world's pose in odom: T_odom_base(odometry) T_world_base(true)^-1; identity at the
start, where odometry starts at the true pose), so that the free bodies, the world geometry
and /base_pose_ground_truth, all in ``world``, stay exact relative to the robot. A
localiser's map -> odom can still be added above odom (odom keeps one parent).

The relative poses and the quaternions are computed by compiled loops that repeat
Pinocchio's arithmetic (``SE3.actInv``: R_p^T R_c and R_p^T (t_c - t_p), sums in index
order; ``SE3ToXYZQUAT``: Eigen's rotation-to-quaternion, whose trace sums r00 + (r11 + r22)),
so the rows are those of ``pin.SE3ToXYZQUAT(oMf[p].actInv(oMf[c]))`` to the bit
(test_session_outputs checks it on random configurations); what stays in Python is one
call per frame that reads its placement (the two youBots' pass: 10 us, where two Pinocchio
calls per frame took 28).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numba import njit, types

from youbot_dynamics.compiled import unchecked
from youbot_dynamics.dynamics.compiled_tree import frame_placements_of, frame_poses, tree_of, work_for
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot

ODOM_FRAME = "odom"
"""The odometry frame of a moving base (REP 105), before ``frame_prefix``."""
WORLD_FRAME = "world"
"""The ground-truth frame of a moving base's scene (free bodies, world geometry), before
``frame_prefix``."""


class FrameTree(NamedTuple):
    """The frames above the robot's links in a node's tf tree (:func:`frame_tree`), names
    prefixed: ``root`` the one root; ``base`` the robot's root link; ``world`` the frame of
    the free bodies, the world geometry and the ground truth; ``odom`` the odometry frame
    (None for a fixed base); ``static`` the latched edges (parent, child) above the robot
    and ``moving`` the per-sample ones (a moving base: odom -> base, odom -> world)."""

    root: str
    base: str
    world: str
    odom: str | None
    static: tuple[tuple[str, str], ...]
    moving: tuple[tuple[str, str], ...]


def frame_tree(root_link: str, prefix: str = "", frame_id: str = "", moving_base: bool = False,
               taken: Sequence[str] = ()) -> FrameTree:
    """The frames and parents of a node's tf tree above the robot (module docstring):
    ``root_link`` the robot's root link, ``frame_id`` the root asked for ('' : the default,
    prefixed), ``moving_base`` whether odometry moves the root link, ``taken`` the other
    frame names of the tree (the robot's links and the free bodies, prefixed). A
    ``frame_id`` or a frame of the tree that would give a frame a second parent is a
    UserInputError."""
    base = prefix + root_link
    if not moving_base:
        root = frame_id or base
        tree = FrameTree(root, base, root, None, ((root, base),) if root != base else (), ())
    else:
        odom, world = prefix + ODOM_FRAME, prefix + WORLD_FRAME
        root = frame_id or odom
        tree = FrameTree(root, base, world, odom, ((root, odom),) if root != odom else (),
                         ((odom, base), (odom, world)))
    edges = (*tree.static, *tree.moving)
    above = {frame for edge in edges for frame in edge} - {base}
    clash = sorted((above & set(taken)) | ({root} & {child for _, child in edges}))
    if clash:
        raise UserInputError(f"frames {clash} of the tf tree (root {root!r}) would have two parents (a link, a "
                             "free body or a frame of the tree): give another frame_id or rename them")
    return tree


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


@njit(cache=True)
def _quaternion_xyzw(m: np.ndarray, out: np.ndarray) -> None:
    """out (4,) = the unit quaternion (x, y, z, w), w >= 0, of the rotation m (3x3), as
    Eigen converts it (trace r00 + (r11 + r22); above 0 from w, else from the largest
    diagonal entry)."""
    t = m[0, 0] + (m[1, 1] + m[2, 2])
    if t > 0.0:
        t = math.sqrt(t + 1.0)
        out[3] = 0.5 * t
        t = 0.5 / t
        out[0] = (m[2, 1] - m[1, 2]) * t
        out[1] = (m[0, 2] - m[2, 0]) * t
        out[2] = (m[1, 0] - m[0, 1]) * t
    else:
        i = 0
        if m[1, 1] > m[0, 0]:
            i = 1
        if m[2, 2] > m[i, i]:
            i = 2
        j = (i + 1) % 3
        k = (j + 1) % 3
        t = math.sqrt(m[i, i] - m[j, j] - m[k, k] + 1.0)
        out[i] = 0.5 * t
        t = 0.5 / t
        out[3] = (m[k, j] - m[j, k]) * t
        out[j] = (m[j, i] + m[i, j]) * t
        out[k] = (m[k, i] + m[i, k]) * t
    if out[3] < 0.0:
        for i in range(4):
            out[i] = -out[i]


_POSES = types.Array(types.float64, 3, "C", readonly=True)
_ROWS = types.Array(types.float64, 2, "C")
_INDICES = types.Array(types.intp, 1, "C", readonly=True)


@njit(types.void(_POSES, _ROWS), cache=True)
def _pose_rows(poses: np.ndarray, out: np.ndarray) -> None:
    """out[e] = translation and quaternion (x, y, z, w), w >= 0, of poses[e] (4x4)."""
    for e in range(poses.shape[0]):
        out[e, 0], out[e, 1], out[e, 2] = poses[e, 0, 3], poses[e, 1, 3], poses[e, 2, 3]
        _quaternion_xyzw(poses[e, :3, :3], out[e, 3:])


@njit(types.void(_POSES, _INDICES, _INDICES, _ROWS), cache=True)
def _relative_pose_rows(poses: np.ndarray, parents: np.ndarray, children: np.ndarray, out: np.ndarray) -> None:
    """out[e] = translation and quaternion (x, y, z, w), w >= 0, of poses[children[e]] in
    the frame of poses[parents[e]] (4x4 each), with the roundings of Pinocchio's actInv."""
    rotation = np.empty((3, 3))
    for e in range(parents.shape[0]):
        p, c = poses[parents[e]], poses[children[e]]
        d0, d1, d2 = c[0, 3] - p[0, 3], c[1, 3] - p[1, 3], c[2, 3] - p[2, 3]
        for i in range(3):
            out[e, i] = p[0, i] * d0 + p[1, i] * d1 + p[2, i] * d2
            for j in range(3):
                rotation[i, j] = p[0, i] * c[0, j] + p[1, i] * c[1, j] + p[2, i] * c[2, j]
        _quaternion_xyzw(rotation, out[e, 3:])


@njit(types.void(types.Array(types.float64, 4, "C", readonly=True), _INDICES, _INDICES,
                 types.Array(types.float64, 3, "C")), cache=True)
def _relative_pose_batch(poses: np.ndarray, parents: np.ndarray, children: np.ndarray, out: np.ndarray) -> None:
    """``_relative_pose_rows`` of each sample: poses (N, frames, 4, 4) into out (N, edges, 7)."""
    for n in range(poses.shape[0]):
        _relative_pose_rows(poses[n], parents, children, out[n])


_relative_pose_batch_unchecked = unchecked(_relative_pose_batch)
"""The same without numba's type dispatch (``LinkFrames.at_many`` passes exactly its types)."""
_frame_poses_unchecked = unchecked(frame_poses)
"""compiled_tree.frame_poses without numba's type dispatch (``LinkFrames.at_many`` passes
exactly its types)."""


def pose_rows(poses: Sequence[np.ndarray]) -> np.ndarray:
    """(k, 7) rows of translation (m) and quaternion (x, y, z, w), w >= 0, of k poses (4x4, m)."""
    stacked = np.ascontiguousarray(np.reshape(poses, (-1, 4, 4)), dtype=np.float64)
    rows = np.empty((len(stacked), 7))
    _pose_rows(stacked, rows)
    return rows


@njit(types.void(types.Array(types.float64, 2, "C", readonly=True), types.Array(types.float64, 3, "C")),
      cache=True)
def _pose_matrices(rows: np.ndarray, out: np.ndarray) -> None:
    """out[e] = the pose (4x4) of rows[e] (translation, quaternion (x, y, z, w), normalised
    here), with the roundings of :func:`~youbot_dynamics.model.lie.matrix_from_quaternion`."""
    for e in range(rows.shape[0]):
        x, y, z, w = rows[e, 3], rows[e, 4], rows[e, 5], rows[e, 6]
        norm = math.sqrt(x * x + y * y + z * z + w * w)
        x, y, z, w = x / norm, y / norm, z / norm, w / norm
        m = out[e]
        m[0, 0], m[0, 1], m[0, 2] = 1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)
        m[1, 0], m[1, 1], m[1, 2] = 2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)
        m[2, 0], m[2, 1], m[2, 2] = 2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)
        m[0, 3], m[1, 3], m[2, 3] = rows[e, 0], rows[e, 1], rows[e, 2]
        m[3, 0], m[3, 1], m[3, 2], m[3, 3] = 0.0, 0.0, 0.0, 1.0


def pose_matrices(rows: np.ndarray) -> np.ndarray:
    """(..., 4, 4) poses (m) of rows (..., 7) of translation (m) and quaternion (x, y, z, w)."""
    rows = np.asarray(rows, dtype=float)
    flat = np.ascontiguousarray(rows.reshape(-1, 7))
    matrices = np.empty((len(flat), 4, 4))
    _pose_matrices(flat, matrices)
    return matrices.reshape(*rows.shape[:-1], 4, 4)


def composed_rows(first: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Rows (k, 7) of ``first`` (one row: the pose of frame B in A) composed with ``rows``
    (k, 7: poses in B): the poses in A."""
    return pose_rows(pose_matrices(first) @ pose_matrices(rows))


class FramesBatch(Sequence[SampleFrames]):
    """The kinematics of :meth:`LinkFrames.at_many` as one array, ``poses`` (N, moving + end
    effectors, 7): each sample's ``link_poses`` then its ``ee`` (rows of translation m and
    quaternion (x, y, z, w) in the frames of :class:`SampleFrames`); ``moving`` the number of
    moving links. Item k is sample k's :class:`SampleFrames` (views of its rows), made only
    when asked for."""

    def __init__(self, poses: np.ndarray, edges: tuple[tuple[str, str], ...], ee_count: int, ee_index: int) -> None:
        self.poses, self.moving, self.edges, self.ee_count, self.ee_index = poses, len(edges), edges, ee_count, \
            ee_index

    def __len__(self) -> int:
        return len(self.poses)

    def __getitem__(self, k: int | slice) -> SampleFrames | FramesBatch:
        """Sample k's :class:`SampleFrames`, or for a slice the batch of those samples."""
        if isinstance(k, slice):
            return FramesBatch(self.poses[k], self.edges, self.ee_count, self.ee_index)
        rows = self.poses[k]
        return SampleFrames(self.edges, rows[:self.moving], rows[self.moving:], self.ee_count, self.ee_index)


def ee_rows(samples: FramesBatch, base: np.ndarray | None = None) -> np.ndarray:
    """(N, k, 7) the ``ee`` rows of N samples in the root frame, or with ``base`` (N, 2, 7;
    a moving base's odom -> base_footprint first) composed with the odometry pose (each
    sample's product as :func:`composed_rows` forms it, all samples in one call)."""
    ee = samples.poses[:, samples.moving:]
    if base is None:
        return ee
    odometry = pose_matrices(np.asarray(base)[:, 0])[:, None]
    return pose_rows(odometry @ pose_matrices(ee)).reshape(ee.shape)


def end_effector_row(sample: SampleFrames, base: np.ndarray | None = None) -> np.ndarray:
    """The row (7,) of the sample's end effector (``ee_index``) in the root frame, or with
    ``base`` (2, 7; a moving base's odom -> base_footprint first) in odom."""
    row = sample.ee[sample.ee_index]
    return row if base is None else composed_rows(base[0], row[None])[0]


def planar_row(x: float, y: float, yaw: float) -> np.ndarray:
    """The row (7,) of a planar pose: translation (x, y, 0) m and the quaternion of ``yaw``
    (rad) about z."""
    return np.array([x, y, 0.0, 0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw)])


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
        pairs = [*((robot.frame_id(j.parent), robot.frame_id(j.child)) for j in moving),
                 *((self._root, e) for e in self._ee)]
        frames = sorted({frame for pair in pairs for frame in pair})
        self._frames = tuple(frames)
        self._parents = np.array([frames.index(p) for p, _ in pairs], dtype=np.intp)
        self._children = np.array([frames.index(c) for _, c in pairs], dtype=np.intp)
        self._tree = tree_of(robot.model)
        """The compiled kinematics of :meth:`at_many` (None where the model has no compiled form)."""
        if self._tree is not None:
            self._placements = frame_placements_of(robot.model, self._frames)
            self._work = work_for(self._tree[0])

    def at(self, q: np.ndarray) -> SampleFrames:
        """The frames at joint positions q (the robot's configuration, Pinocchio order)."""
        pin.framesForwardKinematics(self.robot.model, self._data, np.asarray(q, dtype=float))
        placements = self._data.oMf.tolist()
        placements = np.array([placements[frame].np for frame in self._frames])
        poses = np.empty((len(self._parents), 7))
        _relative_pose_rows(placements, self._parents, self._children, poses)
        moving = len(self._edges)
        return SampleFrames(self._edges, poses[:moving], poses[moving:], len(self.ee_links), self._ee_index)

    def at_many(self, q: np.ndarray) -> FramesBatch:
        """``at`` of every row of q (N, nq): one compiled kinematics pass for them all
        (compiled_tree.frame_poses: Pinocchio's products in its order, so the same numbers)
        where the model has a compiled form, else row by row."""
        if self._tree is None:
            poses = np.array([np.vstack((sample.link_poses, sample.ee)) for sample in map(self.at, q)])
            poses = poses.reshape(len(q), len(self._parents), 7)
        else:
            q = np.ascontiguousarray(q, dtype=float)
            if q.ndim != 2 or q.shape[1] != self.robot.nq:      # the compiled loops read it unchecked
                raise UserInputError(f"at_many: q needs shape (N, nq = {self.robot.nq}); got {q.shape}")
            placements = np.empty((len(q), len(self._frames), 4, 4))
            _frame_poses_unchecked(*self._tree, q, *self._placements, self._work, placements)
            poses = np.empty((len(q), len(self._parents), 7))
            _relative_pose_batch_unchecked(placements, self._parents, self._children, poses)
        return FramesBatch(poses, self._edges, len(self.ee_links), self._ee_index)
