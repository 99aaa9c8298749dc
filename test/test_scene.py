"""Scenes: the packaged ones load; every kind of mistake names the file, the key and the
value; locking joints shrinks the state and the model the rhs works on."""
from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from youbot_dynamics.sim.scene import SceneError, load_scene, scene_dir
from youbot_dynamics.sim.simulator import Simulator
from youbot_dynamics.sim.state import StateLayout

ARM = ["arm_joint_1", "arm_joint_2", "arm_joint_3", "arm_joint_4", "arm_joint_5"]


def packaged(name: str) -> dict:
    return yaml.safe_load((scene_dir() / f"{name}.yaml").read_text())


def write(tmp_path: Path, data: dict, name: str = "scene.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def error_of(tmp_path: Path, data: dict) -> SceneError:
    path = write(tmp_path, data)
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert caught.value.source == str(path)
    assert str(path) in str(caught.value)
    return caught.value


@pytest.mark.parametrize("name", ["arm_swing", "arm_friction", "arm_ptp"])
def test_packaged_scenes_load(name):
    scene = load_scene(name)
    assert scene.name == name
    assert scene.moving == tuple(ARM)
    assert scene.output_times[0] == 0.0 and scene.output_times[-1] == pytest.approx(scene.duration)


def test_unknown_key_names_file_key_and_value(tmp_path):
    data = packaged("arm_swing")
    data["integrator"]["rtoll"] = 1e-6
    error = error_of(tmp_path, data)
    assert error.key == "integrator.rtoll" and "rtoll" in str(error)
    data = packaged("arm_swing")
    data["contact_pairs"] = []
    assert error_of(tmp_path, data).key == "contact_pairs"


def test_missing_files(tmp_path):
    with pytest.raises(Exception) as caught:
        load_scene(tmp_path / "absent.yaml")
    assert "absent.yaml" in str(caught.value)
    data = packaged("arm_swing")
    data["robot"] = "no_such_robot.urdf"
    error = error_of(tmp_path, data)
    assert error.key == "robot" and error.value == "no_such_robot.urdf"


@pytest.mark.parametrize("where", ["moving", "initial", "locked", "friction"])
def test_joint_not_in_urdf(tmp_path, where):
    data = packaged("arm_friction")
    if where == "moving":
        data["moving"] = ARM + ["arm_joint_9"]
    elif where == "initial":
        data["initial"]["q"]["arm_joint_9"] = 0.1
    elif where == "locked":
        data["locked"] = {"wheel_joint_xx": 0.0}
    else:
        data["friction"]["joints"]["arm_joint_9"] = {"law": "viscous", "damping": 1.0}
    error = error_of(tmp_path, data)
    assert error.key.startswith(where)
    assert "arm_joint_9" in str(error) or "wheel_joint_xx" in str(error)


@pytest.mark.parametrize("key", ["rtol", "atol", "energy_tolerance"])
def test_negative_tolerance(tmp_path, key):
    data = packaged("arm_swing")
    data["integrator"][key] = -1e-6
    error = error_of(tmp_path, data)
    assert error.key == f"integrator.{key}" and error.value == -1e-6


def test_waypoint_outside_joint_limits(tmp_path):
    data = packaged("arm_ptp")
    data["controller"]["trajectory"]["waypoints"][2] = {"arm_joint_2": 3.0}  # upper 2.7052603
    error = error_of(tmp_path, data)
    assert error.key == "controller.trajectory.waypoints[2].arm_joint_2"
    assert error.value == 3.0 and "2.70526" in str(error)


@pytest.mark.parametrize("mutate, key", [
    (lambda d: d["integrator"].update(method="rk99"), "integrator.method"),
    (lambda d: d["integrator"].update(method="rk4"), "integrator.dt"),
    (lambda d: d["integrator"].update(method="auto"), "integrator.target_error"),
    (lambda d: d.update(duration="long"), "duration"),
    (lambda d: d["friction"]["joints"]["arm_joint_2"].update(law="sticky"), "friction.joints"),
    (lambda d: d["friction"]["joints"]["arm_joint_2"].pop("sigma0"), "friction.joints"),
    (lambda d: d["initial"]["q"].update(arm_joint_3=0.5), "initial.q.arm_joint_3"),
    (lambda d: d.update(free_bodies=[{"sphere": 1}]), "free_bodies[0].sphere"),
    (lambda d: d["outputs"].update(record=["q", "jerk"]), "outputs.record[1]"),
])
def test_other_mistakes(tmp_path, mutate, key):
    data = copy.deepcopy(packaged("arm_friction"))
    mutate(data)
    assert error_of(tmp_path, data).key == key


def test_yaml_exponent_without_dot_is_a_number(tmp_path):
    data = packaged("arm_swing")
    text = yaml.safe_dump(data).replace("rtol: 1.0e-09", "rtol: 1e-9")
    assert "rtol: 1e-9" in text
    path = tmp_path / "s.yaml"
    path.write_text(text)
    assert load_scene(path).integrator.rtol == 1e-9


def test_state_layout_names_and_views():
    layout = StateLayout.for_joints(["a", "b"], {"z": ["b"], "empty": []})
    assert layout.size == 5 and layout.n_positions == 2
    assert layout.names == ("q[a]", "q[b]", "v[a]", "v[b]", "z[b]")
    x = layout.pack(q=[1, 2], v=[3, 4], z=[5])
    parts = layout.split(x)
    parts["v"][:] = 0.0  # a view: writes through
    assert x.tolist() == [1, 2, 0, 0, 5]
    assert layout.slice("empty") == slice(5, 5)
    assert np.isinf(layout.velocity_bounds([1.0, 2.0], 100.0)[[0, 1, 4]]).all()
    assert layout.velocity_bounds([1.0, 2.0], 100.0)[2:4].tolist() == [100.0, 200.0]


def test_locking_joints_reduces_state_and_rhs_work(tmp_path):
    """Counting, not timing: the state dimension and the dof/bodies ABA runs over."""
    all_joints = packaged("arm_friction")
    all_joints["moving"] = ARM + ["gripper_finger_joint_l", "gripper_finger_joint_r",
                                  "wheel_joint_fl", "wheel_joint_fr", "wheel_joint_bl", "wheel_joint_br"]
    full = Simulator(load_scene(write(tmp_path, all_joints, "full.yaml")))
    arm = Simulator(load_scene("arm_friction"))
    two = packaged("arm_friction")
    two["moving"] = ["arm_joint_2", "arm_joint_3"]
    two["friction"]["joints"] = {k: v for k, v in two["friction"]["joints"].items() if k in two["moving"]}
    two["initial"]["q"] = {k: v for k, v in two["initial"]["q"].items() if k in two["moving"]}
    two["initial"]["v"] = {}
    pair = Simulator(load_scene(write(tmp_path, two, "two.yaml")))
    costs = [s.rhs_cost() for s in (full, arm, pair)]
    # q, v per moving joint plus one LuGre bristle per LuGre joint (joints 2 and 3)
    assert [c["state_dim"] for c in costs] == [2 * 11 + 2, 2 * 5 + 2, 2 * 2 + 2]
    assert [c["nv"] for c in costs] == [11, 5, 2]
    assert costs[0]["bodies"] > costs[1]["bodies"] > costs[2]["bodies"]
    assert [s.layout.size for s in (full, arm, pair)] == [c["state_dim"] for c in costs]
    # without LuGre joints there is no bristle state at all
    swing = Simulator(load_scene("arm_swing"))
    assert swing.rhs_cost()["state_dim"] == 10 and swing.friction is None
