"""The applied joint effort and the simulated sensors against independent computations:
Pinocchio's RNEA at finite-difference accelerations, a static hand computation of the wrist
load, the kinematic base's imposed yaw rate and gravity."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from wrench_support import G, hand_masses, relative_error, sphere_mass, static_load
from youbot_dynamics.scene.reader import read_yaml
from youbot_dynamics.scene.schema import Scene, find_scene, load_scene
from youbot_dynamics.sim.simulator import Simulator



def _plant_state(model, snapshot) -> tuple[np.ndarray, np.ndarray]:
    """The plant's (q, v) of a moving-base snapshot: planar root (x, y, cos, sin; body twist)."""
    x, y, yaw, vx, vy, wz = snapshot.base
    return (np.concatenate([[x, y, np.cos(yaw), np.sin(yaw)], snapshot.q]),
            np.concatenate([[vx, vy, wz], snapshot.v]))


def test_kinematic_base_wheel_effort_is_the_torque_that_imposes_the_motion():
    """base_square (no contact, no friction): the wheels' effort equals RNEA's torque at
    the accelerations differenced from the motion (the wheels accelerate with the base)."""
    sim = Simulator(load_scene("base_square"))
    model, plant, delta = sim.model, sim.model.plant.model, 1e-4
    wheels = model.plant.root_nv + model.base.wheels
    checked = 0
    for t in (0.25, 0.4, 2.2):      # accelerating, then braking (the path switches at 0.5 and 2 s)
        before, now, after = sim.advance_through([t - delta, t, t + delta])
        (q, v), (_, v0), (_, v1) = (_plant_state(model, s) for s in (now, before, after))
        expected = pin.rnea(plant, plant.createData(), q, v, (v1 - v0) / (2 * delta))[wheels]
        assert np.abs(expected).max() > 1e-3        # the wheels do carry a torque here
        np.testing.assert_allclose(now.tau[model.base.wheels], expected, rtol=1e-4, atol=1e-6)
        checked += 1
    assert checked == 3


def test_fixed_base_effort_is_the_controller_torque_that_rnea_and_friction_need():
    """arm_ptp (no contact): /joint_states effort = M(q) a + h(q, v) + tau_friction(v)
    at the differenced accelerations."""
    scene = load_scene("arm_ptp")
    sim = Simulator(scene, scene.pinned_integrator())
    model = sim.model
    robot, delta = model.robot, 1e-4
    data = robot.model.createData()
    for t in (0.3, 0.6):
        before, now, after = sim.advance_through([t - delta, t, t + delta])
        a = (after.v - before.v) / (2 * delta)
        friction = model.friction.torque(now.v, now.z if now.z.size else None) if model.friction else 0.0
        expected = pin.rnea(robot.model, data, now.q, now.v, a) + friction
        np.testing.assert_allclose(now.tau, expected, rtol=1e-3, atol=1e-3 * np.abs(expected).max())


def _turning_square() -> Scene:
    path = find_scene("base_square")
    data = read_yaml(path.read_bytes(), str(path))
    data["base"]["path"]["waypoints"] = [[0.0, 0.0, 1.0], [0.5, 0.0, 1.0]]
    return Scene.from_dict(data, "turning_square", path.parent)


def test_imu_reads_gravity_at_rest_and_the_base_yaw_rate_while_turning():
    sim = Simulator(_turning_square())
    rest = sim.snapshot(sensors=True).sensors.imu
    np.testing.assert_allclose(rest[0], 0.0, atol=1e-12)
    np.testing.assert_allclose(rest[1], [0.0, 0.0, G], atol=1e-9)
    np.testing.assert_allclose(rest[2], [0.0, 0.0, 0.0, 1.0], atol=1e-12)
    snapshots = sim.advance_through(np.arange(1, 41) * 0.05, sensors=True)
    turning = [s for s in snapshots if abs(s.base[5]) > 0.1]
    assert turning
    for s in turning:
        angular, linear, quaternion = s.sensors.imu
        np.testing.assert_allclose(angular, [0.0, 0.0, s.base[5]], atol=1e-9)
        assert linear[2] == pytest.approx(G, abs=1e-9)
        yaw = 2 * np.arctan2(quaternion[2], quaternion[3])
        assert np.cos(yaw - s.base[2]) == pytest.approx(1.0, abs=1e-12)


def test_scenes_without_a_moving_base_or_a_palm_have_no_imu_or_wrist_sensor():
    grasp = Simulator(load_scene("grasp")).snapshot(sensors=True).sensors
    assert grasp.imu is None and grasp.wrist is None and set(grasp.pairs) == {"pad_l/sphere", "pad_r/sphere"}
    arm = Simulator(load_scene("arm_swing")).snapshot(sensors=True).sensors
    assert arm.imu is None and arm.wrist is not None and arm.pairs == {}



