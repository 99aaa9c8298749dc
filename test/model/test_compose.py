"""Composition of several URDFs into one robot, checked through Pinocchio's forward
kinematics and inertias of the composed model, and gravity on a model copy."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.model.compose import (CompositionError, InertialCorrection, Placement, composed_urdf,
                                           robot_with_gravity)
from youbot_dynamics.model.robot import load_robot

URDF = Path(default_urdf())


def pose(xyz, yaw) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, yaw)
    matrix[:3, 3] = xyz
    return matrix


def test_two_robots_sit_at_their_poses_with_prefixed_names_and_corrected_inertials():
    second = pose([0.0, 0.575, 0.084], -np.pi / 2)
    finger = InertialCorrection(mass=0.02, moments=(5.4e-7, 7.1e-7, 2.1e-7))
    robot = load_robot(composed_urdf([Placement(URDF, "yb1_", pose([-0.569, 0.0, 0.084], 0.0)),
                                      Placement(URDF, "yb2_", second, {"gripper_finger_link_l": finger})]))
    single = load_robot(URDF)
    assert robot.nv == 2 * single.nv
    assert set(robot.joint_names) == {p + n for p in ("yb1_", "yb2_") for n in single.joint_names}
    model, data = robot.model, robot.model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    placed = data.oMf[model.getFrameId("yb2_base_footprint")]
    assert np.allclose(placed.homogeneous, second, atol=1e-12)
    # each arm's end effector is its own robot's, moved by the pose
    one = single.model.createData()
    pin.framesForwardKinematics(single.model, one, pin.neutral(single.model))
    local = one.oMf[single.model.getFrameId("arm_link_5")].homogeneous
    assert np.allclose(data.oMf[model.getFrameId("yb2_arm_link_5")].homogeneous, second @ local, atol=1e-12)
    inertia = model.inertias[model.frames[model.getFrameId("yb2_gripper_finger_link_l")].parentJoint]
    assert inertia.mass == pytest.approx(0.02)
    untouched = model.inertias[model.frames[model.getFrameId("yb1_gripper_finger_link_l")].parentJoint]
    assert untouched.mass == pytest.approx(0.01) and np.allclose(np.diag(untouched.inertia), 0.01)


def test_errors_name_the_placement_and_its_part(tmp_path):
    with pytest.raises(CompositionError) as caught:
        composed_urdf([Placement(URDF), Placement(URDF, "b_", inertials={"no_link": InertialCorrection(1.0)})])
    assert (caught.value.index, caught.value.part) == (1, "inertials.no_link")
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'><link", encoding="utf-8")
    with pytest.raises(CompositionError, match="not valid XML") as caught:
        composed_urdf([Placement(broken)])
    assert (caught.value.index, caught.value.part) == (0, "urdf")


def test_a_file_that_urdfdom_forgives_composes(tmp_path):
    """Blank lines before a version-0.0 declaration and an undeclared prefix (pybullet_data's,
    Drake's files), read as load_robot reads them."""
    text = URDF.read_text(encoding="utf-8").split("?>", 1)[-1]
    forgiven = tmp_path / "forgiven.urdf"
    forgiven.write_text('\n<?xml version="0.0" ?>' + text.replace("<robot ", '<robot drake:tag="x" ', 1),
                        encoding="utf-8")
    composed = load_robot(composed_urdf([Placement(URDF, "a_"), Placement(forgiven, "b_")]))
    assert composed.nv == 2 * load_robot(URDF).nv
    missing = tmp_path / "missing.urdf"
    with pytest.raises(CompositionError, match=f"URDF file not found: {missing}") as caught:
        composed_urdf([Placement(missing)])
    assert (caught.value.index, caught.value.part) == (0, "urdf")


def test_gravity_on_a_copy_leaves_the_loaded_model_alone():
    robot = load_robot(URDF)
    moon = robot_with_gravity(robot, [0.0, 0.0, -1.62])
    assert moon.model.gravity.linear.tolist() == [0.0, 0.0, -1.62]
    assert robot.model.gravity.linear.tolist() == [0.0, 0.0, -9.81]
    assert robot_with_gravity(robot, [0.0, 0.0, -9.81]) is robot


def test_a_robot_on_a_moving_base_is_not_welded_to_a_world_link():
    """Unwelded (a moving base): the robot's own root link is the root, no ``world`` link and
    no world joint, the same model as the file's; two robots or a pose are refused."""
    robot = load_robot(composed_urdf([Placement(URDF)], welded=False))
    single = load_robot(URDF)
    assert robot.root_link == single.root_link == "base_footprint"
    assert "world" not in robot.link_names and not any(j.name.endswith("world_joint") for j in robot.tree)
    assert robot.link_names == single.link_names and robot.nv == single.nv
    with pytest.raises(CompositionError, match="one robot") as two:
        composed_urdf([Placement(URDF, "a_"), Placement(URDF, "b_")], welded=False)
    assert two.value.index == 1
    with pytest.raises(CompositionError, match="base.initial.pose") as placed:
        composed_urdf([Placement(URDF, pose=pose([1.0, 0.0, 0.0], 0.0))], welded=False)
    assert placed.value.part == "pose"
