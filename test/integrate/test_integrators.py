"""Integrators: accuracy on analytic problems, orders of convergence, statistics against the
libraries' own counts, events, divergence, conservative long runs, tolerance sweeps, IDA."""
from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest
import sksundae
from scipy.integrate import solve_ivp

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import (DivergenceError, Event, IntegratorStats,
                                                   integrate, integrate_dae)
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS, integrator_names
from youbot_dynamics.studies.elastic_pendulum import (STATE_NAMES, elastic_pendulum_jacobian,
                                                      elastic_pendulum_rhs)

ODE_INTEGRATORS = tuple(name for name in INTEGRATORS if name != "ida")
ADAPTIVE = tuple(name for name in ODE_INTEGRATORS if name not in FIXED_STEP)
IMPLICIT = integrator_names("ode", stiff=True)  # radau, bdf, lsoda, cvode_bdf


def oscillator(t, x):
    """Harmonic oscillator q'' = -q: q = cos t, v = -sin t from (1, 0)."""
    return np.array([x[1], -x[0]])


def oscillator_exact(t):
    return np.array([np.cos(t), -np.sin(t)]).T


def run(integrator, t_eval, dt=1e-3, rtol=1e-8, atol=1e-10, **options):
    return integrate(oscillator, [1.0, 0.0], t_eval, integrator, dt=dt, rtol=rtol, atol=atol,
                     n_positions=1, **options)


# Bound on the error at t = 2 s (dt = 1e-3 for fixed step; rtol 1e-8 / atol 1e-10 else):
# Euler's amplitude grows by (1 + h^2)^(N/2) ~ 1 + t h / 2 = 1.001; symplectic Euler's phase
# error is O(h t); RK4's error is O(t h^4).
ERROR_BOUNDS = {"euler": 2e-3, "symplectic_euler": 1.5e-3, "rk4": 1e-11}


@pytest.mark.parametrize("integrator", ODE_INTEGRATORS)
def test_harmonic_oscillator_error_within_bound(integrator):
    t = np.linspace(0.0, 2.0, 5)
    solution = run(integrator, t)
    assert np.allclose(solution.t, t)
    error = np.abs(solution.x - oscillator_exact(t)).max()
    assert error < ERROR_BOUNDS.get(integrator, 2e-6)
    assert solution.state_names == ("x[0]", "x[1]")


@pytest.mark.parametrize("integrator, order, dt", [("euler", 1, 0.01),
                                                   ("symplectic_euler", 1, 0.01),
                                                   ("rk4", 4, 0.05)])
def test_observed_order_of_convergence(integrator, order, dt):
    t = [0.0, 1.0]
    errors = [np.abs(run(integrator, t, dt=h).x[-1] - oscillator_exact(1.0)).max()
              for h in (dt, dt / 2)]
    assert math.log2(errors[0] / errors[1]) == pytest.approx(order, abs=0.1)


@pytest.mark.parametrize("integrator, reference", [("rk45", "RK45"), ("dop853", "DOP853"),
                                                   ("radau", "Radau"), ("bdf", "BDF"),
                                                   ("lsoda", "LSODA")])
def test_scipy_statistics_equal_solve_ivp(integrator, reference):
    solution = run(integrator, [0.0, 10.0], rtol=1e-6, atol=1e-8)
    expected = solve_ivp(oscillator, (0.0, 10.0), [1.0, 0.0], method=reference, rtol=1e-6,
                         atol=1e-8)
    stats = solution.stats
    assert (stats.steps, stats.rhs_evals, stats.jac_evals) == (
        len(expected.t) - 1, expected.nfev, expected.njev)
    assert np.allclose(solution.x[-1], expected.y[:, -1], rtol=0, atol=1e-12)


def test_rk45_rejected_steps_account_for_every_evaluation():
    stats = run("rk45", [0.0, 10.0], rtol=1e-8, atol=1e-10).stats
    # Initial f and the initial-step estimate, then 6 evaluations per attempted step.
    assert stats.rhs_evals == 2 + 6 * (stats.steps + stats.rejected_steps)
    assert stats.rejected_steps > 0


