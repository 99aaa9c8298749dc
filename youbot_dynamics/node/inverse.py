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

Plausibility: a measured robot neither moves nor pushes much beyond its ratings, nor
stands outside its joint limits. A sample with |v_i| > ``PLAUSIBLE_FACTOR`` (10) x
velocity_limit_i on some joint (a velocity jump of 1e6 rad/s, which gave 3e11 N m), or a
position outside [lower_i - m_i, upper_i + m_i] (m_i: ``POSITION_MARGIN`` of the joint's
range, at least ``MIN_POSITION_MARGIN``; |q_i| <= ``UNLIMITED_POSITION_BOUND`` for a joint
without limits: a position of 1e308 rad is no measurement) is rejected (``out_of_limits``)
before it enters the stencil. A torque with |tau_i| > ``EFFORT_FACTOR`` (2) x
effort_limit_i (``DEFAULT_EFFORT_LIMIT`` where the URDF has none) is more than the motors
give, so it comes from bad samples (a velocity step within the velocity bound, 10 rad/s in
2 ms; an unstamped stream whose receive times bunch up, which gave 56.9 N m on a 9.5 N m
joint) and is not published; the estimate then restarts. The same gates apply to a
single sample and to every row of a batch. :func:`implausible_joints` names the joints.

Friction: the scene's model at the measured velocity; LuGre bristles are taken at their
steady state for v (the bristle deflection cannot be measured).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numba import njit, types

from youbot_dynamics.dynamics.friction import JointFriction, unchecked
from youbot_dynamics.dynamics.rigid_body import inverse_dynamics_batch
from youbot_dynamics.io.stamps import NS_PER_S, STAMP_LIMIT_NS
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.node.commands import DEFAULT_EFFORT_LIMIT, InputRejected, JointSample

DEFAULT_MAX_GAP_NS = 100_000_000
"""Largest spacing (ns) of two samples in one stencil by default (0.1 s: 50 periods of a
500 Hz stream); a longer gap restarts the estimate."""
PLAUSIBLE_FACTOR = 10.0
"""A velocity beyond this multiple of a joint's URDF velocity limit is implausible."""
EFFORT_FACTOR = 2.0
"""A torque beyond this multiple of a joint's URDF effort limit is implausible (the youBot's
rated efforts are what its drives deliver; a clean stream of the arm stays within 0.65 of
them)."""
POSITION_MARGIN = 0.1
"""Fraction of a joint's range by which a measured position may lie outside its limits."""
MIN_POSITION_MARGIN = 0.01
"""Smallest margin (rad or m) outside a joint's limits."""
UNLIMITED_POSITION_BOUND = 1.0e7
"""Largest |position| (rad or m) of a joint without limits (a continuous wheel: 1e7 rad is
11 days at 10 rad/s in one direction; a double there still resolves 2e-9 rad)."""
RESTART_CAUSES = ("backwards", "gap", "non_finite", "implausible")
"""Why the estimate restarted: a sample not after the previous one, a gap longer than
``max_gap_ns``, a non-finite estimate, an implausible torque (counted by the session)."""
_NO_ROWS = np.empty((0, 0))
"""The q and v rows of an empty stencil."""
_LARGEST_INT64 = 2**63 - 1
"""A larger ``max_gap_ns`` is no bound (two stamps of builtin_interfaces/Time are less apart)."""

_INTS = types.Array(types.int64, 1, "C")
_SIGNATURE = types.UniTuple(types.int64, 6)(
    types.Array(types.int64, 1, "C", readonly=True), types.Array(types.boolean, 1, "C", readonly=True),
    types.Array(types.float64, 2, "A", readonly=True), types.int64, types.int64, types.float64,
    types.Array(types.float64, 1, "C"), types.boolean, _INTS, types.Array(types.float64, 2, "C"), _INTS)
"""(stamps, taken, v, held, max_gap_ns, time_constant, filtered, known, ends, estimates,
failed) -> (kept, failed, run, backwards, gaps, known): see :func:`_central_differences`."""


