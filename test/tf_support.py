"""tf as tf2's BufferCore reads it, for the tests: the tree of /tf_static and the /tf of one
stamp (:class:`Tree`: one root, one parent per frame, poses composed along it) and poses of
geometry_msgs compared to 1e-9 m and rad."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

TOLERANCE = 1e-9
"""m and rad."""


def matrix_of(translation, rotation) -> np.ndarray:
    """A 4x4 pose from geometry_msgs' Vector3/Point and Quaternion."""
    matrix = np.eye(4)
    matrix[:3, :3] = Rotation.from_quat([rotation.x, rotation.y, rotation.z, rotation.w]).as_matrix()
    matrix[:3, 3] = translation.x, translation.y, translation.z
    return matrix


def pose_of(pose) -> np.ndarray:
    return matrix_of(pose.position, pose.orientation)


def stamp_of(header) -> int:
    return header.stamp.sec * 10**9 + header.stamp.nanosec


class Tree:
    """tf2 BufferCore's view at one stamp: the static transforms and the dynamic ones of
    that stamp, each child with its parent; ``pose(target, source)`` is source in target."""

    def __init__(self, static, dynamic, stamp_ns: int) -> None:
        self.parents: dict[str, list[tuple[str, np.ndarray]]] = {}
        for transform in (*static.transforms, *dynamic.transforms):
            if transform in dynamic.transforms:
                assert stamp_of(transform.header) == stamp_ns, transform.child_frame_id
            self.parents.setdefault(transform.child_frame_id, []).append(
                (transform.header.frame_id, matrix_of(transform.transform.translation, transform.transform.rotation)))
        frames = set(self.parents) | {parent for edges in self.parents.values() for parent, _ in edges}
        self.roots = sorted(frames - set(self.parents))
        self.frames = frames

    def check(self) -> None:
        twice = {child: [p for p, _ in edges] for child, edges in self.parents.items() if len(edges) > 1}
        assert not twice, f"frames with several parents: {twice}"
        assert len(self.roots) == 1, f"roots {self.roots}"

    def in_root(self, frame: str) -> np.ndarray:
        assert frame in self.frames, f"{frame} is not in the tree"
        pose, seen = np.eye(4), set()
        while frame != self.roots[0]:
            assert frame not in seen, f"cycle through {frame}"
            seen.add(frame)
            parent, transform = self.parents[frame][0]
            pose, frame = transform @ pose, parent
        return pose

    def pose(self, target: str, source: str) -> np.ndarray:
        return np.linalg.solve(self.in_root(target), self.in_root(source))


def pose_error(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(m, rad) between two poses."""
    return (float(np.linalg.norm(a[:3, 3] - b[:3, 3])),
            float(Rotation.from_matrix(a[:3, :3].T @ b[:3, :3]).magnitude()))


def assert_same(a: np.ndarray, b: np.ndarray, what: str) -> None:
    metres, radians = pose_error(a, b)
    assert metres <= TOLERANCE and radians <= TOLERANCE, f"{what}: {metres:.3g} m, {radians:.3g} rad"