@pytest.mark.parametrize("integrator, method", [("cvode_bdf", "BDF"), ("cvode_adams", "Adams")])
def test_cvode_statistics_equal_scikit_sundae_solve(integrator, method):
    solution = run(integrator, [0.0, 10.0], rtol=1e-6, atol=1e-8)

    def rhsfn(t, y, yp):
        yp[:] = oscillator(t, y)
    expected = sksundae.cvode.CVODE(rhsfn, method=method, rtol=1e-6, atol=1e-8).solve(
        [0.0, 10.0], [1.0, 0.0])
    stats = solution.stats
    assert (stats.steps, stats.rhs_evals, stats.jac_evals) == (
        len(expected.t) - 1, expected.nfev, expected.njev)
    assert None not in (stats.rejected_steps, stats.nonlinear_iterations, stats.nonlinear_convergence_failures)


@pytest.mark.parametrize("integrator", ["cvode_bdf", "cvode_adams"])
def test_cvode_counters_match_the_rhs_calls_and_trial_steps(integrator):
    """CVODE's own counters (read out of SUNDIALS) against the calls seen from outside, on
    x' = -x + sin t + tanh(50 (1 - t)) (a steep fall near t = 1 fails error tests) with its
    exact Jacobian: the calls before the first trial step are the start and the initial-step
    estimate, then one call per Newton iteration; each trial step calls at its own new time,
    so the runs of equal times after the start are the attempts, accepted or rejected.
    Measured: BDF 194 steps, 20 rejected, 284 iterations of 287 calls; Adams 131, 17, 199 of
    202."""
    calls: list[float] = []

    def steep(t, x):
        calls.append(t)
        return np.array([-x[0] + np.sin(t) + np.tanh(50.0 * (1.0 - t))])

    solution = integrate(steep, [1.0], [0.0, 3.0], integrator, rtol=1e-8, atol=1e-10,
                         jac=lambda t, x: np.array([[-1.0]]))
    stats = solution.stats
    assert stats.rhs_evals == len(calls)
    start = len(calls) - stats.nonlinear_iterations
    assert 2 <= start <= 6            # f(t0) and cvHin's few estimates (measured 3)
    attempts = 1 + np.count_nonzero(np.diff(calls[start:]))
    assert stats.rejected_steps == attempts - stats.steps
    assert stats.rejected_steps >= 5 and stats.nonlinear_convergence_failures == 0


def stiff_decay(t, x):
    """x0' = -1000 (x0 - cos t), x1' = -x1: stiff."""
    return np.array([-1000.0 * (x[0] - np.cos(t)), -x[1]])


def stiff_decay_exact(t):
    """From x = (0, 1): x0 = (k^2 cos t + k sin t - k^2 e^(-k t)) / (k^2 + 1) with k = 1000,
    x1 = e^-t."""
    k = 1000.0
    x0 = (k * k * np.cos(t) + k * np.sin(t) - k * k * np.exp(-k * t)) / (k * k + 1.0)
    return np.array([x0, np.exp(-t)]).T


def test_lsoda_switches_to_bdf_on_a_stiff_problem_within_tolerance():
    t = np.linspace(0.0, 10.0, 11)
    solution = integrate(stiff_decay, [0.0, 1.0], t, "lsoda", rtol=1e-8, atol=1e-10)
    assert np.abs(solution.x - stiff_decay_exact(t)).max() < 1e-7  # measured 2.7e-8
    expected = solve_ivp(stiff_decay, (0.0, 10.0), [0.0, 1.0], method="LSODA", rtol=1e-8,
                         atol=1e-10)
    stats = solution.stats
    assert (stats.steps, stats.rhs_evals, stats.jac_evals) == (
        len(expected.t) - 1, expected.nfev, expected.njev)
    assert stats.jac_evals > 0  # it switched to BDF: Jacobians, by finite differences
    assert stats.rejected_steps is None and stats.nonlinear_iterations is None
    # Explicit RK45 is held to its stability limit h < 3.3/1000 s: measured 6927 steps
    # against LSODA's 368
    explicit = integrate(stiff_decay, [0.0, 1.0], t, "rk45", rtol=1e-8, atol=1e-10).stats
    assert explicit.steps > 10 * stats.steps