@njit(_SIGNATURE, cache=True)
def _central_differences(stamps: np.ndarray, taken: np.ndarray, v: np.ndarray, held: int, max_gap_ns: int,
                         time_constant: float, filtered: np.ndarray, known: bool, ends: np.ndarray,
                         estimates: np.ndarray, failed: np.ndarray) -> tuple[int, int, int, int, int, int]:
    """The stencils of rows pushed one by one (see the module docstring): ``stamps`` (int
    ns) and ``v`` rows of the ``held`` samples of the stencil, then of the new ones, of which
    those not ``taken`` (index k - held) clear it. For each new row k that completes three
    samples of one stream: ends[i] = k and estimates[i] its estimate (rad/s^2), filtered
    (``time_constant`` > 0 s) from ``filtered`` when ``known``; an estimate not finite
    restarts the stencil and is not kept (failed[j] = k). ``filtered`` ends as the filter's
    state. Returns (estimates kept, failed, samples of the stream at the end, restarts
    backwards, restarts gap, whether ``filtered`` is known)."""
    run, count, bad, backwards, gaps = held, 0, 0, 0, 0
    for k in range(held, stamps.shape[0]):
        if not taken[k - held]:
            run, known = 0, False
            continue
        if run > 0:
            step = stamps[k] - stamps[k - 1]
            if step <= 0 or step > max_gap_ns:
                if step <= 0:
                    backwards += 1
                else:
                    gaps += 1
                run, known = 0, False
        run += 1
        if run < 3:
            continue
        span = (stamps[k] - stamps[k - 2]) / NS_PER_S
        smooth, alpha = time_constant > 0.0 and known, 0.0
        if smooth:
            dt = (stamps[k] - stamps[k - 1]) / NS_PER_S
            alpha = dt / (time_constant + dt)
        finite = True
        for j in range(v.shape[1]):
            estimate = (v[k, j] - v[k - 2, j]) / span
            if smooth:
                estimate = filtered[j] + alpha * (estimate - filtered[j])
            finite = finite and math.isfinite(estimate)
            estimates[count, j] = estimate
        if not finite:
            failed[bad] = k
            bad += 1
            run, known = 0, False
            continue
        filtered[:] = estimates[count]
        known = True
        ends[count] = k
        count += 1
    return count, bad, run, backwards, gaps, 1 if known else 0


_central_differences_unchecked = unchecked(_central_differences)
"""The same without numba's type dispatch (callers pass exactly the signature's types)."""


@njit(types.int64(types.Array(types.float64, 2, "C", readonly=True), types.Array(types.float64, 1, "C", readonly=True)),
      cache=True)
def _plausible_rows(torques: np.ndarray, bound: np.ndarray) -> int:
    """The number of leading rows of ``torques`` (N, nv; N m, N) with |tau_i| <= bound_i on
    every joint (a NaN is not)."""
    for row in range(torques.shape[0]):
        for j in range(torques.shape[1]):
            if not abs(torques[row, j]) <= bound[j]:
                return row
    return torques.shape[0]


_plausible_rows_unchecked = unchecked(_plausible_rows)
"""The same without numba's type dispatch (callers pass exactly the signature's types)."""


def plausible_rows(torques: np.ndarray, bound: np.ndarray) -> int:
    """The number of leading rows of ``torques`` (N, nv; N m, N: a C-ordered float array)
    whose every |tau_i| is within ``bound`` (nv,; :func:`plausible_limit`); N when all are."""
    if not (torques.dtype == bound.dtype == np.float64 and torques.ndim == 2 and torques.flags.c_contiguous
            and bound.shape == torques.shape[1:] and bound.flags.c_contiguous):
        raise ValueError(f"plausible_rows: float64 torques (N, n) and bound (n,); got {torques.dtype} "
                         f"{torques.shape}, {bound.dtype} {bound.shape}")
    return _plausible_rows_unchecked(torques, bound)


@njit(types.boolean(types.Array(types.int64, 1, "C", readonly=True), types.Array(types.float64, 2, "C", readonly=True),
                    types.Array(types.float64, 4, "C", readonly=True), types.int64), cache=True)
def clean_rows(stamps: np.ndarray, values: np.ndarray, bounds: np.ndarray, previous: int) -> bool:
    """True if N samples can all be taken as they are: every stamp (int ns, (N,)) in (0,
    ``STAMP_LIMIT_NS``) and unlike the one before it (``previous`` for the first), every
    position (``values`` rows 0 to N - 1) and velocity (rows N to 2N - 1) within ``bounds``
    (2, 2, 1, columns: lowest then highest; position then velocity) of its column."""
    count = stamps.shape[0]
    for k in range(count):
        if not 0 < stamps[k] < STAMP_LIMIT_NS or stamps[k] == previous:
            return False
        previous = stamps[k]
        for quantity in range(2):
            for j in range(values.shape[1]):
                value = values[quantity * count + k, j]
                if not bounds[0, quantity, 0, j] <= value <= bounds[1, quantity, 0, j]:
                    return False
    return True


