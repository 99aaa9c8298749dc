"""Mecanum-wheel kinematics of the youBot base: wheel speeds from the base twist and back.

One formula (Lynch & Park, *Modern Robotics* section 13.2, omnidirectional wheels): a wheel
grips the floor only across the axis of the roller that touches it, so the contact point
has no velocity along n_i, the floor-plane normal of that roller axis:

    n_i . (v_hub,i - r u_i d_i) = 0   =>   u_i = n_i . v_hub,i / (r n_i . d_i),
    v_hub,i = (vx - wz y_i, vy + wz x_i),

with the base twist V = (vx, vy, wz), the hub position (x_i, y_i), the radius r and the
drive direction d_i (the way the hub moves when the wheel turns by +u_i on the floor,
d_i = a_i x z for the spin axis a_i). Stacked: u = H V with H (4 x 3); back, by least
squares: V = H^+ u (exact when the wheel speeds agree with one twist, the least-squares
twist when they do not: slip).

Frames and signs (REP-103, REP-105): V is the body twist of base_footprint, vx forward
(m/s), vy to the left (m/s), wz counter-clockwise seen from above (rad/s). Wheels, always in
the order WHEEL_JOINTS and matched by name:

    wheel_joint_fl front-left  (+lx, +ly)     wheel_joint_fr front-right (+lx, -ly)
    wheel_joint_bl back-left   (-lx, +ly)     wheel_joint_br back-right  (-lx, -ly)

A wheel speed u_i (rad/s) is the rate of its URDF joint: a rotation about the joint axis,
+y of base_link for all four wheels in urdf/youbot.urdf, so u_i > 0 rolls every wheel
forward (d_i = +x). The youBot driver counts the left wheels the other way round (its
motors face outwards): its speeds are (-u_fl, u_fr, -u_bl, u_br) (test_mecanum checks it).

Rollers (45 degrees): the axis of the roller touching the floor runs along (1, 1)/sqrt 2 on
the fl and br wheels and along (1, -1)/sqrt 2 on fr and bl (base frame, seen from above).
Hence, for the youBot:

    u_fl = (vx - vy - (lx + ly) wz) / r     u_fr = (vx + vy + (lx + ly) wz) / r
    u_bl = (vx + vy - (lx + ly) wz) / r     u_br = (vx - vy + (lx + ly) wz) / r

Figures: youbot_driver config/youbot-base.cfg (wheel radius 0.0475 m, front-rear wheel
distance 0.47 m, left-right 0.3 m), the driver's kinematics. The URDF's wheel joints stand at
x = +-0.228, y = +-0.158 m (lx + ly = 0.386 m against the driver's 0.385 m):
:func:`mecanum_base_from_robot` takes the geometry from a loaded URDF instead.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from youbot_dynamics.compiled import FLOAT
from youbot_dynamics.dynamics.mobile.support import SupportRule
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot

WHEEL_JOINTS = ("wheel_joint_fl", "wheel_joint_fr", "wheel_joint_bl", "wheel_joint_br")
#: youbot_driver config/youbot-base.cfg.
YOUBOT_WHEEL_RADIUS = 0.0475  # m
YOUBOT_FRONT_REAR = 0.47  # m, distance between the front and the rear axles
YOUBOT_LEFT_RIGHT = 0.3  # m, distance between the left and the right wheels
_DIAGONAL = 1.0 / math.sqrt(2.0)
#: Axis of the roller touching the floor, base frame (x, y), per wheel joint.
YOUBOT_ROLLER_AXES: Mapping[str, tuple[float, float]] = {
    "wheel_joint_fl": (_DIAGONAL, _DIAGONAL), "wheel_joint_fr": (_DIAGONAL, -_DIAGONAL),
    "wheel_joint_bl": (_DIAGONAL, -_DIAGONAL), "wheel_joint_br": (_DIAGONAL, _DIAGONAL)}


@dataclass(frozen=True)
class MecanumBase:
    """Geometry of a base on mecanum wheels, one row per wheel in ``names`` order.

    ``positions`` (n, 2): hub positions (x, y) in base_footprint (m); ``drive_directions``
    (n, 2): unit direction the hub moves for a positive wheel speed; ``roller_axes`` (n, 2):
    unit axis of the contact roller; ``radius`` (m). ``jacobian`` H maps the base twist
    (vx, vy, wz) to the wheel speeds (rad/s); ``pseudo_inverse`` H^+ maps them back. Built
    once with the geometry: ``hub_maps`` (:func:`hub_velocity_maps`), ``across`` (n, 2) the
    unit floor-plane directions across the contact rollers (z x e / |e|) and ``support`` the
    wheels' load rule (:class:`~youbot_dynamics.dynamics.mobile.support.SupportRule`).
    """

    names: tuple[str, ...]
    positions: np.ndarray
    drive_directions: np.ndarray
    roller_axes: np.ndarray
    radius: float
    jacobian: np.ndarray = field(init=False, repr=False)
    pseudo_inverse: np.ndarray = field(init=False, repr=False)
    hub_maps: np.ndarray = field(init=False, repr=False)
    across: np.ndarray = field(init=False, repr=False)
    support: SupportRule = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = len(self.names)
        for name in ("positions", "drive_directions", "roller_axes"):
            array = np.array(getattr(self, name), dtype=float)
            if array.shape != (n, 2) or not np.all(np.isfinite(array)):
                raise UserInputError(f"mecanum base: {name} must be {n} finite (x, y) rows, one per "
                                     f"wheel {', '.join(self.names)}; got shape {array.shape}")
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        if not (math.isfinite(self.radius) and self.radius > 0.0):
            raise UserInputError(f"mecanum base: wheel radius must be a positive length (m), got {self.radius}")
        jacobian = mecanum_jacobian(self.positions, self.drive_directions, self.roller_axes, self.radius)
        if np.linalg.matrix_rank(jacobian) < 3:
            raise UserInputError(f"mecanum base with wheels {', '.join(self.names)}: the wheel speeds do not "
                                 "determine the base twist (rank of H below 3); check the roller axes")
        pseudo = np.linalg.pinv(jacobian)
        maps = hub_velocity_maps(self.positions)
        across = np.array([normal / math.hypot(*normal) for normal in roller_normals(self.roller_axes)])
        for array in (jacobian, pseudo, maps, across):
            array.setflags(write=False)
        object.__setattr__(self, "jacobian", jacobian)
        object.__setattr__(self, "pseudo_inverse", pseudo)
        object.__setattr__(self, "hub_maps", maps)
        object.__setattr__(self, "across", across)
        object.__setattr__(self, "support", SupportRule(self.positions))

    def hub_velocities(self, twist: np.ndarray) -> np.ndarray:
        """(n, 2) velocities (m/s, base frame) of the wheel hubs for the base twist
        (vx, vy, wz): v_i = (vx - wz y_i, vy + wz x_i)."""
        return self.hub_maps @ _twist(twist)


def hub_velocity_maps(positions: np.ndarray) -> np.ndarray:
    """(n, 2, 3): for each hub at (x_i, y_i) (m) the map [[1, 0, -y_i], [0, 1, x_i]] of the base
    twist (vx, vy, wz) to the hub's velocity (m/s, base frame)."""
    maps = np.zeros((len(positions), 2, 3))
    maps[:, 0, 0] = maps[:, 1, 1] = 1.0
    maps[:, 0, 2], maps[:, 1, 2] = -positions[:, 1], positions[:, 0]
    return maps


