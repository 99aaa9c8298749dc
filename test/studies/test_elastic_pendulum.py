"""The elastic pendulum: equations against a sympy Lagrangian derivation, Jacobian against
finite differences, energy conservation, the seed's tables, and the pendulum CLI."""
from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp

import youbot_dynamics.cli as cli
from youbot_dynamics.integrate.integrators import DivergenceError
from youbot_dynamics.integrate.registry import integrator_names
from youbot_dynamics.studies.elastic_pendulum import (SEED_STATE0, elastic_pendulum_energy,
                                                      elastic_pendulum_jacobian,
                                                      elastic_pendulum_rhs, elastic_pendulum_study,
                                                      simulate_elastic_pendulum, stability_verdict)

RNG = np.random.default_rng(3)
STATES = [np.array([1.2, 0.0, 0.0, 0.0]), *(RNG.uniform(-2, 2, size=(4, 4)))]


def lagrangian_accelerations():
    """(ax, ay) as functions of (x, y, k) from L = T - V by Euler-Lagrange in sympy."""
    t, k = sp.symbols("t k", positive=True)
    x, y = sp.Function("x")(t), sp.Function("y")(t)
    lagrangian = (x.diff(t) ** 2 + y.diff(t) ** 2) / 2 - y \
        - k * (sp.sqrt(x ** 2 + y ** 2) - 1) ** 2 / 2
    equations = [sp.diff(lagrangian.diff(q.diff(t)), t) - lagrangian.diff(q) for q in (x, y)]
    accelerations = sp.solve(equations, [x.diff(t, 2), y.diff(t, 2)])
    X, Y = sp.symbols("X Y")
    return sp.lambdify((X, Y, k), [accelerations[q.diff(t, 2)].subs({x: X, y: Y})
                                   for q in (x, y)])


@pytest.mark.parametrize("k", [1.0, 50.0])
def test_rhs_matches_euler_lagrange_equations(k):
    accelerations = lagrangian_accelerations()
    for state in STATES:
        expected = [state[2], state[3], *accelerations(state[0], state[1], k)]
        assert elastic_pendulum_rhs(0.0, state, k) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("k", [1.0, 1e4])
def test_jacobian_matches_central_differences(k):
    for state in STATES:
        step = 1e-6
        numeric = np.column_stack([
            (elastic_pendulum_rhs(0, state + step * e, k)
             - elastic_pendulum_rhs(0, state - step * e, k)) / (2 * step) for e in np.eye(4)])
        assert np.allclose(elastic_pendulum_jacobian(0, state, k), numeric,
                           rtol=1e-6, atol=1e-6 * k)


def test_energy_conserved_by_tight_run_and_formula():
    solution, error = simulate_elastic_pendulum(10.0, SEED_STATE0, 20.0, "dop853",
                                                rtol=1e-12, atol=1e-12)
    assert error < 1e-9
    # E0 = k (r - 1)^2 / 2 at rest at r = 1.2, y = 0.
    assert elastic_pendulum_energy(SEED_STATE0, 10.0) == pytest.approx(0.2)
    assert solution.state_names == ("x", "y", "vx", "vy")


def test_energy_growth_reported_as_divergence():
    with pytest.raises(DivergenceError, match="energy drift") as caught:
        # Outputs every 0.1 s, so the steps are dt = 0.05: h w = 5 > 2.83 (RK4 unstable).
        simulate_elastic_pendulum(1e4, SEED_STATE0, 20.0, "rk4", dt=0.05)
    assert set(caught.value.components) == {"x", "y", "vx", "vy"}


@pytest.mark.parametrize("k, n, verdict", [(1, 1000, "stable, inaccurate"),
                                           (20, 1000, "unstable")])
def test_explicit_euler_stability_as_in_seed(k, n, verdict):
    assert stability_verdict(k, n)[0] == verdict


@pytest.fixture(scope="module")
def study_rows():
    return elastic_pendulum_study()


def test_study_cvode_statistics_near_seed_figures(study_rows):
    seed_steps = {("cvode_bdf", 10): 536, ("cvode_adams", 10): 381, ("cvode_bdf", 50): 1100,
                  ("cvode_adams", 50): 737, ("rk45", 10): 201, ("lsoda", 10): 362}
    rows = {(r.integrator, r.k): r for r in study_rows if r.table == "cvode_statistics"}
    assert set(rows) == set(seed_steps)
    for key, steps in seed_steps.items():
        assert rows[key].steps == pytest.approx(steps, rel=0.2), key
    # BDF needs more steps than Adams on this non-stiff problem, as in the seed.
    for k in (10, 50):
        assert rows[("cvode_bdf", k)].steps > rows[("cvode_adams", k)].steps


def test_study_energy_error_falls_with_step_and_tolerance(study_rows):
    by_integrator = {}
    for row in study_rows:
        if row.table == "energy_error":
            by_integrator.setdefault(row.integrator, []).append(row.energy_error)
    assert set(by_integrator) == set(integrator_names("ode"))  # every ODE integrator
    for integrator, errors in by_integrator.items():
        assert all(b < a for a, b in zip(errors, errors[1:])), integrator


@pytest.fixture
def pendulum_cli(monkeypatch):
    monkeypatch.setattr(cli, "COMMAND_MODULES", ("youbot_dynamics.cli.study_commands",))
    return cli.main


def test_cli_pendulum_json(pendulum_cli, capsys):
    assert pendulum_cli(["study", "pendulum", "--k", "10", "--state0", "1.2,0,0,0", "--duration", "20",
                         "--integrator", "rk4", "--dt", "0.01", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    reference, _ = simulate_elastic_pendulum(10.0, SEED_STATE0, 20.0, "dop853", rtol=1e-12,
                                             atol=1e-12)
    assert [result["final_state"][n] for n in ("x", "y", "vx", "vy")] == pytest.approx(
        reference.x[-1], abs=1e-5)
    assert result["stats"]["steps"] == 2000 and result["energy_error"] < 1e-6


def test_cli_pendulum_text_and_study(pendulum_cli, capsys):
    assert pendulum_cli(["study", "pendulum", "--integrator", "cvode_adams"]) == 0
    assert "energy error" in capsys.readouterr().out
    assert pendulum_cli(["study", "pendulum-tables", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {row["table"] for row in rows} == {"euler_stability", "cvode_statistics",
                                              "energy_error"}


@pytest.mark.parametrize("argv, message", [
    (["--state0", "1,2"], "--state0 must be four"),
    (["--integrator", "leapfrog"], "unknown ODE integrator 'leapfrog'"),
    (["--integrator", "rk45", "--dt", "0.1"], "--dt applies to fixed-step"),
    (["--k", "-1"], "stiffness k must be positive"),
])
def test_cli_pendulum_bad_arguments_exit_2(pendulum_cli, capsys, argv, message):
    assert pendulum_cli(["study", "pendulum", *argv]) == 2
    error = capsys.readouterr().err
    assert message in error and len(error.strip().splitlines()) == 1


def test_cli_pendulum_divergence_exit_1(pendulum_cli, capsys):
    assert pendulum_cli(["study", "pendulum", "--k", "1e4", "--integrator", "euler", "--dt",
                         "0.05"]) == 1
    assert "euler diverged at t=" in capsys.readouterr().err
