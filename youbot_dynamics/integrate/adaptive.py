"""Adaptive and implicit integrators from scipy.integrate, driven one step at a time so that
every step is counted: Dormand-Prince 5(4) (RK45), DOP853, Radau IIA (order 5), BDF and
LSODA (ODEPACK's Adams/BDF pair that switches to BDF where it detects stiffness).

Counters: ``nfev``, ``njev``, ``nlu`` come from the solver. For the explicit Runge-Kutta
pairs every attempted step costs ``n_stages`` evaluations, so rejected steps are counted
exactly from the evaluations spent inside each ``step()`` call. scipy does not report
rejected steps or Newton iterations for Radau, BDF and LSODA: those counters are ``None``.

Non-finite values end the run with a DivergenceError: the right-hand side is wrapped by
:func:`~youbot_dynamics.integrate.drive.finite_rhs` (scipy's RK step loops for ever once
its step size is NaN) and a Jacobian with inf/NaN entries is caught at its factorisation.
A step that does not move the clock (LSODA's step size drops to 0 and it reports itself
running for ever) is a collapsed step size.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK45, Radau

from youbot_dynamics.integrate.errors import DivergenceError, IntegrationError
from youbot_dynamics.integrate.statistics import IntegratorStats

SCIPY_SOLVERS = {"rk45": RK45, "dop853": DOP853, "radau": Radau, "bdf": BDF, "lsoda": LSODA}
EXPLICIT = ("rk45", "dop853")

#: scipy's message when the step size underflows: the step size has collapsed.
STEP_COLLAPSE = "Required step size is less than spacing between numbers."


class ScipyStepper:
    """One scipy ``OdeSolver`` step per ``advance``; dense output for ``interpolate``."""

    def __init__(self, method: str, rhs: Callable[[float, np.ndarray], np.ndarray],
                 t0: float, x0: np.ndarray, t_end: float, rtol: float, atol,
                 jac, max_step: float, min_step: float | None, solver: str | None = None) -> None:
        """``method`` names the integrator in messages; ``solver`` is the scipy method run
        (default: ``method``)."""
        self.method, self.solver_name, self.min_step = method, solver or method, min_step
        options = {} if self.solver_name in EXPLICIT or jac is None else {"jac": jac}
        self.solver = SCIPY_SOLVERS[self.solver_name](rhs, t0, np.array(x0, dtype=float), t_end, rtol=rtol,
                                                      atol=atol, max_step=max_step, **options)
        self.t, self.x = t0, self.solver.y
        self.steps = self.rejected = 0
        self.h = 0.0
        self.dense = None

    def advance(self, t_target: float) -> None:
        solver = self.solver
        evals_before = solver.nfev
        try:
            message = solver.step()
        except ValueError as error:  # LU of a Jacobian with inf/NaN entries (radau, bdf)
            if "infs or NaNs" not in str(error):
                raise
            raise DivergenceError(solver.t, self.method, solver.step_size or math.nan,
                                  "non-finite Jacobian") from None
        stalled = solver.status == "running" and solver.step_size == 0
        if solver.status == "failed" or stalled:
            reason = message or "solver failed"
            if stalled or reason == STEP_COLLAPSE:
                raise DivergenceError(solver.t, self.method, solver.step_size or 0.0,
                                      "step size collapsed")
            raise IntegrationError(f"{self.method} failed at t={solver.t:.6g} s: {reason}")
        self.steps += 1
        if self.solver_name in EXPLICIT:
            self.rejected += (solver.nfev - evals_before) // solver.n_stages - 1
        if self.min_step is not None and solver.step_size < self.min_step \
                and solver.status == "running":
            raise DivergenceError(solver.t, self.method, solver.step_size,
                                  f"step size collapsed below min_step={self.min_step:g} s")
        self.h = solver.t - solver.t_old
        self.t, self.x, self.dense = solver.t, solver.y, None

    def interpolate(self, t: float) -> np.ndarray:
        if self.dense is None:
            self.dense = self.solver.dense_output()
        return self.dense(t)

    def finish(self, stats: IntegratorStats) -> None:
        solver = self.solver
        # int(): LSODA's counters are numpy integers from its Fortran work array
        stats.steps, stats.rhs_evals, stats.jac_evals = self.steps, int(solver.nfev), int(solver.njev)
        if self.solver_name in EXPLICIT:
            stats.rejected_steps = self.rejected
            stats.nonlinear_iterations = stats.nonlinear_convergence_failures = 0
        else:
            stats.rejected_steps = stats.nonlinear_iterations = None
            stats.nonlinear_convergence_failures = None