def roller_normals(roller_axes: np.ndarray) -> np.ndarray:
    """n = z x e for roller axes e ((2,) or (n, 2), base frame): the floor-plane direction
    across each contact roller, along which the wheel grips."""
    axes = np.asarray(roller_axes, dtype=float)
    return np.stack([-axes[..., 1], axes[..., 0]], axis=-1)


def mecanum_jacobian(positions: np.ndarray, drive_directions: np.ndarray, roller_axes: np.ndarray,
                     radius: float) -> np.ndarray:
    """H (n x 3): row i = n_i^T [[1, 0, -y_i], [0, 1, x_i]] / (r n_i . d_i), the no-slip
    condition across roller i (module docstring); n_i = z x e_i for the roller axis e_i, and
    the matrix is the hub's velocity map (:func:`hub_velocity_maps`)."""
    normals = roller_normals(roller_axes)
    grip = np.einsum("ij,ij->i", normals, drive_directions)
    if np.any(np.abs(grip) < 1e-9):
        raise UserInputError("mecanum base: a roller axis runs along its wheel's drive direction, so the "
                             "wheel cannot push the base (n . d = 0); check the roller axes")
    return np.einsum("ij,ijk->ik", normals, hub_velocity_maps(positions)) / (radius * grip)[:, None]


