"""IDA's own counters (integrate/sundials.py reads them out of SUNDIALS) against what the run
shows from outside: every residual call, and the trial times at which IDA calls it."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.integrate.integrators import integrate_dae


def steep_forced_dae(calls: list):
    """x' = -x + z, 0 = z - (sin t + tanh(50 (1 - t))): z falls by 2 within about 0.05 s
    of t = 1, where IDA's error test fails. Every call's t is appended to ``calls``."""
    def residual(t, y, yp):
        calls.append(t)
        return np.array([yp[0] + y[0] - y[1], y[1] - np.sin(t) - np.tanh(50.0 * (1.0 - t))])
    return residual


def jacobian(t, y, yp, cj):
    return np.array([[cj + 1.0, -1.0], [0.0, 1.0]])


@pytest.mark.parametrize("suppress", [False, True])
def test_ida_counters_match_the_residual_calls_and_trial_steps(suppress):
    calls: list[float] = []
    # consistent start: z(0) = tanh(50) = 1 (to double precision), x'(0) = 0, z'(0) = 1
    solution = integrate_dae(steep_forced_dae(calls), [1.0, 1.0], [0.0, 1.0], [0.0, 3.0],
                             algebraic=[False, True], rtol=1e-8, atol=1e-10, jac=jacobian,
                             exclude_from_error_test=[False, True] if suppress else None)
    stats = solution.stats
    # With an exact Jacobian IDA evaluates the residual once per Newton iteration.
    assert stats.nonlinear_iterations == stats.rhs_evals == len(calls)
    # Each trial step calls the residual at its own new time t_n + h: the runs of equal
    # times are the attempts, accepted or failed by the error test. (A Newton failure with
    # an old Jacobian is retried at the same time with a new one, so it adds no run.)
    attempts = 1 + np.count_nonzero(np.diff(calls))
    assert stats.rejected_steps == attempts - stats.steps
    assert stats.rejected_steps >= 1          # measured 11 with and without suppression
    assert "n/a" not in stats.summary()


def test_suppressing_the_algebraic_error_changes_the_run():
    """Measured: all in the error test 480 steps and Newton never fails; z suppressed 204
    steps (z's steep fall no longer limits h) and 11 convergence failures, each retried
    with a new Jacobian. Bounds: half the steps, and some failure against none."""
    runs = {}
    for suppress in (False, True):
        solution = integrate_dae(steep_forced_dae([]), [1.0, 1.0], [0.0, 1.0], [0.0, 3.0],
                                 algebraic=[False, True], rtol=1e-8, atol=1e-10,
                                 jac=jacobian,
                                 exclude_from_error_test=[False, True] if suppress else None)
        runs[suppress] = solution.stats
    assert runs[True].steps < 0.6 * runs[False].steps
    assert runs[False].nonlinear_convergence_failures == 0
    assert runs[True].nonlinear_convergence_failures >= 1
