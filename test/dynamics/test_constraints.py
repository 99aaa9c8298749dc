"""Holonomic formulations on the planar pendulum in Cartesian coordinates, checked against
the angle ODE theta'' = -(g/L) sin theta (scipy at tight tolerance) and the closed-form
multiplier lambda = (|v|^2 - g y) / (2 L^2) for g(q) = x^2 + y^2 - L^2, M = I."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from youbot_dynamics.dynamics.constraints import (DAE_FORMULATIONS, HolonomicSystem,
                                                  accelerations_and_multipliers,
                                                  consistent_initial_values, dae_form,
                                                  project_positions, project_velocities)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.constrained import simulate_holonomic

GRAVITY, LENGTH = 9.81, 0.7
PENDULUM = HolonomicSystem(
    name="pendulum", position_names=("x", "y"), n_constraints=1,
    mass=lambda q: np.eye(2),
    forces=lambda q, v: np.array([0.0, -GRAVITY]),
    constraint=lambda q: np.array([q @ q - LENGTH**2]),
    jacobian=lambda q: 2.0 * q[None, :],
    curvature=lambda q, v: np.array([2.0 * v @ v]))
#: The same pendulum with the second derivatives, so that its DAE forms carry the exact
#: Jacobian (M and f constant; d^2 g/dq^2 = 2 I).
PENDULUM_EXACT = HolonomicSystem(
    **{**PENDULUM.__dict__, "mass_derivative": lambda q, w: np.zeros((2, 2)),
       "force_derivatives": lambda q, v: (np.zeros((2, 2)), np.zeros((2, 2))),
       "constraint_hessian": lambda q: 2.0 * np.eye(2)[None]})
THETA0 = 1.2      # from the downward vertical, rad
Q0 = LENGTH * np.array([np.sin(THETA0), -np.cos(THETA0)])
V0 = np.zeros(2)
T_END = 2.0


def exact_positions(times):
    solution = solve_ivp(lambda t, s: [s[1], -GRAVITY / LENGTH * np.sin(s[0])], (0, T_END),
                         [THETA0, 0.0], t_eval=times, rtol=1e-12, atol=1e-12,
                         method="DOP853")
    theta = solution.y[0]
    return LENGTH * np.column_stack((np.sin(theta), -np.cos(theta)))


def test_multiplier_is_the_closed_form():
    q = LENGTH * np.array([0.6, -0.8])
    v = np.array([0.8, 0.6]) * 1.7
    w, lam = accelerations_and_multipliers(PENDULUM, q, v)
    assert lam[0] == pytest.approx((v @ v - GRAVITY * q[1]) / (2 * LENGTH**2), rel=1e-13)
    assert PENDULUM.jacobian(q) @ w + PENDULUM.curvature(q, v) == pytest.approx(0, abs=1e-12)


def central_difference_jacobian(form, y, yp, cj, h=1e-6):
    """dF/dy + cj dF/dy' by central differences along (e_k, cj e_k)."""
    columns = [(form.residual(0.0, y + h * e, yp + cj * h * e)
                - form.residual(0.0, y - h * e, yp - cj * h * e)) / (2 * h)
               for e in np.eye(y.size)]
    return np.array(columns).T


@pytest.mark.parametrize("formulation", DAE_FORMULATIONS)
def test_exact_dae_jacobian_matches_finite_differences(formulation):
    assert dae_form(PENDULUM, formulation, Q0, V0, V0, np.zeros(1)).residual_jacobian is None
    form = dae_form(PENDULUM_EXACT, formulation, Q0, V0, V0, np.zeros(1))
    rng = np.random.default_rng(3)
    y, yp = rng.standard_normal((2, form.y0.size))
    cj = 37.0
    assert form.residual_jacobian(0.0, y, yp, cj) == pytest.approx(
        central_difference_jacobian(form, y, yp, cj), abs=1e-8)


