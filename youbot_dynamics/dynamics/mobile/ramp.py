"""A twist command reached under acceleration limits: the base's twist moves from where it is
toward the commanded one along a straight line in (vx, vy, wz), as fast as the per-axis
limits a_max (m/s^2, m/s^2, rad/s^2; body frame) allow, so that no axis's acceleration
exceeds its limit and the direction of the change is kept.

With D = target - start, the ramp lasts T = max_i |D_i| / a_max_i and

    V(t) = start + D min(1, (t - t0) / T),   dV/dt = D / T while t - t0 < T, else 0,

a continuous twist with a bounded acceleration (the command a step, the base's twist not).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Acceleration limits (m/s^2, m/s^2, rad/s^2) of a base whose scene gives none (no
#: ``base.path``): ROS base_local_planner's defaults acc_lim_x, acc_lim_y, acc_lim_theta.
DEFAULT_A_MAX = (2.5, 2.5, 3.2)


@dataclass(frozen=True)
class TwistRamp:
    """From twist ``start`` at time ``t0`` (s) toward ``target`` (vx m/s, vy m/s, wz rad/s;
    body frame) within ``a_max`` per axis (module docstring)."""

    t0: float
    start: np.ndarray
    target: np.ndarray
    a_max: np.ndarray

    @classmethod
    def held(cls, twist) -> TwistRamp:
        """A ramp already at ``twist`` (held from the start)."""
        twist = np.asarray(twist, dtype=float)
        return cls(0.0, twist, twist, np.full(3, np.inf))

    @property
    def duration(self) -> float:
        """T (s): how long the ramp takes to reach its target."""
        change = np.abs(self.target - self.start)
        return float(np.max(np.divide(change, self.a_max, out=np.zeros(3), where=change > 0.0)))

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(twist, its time derivative) at t (s); the start before t0."""
        duration, elapsed = self.duration, max(t - self.t0, 0.0)
        if elapsed >= duration:
            return self.target, np.zeros(3)
        change = self.target - self.start
        return self.start + change * (elapsed / duration), change / duration

    def toward(self, t: float, target) -> TwistRamp:
        """The ramp from this one's twist at t (s) to a new ``target`` (this one if unchanged)."""
        target = np.asarray(target, dtype=float)
        if np.array_equal(target, self.target):
            return self
        return TwistRamp(t, self.at(t)[0], target, self.a_max)
