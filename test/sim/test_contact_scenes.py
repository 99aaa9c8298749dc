"""The contact scenes against analytic references: bounce heights shrink by e^2
(compliant and impulsive laws, and the constraint stepper), a box on an incline sticks
below atan(mu) and slides at g (sin a - mu cos a) above it, momentum is conserved in a
collision of two free bodies; scene errors name the file and the pair; the CLI reports
contact events."""
from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from youbot_dynamics.cli import main
from youbot_dynamics.scene.schema import SceneError, load_scene, scene_dir
from youbot_dynamics.sim.simulator import Simulator

G = 9.81


def packaged(name: str) -> dict:
    return yaml.safe_load((scene_dir() / f"{name}.yaml").read_text())


def write(tmp_path, data: dict, name: str = "variant"):
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def bounce_heights(simulator: Simulator, result, radius: float) -> np.ndarray:
    """Apex heights of the bottom of the ball over the floor, one per flight, from the
    ballistic energy z - r + vz^2 / 2g at the output sample in the middle of each flight."""
    times = [e.time for e in result.contact_events if e.kind in ("impact", "separation")]
    motion = simulator.model.body_motion(result.x)
    z, vz = motion["position"][:, 0, 2], motion["velocity"][:, 0, 2]
    heights = []
    for start, end in zip(times[:-1], times[1:]):
        i = int(np.argmin(np.abs(result.t - 0.5 * (start + end))))
        heights.append(z[i] - radius + vz[i] ** 2 / (2 * G))
    return np.array(heights)


def test_ball_drop_compliant_bounce_ratio_is_e_squared():
    simulator = Simulator(load_scene("ball_drop"))
    result = simulator.run()
    e = simulator.scene.contacts[0].law.restitution
    heights = bounce_heights(simulator, result, 0.025)
    assert len(heights) >= 3
    assert heights[1:] / heights[:-1] == pytest.approx(e ** 2, rel=0.01)
    first = 1.0 * e ** 2
    assert heights[0] == pytest.approx(first, rel=0.01)
    assert 1e-4 < result.max_penetration < 3e-3
    assert [ev.kind for ev in result.contact_events[:3]] == ["touch", "compression", "separation"]
    touch, separation = result.contact_events[0], result.contact_events[2]
    assert separation.value / touch.value == pytest.approx(e, rel=1e-3)


def test_ball_drop_impulsive_bounce_ratio_is_e_squared(tmp_path):
    data = packaged("ball_drop")
    data["contacts"][0] = {"pair": ["floor", "ball"], "law": "newton", "restitution": 0.8, "friction": 0.3}
    simulator = Simulator(load_scene(write(tmp_path, data)))
    result = simulator.run()
    impacts = [ev for ev in result.contact_events if ev.kind == "impact"]
    assert len(impacts) == 4
    assert impacts[0].value == pytest.approx(simulator.scene.free_bodies[0].body.mass * 1.8 * np.sqrt(2 * G), rel=1e-6)
    heights = bounce_heights(simulator, result, 0.025)
    assert heights / np.concatenate([[1.0], heights[:-1]]) == pytest.approx(0.64, rel=1e-6)


def test_ball_drop_impulsive_law_refuses_resting_contact(tmp_path):
    data = packaged("ball_drop")
    data["contacts"][0] = {"pair": ["floor", "ball"], "law": "newton", "restitution": 0.5, "friction": 0.3}
    data["duration"] = 3.0
    with pytest.raises(Exception, match="rest_speed"):
        Simulator(load_scene(write(tmp_path, data))).run()


def incline(angle: float, law: dict, method: dict, duration: float = 1.0) -> dict:
    data = packaged("box_slide")
    normal = [float(np.sin(angle)), 0.0, float(np.cos(angle))]
    data["world"][0]["shape"]["normal"] = normal
    data["free_bodies"][0]["position"] = [0.05 * c for c in normal]
    data["free_bodies"][0]["orientation"] = [0.0, float(np.sin(angle / 2)), 0.0, float(np.cos(angle / 2))]
    data["contacts"][0] = {"pair": ["incline", "box"], **law}
    data["integrator"], data["duration"] = method, duration
    return data


def slope_motion(simulator: Simulator, result, angle: float) -> np.ndarray:
    p = simulator.model.body_motion(result.x)["position"][:, 0]
    return (p - p[0]) @ np.array([np.cos(angle), 0.0, -np.sin(angle)])


@pytest.mark.parametrize("solver", ["pgs", "admm"])
def test_box_slides_at_g_sin_minus_mu_cos_above_atan_mu(solver):
    scene = load_scene("box_slide").with_integrator(solver, dt=1e-3)
    simulator = Simulator(scene)
    result = simulator.run()
    s = slope_motion(simulator, result, 0.4)
    acceleration = 2 * np.polyfit(result.t, s, 2)[0]
    assert acceleration == pytest.approx(G * (np.sin(0.4) - 0.3 * np.cos(0.4)), rel=0.01)
    assert result.max_penetration < 1e-4


