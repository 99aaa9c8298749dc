"""The gripping scene: two youBots hand a wooden sphere from youBot 1's
plate to the table and on to youBot 2's plate. The whole 28 s run (about 10 s of wall time
under the constraint stepper) must end with the sphere on youBot 2's plate, the grasps must
hold it without slipping, and no contact may overlap by 1 mm or more. Also: the scene's
composition of two robots and its corrections of the URDF."""
from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from youbot_dynamics.scene.schema import SceneError, load_scene, scene_dir
from youbot_dynamics.sim.simulator import Simulator

RADIUS = 0.025        # m, the sphere's
PLATE_TOP = 0.005     # m, above plate_link's origin (the plate box is 0.01 thick)
CLOSED = 0.004        # m, the fingers' closed command (Modia3D's d - 0.002)


def packaged() -> dict:
    return yaml.safe_load((scene_dir() / "gripping.yaml").read_text())


@pytest.fixture(scope="module")
def run():
    simulator = Simulator(load_scene("gripping"))
    result = simulator.run()
    return simulator, result


def first_contacts(result) -> dict[str, float]:
    """Time (s) at which each pair first carries an impulse."""
    first: dict[str, float] = {}
    for event in result.contact_events:
        first.setdefault(event.pair, event.time)
    return first


def closed_samples(simulator: Simulator, result, robot: str) -> np.ndarray:
    """Output indices at which the robot's gripper is commanded closed."""
    finger = simulator.robot.joint_index(f"{robot}_gripper_finger_joint_l")
    desired = np.array([simulator.trajectory.evaluate(t)[0][finger] for t in result.t])
    return np.flatnonzero(np.isclose(desired, CLOSED))


def test_two_youbots_composed_with_prefixed_names_poses_and_corrected_fingers():
    scene = load_scene("gripping")
    robot = scene.robot
    assert robot.nv == 14 and all(name.startswith(("yb1_", "yb2_")) for name in robot.joint_names)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, scene.q0)
    # plate_link sits at (-0.159, 0, 0.046) in base_footprint, the base at the scene's pose
    yb1 = data.oMf[robot.frame_id("yb1_plate_link")].translation
    yb2 = data.oMf[robot.frame_id("yb2_plate_link")]
    assert yb1 == pytest.approx([-0.569 - 0.159, 0.0, 0.084 + 0.046], abs=1e-12)
    assert yb2.translation == pytest.approx([0.0, 0.575 + 0.159, 0.130], abs=1e-12)
    assert yb2.rotation[:, 0] == pytest.approx([0.0, -1.0, 0.0], abs=1e-12)  # yaw -pi/2
    # the fingers' published 0.01 kg m^2 replaced; their mass (10 g) kept
    for name in ("yb1_gripper_finger_link_l", "yb2_gripper_finger_link_r"):
        inertia = robot.model.inertias[robot.model.frames[robot.frame_id(name)].parentJoint]
        assert inertia.mass == pytest.approx(0.01)
        assert inertia.inertia.diagonal() == pytest.approx([5.4167e-7, 7.0833e-7, 2.0833e-7])
    # the wheels are locked (rigid), not states
    assert not any("wheel" in name for name in robot.joint_names)


@pytest.mark.parametrize("mutate, key", [
    (lambda d: d["robot"]["compose"][0]["inertials"].update(no_link={"inertia": [1, 1, 1]}),
     "robot.compose[0].inertials.no_link"),
    (lambda d: d["robot"]["compose"][0]["inertials"].update(gripper_palm_link={"inertia": [1, 1, 3]}),
     "robot.compose[0].inertials.gripper_palm_link.inertia"),
    (lambda d: d["robot"]["compose"][1].update(inertials={"gripper_palm_link": {"mass": -1}}),
     "robot.compose[1].inertials.gripper_palm_link.mass"),
])
def test_bad_inertial_corrections_name_the_key(tmp_path: Path, mutate, key):
    data = copy.deepcopy(packaged())
    # both robots share one mapping through a YAML alias: give youBot 1 its own
    data["robot"]["compose"][0]["inertials"] = dict(data["robot"]["compose"][0]["inertials"])
    mutate(data)
    path = tmp_path / "grip.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert caught.value.key == key and str(path) in str(caught.value)