def wheel_speeds(base: MecanumBase, twist: np.ndarray) -> np.ndarray:
    """Wheel speeds u = H V (rad/s, ``base.names`` order) for the base twist (vx, vy, wz)
    (m/s, m/s, rad/s, base_footprint) (inverse kinematics)."""
    return base.jacobian @ _twist(twist)


def base_twist(base: MecanumBase, speeds: np.ndarray) -> np.ndarray:
    """Base twist (vx, vy, wz) = H^+ u from wheel speeds (rad/s, ``base.names`` order): the
    least-squares twist (forward kinematics)."""
    u = np.asarray(speeds, dtype=float).ravel()
    if u.shape != (len(base.names),):
        raise UserInputError(f"wheel speeds: expected {len(base.names)} values for {', '.join(base.names)}, "
                             f"got {u.size}")
    return base.pseudo_inverse @ u


def youbot_base(front_rear: float = YOUBOT_FRONT_REAR, left_right: float = YOUBOT_LEFT_RIGHT,
                radius: float = YOUBOT_WHEEL_RADIUS) -> MecanumBase:
    """The youBot base of the driver's figures (defaults) or the given axle distances (m)."""
    lx, ly = 0.5 * front_rear, 0.5 * left_right
    corners = {"fl": (lx, ly), "fr": (lx, -ly), "bl": (-lx, ly), "br": (-lx, -ly)}
    return MecanumBase(names=WHEEL_JOINTS,
                       positions=np.array([corners[name.rsplit("_", 1)[1]] for name in WHEEL_JOINTS]),
                       drive_directions=np.tile([1.0, 0.0], (len(WHEEL_JOINTS), 1)),
                       roller_axes=np.array([YOUBOT_ROLLER_AXES[name] for name in WHEEL_JOINTS]),
                       radius=radius)


def mecanum_base_from_robot(robot: Robot, names: Sequence[str] = WHEEL_JOINTS,
                            roller_axes: Mapping[str, Sequence[float]] = YOUBOT_ROLLER_AXES,
                            radius: float = YOUBOT_WHEEL_RADIUS) -> MecanumBase:
    """The base geometry of a loaded URDF: hub positions and drive directions d = a x z of
    the wheel joints ``names`` at the zero configuration, in the root link's frame (the
    URDF's, base_footprint for the youBot); the roller axes and radius as given (the URDF
    holds plain wheels)."""
    positions, drives = [], []
    for name in names:
        joint = next((j for j in robot.tree if j.name == name), None)
        if joint is None or joint.type not in ("continuous", "revolute"):
            raise UserInputError(f"robot '{robot.name}' ({robot.source}): no revolute or continuous wheel "
                                 f"joint '{name}'")
        pose = np.eye(4)
        for step in robot.chain_to(joint.child):
            pose = pose @ step.origin
        axis = pose[:3, :3] @ joint.axis
        drive = np.cross(axis, [0.0, 0.0, 1.0])[:2]
        if np.linalg.norm(drive) < 1e-9:
            raise UserInputError(f"robot '{robot.name}' ({robot.source}): wheel joint '{name}' spins about "
                                 f"the vertical (axis {axis.round(6).tolist()} in the root frame)")
        positions.append(pose[:2, 3])
        drives.append(drive / np.linalg.norm(drive))
    missing = [name for name in names if name not in roller_axes]
    if missing:
        raise UserInputError(f"mecanum base: no roller axis for wheel(s) {', '.join(missing)}")
    return MecanumBase(names=tuple(names), positions=np.array(positions), drive_directions=np.array(drives),
                       roller_axes=np.array([roller_axes[name] for name in names], dtype=float),
                       radius=radius)


def _twist(twist: np.ndarray) -> np.ndarray:
    """(vx, vy, wz) as a float array of 3, or a UserInputError (a float64 vector of 3 as it is:
    the step's twists, without numpy's conversion calls)."""
    if type(twist) is np.ndarray and twist.dtype is FLOAT and twist.shape == (3,):
        return twist
    v = np.asarray(twist, dtype=float).ravel()
    if v.shape != (3,):
        raise UserInputError(f"base twist: expected 3 values (vx m/s, vy m/s, wz rad/s), got {v.size}")
    return v
