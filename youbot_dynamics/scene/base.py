"""The scene's ``base:`` section: how the youBot's base moves.

    base:
      mode: fixed | kinematic | dynamic        # default fixed: the base welded to the world
      wheels: [wheel_joint_fl, wheel_joint_fr, wheel_joint_bl, wheel_joint_br]   # the default
      initial: {pose: [x, y, yaw], twist: [vx, vy, wz]}   # m, rad; body frame m/s, rad/s
      path:                                    # the commanded base motion (optional)
        waypoints: [[x, y, yaw], ...]          # poses in the world (odom) frame, m and rad
        v_max: [vx, vy, wz]                    # per axis, m/s and rad/s (one number: all)
        a_max: [ax, ay, alpha]                 # per axis, m/s^2 and rad/s^2
        dwell: 0.5                             # s at each waypoint
      floor: {mu: 0.5, velocity_scale: 1.0e-3} # roller friction (dynamic): Coulomb mu, m/s
      controller: {kp: 0.5, ki: 5.0, torque_limit: 5.0, release: 2.0}   # wheel-speed PI (dynamic)

``kinematic``: the base follows the path exactly (at rest at ``initial.pose`` without one)
and the wheels roll without slip; the arm feels the base's acceleration. ``dynamic``: the
base is free in the plane; the wheels are pushed by the PI wheel-speed controller toward the
path's twist (the zero twist without a path: a brake) until ``release`` (s, default never),
free after it, or free throughout without a ``controller``; the floor acts through the
rollers. In both modes the wheel joints must be moving joints of the scene; the scene's
controller leaves them to the base (its torque there is replaced).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from youbot_dynamics.dynamics.mobile.mecanum import WHEEL_JOINTS
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.scene.reader import SceneError, SceneReader

BASE_MODES = ("fixed", "kinematic", "dynamic")
BASE_KEYS = ("mode", "wheels", "initial", "path", "floor", "controller")


@dataclass(frozen=True)
class BasePathSpec:
    """Waypoints (k, 3) of the base pose (x m, y m, yaw rad; world frame), the per-axis
    limits v_max (3,) and a_max (3,), the dwell (s) at each waypoint."""

    waypoints: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    dwell: float


@dataclass(frozen=True)
class BaseControllerSpec:
    """The wheel-speed PI: kp (N m s/rad), ki (N m/rad), torque_limit (N m per wheel) and the
    time (s) after which the wheels are released (inf: never)."""

    kp: float
    ki: float
    torque_limit: float
    release: float


@dataclass(frozen=True)
class BaseSpec:
    """The validated ``base:`` section (module docstring)."""

    mode: str = "fixed"
    wheels: tuple[str, ...] = WHEEL_JOINTS
    pose0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    twist0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    path: BasePathSpec | None = None
    mu: float = 0.0
    velocity_scale: float = 1e-3
    controller: BaseControllerSpec | None = None


def read_base(reader: SceneReader, value: Any, robot: Robot) -> BaseSpec:
    """The ``base:`` section of a scene (None or absent: a fixed base) against the scene's
    reduced ``robot`` (its moving joints)."""
    if value is None:
        return BaseSpec()
    data = reader.mapping(value, "base", BASE_KEYS)
    mode = data.get("mode", "fixed")
    if mode not in BASE_MODES:
        raise SceneError(reader.source, "base.mode", f"expected one of {', '.join(BASE_MODES)}", mode)
    if mode == "fixed":
        extra = [key for key in data if key != "mode"]
        if extra:
            raise SceneError(reader.source, f"base.{extra[0]}", "not used by a fixed base", data[extra[0]])
        return BaseSpec()
    wheels = _wheels(reader, data, robot)
    initial = reader.mapping(data.get("initial", {}), "base.initial", ("pose", "twist"))
    pose0 = tuple(reader.vector3(initial.get("pose", [0.0, 0.0, 0.0]), "base.initial.pose"))
    twist0 = tuple(reader.vector3(initial.get("twist", [0.0, 0.0, 0.0]), "base.initial.twist"))
    path = _path(reader, data["path"], pose0) if "path" in data else None
    mu, scale = _floor(reader, data.get("floor", {}))
    controller = _controller(reader, data["controller"]) if "controller" in data else None
    if mode == "kinematic" and (controller is not None or "floor" in data):
        key = "controller" if controller is not None else "floor"
        raise SceneError(reader.source, f"base.{key}", "not used by a kinematic base (it follows the path "
                         "exactly)", data[key])
    return BaseSpec(mode, wheels, pose0, twist0, path, mu, scale, controller)


def _wheels(reader: SceneReader, data: Mapping[str, Any], robot: Robot) -> tuple[str, ...]:
    """``base.wheels``: the four wheel joints, each a moving joint of the scene."""
    wheels = tuple(data.get("wheels", WHEEL_JOINTS))
    for i, name in enumerate(wheels):
        if name not in robot.joint_names:
            raise SceneError(reader.source, f"base.wheels[{i}]", "must be a moving joint of the scene (list it "
                             f"under 'moving'); moving: {', '.join(robot.joint_names)}", name)
    return wheels


def _floor(reader: SceneReader, value: Any) -> tuple[float, float]:
    """``base.floor``: the rollers' Coulomb coefficient mu (>= 0) and velocity scale (m/s)."""
    floor = reader.mapping(value, "base.floor", ("mu", "velocity_scale"))
    mu = reader.number(floor.get("mu", 0.0), "base.floor.mu")
    if mu < 0.0:
        raise SceneError(reader.source, "base.floor.mu", "must be >= 0", mu)
    return mu, reader.positive(floor.get("velocity_scale", 1e-3), "base.floor.velocity_scale")


