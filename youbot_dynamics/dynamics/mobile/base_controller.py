"""Base velocity controller: the commanded twist becomes wheel-speed set points (mecanum
inverse kinematics) and a PI loop on each wheel's speed turns the error into a wheel torque,
saturated at the wheel torque limit, with back-calculation anti-windup (Astrom & Hagglund,
*Advanced PID Control*, 2006, section 3.5):

    e = u_ref - u                       (rad/s; u_ref = H V_cmd)
    tau_raw = kp e + I                  (N m; I is the integral term, in N m)
    tau = clip(tau_raw, -tau_max, tau_max)
    dI/dt = ki e + (tau - tau_raw) / T_t

While the torque is within its limit the last term is zero and I integrates ki e; once it
saturates, I relaxes with the tracking time T_t (s) towards the value that keeps tau_raw
near the limit, instead of winding up. kp in N m s/rad, ki in N m/rad.

The integral term I (one per wheel) is state: the engine carries it and integrates dI/dt
(:meth:`WheelSpeedPI.torques`), a sampled controller steps it (:meth:`WheelSpeedPI.step`).
The law after u_ref runs compiled (:func:`pi_law`, numba: numpy's operations per wheel in
their order, so the same bits).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numba import njit, types

from youbot_dynamics.compiled import FLOAT, unchecked
from youbot_dynamics.dynamics.mobile.mecanum import WHEEL_JOINTS, MecanumBase, wheel_speeds
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot


_READ = types.Array(types.float64, 1, "A", readonly=True)
_OUT = types.Array(types.float64, 1, "C")


@njit(types.void(_READ, _READ, _READ, types.float64, types.float64, _READ, types.float64, _OUT, _OUT), cache=True)
def pi_law(reference: np.ndarray, speeds: np.ndarray, integral: np.ndarray, kp: float, ki: float,
           limit: np.ndarray, tracking_time: float, tau: np.ndarray, rate: np.ndarray) -> None:
    """The module docstring's law per wheel: tau (N m) and dI/dt (N m/s) from the set points
    u_ref and speeds u (rad/s), the integral terms I (N m) and the limits tau_max (N m); the
    clip as numpy's maximum then minimum (a NaN passes through)."""
    n = reference.shape[0]
    if speeds.shape[0] != n or integral.shape[0] != n or limit.shape[0] != n or tau.shape[0] != n \
            or rate.shape[0] != n:
        raise ValueError("wheel speed PI: one set point, speed, integral term, limit and output per wheel")
    for i in range(n):
        error = reference[i] - speeds[i]
        raw = kp * error + integral[i]
        low = raw if raw >= -limit[i] or raw != raw else -limit[i]
        tau[i] = low if low <= limit[i] or low != low else limit[i]
        rate[i] = ki * error + (tau[i] - raw) / tracking_time


#: :func:`pi_law` without numba's type dispatch (float64 vectors: :func:`_float_vector`).
_pi_law_unchecked = unchecked(pi_law)


def _float_vector(values: np.ndarray) -> np.ndarray:
    """``values`` as a float64 vector (any strides: the law's arrays are of layout "A"); an
    array of another shape is refused."""
    if not (type(values) is np.ndarray and values.dtype is FLOAT):
        values = np.asarray(values, dtype=float)
    if values.ndim != 1:
        raise ValueError(f"wheel speed PI: speeds and integral terms are vectors, got shape {values.shape}")
    return values


@dataclass(frozen=True)
class WheelSpeedPI:
    """PI wheel-speed loop of a mecanum base with torque saturation and anti-windup (module
    docstring). ``torque_limit``: N m, one for all wheels or one per wheel (``base.names``
    order); ``tracking_time`` T_t (s), by default the integral time kp / ki."""

    base: MecanumBase
    kp: float
    ki: float
    torque_limit: float | Sequence[float]
    tracking_time: float | None = None

    def __post_init__(self) -> None:
        limit = np.broadcast_to(np.asarray(self.torque_limit, dtype=float), (len(self.base.names),)).copy()
        if not np.all(np.isfinite(limit) & (limit > 0.0)):
            raise UserInputError(f"wheel speed controller: torque_limit must be positive and finite (N m) for "
                                 f"each of {', '.join(self.base.names)}, got {self.torque_limit!r}")
        for name, value in (("kp", self.kp), ("ki", self.ki)):
            if not (math.isfinite(value) and value > 0.0):
                raise UserInputError(f"wheel speed controller: {name} must be positive and finite, got {value!r}")
        tracking = self.kp / self.ki if self.tracking_time is None else float(self.tracking_time)
        if not tracking > 0.0:
            raise UserInputError(f"wheel speed controller: tracking_time must be positive (s), got {tracking!r}")
        limit.setflags(write=False)
        object.__setattr__(self, "torque_limit", limit)
        object.__setattr__(self, "tracking_time", tracking)

    def torques(self, twist_command: np.ndarray, speeds: np.ndarray,
                integral: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(tau (N m), dI/dt (N m/s)) per wheel for the commanded base twist (vx, vy, wz), the
        measured wheel speeds (rad/s) and the integral terms I (N m)."""
        n = len(self.base.names)
        tau, rate = np.empty(n), np.empty(n)
        speeds, integral = _float_vector(speeds), _float_vector(integral)
        _pi_law_unchecked(wheel_speeds(self.base, twist_command), speeds, integral, self.kp, self.ki,
                          self.torque_limit, self.tracking_time, tau, rate)  # the sizes checked in the law
        return tau, rate

    def step(self, twist_command: np.ndarray, speeds: np.ndarray, integral: np.ndarray,
             dt: float) -> tuple[np.ndarray, np.ndarray]:
        """A sampled controller's period dt (s): (tau held over the period (N m), the
        integral terms at its end (N m)), I <- I + dt dI/dt."""
        tau, rate = self.torques(twist_command, speeds, integral)
        return tau, np.asarray(integral, dtype=float) + dt * rate


def wheel_torque_limits(robot: Robot, names: Sequence[str] = WHEEL_JOINTS) -> np.ndarray:
    """The URDF effort limits (N m) of the wheel joints ``names``; a wheel without a finite
    ``<limit effort>`` (a plain continuous joint) is an error asking for one."""
    limits = []
    for name in names:
        limit = float(robot.effort_limit[robot.joint_index(name)])
        if not (math.isfinite(limit) and limit > 0.0):
            raise UserInputError(f"robot '{robot.name}' ({robot.source}): wheel joint '{name}' has no finite "
                                 "effort limit; give the controller a torque_limit (N m) or add "
                                 "<limit effort=...> to the joint")
        limits.append(limit)
    return np.array(limits)
