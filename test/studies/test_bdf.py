"""Fixed-step BDF1-4: exactness on polynomials, measured orders, stability boundary against
the analytic root locus and published A(alpha) angles, the seed's Tables 1-4 verdicts, and
CVODE's order-capped step counts against the seed's."""
import json
import math
from functools import partial

import numpy as np
import pytest

import youbot_dynamics.cli as cli
from youbot_dynamics.studies.bdf import (alpha_angle, amplification, bdf_fixed_step, coefficients,
                                         locus_radius_on_ray, measured_growth, root_locus)
from youbot_dynamics.studies.bdf_study import SEED_CVODE_ORDER, fixed_step_tables, measured_orders
from youbot_dynamics.studies.elastic_pendulum import (SEED_STATE0, elastic_pendulum_jacobian,
                                                      elastic_pendulum_rhs)

ORDERS = (1, 2, 3, 4)


@pytest.mark.parametrize("order", ORDERS)
def test_coefficients_exact_on_polynomials_up_to_their_order(order):
    """sum_j a_j p(t_{n+1-j}) = h b p'(t_{n+1}) for p = t^m, m <= order (h = 1, t_{n+1} =
    0), and not for m = order + 1."""
    a, b = coefficients(order)
    times = -np.arange(order + 1.0)
    for m in range(order + 2):
        left = sum(a[j] * times[j] ** m for j in range(order + 1))
        right = b * (1.0 if m == 1 else 0.0)
        assert (abs(left - right) < 1e-14) == (m <= order), m


def test_measured_orders_on_the_elastic_pendulum():
    """Slopes measured 0.995, 2.004, 2.975, 4.010 (N = 400 -> 800 on [0, 2], k = 10)."""
    for row in measured_orders():
        assert row["measured_order"] == pytest.approx(row["order"], abs=0.1), row


def test_newton_with_difference_jacobian_matches_analytic():
    rhs, jac = partial(elastic_pendulum_rhs, k=10.0), partial(elastic_pendulum_jacobian, k=10.0)
    analytic = bdf_fixed_step(rhs, SEED_STATE0, 2.0, 200, 3, jac=jac)
    difference = bdf_fixed_step(rhs, SEED_STATE0, 2.0, 200, 3)
    np.testing.assert_allclose(difference.x, analytic.x, atol=1e-9)
    assert difference.stats.rhs_evals > analytic.stats.rhs_evals  # 4 per difference Jacobian


@pytest.mark.parametrize("order", ORDERS)
def test_root_locus_is_where_a_root_has_modulus_one(order):
    for theta in np.linspace(0.1, 3.1, 7):
        assert amplification(order, complex(root_locus(order, theta))) == pytest.approx(
            1.0, abs=1e-9)


@pytest.mark.parametrize("order", ORDERS)
def test_written_out_solver_grows_as_its_largest_characteristic_root(order):
    """Per-step growth of the solver on x' = lambda x against max |zeta| of
    rho - z sigma: within 1 % (measured at most 0.42 %; the max-norm of a rotating 2-vector
    does not scale exactly)."""
    for z in (0.3 + 0.3j, 3.0, -1.0 + 2.0j, 0.05j, -5.0):
        assert measured_growth(order, z) == pytest.approx(amplification(order, z), rel=0.01)


@pytest.mark.parametrize("order", ORDERS)
@pytest.mark.parametrize("angle_deg", [0.0, 45.0, 80.0])
def test_written_out_solver_changes_stability_at_the_root_locus(order, angle_deg):
    """The solver's own growth on x' = lambda x, 1 % inside and outside the locus radius
    on a ray (the measured boundary agrees with the locus to 1e-5 relative by bisection)."""
    angle = math.radians(angle_deg)
    radius = locus_radius_on_ray(order, angle)
    assert measured_growth(order, 0.99 * radius * np.exp(1j * angle)) > 1.0
    assert measured_growth(order, 1.01 * radius * np.exp(1j * angle)) < 1.0


