"""Scene -> :class:`~youbot_dynamics.sim.model.SimModel`: :func:`compile` and the builders it
calls, one per part of the model (what each part holds: :mod:`youbot_dynamics.sim.model`).

- :func:`build_plant`: the one Pinocchio model (the robot, with a planar root under a moving
  base, then one free-flyer joint per free body) and each geometry's frame;
- :func:`build_base`: the compiled mobile base (None for a fixed base);
- :func:`build_contact`: the contact model on the plant and which pairs are compliant
  (Hunt-Crossley) and impulsive (Newton);
- :func:`build_layout`, :func:`velocity_index`, :func:`velocity_bounds`: the state layout,
  where the plant's velocity sits in it and the divergence bound of each component;
- :func:`build_control`: the controller, its reference and a Python callback's period;
- :func:`build_stepper`: the constraint stepper of a ``pgs``/``admm`` scene.

Each builder checks what it builds; :func:`compile` calls them in a fixed order, so a scene
with two mistakes always reports the same one.
"""
from __future__ import annotations

import dataclasses
import math
from types import MappingProxyType

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.contact import HuntCrossley, NewtonImpact
from youbot_dynamics.dynamics.contact_model import ContactModel, Pair
from youbot_dynamics.dynamics.contact_stepper import ConstraintStepper, StepperSettings
from youbot_dynamics.dynamics.free_body import add_free_flyer
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.registry import integrator_kind
from youbot_dynamics.model.compose import robot_with_gravity
from youbot_dynamics.model.configuration import require_fixed_root
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.scene.reader import SceneError
from youbot_dynamics.scene.schema import IntegratorSpec, Scene
from youbot_dynamics.sim.controllers import Control, ControllerCallback, Reference, make_controller
from youbot_dynamics.sim.divergence import DivergenceLimits, penetration_limit
from youbot_dynamics.sim.mobile_base import POSE_LABELS, TWIST_LABELS, BaseModel, planar_robot
from youbot_dynamics.sim.model import BLOCKS, SimModel
from youbot_dynamics.sim.sensors import SensorModel
from youbot_dynamics.sim.state import StateLayout
from youbot_dynamics.sim.trajectory import PointToPointTrajectory

#: A joint velocity beyond this multiple of its URDF limit is divergence.
VELOCITY_LIMIT_FACTOR = 100.0
_POSE = ("x", "y", "z", "qx", "qy", "qz", "qw")
_TWIST = ("vx", "vy", "vz", "wx", "wy", "wz")
_CARDAN = ("a1", "a2", "a3", "sequence")


def compile(scene: Scene, integrator: IntegratorSpec | None = None, limits: DivergenceLimits | None = None,
            controller: ControllerCallback | None = None, control_rate: float | None = None) -> SimModel:
    """The SimModel of ``scene`` (with another ``integrator`` or divergence ``limits`` if
    given). ``controller`` replaces the scene's controller by a Python callback
    (t, q, v) -> tau run at ``control_rate`` (Hz, default the output rate), its torque held
    in between (the integrator is not restarted at the control ticks)."""
    integrator = integrator or scene.integrator
    limits = limits or DivergenceLimits()
    if integrator.method == "auto":
        integrator = scene.pinned_integrator()   # a one-line error naming the command to run
    robot = scene.robot
    require_fixed_root(robot, scene.source)
    friction = scene.joint_friction(robot)
    plant, frames = build_plant(scene)
    base = build_base(scene, plant, integrator)
    contact, compliant, impulsive = build_contact(scene, plant, frames)
    layout = build_layout(scene, friction, compliant, base)
    bounds = velocity_bounds(layout, scene, base, limits)
    control = build_control(scene, friction, controller, control_rate)
    stepper = build_stepper(scene, contact, integrator)
    passive = scene.controller.type == "none" and (base is None or (base.dynamic and base.pi is None))
    return SimModel(
        scene=scene, integrator=integrator, limits=limits, robot=robot, plant=plant,
        body_names=tuple(s.body.name for s in scene.free_bodies), friction=friction, control=control,
        contact=contact, compliant=compliant, impulsive=impulsive, stepper=stepper, layout=layout,
        bounds=bounds, penetration_limits=penetration_limits(scene, limits),
        conservative=passive and is_lossless(scene, friction, controller, base),
        passive=passive, ee_frame=plant.frame_id(robot.end_effectors[0]),
        velocity_index=velocity_index(layout, scene, base), base=base,
        slices=MappingProxyType({symbol: layout.slice(symbol) for symbol in BLOCKS}),
        coordinates=tuple(spec.rotation_coordinates for spec in scene.free_bodies),
        sensors=SensorModel(plant, scene.wrist_sensor, contact, base is not None, scene.urdf))