def test_box_sticks_below_atan_mu(tmp_path):
    angle = 0.25                                     # atan(0.3) = 0.2915
    data = incline(angle, {"law": "constraint", "restitution": 0.0, "friction": 0.3},
                   {"method": "pgs", "dt": 1e-3})
    simulator = Simulator(load_scene(write(tmp_path, data)))
    result = simulator.run()
    assert np.max(np.abs(slope_motion(simulator, result, angle))) < 1e-6
    # just above the limit it slides
    data = incline(0.30, {"law": "constraint", "restitution": 0.0, "friction": 0.3}, {"method": "pgs", "dt": 1e-3})
    simulator = Simulator(load_scene(write(tmp_path, data)))
    result = simulator.run()
    s = slope_motion(simulator, result, 0.30)
    assert 2 * np.polyfit(result.t, s, 2)[0] == pytest.approx(G * (np.sin(0.3) - 0.3 * np.cos(0.3)), rel=0.01)


def two_balls(law: dict, gravity=(0.0, 0.0, 0.0)) -> dict:
    ball = {"shape": {"type": "sphere", "radius": 0.05}, "density": 700}
    return {"name": "collision", "robot": "none", "gravity": list(gravity),
            "free_bodies": [{"name": "a", **ball, "position": [0, 0, 0], "velocity": [1.0, 0.2, 0]},
                            {"name": "b", "shape": {"type": "sphere", "radius": 0.05}, "density": 2100,
                             "position": [0.3, 0.01, 0], "velocity": [-0.5, 0, 0]}],
            "contacts": [{"pair": ["a", "b"], **law}],
            "integrator": {"method": "rk45", "rtol": 1e-9, "atol": 1e-12}, "duration": 0.5,
            "outputs": {"rate": 100, "record": ["q"]}}


@pytest.mark.parametrize("law", [
    {"law": "newton", "restitution": 0.5, "friction": 0.4},
    {"law": "hunt_crossley", "stiffness": 1e6, "restitution": 0.5, "friction": 0.4},
])
def test_collision_of_two_bodies_conserves_momentum(tmp_path, law):
    simulator = Simulator(load_scene(write(tmp_path, two_balls(law))))
    result = simulator.run()
    bodies = [spec.body for spec in simulator.scene.free_bodies]
    motion = simulator.model.body_motion(result.x)
    u, w, p = motion["velocity"], motion["angular_velocity"], motion["position"]
    masses = np.array([b.mass for b in bodies])
    linear = np.einsum("k,tki->ti", masses, u)
    assert np.abs(linear - linear[0]).max() < 1e-8 * masses.sum()
    angular = np.cross(p, masses[None, :, None] * u).sum(axis=1) + \
        np.einsum("kij,tkj->ti", np.array([b.inertia for b in bodies]), w)
    assert np.abs(angular - angular[0]).max() < 1e-8
    # the impact normal from the straight-line approach: |d0 + du t| = r_a + r_b
    d0, du = p[0, 1] - p[0, 0], u[0, 1] - u[0, 0]
    a, b, c = du @ du, 2 * d0 @ du, d0 @ d0 - 0.1 ** 2
    t_contact = (-b - np.sqrt(b * b - 4 * a * c)) / (2 * a)
    normal = (d0 + du * t_contact) / 0.1
    approach = du @ normal
    # a glancing impact with friction: the normal relative velocity is reversed by e
    assert (u[-1, 1] - u[-1, 0]) @ normal == pytest.approx(-0.5 * approach, rel=0.02)


@pytest.mark.parametrize("mutate, words", [
    (lambda d: d["contacts"][0].update(law="velcro"), "unknown contact law 'velcro'"),
    (lambda d: d["contacts"][0].pop("stiffness"), "missing parameter(s) stiffness"),
    (lambda d: d["contacts"][0].update(pair=["floor", "moon"]), "expected two geometry"),
    (lambda d: d["integrator"].update(method="pgs", dt=1e-3), "constraint stepper"),
])
def test_scene_errors_name_the_file_and_the_pair(tmp_path, mutate, words):
    data = packaged("ball_drop")
    mutate(data)
    path = write(tmp_path, data)
    with pytest.raises(SceneError) as error:
        load_scene(path)
    assert str(path) in str(error.value) and words in str(error.value)
    assert error.value.key.startswith("contacts") or error.value.key.startswith("integrator")


@pytest.mark.parametrize("mutate, key", [
    (lambda d: d["world"].append({"name": "floor", "shape": {"type": "sphere", "radius": 0.1}}), "world[1].name"),
    (lambda d: d["world"].append({"name": "ball", "shape": {"type": "sphere", "radius": 0.1}}), "world[1].name"),
    (lambda d: d["free_bodies"].append(dict(d["free_bodies"][0])), "free_bodies[1].name"),
])
def test_a_name_used_twice_is_reported_where_it_is_declared_again(tmp_path, mutate, key):
    data = packaged("ball_drop")
    mutate(data)
    with pytest.raises(SceneError, match="name already used by") as error:
        load_scene(write(tmp_path, data))
    assert error.value.key == key


