"""Rotations study: Cardan angles, adaptive Cardan and quaternions on a torque-free top,
against scipy's Euler-angle conventions, finite differences and the closed-form top."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from youbot_dynamics.model.lie import exp_so3, skew, unskew
from youbot_dynamics.model.rotations import (SEQUENCES, cardan_angles, cardan_matrix,
                                             cardan_rate_matrix, euler_equations)
from youbot_dynamics.studies.rotations import (RUNS, attitude_error, axisymmetric_top,
                                               simulate_rotation)

ANGLES = np.array([0.4, -0.9, 2.1])


@pytest.mark.parametrize("sequence", SEQUENCES)
def test_cardan_matrix_is_scipys_intrinsic_sequence(sequence):
    expected = Rotation.from_euler(sequence.upper(), ANGLES).as_matrix()
    np.testing.assert_allclose(cardan_matrix(sequence, ANGLES), expected, atol=1e-15)
    np.testing.assert_allclose(cardan_angles(sequence, expected), ANGLES, atol=1e-12)


@pytest.mark.parametrize("sequence", SEQUENCES)
def test_cardan_rate_matrix_maps_angle_rates_to_body_rate(sequence):
    """[w] = R^T R' by central differences of cardan_matrix along a' (h = 1e-6: error
    ~1e-12 measured, bound 1e-8)."""
    rates, h = np.array([0.3, -1.2, 0.7]), 1e-6
    derivative = (cardan_matrix(sequence, ANGLES + h * rates)
                  - cardan_matrix(sequence, ANGLES - h * rates)) / (2 * h)
    w = unskew(cardan_matrix(sequence, ANGLES).T @ derivative)
    np.testing.assert_allclose(cardan_rate_matrix(sequence, ANGLES) @ rates, w, atol=1e-8)


def test_cardan_rate_matrix_is_singular_at_gimbal_lock():
    for middle in (0.3, 1.5, np.pi / 2):
        det = np.linalg.det(cardan_rate_matrix("xyz", np.array([0.2, middle, -0.4])))
        assert abs(det) == pytest.approx(abs(np.cos(middle)), abs=1e-15)


@pytest.mark.parametrize("name", RUNS)
def test_closed_form_top_solves_the_equations_of_motion(name):
    """The closed form against the ODE it claims to solve: R' = R [w] and Euler's
    equations by central differences (h = 1e-5: ~1e-9 measured, bound 1e-7), and the
    world angular momentum R J w constant."""
    run = RUNS[name]
    inertia, w0 = np.array(run.inertia), np.array(run.w0)
    t, h = np.array([0.7, 3.1]), 1e-5
    rotations, rates = axisymmetric_top(inertia, run.rotation0, w0, t)
    after, after_rates = axisymmetric_top(inertia, run.rotation0, w0, t + h)
    before, before_rates = axisymmetric_top(inertia, run.rotation0, w0, t - h)
    for i in range(t.size):
        np.testing.assert_allclose((after[i] - before[i]) / (2 * h),
                                   rotations[i] @ skew(rates[i]), atol=1e-7)
        np.testing.assert_allclose((after_rates[i] - before_rates[i]) / (2 * h),
                                   euler_equations(inertia, rates[i]), atol=1e-7)
        np.testing.assert_allclose(rotations[i] @ (inertia * rates[i]),
                                   run.rotation0 @ (inertia * w0), atol=1e-12)


def test_attitude_error_is_the_rotation_angle_between():
    rotation = exp_so3(np.array([0.1, 0.2, -0.3]))
    turned = rotation @ exp_so3(np.array([0.0, 0.0, 1e-3]))
    assert attitude_error(turned[None], rotation[None])[0] == pytest.approx(1e-3, rel=1e-9)


TOL = 1e-8
#: Global attitude error allowed, in units of the requested tol: the error accumulates over
#: 10 s of turning; measured 11x (top, all three), 13x and 5x (tumble, adaptive and
#: quaternion) at tol 1e-8 with rk45; the bound has a margin of 2x over the largest.
GLOBAL_FACTOR = 30


@pytest.fixture(scope="module")
def tumble():
    return {f: simulate_rotation(RUNS["tumble"], f, tol=TOL)
            for f in ("cardan", "cardan_adaptive", "quaternion")}


def test_gimbal_lock_fixed_sequence_crawls(tumble):
    """Passing within 1e-4 rad of gimbal lock six times, the x-y-z sequence needs many
    small steps (measured 466 steps against the quaternion's 83, 5.6x)."""
    fixed, quaternion = tumble["cardan"], tumble["quaternion"]
    assert fixed.failure is not None or fixed.stats.steps > 4 * quaternion.stats.steps


@pytest.mark.parametrize("formulation", ["cardan_adaptive", "quaternion"])
def test_gimbal_lock_adaptive_and_quaternion_pass(tumble, formulation):
    """Adaptive Cardan switches once to x-z-y (whose middle angle then stays near 0) and
    takes fewer steps than the quaternion (measured 52 against 83); both meet the closed
    form."""
    result = tumble[formulation]
    assert result.failure is None
    assert result.errors["attitude"] < GLOBAL_FACTOR * TOL
    assert result.stats.steps <= tumble["quaternion"].stats.steps
    if formulation == "cardan_adaptive":
        assert result.switches >= 1
        assert np.max(np.abs(result.middle_angle)) <= 1.5 + 1e-6


@pytest.mark.parametrize("formulation", ["cardan", "cardan_adaptive", "quaternion"])
def test_all_three_meet_the_closed_form_top(formulation):
    result = simulate_rotation(RUNS["top"], formulation, tol=TOL)
    assert result.failure is None
    assert result.errors["attitude"] < GLOBAL_FACTOR * TOL
    assert result.errors["rate"] < GLOBAL_FACTOR * TOL
    if formulation == "quaternion":  # |q| drift: measured 1e-8 (= tol)
        assert np.max(np.abs(result.quaternion_norm - 1.0)) < 10 * TOL


def test_pure_spin_about_the_first_axis_is_linear_in_cardan_angles():
    """The seed's claim in its cleanest form: spin about x alone makes a1 = 10 t exactly,
    so Cardan takes a handful of steps where the quaternion's components oscillate
    (measured 5 against 408 steps)."""
    spin = RUNS["spin"]
    run = type(spin)("spin", spin.inertia, spin.rotation0, (10.0, 0.0, 0.0), spin.t_end, "")
    cardan = simulate_rotation(run, "cardan", tol=TOL)
    quaternion = simulate_rotation(run, "quaternion", tol=TOL)
    assert cardan.stats.steps * 10 < quaternion.stats.steps
    assert cardan.errors["attitude"] < 1e-10 and quaternion.errors["attitude"] < GLOBAL_FACTOR * TOL


def test_cli_rotations_json_and_plot(tmp_path, capsys):
    import json

    from youbot_dynamics.cli import main
    plot = tmp_path / "rotations.png"
    assert main(["study", "rotations", "--runs", "top", "--tol", "1e-6", "--plot", str(plot),
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert [row["formulation"] for row in report["rows"]] == ["cardan", "cardan_adaptive",
                                                             "quaternion"]
    assert report["spin_wobble_sweep"] == [] and plot.stat().st_size > 10_000
    assert all(row["attitude_error"] < GLOBAL_FACTOR * 1e-6 for row in report["rows"])
    assert main(["study", "rotations", "--runs", "wobble"]) == 2


@pytest.mark.parametrize("argv, stand_in", [
    (["study", "rotations", "--plot"], "youbot_dynamics.studies.rotations.rotations_study"),
    (["study", "uncertainty", "--plot"], "youbot_dynamics.studies.uncertain_pendulum.linear_propagation"),
    (["study", "bdf", "--choppy-plot"], "youbot_dynamics.studies.bdf_study.fixed_step_tables"),
])
def test_study_plot_paths_checked_before_the_run(monkeypatch, capsys, tmp_path, argv, stand_in):
    from youbot_dynamics.cli import main

    def ran(*args, **kwargs):
        pytest.fail("the run started before the output path was checked")
    monkeypatch.setattr(stand_in, ran)
    assert main([*argv, str(tmp_path / "absent" / "plot.png")]) == 2
    error = capsys.readouterr().err
    assert "does not exist" in error and len(error.strip().splitlines()) == 1