def test_grip_force_budget_carries_the_sphere_below_the_finger_effort_limit():
    """Each finger, commanded 1 mm into the sphere, presses with kp m e below its 1 N limit;
    two of them carry the sphere's weight by friction with margin."""
    scene = load_scene("gripping")
    robot = scene.robot
    name = "yb1_gripper_finger_joint_l"
    finger = robot.joint_index(name)
    mass = robot.model.inertias[robot.model.getJointId(name)].mass
    normal = scene.controller.kp[finger] * mass * 0.001
    assert robot.effort_limit[finger] == 1.0
    assert normal == pytest.approx(0.9)
    mu = next(p.law.friction for p in scene.contacts if p.name == "yb1_pad_l/sphere")
    weight = scene.free_bodies[0].body.mass * 9.81
    assert weight == pytest.approx(0.449, abs=1e-3)
    assert 2 * mu * normal / weight == pytest.approx(1.20, abs=0.01)


def test_sphere_ends_at_rest_on_youbot_2s_plate(run):
    simulator, result = run
    on_plate = simulator.body_in_link(result, "sphere", "yb2_plate_link")[-1]
    assert abs(on_plate[0]) < 0.1 - RADIUS / 2 and abs(on_plate[1]) < 0.15 - RADIUS / 2
    assert on_plate[2] == pytest.approx(PLATE_TOP + RADIUS, abs=1e-3)
    speed = np.linalg.norm(simulator.model.body_motion(result.x[-1])["velocity"])
    assert speed < 5e-3


def test_hand_over_touches_plate_pads_table_pads_plate_in_order(run):
    _, result = run
    first = first_contacts(result)
    order = ["yb1_plate/sphere", "yb1_pad_l/sphere", "table/sphere", "yb2_pad_l/sphere", "yb2_plate/sphere"]
    assert [first[pair] for pair in order] == sorted(first[pair] for pair in order)
    assert abs(first["yb1_pad_l/sphere"] - first["yb1_pad_r/sphere"]) < 0.05
    assert abs(first["yb2_pad_l/sphere"] - first["yb2_pad_r/sphere"]) < 0.05


@pytest.mark.parametrize("robot, set_down", [("yb1", "table/sphere"), ("yb2", "yb2_plate/sphere")])
def test_closed_grasp_holds_the_sphere_without_slip(run, robot, set_down):
    """In the palm's frame the sphere stays where the grasp closed on it: within 0.5 mm while
    carried, within 1.5 mm while the arm presses it onto the table or plate."""
    simulator, result = run
    closed = closed_samples(simulator, result, robot)
    assert result.t[closed[-1]] - result.t[closed[0]] > 4.0
    in_palm = simulator.body_in_link(result, "sphere", f"{robot}_gripper_palm_link")[closed]
    drift = np.linalg.norm(in_palm - in_palm[0], axis=1)
    carried = result.t[closed] < first_contacts(result).get(set_down, np.inf) if robot == "yb1" else \
        np.ones(closed.size, dtype=bool)
    assert drift[carried].max() < 5e-4
    assert drift.max() < 1.5e-3
    # centred between the pads (the grasp centre is 4 mm along x and 66 mm along z of the palm)
    assert in_palm[:, 1] == pytest.approx(0.0, abs=1e-3)


def test_penetration_stays_below_a_millimetre_and_the_statistics_are_complete(run):
    _, result = run
    assert 0.0 < result.max_penetration < 1e-3
    stats = result.stats
    # 28 s in 1 ms steps: equal steps per output interval, no round-off slivers
    assert stats.steps == 28000
    assert stats.nonlinear_iterations > 0 and stats.events == len(result.contact_events)
    assert stats.simulated_time == pytest.approx(28.0) and stats.wall_time > 0.0
    assert np.all(np.isfinite(result.x))


def test_resting_contact_over_step_wise_calls_is_one_event():
    """The node advances the stepper sample by sample: the sphere resting on youBot 1's plate
    is one contact event however many calls it lasts, and the deepest overlap is kept."""
    simulator = Simulator(load_scene("gripping"))
    simulator.advance_through([0.02, 0.04])
    for t in (0.06, 0.08, 0.10):
        simulator.advance(t)
    assert [(e.pair, e.time) for e in simulator.events] == [("yb1_plate/sphere", pytest.approx(0.001))]
    assert simulator.state.deepest > 0.0
    simulator.reset()
    assert not simulator.events and simulator.state.deepest == 0.0
