"""Radau IIA of order 5 for differential-algebraic equations M y' = f(t, y) of index 1, 2
and 3 (integrator ``radau5``), after Hairer and Wanner's RADAU5 (Solving ODEs II, sec. IV.8
and VII.8; the code the IVP test set runs on Andrew's squeezer).

The method. Three-stage collocation at c = ((4 - sqrt 6)/10, (4 + sqrt 6)/10, 1); the
stage increments Z solve M Z_i = h sum_j a_ij f(t + c_j h, y + Z_j). Simplified Newton on the
transformed increments W = T^-1 Z splits the 3n x 3n system into one real system
(gamma/h M - J) and one complex system ((alpha + i beta)/h M - J), factored once per step
size and Jacobian (J = df/dy, kept across steps while Newton contracts at a rate
theta <= 1e-3). Newton follows RADAU5: at most 7 iterations; converged when
theta / (1 - theta) |dW| <= kappa tol (|dW| <= kappa tol at the first iteration: RADAU5
carries theta over from the last step there, which on the circle test of
test_radau_dae.py lost two digits of q) with kappa tol = max(10 eps / rtol, min(0.03, sqrt(rtol))); when the rate
predicts no convergence in the iterations left, h is cut by RADAU5's factor from that
prediction, and a diverging or unfinished iteration halves h; either recomputes J if it is
not current. The error estimate is
RADAU5's (gamma/h M - J)^-1 (f(t, y) + M (e . Z) / h), improved once by a further f call
after a rejection or on the first step; the step size follows Gustafsson's predictive
controller with the safety factor 0.9 (2 k_max + 1) / (2 k_max + k).

Index-dependent error scaling (Hairer, Lubich and Roche 1989; RADAU5's NIND2, NIND3): the
weight of a component of index 2 is divided by h and of index 3 by h^2, in the error test
and in Newton's norm. For a mechanism in index-3 form y = (q, v, w, lambda), q is of
index 1, v of index 2, w and lambda of index 3: their local errors, O(h^2) and O(h) larger
than q's by the nature of the method, no longer force tiny steps, and what the test keeps
within rtol is q. ``index`` all ones is the plain error test on every component.

Tolerances are used as given (scipy's Radau convention), not mapped to 0.1 rtol^(2/3) as
the Fortran RADAU5 does. Dense output is the collocation polynomial. Counters: steps,
f evaluations, Jacobians, rejected steps (error-test failures), Newton iterations and
Newton convergence failures, LU factorisations (of the real/complex pair).
"""
from __future__ import annotations

import time
from typing import Callable, Sequence

import numpy as np
from scipy.linalg import lu_factor, lu_solve

from youbot_dynamics.dynamics.constraints import DaeForm
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.drive import Solution, StateCheck, drive, state_names_or_default
from youbot_dynamics.integrate.errors import DivergenceError
from youbot_dynamics.integrate.integrators import checked_positive, checked_state, checked_times
from youbot_dynamics.integrate.statistics import IntegratorStats

__all__ = ["Radau5Dae", "integrate_radau_dae", "holonomic_index", "integrate_dae_form"]

SQRT6 = 6.0 ** 0.5
#: Collocation nodes.
C = np.array([(4.0 - SQRT6) / 10.0, (4.0 + SQRT6) / 10.0, 1.0])
#: Error estimate weights (RADAU5's DD1..DD3, gamma_0 folded in).
E = np.array([-13.0 - 7.0 * SQRT6, -13.0 + 7.0 * SQRT6, -1.0]) / 3.0
#: Eigenvalues of A^-1: one real, one complex pair.
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)
MU_COMPLEX = (3.0 + 0.5 * (3.0 ** (1.0 / 3.0) - 3.0 ** (2.0 / 3.0))
              - 0.5j * (3.0 ** (5.0 / 6.0) + 3.0 ** (7.0 / 6.0)))