def test_wrist_wrench_of_the_hand_at_rest_is_its_weight_moved_to_the_palm():
    """gripping at t = 0 (arms and fingers at rest, gravity compensated): youBot 1's wrist
    reads the weight of its palm and both fingers pushed up, about the palm's origin, in its
    frame, to 1 % (a static hand computation from the URDF's masses)."""
    sim = Simulator(load_scene("gripping"))
    reading = sim.snapshot(sensors=True).sensors.wrist
    model, data = sim.model, sim.state.data
    plant = model.plant.model
    pin.framesForwardKinematics(plant, data, model.configuration(sim.state.x))
    palm = data.oMf[model.sensors.wrist.frame]
    assert model.sensors.wrist.link == "yb1_gripper_palm_link"
    expected = static_load(palm, hand_masses(plant, data, model.scene.urdf, "yb1_"))
    assert relative_error(reading, expected) <= 0.01, (reading, expected)

CANDLE = {"arm_joint_1": 2.9496, "arm_joint_2": 1.1345, "arm_joint_3": -2.5482, "arm_joint_4": 1.7890,
          "arm_joint_5": 2.9234}
SPHERE_RADIUS, WOOD = 0.025, 700.0


def _tray_scene(rpy=(0.0, 0.0, 0.0), xyz=(0.0, 0.0, 0.0), sphere=(0.0, 0.0, 1.0),
                pair=("tray", "sphere")) -> Scene:
    """The arm and the fingers locked in the candle pose (one wheel moves, unloaded), a level tray
    (10 x 10 x 1 cm box, placed at ``xyz``, ``rpy`` in the palm's frame) on the palm and a
    wooden sphere at ``sphere`` (world, m); constraint contact (PGS, 1 ms) of ``pair``."""
    return Scene.from_dict({
        "name": "tray", "moving": ["wheel_joint_fl"], "locked": CANDLE,
        "free_bodies": [{"name": "sphere", "shape": {"type": "sphere", "radius": SPHERE_RADIUS}, "density": WOOD,
                         "position": list(sphere)}],
        "geometry": [{"name": "tray", "link": "gripper_palm_link", "shape": {"type": "box", "size": [0.1, 0.1, 0.01]},
                      "pose": {"xyz": list(xyz), "rpy": list(rpy)}}],
        "contacts": [{"pair": list(pair), "law": "constraint", "restitution": 0.0, "friction": 0.5}],
        "integrator": {"method": "pgs", "dt": 1e-3}, "duration": 1.0}, "tray", find_scene("base_square").parent)


@pytest.mark.parametrize("pair", [("tray", "sphere"), ("sphere", "tray")])
def test_wrist_wrench_of_the_hand_holding_a_sphere_at_rest_is_their_weight_moved_to_the_palm(pair):
    """A dedicated static case: the sphere rests off-centre on a tray on the palm (arm locked).
    The wrist reads the weight of palm, fingers and sphere pushed up, about the palm's origin,
    in its frame, to 1 %, whichever way round the pair is declared; the pair's wrench is the
    sphere's weight, up, through its centre (on the tray: down, in the palm's frame)."""
    probe = Simulator(_tray_scene())
    model, data = probe.model, probe.state.data
    pin.framesForwardKinematics(model.plant.model, data, model.configuration(probe.state.x))
    palm = data.oMf[model.plant.model.getFrameId("gripper_palm_link", pin.BODY)]
    centre = palm.translation + [0.0, 0.0, 0.12]          # the tray 12 cm above the palm, level
    sim = Simulator(_tray_scene(pin.rpy.matrixToRpy(palm.rotation.T), palm.rotation.T @ (centre - palm.translation),
                                centre + [0.03, 0.01, 0.005 + SPHERE_RADIUS], pair))
    last = sim.advance_through(np.arange(1, 31) * 0.01, sensors=True)[-1]
    mass = sphere_mass(SPHERE_RADIUS, WOOD)
    position = last.bodies["sphere"][:3, 3]
    assert np.abs(last.v).max() < 1e-6 and np.linalg.norm(position - centre - [0.03, 0.01, 0.03]) < 1e-4
    model, data = sim.model, sim.state.data
    pin.framesForwardKinematics(model.plant.model, data, model.configuration(sim.state.x))
    expected = static_load(palm, hand_masses(model.plant.model, data, model.scene.urdf, "") + [(mass, position)])
    assert relative_error(last.sensors.wrist, expected) <= 0.01, (last.sensors.wrist, expected)
    assert np.linalg.norm(expected[1]) > 1e-3       # an off-centre load: the torque counts
    up = np.array([0.0, 0.0, G])
    pair_force, pair_torque = last.sensors.pairs["/".join(pair)]
    if pair[1] == "sphere":
        np.testing.assert_allclose(last.bodies["sphere"][:3, :3] @ pair_force, mass * up, rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(pair_torque, 0.0, atol=1e-9)
    else:
        np.testing.assert_allclose(palm.rotation @ pair_force, -mass * up, rtol=1e-6, atol=1e-9)
