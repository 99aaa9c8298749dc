"""The generated scene of N youBots in a row (scene/row.py) against N single youBots loaded
by Pinocchio from the package's URDF: masses, joint counts, the grippers' placements, and
robots that move alike without touching each other's sphere."""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.scene.row import ARM, BASE_HEIGHT, FINGERS, SPACING, SPHERE, youbot_row, youbot_row_scene
from youbot_dynamics.sim.simulator import Simulator

SIZES = (1, 2, 4, 8)


@pytest.fixture(scope="module")
def single() -> pin.Model:
    return pin.buildModelFromUrdf(default_urdf())


@pytest.fixture(scope="module")
def scenes():
    return {n: youbot_row_scene(n, 1.0) for n in SIZES}


def all_mass(model: pin.Model) -> float:
    """kg of every body, those welded to the world (the universe's inertia) included."""
    return sum(inertia.mass for inertia in model.inertias)


@pytest.mark.parametrize("n", SIZES)
def test_the_composed_model_is_n_youbots(n, scenes, single):
    scene = scenes[n]
    full = pin.buildModelFromXML(scene.urdf)  # every joint, none locked
    assert all_mass(full) == pytest.approx(n * all_mass(single), rel=1e-12)
    assert pin.computeTotalMass(full) == pytest.approx(n * pin.computeTotalMass(single), rel=1e-12)
    assert full.njoints - 1 == n * (single.njoints - 1)
    assert full.nv == n * single.nv
    # the simulated robot: arm and fingers moving, wheels locked (Pinocchio's own reduction
    # of one youBot beside it); locking keeps every mass
    locked = [single.getJointId(name) for name in single.names[1:] if name not in ARM + FINGERS]
    one = pin.buildReducedModel(single, locked, pin.neutral(single))
    assert scene.robot.nv == n * one.nv == 7 * n
    assert pin.computeTotalMass(scene.robot.model) == pytest.approx(n * pin.computeTotalMass(one), rel=1e-12)
    assert all_mass(scene.robot.model) == pytest.approx(n * all_mass(single), rel=1e-12)
    assert len(scene.free_bodies) == n and len(scene.contacts) == 3 * n
    sphere = 700 * 4 / 3 * math.pi * 0.025 ** 3
    assert all(b.body.mass == pytest.approx(sphere, rel=1e-12) for b in scene.free_bodies)


@pytest.mark.parametrize("n", SIZES)
def test_every_gripper_stands_where_a_single_youbot_puts_it(n, scenes, single):
    """Robot i's palm at the scene's q0 = a single youBot's palm at the same joint values,
    moved by SPACING (i - 1) along x and BASE_HEIGHT up."""
    scene = scenes[n]
    model, data = scene.robot.model, scene.robot.model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model) if not len(scene.q0) else scene.q0)
    one_data, q = single.createData(), pin.neutral(single)
    for name, value in youbot_row(1)["initial"]["q"].items():
        q[single.joints[single.getJointId(name.removeprefix("yb1_"))].idx_q] = value
    pin.framesForwardKinematics(single, one_data, q)
    palm = one_data.oMf[single.getFrameId("gripper_palm_link")]
    for i in range(n):
        placed = data.oMf[model.getFrameId(f"yb{i + 1}_gripper_palm_link")]
        np.testing.assert_allclose(placed.rotation, palm.rotation, atol=1e-12)
        np.testing.assert_allclose(placed.translation, palm.translation + [SPACING * i, 0.0, BASE_HEIGHT],
                                   atol=1e-12)
        sphere = scene.free_bodies[i].position
        np.testing.assert_allclose(sphere, [SPACING * i + SPHERE[0], SPHERE[1], BASE_HEIGHT + SPHERE[2]], atol=1e-15)


def test_the_robots_move_alike_and_apart():
    """Two robots over the first 0.3 s (the gripper opening, the arm on its way): the same
    joint motion to rounding, each sphere resting on its own plate."""
    simulator = Simulator(youbot_row_scene(2, 0.3))
    result = simulator.run()
    q = result.x[:, :14]
    # measured: 9e-19 rad apart; bound 1e-9 rad (x86-64 rounding of one robot against the
    # other; a coupling through the contact solver would show at the 1e-6 level)
    np.testing.assert_allclose(q[:, :7], q[:, 7:], atol=1e-9)
    assert np.ptp(q[:, 5]) > 1e-3  # the fingers did move
    z = simulator.model.body_motion(result.x)["position"][:, :, 2]
    # measured: 0 m of motion (at rest on the plate); bound 1e-4 m, far below a fall (the plate's 0.01 m)
    np.testing.assert_allclose(z, BASE_HEIGHT + SPHERE[2], atol=1e-4)


@pytest.mark.parametrize("n", [0, -1, 2.0, True])
def test_a_row_needs_a_positive_whole_number_of_robots(n):
    with pytest.raises(ValueError, match="number of robots"):
        youbot_row(n)