#: T^-1 A^-1 T = diag(MU_REAL, [[Re, -Im], [Im, Re]] of MU_COMPLEX).
T = np.array([[0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
              [0.25021312296533332, 0.20412935229379994, -0.38294211275726192],
              [1.0, 1.0, 0.0]])
TI = np.array([[4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
               [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
               [0.50287263494578682, -2.57192694985560522, 0.59603920482822492]])
TI_REAL = TI[0]
TI_COMPLEX = TI[1] + 1j * TI[2]
#: The collocation polynomial: y(t_old + x h) = y_old + (Z^T P) (x, x^2, x^3).
P = np.array([[13.0 / 3.0 + 7.0 * SQRT6 / 3.0, -23.0 / 3.0 - 22.0 * SQRT6 / 3.0,
               10.0 / 3.0 + 5.0 * SQRT6],
              [13.0 / 3.0 - 7.0 * SQRT6 / 3.0, -23.0 / 3.0 + 22.0 * SQRT6 / 3.0,
               10.0 / 3.0 - 5.0 * SQRT6],
              [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0]])
#: Newton iterations per step (RADAU5's default NIT).
NEWTON_MAXITER = 7
MIN_FACTOR, MAX_FACTOR = 0.2, 10.0
#: Keep h (and the factorisations) when the controller asks for a growth below this.
KEEP_STEP_BELOW = 1.2
#: Recompute J after a step whose Newton contracted more slowly than this (RADAU5's THET).
JACOBIAN_RATE = 1e-3
#: Step-size factor after a diverging or unfinished Newton iteration.
UNEXPECTED_FACTOR = 0.5
EPS = np.finfo(float).eps
#: RADAU5's default first step (s) when none is given.
FIRST_STEP = 1e-6


def rms(values: np.ndarray) -> float:
    """Root mean square of all entries (RADAU5's norm)."""
    return float(np.sqrt(np.mean(np.square(values))))


def forward_difference_jacobian(fun: Callable, t: float, y: np.ndarray, f: np.ndarray
                                ) -> np.ndarray:
    """df/dy by forward differences, increments sqrt(eps) max(|y_j|, 1e-5) (RADAU5's)."""
    jacobian = np.empty((f.size, y.size))
    for j in range(y.size):
        step = np.sqrt(EPS) * max(abs(y[j]), 1e-5)
        shifted = y.copy()
        shifted[j] += step
        jacobian[:, j] = (fun(t, shifted) - f) / step
    return jacobian


class Radau5Dae:
    """Radau IIA (order 5) on M y' = f(t, y) from a consistent y0, one accepted step per
    ``advance`` (a :class:`~youbot_dynamics.integrate.drive.Stepper` for ``drive``).

    ``mass``: constant (n, n) M (singular for a DAE); ``index[i]`` in {1, 2, 3}: the index
    of y_i, whose error weight atol_i + rtol |y_i| is divided by h^(index_i - 1);
    ``jac(t, y)``: df/dy (forward differences without it); times in s.
    """

    def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray],
                 jac: Callable[[float, np.ndarray], np.ndarray] | None, mass: np.ndarray,
                 t0: float, y0: np.ndarray, t_end: float, rtol: float, atol,
                 index: np.ndarray, first_step: float | None = None,
                 max_step: float = np.inf) -> None:
        self.name = "radau5"
        self.counters = dict(rhs_evals=0, jac_evals=0, rejected_steps=0,
                             nonlinear_iterations=0, nonlinear_convergence_failures=0,
                             lu_decompositions=0)
        self.user_fun, self.user_jac = fun, jac
        self.mass = np.array(mass, dtype=float)
        self.t_end, self.rtol, self.max_step = float(t_end), float(rtol), float(max_step)
        self.atol = np.broadcast_to(np.asarray(atol, dtype=float), y0.shape).copy()
        self.exponent = np.asarray(index, dtype=float) - 1.0
        self.newton_tol = max(10.0 * EPS / rtol, min(0.03, rtol ** 0.5))
        self.t, self.x = float(t0), np.array(y0, dtype=float)
        self.f = self.fun(self.t, self.x)
        self.jacobian = self.jac(self.t, self.x, self.f)
        self.current_jac = True
        self.lu: tuple | None = None
        self.h_next = min(first_step or FIRST_STEP, t_end - t0)
        self.h, self.h_old, self.error_old = 0.0, None, None
        self.t_old, self.y_old, self.Q = None, None, None
        self.steps = 0

    def fun(self, t: float, y: np.ndarray) -> np.ndarray:
        self.counters["rhs_evals"] += 1
        return self.user_fun(t, y)

    def jac(self, t: float, y: np.ndarray, f: np.ndarray) -> np.ndarray:
        self.counters["jac_evals"] += 1
        if self.user_jac is None:
            return forward_difference_jacobian(self.fun, t, y, f)
        return np.asarray(self.user_jac(t, y), dtype=float)

    def weights(self, magnitude: np.ndarray, h: float) -> np.ndarray:
        """atol + rtol |y|, divided by h^(index - 1) (the index-dependent scaling)."""
        return (self.atol + self.rtol * magnitude) / h ** self.exponent

    def factorise(self, h: float) -> tuple:
        """LU of (MU_REAL / h) M - J and (MU_COMPLEX / h) M - J."""
        self.counters["lu_decompositions"] += 1
        return (lu_factor(MU_REAL / h * self.mass - self.jacobian, check_finite=False),
                lu_factor(MU_COMPLEX / h * self.mass - self.jacobian, check_finite=False))

    def collocation(self, h: float, Z0: np.ndarray, scale: np.ndarray
                    ) -> tuple[float | None, int, np.ndarray, float]:
        """Simplified Newton on the stage increments with RADAU5's tests. Returns (None
        when converged, else the factor for h; iterations; Z; theta, the contraction
        rate, JACOBIAN_RATE when it converged at the first iteration)."""
        lu_real, lu_complex = self.lu
        W, Z = TI @ Z0, Z0
        dW = np.empty_like(W)
        faccon = 1.0
        theta, previous, previous_ratio = JACOBIAN_RATE, None, None
        for k in range(NEWTON_MAXITER):
            F = np.array([self.fun(self.t + C[i] * h, self.x + Z[i]) for i in range(3)])
            if not np.all(np.isfinite(F)):
                return UNEXPECTED_FACTOR, k + 1, Z, theta
            f_real = F.T @ TI_REAL - MU_REAL / h * (self.mass @ W[0])
            f_complex = F.T @ TI_COMPLEX - MU_COMPLEX / h * (self.mass @ (W[1] + 1j * W[2]))
            dW[0] = lu_solve(lu_real, f_real, check_finite=False)
            complex_step = lu_solve(lu_complex, f_complex, check_finite=False)
            dW[1], dW[2] = complex_step.real, complex_step.imag
            norm = rms(dW / scale)
            if previous is not None and k < NEWTON_MAXITER - 1:
                ratio = norm / previous
                theta = ratio if previous_ratio is None else np.sqrt(ratio * previous_ratio)
                previous_ratio = ratio
                if theta >= 0.99:
                    return UNEXPECTED_FACTOR, k + 1, Z, theta
                faccon = theta / (1.0 - theta)
                remaining = NEWTON_MAXITER - 2 - k
                predicted = faccon * norm * theta ** remaining / self.newton_tol
                if predicted >= 1:  # too slow to converge within the iterations left
                    quotient = max(1e-4, min(20.0, predicted))
                    return 0.8 * quotient ** (-1.0 / (4.0 + remaining)), k + 1, Z, theta
            previous = max(norm, EPS)
            W += dW
            Z = T @ W
            if faccon * norm <= self.newton_tol:
                return None, k + 1, Z, theta
        return UNEXPECTED_FACTOR, NEWTON_MAXITER, Z, theta

    def advance(self, t_target: float) -> None:
        """One accepted step (the last one ends exactly at t_end)."""
        t, y = self.t, self.x
        h = min(self.h_next, self.max_step)
        rejected = False
        first = self.Q is None
        while True:
            if h < 10.0 * np.spacing(max(abs(t), abs(self.t_end))):
                raise DivergenceError(t, self.name, h, "step size collapsed")
            h = min(h, self.t_end - t)
            Z0 = np.zeros((3, y.size)) if first else self.interpolate(t + C * h).T - y
            if self.lu is None:
                self.lu = self.factorise(h)
            scale = self.weights(np.abs(y), h)
            failed, iterations, Z, theta = self.collocation(h, Z0, scale)
            self.counters["nonlinear_iterations"] += iterations
            if failed is not None:
                self.counters["nonlinear_convergence_failures"] += 1
                h *= failed
                if not self.current_jac:
                    self.jacobian = self.jac(t, y, self.f)
                    self.current_jac = True
                self.lu, rejected = None, True
                continue
            y_new = y + Z[-1]
            mass_ze = self.mass @ (Z.T @ E) / h
            error_scale = self.weights(np.maximum(np.abs(y), np.abs(y_new)), h)
            error = lu_solve(self.lu[0], self.f + mass_ze, check_finite=False)
            error_norm = rms(error / error_scale)
            if error_norm > 1 and (rejected or first):
                error = lu_solve(self.lu[0], self.fun(t, y + error) + mass_ze,
                                 check_finite=False)
                error_norm = rms(error / error_scale)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + iterations)
            if error_norm > 1:
                self.counters["rejected_steps"] += 1
                h *= max(MIN_FACTOR, safety * error_norm ** -0.25)
                self.lu, rejected = None, True
                continue
            break
        self.accept(t, y, h, y_new, Z, error_norm, safety, theta > JACOBIAN_RATE)

    def accept(self, t: float, y: np.ndarray, h: float, y_new: np.ndarray, Z: np.ndarray,
               error_norm: float, safety: float, recompute_jac: bool) -> None:
        """Take the step; Gustafsson's predictive step-size choice for the next one,
        keeping h and the factorisations when J stays and h would grow by less than
        KEEP_STEP_BELOW."""
        if self.h_old is None or self.error_old is None or error_norm == 0:
            multiplier = 1.0
        else:
            multiplier = h / self.h_old * (self.error_old / error_norm) ** 0.25
        with np.errstate(divide="ignore"):
            factor = min(MAX_FACTOR, safety * min(1.0, multiplier) * error_norm ** -0.25)
        if not recompute_jac and 1.0 <= factor < KEEP_STEP_BELOW:
            factor = 1.0
        else:
            self.lu = None
        self.steps += 1
        self.t_old, self.y_old, self.Q = t, y, Z.T @ P
        self.t, self.x, self.h = t + h, y_new, h
        if self.t_end - self.t <= 1e-12 * max(abs(self.t_end), 1.0):
            self.t = self.t_end
        self.f = self.fun(self.t, y_new)
        self.current_jac = recompute_jac
        if recompute_jac:
            self.jacobian = self.jac(self.t, y_new, self.f)
        self.h_old, self.error_old = h, error_norm
        self.h_next = h * factor

    def interpolate(self, t) -> np.ndarray:
        """The collocation polynomial of the last step at t (s; a scalar or an array of
        times, then one column per time)."""
        x = (np.asarray(t, dtype=float) - self.t_old) / self.h
        powers = np.cumprod(np.stack([x, x, x]), axis=0)
        if np.ndim(t) == 0:
            return self.y_old + self.Q @ powers
        return self.y_old[:, None] + self.Q @ powers

    def finish(self, stats: IntegratorStats) -> None:
        stats.steps = self.steps
        for name in ("rhs_evals", "jac_evals", "rejected_steps", "nonlinear_iterations",
                     "nonlinear_convergence_failures"):
            setattr(stats, name, self.counters[name])


