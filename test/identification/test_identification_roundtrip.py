"""Identification end to end: the optimised excitation, bags recorded from a perturbed
youBot, and the identified base parameters against the perturbed truth.

Two ways of recording (see identification.synthetic):
- through the simulator: the dynamics node's simulation session runs the scene
  config/scenes/identification.yaml with the perturbed URDF, the excitation arrives as a
  /joint_trajectory and the computed-torque controller tracks it; the node's MCAP is the bag,
  and Gaussian noise of NOISE N m is added to its recorded (applied) efforts afterwards;
- by inverse dynamics of the perturbed robot (Pinocchio's RNEA plus the simulator's friction
  law) along the excitation's exact q, qd, qdd, with the same noise on every effort.
"""
from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.cli import main
from youbot_dynamics.dynamics import friction
from youbot_dynamics.identification import synthetic
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.identification.base_parameters import base_parameters
from youbot_dynamics.identification.consistency import consistent_fit, pseudo_inertia_eigenvalues
from youbot_dynamics.identification.excitation import (ExcitationLimits, FourierTrajectory, condition_number,
                                                       optimise_excitation, random_fourier)
from youbot_dynamics.identification.identify import (ARM_JOINTS, identify_bag, layout_for, prediction_rms)
from youbot_dynamics.identification.measurements import preprocess, read_joint_samples
from youbot_dynamics.identification.urdf_output import body_links
from youbot_dynamics.model.robot import load_robot
from youbot_dynamics.node.commands import MAX_TRAJECTORY_POINTS

NOISE = 0.05          # N m, standard deviation of the effort noise (youBot current-based torques: ~0.1)
RATE = 500.0          # Hz, /joint_states
LIMITS = ExcitationLimits()


@pytest.fixture(scope="module")
def nominal():
    return load_robot(default_urdf())


@pytest.fixture(scope="module")
def layout(nominal):
    return layout_for(nominal)


@pytest.fixture(scope="module")
def base(layout):
    return base_parameters(layout)


@pytest.fixture(scope="module")
def excitation(layout, base):
    # short form: 3 harmonics over a 10 s period, 25 SLSQP iterations
    return optimise_excitation(layout, base, period=10.0, harmonics=3, iterations=25, seed=0)


def perturbed_urdf(rng: np.random.Generator) -> str:
    """The youBot with masses +-20 %, COMs moved 1 cm, inertias x U(0.7, 1.3), the arm's
    damping and Coulomb friction from U(0.2, 0.8) (the URDF: 1 and 0.5)."""
    return synthetic.perturbed_urdf(default_urdf(), ARM_JOINTS, rng)


def record(path, robot, trajectory: FourierTrajectory, duration: float, rng: np.random.Generator) -> None:
    """/joint_states at RATE with effort noise NOISE; a gripper finger rides along at 0."""
    synthetic.record_joint_states(path, robot, trajectory, duration, RATE, NOISE, rng,
                                  passengers=("gripper_finger_joint_l",))


# --------------------------------------------------------------------------------------
# Excitation
# --------------------------------------------------------------------------------------
def test_optimised_excitation_keeps_limits_starts_at_rest_and_lowers_the_condition(excitation, layout, base):
    trajectory = excitation.trajectory
    q, v, a = trajectory.evaluate(np.linspace(0.0, trajectory.period, 4001))   # 67x denser than the optimiser's grid
    robot = layout.robot
    # the optimiser's constraints hold on its 60-point grid; between grid points measured:
    # positions 1.6e-3 rad past the shrunk limits (bound: half the 0.1 rad margin), speed 1.0 %
    # over its bound (bound 2 %), accelerations 1.8 rad/s^2 inside theirs (bound 2 %)
    assert np.all(q >= robot.lower + 0.5 * LIMITS.margin) and np.all(q <= robot.upper - 0.5 * LIMITS.margin)
    assert np.all(np.abs(v) <= 1.02 * LIMITS.velocity_fraction * robot.velocity_limit)
    assert np.all(np.abs(a) <= 1.02 * LIMITS.acceleration)
    np.testing.assert_allclose(v[0], 0.0, atol=1e-9)   # measured 1e-16
    np.testing.assert_allclose(a[0], 0.0, atol=1e-9)
    # the nominal robot's efforts (Pinocchio's RNEA plus the URDF's friction) within the URDF's
    # effort limits at every point (before: 43 % and 22 % of the points beyond joints 4 and 5's;
    # measured at most 96 % of a limit)
    assert np.all(np.abs(nominal_efforts(robot, q, v, a)) <= robot.effort_limit)
    assert excitation.condition < 0.5 * excitation.initial_condition   # measured 2150 -> 115
    # against random Fourier trajectories of the same period and harmonics, in the same limits
    randoms = [condition_number(layout, base, random_fourier(layout, 10.0, 3, LIMITS, np.random.default_rng(s)))
               for s in range(1, 6)]
    assert excitation.condition < 0.5 * min(randoms), (excitation.condition, randoms)   # measured 154 vs 4017..24839


