"""Collision geometry and queries through coal (no hand-written GJK/EPA).

A :class:`Shape` is a primitive in its owner's frame (metres): ``sphere`` (radius),
``box`` (size: full edge lengths x, y, z), ``cylinder`` and ``capsule`` (radius, length
along the local z axis; the capsule's length excludes its caps), ``halfspace`` (unit normal
and offset d: the solid is n . x <= d). A :class:`Geometry` places a shape on an owner: the
``world``, a free ``body`` or a robot ``link``, with a 4x4 placement in the owner's frame.

:func:`contact_points` returns the contact points of two placed shapes (world frame): the
closest pair of points when they are apart (signed distance > 0, within ``margin``), and,
when they overlap, coal's contact patch (several points for a face on a face, one point
otherwise). Every point carries the witness points on both shapes, the unit normal from
shape 1 to shape 2 and the depth (m, > 0 for overlap).

:class:`BroadPhase` keeps the declared pairs and hands to the narrow phase only those whose
world axis-aligned bounding boxes, inflated by the margin, overlap: the narrow-phase cost
grows with the pairs that are close.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import coal
import numpy as np

from youbot_dynamics.errors import UserInputError

SHAPES = {"sphere": ("radius",), "box": ("size",), "cylinder": ("radius", "length"),
          "capsule": ("radius", "length"), "halfspace": ("normal", "offset")}
OWNERS = ("world", "body", "link")
#: Shapes whose overlap with a flat face can be a patch of several points.
FLAT = ("box", "cylinder", "halfspace")


@dataclass(frozen=True)
class Shape:
    """A primitive: ``kind`` (see SHAPES) and its dimensions (m)."""

    kind: str
    radius: float = 0.0
    length: float = 0.0
    size: tuple[float, float, float] = (0.0, 0.0, 0.0)
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    offset: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in SHAPES:
            raise UserInputError(f"unknown shape kind {self.kind!r}; known: {', '.join(SHAPES)}")

    def coal_geometry(self) -> coal.CollisionGeometry:
        """The coal shape."""
        if self.kind == "sphere":
            return coal.Sphere(self.radius)
        if self.kind == "box":
            return coal.Box(*self.size)
        if self.kind == "cylinder":
            return coal.Cylinder(self.radius, self.length)
        if self.kind == "capsule":
            return coal.Capsule(self.radius, self.length)
        normal = np.asarray(self.normal, dtype=float)
        return coal.Halfspace(normal / np.linalg.norm(normal), self.offset)


@dataclass(frozen=True)
class Geometry:
    """A named shape on an owner (``world``, ``body`` or ``link`` named ``owner_name``),
    placed by the 4x4 ``placement`` in the owner's frame."""

    name: str
    shape: Shape
    owner: str
    owner_name: str
    placement: np.ndarray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self) -> None:
        if self.owner not in OWNERS:
            raise UserInputError(f"geometry {self.name!r}: unknown owner kind {self.owner!r}; "
                                 f"known: {', '.join(OWNERS)}")


@dataclass(frozen=True)
class ContactPoint:
    """World-frame witness points on shape 1 and 2 (m), unit normal from 1 to 2, depth (m,
    > 0 when overlapping, -distance otherwise)."""

    point1: np.ndarray
    point2: np.ndarray
    normal: np.ndarray
    depth: float


def transform(pose: np.ndarray) -> coal.Transform3s:
    """A coal transform from a 4x4 homogeneous pose."""
    return coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))


class PlacedPair:
    """The narrow phase of one declared pair: coal shapes and reusable requests."""

    def __init__(self, shape1: Shape, shape2: Shape) -> None:
        self.geometry1, self.geometry2 = shape1.coal_geometry(), shape2.coal_geometry()
        self.distance_request = coal.DistanceRequest()
        self.distance_request.enable_signed_distance = True
        self.collision_request = coal.CollisionRequest()
        self.patch_request = coal.ContactPatchRequest()
        self.patches = shape1.kind in FLAT and shape2.kind in FLAT

    def signed_distance(self, pose1: np.ndarray, pose2: np.ndarray) -> float:
        """Signed distance (m, < 0 when overlapping)."""
        result = coal.DistanceResult()
        return coal.distance(self.geometry1, transform(pose1), self.geometry2, transform(pose2),
                             self.distance_request, result)

    def contact_points(self, pose1: np.ndarray, pose2: np.ndarray, margin: float) -> list[ContactPoint]:
        """Contact points of the pair at the given world poses (see module docstring)."""
        t1, t2 = transform(pose1), transform(pose2)
        result = coal.DistanceResult()
        distance = coal.distance(self.geometry1, t1, self.geometry2, t2, self.distance_request, result)
        if distance > margin:
            return []
        p1, p2 = result.getNearestPoint1().copy(), result.getNearestPoint2().copy()
        normal = np.array(result.normal, dtype=float)
        if distance > 0.0 or not self.patches:
            return [ContactPoint(p1, p2, normal, -float(distance))]
        collision = coal.CollisionResult()
        coal.collide(self.geometry1, t1, self.geometry2, t2, self.collision_request, collision)
        if not collision.isCollision():
            return [ContactPoint(p1, p2, normal, -float(distance))]
        patches = coal.ContactPatchResult(self.patch_request)
        coal.computeContactPatch(self.geometry1, t1, self.geometry2, t2, collision, self.patch_request, patches)
        patch = patches.getContactPatch(0)
        normal = np.array(patch.getNormal(), dtype=float)
        depth = -float(patch.penetration_depth)
        return [ContactPoint(patch.getPointShape1(i).copy(), patch.getPointShape2(i).copy(), normal, depth)
                for i in range(patch.size())]


class BroadPhase:
    """Axis-aligned bounding boxes of the declared pairs' shapes: :meth:`close_pairs` gives
    the indices of the pairs whose boxes, inflated by ``margin`` (m), overlap."""

    def __init__(self, shapes: Sequence[Shape], pairs: Sequence[tuple[int, int]], margin: float) -> None:
        self.objects = [coal.CollisionObject(shape.coal_geometry(), coal.Transform3s()) for shape in shapes]
        self.pairs = list(pairs)
        #: The shapes with a finite box that some pair uses (half-spaces are always close).
        self.bounded = sorted({i for pair in self.pairs for i in pair if shapes[i].kind != "halfspace"})
        self.margin = margin

    def close_pairs(self, poses: Sequence[np.ndarray]) -> list[int]:
        """Pairs (indices into ``pairs``) worth a narrow-phase query at these world poses."""
        lower, upper = {}, {}
        for i in self.bounded:
            obj = self.objects[i]
            obj.setTransform(transform(poses[i]))
            obj.computeAABB()
            box = obj.getAABB()
            lower[i], upper[i] = box.min_ - self.margin, box.max_ + self.margin
        close = []
        for k, (a, b) in enumerate(self.pairs):
            if a in lower and b in lower and (np.any(lower[a] > upper[b]) or np.any(lower[b] > upper[a])):
                continue
            close.append(k)
        return close