def integrate_radau_dae(fun: Callable[[float, np.ndarray], np.ndarray], mass, y0, t_eval,
                        *, index: Sequence[int] | None = None, rtol: float = 1e-6,
                        atol: float | np.ndarray = 1e-8,
                        jac: Callable[[float, np.ndarray], np.ndarray] | None = None,
                        state_names: Sequence[str] | None = None,
                        first_step: float | None = None, max_step: float = np.inf,
                        max_steps: int | None = None) -> tuple[Solution, dict]:
    """Solve M y' = f(t, y) with :class:`Radau5Dae` from a consistent y0 at t_eval[0]
    with outputs at t_eval (s). ``index`` (default all 1): each component's index, 1 to 3.
    Returns the Solution and the solver's counters (with ``lu_decompositions``)."""
    start = time.perf_counter()
    times = checked_times(t_eval)
    y = checked_state("y0", y0)
    mass = np.asarray(mass, dtype=float)
    indices = np.ones(y.size, dtype=int) if index is None else np.asarray(index).ravel()
    if mass.shape != (y.size, y.size) or indices.size != y.size:
        raise UserInputError(f"radau5: y0 has {y.size} components but the mass matrix is "
                             f"{mass.shape} and index has {indices.size} entries")
    if not np.all(np.isin(indices, (1, 2, 3))):
        raise UserInputError(f"radau5: each index must be 1, 2 or 3, got {indices.tolist()}")
    checked_positive("rtol", rtol)
    checked_positive("atol", atol)
    names = state_names_or_default(state_names, y.size)
    stepper = Radau5Dae(fun, jac, mass, times[0], y, times[-1], rtol, atol, indices,
                        first_step, max_step)
    solution = drive(stepper, "radau5", times, (), StateCheck("radau5", names, None, None),
                     names, max_steps=max_steps)
    solution.stats.wall_time = time.perf_counter() - start
    return solution, dict(stepper.counters)