# ---- the plant and the base --------------------------------------------------------------------
def build_plant(scene: Scene) -> tuple[Robot, list[int | None]]:
    """The plant: the scene's robot (under a moving base rebuilt with a planar root from the
    URDF the scene read, with the scene's gravity) with one free-flyer joint per free body
    appended; and the frame id of each of the scene's geometries (None: world)."""
    robot = scene.robot
    if scene.base.mode != "fixed":
        robot = robot_with_gravity(planar_robot(scene.urdf_document, scene.moving, scene.locked),
                                   scene.gravity)
    bodies = [spec.body for spec in scene.free_bodies]
    if not bodies:
        plant = robot
        body_frames = {}
    else:
        model = pin.Model(robot.model)
        body_frames = {body.name: add_free_flyer(model, body)[1] for body in bodies}
        plant = dataclasses.replace(robot, model=model)
    frames = [None if g.owner == "world" else body_frames[g.owner_name] if g.owner == "body"
              else robot.frame_id(g.owner_name) for g in scene.geometries]
    return plant, frames


def build_base(scene: Scene, plant: Robot, integrator: IntegratorSpec) -> BaseModel | None:
    """The scene's moving base on ``plant`` (None for a fixed base); a UserInputError for a
    moving base with mimic joints or a kinematic one under the constraint stepper."""
    if scene.base.mode == "fixed":
        return None
    base = BaseModel.compile(scene.base, scene.robot, plant.nv, scene.gravity)
    if plant.mimic or (base.mode == "kinematic" and integrator_kind(integrator.method) == "stepper"):
        raise UserInputError(f"{scene.source}: base: a {base.mode} base takes neither mimic joints nor, "
                             "when kinematic, the constraint stepper")
    return base


# ---- contact -----------------------------------------------------------------------------------
def build_contact(scene: Scene, plant: Robot, frames: list[int | None]
                  ) -> tuple[ContactModel | None, tuple[int, ...], tuple[int, ...]]:
    """(the contact model on the plant, None in a scene without contact; the indices of the
    compliant (Hunt-Crossley) pairs; those of the impulsive (Newton) pairs)."""
    pairs = [Pair(p.name, *(next(i for i, g in enumerate(scene.geometries) if g.name == name)
                            for name in (p.geometry1, p.geometry2)), p.law) for p in scene.contacts]
    contact = ContactModel(plant.model, scene.geometries, frames, pairs) if scene.has_contact else None
    compliant = tuple(k for k, p in enumerate(pairs) if isinstance(p.law, HuntCrossley))
    impulsive = tuple(k for k, p in enumerate(pairs) if isinstance(p.law, NewtonImpact))
    return contact, compliant, impulsive


def build_stepper(scene: Scene, contact: ContactModel | None, integrator: IntegratorSpec) -> ConstraintStepper | None:
    """The constraint stepper of a scene integrated by one (None otherwise); a SceneError for
    a free body it cannot move (rotation coordinates other than the chart)."""
    if integrator_kind(integrator.method) != "stepper":
        return None
    for i, body in enumerate(scene.free_bodies):
        if body.rotation_coordinates != "chart":
            raise SceneError(scene.source, f"free_bodies[{i}].rotation_coordinates", "the constraint stepper "
                             f"({integrator.method}) moves free bodies on SE(3) with pin.integrate: give chart "
                             "(the default) or an ODE integrator", body.rotation_coordinates)
    return ConstraintStepper(contact, StepperSettings(solver=integrator.method))


def penetration_limits(scene: Scene, limits: DivergenceLimits) -> dict[str, float]:
    """The overlap (m) beyond which each contact pair, by name, is divergence."""
    shapes = {g.name: g.shape for g in scene.geometries}
    return {p.name: penetration_limit(shapes[p.geometry1], shapes[p.geometry2], limits.penetration_fraction)
            for p in scene.contacts}


