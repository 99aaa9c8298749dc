"""The compiled mobile base of a scene (``base: kinematic | dynamic``): the planar root of
the plant, the commanded motion, the wheel-floor forces and the wheel-speed controller.

The root is Pinocchio's JointModelPlanar between the world and base_footprint:
configuration (x, y, cos yaw, sin yaw), velocity the body-frame twist (vx, vy, wz). The
engine's state holds the pose as (x, y, yaw) with yaw unwrapped, rates
d(x, y)/dt = R(yaw) (vx, vy), d yaw/dt = wz. That chart is global and exact: (x, y, yaw) in
R^3 is the universal cover of SE(2), so, unlike the free bodies' SE(3) charts, it needs no
reference pose, no folding guard and no normalisation, and every ODE integrator keeps the
root on its manifold (cos^2 + sin^2 = 1 by construction).

The kinematic base prescribes the root and the wheels: pose, twist and body-frame
acceleration from the path or from a twist command, which the base reaches within the
path's a_max (:class:`~youbot_dynamics.dynamics.mobile.ramp.TwistRamp`, both modes;
:meth:`BaseModel.command`), wheel speeds u = H V and
accelerations H dV/dt (no slip); the other degrees of freedom f obey
M_ff a_f = tau_f - (M_fp a_p + b)_f, the whole-body equations with the prescribed
accelerations a_p given (RNEA at (q, v, [a_p, 0]) gives M_fp a_p + b).

The dynamic base: each wheel's floor contact carries the normal load of the static weight
distribution of the robot's centre of mass (it moves with the arm;
:func:`~youbot_dynamics.dynamics.mobile.wheel_floor.wheel_normal_forces`, the carried free
bodies not counted, the acceleration's load transfer neglected), and the roller law
(:func:`~youbot_dynamics.dynamics.mobile.wheel_floor.roller_forces`; in the step one compiled
loop, :mod:`~youbot_dynamics.dynamics.mobile.floor_kernel`) acts on the contact point's slip: a force (Fx, Fy) at wheel i (hub at (x_i, y_i), base frame) is the
generalised force (Fx, Fy, x_i Fy - y_i Fx) on the root and -r F . d_i on the wheel. The wheel
torques come from the PI wheel-speed loop (:class:`~youbot_dynamics.dynamics.mobile
.base_controller.WheelSpeedPI`), its integral terms part of the state.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin
from numba import njit, types

from youbot_dynamics.compiled import unchecked
from youbot_dynamics.dynamics.mobile.base_controller import WheelSpeedPI
from youbot_dynamics.dynamics.mobile.mecanum import (MecanumBase, mecanum_base_from_robot,
                                                     wheel_speeds)
from youbot_dynamics.dynamics.mobile.ramp import DEFAULT_A_MAX, TwistRamp
from youbot_dynamics.dynamics.mobile.floor_kernel import roller_floor_force
from youbot_dynamics.dynamics.rigid_body import symmetrised
from youbot_dynamics.model.robot import Robot, URDFDocument, keep_joints, robot_from_urdf
from youbot_dynamics.scene.base import BaseSpec
from youbot_dynamics.sim.trajectory import POINTS, TIMING, PointToPointTrajectory, desired_motion


@njit(types.void(POINTS, TIMING, types.float64, types.Array(types.float64, 2, "C"),
                 types.Array(types.float64, 2, "C")), cache=True)
def _path_command(points: np.ndarray, timing: np.ndarray, t: float, motion: np.ndarray, out: np.ndarray) -> None:
    """A base path's command at t (s), :meth:`BaseModel.command`'s formula in one compiled
    call: motion = the path's (x, y, yaw), its rate and acceleration (world frame;
    :func:`~youbot_dynamics.sim.trajectory.desired_motion`, (3, 3)), out = the pose, the
    body-frame twist V = (R^T p', yaw') and dV/dt = (R^T p'' - yaw' S V_xy, yaw'') (3, 3;
    the Python form's operations in its order)."""
    if out.shape[0] != 3 or out.shape[1] != 3 or points.shape[1] != 3:
        raise ValueError("base command: a path of (x, y, yaw) points and a (3, 3) output")
    desired_motion(points, timing, t, motion)
    pose, rate, acceleration = motion[0], motion[1], motion[2]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    vx, vy = c * rate[0] + s * rate[1], -s * rate[0] + c * rate[1]
    ax, ay = c * acceleration[0] + s * acceleration[1], -s * acceleration[0] + c * acceleration[1]
    for i in range(3):
        out[0, i] = pose[i]
    out[1, 0], out[1, 1], out[1, 2] = vx, vy, rate[2]
    out[2, 0], out[2, 1], out[2, 2] = ax + rate[2] * vy, ay - rate[2] * vx, acceleration[2]


#: :func:`_path_command` without numba's type dispatch (a path's ``compiled`` arrays, a float t).
_path_command_unchecked = unchecked(_path_command)
#: the roller law without numba's type dispatch (float64 arrays: :meth:`BaseModel.floor_force`)
_roller_floor_force_unchecked = unchecked(roller_floor_force)

#: Labels of the base's state blocks: the pose (world frame) and the body-frame twist.
POSE_LABELS = ("base.x", "base.y", "base.yaw")
TWIST_LABELS = ("base.vx", "base.vy", "base.wz")


@dataclass(frozen=True)
class BaseMotion:
    """A kinematic base's motion at one instant: pose (x, y, yaw; world, m and rad; None
    under a twist command: the base integrates it), body
    twist (vx, vy, wz) and its rate, wheel speeds (rad/s) and accelerations (rad/s^2), the
    wheels in ``mecanum.names`` order."""

    pose: np.ndarray | None
    twist: np.ndarray
    acceleration: np.ndarray
    wheel_speeds: np.ndarray
    wheel_accelerations: np.ndarray


@dataclass(frozen=True, eq=False)
class BaseModel:
    """A scene's moving base, compiled (immutable). ``wheels``: indices of the wheel joints
    in the robot's joints, ``mecanum.names`` order; ``prescribed`` and ``free``: indices
    into the plant's velocity of what a kinematic base imposes (root and wheels) and of the
    rest; ``gravity`` (m/s^2) the magnitude the wheel loads use; ``a_max`` (m/s^2, m/s^2,
    rad/s^2; body frame) the acceleration limits a twist command is reached within: the
    path's, else :data:`~youbot_dynamics.dynamics.mobile.ramp.DEFAULT_A_MAX`."""

    mode: str
    mecanum: MecanumBase
    wheels: np.ndarray
    prescribed: np.ndarray
    free: np.ndarray
    path: PointToPointTrajectory | None
    pose0: np.ndarray
    twist0: np.ndarray
    mu: float
    velocity_scale: float
    pi: WheelSpeedPI | None
    release: float
    gravity: float
    a_max: np.ndarray

    @classmethod
    def compile(cls, spec: BaseSpec, robot: Robot, plant_nv: int, gravity: np.ndarray) -> BaseModel:
        """The base of ``spec`` for the scene's reduced fixed-root ``robot`` (its wheel
        geometry) on a plant of ``plant_nv`` velocities with a planar root."""
        mecanum = mecanum_base_from_robot(robot, spec.wheels)
        wheels = np.array([robot.joint_index(name) for name in spec.wheels], dtype=np.int64)
        prescribed = np.concatenate([np.arange(3), 3 + wheels])
        free = np.setdiff1d(np.arange(plant_nv), prescribed)
        path = None if spec.path is None else PointToPointTrajectory.through(
            spec.path.waypoints, spec.path.v_max, spec.path.a_max, spec.path.dwell)
        pi, release = None, math.inf
        if spec.controller is not None:
            c = spec.controller
            pi, release = WheelSpeedPI(mecanum, c.kp, c.ki, c.torque_limit), c.release
        a_max = np.array(DEFAULT_A_MAX if spec.path is None else spec.path.a_max, dtype=float)
        return cls(spec.mode, mecanum, wheels, prescribed, free, path, np.array(spec.pose0), np.array(spec.twist0),
                   spec.mu, spec.velocity_scale, pi, release, float(np.linalg.norm(gravity)), a_max)

    @property
    def dynamic(self) -> bool:
        """Whether the root is free (the floor and the wheel torques move it)."""
        return self.mode == "dynamic"

    # ---- the commanded motion -----------------------------------------------------------------
    def command(self, t: float, twist: TwistRamp | None = None) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
        """The commanded pose (x, y, yaw; world, m and rad), body-frame twist (vx, vy, wz) and
        its time derivative at t (s): a ``twist`` command's, reached within ``a_max`` (no
        pose: the base integrates it), else the path's, or rest at the initial pose.
        With R the path's yaw rotation, V = (R^T p', yaw') and
        dV/dt = (R^T p'' - yaw' S V_xy, yaw'') with S (vx, vy) = (-vy, vx)."""
        if twist is not None:
            return None, *twist.at(t)
        if self.path is None:
            return self.pose0, np.zeros(3), np.zeros(3)
        points, timing = self.path.compiled
        motion, out = np.empty((3, 3)), np.empty((3, 3))
        _path_command_unchecked(points, timing, float(t), motion, out)
        return out[0], out[1], out[2]

    def motion(self, t: float, twist: TwistRamp | None = None) -> BaseMotion:
        """The commanded motion at t (s) (of a ``twist`` command if given) with the wheels rolling
        without slip along it: speeds H V and accelerations H dV/dt."""
        pose, twist, acceleration = self.command(t, twist)
        return BaseMotion(pose, twist, acceleration, wheel_speeds(self.mecanum, twist),
                          wheel_speeds(self.mecanum, acceleration))

    # ---- the planar root ------------------------------------------------------------------------
    @staticmethod
    def root_configuration(pose: np.ndarray) -> np.ndarray:
        """Pinocchio's planar configuration (x, y, cos yaw, sin yaw) of a pose (x, y, yaw)."""
        return np.array([pose[0], pose[1], math.cos(pose[2]), math.sin(pose[2])])

    @staticmethod
    def pose_rate(pose: np.ndarray, twist: np.ndarray) -> np.ndarray:
        """d(x, y, yaw)/dt (world frame) at the body-frame twist (vx, vy, wz)."""
        c, s = math.cos(pose[2]), math.sin(pose[2])
        return np.array([c * twist[0] - s * twist[1], s * twist[0] + c * twist[1], twist[2]])

    @staticmethod
    def unwrapped_pose(root: np.ndarray, previous_yaw: float) -> np.ndarray:
        """(x, y, yaw) of a planar configuration, the yaw taken within pi of ``previous_yaw``."""
        yaw = math.atan2(root[3], root[2])
        return np.array([root[0], root[1], previous_yaw + math.remainder(yaw - previous_yaw, 2.0 * math.pi)])

    # ---- forces --------------------------------------------------------------------------------
    def wheel_loads(self, plant: pin.Model, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Normal force (N) on each wheel: the static weight distribution of the robot's
        centre of mass (the root joint's subtree: free bodies left out) at configuration q."""
        pin.centerOfMass(plant, data, q, True)  # subtree centres of mass, each in its joint's frame
        # wheel_normal_forces without a load transfer (its checks hold by construction here)
        x, y, _ = data.com[1].tolist()
        return self.mecanum.support.loads_at(x, y, data.mass[1] * self.gravity)

    def floor_force(self, plant: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Generalised force (plant nv; N, N m) of the roller friction at the four contacts
        at plant state (q, v)."""
        generalised = np.zeros(plant.nv)
        if self.mu == 0.0:
            return generalised
        mecanum = self.mecanum
        v = np.asarray(v, dtype=float)
        if v.shape != (plant.nv,):      # the kernel reads v at the base's and wheels' dofs unchecked
            raise ValueError(f"floor force: v needs the plant's nv = {plant.nv} velocities, got shape {v.shape}")
        # the loads, hub velocities (numpy's product) and the base's tables are float64 too
        _roller_floor_force_unchecked(v, self.wheel_loads(plant, data, q), mecanum.hub_velocities(v[:3]),
                                      mecanum.positions, mecanum.drive_directions, mecanum.across, mecanum.radius,
                                      self.mu, self.velocity_scale, self.wheels, generalised)
        return generalised

    def wheel_torques(self, t: float, speeds: np.ndarray, integral: np.ndarray,
                      twist: TwistRamp | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(torque N m, d integral/dt N m/s) of the PI loop per wheel (``mecanum.names``
        order) toward the commanded twist at t (s) (``twist`` if given, else the path's);
        zero once released or without a loop (a step asks once: the engine hands the rate on
        with the torque, :func:`~youbot_dynamics.sim.engine.controlled_torque`)."""
        if self.pi is None or t >= self.release:
            return np.zeros(len(self.wheels)), np.zeros(len(self.wheels))
        return self.pi.torques(self.command(t, twist)[1], speeds, integral)

    def prescribed_accelerations(self, plant: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray,
                                 generalised: np.ndarray, imposed: np.ndarray) -> np.ndarray:
        """The plant's accelerations (nv) with the root's and the wheels' given (``imposed``,
        ``prescribed`` order) under the generalised force on the free ones:
        a_f = M_ff^-1 (tau_f - (M_fp a_p + b)_f)."""
        a = np.zeros(plant.nv)
        a[self.prescribed] = imposed
        bias = pin.rnea(plant, data, q, v, a)
        mass = symmetrised(pin.crba(plant, data, q))
        free = self.free
        a[free] = np.linalg.solve(mass[np.ix_(free, free)], generalised[free] - bias[free])
        return a


def planar_robot(urdf: URDFDocument, moving: Sequence[str], locked: Mapping[str, float]) -> Robot:
    """The scene's reduced robot (from its URDF as the scene read it) with a planar root
    (Pinocchio's planar joint between the world and its root link)."""
    return keep_joints(robot_from_urdf(urdf, "planar"), moving, locked)