def holonomic_index(form: DaeForm) -> np.ndarray:
    """The index of each component of a holonomic DAE form's y, for its error weights.
    ``index3``: q 1, v 2, w and lambda 3 (Hairer's classification); ``index2``: q and v 1,
    w and lambda 2; ``ggl``: as index2, and mu (zero on exact solutions) weighted as
    index 3: with index-2 weights on mu the squeezer's step collapsed at t = 5e-5 s at
    rtol 1e-8, atol 1e-11 (2135 steps at rtol 1e-6); with index 3, 668 steps and 7.2e-10."""
    index = np.ones(form.y0.size, dtype=int)
    if form.name == "index3":
        index[form.n:2 * form.n] = 2
        index[2 * form.n:] = 3
    else:
        index[2 * form.n:3 * form.n + form.m] = 2
        index[3 * form.n + form.m:] = 3
    return index


def integrate_dae_form(form: DaeForm, t_eval, *, rtol: float, atol: float | np.ndarray,
                       exact_jacobian: bool = True, index_scaling: bool = True,
                       first_step: float | None = None,
                       max_steps: int | None = None) -> tuple[Solution, dict]:
    """A holonomic DAE form (residual F(t, y, y') = M y' - f(t, y), linear in y' with a
    constant M) with :func:`integrate_radau_dae`: M = dF/dy' (read off the residual, exact
    for a linear dependence), f(t, y) = -F(t, y, 0), df/dy = -dF/dy from the form's exact
    iteration matrix at cj = 0 when ``exact_jacobian`` (else forward differences).
    ``index_scaling``: Hairer's index-dependent weights (:func:`holonomic_index`); False
    puts every component in the error test with its plain weight."""
    t0, size = float(np.asarray(t_eval)[0]), form.y0.size
    base = form.residual(t0, form.y0, form.yp0)
    mass = np.array([form.residual(t0, form.y0, form.yp0 + unit) - base
                     for unit in np.eye(size)]).T
    zero = np.zeros(size)

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        return -form.residual(t, y, zero)

    jac = None
    if exact_jacobian and form.residual_jacobian is not None:
        def jac(t: float, y: np.ndarray) -> np.ndarray:
            return -form.residual_jacobian(t, y, zero, 0.0)

    index = holonomic_index(form) if index_scaling else None
    return integrate_radau_dae(fun, mass, form.y0, t_eval, index=index, rtol=rtol, atol=atol,
                               jac=jac, state_names=form.state_names, first_step=first_step,
                               max_steps=max_steps)