@pytest.mark.parametrize("formulation,integrator,tolerance,system", [
    ("index1", "dop853", 1e-7, PENDULUM), ("index1-baumgarte", "dop853", 1e-7, PENDULUM),
    ("index1-projection", "dop853", 1e-7, PENDULUM), ("index2", "ida", 1e-4, PENDULUM),
    ("ggl", "ida", 1e-4, PENDULUM), ("index2", "ida", 1e-4, PENDULUM_EXACT),
    ("ggl", "ida", 1e-4, PENDULUM_EXACT)])
def test_formulations_follow_the_angle_ode(formulation, integrator, tolerance, system):
    times = np.linspace(0.0, T_END, 21)
    run = simulate_holonomic(system, formulation, integrator, Q0, V0, times,
                             rtol=1e-10 if integrator != "ida" else 1e-8, atol=1e-12,
                             baumgarte_rate=20.0)
    assert np.max(np.abs(run.q - exact_positions(times))) < tolerance * LENGTH
    expected = [(v @ v - GRAVITY * q[1]) / (2 * LENGTH**2) for q, v in zip(run.q, run.v)]
    assert run.multipliers[:, 0] == pytest.approx(expected, rel=1e-3)


def test_ida_options_reach_the_solver():
    times = [0.0, T_END]
    free = simulate_holonomic(PENDULUM_EXACT, "ggl", "ida", Q0, V0, times, rtol=1e-6)
    capped = simulate_holonomic(PENDULUM_EXACT, "ggl", "ida", Q0, V0, times, rtol=1e-6,
                                ida_options={"max_step": 0.001})
    assert free.stats.steps < T_END / 0.001 <= capped.stats.steps


def test_projections_land_on_the_manifolds_nearest_in_the_mass_metric():
    mass = np.diag([1.0, 3.0])
    system = HolonomicSystem(**{**PENDULUM.__dict__, "mass": lambda q: mass})
    for offset in (0.1, 1e-4):
        guess = Q0 + offset * np.array([1.0, -2.0])
        q, iterations = project_positions(system, guess)
        assert abs(system.constraint(q)[0]) < 1e-12 and iterations > 0
        tangent = np.array([-q[1], q[0]]) / LENGTH
        step = q - guess
        # optimality of min (q - guess)^T M (q - guess) on the circle holds to first order:
        # the step's M-component along the tangent is O(|step|^2)
        cosine = abs(tangent @ mass @ step) / np.linalg.norm(mass @ step)
        assert cosine < 2.0 * np.linalg.norm(step) / LENGTH
    v = project_velocities(system, q, np.array([1.0, 2.0]))
    assert system.jacobian(q) @ v == pytest.approx(0, abs=1e-12)


def test_consistent_initialisation_from_a_perturbed_guess():
    q, v, w, lam, iterations = consistent_initial_values(
        PENDULUM, np.array([0.3, -0.9]), np.array([1.0, 5.0]), fixed=(0,))
    assert q[0] == 0.3 and q[1] == pytest.approx(-np.sqrt(LENGTH**2 - 0.09), rel=1e-12)
    assert iterations > 1
    assert PENDULUM.jacobian(q) @ v == pytest.approx(0, abs=1e-12) and v[0] == 1.0
    assert lam[0] == pytest.approx((v @ v - GRAVITY * q[1]) / (2 * LENGTH**2), rel=1e-12)


def test_bad_requests_are_user_errors():
    with pytest.raises(UserInputError, match="free coordinates"):
        consistent_initial_values(PENDULUM, Q0, V0, fixed=(0, 1))
    with pytest.raises(UserInputError, match="needs ida"):
        simulate_holonomic(PENDULUM, "index2", "rk45", Q0, V0, [0, 1])
    with pytest.raises(UserInputError, match="not a DAE formulation"):
        dae_form(PENDULUM, "index1", Q0, V0, V0, np.zeros(1))
    with pytest.raises(UserInputError, match="exact DAE Jacobian needs"):
        simulate_holonomic(PENDULUM, "index2", "ida", Q0, V0, [0, 1], exact_jacobian=True)
