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

import math
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
_NO_ROWS = np.empty((0, 0))
"""The q and v rows of an empty stencil."""


class AccelerationEstimator:
    """Central differences of velocity over the last three samples of one unbroken stream
    (see the module docstring); ``max_gap_ns`` (int ns > 0) is the longest spacing. The
    samples of the stencil (at most three, oldest first) are held as arrays: their stamps
    (int ns), q and v rows."""

    def __init__(self, time_constant: float = 0.0, max_gap_ns: int = DEFAULT_MAX_GAP_NS) -> None:
        if not time_constant >= 0.0:
            raise ValueError(f"acceleration filter time constant must be >= 0 s, got {time_constant}")
        if not max_gap_ns > 0:
            raise ValueError(f"largest sample gap must be > 0 ns, got {max_gap_ns}")
        self.time_constant, self.max_gap_ns = float(time_constant), int(max_gap_ns)
        self.restarts = dict.fromkeys(RESTART_CAUSES, 0)
        self.clear()

    @property
    def samples(self) -> list[JointSample]:
        """The samples of the stencil, oldest first (at most three)."""
        return [JointSample(stamp, q, v) for stamp, q, v in zip(self._stamps, self._q, self._v)]

    def clear(self) -> None:
        """Forget the samples and the filter state (the next estimate needs three samples)."""
        self._stamps: list[int] = []
        self._q = self._v = _NO_ROWS
        self.filtered: np.ndarray | None = None

    def restart(self, cause: str) -> None:
        """``clear``, counted under ``cause`` (one of ``RESTART_CAUSES``)."""
        self.restarts[cause] += 1
        self.clear()

    def _break(self, step: int) -> str | None:
        """The restart cause of a sample ``step`` ns after the previous one (None: same stream)."""
        return "backwards" if step <= 0 else "gap" if step > self.max_gap_ns else None

    def push(self, sample: JointSample) -> tuple[JointSample, np.ndarray] | None:
        """Add a sample; returns (the middle sample, its acceleration estimate rad/s^2) once
        three of one stream are known. A sample not after the previous one, or more than
        ``max_gap_ns`` after it, restarts the stencil with itself. A non-finite estimate
        restarts it and raises ``non_finite``. Time differences are taken between
        integer-nanosecond stamps, exact at any magnitude (wall-clock stamps included)."""
        if self._stamps:
            cause = self._break(sample.stamp_ns - self._stamps[-1])
            if cause is not None:
                self.restart(cause)
        if self._stamps:
            self._stamps = [*self._stamps[-2:], sample.stamp_ns]
            self._q = np.concatenate((self._q[-2:], sample.q[None, :]))
            self._v = np.concatenate((self._v[-2:], sample.v[None, :]))
        else:
            self._stamps, self._q, self._v = [sample.stamp_ns], sample.q[None, :], sample.v[None, :]
        if len(self._stamps) < 3:
            return None
        before, middle, after = self._stamps
        with np.errstate(over="ignore", invalid="ignore"):     # checked just below
            estimate = (self._v[2] - self._v[0]) / ((after - before) / NS_PER_S)
            if self.time_constant > 0.0 and self.filtered is not None:
                dt = (after - middle) / NS_PER_S
                alpha = dt / (self.time_constant + dt)
                estimate = self.filtered + alpha * (estimate - self.filtered)
        if not np.isfinite(estimate).all():
            self.restart("non_finite")
            raise InputRejected("non_finite", f"acceleration estimate at {middle} ns is not finite "
                                "(velocities too large to difference)")
        self.filtered = estimate
        return JointSample(middle, self._q[1], self._v[1]), estimate

    def push_rows(self, stamps: Sequence[int], q: np.ndarray, v: np.ndarray, taken: Sequence[bool]
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """``push`` of each row in turn (stamps int ns (N,), q (N, nq), v (N, nv); a row not
        ``taken``, a rejected sample whose stamp and values are ignored: ``clear``), the
        estimates computed at once: the middle samples' stamps (int64 ns, (M,)), q (M, nq),
        v (M, nv) and their estimates a (M, nv; rad/s^2), in order. None, with nothing
        changed, when a push would have raised (an estimate not finite) or with a filter
        (``time_constant`` > 0: each estimate depends on the last); then push one by one."""
        if self.time_constant > 0.0:
            return None
        held = len(self._stamps)
        run, last, restarts, ends = held, self._stamps[-1] if held else 0, [], []
        for k, (stamp, ok) in enumerate(zip(stamps, taken)):     # run: samples of the stream ending at k
            if not ok:
                run = 0
                continue
            cause = self._break(stamp - last) if run else None
            if cause is not None:
                restarts.append(cause)
                run = 0
            run, last = run + 1, stamp
            if run >= 3:
                ends.append(held + k)
        all_stamps = np.array([*self._stamps, *stamps], dtype=np.int64)
        all_q, all_v = (np.concatenate((self._q, q)), np.concatenate((self._v, v))) if held else (q, v)
        if ends and ends[-1] - ends[0] != len(ends) - 1:     # stencils of several streams: indices
            after = np.array(ends, dtype=np.intp)
            before, middle = after - 2, after - 1
        else:                                               # of one stream (or none): slices
            end = ends[-1] + 1 if ends else 2
            before, middle, after = slice(end - 2 - len(ends), end - 2), slice(end - 1 - len(ends), end - 1), \
                slice(end - len(ends), end)
        with np.errstate(over="ignore", invalid="ignore"):     # checked just below
            spans = (all_stamps[after] - all_stamps[before]) / NS_PER_S
            estimates = (all_v[after] - all_v[before]) / spans[:, None]
            if not math.isfinite(np.add.reduce(estimates, axis=None)):    # one pass; an overflowing sum: push one by one
                return None
        for cause in restarts:
            self.restarts[cause] += 1
        if run < 3:
            self.filtered = None
        elif ends:
            self.filtered = estimates[-1]
        keep = min(run, 3)
        if keep:
            self._stamps, self._q, self._v = all_stamps[-keep:].tolist(), all_q[-keep:], all_v[-keep:]
        else:
            self._stamps, self._q, self._v = [], _NO_ROWS, _NO_ROWS
        return all_stamps[middle], all_q[middle], all_v[middle], estimates

    def state(self) -> tuple:
        """What ``restore`` puts back: the samples, the filter state, the restart counts."""
        return self._stamps, self._q, self._v, self.filtered, dict(self.restarts)

    def restore(self, state: tuple) -> None:
        """Back to a ``state()``."""
        self._stamps, self._q, self._v, self.filtered, restarts = state
        self.restarts = dict(restarts)


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
