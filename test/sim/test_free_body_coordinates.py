"""A free body's rotation coordinates in a scene (``rotation_coordinates: chart | quaternion |
cardan_adaptive``): each against the closed form of the torque-free axisymmetric top
(studies/rotations.py, an independent formula), thrown in free fall so that gravity moves the
centre of mass ballistically and leaves the attitude alone; the tumble through the x-y-z
sequence's gimbal lock (the adaptive sequence switches, the fixed one of the rotations study
crawls); the default chart unchanged; the constraint stepper's refusal."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.model.lie import quaternion_from_matrix
from youbot_dynamics.model.rotations import SWITCH_ANGLE
from youbot_dynamics.scene.reader import SceneError
from youbot_dynamics.scene.schema import Scene
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.build import compile
from youbot_dynamics.studies.rotations import (RUNS, attitude_error, axisymmetric_top,
                                               simulate_rotation)

COORDINATES = ("chart", "quaternion", "cardan_adaptive")
TOL = 1e-8
GRAVITY = np.array([0.0, 0.0, -9.81])
VELOCITY = np.array([0.3, -0.2, 4.0])   # m/s, world: thrown up


def top_scene(run_name: str, coordinates: str, gravity=GRAVITY, velocity=VELOCITY) -> Scene:
    """The rotations study's run as a free body of a scene: inertia, R0 and the body rate w0
    (given to the scene as the world-frame R0 w0), thrown with ``velocity`` (m/s)."""
    run = RUNS[run_name]
    body = {"name": "top", "shape": {"type": "sphere", "radius": 0.1}, "mass": 2.0, "inertia": list(run.inertia),
            "position": [0.0, 0.0, 1.0], "orientation": quaternion_from_matrix(run.rotation0).tolist(),
            "velocity": list(velocity), "angular_velocity": (run.rotation0 @ np.array(run.w0)).tolist(),
            "rotation_coordinates": coordinates}
    return Scene.from_dict({"robot": "none", "gravity": list(gravity), "free_bodies": [body],
                            "integrator": {"method": "rk45", "rtol": TOL, "atol": TOL},
                            "duration": run.t_end, "outputs": {"rate": 20, "record": ["q"]}})


def closed_form_errors(run_name: str, result, model) -> tuple[float, float, float]:
    """Largest attitude error (rad), body-rate error (rad/s) and centre-of-mass error (m)
    against the closed-form top and the ballistic parabola."""
    run = RUNS[run_name]
    motion = model.body_motion(result.x)
    rotations, omega = motion["rotation"][:, 0], motion["angular_velocity"][:, 0]
    references, rates = axisymmetric_top(np.array(run.inertia), run.rotation0, np.array(run.w0), result.t)
    body_rates = np.einsum("kji,kj->ki", rotations, omega)
    t = result.t[:, None]
    parabola = np.array([0.0, 0.0, 1.0]) + VELOCITY * t + 0.5 * GRAVITY * t ** 2
    return (float(attitude_error(rotations, references).max()), float(np.abs(body_rates - rates).max()),
            float(np.abs(motion["position"][:, 0] - parabola).max()))


@pytest.mark.parametrize("coordinates", COORDINATES)
def test_each_coordinates_meet_the_closed_form_top_in_free_fall(coordinates):
    """rk45 at rtol = atol = 1e-8 over 10 s of the nutating top: measured attitude errors
    1.8e-8 (chart), 2.5e-8 (quaternion), 3.1e-8 (cardan_adaptive) rad, body-rate errors
    4.0e-8, 4.0e-8, 4.8e-8 rad/s; the bound, 30 tol, is the rotations study's
    (test_rotations.py), a margin of 6x. The centre of mass falls to z = -449 m on the
    parabola: measured 3.2e-6, 2.7e-6, 3.4e-6 m off, bound 1e-5 m."""
    model = compile(top_scene("top", coordinates))
    result = engine.run(model)
    attitude, rate, position = closed_form_errors("top", result, model)
    assert attitude < 30 * TOL and rate < 30 * TOL
    assert position < 1e-5
    assert result.conservative and result.energy_error < 1e-4   # J; measured 2.7e-5, 2.9e-5, 3.9e-5
    events = result.attitude_events
    if coordinates == "chart":   # the chart folds as it turns; the others never fold
        assert events["recentre"] > 10 and events["sequence"] == 0
    else:
        assert events["recentre"] == 0
    if coordinates == "quaternion":   # |q| drifts below the tolerance (measured 1.9e-9)
        assert 0.0 < result.quaternion_drift < 10 * TOL
        pose = result.x[:, model.block("pose")]
        np.testing.assert_allclose(np.linalg.norm(pose[:, 3:], axis=1), 1.0, atol=1e-15)  # projected at outputs
    else:
        assert result.quaternion_drift is None


def test_adaptive_cardan_switches_through_gimbal_lock_where_the_fixed_sequence_crawls():
    """The tumble (end over end, passing within 1e-4 rad of the x-y-z gimbal lock): in the
    scene the adaptive sequence switches to x-z-y once (whose middle angle then stays near
    0) and meets the closed form (measured 2.4e-7 rad at tol 1e-8, bound 1e-6 rad); the
    rotations study's fixed x-y-z sequence at the same tolerance takes many more steps
    (measured 466 against the scene's 46; bound 3x)."""
    model = compile(top_scene("tumble", "cardan_adaptive", gravity=(0.0, 0.0, 0.0), velocity=(0.0, 0.0, 0.0)))
    result = engine.run(model)
    assert result.attitude_events == {"recentre": 0, "sequence": 1}
    cardan = result.x[:, model.block("cardan")]
    assert np.abs(cardan[:, 1]).max() <= SWITCH_ANGLE + 1e-6
    assert cardan[-1, 3] == 1.0   # x-z-y
    run = RUNS["tumble"]
    motion = model.body_motion(result.x)
    references, _ = axisymmetric_top(np.array(run.inertia), run.rotation0, np.array(run.w0), result.t)
    assert attitude_error(motion["rotation"][:, 0], references).max() < 100 * TOL
    fixed = simulate_rotation(run, "cardan", tol=TOL)
    assert fixed.failure is not None or fixed.stats.steps > 3 * result.stats.steps


def test_quaternion_coordinates_pass_the_tumble():
    """Measured 8.6e-8 rad off the closed form, |q| drift 1.3e-7."""
    model = compile(top_scene("tumble", "quaternion", gravity=(0.0, 0.0, 0.0), velocity=(0.0, 0.0, 0.0)))
    result = engine.run(model)
    run = RUNS["tumble"]
    references, _ = axisymmetric_top(np.array(run.inertia), run.rotation0, np.array(run.w0), result.t)
    assert attitude_error(model.body_motion(result.x)["rotation"][:, 0], references).max() < 100 * TOL
    assert result.quaternion_drift < 100 * TOL


def test_chart_is_the_default_and_keeps_the_state_layout():
    """No key is ``chart``: the same layout as before the key existed (no ``cardan``
    block) and the same run, bit for bit, as ``chart`` written out (before/after this
    change the packaged free-body scenes' outputs hash the same: see the README)."""
    body = {"name": "top", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "inertia": [1, 1, 2],
            "angular_velocity": [0.5, 0.3, 3.0]}
    data = {"robot": "none", "gravity": [0, 0, 0], "duration": 1.0, "free_bodies": [body]}
    model = compile(Scene.from_dict(data))
    assert model.coordinates == ("chart",) and model.all_charts
    assert [block.symbol for block in model.layout.extra] == ["twist", "pose", "chart"]
    explicit = compile(Scene.from_dict({**data, "free_bodies": [{**body, "rotation_coordinates": "chart"}]}))
    assert np.array_equal(engine.run(model).x, engine.run(explicit).x)


def test_mixed_coordinates_in_one_scene_move_each_body_alike():
    """Three copies of the same thrown top side by side, one per coordinates: the same
    motion to the tolerance's order (measured 3e-8 rad)."""
    run = RUNS["top"]
    data = {"robot": "none", "gravity": GRAVITY.tolist(), "duration": 2.0,
            "integrator": {"method": "rk45", "rtol": TOL, "atol": TOL},
            "free_bodies": [{"name": f"top_{c}", "shape": {"type": "sphere", "radius": 0.1}, "mass": 2.0,
                             "inertia": list(run.inertia), "position": [3.0 * k, 0.0, 1.0],
                             "orientation": quaternion_from_matrix(run.rotation0).tolist(),
                             "velocity": VELOCITY.tolist(),
                             "angular_velocity": (run.rotation0 @ np.array(run.w0)).tolist(),
                             "rotation_coordinates": c}
                            for k, c in enumerate(COORDINATES)]}
    model = compile(Scene.from_dict(data))
    result = engine.run(model)
    motion = model.body_motion(result.x)
    for k in (1, 2):
        assert attitude_error(motion["rotation"][:, k], motion["rotation"][:, 0]).max() < 30 * TOL
        np.testing.assert_allclose(motion["position"][:, k] - [3.0 * k, 0, 0], motion["position"][:, 0], atol=1e-6)


def test_unknown_coordinates_and_the_constraint_stepper_name_the_key():
    data = {"robot": "none", "free_bodies": [{"name": "b", "shape": {"type": "sphere", "radius": 0.1},
                                              "mass": 1.0, "inertia": [1, 1, 1],
                                              "rotation_coordinates": "euler"}]}
    with pytest.raises(SceneError, match=r"free_bodies\[0\]\.rotation_coordinates: expected one of chart, "
                                         r"quaternion, cardan_adaptive \(got 'euler'\)"):
        Scene.from_dict(data)
    data["free_bodies"][0]["rotation_coordinates"] = "quaternion"
    data.update(world=[{"name": "floor", "shape": {"type": "halfspace", "normal": [0, 0, 1]}}],
                contacts=[{"pair": ["b", "floor"], "law": "constraint", "restitution": 0.0, "friction": 0.5}], integrator={"method": "pgs", "dt": 1e-3})
    with pytest.raises(SceneError, match=r"free_bodies\[0\]\.rotation_coordinates: the constraint stepper"):
        compile(Scene.from_dict(data))
