"""Document 000's runs as it runs them: the ModiaLang pendulum's statistics log beside
ours (RK45, the nearest scipy pair to Tsit5), the ModiaBase low-pass assign list (a valid
perfect matching with our blocks), and the Modia3D pendulums against closed forms."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.studies import modia3d_pendulums
from youbot_dynamics.studies.equation_figures import hand_written_pendulum, run_model
from youbot_dynamics.studies.equations import cartesian_pendulum
from youbot_dynamics.studies.modia_log import DOCUMENT_LOG, run_as_document
from youbot_dynamics.studies.structure import (LOWPASS_INCIDENCE, augmenting_path_matching,
                                               is_perfect_matching, structure_report)


def test_modia_pendulum_run_as_the_document_beside_its_log():
    """L = 0.5 m, rtol 1e-6, atol 1e-7 (Modia's 0.1 tol), 501 results every 0.02 s.
    Measured with scipy's RK45: 129 accepted, 7 rejected, 818 evaluations (= 6 x 136 + 2),
    against the document's Tsit5 152 / 0 / 913; phi 6.2e-7 rad from a 1e-12 run (bound 1e-5)."""
    ours = run_as_document()
    assert (ours["nResults"], ours["interval"], ours["nStates"]) == (501, 0.02, 2)
    assert (DOCUMENT_LOG["nResults"], DOCUMENT_LOG["nAcceptedSteps"],
            DOCUMENT_LOG["nf (integrator)"]) == (501, 152, 913)
    assert (ours["nAcceptedSteps"], ours["nRejectedSteps"], ours["nf (integrator)"]) == \
        (129, 7, 818)
    # both FSAL 7-stage pairs: 6 new evaluations per step (Tsit5: 152 x 6 + 1 = 913)
    assert ours["nf (integrator)"] == 6 * (ours["nAcceptedSteps"] + ours["nRejectedSteps"]) + 2
    reference = integrate(lambda t, x: np.array([x[1], -(0.5 * x[1] + 9.81 * 0.5 * np.sin(x[0]))
                                                 / 0.25]),
                          [1.57, 0.0], ours["t"], "dop853", rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(ours["phi"] - reference.x[:, 0])) < 1e-5


def test_lowpass_document_assign_is_a_perfect_matching_with_our_blocks():
    report = structure_report("lowpass")
    assert report["document_assign"] == [2, 6, 3, 1, 0, 5, 4]
    assert report["assign"] == [1, 6, 4, 3, 0, 5, 2]
    assert report["document_assign_is_perfect_matching"] and report["perfect_matching"]
    assert report["document_assign_blocks"] == report["blocks"] == [[6], [1, 2, 3, 4], [5]]
    equation_vars = [{j - 1 for j in vs} for vs in LOWPASS_INCIDENCE]
    # a wrong list is refused: f1 does not hold variable 3
    assert not is_perfect_matching(equation_vars, [2, 6, 1, 3, 0, 5, 4])
    unknowns = [0, 1, 2, 3, 5, 6]
    forward = augmenting_path_matching(equation_vars, unknowns)
    backward = augmenting_path_matching(equation_vars, unknowns, last_first=True)
    assert [forward.get(j, -1) + 1 for j in range(7)] == report["assign"]
    assert [backward.get(j, -1) + 1 for j in range(7)] == report["document_assign"]


@pytest.mark.parametrize("radius", [0.5, 0.3])
def test_modia3d_pendulum1_period_is_the_elliptic_closed_form(radius):
    """Released horizontal: T = 4 sqrt(r / g) K(1/2) = 1.674317 s (r = 0.5 m); measured
    agreement 1e-11 s."""
    pendulum = modia3d_pendulums.pendulum1(radius)
    solution = modia3d_pendulums.simulate(pendulum)
    exact = modia3d_pendulums.released_horizontal_period(radius)
    assert modia3d_pendulums.first_return_time(solution) == pytest.approx(exact, abs=1e-7)
    assert modia3d_pendulums.released_horizontal_period(0.5) == pytest.approx(1.674317, abs=1e-6)
    assert np.ptp(pendulum.energy(solution.x)) < 1e-6


def test_modia3d_pendulum3_loses_what_the_damper_dissipates():
    """Steel box 320 kg, I = 107.73 kg m^2; E(0) - E(3 s) = integral of d phi'^2 dt
    (measured 1454.41 J both, 7e-5 J apart with 1501 trapezoid points; bound 1e-6 relative,
    1.5e-3 J)."""
    pendulum = modia3d_pendulums.pendulum3()
    assert (pendulum.mass, pendulum.inertia) == pytest.approx((320.0, 107.7333), abs=1e-4)
    solution = modia3d_pendulums.simulate(pendulum)
    energy = pendulum.energy(solution.x)
    dissipated = np.trapezoid(pendulum.damping * solution.x[:, 1] ** 2, solution.t)
    assert energy[0] - energy[-1] == pytest.approx(dissipated, rel=1e-6)
    assert energy[0] - energy[-1] == pytest.approx(1454.41, abs=0.01)


def test_mtk_cartesian_pendulum_with_the_documents_start_meets_the_angle_form():
    """x = 1, y = 0 at rest, g = 9.8, L = 1 on [0, 10] s (document 000's ModelingToolkit
    run): the generated ODE (DOP853, tol 1e-10, state selection changing 18 times) against
    theta'' = -g sin(theta) by hand: measured 9.2e-9 m apart."""
    model = cartesian_pendulum()
    assert (model.variables["x"], model.variables["y"], model.parameters["g"],
            model.parameters["L"], model.t_end) == (1.0, 0.0, 9.8, 1.0, 10.0)
    run = run_model(model, tol=1e-10, outputs=501)
    t, x = run.values("x")
    _, y = run.values("y")
    reference = hand_written_pendulum(model, t)
    assert np.max(np.hypot(x - reference[:, 0], y - reference[:, 1])) < 1e-7
    assert len(run.segments) == 18
