"""What the simulated sensors read at one instant, from the plant's state, its accelerations
and the contact forces that produced them.

- The wrist force/torque sensor (:class:`WristSensor`) sits in the joint between a link (the
  scene's ``wrist_sensor``, by default the youBot's palm) and its parent. It reads the wrench
  the proximal side exerts on the distal side (that link and every link below it), as a
  real sensor between wrist and hand does: Newton-Euler on the distal links,
  W = sum_b (I_b (a_b - g) + v_b x* I_b v_b) - sum of the contact wrenches on distal links,
  at the link's origin, in its frame (force N, torque N m). At rest holding a body it reads
  the weight of the hand and the body, pushed up: +m g.
- Each contact pair's wrench (:func:`contact_forces`, :func:`pair_wrenches`): the contact
  forces on the pair's second geometry, summed about the origin of that geometry's frame (a
  link's or a free body's; the world for world geometry), in that frame.
- The base IMU (:func:`imu`): base_link's angular velocity (rad/s) and proper acceleration
  (m/s^2: the classical acceleration minus gravity, so +9.81 up at rest), in base_link, and
  its orientation in the world.

The forces are those of the step that ended at the instant: the constraint stepper's
impulses over that step (its velocity change gives the accelerations), or the compliant law
at the state (ABA's accelerations).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.contact_model import ContactModel
from youbot_dynamics.dynamics.contact_stepper import StepReport, contact_rotation
from youbot_dynamics.model.robot import Robot, TreeJoint

PointForce = tuple[int, np.ndarray, np.ndarray]
"""(pair index, point (world, m), force on the pair's second geometry (world, N))."""
_NO_ROTATION = np.zeros(3)
"""The angular part of gravity's spatial acceleration (rad/s^2: none)."""
_NO_ROTATION.setflags(write=False)


@dataclass(frozen=True)
class Readings:
    """The sensors at one instant. ``wrist``: (force (3,) N, torque (3,) N m) in the sensor
    link's frame, None without a wrist sensor; ``pairs``: per contact pair name (force, torque)
    on its second geometry about that geometry's frame origin, in that frame (zero when the
    pair does not touch); ``imu``: (angular velocity (3,) rad/s, proper acceleration (3,)
    m/s^2, both in base_link, orientation of base_link in the world (x, y, z, w)), None
    without a moving base."""

    wrist: tuple[np.ndarray, np.ndarray] | None = None
    pairs: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    imu: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


def contact_forces(contact: ContactModel, step: StepReport | None, h: float) -> list[PointForce]:
    """Every contact point's force of a constraint step of ``h`` s (impulse / h: the mean
    force over the step) as :data:`PointForce`, at the point on the second geometry."""
    if step is None or step.impulses is None:
        return []
    index = {pair.name: k for k, pair in enumerate(contact.pairs)}
    impulses = step.impulses.reshape(-1, 3)
    return [(index[name], point.point2, contact_rotation(point.normal) @ impulse / h)
            for name, point, impulse in zip(step.names, step.points, impulses)]


class SensorModel:
    """The sensors of a compiled scene's plant (``robot``, the plant's Robot): the wrist sensor at
    ``wrist_link`` (None: none; the links' inertias from the robot's ``urdf`` text), the
    contact pairs of ``contact`` (None: none) and the IMU at base_link when ``moving_base``."""

    def __init__(self, robot: Robot, wrist_link: str | None, contact: ContactModel | None,
                 moving_base: bool, urdf: str = "") -> None:
        plant = robot.model
        self.plant, self.contact = plant, contact
        self.wrist = None if wrist_link is None else WristSensor(plant, robot.tree, wrist_link, urdf)
        self.imu_frame = plant.getFrameId("base_link", pin.BODY) if moving_base and \
            plant.existFrame("base_link", pin.BODY) else None
        #: per pair, the frame of its second geometry (None: the world)
        self.pair_frames = [] if contact is None else [contact.frames[pair.second] for pair in contact.pairs]

    def read(self, data: pin.Data, q: np.ndarray, v: np.ndarray, a: np.ndarray,
             forces: list[PointForce]) -> Readings:
        """The readings at plant configuration q, velocity v and acceleration a (Pinocchio's
        conventions) under the contact ``forces``."""
        plant = self.plant
        pin.forwardKinematics(plant, data, q, v, a)
        pin.updateFramePlacements(plant, data)
        wrist = None if self.wrist is None else self.wrist.wrench(data, forces, self.contact)
        pairs = {} if self.contact is None else pair_wrenches(self.contact, self.pair_frames, data, forces)
        return Readings(wrist, pairs, None if self.imu_frame is None else imu(plant, data, self.imu_frame))


def link_inertias(model: pin.Model) -> dict[str, pin.Inertia]:
    """Each link's own spatial inertia in its frame, by name, from a model built from a URDF:
    a fixed joint's frame carries its child link's; a moving joint's body holds its child
    link's plus those of the links fixed below it (Pinocchio's inertia is linear in its
    dynamic parameters, so theirs are subtracted)."""
    own: dict[str, pin.Inertia] = {}
    body_of = {}
    for f, frame in enumerate(model.frames):
        if frame.type == pin.FrameType.BODY and model.frames[frame.parentFrame].type == pin.FrameType.JOINT:
            body_of[frame.parentJoint] = frame.name
    parameters = {j: model.inertias[j].toDynamicParameters() for j in body_of}
    for frame in model.frames:
        if frame.type == pin.FrameType.FIXED_JOINT:
            child = next(f.name for f in model.frames if f.type == pin.FrameType.BODY
                         and model.frames[f.parentFrame].name == frame.name)
            own[child] = frame.inertia
            if frame.parentJoint in parameters:
                parameters[frame.parentJoint] = parameters[frame.parentJoint] \
                    - frame.placement.act(frame.inertia).toDynamicParameters()
    own.update({name: pin.Inertia.FromDynamicParameters(parameters[j]) for j, name in body_of.items()})
    return own


def _world_wrench(point: np.ndarray, force: np.ndarray) -> pin.Force:
    """A force (world, N) at a point (world, m) as a spatial force about the world origin
    (the moment point x force in Python floats: numpy.cross's arithmetic, without its
    overhead on one pair of 3-vectors)."""
    (p0, p1, p2), (f0, f1, f2) = point.tolist(), force.tolist()
    return pin.Force(force, np.array([p1 * f2 - p2 * f1, p2 * f0 - p0 * f2, p0 * f1 - p1 * f0]))


def pair_wrenches(contact: ContactModel, frames: list[int | None], data: pin.Data,
                  forces: list[PointForce]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per pair (force N, torque N m) on its second geometry about the origin of the frame
    ``frames[k]`` (placed in ``data``), in that frame; world geometry: in the world."""
    totals = [pin.Force.Zero() for _ in contact.pairs]
    for k, point, force in forces:
        totals[k] += _world_wrench(point, force)
    result, placements = {}, data.oMf
    for pair, frame, total in zip(contact.pairs, frames, totals):
        local = total if frame is None else placements[frame].actInv(total)
        result[pair.name] = (local.linear.copy(), local.angular.copy())
    return result


def imu(plant: pin.Model, data: pin.Data, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(angular velocity rad/s, proper acceleration m/s^2, both in the frame; its orientation
    in the world, x, y, z, w) of ``frame`` after forwardKinematics with accelerations."""
    rotation = data.oMf[frame].rotation
    angular = pin.getFrameVelocity(plant, data, frame, pin.LOCAL).angular.copy()
    linear = pin.getFrameClassicalAcceleration(plant, data, frame, pin.LOCAL).linear - rotation.T @ plant.gravity.linear
    return angular, linear, pin.Quaternion(rotation).coeffs().copy()


class WristSensor:
    """A force/torque sensor in the joint between ``link`` and its parent, on the plant
    ``plant`` (its kinematic ``tree``, locked joints included): the distal links (``link`` and
    every link below it) and their rigid parts ((plant joint, the link's spatial inertia in
    that joint's frame)), the inertias from the robot's URDF (``urdf``, text), so that links a
    scene locks (merged into their parent's body by the reduction) count as well."""

    def __init__(self, plant: pin.Model, tree: Sequence[TreeJoint], link: str, urdf: str) -> None:
        self.link = link
        self.frame = plant.getFrameId(link, pin.BODY)
        links = {link}
        for joint in tree:  # parents come first in the tree
            if joint.parent in links:
                links.add(joint.child)
        #: the distal links' frames (what contact geometry hangs on)
        self.distal = frozenset(plant.getFrameId(name, pin.BODY) for name in links)
        own = link_inertias(pin.buildModelFromXML(urdf))
        self.gravity = plant.gravity.linear.copy()
        """The plant's gravity (m/s^2, world frame)."""
        self.parts = tuple((plant.frames[f].parentJoint, plant.frames[f].placement.act(own[plant.frames[f].name]))
                           for f in sorted(self.distal) if plant.frames[f].name in own)

    @property
    def mass(self) -> float:
        """The distal links' mass (kg)."""
        return float(sum(inertia.mass for _, inertia in self.parts))

    def wrench(self, data: pin.Data, forces: list[PointForce],
               contact: ContactModel | None) -> tuple[np.ndarray, np.ndarray]:
        """(force N, torque N m) the proximal side exerts on the distal side, at the link's
        origin in its frame, from data's kinematics (velocities and accelerations placed)
        and the contact ``forces``."""
        total, placements, velocities, accelerations = pin.Force.Zero(), data.oMi, data.v, data.a
        for joint, inertia in self.parts:
            placement, velocity = placements[joint], velocities[joint]
            acceleration = accelerations[joint] - pin.Motion(placement.rotation.T @ self.gravity, _NO_ROTATION)
            total += placement.act(inertia * acceleration + velocity.cross(inertia * velocity))
        for k, point, force in forces:
            pair = contact.pairs[k]
            if contact.frames[pair.second] in self.distal:
                total -= _world_wrench(point, force)
            if contact.frames[pair.first] in self.distal:
                total += _world_wrench(point, force)
        local = data.oMf[self.frame].actInv(total)
        return local.linear.copy(), local.angular.copy()
