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
bounding balls (:attr:`Shape.bounding_radius` about the shape's origin), inflated by the
margin, overlap: a few float operations per pair, and the narrow-phase cost grows with the
pairs that are close.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple, Sequence

import coal
import numpy as np
import pinocchio as pin

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

    @property
    def bounding_radius(self) -> float:
        """Radius (m) of the smallest ball about the shape's origin that holds it (inf for a
        half-space)."""
        if self.kind == "sphere":
            return self.radius
        if self.kind == "box":
            return 0.5 * math.sqrt(sum(edge * edge for edge in self.size))
        if self.kind == "cylinder":
            return math.hypot(self.radius, 0.5 * self.length)
        if self.kind == "capsule":
            return self.radius + 0.5 * self.length
        return math.inf

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


class ContactPoint(NamedTuple):
    """World-frame witness points on shape 1 and 2 (m), unit normal from 1 to 2, depth (m,
    > 0 when overlapping, -distance otherwise). A named tuple: built several times a step."""

    point1: np.ndarray
    point2: np.ndarray
    normal: np.ndarray
    depth: float


def transform(pose: np.ndarray | pin.SE3) -> pin.SE3:
    """A pose as coal takes it: a ``pin.SE3`` (coal converts it in C++), a 4x4 homogeneous
    pose copied into one."""
    return pose if isinstance(pose, pin.SE3) else pin.SE3(pose)


class PlacedPair:
    """The narrow phase of one declared pair: coal shapes and reusable requests and result."""

    def __init__(self, shape1: Shape, shape2: Shape) -> None:
        self.geometry1, self.geometry2 = shape1.coal_geometry(), shape2.coal_geometry()
        self.distance_request = coal.DistanceRequest()
        self.distance_request.enable_signed_distance = True
        self.distance_result = coal.DistanceResult()
        self.collision_request = coal.CollisionRequest()
        self.patch_request = coal.ContactPatchRequest()
        self.patches = shape1.kind in FLAT and shape2.kind in FLAT

    def _distance(self, t1, t2) -> float:
        """coal's signed distance (m) at world poses t1, t2 (pin.SE3 or coal transforms); the
        witnesses and normal stay in ``distance_result``."""
        result = self.distance_result
        result.clear()  # coal keeps the smaller of the stored and the new distance
        return coal.distance(self.geometry1, t1, self.geometry2, t2, self.distance_request, result)

    def signed_distance(self, pose1: np.ndarray | pin.SE3, pose2: np.ndarray | pin.SE3) -> float:
        """Signed distance (m, < 0 when overlapping) at world poses (4x4 or pin.SE3)."""
        return self._distance(transform(pose1), transform(pose2))

    def contact_points(self, pose1: np.ndarray | pin.SE3, pose2: np.ndarray | pin.SE3,
                       margin: float) -> list[ContactPoint]:
        """Contact points of the pair at the given world poses (4x4 or pin.SE3; see module
        docstring)."""
        t1, t2 = transform(pose1), transform(pose2)
        distance = self._distance(t1, t2)
        if distance > margin:
            return []
        return self.witnessed(distance, self.distance_result, t1, t2)

    def witnessed(self, distance: float, result: coal.DistanceResult, t1, t2) -> list[ContactPoint]:
        """The contact points of coal's signed ``distance`` (m) and its ``result`` (witness
        points and normal) at world poses t1, t2 (pin.SE3 or coal transforms): the witness
        pair, or coal's contact patch where two flat shapes overlap (see module docstring)."""
        p1, p2 = result.getNearestPoint1(), result.getNearestPoint2()  # fresh arrays
        normal = result.normal.copy()  # float64; a view into the result otherwise
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
    """Bounding balls of the declared pairs' shapes: :meth:`close_pairs` gives the indices of
    the pairs whose balls, inflated by ``margin`` (m), overlap. Conservative: a pair within
    ``margin`` is never left out (a ball holds its shape; ``SLACK`` covers the rounding of
    the centres)."""

    #: Added to every reach (m): the rounding of world centres is far below it.
    SLACK = 1e-9

    def __init__(self, shapes: Sequence[Shape], pairs: Sequence[tuple[int, int]], margin: float) -> None:
        self.pairs = list(pairs)
        self.margin = margin
        reach = [shapes[a].bounding_radius + shapes[b].bounding_radius + margin + self.SLACK for a, b in self.pairs]
        #: (pair, first, second, squared reach) of the bounded pairs; a half-space's are always close.
        self.tests = [(k, a, b, r * r) for k, ((a, b), r) in enumerate(zip(self.pairs, reach)) if math.isfinite(r)]
        self.always = [k for k, r in enumerate(reach) if not math.isfinite(r)]

    def close_pairs(self, centres: Sequence[Sequence[float]]) -> list[int]:
        """Pairs (indices into ``pairs``) worth a narrow-phase query with the shapes' origins
        at ``centres`` (per shape x, y, z, world, m; a half-space's is not read), in
        increasing order. Plain float arithmetic: for the few pairs a scene declares, a
        numpy pass costs more in dispatch (about 20 us) than this loop."""
        close = list(self.always)
        for k, a, b, reach2 in self.tests:
            xa, ya, za = centres[a]
            xb, yb, zb = centres[b]
            dx, dy, dz = xa - xb, ya - yb, za - zb
            if dx * dx + dy * dy + dz * dz <= reach2:
                close.append(k)
        if self.always:
            close.sort()
        return close
