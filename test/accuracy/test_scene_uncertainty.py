"""``value ± sigma`` scene parameters and their propagation (accuracy/scene_uncertainty.py):
the reader keeps the value and records the parameter; the seed's damped pendulum as a scene
(config/scenes/uncertain_pendulum.yaml: a one-joint URDF, uncertain mass and damping) against
studies/uncertain_pendulum.py, an independent implementation (the same pendulum as equations,
RK4 at h = 0.01 s, linear propagation by the ``uncertainties`` package's derivatives)."""
from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest

from youbot_dynamics.accuracy import scene_uncertainty
from youbot_dynamics.cli import main
from youbot_dynamics.scene.reader import SceneError
from youbot_dynamics.scene.schema import Scene, load_scene
from youbot_dynamics.studies import uncertain_pendulum

PENDULUM = "uncertain_pendulum"
MASS, DAMPING = "robot.compose[0].inertials.bob.mass", "friction.joints.pivot.damping"
T_END = 3.0
BALL = {"robot": "none", "free_bodies": [{"name": "ball", "shape": {"type": "sphere", "radius": 0.05},
                                          "mass": "0.2 +- 0.01", "inertia": [1e-4, 1e-4, 1e-4],
                                          "position": [0, 0, "1.0 ± 0.1"]}],
        "world": [{"name": "floor", "shape": {"type": "halfspace", "normal": [0, 0, 1]}}],
        "contacts": [{"pair": ["ball", "floor"], "law": "hunt_crossley", "stiffness": 1e6,
                      "restitution": "0.8 ± 0.05", "friction": 0.3}]}


def test_uncertain_numbers_read_as_their_value_and_are_recorded():
    scene = Scene.from_dict(BALL)
    assert dict(scene.uncertain) == {"free_bodies[0].position[2]": (1.0, 0.1), "free_bodies[0].mass": (0.2, 0.01),
                                     "contacts[0].restitution": (0.8, 0.05)}
    assert scene.free_bodies[0].position[2] == 1.0 and scene.free_bodies[0].body.mass == 0.2
    assert scene.contacts[0].law.restitution == 0.8
    sample = Scene.from_dict(BALL, values={"contacts[0].restitution": 0.7, "free_bodies[0].mass": 0.25})
    assert sample.contacts[0].law.restitution == 0.7 and sample.free_bodies[0].body.mass == 0.25
    assert sample.uncertain == scene.uncertain
    pendulum = load_scene(PENDULUM)
    assert dict(pendulum.uncertain) == {MASS: (1.0, 0.2), DAMPING: (0.5, 0.2)}


@pytest.mark.parametrize("text", ["1 ± x", "± 0.2", "1 ± 0", "1 +- -0.2", "1 ± 0.2 ± 0.1", "nan ± 1"])
def test_a_malformed_uncertain_number_names_its_key(text):
    data = {**BALL, "free_bodies": [{**BALL["free_bodies"][0], "mass": text}]}
    with pytest.raises(SceneError, match=r"<dict>: free_bodies\[0\]\.mass: expected 'value ± sigma' .*sigma > 0 "
                                         rf"\(got '{re.escape(text)}'\)"):
        Scene.from_dict(data)


def test_a_value_for_a_certain_key_is_refused():
    with pytest.raises(SceneError, match=r"free_bodies\[0\]\.inertia\[0\]: not an uncertain parameter of the scene "
                                         r"\(uncertain: free_bodies\[0\]\.mass, "):
        Scene.from_dict(BALL, values={"free_bodies[0].inertia[0]": 1.0})


def test_a_sample_the_validator_refuses_is_drawn_again(tmp_path):
    """Damping 0.1 ± 0.2 draws a negative damping one time in three; the scene refuses it
    (friction must be >= 0), so every sample kept is >= 0, and the draws are seeded."""
    source = scene_uncertainty.find_scene(PENDULUM)
    path = tmp_path / "pendulum.yaml"
    path.write_text(source.read_text(encoding="utf-8").replace('"0.5 ± 0.2"', '"0.1 ± 0.2"').replace(
        "uncertain_pendulum.urdf", str(source.parent / "uncertain_pendulum.urdf")), encoding="utf-8")
    keys, samples = scene_uncertainty.parameter_samples(path, 30, seed=3)
    assert keys == (MASS, DAMPING)
    assert np.all(samples[:, 1] >= 0) and np.all(samples[:, 0] > 0)
    assert np.array_equal(samples, scene_uncertainty.parameter_samples(path, 30, seed=3)[1])
    first = np.random.default_rng(3).normal([1.0, 0.1], [0.2, 0.2], size=(30, 2))
    assert np.sum(first[:, 1] < 0) >= 5     # so redrawing did happen (measured 9 of 30)


def pendulum_reference(samples: np.ndarray | None = None):
    """studies/uncertain_pendulum.py with L fixed at 0.8 m (sigma 0)."""
    parameters = {"L": (0.8, 0.0), "m": (1.0, 0.2), "d": (0.5, 0.2)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)   # uncertainties warns of the zero sigma
        linear = uncertain_pendulum.linear_propagation(T_END, parameters)
    if samples is None:
        return linear
    return linear, uncertain_pendulum.sample_traces(np.column_stack([np.full(len(samples), 0.8), samples]), T_END)


def test_linear_band_of_the_pendulum_scene_meets_the_uncertainties_package():
    """The scene's band (central differences of rk45 runs at tol 1e-10) against the
    uncertainties package through the equations' RK4: measured 1.3e-6 rad apart (sigma
    up to 0.24 rad over 3 s), the nominal runs 4.7e-8 rad (RK4's own error at h = 0.01 s);
    bounds 1e-5 and 1e-6 rad."""
    linear, sensitivities = scene_uncertainty.linear_propagation(PENDULUM, "q[pivot]", T_END)
    reference = pendulum_reference()
    np.testing.assert_allclose(linear.t, reference.t, atol=1e-12)
    assert np.abs(linear.mean - reference.mean).max() < 1e-6
    assert np.abs(linear.sigma - reference.sigma).max() < 1e-5
    assert reference.sigma.max() > 0.2
    assert sensitivities.shape == (2, len(linear.t))


def test_monte_carlo_samples_of_the_scene_meet_the_equations():
    """Each Monte Carlo run of the scene against the equations' RK4 with the same
    parameters (measured 6.2e-8 rad apart, bound 1e-6)."""
    sampled, keys, samples, traces = scene_uncertainty.monte_carlo(PENDULUM, "q[pivot]", 6, seed=1,
                                                                   duration=T_END)
    assert keys == (MASS, DAMPING) and traces.shape == (len(sampled.t), 6)
    _, reference = pendulum_reference(samples)
    assert np.abs(traces - reference).max() < 1e-6
    np.testing.assert_allclose(sampled.sigma, reference.std(axis=1, ddof=1), atol=1e-6)


def test_scene_uncertainty_command(capsys, tmp_path):
    plot = tmp_path / "band.png"
    assert main(["scene-uncertainty", PENDULUM, "--output", "v[pivot]", "--samples", "3", "--duration", "0.5",
                 "--workers", "0", "--json", "--plot", str(plot)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["parameters"] == [MASS, DAMPING] and report["t_end"] == 0.5
    assert report["band_width_linear_end"] == pytest.approx(2 * report["sigma_linear_end"])
    assert plot.stat().st_size > 10_000
    assert main(["scene-uncertainty", PENDULUM, "--output", "q[elbow]", "--workers", "0"]) == 2
    assert "--output 'q[elbow]' is no state component; components: q[pivot], v[pivot]" in capsys.readouterr().err
