"""Andrew's squeezer against the IVP test set (benchmarks.md section 1)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from youbot_dynamics.cli import main
from youbot_dynamics.dynamics.constraints import (DAE_FORMULATIONS, consistent_initial_values,
                                                  dae_form)
from youbot_dynamics.studies.squeezer import (LAMBDA0, Q0, V0, W0, reference_error,
                                              simulate_squeezer, squeezer_system, suppression_run)

RNG = np.random.default_rng(7)


def test_generated_jacobian_and_curvature_match_finite_differences():
    system = squeezer_system()
    q, v = Q0 + 0.1 * RNG.standard_normal(7), 50.0 * RNG.standard_normal(7)
    h = 1e-6
    columns = [(system.constraint(q + h * e) - system.constraint(q - h * e)) / (2 * h)
               for e in np.eye(7)]
    assert system.jacobian(q) == pytest.approx(np.array(columns).T, abs=1e-9)
    # g_qq(v, v) = d/dt (G(q) v) along q' = v with v held
    dgv = (system.jacobian(q + h * v) @ v - system.jacobian(q - h * v) @ v) / (2 * h)
    assert system.curvature(q, v) == pytest.approx(dgv, rel=1e-6)


@pytest.mark.parametrize("formulation", DAE_FORMULATIONS)
def test_exact_dae_jacobian_matches_finite_differences(formulation):
    form = dae_form(squeezer_system(), formulation, Q0, V0, W0, LAMBDA0)
    y = form.y0 + 0.1 * RNG.standard_normal(form.y0.size)
    yp = form.yp0 + RNG.standard_normal(form.y0.size)
    cj, h = 1e3, 1e-6
    columns = [(form.residual(0.0, y + h * e, yp + cj * h * e)
                - form.residual(0.0, y - h * e, yp - cj * h * e)) / (2 * h)
               for e in np.eye(y.size)]
    exact = form.residual_jacobian(0.0, y, yp, cj)
    assert exact == pytest.approx(np.array(columns).T, rel=1e-6, abs=1e-9 * cj)


def test_published_consistent_values_are_reproduced():
    q, v, w, lam, _ = consistent_initial_values(squeezer_system(), Q0, V0, fixed=(1,))
    assert np.max(np.abs(squeezer_system().constraint(Q0))) < 1e-16
    assert w == pytest.approx(W0, rel=1e-12, abs=1e-9)
    assert lam == pytest.approx(LAMBDA0, rel=1e-12, abs=1e-11)


def test_newton_initialisation_from_a_perturbed_guess():
    guess = Q0 + 0.05 * RNG.standard_normal(7)
    guess[1] = 0.0                                   # Theta held, as in the test set
    v_guess = np.ones(7)
    v_guess[1] = 0.0                                 # Theta' = 0 held: v must come out 0
    q, v, w, lam, iterations = consistent_initial_values(
        squeezer_system(), guess, v_guess, fixed=(1,))
    assert iterations >= 3
    assert np.max(np.abs(squeezer_system().constraint(q))) < 1e-13
    assert q == pytest.approx(Q0, abs=1e-12)         # the branch of the published q0
    assert v == pytest.approx(V0, abs=1e-12)
    assert w == pytest.approx(W0, rel=1e-9, abs=1e-6)
    assert lam == pytest.approx(LAMBDA0, rel=1e-9, abs=1e-8)


@pytest.mark.parametrize("formulation,integrator,rtol,bound", [
    ("index1", "dop853", 1e-10, 2e-9),             # reference's own accuracy is ~1e-9
    ("index1-projection", "dop853", 1e-10, 2e-9),
    ("index2", "ida", 1e-10, 1e-8),
    ("ggl", "ida", 1e-10, 1e-8),
    ("index2", "radau5", 1e-8, 1e-8),              # measured 2.2e-10
    ("ggl", "radau5", 1e-8, 1e-8)])                # measured 7.2e-10
def test_state_at_reference_time(formulation, integrator, rtol, bound):
    run = simulate_squeezer(formulation, integrator, rtol=rtol, n_outputs=4)
    assert np.max(reference_error(run.q[-1])) < bound


def test_index3_runs_with_the_exact_jacobian():
    """Index 3 with the exact iteration matrix (IDA's finite differences needed about
    7000 steps here). v, w and lambda sit under a loose absolute tolerance (see
    dynamics.constraints), so q's error is not controlled and swings with round-off:
    runs at rtol 1e-8 x (0.97, 0.99, 0.997, 1, 1.001, 1.003, 1.01, 1.03) measured q errors
    against the reference from 1.3e-4 to 0.26 (1.26e-3 at rtol 1e-8 on another CPU) and
    1237 to 5478 steps. What holds on any CPU is asserted: the position constraints that
    index 3 enforces (|g(q)| measured <= 9.4e-12 m over those runs; bound 1e-10 m), the
    count of Jacobians (169 to 269; bound 500), and q the squeezer's motion rather than
    a wrong one (relative error <= 0.26; bound 1, a sign or mode error gives > 1)."""
    run = simulate_squeezer("index3", "ida", rtol=1e-8, n_outputs=4)
    assert run.stats.jac_evals < 500
    assert np.max(np.abs(run.position_residual[-1])) < 1e-10
    assert np.max(reference_error(run.q[-1])) < 1.0


def test_index3_with_the_higher_index_variables_out_of_the_error_test():
    """Index 3 within 1e-6 (relative, on q) of the reference at
    t = 0.03 s at rtol no tighter than 1e-8. radau5 (the index3 default) scales the error
    weights of v by 1/h and of w, lambda by 1/h^2. Measured at rtol 1e-8 (atol 1e-11):
    2.9e-7 in 476 steps, max|g| 6e-16 m; bound 1e-6 (3.5x margin)."""
    run = simulate_squeezer("index3", rtol=1e-8, n_outputs=4)
    assert run.stats.integrator == "radau5"
    assert np.max(reference_error(run.q[-1])) < 1e-6
    assert np.max(np.abs(run.position_residual[-1])) < 1e-10
    assert None not in (run.stats.rejected_steps, run.stats.nonlinear_iterations,
                        run.stats.nonlinear_convergence_failures)


def test_index3_needs_the_index_scaling():
    """The same Radau IIA with every component under the plain weights cannot pass the
    error test on w and lambda at any step size: the step collapses at t = 0."""
    cell = suppression_run("index3", "radau5, all in error test", 1e-6, 2)
    assert cell.error is None and "t = 0 s, step size collapsed" in cell.failure


def test_index3_residual_vanishes_on_an_accurate_solution():
    accurate = simulate_squeezer("index1", "dop853", rtol=1e-10, n_outputs=3)
    system = squeezer_system()
    q, v, lam = accurate.q[1], accurate.v[1], accurate.multipliers[1]
    w = np.linalg.solve(system.mass(q), system.forces(q, v) - system.jacobian(q).T @ lam)
    form = dae_form(system, "index3", Q0, V0, W0, LAMBDA0)
    y = np.concatenate((q, v, w, lam))
    residual = form.residual(0.0, y, np.concatenate((v, w, np.zeros(13))))
    assert np.max(np.abs(residual[:21])) < 1e-9 * np.max(np.abs(w))
    assert np.max(np.abs(residual[21:])) < 1e-10


def test_drift_is_largest_without_stabilisation():
    drift = {}
    for formulation in ("index1", "index1-baumgarte", "index1-projection"):
        run = simulate_squeezer(formulation, "rk45", rtol=1e-6, n_outputs=31)
        drift[formulation] = (np.abs(run.position_residual).max(),
                              np.abs(run.velocity_residual[-1]).max())
    for stabilised in ("index1-baumgarte", "index1-projection"):
        assert drift[stabilised][0] < 0.1 * drift["index1"][0]
        assert drift[stabilised][1] < drift["index1"][1]
    assert drift["index1-projection"][0] < 1e-12


def test_cli_json_and_errors(capsys, tmp_path):
    assert main(["study", "squeezer", "--formulation", "index1", "--integrator", "dop853",
                 "--rtol", "1e-8", "--json", "--plot", str(tmp_path / "drift.png")]) == 0
    report = json.loads(capsys.readouterr().out)
    assert max(report["relative_error_vs_reference"]) < 1e-6
    assert (tmp_path / "drift.png").stat().st_size > 10_000
    assert main(["study", "squeezer", "--formulation", "index2", "--jacobian", "fd", "--rtol", "1e-4",
                 "--outputs", "3", "--json"]) == 0
    assert max(json.loads(capsys.readouterr().out)["relative_error_vs_reference"]) < 1e-2
    assert main(["study", "squeezer", "--formulation", "index3", "--integrator", "rk45"]) == 2
    assert main(["study", "squeezer", "--formulation", "index1", "--integrator", "radau5"]) == 2
    assert main(["study", "squeezer", "--formulation", "index1", "--rtol", "-1"]) == 2
    assert main(["study", "structure", "pendulum", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["structural_index"] == 3


def test_cli_suppression_tables(capsys):
    """The grids at one tolerance (measured at tol 1e-4: index 3 fails at t = 0 with IDA
    either way and with radau5 unscaled, index-scaled radau5 9.9e-4 in 47 steps; index 2:
    IDA with w, lambda in its error test spends the step budget, suppressed 1.1e-3 in 321
    steps, radau5 unscaled and scaled both within 1e-4)."""
    assert main(["study", "squeezer", "--table", "--tolerances", "1e-4", "--outputs", "3",
                 "--json"]) == 0
    tables = json.loads(capsys.readouterr().out)
    index3, index2 = tables["index3"]["rows"][0], tables["index2"]["rows"][0]
    assert tables["index3"]["document_table"] == 8 and tables["index2"]["document_table"] == 9
    assert index3["radau5, all in error test"]["failure"].startswith("t = 0 s")
    assert index3["radau5, index-scaled"]["error"] < 2e-2
    assert index2["ida, suppressed"]["error"] < 1e-2
    assert index2["radau5, index-scaled"]["error"] < 1e-3
    assert main(["study", "squeezer", "--table", "--tolerances", "0"]) == 2
