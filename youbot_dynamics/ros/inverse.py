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

Restarts: the estimate uses only samples of one unbroken stream. A sample that is not
later than the previous one (a replay that restarts its time base, a duplicate), or that
comes more than ``max_gap_ns`` after it (a pause, a one-off stamp of 1e6 s), starts a new
stencil: the samples before it and the filter state are forgotten (``clear``), and the
next torque comes after three good samples. So does an estimate that is not finite (an
overflowing velocity difference): it is rejected, never filtered. ``restarts`` counts the
restarts by cause.

Plausibility (rule: ``PLAUSIBLE_FACTOR`` = 10 times the URDF's rated limits): a measured
robot neither moves nor pushes much beyond its ratings. A sample with |v_i| >
10 x velocity_limit_i on some joint (a velocity jump of 1e6 rad/s, which gave 3e11 N m) is
rejected (``out_of_limits``) before it enters the stencil; a torque with |tau_i| >
10 x effort_limit_i (``DEFAULT_EFFORT_LIMIT`` where the URDF has none) comes from bad
samples (a velocity step within the velocity bound, 10 rad/s in 2 ms) and is not
published; the estimate then restarts. :func:`implausible_joints` names the joints.

Friction: the scene's model at the measured velocity; LuGre bristles are taken at their
steady state for v (the bristle deflection cannot be measured).
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import inverse_dynamics, inverse_dynamics_batch
from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.ros.commands import DEFAULT_EFFORT_LIMIT, InputRejected, JointSample

DEFAULT_MAX_GAP_NS = 100_000_000
"""Largest spacing (ns) of two samples in one stencil by default (0.1 s: 50 periods of a
500 Hz stream); a longer gap restarts the estimate."""
PLAUSIBLE_FACTOR = 10.0
"""A velocity or torque beyond this multiple of a joint's URDF limit is implausible."""
RESTART_CAUSES = ("backwards", "gap", "non_finite", "implausible")
"""Why the estimate restarted: a sample not after the previous one, a gap longer than
``max_gap_ns``, a non-finite estimate, an implausible torque (counted by the session)."""


class AccelerationEstimator:
    """Central differences of velocity over the last three samples of one unbroken stream
    (see the module docstring); ``max_gap_ns`` (int ns > 0) is the longest spacing."""

    def __init__(self, time_constant: float = 0.0, max_gap_ns: int = DEFAULT_MAX_GAP_NS) -> None:
        if not time_constant >= 0.0:
            raise ValueError(f"acceleration filter time constant must be >= 0 s, got {time_constant}")
        if not max_gap_ns > 0:
            raise ValueError(f"largest sample gap must be > 0 ns, got {max_gap_ns}")
        self.time_constant, self.max_gap_ns = float(time_constant), int(max_gap_ns)
        self.restarts = dict.fromkeys(RESTART_CAUSES, 0)
        self.clear()

    def clear(self) -> None:
        """Forget the samples and the filter state (the next estimate needs three samples)."""
        self.samples: list[JointSample] = []
        self.filtered: np.ndarray | None = None

    def restart(self, cause: str) -> None:
        """``clear``, counted under ``cause`` (one of ``RESTART_CAUSES``)."""
        self.restarts[cause] += 1
        self.clear()

    def push(self, sample: JointSample) -> tuple[JointSample, np.ndarray] | None:
        """Add a sample; returns (the middle sample, its acceleration estimate rad/s^2) once
        three of one stream are known. A sample not after the previous one, or more than
        ``max_gap_ns`` after it, restarts the stencil with itself. A non-finite estimate
        restarts it and raises ``non_finite``. Time differences are taken between
        integer-nanosecond stamps, exact at any magnitude (wall-clock stamps included)."""
        if self.samples:
            step = sample.stamp_ns - self.samples[-1].stamp_ns
            if step <= 0 or step > self.max_gap_ns:
                self.restart("backwards" if step <= 0 else "gap")
        self.samples = [*self.samples[-2:], sample]
        if len(self.samples) < 3:
            return None
        before, middle, after = self.samples
        with np.errstate(over="ignore", invalid="ignore"):     # checked just below
            estimate = (after.v - before.v) / ((after.stamp_ns - before.stamp_ns) / NS_PER_S)
            if self.time_constant > 0.0 and self.filtered is not None:
                dt = (after.stamp_ns - middle.stamp_ns) / NS_PER_S
                alpha = dt / (self.time_constant + dt)
                estimate = self.filtered + alpha * (estimate - self.filtered)
        if not np.isfinite(estimate).all():
            self.restart("non_finite")
            raise InputRejected("non_finite", f"acceleration estimate at {middle.stamp_ns} ns is not finite "
                                "(velocities too large to difference)")
        self.filtered = estimate
        return middle, estimate

    def push_many(self, samples: Sequence[JointSample | None]) -> list[tuple[int, JointSample, np.ndarray]] | None:
        """``push`` of each sample in turn (None: ``clear``, for a rejected one), the
        estimates computed at once: (index of the sample that completed the stencil, the
        middle sample, its estimate), in order. None, with nothing changed, when a push
        would have raised (an estimate not finite) or with a filter (``time_constant`` > 0:
        each estimate depends on the last); then push one by one."""
        if self.time_constant > 0.0:
            return None
        window, restarts, stencils = list(self.samples), dict.fromkeys(RESTART_CAUSES, 0), []
        for index, sample in enumerate(samples):
            if sample is None:
                window = []
                continue
            if window:
                step = sample.stamp_ns - window[-1].stamp_ns
                if step <= 0 or step > self.max_gap_ns:
                    restarts["backwards" if step <= 0 else "gap"] += 1
                    window = []
            window = [*window[-2:], sample]
            if len(window) == 3:
                stencils.append((index, *window))
        if stencils:
            spans = np.array([after.stamp_ns - before.stamp_ns for _, before, _, after in stencils]) / NS_PER_S
            with np.errstate(over="ignore", invalid="ignore"):     # checked just below
                estimates = (np.array([after.v for *_, after in stencils]) -
                             np.array([before.v for _, before, _, _ in stencils])) / spans[:, None]
            if not np.isfinite(estimates).all():
                return None
            self.filtered = estimates[-1]
        self.samples = window
        for cause, count in restarts.items():
            self.restarts[cause] += count
        return [(index, middle, estimate) for (index, _, middle, _), estimate in zip(stencils, estimates)] \
            if stencils else []

    def state(self) -> tuple:
        """What ``restore`` puts back: the samples, the filter state, the restart counts."""
        return list(self.samples), self.filtered, dict(self.restarts)

    def restore(self, state: tuple) -> None:
        """Back to a ``state()``."""
        samples, filtered, restarts = state
        self.samples, self.filtered, self.restarts = list(samples), filtered, dict(restarts)


def plausible_limit(robot: Robot, quantity: str = "effort") -> np.ndarray:
    """|tau_i| (N m, N; ``quantity`` "effort") or |v_i| (rad/s, m/s; "velocity") above which
    a value is implausible: ``PLAUSIBLE_FACTOR`` times the URDF limit; where the URDF has
    none, ``DEFAULT_EFFORT_LIMIT`` for efforts and no bound for velocities."""
    limit = np.asarray(robot.effort_limit if quantity == "effort" else robot.velocity_limit, dtype=float)
    return PLAUSIBLE_FACTOR * np.where(np.isfinite(limit), limit,
                                       DEFAULT_EFFORT_LIMIT if quantity == "effort" else np.inf)


def implausible_joints(robot: Robot, values: np.ndarray, quantity: str = "effort") -> list[str]:
    """Names of the joints whose ``values`` (joint order; torques or velocities, see
    :func:`plausible_limit`) are not finite or beyond the plausible bound."""
    bad = ~(np.abs(values) <= plausible_limit(robot, quantity))
    return [name for name, flag in zip(robot.joint_names, bad) if flag]


class InverseDynamics:
    """tau = RNEA(q, v, a) + tau_friction(v) for a robot and its friction model (or None),
    of one sample (``torque``) or of many (``torques``, Pinocchio's batch RNEA)."""

    def __init__(self, robot: Robot, friction: JointFriction | None) -> None:
        self.robot, self.friction = robot, friction
        self.data = robot.model.createData()
        self.pool = pin.ModelPool(robot.model, 1)

    def _bristles(self, v: np.ndarray) -> np.ndarray | None:
        if self.friction is None or self.friction.lugre is None:
            return None
        if v.ndim == 1:
            return self.friction.steady_state_bristles(v)
        return np.array([self.friction.steady_state_bristles(row) for row in v])

    def torque(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Joint torques (N m, N) in joint order."""
        return inverse_dynamics(self.robot, self.data, q, v, a, self.friction, self._bristles(v))

    def torques(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Joint torques (N, nv) of N samples (rows of q, v, a)."""
        return inverse_dynamics_batch(self.robot, q, v, a, self.friction, self._bristles(v), pool=self.pool)