clean_rows_unchecked = unchecked(clean_rows)
"""The same without numba's type dispatch (callers pass exactly the signature's types)."""


class Estimates(NamedTuple):
    """The estimates of rows pushed (:meth:`AccelerationEstimator.push_rows`), in order: the
    middle samples' stamps (int64 ns, (M,)), q (M, nq), v (M, nv), their accelerations
    ``a`` (M, nv; rad/s^2), the ``non_finite`` errors of the estimates dropped, and ``ends``
    (int64, (M,)): the index, among the rows pushed, of each estimate's last sample."""

    stamps: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    errors: list[InputRejected]
    ends: np.ndarray


class AccelerationEstimator:
    """Central differences of velocity over the last three samples of one unbroken stream
    (see the module docstring); ``max_gap_ns`` (int ns > 0) is the longest spacing. The
    samples of the stencil (at most three, oldest first) are held as arrays: their stamps
    (int ns), q and v rows. One compiled loop pushes a sample or a batch of them."""

    def __init__(self, time_constant: float = 0.0, max_gap_ns: int = DEFAULT_MAX_GAP_NS) -> None:
        if not time_constant >= 0.0:
            raise ValueError(f"acceleration filter time constant must be >= 0 s, got {time_constant}")
        if not max_gap_ns > 0:
            raise ValueError(f"largest sample gap must be > 0 ns, got {max_gap_ns}")
        self.time_constant, self.max_gap_ns = float(time_constant), int(max_gap_ns)
        self._gap_bound = min(self.max_gap_ns, _LARGEST_INT64)
        """``max_gap_ns`` as the compiled loop takes it (an int64)."""
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

    def push(self, sample: JointSample) -> tuple[JointSample, np.ndarray] | None:
        """Add a sample; returns (the middle sample, its acceleration estimate rad/s^2) once
        three of one stream are known. A sample not after the previous one, or more than
        ``max_gap_ns`` after it, restarts the stencil with itself. A non-finite estimate
        restarts it and raises ``non_finite``. Time differences are taken between
        integer-nanosecond stamps, exact at any magnitude (wall-clock stamps included)."""
        pushed = self.push_rows([sample.stamp_ns], sample.q[None, :], sample.v[None, :], [True])
        if pushed.errors:
            raise pushed.errors[0]
        return (JointSample(int(pushed.stamps[0]), pushed.q[0], pushed.v[0]), pushed.a[0]) if len(pushed.stamps) \
            else None

    def push_rows(self, stamps: Sequence[int], q: np.ndarray, v: np.ndarray, taken: Sequence[bool]) -> Estimates:
        """``push`` of each row in turn (stamps int ns (N,), q (N, nq), v (N, nv); a row not
        ``taken``, a rejected sample whose stamp and values are ignored: ``clear``): the
        :class:`Estimates`, with the ``non_finite`` errors ``push`` would have raised (the
        estimate restarted at each)."""
        held, count = len(self._stamps), len(stamps)
        if not len(q) == len(v) == len(taken) == count or np.ndim(v) != 2:     # the compiled loop trusts them
            raise ValueError(f"push_rows: {count} stamps need as many rows of q and v and taken flags; got "
                             f"q {np.shape(q)}, v {np.shape(v)}, {len(taken)} flags")
        all_stamps = np.array([*self._stamps, *stamps], dtype=np.int64)
        all_q, all_v = ((np.concatenate((self._q, q)), np.concatenate((self._v, v))) if held
                        else (q, np.asarray(v, dtype=float)))
        filtered, known = (np.empty(all_v.shape[1]), False) if self.filtered is None else (self.filtered.copy(), True)
        ends, failed = np.empty((2, count), dtype=np.int64)
        estimates = np.empty((count, all_v.shape[1]))
        kept, bad, run, backwards, gaps, known = _central_differences_unchecked(     # the types it was compiled for
            all_stamps, np.array(taken, dtype=bool), all_v, held, self._gap_bound, self.time_constant, filtered,
            known, ends, estimates, failed)
        if backwards or gaps or bad:
            self.restarts["backwards"] += backwards
            self.restarts["gap"] += gaps
            self.restarts["non_finite"] += bad
        self.filtered = filtered if known else None
        keep = min(run, 3)
        self._stamps, self._q, self._v = ((all_stamps[-keep:].tolist(), all_q[-keep:], all_v[-keep:]) if keep
                                          else ([], _NO_ROWS, _NO_ROWS))
        first, last = (int(ends[0]), int(ends[kept - 1])) if kept else (0, -1)
        middle = slice(first - 1, last) if last - first == kept - 1 else ends[:kept] - 1    # one stream: a slice
        errors = [InputRejected("non_finite", f"acceleration estimate at {all_stamps[k - 1]} ns is not finite "
                                "(velocities too large to difference)") for k in failed[:bad].tolist()] if bad else []
        return Estimates(all_stamps[middle], all_q[middle], all_v[middle], estimates[:kept], errors,
                         ends[:kept] - held)

    def state(self) -> tuple:
        """What ``restore`` puts back: the samples, the filter state, the restart counts."""
        return self._stamps, self._q, self._v, self.filtered, dict(self.restarts)

    def restore(self, state: tuple) -> None:
        """Back to a ``state()``."""
        self._stamps, self._q, self._v, self.filtered, restarts = state
        self.restarts = dict(restarts)


