"""Fixed-step integrators written as tight loops: explicit Euler, semi-implicit
(symplectic) Euler and classic Runge-Kutta 4.

Steps have size dt except the last before an output time, which lands on it exactly
(h = min(dt, distance to the output)). Events are located by *re-stepping*: the state at a
time t inside the step [t_k, t_k + h] is the method's own step of size t - t_k from t_k, and
Brent's method finds the zero of the event function on it (see integration.drive).

A right-hand side may carry a compiled form of these loops as its ``compiled_steps``
attribute (see :class:`CompiledLoop`; a robot alone under a held torque has one,
:mod:`youbot_dynamics.sim.compiled_steps`): ``advance`` then runs its steps in one call
(the same steps, the same checks after each).
"""
from __future__ import annotations

from typing import Callable, Protocol

import numpy as np

from youbot_dynamics.integrate.drive import StateCheck
from youbot_dynamics.integrate.statistics import IntegratorStats

Rhs = Callable[[float, np.ndarray], np.ndarray]


def euler_step(rhs: Rhs, t: float, x: np.ndarray, h: float, n: int) -> np.ndarray:
    """Explicit Euler: x_{k+1} = x_k + h f(t_k, x_k)."""
    return x + h * rhs(t, x)


def symplectic_euler_step(rhs: Rhs, t: float, x: np.ndarray, h: float, n: int) -> np.ndarray:
    """Semi-implicit Euler for x = [q (n), v (n), extra]: v_{k+1} = v_k + h a(t_k, q_k, v_k),
    q_{k+1} = q_k + h v_{k+1}; extra states by explicit Euler."""
    x_new = x + h * rhs(t, x)
    x_new[:n] = x[:n] + h * x_new[n:2 * n]
    return x_new


def rk4_step(rhs: Rhs, t: float, x: np.ndarray, h: float, n: int) -> np.ndarray:
    """Classic fourth-order Runge-Kutta step."""
    half = 0.5 * h
    k1 = rhs(t, x)
    k2 = rhs(t + half, x + half * k1)
    k3 = rhs(t + half, x + half * k2)
    k4 = rhs(t + h, x + h * k3)
    return x + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)


#: name -> (step function, right-hand-side evaluations per step)
FIXED_STEP_METHODS = {
    "euler": (euler_step, 1),
    "symplectic_euler": (symplectic_euler_step, 1),
    "rk4": (rk4_step, 4),
}


class CompiledLoop(Protocol):
    """The steps of :meth:`FixedStepStepper.advance` in one call: from (t, x) towards
    t_target, x updated in place, ``previous`` set to the state before the last step; one
    step when ``single``, else up to t_target or the first step whose state is not finite or
    beyond ``bounds``. Returns (t, t before the last step, the last step's size, steps)."""

    def __call__(self, method: str, t: float, x: np.ndarray, t_target: float, dt: float, single: bool,
                 bounds: np.ndarray, previous: np.ndarray) -> tuple[float, float, float, int]: ...


class FixedStepStepper:
    """Advances with steps of dt; one step per ``advance`` when events need watching, else
    every step up to the output time in one tight loop (checked after each step)."""

    def __init__(self, method: str, rhs: Rhs, t0: float, x0: np.ndarray, dt: float,
                 n_positions: int, single_steps: bool, check: StateCheck) -> None:
        self.step_function, self.evals_per_step = FIXED_STEP_METHODS[method]
        self.rhs, self.dt, self.n = rhs, dt, n_positions
        self.single_steps, self.check = single_steps, check
        self.t, self.x = t0, np.array(x0, dtype=float)
        self.t_previous, self.x_previous = t0, self.x
        self.steps = self.extra_evals = 0
        self.h = 0.0
        self.method = method
        self.compiled: CompiledLoop | None = getattr(rhs, "compiled_steps", None)
        self.bounds = np.full(self.x.shape, np.inf) if check.bounds is None else np.array(check.bounds, dtype=float)

    def advance(self, t_target: float) -> None:
        if self.compiled is not None:
            x, previous = self.x.copy(), np.empty_like(self.x)
            t, t_previous, h, steps = self.compiled(self.method, self.t, x, t_target, self.dt, self.single_steps,
                                                    self.bounds, previous)
            if steps:
                self.t_previous, self.x_previous = t_previous, previous
                self.check.step(t, x, h)
                self.t, self.x, self.h = t, x, h
                self.steps += steps
            return
        step, rhs, dt, n, check = self.step_function, self.rhs, self.dt, self.n, self.check
        t, x = self.t, self.x
        tolerance = 1e-9 * dt
        steps, h = 0, self.h
        while t < t_target:
            remaining = t_target - t
            h = remaining if remaining <= dt + tolerance else dt
            self.t_previous, self.x_previous = t, x
            x = step(rhs, t, x, h, n)
            t = t_target if h == remaining else t + h
            steps += 1
            check.step(t, x, h)
            if self.single_steps:
                break
        self.t, self.x, self.h = t, x, h
        self.steps += steps

    def interpolate(self, t: float) -> np.ndarray:
        self.extra_evals += self.evals_per_step
        return self.step_function(self.rhs, self.t_previous, self.x_previous,
                                  t - self.t_previous, self.n)

    def finish(self, stats: IntegratorStats) -> None:
        stats.steps = self.steps
        stats.rhs_evals = self.steps * self.evals_per_step + self.extra_evals
        stats.jac_evals = stats.rejected_steps = 0
        stats.nonlinear_iterations = stats.nonlinear_convergence_failures = 0