# ---- the state layout --------------------------------------------------------------------------
def build_layout(scene: Scene, friction: JointFriction | None, compliant: tuple[int, ...],
                 base: BaseModel | None) -> StateLayout:
    """The continuous state's blocks (``BLOCKS`` order, empty ones left out) and their labels."""
    names = [spec.body.name for spec in scene.free_bodies]
    cardan = [spec.body.name for spec in scene.free_bodies if spec.rotation_coordinates == "cardan_adaptive"]
    lugre = [] if friction is None else list(friction.lugre_joints)
    pairs = [scene.contacts[k].name for k in compliant]
    moving = base is not None
    return StateLayout.for_joints(scene.robot.joint_names, {
        "base": POSE_LABELS if moving else (),
        "base_v": TWIST_LABELS if moving else (),
        "wheel_i": [f"{n}.integral" for n in base.mecanum.names] if moving and base.pi else (),
        "twist": [f"{n}.{a}" for n in names for a in _TWIST],
        "z": lugre,
        "pose": [f"{n}.{a}" for n in names for a in _POSE],
        "chart": [f"{n}.d{a}" for n in names for a in _TWIST],
        "cardan": [f"{n}.{a}" for n in cardan for a in _CARDAN],
        "s": pairs,
        "armed": pairs})


def velocity_bounds(layout: StateLayout, scene: Scene, base: BaseModel | None, limits: DivergenceLimits) -> np.ndarray:
    """The bound of each state component beyond which it is divergence: VELOCITY_LIMIT_FACTOR
    x a joint's URDF velocity limit (rad/s, m/s), the divergence limits' body speed (m/s) and
    spin (rad/s) for the free bodies' and the base's twists, inf elsewhere."""
    bounds = layout.velocity_bounds(scene.robot.velocity_limit, VELOCITY_LIMIT_FACTOR)
    bounds[layout.slice("twist")] = np.tile(np.repeat([limits.body_speed, limits.body_spin], 3),
                                            len(scene.free_bodies))
    if base is not None:  # the base's twist within the free bodies' speed and spin limits
        bounds[layout.slice("base_v")] = [limits.body_speed, limits.body_speed, limits.body_spin]
    return bounds


def velocity_index(layout: StateLayout, scene: Scene, base: BaseModel | None) -> slice | np.ndarray:
    """Where the plant's generalised velocity sits in x: the slice [v, twist], or with a moving
    base the index array [base_v, v, twist] (base, base_v and wheel_i lie between v and twist)."""
    velocity = layout.slice("v")
    if base is None:
        return slice(velocity.start, velocity.stop + 6 * len(scene.free_bodies))
    return np.r_[layout.slice("base_v"), velocity, layout.slice("twist")]


# ---- control -----------------------------------------------------------------------------------
def build_control(scene: Scene, friction: JointFriction | None, callback: ControllerCallback | None,
                  control_rate: float | None) -> Control:
    """The scene's controller and its reference (the initial pose, or the point-to-point
    trajectory through the scene's waypoints), with a Python ``callback``'s period (s):
    1 / ``control_rate`` (Hz, default the output rate); a UserInputError for a rate that
    gives no positive finite period."""
    spec = scene.controller
    trajectory = None if spec.trajectory is None else PointToPointTrajectory.through(
        np.vstack([scene.q0, spec.trajectory.waypoints]), spec.trajectory.v_max,
        spec.trajectory.a_max, spec.trajectory.dwell)
    period = None
    if callback is not None:
        period = 1.0 / (control_rate or scene.outputs.rate)
        if not math.isfinite(period) or period <= 0.0:
            raise UserInputError(f"{scene.source}: control_rate {control_rate!r} Hz must be positive")
    return Control(make_controller(spec.type, scene.robot, spec.kp, spec.kd, friction),
                   Reference(scene.q0, trajectory), callback, period)


def is_lossless(scene: Scene, friction: JointFriction | None, callback: ControllerCallback | None,
                base: BaseModel | None) -> bool:
    """Whether a passive scene also loses no energy (so that its energy is conserved): no
    joint friction, no contact pair, no Python controller, no floor friction under the base."""
    return friction is None and not scene.contacts and callback is None and (base is None or base.mu == 0.0)
