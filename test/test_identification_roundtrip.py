"""Identification end to end: the optimised excitation, a bag recorded from a perturbed
youBot, and the identified base parameters against the perturbed truth.

"Simulation" here is the inverse dynamics of the perturbed robot (Pinocchio's RNEA plus the
simulator's friction law) along the excitation's exact q, qd, qdd, with Gaussian noise of
NOISE N m added to every effort (see identification.synthetic).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.cli import main
from youbot_dynamics.identification import synthetic
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.identification.base_parameters import base_parameters
from youbot_dynamics.identification.excitation import (ExcitationLimits, FourierTrajectory, condition_number,
                                                       optimise_excitation, random_fourier)
from youbot_dynamics.identification.identify import (ARM_JOINTS, identify_bag, layout_for, prediction_rms)
from youbot_dynamics.identification.measurements import preprocess, read_joint_samples
from youbot_dynamics.model.robot import load_robot

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
    assert excitation.condition < 0.5 * excitation.initial_condition   # measured 2150 -> 154
    # against random Fourier trajectories of the same period and harmonics, in the same limits
    randoms = [condition_number(layout, base, random_fourier(layout, 10.0, 3, LIMITS, np.random.default_rng(s)))
               for s in range(1, 6)]
    assert excitation.condition < 0.5 * min(randoms), (excitation.condition, randoms)   # measured 154 vs 4017..24839


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


def test_projection_finds_consistent_parameters_for_a_physical_robot(layout, base, truth_robot):
    """Base values of a physical robot (the perturbed youBot) admit consistent standard
    parameters; the minimum-norm ones from the nominal URDF do not, so the projection works."""
    from youbot_dynamics.identification.consistency import nearest_consistent, pseudo_inertia_eigenvalues
    values = base.of(layout_for(truth_robot).standard_parameters())
    projection = nearest_consistent(layout, base, values, layout.standard_parameters())
    assert min(pseudo_inertia_eigenvalues(layout, projection.start).values()) < 0   # measured -1.7e-3
    assert projection.success, projection.message
    assert projection.base_error < 1e-9                                             # measured 1e-16
    assert min(pseudo_inertia_eigenvalues(layout, projection.theta).values()) >= 0.999e-6   # margin 1e-6


def test_cli_write_urdf_keeps_the_base_parameters_with_consistent_bodies(excitation, truth_robot, layout, base,
                                                                          tmp_path, capsys):
    """A quiet bag (1e-4 N m noise) of the perturbed youBot: base values near a physical set."""
    bag, out = tmp_path / "quiet.mcap", tmp_path / "identified.urdf"
    synthetic.record_joint_states(bag, truth_robot, excitation.trajectory, 20.0, RATE, 1e-4,
                                  np.random.default_rng(15))
    assert main(["identify", str(bag), "--json"]) == 0
    estimate = np.array([p["value"] for p in json.loads(capsys.readouterr().out)["wls"]["parameters"]])
    assert main(["identify", str(bag), "--write-urdf", str(out)]) == 0
    assert "projection moved the standard parameters per body" in capsys.readouterr().out
    text = out.read_text()
    assert f"identify from {bag}" in text and "cond(W)" in text and "Torque offsets" in text
    reloaded = layout_for(load_robot(out))
    theta = reloaded.standard_parameters()
    written = np.array(["offset" not in name for name in base.names])[base.independent]  # offsets: no URDF field
    # measured 4.7e-13 (12 significant digits in the file); bound 1e-9
    np.testing.assert_allclose(base.of(theta)[written], estimate[written], atol=1e-9)
    from youbot_dynamics.identification.consistency import pseudo_inertia_eigenvalues
    # the projection's margin is 1e-6 kg m^2; measured 1.0e-6 after the round trip through text
    assert min(pseudo_inertia_eigenvalues(reloaded, theta).values()) > 0.9e-6


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
