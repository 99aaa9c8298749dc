"""The one engine: one plant, one contact model for every law, a copyable state, free
functions, and a Python controller at a control rate."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yaml

from youbot_dynamics.dynamics.contact_model import ContactModel
from youbot_dynamics.scene.schema import Scene, load_scene, scene_dir
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim.controllers import Reference
from youbot_dynamics.sim.simulator import Simulator

LAWS = {
    "compliant": {"law": "hunt_crossley", "stiffness": 1e7, "exponent": 1.5, "restitution": 0.8,
                  "friction": 0.3, "velocity_scale": 1e-3},
    "impulsive": {"law": "newton", "restitution": 0.8, "friction": 0.3},
    "stepper": {"law": "constraint", "restitution": 0.8, "friction": 0.3},
}
INTEGRATOR = {"compliant": {"method": "rk45", "rtol": 1e-8, "atol": 1e-10},
              "impulsive": {"method": "rk45", "rtol": 1e-8, "atol": 1e-10},
              "stepper": {"method": "pgs", "dt": 1e-3}}


def ball_drop(tmp_path, law: str):
    data = yaml.safe_load((scene_dir() / "ball_drop.yaml").read_text())
    data["contacts"] = [{"pair": ["floor", "ball"], **LAWS[law]}]
    data["integrator"], data["duration"] = INTEGRATOR[law], 0.6
    path = tmp_path / f"ball_{law}.yaml"
    path.write_text(yaml.safe_dump(data))
    return load_scene(path)


@pytest.mark.parametrize("law", sorted(LAWS))
def test_every_contact_law_reads_its_geometry_from_the_one_contact_model(tmp_path, law):
    model = compile(ball_drop(tmp_path, law))
    contact = model.contact
    assert isinstance(contact, ContactModel) and contact.model is model.plant.model
    if law == "stepper":
        assert model.stepper.contact is contact
    calls = []
    originals = {name: getattr(ContactModel, name) for name in ("poses", "placements", "touching")}  # all laws', the stepper's

    def spy(original):
        def spied(self, *args):
            calls.append(self)
            return original(self, *args)
        return spied

    for name, original in originals.items():
        setattr(ContactModel, name, spy(original))
    try:
        result = engine.run(model)
    finally:
        for name, original in originals.items():
            setattr(ContactModel, name, original)
    # the ball (1 m drop, first touch at sqrt(2/g) = 0.45 s) hit the floor, and every pose
    # query of the run went to this one object
    assert calls and all(c is contact for c in calls)
    assert result.contact_events and result.contact_events[0].time == pytest.approx(np.sqrt(2 / 9.81), abs=2e-3)


def test_free_bodies_are_free_flyers_of_the_plant():
    model = compile(load_scene("ball_drop"))
    plant = model.plant.model
    assert [plant.names[j] for j in range(1, plant.njoints)] == ["ball"]
    assert plant.joints[1].shortname() == "JointModelFreeFlyer"
    # the plant's mass matrix of the ball is diag(m, m, m, I): Pinocchio's free-flyer
    body = model.scene.free_bodies[0].body
    data = plant.createData()
    mass = pin.crba(plant, data, pin.neutral(plant))
    assert np.diag(mass)[:3] == pytest.approx([body.mass] * 3)
    assert np.diag(mass)[3:] == pytest.approx(np.diag(body.inertia))


def test_a_saved_state_runs_on_identically():
    simulator = Simulator(load_scene("arm_ptp"))
    simulator.advance_through([0.1, 0.2])
    saved = simulator.get_state()
    first = simulator.advance_through([0.3, 0.4])
    simulator.advance(0.5)
    simulator.set_state(saved)
    again = simulator.advance_through([0.3, 0.4])
    for a, b in zip(first, again):
        assert a.t == b.t and np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v)
    assert saved.t == pytest.approx(0.2)   # the saved copy did not move on


def test_reset_restores_the_scenes_reference_after_a_followed_trajectory():
    simulator = Simulator(load_scene("arm_ptp"))
    scene_reference = simulator.state.reference
    simulator.state.reference = Reference(simulator.q + 0.1)
    simulator.reset()
    assert simulator.state.reference is scene_reference


def test_python_controller_at_a_control_rate_holds_the_arm_against_gravity():
    """A gravity-compensation callback at 100 Hz: with the arm at rest, g(q) held over each
    control period is the exact holding torque, so the arm stays where it is; without it the
    arm falls (arm_swing)."""
    scene = load_scene("arm_swing").with_duration(0.5)
    robot = compile(scene).robot
    data = robot.model.createData()
    ticks = []

    def gravity_compensation(t, q, v):
        ticks.append(t)
        return pin.computeGeneralizedGravity(robot.model, data, q)

    model = compile(scene, controller=gravity_compensation, control_rate=100.0)
    at_rest = np.zeros(robot.nv)
    held = engine.run(model, engine.initial_state(model, v=at_rest))
    free_model = compile(scene)
    free = engine.run(free_model, engine.initial_state(free_model, v=at_rest))
    q = held.layout.slice("q")
    # measured drift 2.7e-11 rad at rtol 1e-9 (the scene's dop853); bound 1e-6 rad
    assert np.abs(held.x[:, q] - held.x[0, q]).max() < 1e-6
    assert np.abs(free.x[-1, q] - free.x[0, q]).max() > 0.1
    # asked once at t = 0 and at every tick up to the end: 0.01, 0.02, ..., 0.5 s
    assert ticks[0] == 0.0 and np.allclose(np.diff(ticks), 0.01) and len(ticks) == 51


def test_gripping_runs_with_the_compliant_law_and_with_pgs():
    """The same scene data, once with its constraint contacts (PGS) and once with compliant
    Hunt-Crossley pairs on an adaptive integrator: over 0.3 s the sphere rests on youBot 1's
    plate in both, the compliant one lower by the static Hertz deflection (m g / k)^(1/n)."""
    data = yaml.safe_load((scene_dir() / "gripping.yaml").read_text())
    data.update(duration=0.3, outputs={"rate": 100, "record": ["q"]})
    stiffness, exponent = 1e5, 1.5
    compliant = {**data, "integrator": {"method": "rk45", "tol": 1e-6},
                 "contacts": [{"pair": c["pair"], "law": "hunt_crossley", "stiffness": stiffness,
                               "exponent": exponent, "restitution": 0.6, "friction": 0.3,
                               "velocity_scale": 1e-3} for c in data["contacts"]]}
    final = {}
    for name, spec in (("pgs", data), ("compliant", compliant)):
        model = compile(Scene.from_dict(spec, source=f"gripping ({name})", base_dir=scene_dir()))
        result = engine.run(model)
        final[name] = model.body_motion(result.x[-1])["position"][0, 0]
    mass = next(b.body.mass for b in load_scene("gripping").free_bodies if b.body.name == "sphere")
    hertz = (mass * 9.81 / stiffness) ** (1.0 / exponent)   # 2.7234e-4 m
    # measured: x, y equal to the last digit; z lower by 2.7234e-4 m (Hertz 2.7234e-4): bound 2 %
    assert final["compliant"][:2] == pytest.approx(final["pgs"][:2], abs=1e-6)
    assert final["pgs"][2] - final["compliant"][2] == pytest.approx(hertz, rel=0.02)


def test_the_recorded_torque_is_what_the_python_controller_applied():
    """Outputs at 50 Hz, a controller at 20 Hz returning its call count: each output
    records the torque held since the last tick (ticks at 0, 0.05, 0.1, 0.15 s)."""
    scene = load_scene("arm_ptp").with_duration(0.2)
    assert "tau" in scene.outputs.record
    calls = []

    def counting(t, q, v):
        calls.append(t)
        return np.full(len(q), 0.1 * len(calls))

    result = engine.run(compile(scene, controller=counting, control_rate=20.0))
    assert calls == pytest.approx([0.0, 0.05, 0.1, 0.15, 0.2])
    held = [0.1 * (1 + int(t / 0.05 + 1e-9)) for t in result.t]
    assert result.series["tau"][:, 0] == pytest.approx(held)