def test_real_axis_boundaries_and_published_alpha_angles():
    """Real-axis boundaries 2, 4, 20/3, 32/3 (rho(-1)/sigma(-1)); A(alpha) 90, 90, 86.03,
    73.35 deg (Hairer & Wanner, Solving ODEs II, Table V.2.3)."""
    for order, boundary in zip(ORDERS, (2.0, 4.0, 20.0 / 3.0, 32.0 / 3.0)):
        assert locus_radius_on_ray(order, 0.0) == pytest.approx(boundary, rel=1e-9)
    for order, alpha in zip(ORDERS, (90.0, 90.0, 86.03, 73.35)):
        assert math.degrees(alpha_angle(order)) == pytest.approx(alpha, abs=0.01)


@pytest.fixture(scope="module")
def seed_cells():
    return {(row.method, row.k, row.n_steps): row
            for row in fixed_step_tables(("bdf2", "bdf3", "bdf4"), seed_only=True,
                                         reference_tol=1e-10)}


def test_bdf_seed_verdicts_reproduced(seed_cells):
    """BDF2 stable but inaccurate at k = 100 and 2000 (N = 1000); BDF3 at k = 500 and BDF4
    at k = 400 unstable, their h sqrt(k) = 0.45i, 0.40i inside the unstable lobes."""
    assert len(seed_cells) == 4
    for row in seed_cells.values():
        assert row.verdict == row.seed, row


def test_energy_criterion_flips_bdf2_verdicts(seed_cells):
    """BDF2 damps the spring: it loses energy (growth 0) so our verdict is stable, while
    the energy-error criterion calls it unstable (|E - E0| 1.06 at k = 100, 40 at 2000)."""
    for k in (100, 2000):
        row = seed_cells[("bdf2", k, 1000)]
        assert row.energy_verdict == "unstable" and row.energy_growth <= 0.0


@pytest.fixture
def pendulum_cli(monkeypatch):
    monkeypatch.setattr(cli, "COMMAND_MODULES", ("youbot_dynamics.cli.study_commands",))
    return cli.main


@pytest.mark.parametrize("k", [10, pytest.param(50, marks=pytest.mark.slow)])
def test_cvode_order_one_step_counts_as_the_seeds(pendulum_cli, capsys, k):
    """Measured 38 501 and 76 856 steps: the seed's figures exactly (acceptance: 10 %)."""
    assert pendulum_cli(["study", "pendulum", "--k", str(k), "--integrator", "cvode_bdf",
                         "--max-order", "1", "--jacobian", "difference", "--json"]) == 0
    steps = json.loads(capsys.readouterr().out)["stats"]["steps"]
    assert steps == pytest.approx(SEED_CVODE_ORDER[(k, 1)], rel=0.1)


def test_max_order_refused_for_other_integrators(pendulum_cli, capsys):
    assert pendulum_cli(["study", "pendulum", "--integrator", "rk45", "--max-order", "2"]) == 2
    assert "--max-order applies to cvode" in capsys.readouterr().err
    assert pendulum_cli(["study", "pendulum", "--integrator", "cvode_bdf", "--max-order", "6"]) == 2
    assert "max_order must be 1..5" in capsys.readouterr().err


def test_explicit_euler_seed_accurate_cells_are_inaccurate_by_position():
    """The seed calls explicit Euler accurate at N = 10000 for k = 1 and 20; against the
    reference its position is off by 0.084 m and 0.156 m (measured): stable, inaccurate
    by our 1 cm criterion, and by energy (max|E-E0| 0.044 and 0.57) too."""
    rows = fixed_step_tables(("euler",), seed_only=True, reference_tol=1e-10)
    for row in rows:
        if row.n_steps == 10000:
            assert row.seed == "accurate" and row.verdict == "stable, inaccurate"
            assert row.position_error > 0.05 and row.energy_verdict == "stable, inaccurate"
        else:
            assert row.verdict == row.seed


def test_choppy_traces_plot(tmp_path):
    """At rtol = atol = 0.1 both CVODE methods are visibly off the reference (measured
    0.64 m for BDF, 2.29 m for Adams, within 56 and 45 steps)."""
    from youbot_dynamics.studies.pendulum_figures import plot_choppy_traces
    figures = plot_choppy_traces(str(tmp_path / "choppy.png"))
    assert (tmp_path / "choppy.png").stat().st_size > 10_000
    for run in figures.values():
        assert run["position_error"] > 0.1 and run["steps"] < 200
