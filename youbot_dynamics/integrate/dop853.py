"""DOP853 (Hairer's explicit Runge-Kutta 8(5,3) pair) with its step-size control and dense
output in compiled code, for a right-hand side that has a compiled form: the integrator
``dop853_compiled``.

The method and its control are scipy's ``DOP853`` (Hairer, Norsett, Wanner, Solving ODEs I,
sec. II.4-II.6 and II.10; the coefficients are scipy's class attributes): the initial step
of :func:`initial_step`, 12 evaluations per attempted step (11 stages and f at the new
state, which is the next step's first stage), the error norm :func:`error_norm` of the
fifth- and third-order estimates, the new step h |err|^(-1/8) * 0.9 within [0.2, 10] times
the old (no growth right after a rejection), steps of at least 10 ulp of t, and a dense
output of order 7 from 3 more evaluations, computed only for a step that holds an output or
an event. So a run takes the steps scipy's DOP853 takes (their sizes equal to about 1e-6
relative: the error estimate, a difference of nearly equal stages, carries the rounding of
their sums, which differ from numpy's dot products) and its states agree to rounding
(test/sim/test_compiled_dop853.py).

What runs in compiled code is split in two, because numba caches no function that takes
another compiled function as an argument: this module holds the method's arithmetic
(:func:`stage_state`, :func:`error_norm`, :func:`step_factor`, :func:`dense_coefficients`,
:func:`dense_state`); the right-hand side's owner writes the loop that calls its own
derivative between them (:class:`CompiledDop853`; a robot alone under a held torque has
one, :mod:`youbot_dynamics.sim.compiled_steps`). A right-hand side without such a loop is
integrated by scipy's DOP853 itself (integrate/registry.py): the same steps, in Python.
"""
from __future__ import annotations

import math
from typing import Callable, Protocol

import numpy as np
from numba import njit
from scipy.integrate import DOP853

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.errors import DivergenceError
from youbot_dynamics.integrate.statistics import IntegratorStats

#: Stages per attempted step (the 12th is f at the new state) and with the dense output.
STAGES, STAGES_DENSE = 12, 16
#: The Butcher matrix, extended: rows 1-11 the stages, row 12 the solution's weights B
#: (stage 12 is f at the new state), rows 13-15 the dense output's extra stages.
A = np.zeros((STAGES_DENSE, STAGES_DENSE))
A[:STAGES, :STAGES] = DOP853.A
A[STAGES, :STAGES] = DOP853.B
A[STAGES + 1:] = DOP853.A_EXTRA
#: The stages' nodes c (fractions of the step), extended as ``A``.
C = np.concatenate([DOP853.C, [1.0], DOP853.C_EXTRA])
#: The fifth- and third-order error estimates' weights (over stages 0-12).
E5, E3 = np.array(DOP853.E5), np.array(DOP853.E3)
#: The dense output's weights (4, 16): its coefficients 3-6.
D = np.array(DOP853.D)
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
ERROR_EXPONENT = -1.0 / 8.0  # -1 / (error estimator order 7 + 1)
#: The smallest relative tolerance (scipy raises a smaller one to it).
RTOL_FLOOR = 100 * np.finfo(float).eps

#: What a loop's call ended with (:class:`CompiledDop853`): t_target reached (or one step
#: taken, or the step budget spent); an accepted state not finite or beyond its bounds
#: (drive's check names it); the step size below 10 ulp of t; an accepted step below the
#: caller's min_step; a stage's derivative not finite.
REACHED, BAD_STATE, COLLAPSED, BELOW_MIN_STEP, NON_FINITE = range(5)


@njit(cache=True)
def stage_state(x: np.ndarray, K: np.ndarray, s: int, h: float, out: np.ndarray) -> None:
    """out = x + (sum_{j<s} A[s, j] K[j]) h: the state stage s evaluates (s = 12: the new
    state), h the step (s)."""
    for i in range(x.shape[0]):
        increment = 0.0
        for j in range(s):
            increment += A[s, j] * K[j, i]
        out[i] = x[i] + increment * h


@njit(cache=True)
def error_norm(K: np.ndarray, h: float, x: np.ndarray, x_new: np.ndarray, rtol: float,
               atol: np.ndarray) -> float:
    """DOP853's error norm of a step of size h (s) from x to x_new (stages K[0..12]): with
    the scale sc_i = atol_i + rtol max(|x_i|, |x_new_i|) and e5, e3 the fifth- and
    third-order estimates over sc, |h| |e5|^2 / sqrt((|e5|^2 + 0.01 |e3|^2) n). The step is
    accepted below 1."""
    n = x.shape[0]
    squares5 = squares3 = 0.0
    for i in range(n):
        scale = atol[i] + max(abs(x[i]), abs(x_new[i])) * rtol
        e5 = e3 = 0.0
        for j in range(STAGES + 1):
            e5 += E5[j] * K[j, i]
            e3 += E3[j] * K[j, i]
        squares5 += (e5 / scale) ** 2
        squares3 += (e3 / scale) ** 2
    if squares5 == 0.0 and squares3 == 0.0:
        return 0.0
    return abs(h) * squares5 / math.sqrt((squares5 + 0.01 * squares3) * n)