@pytest.mark.parametrize("urdf, words", [(None, "missing"), ("nowhere.urdf", "file not found"),
                                         ("broken.urdf", "not valid XML")])
def test_a_composed_robot_file_that_cannot_be_read_names_its_key(tmp_path, urdf, words):
    (tmp_path / "broken.urdf").write_text("<robot name='x'><link name='a'></robot>")
    data = packaged("ball_drop")
    data["robot"] = {"compose": [{"prefix": "a_"} if urdf is None else {"urdf": urdf, "prefix": "a_"}]}
    with pytest.raises(SceneError, match=words) as error:
        load_scene(write(tmp_path, data))
    assert error.value.key == "robot.compose[0].urdf"


def test_constraint_law_needs_the_stepper(tmp_path):
    data = packaged("box_slide")
    data["integrator"] = {"method": "rk45"}
    with pytest.raises(SceneError, match="incline/box") as error:
        load_scene(write(tmp_path, data))
    assert error.value.key == "integrator.method"


def test_simulate_json_reports_contact_events(capsys):
    assert main(["simulate", "--scene", "ball_drop", "--duration", "1.3", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    kinds = [(e["pair"], e["kind"]) for e in report["contact_events"]]
    assert kinds[:6] == [("floor/ball", "touch"), ("floor/ball", "compression"), ("floor/ball", "separation")] * 2
    first = report["contact_events"][0]
    assert first["time"] == pytest.approx(np.sqrt(2 / G), rel=1e-6)
    assert first["value"] == pytest.approx(np.sqrt(2 * G), rel=1e-6)
    assert report["final_state"]["pose[ball.z]"] > 0.025 and report["max_penetration"] > 0


def test_grasp_at_the_friction_cone_limit_creeps_or_slips_as_coulomb_predicts(capsys):
    assert main(["contact-extremes", "--table", "grasp", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["grasp"]
    v_s = 1e-3
    for row, s in zip(rows, (0.9, 0.99, 1.01, 1.1)):
        assert row["status"] == "ok"
        if s < 1:   # held: creeps at the regularised law's v_s s / sqrt(1 - s^2)
            assert row["held"] and row["sink_speed_m_s"] == pytest.approx(v_s * s / np.sqrt(1 - s * s), rel=0.01)
        else:       # slips: m a = m g - 2 mu N
            assert not row["held"]
    assert rows[-1]["measured_accel_m_s2"] == pytest.approx(G * (1 - 1 / 1.1), rel=0.01)


def test_light_body_on_heavy_one_stays_put_with_the_constraint_stepper():
    from youbot_dynamics.accuracy.contact_extremes import light_on_heavy
    for row in light_on_heavy():
        assert row["status"] == "ok"
        if row["integrator"].startswith("constraint"):
            assert row["light_drift_m"] < 1e-6 and row["max_penetration_m"] < 1e-6
        else:   # compliant: settles by the static deflection (98 N on k = 1e6: (98 / 1e6)^(2/3) = 2.1 mm)
            assert row["heavy_drift_m"] == pytest.approx((10 * G / 1e6) ** (2 / 3), rel=0.05)


def test_stepwise_constraint_stepping_counts_each_contact_event_once():
    """The node advances sample block by sample block: the summed statistics must count a
    contact event once, as one whole run does."""
    scene = load_scene("box_slide").with_integrator("pgs", dt=1e-3)
    whole = Simulator(scene).run()
    simulator = Simulator(scene)
    simulator.reset()
    for block in np.array_split(scene.output_times[1:], 10):
        simulator.advance_through(block)
    assert len(whole.contact_events) >= 1
    assert simulator.stats.events == whole.stats.events == len(whole.contact_events)
    assert simulator.stats.rhs_evals == simulator.stats.steps and simulator.stats.jac_evals is None


def test_first_bounce_of_the_stiffness_sweep_reaches_e_squared_of_the_drop():
    """contact-extremes' bounce figures on the packaged ball_drop (1 m, e = 0.8, exact
    Hunt-Crossley damping): apex e^2 x 1 m, no energy gained at the impact."""
    from youbot_dynamics.accuracy.contact_extremes import (ball_drop_data, first_bounce,
                                                           integrator_of, run_case)

    law = {"law": "hunt_crossley", "stiffness": 1e7, "restitution": 0.8, "friction": 0.3}
    simulator, result, status, _ = run_case(ball_drop_data(law, integrator_of("rk45", None), 1.1))
    assert status == "ok"
    bounce = first_bounce(simulator, result, 0.8)
    assert bounce["apex_m"] == pytest.approx(0.64, rel=2e-3)
    assert abs(bounce["energy_gain_J"]) < 1e-3 * simulator.scene.free_bodies[0].body.mass * G