@pytest.mark.parametrize("integrator", ODE_INTEGRATORS)
def test_statistics_populated_and_consistent(integrator):
    solution = integrate(stiff_decay, [0.0, 1.0], [0.0, 1.0], integrator, dt=1e-4,
                         rtol=1e-6, atol=1e-8, n_positions=1)
    stats = solution.stats
    assert stats.integrator == integrator and stats.steps > 0 and stats.wall_time > 0
    assert stats.simulated_time == pytest.approx(1.0)
    assert stats.real_time_factor == pytest.approx(1.0 / stats.wall_time)
    if integrator in FIXED_STEP or integrator in ("rk45", "dop853", "dop853_compiled"):
        assert stats.rhs_evals >= stats.steps and stats.jac_evals == 0
    else:
        assert stats.jac_evals > 0
    assert set(stats.as_dict()) >= {"steps", "rhs_evals", "real_time_factor"}


def test_statistics_merge_sums_segments_and_keeps_unknowns_unknown():
    total = IntegratorStats("cvode_bdf")
    total += IntegratorStats("cvode_bdf", steps=3, rhs_evals=5, rejected_steps=None,
                             wall_time=0.5, simulated_time=1.0)
    total += IntegratorStats("cvode_bdf", steps=4, rhs_evals=6, rejected_steps=None,
                             wall_time=0.5, simulated_time=2.0)
    assert (total.steps, total.rhs_evals, total.rejected_steps) == (7, 11, None)
    assert total.real_time_factor == pytest.approx(3.0)


# q = cos t crosses zero falling at pi/2 and rising at 3 pi/2.
EVENT_TOLERANCE = {"euler": 0.02, "symplectic_euler": 0.02}


@pytest.mark.parametrize("integrator", ODE_INTEGRATORS)
def test_terminal_event_located_and_direction_respected(integrator):
    tolerance = EVENT_TOLERANCE.get(integrator, 1e-6)
    t = np.linspace(0.0, 6.0, 7)
    falling = run(integrator, t, dt=1e-3, events=[Event("down", lambda t, x: x[0], -1)])
    assert falling.terminated_by == "down"
    assert falling.t[-1] == pytest.approx(np.pi / 2, abs=tolerance)
    assert falling.t[:-1] == pytest.approx([0.0, 1.0])
    assert falling.x[-1, 0] == pytest.approx(0.0, abs=1e-9)
    rising = run(integrator, t, dt=1e-3, events=[Event("up", lambda t, x: x[0], +1)])
    assert rising.t[-1] == pytest.approx(3 * np.pi / 2, abs=tolerance)
    assert len(rising.events) == 1 and rising.stats.events == 1


@pytest.mark.parametrize("integrator", ("rk4", "rk45", "cvode_adams"))
def test_non_terminal_events_recorded_and_run_continues(integrator):
    t = np.linspace(0.0, 6.0, 7)
    solution = run(integrator, t, dt=1e-3,
                   events=[Event("zero", lambda t, x: x[0], 0, terminal=False)])
    assert solution.terminated_by is None and solution.t[-1] == 6.0
    assert [e.time for e in solution.events] == pytest.approx([np.pi / 2, 3 * np.pi / 2],
                                                              abs=1e-6)
    assert [e.name for e in solution.events] == ["zero", "zero"]


STIFF_K = 1e4
STIFF_STATE0 = [np.sin(0.5), -np.cos(0.5), 0.0, 0.0]   # rest length, 0.5 rad from vertical