def plausible_limit(robot: Robot, quantity: str = "effort") -> np.ndarray:
    """|tau_i| (N m, N; ``quantity`` "effort") or |v_i| (rad/s, m/s; "velocity") above which
    a value is implausible: ``EFFORT_FACTOR`` or ``PLAUSIBLE_FACTOR`` times the URDF limit;
    where the URDF has none, ``DEFAULT_EFFORT_LIMIT`` for efforts and no bound for velocities."""
    if quantity == "effort":
        limit = np.asarray(robot.effort_limit, dtype=float)
        return EFFORT_FACTOR * np.where(np.isfinite(limit), limit, DEFAULT_EFFORT_LIMIT)
    limit = np.asarray(robot.velocity_limit, dtype=float)
    return PLAUSIBLE_FACTOR * np.where(np.isfinite(limit), limit, np.inf)


def position_bounds(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest plausible measured position of each joint (rad or m, joint
    order; see the module docstring): its limits widened by ``POSITION_MARGIN`` of its
    range (at least ``MIN_POSITION_MARGIN``), or +-``UNLIMITED_POSITION_BOUND`` without
    limits."""
    lower, upper = np.asarray(robot.lower, dtype=float), np.asarray(robot.upper, dtype=float)
    limited = np.isfinite(lower) & np.isfinite(upper)
    margin = np.maximum(POSITION_MARGIN * np.where(limited, upper - lower, 0.0), MIN_POSITION_MARGIN)
    return (np.where(limited, lower - margin, -UNLIMITED_POSITION_BOUND),
            np.where(limited, upper + margin, UNLIMITED_POSITION_BOUND))


def implausible_joints(robot: Robot, values: np.ndarray, quantity: str = "effort") -> list[str]:
    """Names of the joints whose ``values`` (joint order; torques or velocities, see
    :func:`plausible_limit`) are not finite or beyond the plausible bound."""
    bad = ~(np.abs(values) <= plausible_limit(robot, quantity))
    return [name for name, flag in zip(robot.joint_names, bad) if flag]


class InverseDynamics:
    """tau = RNEA(q, v, a) + tau_friction(v) for a robot and its friction model (or None),
    of many samples at once (``torques``, Pinocchio's batch RNEA; ``torque``: a batch of
    one). ``data`` is a Pinocchio Data of the robot for other uses (energies)."""

    def __init__(self, robot: Robot, friction: JointFriction | None) -> None:
        self.robot, self.friction = robot, friction
        self.data = robot.model.createData()
        self.pool = pin.ModelPool(robot.model, 1)

    def torque(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Joint torques (N m, N) in joint order of one sample."""
        return self.torques(np.asarray(q)[None, :], np.asarray(v)[None, :], np.asarray(a)[None, :])[0]

    def torques(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Joint torques (N, nv; N m, N) of N samples (rows of q, v, a); LuGre bristles at
        their steady state for v."""
        bristles = None if self.friction is None or self.friction.lugre is None else \
            np.array([self.friction.steady_state_bristles(row) for row in v])
        return inverse_dynamics_batch(self.robot, q, v, a, self.friction, bristles, pool=self.pool)