def _controller(reader: SceneReader, value: Any) -> BaseControllerSpec:
    """``base.controller``: the wheel-speed PI's gains and torque limit, and its release time."""
    spec = reader.mapping(value, "base.controller", ("kp", "ki", "torque_limit", "release"))
    missing = [key for key in ("kp", "ki", "torque_limit") if key not in spec]
    if missing:
        raise SceneError(reader.source, f"base.controller.{missing[0]}", "missing: the wheel-speed PI needs "
                         "kp (N m s/rad), ki (N m/rad) and torque_limit (N m)")
    release = reader.positive(spec["release"], "base.controller.release") if "release" in spec else math.inf
    return BaseControllerSpec(*(reader.positive(spec[k], f"base.controller.{k}")
                                for k in ("kp", "ki", "torque_limit")), release)


def _path(reader: SceneReader, value: Any, pose0: tuple[float, ...]) -> BasePathSpec:
    data = reader.mapping(value, "base.path", ("waypoints", "v_max", "a_max", "dwell"))
    raw = data.get("waypoints")
    if not isinstance(raw, list) or not raw:
        raise SceneError(reader.source, "base.path.waypoints", "expected a non-empty list of [x, y, yaw]", raw)
    points = [np.asarray(pose0)] + [reader.vector3(p, f"base.path.waypoints[{i}]") for i, p in enumerate(raw)]
    limits = []
    for key in ("v_max", "a_max"):
        if key not in data:
            raise SceneError(reader.source, f"base.path.{key}", "missing: give the per-axis limit (x, y, yaw)")
        item = data[key]
        item = reader.vector3(item if isinstance(item, list) else [item] * 3, f"base.path.{key}")
        if not np.all(item > 0.0):
            raise SceneError(reader.source, f"base.path.{key}", "limits must be positive", item.tolist())
        limits.append(item)
    dwell = reader.number(data.get("dwell", 0.0), "base.path.dwell")
    if dwell < 0.0:
        raise SceneError(reader.source, "base.path.dwell", "must be >= 0 s", dwell)
    return BasePathSpec(np.array(points), *limits, dwell)