@njit(cache=True)
def step_factor(norm: float, after_rejection: bool) -> float:
    """The next step size over this one for an error norm ``norm``: 0.9 norm^(-1/8) within
    [0.2, 10], at most 1 for an accepted step that followed a rejection."""
    if norm < 1.0:
        factor = MAX_FACTOR if norm == 0.0 else min(MAX_FACTOR, SAFETY * norm ** ERROR_EXPONENT)
        return min(1.0, factor) if after_rejection else factor
    return max(MIN_FACTOR, SAFETY * norm ** ERROR_EXPONENT)


@njit(cache=True)
def minimum_step(t: float) -> float:
    """The smallest step (s) at time t (s): 10 ulp of t."""
    return 10.0 * abs(np.nextafter(t, np.inf) - t)


@njit(cache=True)
def dense_coefficients(K: np.ndarray, h: float, x_old: np.ndarray, x: np.ndarray, F: np.ndarray) -> None:
    """F (7, n) = the dense output's coefficients over the step of size h (s) from x_old to
    x, from its stages K[0..15] (K[0] f at x_old, K[12] f at x)."""
    for i in range(x.shape[0]):
        delta = x[i] - x_old[i]
        F[0, i] = delta
        F[1, i] = h * K[0, i] - delta
        F[2, i] = 2.0 * delta - h * (K[STAGES, i] + K[0, i])
        for row in range(D.shape[0]):
            total = 0.0
            for j in range(STAGES_DENSE):
                total += D[row, j] * K[j, i]
            F[3 + row, i] = h * total


@njit(cache=True)
def dense_state(F: np.ndarray, x_old: np.ndarray, theta: float, out: np.ndarray) -> None:
    """out = the dense output at the fraction ``theta`` of the step (0: x_old, 1: the new
    state), Horner's scheme in theta and 1 - theta alternately from F's last row."""
    rows = F.shape[0]
    for i in range(x_old.shape[0]):
        value = 0.0
        for k in range(rows):
            value += F[rows - 1 - k, i]
            value *= theta if k % 2 == 0 else 1.0 - theta
        out[i] = value + x_old[i]


def rms(values: np.ndarray) -> float:
    """Root mean square of a vector in scipy's form (its ``norm``: |values| / sqrt(n)), so the
    initial step is scipy's to the bit; radau_dae's ``rms`` is Hairer's mean of squares."""
    return float(np.linalg.norm(values)) / math.sqrt(values.size)


def initial_step(derivative: Callable[[np.ndarray], np.ndarray], t0: float, x0: np.ndarray, f0: np.ndarray,
                 t_end: float, max_step: float, rtol: float, atol: np.ndarray,
                 name: str = "dop853_compiled") -> float:
    """The first step size (s), Hairer's II.4 estimate for an error of order 8 as scipy's
    ``select_initial_step`` makes it: h0 = 0.01 |x0| / |f0| (norms scaled by atol + rtol
    |x0|; 1e-6 s if either is below 1e-5), one Euler step of h0 to estimate |f'|, then
    h = min(100 h0, (0.01 / max(|f0|, |f'|))^(1/8), t_end - t0, max_step). ``derivative``
    gives f(x) (the system is autonomous: a held torque); one evaluation. A non-finite f
    there is a DivergenceError naming ``name``."""
    length = abs(t_end - t0)
    if length == 0.0:
        return 0.0
    scale = atol + np.abs(x0) * rtol
    d0, d1 = rms(x0 / scale), rms(f0 / scale)
    h0 = min(1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1, length)
    d2 = rms((derivative(x0 + h0 * f0) - f0) / scale) / h0
    if not math.isfinite(d2):
        raise DivergenceError(t0 + h0, name, h0, "non-finite derivative inside a step")
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100 * h0, h1, length, max_step)


