"""The applied joint effort and the simulated sensors against independent computations:
Pinocchio's RNEA at finite-difference accelerations, a static hand computation of the wrist
load, the kinematic base's imposed yaw rate and gravity."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.scene.reader import read_yaml
from youbot_dynamics.scene.schema import Scene, find_scene, load_scene
from youbot_dynamics.sim.simulator import Simulator

G = 9.81


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
    """gripping at t = 0 (arms and fingers at rest, gravity compensated): the wrist reads
    the weight of the palm and both fingers (URDF masses 0.1, 0.01, 0.01 kg) pushed up, about
    the palm's origin, in its frame, to 1 % (a static hand computation)."""
    sim = Simulator(load_scene("gripping"))
    reading = sim.snapshot(sensors=True).sensors.wrist
    model, data = sim.model, sim.state.data
    plant = model.plant.model
    pin.framesForwardKinematics(plant, data, model.configuration(sim.state.x))
    palm = data.oMf[model.sensors.wrist.frame]
    up, force, torque = np.array([0.0, 0.0, G]), np.zeros(3), np.zeros(3)
    for name, mass in (("yb1_gripper_palm_link", 0.1), ("yb1_gripper_finger_link_l", 0.01),
                       ("yb1_gripper_finger_link_r", 0.01)):
        frame = plant.getFrameId(name, pin.BODY)
        centre = data.oMf[frame].act(_com_in_link(model.scene.urdf, name))
        force += mass * up
        torque += np.cross(centre - palm.translation, mass * up)
    expected = np.concatenate([palm.rotation.T @ force, palm.rotation.T @ torque])
    measured = np.concatenate(reading)
    assert np.linalg.norm(measured - expected) <= 0.01 * np.linalg.norm(expected), (measured, expected)


def _com_in_link(urdf: str, link: str) -> np.ndarray:
    """The centre of mass (m) of ``link`` in its frame, read from the URDF's <inertial>."""
    from lxml import etree
    element = etree.fromstring(urdf.encode()).find(f"link[@name='{link}']/inertial/origin")
    return np.zeros(3) if element is None else np.array([float(v) for v in element.get("xyz", "0 0 0").split()])
