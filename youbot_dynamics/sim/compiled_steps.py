"""The integration loops of a robot alone under a held torque, compiled: the fixed-step
ones (explicit Euler, semi-implicit Euler, RK4) and DOP853 with its step-size control
(``dop853_compiled``), every step of an ``advance`` in one call, no Python per step.

The same steps as :mod:`youbot_dynamics.integrate.fixed_step` (the same arithmetic in the
same order: x + h f; x + (h / 6) (k1 + 2 (k2 + k3) + k4); the step sizes of
``FixedStepStepper.advance``) on the state x = [q (n), v (n), z (LuGre bristles)] with

    dq/dt = v,   dv/dt = ABA(q, v, tau - tau_friction(v, z)),   dz/dt = LuGre rates,

ABA from :mod:`youbot_dynamics.dynamics.compiled_tree` (Pinocchio's algorithm; equal to
pin.aba to rounding) and the friction laws of :mod:`youbot_dynamics.dynamics.friction`. So a
run matches the Python loop over pin.aba to rounding (test_compiled_steps). The divergence
checks of :class:`~youbot_dynamics.integrate.drive.StateCheck` (finite, within bounds) run
after every step: the loop stops at the first step that fails them and leaves it to the
Python check to raise with that step's time.

DOP853's arithmetic is :mod:`youbot_dynamics.integrate.dop853`'s (numba caches no function
that takes another compiled function, so the loop that calls this module's derivative
between its kernels is written here): the steps of scipy's DOP853 on the same system.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from youbot_dynamics.dynamics.compiled_tree import aba, work_for
from youbot_dynamics.dynamics.friction import left_torque_and_rates
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.dop853 import (BAD_STATE, BELOW_MIN_STEP, COLLAPSED, NON_FINITE, REACHED, STAGES,
                                              STAGES_DENSE, dense_coefficients, error_norm, minimum_step, stage_state,
                                              step_factor)
from youbot_dynamics.integrate.drive import finite_within

METHOD_CODES = {"euler": 0, "symplectic_euler": 1, "rk4": 2}


@njit(cache=True)
def _derivative(ints, reals, table, joints, tau, x, work, left, dx) -> None:
    """dx = dx/dt at x (see the module docstring); ``left`` (n) scratch."""
    n = ints.shape[0]
    q, v, z = x[:n], x[n:2 * n], x[2 * n:]
    left_torque_and_rates(v, z, tau, table, joints, left, dx[2 * n:])
    aba(ints, reals, q, v, left, work, dx[n:2 * n])
    dx[:n] = v


@njit(cache=True)
def _step(method, ints, reals, table, joints, tau, x, h, n, work, left, stages, out) -> None:
    """out = one step of size h (s) from x; ``stages`` (5, size) scratch."""
    k1, k2, k3, k4, point = stages[0], stages[1], stages[2], stages[3], stages[4]
    _derivative(ints, reals, table, joints, tau, x, work, left, k1)
    if method == 2:
        half = 0.5 * h
        for i in range(x.shape[0]):
            point[i] = x[i] + half * k1[i]
        _derivative(ints, reals, table, joints, tau, point, work, left, k2)
        for i in range(x.shape[0]):
            point[i] = x[i] + half * k2[i]
        _derivative(ints, reals, table, joints, tau, point, work, left, k3)
        for i in range(x.shape[0]):
            point[i] = x[i] + h * k3[i]
        _derivative(ints, reals, table, joints, tau, point, work, left, k4)
        sixth = h / 6.0
        for i in range(x.shape[0]):
            out[i] = x[i] + sixth * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i])
        return
    for i in range(x.shape[0]):
        out[i] = x[i] + h * k1[i]
    if method == 1:
        for i in range(n):
            out[i] = x[i] + h * out[n + i]


@njit(cache=True)
def fixed_steps(method, ints, reals, table, joints, tau, x, t, t_target, dt, single, bounds, previous, stages, work,
                left):
    """Steps of ``FixedStepStepper.advance`` from (t, x) towards ``t_target`` (s): x is
    updated in place, ``previous`` receives the state before the last step. Stops after
    one step when ``single``, or after a step whose state is not finite or outside
    ``bounds``. Returns (t, t before the last step, the last step's size h, steps);
    ``stages`` (5, size), ``work`` (compiled_tree.work_for) and ``left`` (n) scratch."""
    n = ints.shape[0]
    tolerance = 1e-9 * dt
    steps, h, t_previous = 0, 0.0, t
    while t < t_target:
        remaining = t_target - t
        h = remaining if remaining <= dt + tolerance else dt
        t_previous = t
        previous[:] = x
        _step(method, ints, reals, table, joints, tau, previous, h, n, work, left, stages, x)
        t = t_target if h == remaining else t + h
        steps += 1
        if single or not finite_within(x, bounds):
            break
    return t, t_previous, h, steps


@njit(cache=True)
def _dop853_attempt(ints, reals, table, joints, tau, x, h, K, x_new, work, left) -> bool:
    """One attempted DOP853 step of size h (s) from x, K[0] = f(x) on entry: stages 1-11
    into K, x_new = the new state and K[12] = f(x_new). False at a derivative that is not
    finite."""
    for s in range(1, STAGES + 1):
        stage_state(x, K, s, h, x_new)
        _derivative(ints, reals, table, joints, tau, x_new, work, left, K[s])
        if not math.isfinite(K[s].sum()):
            return False
    return True


@njit(cache=True)
def dop853_steps(ints, reals, table, joints, tau, t, x, f, h_abs, t_target, t_end, limits, atol, single, bounds,
                 budget, x_old, K, x_new, work, left):
    """DOP853 steps from (t, x) towards ``t_target`` (s) as
    :meth:`~youbot_dynamics.integrate.dop853.CompiledDop853.dop853` describes them (the
    arguments and the result are its, after the robot's tree, friction and torque, and
    before the ``work`` and ``left`` scratch of :func:`_derivative`)."""
    max_step, min_step, rtol = limits[0], limits[1], limits[2]
    steps, rejected, t_old = 0, 0, t
    while t < t_target and steps < budget:
        floor = minimum_step(t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < floor:
            h_abs = floor
        after_rejection = False
        while True:
            if h_abs < floor:
                return COLLAPSED, t, t_old, h_abs, steps, rejected
            t_new = min(t + h_abs, t_end)
            h = t_new - t
            h_abs = abs(h)
            K[0] = f
            if not _dop853_attempt(ints, reals, table, joints, tau, x, h, K, x_new, work, left):
                return NON_FINITE, t, t_old, h_abs, steps, rejected
            norm = error_norm(K, h, x, x_new, rtol, atol)
            h_abs *= step_factor(norm, after_rejection)
            if norm < 1.0:
                break
            after_rejection = True
            rejected += 1
        x_old[:] = x
        x[:] = x_new
        f[:] = K[STAGES]
        t_old, t = t, t_new
        steps += 1
        if not finite_within(x, bounds):
            return BAD_STATE, t, t_old, h_abs, steps, rejected
        if h < min_step and t < t_end:
            return BELOW_MIN_STEP, t, t_old, h_abs, steps, rejected
        if single:
            break
    return REACHED, t, t_old, h_abs, steps, rejected


@njit(cache=True)
def dop853_dense(ints, reals, table, joints, tau, K, h, x_old, x, F, scratch, work, left) -> None:
    """F = the dense output's coefficients of the step of size h (s) from x_old to x: its
    3 extra stages into K[13..15] (``scratch`` holds their states), then
    :func:`~youbot_dynamics.integrate.dop853.dense_coefficients`."""
    for s in range(STAGES + 1, STAGES_DENSE):
        stage_state(x_old, K, s, h, scratch)
        _derivative(ints, reals, table, joints, tau, scratch, work, left, K[s])
    dense_coefficients(K, h, x_old, x, F)


class CompiledSteps:
    """The compiled loops of one robot under the held torque ``tau`` (N m, joint order):
    ``ints``, ``reals`` from :func:`~youbot_dynamics.dynamics.compiled_tree.tree_of`, the
    friction's ``table`` and LuGre ``joints``; the state x = [q, v, z] has 2 n + len(joints)
    entries. Called as ``FixedStepStepper`` calls it: (method, t, x, t_target, dt, single,
    bounds, previous) -> (t, t_previous, h, steps); DOP853's loop as
    :class:`~youbot_dynamics.integrate.dop853.CompiledDop853`. Holds its scratch arrays."""

    def __init__(self, ints: np.ndarray, reals: np.ndarray, table: np.ndarray, joints: np.ndarray,
                 tau: np.ndarray) -> None:
        self.system = (ints, reals, table, joints, np.array(tau, dtype=float))
        n = ints.shape[0]
        self.size = 2 * n + joints.shape[0]
        self.stages, self.scratch = np.empty((5, self.size)), (work_for(ints), np.empty(n))

    def _checked(self, x: np.ndarray) -> np.ndarray:
        """x if it is a state of this robot (float64, (2 n + LuGre joints,)); a UserInputError
        naming the sizes otherwise (the loops index their scratch by the model's size)."""
        if x.shape != (self.size,) or x.dtype != np.float64:
            raise UserInputError(f"compiled loop: the state x = [q, v, z] needs {self.size} float64 values; got "
                                 f"shape {x.shape}, dtype {x.dtype}")
        return x

    def __call__(self, method: str, t: float, x: np.ndarray, t_target: float, dt: float, single: bool,
                 bounds: np.ndarray, previous: np.ndarray) -> tuple[float, float, float, int]:
        return fixed_steps(METHOD_CODES[method], *self.system, self._checked(x), float(t), float(t_target), float(dt),
                           bool(single), bounds, previous, self.stages, *self.scratch)

    def derivative(self, x: np.ndarray) -> np.ndarray:
        """dx/dt at x (a new array; see the module docstring)."""
        dx = np.empty(x.shape[0])
        _derivative(*self.system, self._checked(np.ascontiguousarray(x, dtype=float)), *self.scratch, dx)
        return dx

    def dop853(self, t: float, x: np.ndarray, f: np.ndarray, h_abs: float, t_target: float, t_end: float,
               limits: np.ndarray, atol: np.ndarray, single: bool, bounds: np.ndarray, budget: int,
               x_old: np.ndarray, K: np.ndarray, x_new: np.ndarray) -> tuple[int, float, float, float, int, int]:
        """DOP853 steps towards t_target (s): :func:`dop853_steps`."""
        return dop853_steps(*self.system, float(t), self._checked(x), f, float(h_abs), float(t_target), float(t_end), limits, atol,
                            bool(single), bounds, int(budget), x_old, K, x_new, *self.scratch)

    def dop853_dense(self, K: np.ndarray, h: float, x_old: np.ndarray, x: np.ndarray, F: np.ndarray,
                     scratch: np.ndarray) -> None:
        """The last step's dense output coefficients: :func:`dop853_dense`."""
        dop853_dense(*self.system, K, float(h), x_old, x, F, scratch, *self.scratch)