class CompiledDop853(Protocol):
    """A right-hand side's compiled DOP853 loop (the owner's, calling its own derivative
    between this module's kernels), as :class:`CompiledDop853Stepper` calls it."""

    def derivative(self, x: np.ndarray) -> np.ndarray:
        """f(x), a new array."""

    def dop853(self, t: float, x: np.ndarray, f: np.ndarray, h_abs: float, t_target: float, t_end: float,
               limits: np.ndarray, atol: np.ndarray, single: bool, bounds: np.ndarray, budget: int,
               x_old: np.ndarray, K: np.ndarray, x_new: np.ndarray) -> tuple[int, float, float, float, int, int]:
        """DOP853 steps from (t, x), f = f(x), with the proposed step size h_abs (s)
        towards t_target (s), never beyond t_end: x and f updated in place, x_old the state
        before the last step, K its stages; ``limits`` = (max_step, min_step (s), rtol). One
        step when ``single``, at most ``budget`` steps, and none after an accepted state
        that is not finite or beyond ``bounds``. Returns (status, t, t before the last
        step, the next proposed step size, accepted steps, rejected steps); status one of
        REACHED, BAD_STATE, COLLAPSED, BELOW_MIN_STEP, NON_FINITE."""

    def dop853_dense(self, K: np.ndarray, h: float, x_old: np.ndarray, x: np.ndarray, F: np.ndarray,
                     scratch: np.ndarray) -> None:
        """F = the dense output's coefficients of the last step (size h, s, from x_old to
        x): its 3 extra stages into K[13..15], then :func:`dense_coefficients`."""


#: Steps allowed in one call without a step budget.
NO_BUDGET = 2 ** 62


class CompiledDop853Stepper:
    """DOP853 through a compiled loop: every step up to the next output time in one call
    (one step per ``advance`` when events need watching), the dense output only where an
    output or an event falls."""

    def __init__(self, name: str, loop: CompiledDop853, t0: float, x0: np.ndarray, t_end: float, rtol: float,
                 atol: float | np.ndarray, max_step: float, min_step: float | None, single_steps: bool,
                 bounds: np.ndarray | None, max_steps: int | None) -> None:
        self.name, self.loop, self.t_end, self.single = name, loop, t_end, single_steps
        self.t, self.x = t0, np.array(x0, dtype=float)
        n = self.x.size
        rtol = max(float(rtol), RTOL_FLOOR)
        atol = np.asarray(atol, dtype=float)
        if atol.ndim > 1 or atol.size not in (1, n):
            raise UserInputError(f"{name}: atol must be one number or {n} (one per state component); got shape "
                                 f"{atol.shape}")
        self.atol = np.ascontiguousarray(np.broadcast_to(atol, (n,)))
        self.limits = np.array([max_step, 0.0 if min_step is None else min_step, rtol])
        self.bounds = np.full(n, np.inf) if bounds is None else np.array(bounds, dtype=float)
        self.max_steps = NO_BUDGET if max_steps is None else max_steps
        self.f = self.loop.derivative(self.x)
        if not math.isfinite(self.f.sum()):
            raise DivergenceError(t0, name, 0.0, "non-finite derivative at the initial state")
        self.h_abs = initial_step(self.loop.derivative, t0, self.x, self.f, t_end, max_step, rtol, self.atol,
                                  name)
        self.K, self.F = np.empty((STAGES_DENSE, n)), np.empty((7, n))
        self.x_old, self.x_new = self.x.copy(), np.empty(n)
        self.t_old, self.h = t0, 0.0
        self.steps = self.rejected = self.dense_outputs = 0
        self.dense_ready = False

    def advance(self, t_target: float) -> None:
        budget = self.max_steps + 1 - self.steps    # one over: drive raises StepBudgetError
        status, t, t_old, self.h_abs, steps, rejected = self.loop.dop853(
            self.t, self.x, self.f, self.h_abs, t_target, self.t_end, self.limits, self.atol, self.single,
            self.bounds, budget, self.x_old, self.K, self.x_new)
        self.steps += steps
        self.rejected += rejected
        if steps:
            self.t, self.t_old, self.h, self.dense_ready = t, t_old, t - t_old, False
        if status == COLLAPSED:
            raise DivergenceError(self.t, self.name, self.h_abs, "step size collapsed")
        if status == BELOW_MIN_STEP:
            raise DivergenceError(self.t, self.name, self.h,
                                  f"step size collapsed below min_step={self.limits[1]:g} s")
        if status == NON_FINITE:
            raise DivergenceError(self.t, self.name, self.h_abs, "non-finite derivative inside a step")

    def interpolate(self, t: float) -> np.ndarray:
        if not self.dense_ready:
            self.loop.dop853_dense(self.K, self.h, self.x_old, self.x, self.F, self.x_new)
            self.dense_outputs += 1
            self.dense_ready = True
        out = np.empty_like(self.x)
        dense_state(self.F, self.x_old, (t - self.t_old) / self.h, out)
        return out

    def finish(self, stats: IntegratorStats) -> None:
        stats.steps, stats.rejected_steps = self.steps, self.rejected
        # f at x0 and the initial step's estimate, 12 per attempted step, 3 per dense output
        stats.rhs_evals = 2 + STAGES * (self.steps + self.rejected) + 3 * self.dense_outputs
        stats.jac_evals = stats.nonlinear_iterations = stats.nonlinear_convergence_failures = 0