def nominal_efforts(robot, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """(N, nv) efforts (N m) of ``robot`` along the samples: RNEA plus viscous and regularised
    Coulomb friction from the URDF's <dynamics>."""
    data = robot.model.createData()
    rnea = np.array([pin.rnea(robot.model, data, qk, vk, ak) for qk, vk, ak in zip(q, v, a)])
    return rnea + robot.damping * v + friction.coulomb(v, robot.friction, friction.DEFAULT_VELOCITY_SCALE)


def test_excitation_file_round_trips(excitation, tmp_path):
    path = tmp_path / "excite.yaml"
    excitation.trajectory.write(path, rate=50.0)
    again = FourierTrajectory.read(path)
    t = np.linspace(0, 10, 7)
    np.testing.assert_array_equal(again.evaluate(t)[0], excitation.trajectory.evaluate(t)[0])
    (tmp_path / "bad.yaml").write_text("joint_names: [a]\n")
    with pytest.raises(UserInputError, match="bad.yaml.*Fourier"):
        FourierTrajectory.read(tmp_path / "bad.yaml")


# --------------------------------------------------------------------------------------
# Round trip
# --------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def truth_robot():
    return load_robot(perturbed_urdf(np.random.default_rng(12)))


@pytest.fixture(scope="module")
def excitation_bag(excitation, truth_robot, tmp_path_factory):
    bag = tmp_path_factory.mktemp("bags") / "excitation.mcap"
    record(bag, truth_robot, excitation.trajectory, 20.0, np.random.default_rng(13))
    return bag


def test_round_trip_recovers_perturbed_base_parameters(excitation_bag, truth_robot, layout, base, tmp_path):
    truth = base.of(layout_for(truth_robot).standard_parameters())
    result = identify_bag(excitation_bag, load_robot(default_urdf()))
    z = (result.wls.values - truth) / result.wls.std
    # measured: max |z| 2.54 over the 44 base parameters (seeds 12/13), cond(W) 154; bench: 1.8..2.7 over 5 seeds
    assert np.all(np.abs(z) < 3.0), [(result.names[i], z[i]) for i in np.flatnonzero(np.abs(z) >= 3)]
    # held out: a random Fourier trajectory the identification never saw
    rng = np.random.default_rng(14)
    held_out = tmp_path / "held_out.mcap"
    record(held_out, truth_robot, random_fourier(layout, 8.0, 4, LIMITS, rng), 8.0, rng)
    motion = preprocess(read_joint_samples(held_out, ARM_JOINTS))
    identified = prediction_rms(layout, base, result.wls.values, motion)
    urdf = prediction_rms(layout, base, result.nominal, motion)
    # measured: identified 0.049..0.050 N m per joint (noise 0.05, bound 0.06); nominal URDF 0.08..0.52 N m
    assert np.all(identified < 1.2 * NOISE), identified
    assert np.all(urdf > 1.5 * NOISE), urdf


def test_cli_identify_prints_json_and_plots(excitation_bag, tmp_path, capsys):
    plot = tmp_path / "fit.png"
    assert main(["identify", str(excitation_bag), "--json", "--plot", str(plot)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["base_parameters"] == 44 and len(report["wls"]["parameters"]) == 44
    assert report["joints"] == list(ARM_JOINTS)
    # 20 s at 500 Hz, 150 samples per edge dropped, decimated by 25 to 20 Hz: 9700 / 25 = 388 samples
    assert report["samples"] == 388
    assert max(report["wls"]["residual_rms"]) < 0.015   # measured 0.0094 (filtered noise 0.05 sqrt(20/500) = 0.01)
    assert set(report["pseudo_inertia_min_eigenvalue"]) == set(ARM_JOINTS)
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["identify", str(excitation_bag), "--friction", "viscous,coulomb"]) == 0
    text = capsys.readouterr().out
    assert "39 base parameters of 60 standard" in text and ".offset" not in text   # 29 inertial + 10 friction


def test_cli_excite_writes_a_trajectory_file(tmp_path, capsys):
    out = tmp_path / "excite.yaml"
    assert main(["excite", "-o", str(out), "--harmonics", "2", "--iterations", "3", "--period", "4",
                 "--rate", "50", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["base_parameters"] == 44
    assert report["condition_optimised"] <= report["condition_initial"]
    import yaml
    document = yaml.safe_load(out.read_text())
    assert document["joint_names"] == list(ARM_JOINTS) and len(document["points"]) == 4 * 50 + 1
    assert document["points"][-1]["time_from_start"] == {"sec": 4, "nanosec": 0}
    trajectory = FourierTrajectory.read(out)
    np.testing.assert_allclose(trajectory.evaluate(np.array([0.5]))[0][0], document["points"][25]["positions"],
                               rtol=0, atol=1e-12)   # the sampled points are the series (measured 0)
    assert main(["excite", "--joints", "arm_joint_9"]) == 2
    assert "arm_joint_9" in capsys.readouterr().err
    assert main(["excite", "-o", str(out), "--harmonics", "2", "--iterations", "3", "--period", "4", "--rate", "300",
                 "--json"]) == 0   # 1201 points would not fit one message: 249.75 Hz, 1000 points
    assert json.loads(capsys.readouterr().out)["rate"] == 999 / 4
    assert len(yaml.safe_load(out.read_text())["points"]) == 1000


def test_cli_excite_default_fits_one_trajectory_message_within_effort_limits(layout, tmp_path, capsys):
    """The default 10 s period at 100 Hz would be 1001 points, one more than the node takes
    (before: written, then refused as too_large); the default rate fits 1000, ending at the
    period; every written point is within the effort limits."""
    out = tmp_path / "excite.yaml"
    assert main(["excite", "-o", str(out), "--harmonics", "2", "--iterations", "3", "--json"]) == 0
    import yaml
    points = yaml.safe_load(out.read_text())["points"]
    assert len(points) == MAX_TRAJECTORY_POINTS == 1000
    assert points[-1]["time_from_start"] == {"sec": 10, "nanosec": 0}
    q, v, a = (np.array([p[key] for p in points]) for key in ("positions", "velocities", "accelerations"))
    assert np.all(np.abs(nominal_efforts(layout.robot, q, v, a)) <= layout.robot.effort_limit)


# --------------------------------------------------------------------------------------
# Round trip through the simulator (the dynamics node's session) and a consistent URDF
# --------------------------------------------------------------------------------------
NODE_RATE = 200.0     # Hz, the node's publish rate (/joint_states in its MCAP); long form 500


@pytest.fixture(scope="module")
def truth_urdf(tmp_path_factory):
    path = tmp_path_factory.mktemp("truth") / "youbot_perturbed.urdf"
    path.write_text(perturbed_urdf(np.random.default_rng(12)))
    return path


def node_bag(directory, truth_urdf, trajectory: FourierTrajectory, duration: float, rate: float,
             rng: np.random.Generator):
    """The node's bag (``rate`` Hz) of the perturbed youBot tracking ``trajectory`` for
    ``duration`` s, and its copy with N(0, NOISE^2) on the arm's efforts; returns (exact, noisy)."""
    scene = synthetic.excitation_scene(truth_urdf, trajectory, duration, directory / "scene.yaml")
    exact, noisy = directory / "node.mcap", directory / "noisy.mcap"
    synthetic.simulate_excitation(scene, trajectory, rate, exact)
    synthetic.add_effort_noise(exact, noisy, ARM_JOINTS, NOISE, rng)
    return exact, noisy


def simulator_round_trip(excitation, truth_urdf, layout, base, directory, duration: float, held_out: float,
                         rate: float = NODE_RATE):
    """Identify from the node's noisy bag of the excitation; score on a held-out random
    Fourier trajectory the node ran too. Returns (identification, z against the truth,
    held-out RMS identified, held-out RMS of the nominal URDF, exact bag, noisy bag)."""
    exact, noisy = node_bag(directory, truth_urdf, excitation.trajectory, duration, rate, np.random.default_rng(16))
    truth = base.of(layout_for(load_robot(truth_urdf)).standard_parameters())
    # the node's q and v are the simulator's state (exact; the noise is on the efforts):
    # the regressor is evaluated at them, not at low-passed ones (see measurements.preprocess)
    result = identify_bag(noisy, load_robot(default_urdf()), states="measured")
    z = (result.wls.values - truth) / result.wls.std
    rng = np.random.default_rng(14)
    other = directory / "held_out"
    other.mkdir()
    _, held_out_bag = node_bag(other, truth_urdf, random_fourier(layout, held_out, 4, LIMITS, rng), held_out, rate,
                               rng)
    motion = preprocess(read_joint_samples(held_out_bag, ARM_JOINTS), states="measured")
    return (result, z, prediction_rms(layout, base, result.wls.values, motion),
            prediction_rms(layout, base, result.nominal, motion), exact, noisy)


@pytest.fixture(scope="module")
def node_round_trip(excitation, truth_urdf, layout, base, tmp_path_factory):
    # short form: one 10 s period of the excitation, a 5 s held-out trajectory, at 200 Hz
    return simulator_round_trip(excitation, truth_urdf, layout, base, tmp_path_factory.mktemp("node"), 10.0, 5.0)


def test_node_records_the_applied_torques_and_the_noise_is_what_was_added(node_round_trip, excitation, layout):
    *_, exact, noisy = node_round_trip
    clean = read_joint_samples(exact, ARM_JOINTS)
    measured = read_joint_samples(noisy, ARM_JOINTS)
    assert len(clean.t) == 10 * int(NODE_RATE) + 1 and clean.rate == pytest.approx(NODE_RATE)
    np.testing.assert_array_equal(measured.q, clean.q)
    # the added noise: 2001 draws per joint, std 0.05 N m within 7 % (sampling error 1.6 %)
    np.testing.assert_allclose(np.std(measured.effort - clean.effort, axis=0), NOISE, rtol=0.07)
    # the node followed the excitation (computed torque, kp 400, kd 40, the truth's own model)
    # within the effort limits, which the excitation keeps on the nominal robot: the perturbed
    # truth needs at most 93 % of them (measured), nothing is clipped, and the tracking error
    # is 1.1e-5 rad at most (measured; before the excitation kept the limits: joint 4 clipped
    # 22 % of the time and 0.34 rad of error); bounds 1 and 1e-3 rad
    q, _, _ = excitation.trajectory.evaluate(clean.t)
    share = np.abs(clean.effort) / layout.robot.effort_limit
    assert np.all(share < 1.0), share.max(axis=0)
    assert np.abs(clean.q - q).max() < 1e-3, np.abs(clean.q - q).max(axis=0)


def test_round_trip_through_the_simulator_recovers_the_perturbed_base_parameters(node_round_trip):
    result, z, identified, urdf, *_ = node_round_trip
    # measured (truth seed 12, noise seed 16, 10 s at 200 Hz, noise 0.05 N m added to the
    # node's efforts): max |z| 1.86 over the 44 base parameters, cond(W) 130. Over noise seeds
    # 13, 15-21 max |z| is 1.74..3.76 (3 of 8 above 3); truth seeds 1-5 (noise seed + 1):
    # 2.08..3.35 (1 of 5 above 3). For 44 independent normal z, P(max |z| > 3) = 11 %.
    assert np.all(np.abs(z) < 3.0), [(result.names[i], z[i]) for i in np.flatnonzero(np.abs(z) >= 3)]
    # held out (5 s, through the node too): measured identified 0.049..0.051 N m per joint
    # (bound 1.2 x 0.05; seeds 1-5: at most 0.053), the nominal URDF 0.08..0.51 N m
    assert np.all(identified < 1.2 * NOISE), identified
    assert np.all(urdf > 1.5 * NOISE), urdf


@pytest.mark.slow
def test_round_trip_through_the_simulator_long_form(excitation, truth_urdf, layout, base, tmp_path):
    """Two periods (20 s) of the excitation, an 8 s held-out trajectory, at 500 Hz."""
    result, z, identified, urdf, *_ = simulator_round_trip(excitation, truth_urdf, layout, base, tmp_path, 20.0, 8.0,
                                                           500.0)
    assert np.all(np.abs(z) < 3.0), [(result.names[i], z[i]) for i in np.flatnonzero(np.abs(z) >= 3)]
    assert np.all(identified < 1.2 * NOISE) and np.all(urdf > 1.5 * NOISE), (identified, urdf)


def test_consistent_fit_keeps_a_physical_robots_base_values(layout, base, truth_robot, excitation_bag):
    """Base values of a physical robot (the perturbed youBot) with the covariance of a real
    estimate: the minimum-norm standard parameters from the nominal URDF are not consistent (measured
    smallest eigenvalue -1.7e-3),
    the fit is, and reproduces the values to a small fraction of their standard deviations."""
    from youbot_dynamics.identification.consistency import standard_from_base
    values = base.of(layout_for(truth_robot).standard_parameters())
    assert min(pseudo_inertia_eigenvalues(layout, standard_from_base(base, values,
                                                                     layout.standard_parameters())).values()) < 0
    covariance = identify_bag(excitation_bag, load_robot(default_urdf())).wls.covariance
    fit = consistent_fit(layout, base, values, covariance, body_links(default_urdf(), layout))
    assert fit.success, fit.message
    assert fit.smallest_eigenvalue > 0
    assert min(pseudo_inertia_eigenvalues(layout, fit.theta).values()) > 0
    # measured 0.17 standard deviations at most (the prior pulls, weight 1); bound 0.5
    assert np.abs(fit.moved_std).max() < 0.5, np.abs(fit.moved_std).max()


def test_cli_write_urdf_fits_consistent_links_to_the_node_bag(node_round_trip, truth_urdf, layout, base,
                                                               tmp_path, capsys):
    """The noisy node bag: the minimum-norm standard parameters are not consistent (bodies
    2-4); --write-urdf fits every link consistent by construction, body 5's arm_link_5, palm
    and fingers each on its own, and reports how far the base parameters moved."""
    result, *_, noisy = node_round_trip
    out = tmp_path / "identified.urdf"
    assert main(["identify", str(noisy), "--states", "measured", "--write-urdf", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "the consistent fit moved the base parameters by at most" in printed
    assert "the written URDF:" not in printed                         # no warning: every link physical
    text = out.read_text()
    assert f"identify from {noisy}" in text and "log-Cholesky" in text and "Torque offsets" in text
    fit = consistent_fit(layout, base, result.wls.values, result.wls.covariance, body_links(default_urdf(), layout))
    assert fit.success
    # measured: moved at most 0.89 standard deviations; bound 2 (other noise seeds: up to 2.5)
    assert np.abs(fit.moved_std).max() < 2.0, np.abs(fit.moved_std).max()
    # the fitted set is still within 3 standard deviations of the truth (measured 1.76)
    truth = base.of(layout_for(load_robot(truth_urdf)).standard_parameters())
    assert np.all(np.abs(fit.base_values - truth) < 3.0 * result.wls.std)
    reloaded = load_robot(out)
    assert not reloaded.warnings
    theta = layout_for(reloaded).standard_parameters()
    written = np.array(["offset" not in name for name in base.names])[base.independent]  # offsets: no URDF field
    # measured 5e-13 (12 significant digits in the file); bound 1e-9
    np.testing.assert_allclose(base.of(theta)[written], fit.base_values[written], atol=1e-9)
    assert min(pseudo_inertia_eigenvalues(layout_for(reloaded), theta).values()) > 0
    # with --json the same URDF is written, and the document says so
    # (before: the command returned after printing the JSON and wrote nothing)
    in_json = tmp_path / "identified_json.urdf"
    assert main(["identify", str(noisy), "--states", "measured", "--json", "--write-urdf", str(in_json)]) == 0
    document = json.loads(capsys.readouterr().out)
    assert in_json.read_text() == text
    assert document["written_urdf"]["output"] == str(in_json) and document["written_urdf"]["warnings"] == []
    assert document["written_urdf"]["moved_std_max"] == pytest.approx(np.abs(fit.moved_std).max(), rel=1e-9)
