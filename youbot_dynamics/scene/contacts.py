"""The contact sections of a scene: robot composition (composed by model/compose.py), free
bodies, static world geometry, geometry on robot links and contact pairs (read by
:mod:`youbot_dynamics.scene.schema`).

Keys (SI units; a pose is ``{xyz: [m, m, m], rpy: [rad, rad, rad]}``, default identity;
a shape is ``{type: sphere|box|cylinder|capsule|halfspace, <dimensions>}``, see
:mod:`youbot_dynamics.dynamics.collision`)::

    robot: none                       # no robot: free bodies and world geometry only
    robot:                            # several robots as one Robot (names prefixed)
      compose:
        - urdf: urdf/youbot.urdf
          prefix: yb1_
          pose: {xyz: [...], rpy: [...]}  # the robot's root link in the common ``world``
          inertials:                      # optional corrections of the file's link inertials
            gripper_finger_link_l: {mass: kg, inertia: [Ixx, Iyy, Izz]}   # kg m^2, principal
                                          # moments about the file's inertial origin and axes
    free_bodies:
      - name: ball
        shape: {type: sphere, radius: 0.05}
        density: 700                  # kg/m^3, or mass: kg and inertia: [Ixx, Iyy, Izz]
        position: [0, 0, 1]           # m, world frame (centre of mass)
        orientation: [0, 0, 0, 1]     # quaternion x, y, z, w
        velocity: [0, 0, 0]           # m/s, world frame
        angular_velocity: [0, 0, 0]   # rad/s, world frame
        rotation_coordinates: chart   # chart | quaternion | cardan_adaptive (issue 13's
                                      # ``orientation: quaternion | cardan_adaptive``; the
                                      # key ``orientation`` is the initial quaternion)
    world:
      - {name: floor, shape: {type: halfspace, normal: [0, 0, 1], offset: 0}, pose: ...}
    geometry:
      - {name: finger, link: gripper_finger_link_l, shape: {...}, pose: ...}
    contacts:
      - {pair: [ball, floor], law: hunt_crossley, stiffness: 1e5, restitution: 0.8, friction: 0.3}

``rotation_coordinates`` chooses the coordinates an ODE integrator moves the body's attitude
in (sim/model.py): ``chart`` (default) a tangent chart of SE(3) folded into a reference pose
at 1 rad; ``quaternion`` position and quaternion (x, y, z, w) integrated directly,
p' = R v, q' = q (x) (w, 0) / 2, read as q / |q| and renormalised at the outputs;
``cardan_adaptive`` position and Cardan angles switching x-y-z <-> x-z-y (Modia3D) by a
state event when the middle angle passes 1.5 rad. The constraint stepper (pgs, admm)
integrates on SE(3) with ``pin.integrate`` and takes ``chart`` only.

A free body's name is also the name of its shape in ``contacts``. Every mistake is a
SceneError naming the source, the key and the value.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.collision import SHAPES, Geometry, Shape
from youbot_dynamics.dynamics.contact import ContactLaw, ContactLawError, contact_law_from_spec
from youbot_dynamics.dynamics.free_body import FreeBody
from youbot_dynamics.model import limits
from youbot_dynamics.model.compose import (CompositionError, InertialCorrection, Placement,
                                           composed_urdf)
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.scene.reader import SceneError, SceneReader, is_uncertain

SHAPE_KEYS = ("type", "radius", "length", "size", "normal", "offset")
#: A free body's attitude coordinates (``rotation_coordinates``), the default first.
ROTATION_COORDINATES = ("chart", "quaternion", "cardan_adaptive")


@dataclass(frozen=True)
class FreeBodySpec:
    """A free body and its initial state (world frame; quaternion x, y, z, w) and the
    coordinates its attitude is integrated in (one of ROTATION_COORDINATES)."""

    body: FreeBody
    shape: Shape
    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    rotation_coordinates: str = "chart"


@dataclass(frozen=True)
class ContactPairSpec:
    """A declared pair: its name (``a/b``), the two geometry names and the law."""

    name: str
    geometry1: str
    geometry2: str
    law: ContactLaw


def pose_matrix(reader: SceneReader, value: Any, key: str) -> np.ndarray:
    """4x4 pose from ``{xyz, rpy}`` (roll-pitch-yaw, URDF convention)."""
    data = reader.mapping(value if value is not None else {}, key, ("xyz", "rpy"))
    pose = np.eye(4)
    pose[:3, 3] = reader.vector3(data.get("xyz", [0, 0, 0]), f"{key}.xyz", limits.LENGTH)
    pose[:3, :3] = pin.rpy.rpyToMatrix(*reader.vector3(data.get("rpy", [0, 0, 0]), f"{key}.rpy"))
    return pose


def read_shape(reader: SceneReader, value: Any, key: str) -> Shape:
    """A :class:`Shape` from ``{type, dimensions}``."""
    data = reader.mapping(value, key, SHAPE_KEYS)
    kind = data.get("type")
    if kind not in SHAPES:
        raise SceneError(reader.source, f"{key}.type", f"expected one of {', '.join(SHAPES)}", kind)
    allowed = SHAPES[kind]
    for name in data:
        if name != "type" and name not in allowed:
            raise SceneError(reader.source, f"{key}.{name}", f"not a dimension of a {kind} "
                             f"(dimensions: {', '.join(allowed)})", data[name])
    values: dict[str, Any] = {}
    for name in allowed:
        if name not in data and not (kind == "halfspace" and name == "offset"):
            raise SceneError(reader.source, f"{key}.{name}", f"missing: a {kind} needs {', '.join(allowed)}")
        if name in ("size", "normal"):
            values[name] = tuple(reader.vector3(data[name], f"{key}.{name}", limits.LENGTH))
        elif name in data:
            values[name] = reader.number(data[name], f"{key}.{name}", limits.LENGTH)
    for name, number in values.items():
        if name in ("radius", "length") and number <= 0 or name == "size" and min(number) <= 0:
            raise SceneError(reader.source, f"{key}.{name}", "must be positive", number)
    if kind == "halfspace" and np.linalg.norm(values["normal"]) == 0:
        raise SceneError(reader.source, f"{key}.normal", "must not be zero", values["normal"])
    return Shape(kind, **values)


def read_composition(reader: SceneReader, value: Any, base_dir: Path | None, welded: bool = True) -> str:
    """The URDF text of ``robot: {compose: [{urdf, prefix, pose, inertials}, ...]}``
    (model/compose.py composes it); files relative to ``base_dir``, else the package share;
    ``welded`` False under a moving base (one robot, not welded to a world link)."""
    entries = reader.mapping(value, "robot", ("compose",)).get("compose")
    if not isinstance(entries, list) or not entries:
        raise SceneError(reader.source, "robot.compose", "expected a non-empty list of {urdf, prefix, pose}", entries)
    placements = []
    for i, entry in enumerate(entries):
        key = f"robot.compose[{i}]"
        entry = reader.mapping(entry, key, ("urdf", "prefix", "pose", "inertials"))
        placements.append(Placement(reader.file(entry.get("urdf"), f"{key}.urdf", base_dir),
                                    str(entry.get("prefix", "")), pose_matrix(reader, entry.get("pose"), f"{key}.pose"),
                                    read_inertials(reader, entry.get("inertials", {}), f"{key}.inertials")))
    try:
        return composed_urdf(placements, welded)
    except CompositionError as error:
        raise SceneError(reader.source, f"robot.compose[{error.index}].{error.part}", error.problem) from None


def read_inertials(reader: SceneReader, value: Any, key: str) -> dict[str, InertialCorrection]:
    """``{link: {mass: kg, inertia: [Ixx, Iyy, Izz]}}``: positive masses, principal moments
    that are positive and obey the triangle inequality."""
    corrections = {}
    for name, correction in reader.mapping(value, key).items():
        where = f"{key}.{name}"
        correction = reader.mapping(correction, where, ("mass", "inertia"))
        mass = moments = None
        if "mass" in correction:
            mass = reader.positive(correction["mass"], f"{where}.mass", limits.MASS)
        if "inertia" in correction:
            moments = reader.vector3(correction["inertia"], f"{where}.inertia", limits.INERTIA)
            if np.any(moments <= 0) or 2 * moments.max() > moments.sum():
                raise SceneError(reader.source, f"{where}.inertia", "principal moments must be positive and "
                                 "obey the triangle inequality", moments.tolist())
            moments = tuple(float(m) for m in moments)
        corrections[name] = InertialCorrection(mass, moments)
    return corrections


def read_free_bodies(reader: SceneReader, value: Any) -> tuple[FreeBodySpec, ...]:
    """The ``free_bodies`` list."""
    if not isinstance(value, list):
        raise SceneError(reader.source, "free_bodies", "expected a list of bodies", value)
    specs = []
    for i, entry in enumerate(value):
        key = f"free_bodies[{i}]"
        data = reader.mapping(entry, key, ("name", "shape", "density", "mass", "inertia", "position",
                                           "orientation", "velocity", "angular_velocity",
                                           "rotation_coordinates"))
        name = data.get("name")
        if not isinstance(name, str) or not name:
            raise SceneError(reader.source, f"{key}.name", "missing: give the body a name", name)
        shape = read_shape(reader, data.get("shape"), f"{key}.shape")
        if shape.kind == "halfspace":
            raise SceneError(reader.source, f"{key}.shape.type", "a free body needs a finite shape", "halfspace")
        if "density" in data:
            if "mass" in data or "inertia" in data:
                raise SceneError(reader.source, f"{key}.density", "give density, or mass and inertia, not both")
            body = FreeBody.from_shape(name, shape, reader.positive(data["density"], f"{key}.density"))
            reader.bounded(body.mass, f"{key}.density", limits.MASS)
            reader.bounded(float(np.max(body.inertia)), f"{key}.density", limits.INERTIA)
        elif "mass" in data and "inertia" in data:
            inertia = reader.vector3(data["inertia"], f"{key}.inertia", limits.INERTIA)
            if np.any(inertia <= 0):
                raise SceneError(reader.source, f"{key}.inertia", "principal moments must be positive", inertia.tolist())
            body = FreeBody(name, reader.positive(data["mass"], f"{key}.mass", limits.MASS), np.diag(inertia))
        else:
            raise SceneError(reader.source, f"{key}.density", "missing: give density (kg/m^3) or mass and inertia")
        quaternion = data.get("orientation", [0.0, 0.0, 0.0, 1.0])
        if not isinstance(quaternion, list) or len(quaternion) != 4:
            raise SceneError(reader.source, f"{key}.orientation", "expected a quaternion [x, y, z, w]", quaternion)
        quaternion = np.array([reader.number(x, f"{key}.orientation[{j}]") for j, x in enumerate(quaternion)])
        if not np.any(quaternion):
            raise SceneError(reader.source, f"{key}.orientation", "must not be zero", quaternion.tolist())
        quaternion = quaternion / np.abs(quaternion).max()  # its norm cannot overflow (1e200 components)
        coordinates = data.get("rotation_coordinates", ROTATION_COORDINATES[0])
        if coordinates not in ROTATION_COORDINATES:
            raise SceneError(reader.source, f"{key}.rotation_coordinates",
                             f"expected one of {', '.join(ROTATION_COORDINATES)}", coordinates)
        specs.append(FreeBodySpec(
            body, shape, reader.vector3(data.get("position", [0, 0, 0]), f"{key}.position", limits.LENGTH),
            quaternion / np.linalg.norm(quaternion),
            reader.vector3(data.get("velocity", [0, 0, 0]), f"{key}.velocity", limits.SPEED),
            reader.vector3(data.get("angular_velocity", [0, 0, 0]), f"{key}.angular_velocity",
                           limits.ANGULAR_SPEED), coordinates))
    return tuple(specs)


def read_geometries(reader: SceneReader, world: Any, attached: Any, robot: Robot,
                    bodies: Sequence[FreeBodySpec]) -> tuple[Geometry, ...]:
    """World geometry, link geometry and one geometry per free body (its shape)."""
    declared: dict[str, str] = {}  # name -> the key that declared it

    def declare(name: str, key: str) -> None:
        if name in declared:
            raise SceneError(reader.source, key, f"name already used by {declared[name]} (geometries and free "
                             "bodies need distinct names)", name)
        declared[name] = key

    geometries = []
    for i, spec in enumerate(bodies):
        declare(spec.body.name, f"free_bodies[{i}].name")
        geometries.append(Geometry(spec.body.name, spec.shape, "body", spec.body.name))
    for section, value, owner in (("world", world, "world"), ("geometry", attached, "link")):
        if not isinstance(value, list):
            raise SceneError(reader.source, section, "expected a list of {name, shape, pose}", value)
        for i, entry in enumerate(value):
            key = f"{section}[{i}]"
            data = reader.mapping(entry, key, ("name", "shape", "pose") + (("link",) if owner == "link" else ()))
            name = data.get("name")
            if not isinstance(name, str) or not name:
                raise SceneError(reader.source, f"{key}.name", "missing: give the geometry a name", name)
            declare(name, f"{key}.name")
            owner_name = "world"
            if owner == "link":
                owner_name = data.get("link")
                if owner_name not in robot.link_names:
                    raise SceneError(reader.source, f"{key}.link", "not a link of the robot", owner_name)
            geometries.append(Geometry(name, read_shape(reader, data.get("shape"), f"{key}.shape"), owner, owner_name,
                                       pose_matrix(reader, data.get("pose"), f"{key}.pose")))
    return tuple(geometries)


def read_contacts(reader: SceneReader, value: Any, geometries: Sequence[Geometry]) -> tuple[ContactPairSpec, ...]:
    """The ``contacts`` list: pairs of geometry names and their laws."""
    if not isinstance(value, list):
        raise SceneError(reader.source, "contacts", "expected a list of {pair: [a, b], law: ..., parameters}", value)
    by_name = {g.name: g for g in geometries}
    pairs = []
    for i, entry in enumerate(value):
        key = f"contacts[{i}]"
        data = dict(reader.mapping(entry, key))
        pair = data.pop("pair", None)
        if not isinstance(pair, list) or len(pair) != 2 or any(name not in by_name for name in pair):
            raise SceneError(reader.source, f"{key}.pair", "expected two geometry or free-body names "
                             f"(known: {', '.join(by_name)})", pair)
        name = f"{pair[0]}/{pair[1]}"
        for parameter, number in data.items():   # "v ± s" read here; the law checks the rest
            if is_uncertain(number):
                data[parameter] = reader.number(number, f"{key}.{parameter}")
        if by_name[pair[0]].owner != "body" and by_name[pair[1]].owner != "body":
            raise SceneError(reader.source, f"{key}.pair", "one side must be a free body", name)
        try:
            law = contact_law_from_spec(data, f"pair {name}")
        except ContactLawError as error:
            raise SceneError(reader.source, key, str(error), name) from None
        pairs.append(ContactPairSpec(name, pair[0], pair[1], law))
    return tuple(pairs)
