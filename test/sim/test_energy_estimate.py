"""The energy ledger's cheaper form of the stored energy (sim/divergence.py, body_energy):
the energy the ledger checks (the mass-matrix form) but for rounding, and the ledger's verdict
with it is the exact value's, at the tolerance's edge too; with an armature the two part, so
the engine does not use it there."""
from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.dynamics.rigid_body import kinetic_energy, potential_energy
from youbot_dynamics.model.robot import load_robot
from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.sim.divergence import body_energy, energy_ledger_monitor, estimate_margin
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.simulator import Simulator


@pytest.fixture(scope="module")
def swing():
    """arm_swing's plant (the youBot arm, no armature) and its states over the 2 s swing."""
    simulator = Simulator(load_scene("arm_swing"))
    return simulator.model, simulator.run().x


def exact(robot, data, q, v) -> float:
    return kinetic_energy(robot, data, q, v) + potential_energy(robot, data, q)


def test_the_body_energy_is_the_mass_matrix_energy_but_for_rounding(swing):
    # measured: apart by at most 1.8e-14 J, 1.2e-15 of the size (up to 15 J); bound 1e-12 of it
    model, states = swing
    robot, data = model.plant, model.plant.model.createData()
    for x in states[::10]:
        q, v = model.configuration(x), model.velocity(x)
        energy, kinetic, potential = body_energy(robot, data, q, v)
        assert abs(energy - exact(robot, data, q, v)) <= 1e-12 * (kinetic + abs(potential))


def test_with_an_armature_the_two_forms_part(swing):
    # why the engine leaves the estimate out for a plant with armature: Pinocchio 4.1's kinetic
    # energy leaves out the armature of arm_joint_1 (RevoluteUnaligned) and counts the others'
    model, states = swing
    armed = pin.Model(model.plant.model)
    armed.armature = np.full(model.plant.nv, 0.1)
    robot = dataclasses.replace(model.plant, model=armed)
    data = armed.createData()
    apart = [exact(robot, data, model.configuration(x), model.velocity(x))
             - body_energy(robot, data, model.configuration(x), model.velocity(x))[0] for x in states[::10]]
    assert max(apart) > 1e-3


@pytest.mark.parametrize("edge", [-1e-9, -1e-14, 0.0, 1e-14, 1e-9])
def test_the_ledger_with_the_estimate_says_what_the_exact_ledger_says(swing, edge):
    # the tolerance put at each state's exact growth (+- a hair): the ledger must fall back on
    # the exact value there, so both complain at the same states, word for word; far below
    # the tolerance the exact value is not computed
    model, states = swing
    robot, data = model.plant, model.plant.model.createData()
    calls = []

    def energy(x):
        calls.append(1)
        return exact(robot, data, model.configuration(x), model.velocity(x))

    def estimate(x):
        return body_energy(robot, data, model.configuration(x), model.velocity(x))

    energy0 = energy(states[0]) - 1.0  # every state "grew" by about 1 J
    for x in states[::25]:
        tolerance = energy(x) - energy0 + edge
        assert energy_ledger_monitor(energy, energy0, tolerance, estimate)(0.0, x) == \
            energy_ledger_monitor(energy, energy0, tolerance)(0.0, x)
        far = tolerance + 2 * estimate_margin(*estimate(x)[1:], energy0)
        calls.clear()
        assert energy_ledger_monitor(energy, energy0, far, estimate)(0.0, x) is None
        assert not calls


COAXIAL = """<robot name="coaxial">
  <link name="base"/>
  <link name="a"><inertial><mass value="1e-6"/><inertia ixx="1e-10" iyy="1e-10" izz="1e-10" ixy="0" ixz="0" iyz="0"/>
  </inertial></link>
  <link name="b"><inertial><mass value="10"/><inertia ixx="100" iyy="100" izz="100" ixy="0" ixz="0" iyz="0"/>
  </inertial></link>
  <joint name="j1" type="continuous"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit effort="10" velocity="5"/></joint>
  <joint name="j2" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit effort="10" velocity="5"/></joint>
</robot>"""


def test_an_ill_conditioned_mass_matrix_keeps_the_exact_verdict(tmp_path):
    """Two coaxial links of inertias 1e-10 and 100 kg m^2 spinning against each other (link b
    at rest in the world: T = I_a w^2 / 2 = 4.5e-4 J): the two forms part by 7.6e-6 of T (the
    mass-matrix form loses I_a to rounding), inside ESTIMATE_MARGIN (1e-4 of T, a factor 13);
    with the tolerance a hair above the exact growth the ledger still says what the exact
    ledger says (with the earlier margin, 1e-6 of T, it did not)."""
    path = tmp_path / "coaxial.urdf"
    path.write_text(COAXIAL)
    robot = load_robot(path)
    data = robot.model.createData()
    q, v = pin.neutral(robot.model), np.array([3e3, -3e3])
    exact_energy = exact(robot, data, q, v)
    energy, kinetic, _ = body_energy(robot, data, q, v)
    assert energy == pytest.approx(0.5 * 1e-10 * 3e3 ** 2, rel=1e-12)
    assert 1e-6 < abs(energy - exact_energy) / kinetic < 1e-5      # measured 7.6e-6
    for tolerance in (exact_energy * (1 - 1e-9), exact_energy * (1 + 1e-9), 4.50001e-4):
        with_estimate = energy_ledger_monitor(lambda x: exact_energy, 0.0, tolerance,
                                              lambda x: body_energy(robot, data, q, v))(0.0, v)
        assert with_estimate == energy_ledger_monitor(lambda x: exact_energy, 0.0, tolerance)(0.0, v)


@pytest.mark.parametrize("armature", [0.0, 0.1])
def test_the_engine_takes_the_exact_form_with_an_armature(swing, armature, monkeypatch):
    """The engine's ledger (engine._monitor) on arm_swing: without armature it asks the
    cheaper form first, with one it computes only the exact form (the two part there)."""
    model, states = swing
    armed = pin.Model(model.plant.model)
    armed.armature = np.full(model.plant.nv, armature)
    plant = dataclasses.replace(model.plant, model=armed)
    asked = []
    monkeypatch.setattr(engine, "body_energy", lambda *args: asked.append(1) or body_energy(*args))
    simulator = Simulator(dataclasses.replace(load_scene("arm_swing"), robot=plant).with_duration(0.05))
    simulator.run()
    assert bool(asked) == (armature == 0.0)
