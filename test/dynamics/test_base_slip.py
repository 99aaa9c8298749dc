"""The base pieces composed: a planar rigid base on four mecanum wheels, driven by the PI
wheel-speed controller through the roller friction law, with the normal loads of the weight.

Not the engine's model (that is Pinocchio's whole-body one): a reduced one written here, in
the test, to check that the pieces fit. Below the friction limit the base follows the command
and the odometry of the wheel speeds follows the true pose; above it the wheels slip and the
acceleration saturates at the limit. For 45-degree rollers that limit is mu g / sqrt 2, not
mu g: a wheel pushes only across its contact roller, at 45 degrees to the drive direction, so
per wheel |F| = sqrt 2 tau / r carries a forward force tau / r, and |F| <= mu N."""
from __future__ import annotations

import math

import numpy as np

from youbot_dynamics.dynamics.mobile.base_controller import WheelSpeedPI
from youbot_dynamics.dynamics.mobile.mecanum import roller_normals, youbot_base
from youbot_dynamics.dynamics.mobile.odometry import odometry_step
from youbot_dynamics.dynamics.mobile.wheel_floor import (contact_slip_velocities, roller_forces,
                                                         wheel_normal_forces, wheel_spin_torques)
from youbot_dynamics.integrate.integrators import integrate

BASE = youbot_base()
MASS, YAW_INERTIA, WHEEL_INERTIA = 36.06, 3.7, 0.0152  # kg, kg m^2, kg m^2 (the URDF youBot's figures, rounded)
MU, VELOCITY_SCALE, G = 0.5, 1e-3, 9.81
LOADS = wheel_normal_forces(BASE, MASS, [0.0, 0.0], gravity=G)
LIMIT_ACCELERATION = MU * G / math.sqrt(2.0)  # 3.468 m/s^2


def rhs_of(controller: WheelSpeedPI, command: np.ndarray):
    """x = (x, y, theta, vx, vy, wz (body frame), u (4 wheel speeds), I (4 integral terms))."""
    def rhs(t, s):
        theta, twist, speeds, integral = s[2], s[3:6], s[6:10], s[10:14]
        forces = roller_forces(BASE, contact_slip_velocities(BASE, twist, speeds), LOADS, MU, VELOCITY_SCALE)
        total = forces.sum(axis=0)
        moment = float(np.sum(BASE.positions[:, 0] * forces[:, 1] - BASE.positions[:, 1] * forces[:, 0]))
        tau, rate = controller.torques(command, speeds, integral)
        c, s_ = math.cos(theta), math.sin(theta)
        vx, vy, wz = twist
        return np.concatenate([[c * vx - s_ * vy, s_ * vx + c * vy, wz,
                                total[0] / MASS + wz * vy, total[1] / MASS - wz * vx, moment / YAW_INERTIA],
                               (tau + wheel_spin_torques(BASE, forces)) / WHEEL_INERTIA, rate])
    return rhs


def run(torque_limit: float, command, t_end: float, n_out: int = 51):
    controller = WheelSpeedPI(BASE, kp=0.5, ki=5.0, torque_limit=torque_limit)
    return integrate(rhs_of(controller, np.asarray(command, dtype=float)), np.zeros(14),
                     np.linspace(0.0, t_end, n_out), "radau", rtol=1e-8, atol=1e-10)


def across_rollers(state: np.ndarray) -> np.ndarray:
    """Slip (m/s) of each contact point across its roller: the part friction resists (along
    the roller the contact point moves freely, the roller turning)."""
    slips = contact_slip_velocities(BASE, state[3:6], state[6:10])
    return np.einsum("ij,ij->i", slips, roller_normals(BASE.roller_axes))


def torque_for(acceleration: float) -> float:
    """Wheel torque (N m) whose forward force tau / r per wheel accelerates the whole base at
    ``acceleration`` (m/s^2), the wheels' own inertia aside."""
    return acceleration * MASS * BASE.radius / 4


def test_below_the_friction_limit_the_base_follows_and_odometry_holds():
    command = np.array([0.3, 0.2, 0.4])
    solution = run(torque_for(0.5 * LIMIT_ACCELERATION), command, 2.0, n_out=201)
    slips = np.array([across_rollers(s) for s in solution.x])
    assert np.abs(slips).max() < 20 * VELOCITY_SCALE  # creep of the regularised law: measured 4.4e-4 m/s
    assert np.allclose(solution.x[-1, 3:6], command, atol=1e-3)  # measured 4.8e-5
    pose = np.zeros(3)  # odometry of the wheel speeds, held over each output interval
    for k in range(len(solution.t) - 1):
        pose = odometry_step(BASE, pose, 0.5 * (solution.x[k, 6:10] + solution.x[k + 1, 6:10]),
                             solution.t[k + 1] - solution.t[k])
    assert np.linalg.norm(pose[:2] - solution.x[-1, :2]) < 5e-3  # measured 1.8e-4 m after 2 s


def test_above_the_friction_limit_the_wheels_slip_and_acceleration_saturates():
    solution = run(torque_for(2.0 * LIMIT_ACCELERATION), [1.0, 0.0, 0.0], 0.2)
    k = np.searchsorted(solution.t, 0.1)
    acceleration = (solution.x[k, 3] - solution.x[k - 5, 3]) / (solution.t[k] - solution.t[k - 5])
    assert math.isclose(acceleration, LIMIT_ACCELERATION, rel_tol=1e-2)  # measured 8.5e-5 off
    assert np.all(np.abs(across_rollers(solution.x[k])) > 50 * VELOCITY_SCALE)  # measured 0.086 m/s, growing
