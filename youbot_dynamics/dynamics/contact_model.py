"""The contact geometry of a scene on its one Pinocchio model, read by every contact law.

Each geometry hangs on a frame of the model: a robot link's frame, a free body's frame
(the free-flyer joint added by :func:`~youbot_dynamics.dynamics.free_body.add_free_flyer`)
or none (world geometry). After ``pin.framesForwardKinematics`` (or
``computeJointJacobians`` + ``updateFramePlacements``) on a Data of that model,
:meth:`ContactModel.placements` gives the world pose of every geometry from ``data.oMf``
(:meth:`ContactModel.poses` as 4x4 matrices), :meth:`ContactModel.centres` the centres of
their bounding balls for the broad phase, :meth:`ContactModel.points` one pair's contact points,
:meth:`ContactModel.touching` every pair's within a margin straight from the joint placements
(coal's geometry model on the C++ side: Pinocchio's GeometryModel), and
:meth:`ContactModel.relative_jacobian` the 3 x nv map from the generalised velocity (robot
joints and body twists alike) to a contact point's relative velocity, from Pinocchio's frame
Jacobians. The compliant law (:meth:`ContactModel.compliant_force`, a generalised force for
ABA), the impulsive law (:meth:`ContactModel.impact_impulse`, with the inverse mass matrix of
``computeMinverse``) and the constraint stepper
(:mod:`youbot_dynamics.dynamics.contact_stepper`) all read this one object.

Conventions (:mod:`youbot_dynamics.dynamics.contact`): pair k's normal points from its first
geometry to its second, relative velocity u = v2 - v1 at the contact point (world frame,
m/s), forces on geometry 2 (N). Where a pair's overlap is a patch of N points (a face on a
face), each point carries 1/N of the compliant law's force at the patch depth.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.collision import BroadPhase, ContactPoint, Geometry, PlacedPair
from youbot_dynamics.dynamics.contact import (ContactLaw, HuntCrossley, hunt_crossley_force,
                                              hunt_crossley_potential, hysteresis_factor, newton_impulse,
                                              regularised_coulomb)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.lie import skew

#: Pairs farther apart than this (m) skip the narrow phase of the compliant law.
BROAD_PHASE_MARGIN = 1e-3


@dataclass(frozen=True)
class Pair:
    """A declared contact pair: name, indices of its two geometries, its law."""

    name: str
    first: int
    second: int
    law: ContactLaw


class ContactModel:
    """Geometries on the frames of ``model`` (``frames[i]`` is geometry i's frame id, None
    for world geometry) and the declared pairs; immutable after construction (the coal
    requests and the geometry data it holds are scratch space)."""

    def __init__(self, model: pin.Model, geometries: Sequence[Geometry], frames: Sequence[int | None],
                 pairs: Sequence[Pair], margin: float = BROAD_PHASE_MARGIN) -> None:
        self.model = model
        self.geometries = tuple(geometries)
        self.frames = tuple(frames)
        self.pairs = tuple(pairs)
        self.narrow = [PlacedPair(self.geometries[p.first].shape, self.geometries[p.second].shape)
                       for p in self.pairs]
        self.broad = BroadPhase([g.shape for g in self.geometries], [(p.first, p.second) for p in self.pairs],
                                margin)
        #: Each geometry's placement in its frame (pin.SE3) where it is not the identity (where
        #: it is, the geometry's world pose is data.oMf[frame] itself).
        self._offsets = {i: pin.SE3(g.placement) for i, g in enumerate(self.geometries)
                         if not np.array_equal(g.placement, np.eye(4))}
        #: Geometry fixed to the world (world geometry, links on the universe joint): its world
        #: pose (pin.SE3, what :meth:`placements` would compute from data.oMf) and its
        #: bounding-ball centre (the shape's origin, world, m), kept from the start (None for
        #: the others). The others' (index, frame, offset or None) are placed after each
        #: kinematics pass.
        self._fixed_poses: list[pin.SE3 | None] = [None] * len(self.geometries)
        self._fixed_centres: list[tuple[float, float, float] | None] = [None] * len(self.geometries)
        self._moving: list[tuple[int, int, pin.SE3 | None]] = []
        for i, frame in enumerate(self.frames):
            offset = self._offsets.get(i)
            if frame is None:
                pose = pin.SE3(self.geometries[i].placement)
            elif model.frames[frame].parentJoint == 0:
                pose = model.frames[frame].placement if offset is None else model.frames[frame].placement * offset
            else:
                self._moving.append((i, frame, offset))
                continue
            self._fixed_poses[i], self._fixed_centres[i] = pose, tuple(pose.translation.tolist())
        #: coal's geometry model on the joints of ``model`` (geometry i is object i, pair k
        #: collision pair k) and its data (scratch space like the coal requests): for
        #: :meth:`touching`, one C++ call places every geometry, one measures every pair.
        self.geometry_model = pin.GeometryModel()
        for i, geometry in enumerate(self.geometries):
            joint, frame, placement = self._attachment(i)
            self.geometry_model.addGeometryObject(pin.GeometryObject(geometry.name, joint, frame, placement,
                                                                     geometry.shape.coal_geometry()))
        for pair in self.pairs:
            if self.geometry_model.existCollisionPair(pin.CollisionPair(pair.first, pair.second)):
                raise UserInputError(f"contact pair {pair.name} is declared twice; declare it once")
            self.geometry_model.addCollisionPair(pin.CollisionPair(pair.first, pair.second))
        self.geometry_data = self.geometry_model.createData()
        for request in self.geometry_data.distanceRequests:
            request.enable_signed_distance = True
        placed = self.geometry_data.oMg
        #: per pair: its distance result and its geometries' world poses (references into the
        #: geometry data, filled by each :meth:`touching`) and its narrow phase
        self._measured = [(self.geometry_data.distanceResults[k], placed[pair.first], placed[pair.second],
                           self.narrow[k]) for k, pair in enumerate(self.pairs)]

    def _attachment(self, geometry: int) -> tuple[int, int, pin.SE3]:
        """Geometry i's joint, frame and placement in the joint's frame (pin.SE3, m): the
        frame's placement times the geometry's in the frame (the universe's for world
        geometry)."""
        frame = self.frames[geometry]
        offset = pin.SE3(self.geometries[geometry].placement)
        if frame is None:
            return 0, 0, offset
        return self.model.frames[frame].parentJoint, frame, self.model.frames[frame].placement * offset

    # ---- geometry ---------------------------------------------------------------------------
    def placements(self, data: pin.Data) -> list[pin.SE3]:
        """World poses (pin.SE3, m) of the geometries from ``data.oMf`` (frames placed
        first): the frame's pose times the geometry's placement in it (Pinocchio's SE3
        product), the frame's own where the geometry sits at its origin, kept from the start
        for geometry fixed to the world. One pose per geometry per kinematics pass: the broad
        phase reads their origins, the narrow phase the poses."""
        placed = list(self._fixed_poses)
        frames = data.oMf
        for i, frame, offset in self._moving:
            placed[i] = frames[frame] if offset is None else frames[frame] * offset
        return placed

    def poses(self, data: pin.Data) -> list[np.ndarray]:
        """World poses (4x4, m) of the geometries from ``data.oMf`` (frames placed first):
        :meth:`placements` as matrices."""
        return [placement.homogeneous for placement in self.placements(data)]

    def centres(self, placements: Sequence[pin.SE3]) -> list[tuple[float, float, float]]:
        """World centres (x, y, z per geometry, m) of the geometries' bounding balls (their
        shapes' origins) at :meth:`placements`: what :meth:`BroadPhase.close_pairs` reads."""
        centres = list(self._fixed_centres)
        for i, _, _ in self._moving:
            centres[i] = placements[i].translation.tolist()
        return centres

    def points(self, k: int, poses: Sequence[np.ndarray], margin: float) -> list[ContactPoint]:
        """Contact points of pair k at these poses, gaps up to ``margin`` (m) included."""
        pair = self.pairs[k]
        return self.narrow[k].contact_points(poses[pair.first], poses[pair.second], margin)

    def touching(self, data: pin.Data, margin: float) -> list[tuple[int, list[ContactPoint]]]:
        """(k, contact points) of every pair k within ``margin`` (m), in pair order, at the
        joint placements of ``data`` (data.oMi, after any kinematics pass): coal's geometry
        model places every geometry and measures every pair in two C++ calls (the queries of
        :meth:`points`, the same results), and only the pairs within the margin are read on."""
        pin.updateGeometryPlacements(self.model, data, self.geometry_model, self.geometry_data)
        pin.computeDistances(self.geometry_model, self.geometry_data)
        found = []
        for k, (result, placed1, placed2, narrow) in enumerate(self._measured):
            distance = result.min_distance
            if not distance > margin:
                points = narrow.witnessed(distance, result, placed1, placed2)
                if points:
                    found.append((k, points))
        return found

    def gap(self, k: int, poses: Sequence[np.ndarray]) -> float:
        """Signed distance (m, < 0 overlapping) of pair k."""
        pair = self.pairs[k]
        return self.narrow[k].signed_distance(poses[pair.first], poses[pair.second])

    def overlaps(self, poses: Sequence[np.ndarray]) -> dict[str, float]:
        """The deepest overlap (m, >= 0) of every pair, by pair name."""
        return {pair.name: max([0.0] + [c.depth for c in self.points(k, poses, 0.0)])
                for k, pair in enumerate(self.pairs)}

    def owner_joint(self, geometry: int) -> int:
        """The joint that carries geometry i (0, the universe, for world geometry)."""
        frame = self.frames[geometry]
        return 0 if frame is None else self.model.frames[frame].parentJoint

    # ---- velocities (after computeJointJacobians + updateFramePlacements) ------------------
    def point_jacobian(self, data: pin.Data, geometry: int, point: np.ndarray) -> np.ndarray:
        """3 x nv: world-frame velocity (m/s) of the material point at ``point`` (world, m)
        moving with geometry i's frame."""
        frame = self.frames[geometry]
        if frame is None:
            return np.zeros((3, self.model.nv))
        jacobian = pin.getFrameJacobian(self.model, data, frame, pin.LOCAL_WORLD_ALIGNED)
        return jacobian[:3] - skew(point - data.oMf[frame].translation) @ jacobian[3:]

    def relative_jacobian(self, data: pin.Data, k: int, point: np.ndarray) -> np.ndarray:
        """3 x nv: velocity at ``point`` (world, m) of pair k's second geometry relative to its
        first (generalised velocity -> m/s, world frame)."""
        pair = self.pairs[k]
        return self.point_jacobian(data, pair.second, point) - self.point_jacobian(data, pair.first, point)

    def approach(self, data: pin.Data, k: int, poses: Sequence[np.ndarray],
                 v: np.ndarray) -> tuple[ContactPoint, np.ndarray, np.ndarray]:
        """Pair k's nearest contact point, its relative Jacobian (3 x nv) and relative
        velocity (m/s) at generalised velocity v."""
        c = self.points(k, poses, np.inf)[0]
        relative = self.relative_jacobian(data, k, 0.5 * (c.point1 + c.point2))
        return c, relative, relative @ v

    # ---- laws ----------------------------------------------------------------------------------
    def compliant_force(self, data: pin.Data, q: np.ndarray, v: np.ndarray, poses: Sequence[np.ndarray],
                        compliant: Sequence[int], approach_speeds: np.ndarray) -> np.ndarray:
        """Generalised force (nv; N m, N) of the Hunt-Crossley pairs ``compliant`` (indices
        into ``pairs``; pair ``compliant[j]`` last touched at ``approach_speeds[j]``, m/s):
        sum of J^T f over the overlapping points. ``poses`` are those at q, and ``data``'s
        frames are placed at q."""
        generalised = np.zeros(self.model.nv)
        for _, _, relative, force in self.compliant_point_forces(data, q, v, poses, compliant, approach_speeds):
            generalised += relative.T @ force
        return generalised

    def compliant_point_forces(self, data: pin.Data, q: np.ndarray, v: np.ndarray, poses: Sequence[np.ndarray],
                               compliant: Sequence[int], approach_speeds: np.ndarray):
        """Per overlapping point of the compliant pairs (arguments as :meth:`compliant_force`):
        (pair index, point (world, m: midway between the surfaces), relative Jacobian (3 x nv),
        force on the pair's second geometry (world, N))."""
        close = set(self.broad.close_pairs(self.centres(self.placements(data))))
        jacobians_ready = False
        for j, k in enumerate(compliant):
            if k not in close:
                continue
            points = [c for c in self.points(k, poses, 0.0) if c.depth > 0.0]
            if not points:
                continue
            if not jacobians_ready:
                pin.computeJointJacobians(self.model, data, q)
                pin.updateFramePlacements(self.model, data)
                jacobians_ready = True
            law: HuntCrossley = self.pairs[k].law
            chi = hysteresis_factor(law.restitution, approach_speeds[j], law.damping_model)
            for c in points:
                point = 0.5 * (c.point1 + c.point2)
                relative = self.relative_jacobian(data, k, point)
                u = relative @ v
                un = float(u @ c.normal)
                fn = hunt_crossley_force(c.depth, -un, law.stiffness, law.exponent, chi) / len(points)
                yield k, point, relative, fn * c.normal + regularised_coulomb(u - un * c.normal, fn, law.friction,
                                                                            law.velocity_scale)

    def elastic_energy(self, poses: Sequence[np.ndarray], compliant: Sequence[int]) -> float:
        """Energy (J) in the springs of the compliant pairs: per contact point 1/N of the
        law's potential at the patch depth, as the force is shared."""
        stored = 0.0
        for k in compliant:
            law: HuntCrossley = self.pairs[k].law
            points = [c for c in self.points(k, poses, 0.0) if c.depth > 0.0]
            stored += sum(hunt_crossley_potential(c.depth, law.stiffness, law.exponent)
                          for c in points) / max(len(points), 1)
        return stored

    def impact_impulse(self, inverse_mass: np.ndarray, relative: np.ndarray, u: np.ndarray,
                       normal: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Newton's impact of pair k: the impulse on geometry 2 (N s, world) and the change of
        the generalised velocity M^-1 J^T Lambda, for the relative Jacobian J at the point,
        the relative velocity u (m/s) and the normal."""
        law = self.pairs[k].law
        impulse, _ = newton_impulse(relative @ inverse_mass @ relative.T, u, normal, law.restitution, law.friction)
        return impulse, inverse_mass @ relative.T @ impulse
