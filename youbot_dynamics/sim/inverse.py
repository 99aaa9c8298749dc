"""Inverse dynamics of measured motion: accelerations estimated from joint-state samples,
then tau = RNEA(q, v, a) + tau_friction(v).

Acceleration estimate (for samples q_k, v_k at times t_k, spacing not necessarily even):
the central difference of velocity

    a_hat(t_k) = (v_{k+1} - v_{k-1}) / (t_{k+1} - t_{k-1}),

published one sample late (at t_k, with q_k, v_k). Because v is the integral of a, this is
exactly the mean of a(s) over the window [t_{k-1}, t_{k+1}] (a box-car filter of the
acceleration, zero phase lag at t_k). Hence the bound used by the tests:

    |a_hat_i(t_k) - a_i(t_k)| <= max_{s in [t_{k-1}, t_{k+1}]} |a_i(s) - a_i(t_k)|,

and the torque error M(q_k) (a_hat - a) satisfies, per joint i,

    |tau_hat_i - tau_i| <= sum_j |M_ij(q_k)| max_s |a_j(s) - a_j(t_k)|,

whatever the smoothness of a (jumps of a_d in a trapezoidal profile included). For smooth a
and even spacing h it is a''(t_k) h^2 / 6 + O(h^4). Optionally (``time_constant`` > 0 s)
a first-order low-pass a_f += alpha (a_hat - a_f), alpha = dt / (time_constant + dt), damps
measurement noise; the bound above then no longer holds (it adds lag).

Friction: the scene's model at the measured velocity; LuGre bristles are taken at their
steady state for v (the bristle deflection cannot be measured).
"""
from __future__ import annotations

import numpy as np

from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import inverse_dynamics
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.sim.commands import NS_PER_S, InputRejected, JointSample


class AccelerationEstimator:
    """Central differences of velocity over the last three samples (see the module docstring)."""

    def __init__(self, time_constant: float = 0.0) -> None:
        if not time_constant >= 0.0:
            raise ValueError(f"acceleration filter time constant must be >= 0 s, got {time_constant}")
        self.time_constant = float(time_constant)
        self.clear()

    def clear(self) -> None:
        """Forget the samples (after a jump in time, e.g. a replay that restarts)."""
        self.samples: list[JointSample] = []
        self.filtered: np.ndarray | None = None

    def push(self, sample: JointSample) -> tuple[JointSample, np.ndarray] | None:
        """Add a sample; returns (the middle sample, its acceleration estimate rad/s^2) once
        three are known. A sample not later than the previous one raises ``bad_timing``.
        Time differences are taken between integer-nanosecond stamps, exact at any
        magnitude (wall-clock stamps included)."""
        if self.samples and not sample.stamp_ns > self.samples[-1].stamp_ns:
            raise InputRejected("bad_timing", f"sample stamped {sample.stamp_ns} ns is not after the previous "
                                f"one at {self.samples[-1].stamp_ns} ns")
        self.samples = [*self.samples[-2:], sample]
        if len(self.samples) < 3:
            return None
        before, middle, after = self.samples
        estimate = (after.v - before.v) / ((after.stamp_ns - before.stamp_ns) / NS_PER_S)
        if self.time_constant > 0.0 and self.filtered is not None:
            dt = (after.stamp_ns - middle.stamp_ns) / NS_PER_S
            alpha = dt / (self.time_constant + dt)
            estimate = self.filtered + alpha * (estimate - self.filtered)
        self.filtered = estimate
        return middle, estimate


class InverseDynamics:
    """tau = RNEA(q, v, a) + tau_friction(v) for a robot and its friction model (or None)."""

    def __init__(self, robot: Robot, friction: JointFriction | None) -> None:
        self.robot, self.friction = robot, friction
        self.data = robot.model.createData()

    def torque(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Joint torques (N m, N) in joint order."""
        z = None if self.friction is None or self.friction.lugre is None else self.friction.steady_state_bristles(v)
        return inverse_dynamics(self.robot, self.data, q, v, a, self.friction, z)
