"""Radau IIA (order 5) for DAEs (integrate/radau_dae.py): its coefficients against the published
Butcher tableau, an ODE and an index-3 DAE with closed-form solutions, and the effect of
the index-dependent error scaling."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.dynamics.constraints import HolonomicSystem, dae_form
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate import radau_dae
from youbot_dynamics.integrate.radau_dae import (holonomic_index, integrate_dae_form,
                                                 integrate_radau_dae)

SQRT6 = np.sqrt(6.0)
#: Radau IIA order 5 (Hairer and Wanner, Solving ODEs II, Table IV.5.6).
BUTCHER_A = np.array([
    [(88 - 7 * SQRT6) / 360, (296 - 169 * SQRT6) / 1800, (-2 + 3 * SQRT6) / 225],
    [(296 + 169 * SQRT6) / 1800, (88 + 7 * SQRT6) / 360, (-2 - 3 * SQRT6) / 225],
    [(16 - SQRT6) / 36, (16 + SQRT6) / 36, 1 / 9]])


def test_transformation_diagonalises_the_inverse_butcher_matrix():
    alpha, beta = radau_dae.MU_COMPLEX.real, radau_dae.MU_COMPLEX.imag
    blocks = np.array([[radau_dae.MU_REAL, 0, 0], [0, alpha, -beta], [0, beta, alpha]])
    assert radau_dae.T @ radau_dae.TI == pytest.approx(np.eye(3), abs=1e-15)
    assert radau_dae.T @ blocks @ radau_dae.TI == pytest.approx(np.linalg.inv(BUTCHER_A),
                                                                abs=1e-13)
    assert BUTCHER_A.sum(axis=1) == pytest.approx(radau_dae.C, abs=1e-15)
    # the dense-output polynomial passes through every stage: P (c, c^2, c^3) = e_i
    powers = np.array([radau_dae.C, radau_dae.C ** 2, radau_dae.C ** 3])
    assert radau_dae.P @ powers == pytest.approx(np.eye(3), abs=1e-14)


def test_ode_with_identity_mass_against_the_closed_form():
    """y'' = -y as a first-order system: y = (cos t, -sin t) on [0, 10] s."""
    t = np.linspace(0.0, 10.0, 21)
    solution, counters = integrate_radau_dae(lambda t, y: np.array([y[1], -y[0]]), np.eye(2),
                                             [1.0, 0.0], t, rtol=1e-9, atol=1e-12,
                                             jac=lambda t, y: np.array([[0.0, 1.0],
                                                                        [-1.0, 0.0]]))
    exact = np.array([np.cos(t), -np.sin(t)]).T
    # measured 2.4e-9 at rtol 1e-9 (dense output included); bound 10x
    assert np.abs(solution.x - exact).max() < 3e-8
    assert counters["lu_decompositions"] >= 1 and solution.stats.steps > 10


def circle(omega: float) -> HolonomicSystem:
    """A unit point mass on the unit circle, no force: uniform rotation q = (cos wt,
    sin wt) with lambda = w^2 (g = (|q|^2 - 1)/2, so G^T lambda = q lambda)."""
    zero2 = np.zeros((2, 2))
    return HolonomicSystem(
        name="circle", position_names=("x", "y"), n_constraints=1,
        mass=lambda q: np.eye(2), forces=lambda q, v: np.zeros(2),
        constraint=lambda q: np.array([0.5 * (q @ q - 1.0)]),
        jacobian=lambda q: q.reshape(1, 2), curvature=lambda q, v: np.array([v @ v]),
        mass_derivative=lambda q, w: zero2, force_derivatives=lambda q, v: (zero2, zero2),
        constraint_hessian=lambda q: np.eye(2).reshape(1, 2, 2))


@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_index3_circle_against_the_closed_form(rtol):
    omega = 3.0
    form = dae_form(circle(omega), "index3", np.array([1.0, 0.0]), np.array([0.0, omega]),
                    np.array([-omega ** 2, 0.0]), np.array([omega ** 2]))
    assert holonomic_index(form).tolist() == [1, 1, 2, 2, 3, 3, 3]
    t = np.linspace(0.0, 2.0, 41)
    solution, _ = integrate_dae_form(form, t, rtol=rtol, atol=rtol)
    q_exact = np.array([np.cos(omega * t), np.sin(omega * t)]).T
    q_error = np.abs(form.positions(solution.x) - q_exact).max()
    # measured q errors 2.4e-6 (rtol 1e-6) and 7.4e-10 (rtol 1e-9) over the 41 outputs
    # (dense output included); bound 50 rtol
    assert q_error < 50 * rtol
    # lambda (index 3, order 2 in Radau IIA, weighted by 1/h^2) measured within 0.031 and
    # 4.2e-4 of w^2 = 9 at the outputs: bound 0.1, the multiplier of this motion
    assert np.abs(form.multipliers(solution.x)[:, 0] - omega ** 2).max() < 0.1
    # |q| = 1 measured within 1.4e-7 and 2.3e-10 (interpolated), 2.5e-10 at step ends
    assert np.abs(np.hypot(*form.positions(solution.x).T) - 1.0).max() < rtol


def test_forward_difference_jacobian_runs_as_the_exact_one():
    """Without the exact df/dy RADAU5's forward differences stand in: the circle at rtol
    1e-6 then measured q within 2.8e-6 (exact: 2.4e-6) with as many Jacobians, 94; bound
    50 rtol. Their evaluations are counted: 3 per Newton iteration, 1 per step, 7 per J."""
    omega, t = 3.0, np.array([0.0, 2.0])
    form = dae_form(circle(omega), "index3", np.array([1.0, 0.0]), np.array([0.0, omega]),
                    np.array([-omega ** 2, 0.0]), np.array([omega ** 2]))
    solution, _ = integrate_dae_form(form, t, rtol=1e-6, atol=1e-6, exact_jacobian=False)
    q_end = form.positions(solution.x[-1])
    assert np.abs(q_end - [np.cos(omega * 2.0), np.sin(omega * 2.0)]).max() < 5e-5
    stats = solution.stats
    assert stats.rhs_evals >= 3 * stats.nonlinear_iterations + stats.steps + 7 * stats.jac_evals


def test_errors_name_the_wrong_input():
    with pytest.raises(UserInputError, match="index must be 1, 2 or 3"):
        integrate_radau_dae(lambda t, y: -y, np.eye(1), [1.0], [0.0, 1.0], index=[4])
    with pytest.raises(UserInputError, match="mass matrix is"):
        integrate_radau_dae(lambda t, y: -y, np.eye(2), [1.0], [0.0, 1.0])