@pytest.mark.parametrize("integrator, dt", [("euler", 0.01), ("rk4", 0.05)])
def test_stiff_spring_pendulum_explicit_large_step_diverges_loudly(integrator, dt):
    rhs = partial(elastic_pendulum_rhs, k=STIFF_K)
    # |1 + i h w| > 1 for Euler; h w = 5 lies outside RK4's stability interval (2.83).
    with pytest.raises(DivergenceError) as caught:
        integrate(rhs, STIFF_STATE0, [0.0, 30.0], integrator, dt=dt, state_names=STATE_NAMES)
    error = caught.value
    assert (error.integrator, error.step_size, error.reason) == (integrator, dt,
                                                                 "non-finite state")
    assert 0 < error.time < 30 and set(error.components) <= set(STATE_NAMES)
    assert error.components and f"t={error.time:.6g} s" in str(error)
    with pytest.raises(DivergenceError) as bounded:
        integrate(rhs, STIFF_STATE0, [0.0, 30.0], integrator, dt=dt, state_names=STATE_NAMES,
                  bounds=np.full(4, 100.0))
    assert bounded.value.reason == "state outside its bounds"
    assert bounded.value.time < 1.0
    assert all(abs(v) > 100 for v in bounded.value.components.values())


@pytest.mark.parametrize("integrator", IMPLICIT)
def test_stiff_spring_pendulum_implicit_within_tolerance(integrator):
    rhs = partial(elastic_pendulum_rhs, k=STIFF_K)
    t = np.linspace(0.0, 2.0, 21)
    reference = integrate(rhs, STIFF_STATE0, t, "dop853", rtol=1e-12, atol=1e-12)
    solution = integrate(rhs, STIFF_STATE0, t, integrator, rtol=1e-6, atol=1e-8,
                         jac=partial(elastic_pendulum_jacobian, k=STIFF_K))
    assert np.abs(solution.x[:, :2] - reference.x[:, :2]).max() < 1e-4


@pytest.mark.parametrize("integrator", ADAPTIVE)
def test_blow_up_is_step_size_collapse(integrator):
    # y' = y^2, y(0) = 1 has y = 1 / (1 - t): it blows up at t = 1.
    with pytest.raises(DivergenceError) as caught:
        integrate(lambda t, y: y * y, [1.0], [0.0, 2.0], integrator)
    assert caught.value.time == pytest.approx(1.0, abs=1e-3)
    assert "step size collapsed" in caught.value.reason


def test_min_step_reports_collapse():
    with pytest.raises(DivergenceError, match="min_step"):
        integrate(lambda t, y: y * y, [1.0], [0.0, 2.0], "rk45", min_step=1e-4)


def test_monitor_reason_becomes_divergence_error():
    with pytest.raises(DivergenceError, match="too far") as caught:
        run("rk4", np.linspace(0, 3, 31), monitor=lambda t, x: "too far" if t > 1 else None)
    assert caught.value.time == pytest.approx(1.1)
    assert set(caught.value.components) == {"x[0]", "x[1]"}


def test_long_conservative_run_symplectic_bounded_explicit_grows():
    # 1000 s of q'' = -q at dt = 0.01 (1e5 steps): E = (q^2 + v^2) / 2, E0 = 1/2.
    t = np.linspace(0.0, 1000.0, 11)
    drift = {}
    for integrator in ("euler", "symplectic_euler"):
        x = run(integrator, t, dt=0.01).x
        drift[integrator] = np.abs(0.5 * (x ** 2).sum(axis=1) - 0.5) / 0.5
    # Explicit Euler multiplies E by (1 + h^2) per step: e^10 after 1e5 steps.
    assert drift["euler"][-1] == pytest.approx(math.expm1(1e5 * math.log1p(1e-4)), rel=1e-3)
    assert np.all(np.diff(drift["euler"]) > 0)
    # Symplectic Euler conserves a modified energy: the drift stays O(h) forever.
    assert drift["symplectic_euler"].max() < 0.01
    assert drift["symplectic_euler"][-1] < 2 * drift["symplectic_euler"][1] + 1e-3


@pytest.mark.parametrize("integrator", ADAPTIVE)
def test_tolerance_sweep_error_decreases_down_to_1e_9(integrator):
    tolerances = (1e-3, 1e-5, 1e-7, 1e-9)
    errors = [np.abs(run(integrator, [0.0, 10.0], rtol=tol, atol=tol * 1e-2).x[-1]
                     - oscillator_exact(10.0)).max() for tol in tolerances]
    assert all(later < earlier / 5 for earlier, later in zip(errors, errors[1:]))
    assert errors[-1] < 1e-7


