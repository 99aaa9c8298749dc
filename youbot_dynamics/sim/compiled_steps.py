"""The fixed-step loops (explicit Euler, semi-implicit Euler, RK4) of a robot alone under a
held torque, compiled: every step of an ``advance`` in one call, no Python per step.

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
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from youbot_dynamics.dynamics.compiled_tree import aba, work_for
from youbot_dynamics.dynamics.friction import left_torque_and_rates

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
def fixed_steps(method, ints, reals, table, joints, tau, x, t, t_target, dt, single, bounds, previous, stages):
    """Steps of ``FixedStepStepper.advance`` from (t, x) towards ``t_target`` (s): x is
    updated in place, ``previous`` receives the state before the last step. Stops after
    one step when ``single``, or after a step whose state is not finite or outside
    ``bounds``. Returns (t, t before the last step, the last step's size h, steps)."""
    n = ints.shape[0]
    work, left = work_for(ints), np.empty(n)
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
        if single:
            break
        bad = False
        for i in range(x.shape[0]):
            if not (math.isfinite(x[i]) and abs(x[i]) <= bounds[i]):
                bad = True
        if bad:
            break
    return t, t_previous, h, steps


class CompiledSteps:
    """The compiled loop of one robot under the held torque ``tau`` (N m, joint order):
    ``ints``, ``reals`` from :func:`~youbot_dynamics.dynamics.compiled_tree.tree_of`, the
    friction's ``table`` and LuGre ``joints``. Called as ``FixedStepStepper`` calls it:
    (method, t, x, t_target, dt, single, bounds, previous) -> (t, t_previous, h, steps)."""

    def __init__(self, ints: np.ndarray, reals: np.ndarray, table: np.ndarray, joints: np.ndarray,
                 tau: np.ndarray) -> None:
        self.tree, self.table, self.joints = (ints, reals), table, joints
        self.tau = np.array(tau, dtype=float)

    def __call__(self, method: str, t: float, x: np.ndarray, t_target: float, dt: float, single: bool,
                 bounds: np.ndarray, previous: np.ndarray) -> tuple[float, float, float, int]:
        stages = np.empty((5, x.shape[0]))
        return fixed_steps(METHOD_CODES[method], *self.tree, self.table, self.joints, self.tau, x, float(t),
                           float(t_target), float(dt), bool(single), bounds, previous, stages)
