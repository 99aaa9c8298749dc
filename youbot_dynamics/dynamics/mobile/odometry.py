"""Wheel odometry on SE(2): the base pose in the odom frame (REP-105) from measured wheel
speeds, exact for a twist held constant over each step.

A pose is (x, y, theta): the position of base_footprint in odom (m) and its yaw (rad,
counter-clockwise, not wrapped, so that a count of turns survives). Over a step dt with the
body twist V = (vx, vy, wz) held constant the pose moves by the SE(2) exponential,

    T(t + dt) = T(t) exp([V] dt),

the planar case of the screw exponential (:func:`youbot_dynamics.model.lie.exp_se3` of the
twist (0, 0, wz, vx, vy, 0) dt): the body-frame displacement
((vx sin a - vy (1 - cos a)) / wz, (vx (1 - cos a) + vy sin a) / wz) with a = wz dt, and the
yaw advances by a. Not Euler: a circle driven at constant twist closes on itself.
"""
from __future__ import annotations

import math

import numpy as np

from youbot_dynamics.dynamics.mobile.mecanum import MecanumBase, base_twist
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.lie import exp_se3


def se2_step(pose: np.ndarray, twist: np.ndarray, dt: float) -> np.ndarray:
    """Pose (x, y, theta) after dt (s) at the constant body twist (vx, vy, wz): T exp([V] dt)."""
    x, y, theta = np.asarray(pose, dtype=float).ravel()
    vx, vy, wz = np.asarray(twist, dtype=float).ravel()
    displacement = exp_se3(np.array([0.0, 0.0, wz * dt, vx * dt, vy * dt, 0.0]))[:2, 3]
    c, s = math.cos(theta), math.sin(theta)
    return np.array([x + c * displacement[0] - s * displacement[1],
                     y + s * displacement[0] + c * displacement[1], theta + wz * dt])


def odometry_step(base: MecanumBase, pose: np.ndarray, speeds: np.ndarray, dt: float) -> np.ndarray:
    """Pose (x, y, theta) after dt (s) with the measured wheel speeds (rad/s, ``base.names``
    order) held over the step: the least-squares base twist, then :func:`se2_step`."""
    if not (math.isfinite(dt) and dt >= 0.0):
        raise UserInputError(f"odometry step: dt must be a finite non-negative time (s), got {dt}")
    return se2_step(pose, base_twist(base, speeds), dt)