def forced_dae(t, y, yp):
    """x' = -x + z, 0 = z - sin t: x = (sin t - cos t)/2 + (x0 + 1/2) e^-t."""
    return np.array([yp[0] + y[0] - y[1], y[1] - np.sin(t)])


def forced_dae_exact(t, x0=1.0):
    x = 0.5 * (np.sin(t) - np.cos(t)) + (x0 + 0.5) * np.exp(-t)
    return np.array([x, np.sin(t)]).T


@pytest.mark.parametrize("excluded", [None, [False, False], [False, True]])
def test_ida_index_one_dae_against_analytic_solution(excluded):
    t = np.linspace(0.0, 5.0, 11)
    solution = integrate_dae(forced_dae, [1.0, 0.0], [-1.0, 1.0], t, algebraic=[False, True],
                             rtol=1e-8, atol=1e-10, exclude_from_error_test=excluded,
                             state_names=("x", "z"))
    assert np.abs(solution.x - forced_dae_exact(t)).max() < 1e-6
    exact_xp = -forced_dae_exact(t)[:, 0] + np.sin(t)
    assert np.abs(solution.xp[:, 0] - exact_xp).max() < 1e-5
    assert solution.stats.integrator == "ida" and solution.stats.steps > 0


def test_ida_exclusion_of_a_differential_component_is_refused():
    with pytest.raises(UserInputError, match="exactly the algebraic"):
        integrate_dae(forced_dae, [1.0, 0.0], [-1.0, 1.0], [0.0, 1.0],
                      algebraic=[False, True], exclude_from_error_test=[True, True])


def test_ida_event_and_jacobian():
    solution = integrate_dae(forced_dae, [1.0, 0.0], [-1.0, 1.0], [0.0, 5.0],
                             algebraic=[False, True], rtol=1e-8, atol=1e-10,
                             jac=lambda t, y, yp, cj: np.array([[cj + 1.0, -1.0], [0.0, 1.0]]),
                             events=[Event("z=0.5", lambda t, y: y[1] - 0.5, +1)])
    assert solution.t[-1] == pytest.approx(np.pi / 6, abs=1e-7)
    assert solution.terminated_by == "z=0.5"


@pytest.mark.parametrize("call, message", [
    (lambda: run("leapfrog", [0, 1]), "unknown ODE integrator 'leapfrog'.*rk45"),
    (lambda: run("ida", [0, 1]), "integrate_dae"),
    (lambda: run("euler", [0, 1], dt=None), "fixed steps: give dt"),
    (lambda: run("rk4", [0, 1], dt=-0.1), "dt must be positive"),
    (lambda: run("rk45", [0, 1], rtol=0.0), "rtol must be positive"),
    (lambda: run("bdf", [0, 1], atol=[1e-8, -1]), "atol must be positive"),
    (lambda: run("rk45", [1, 0]), "strictly increasing"),
    (lambda: run("rk45", [0, 1], state_names=["a"]), "state_names has 1 names"),
    (lambda: integrate(oscillator, [1, 0], [0, 1], "symplectic_euler", dt=0.1),
     "n_positions"),
    (lambda: integrate_dae(forced_dae, [1, 0], [1], [0, 1], algebraic=[False, True]),
     "yp0 has 1"),
])
def test_bad_arguments_raise_user_input_error(call, message):
    with pytest.raises(UserInputError, match=message):
        call()


def test_summary_says_n_a_for_counters_the_backend_does_not_report():
    from youbot_dynamics.integrate.integrators import IntegratorStats
    stats = IntegratorStats("cvode_bdf", steps=12, rhs_evals=30, jac_evals=2, rejected_steps=None,
                            nonlinear_iterations=None, nonlinear_convergence_failures=None,
                            events=0, wall_time=0.5, simulated_time=2.0)
    line = stats.summary()
    assert line.startswith("cvode_bdf: 12 steps, 30 rhs evaluations, 2 Jacobians, n/a rejected steps")
    assert "None" not in line and "real-time factor 4" in line
