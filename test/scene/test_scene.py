"""Scenes: the packaged ones load, from their files and from mappings alike; every kind of
mistake names the source, the key and the value; the robot is loaded once; locking joints
shrinks the state and the model the rhs works on."""
from __future__ import annotations

import copy
import dataclasses
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
import yaml

import youbot_dynamics.model.robot as robot_module
import youbot_dynamics.scene.schema as scene_module
from youbot_dynamics import default_urdf
from youbot_dynamics.model.robot import Robot, URDFDocument
from youbot_dynamics.scene.schema import Scene, SceneError, load_scene, scene_dir
from youbot_dynamics.sim.simulator import Simulator
from youbot_dynamics.sim.state import StateLayout

from scene_support import error_of, packaged, write

ARM = ["arm_joint_1", "arm_joint_2", "arm_joint_3", "arm_joint_4", "arm_joint_5"]


def assert_same(a, b, where: str = "scene") -> None:
    """Field by field (arrays exactly, Robots by name, source, joints and Pinocchio model)."""
    if isinstance(a, Robot):
        assert (a.name, a.source, a.joint_names, dict(a.locked)) == (b.name, b.source, b.joint_names, dict(b.locked))
        assert a.model == b.model, where
    elif isinstance(a, URDFDocument):
        assert_same((a.label, a.tree, a.root_link, a.forgiven), (b.label, b.tree, b.root_link, b.forgiven), where)
    elif dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for field in dataclasses.fields(a):
            assert_same(getattr(a, field.name), getattr(b, field.name), f"{where}.{field.name}")
    elif isinstance(a, np.ndarray):
        assert np.array_equal(a, b), where
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif hasattr(a, "items"):
        assert a.keys() == b.keys(), where
        for key in a:
            assert_same(a[key], b[key], f"{where}.{key}")
    else:
        assert a == b, where


@pytest.mark.parametrize("path", sorted(scene_dir().glob("*.yaml")), ids=lambda p: p.stem)
def test_every_packaged_scene_from_its_mapping_equals_the_loaded_file(path):
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    assert_same(Scene.from_dict(data, str(path), path.parent), load_scene(path.stem))


def test_scene_from_a_mapping_without_any_file():
    data = {"robot": "none", "gravity": [0, 0, -1.62], "duration": 0.5,
            "free_bodies": [{"name": "ball", "shape": {"type": "sphere", "radius": 0.05}, "density": 700,
                             "position": [0, 0, 1]}],
            "integrator": {"method": "lsoda", "tol": 1e-8}}
    scene = Scene.from_dict(data)
    assert (scene.name, scene.source, scene.urdf_path) == ("scene", "<dict>", None)
    assert scene.robot.nv == 0 and scene.free_bodies[0].body.name == "ball"
    assert scene.robot.model.gravity.linear.tolist() == [0, 0, -1.62]  # the scene's gravity in the model
    arm = Scene.from_dict({"moving": ARM[:2], "duration": 0.1}, source="notebook cell 3")
    assert arm.urdf_path == Path(default_urdf()) and arm.urdf == Path(default_urdf()).read_text(encoding="utf-8")
    assert arm.robot.joint_names == tuple(ARM[:2]) and arm.name == "scene"
    with pytest.raises(SceneError) as caught:
        Scene.from_dict({"moving": ["arm_joint_9"]}, source="notebook cell 3")
    assert caught.value.key == "moving[0]" and str(caught.value).startswith("notebook cell 3: moving[0]: ")


def test_relative_files_are_found_in_base_dir_then_the_package_share(tmp_path):
    urdf = Path(default_urdf())
    (tmp_path / "mine.urdf").write_text(urdf.read_text(encoding="utf-8"), encoding="utf-8")
    data = {"robot": "mine.urdf", "moving": ARM}
    assert Scene.from_dict(data, base_dir=tmp_path).urdf_path == tmp_path / "mine.urdf"
    with pytest.raises(SceneError, match="file not found in .*share") as caught:
        Scene.from_dict(data)  # no base_dir: the package share only
    assert caught.value.key == "robot" and caught.value.value == "mine.urdf"
    packaged_urdf = {"robot": "urdf/youbot.urdf", "moving": ARM}
    assert Scene.from_dict(packaged_urdf).urdf_path == urdf.resolve()


@pytest.mark.parametrize("name", ["arm_friction", "base_square"])
def test_the_robot_is_parsed_once_per_scene(monkeypatch, name):
    """Once per scene, a moving base's planar plant included: the compiler rebuilds the
    robot with its planar root from the URDF the scene read, never from the file again."""
    calls = []
    real = robot_module.read_urdf
    counting = lambda *a, **k: calls.append(a) or real(*a, **k)  # noqa: E731
    monkeypatch.setattr(scene_module, "read_urdf", counting)
    monkeypatch.setattr(robot_module, "read_urdf", counting)
    scene = load_scene(name)
    assert len(calls) == 1 and isinstance(scene.robot, Robot)
    simulator = Simulator(scene)
    assert simulator.robot is scene.robot
    plant = simulator.model.plant                 # a moving base: the planar root's (cos, sin)
    assert plant.nq - plant.nv == (0 if scene.base.mode == "fixed" else 1)
    assert len(calls) == 1
    assert scene.with_duration(0.1).robot is scene.robot and len(calls) == 1


def test_a_scene_with_its_urdf_pickles():
    """A scene goes to a sweep's worker as Dask sends it (cloudpickle): its URDF is read
    again there."""
    scene = load_scene("base_square")
    again = cloudpickle.loads(cloudpickle.dumps(scene))
    assert_same(again, scene)


def test_composed_robot_keeps_its_urdf_text_and_no_file():
    scene = load_scene("gripping")
    assert scene.urdf_path is None and "yb2_world_joint" in scene.urdf
    assert scene.robot.nv == 14 and scene.robot.source == "<URDF string>"


def test_auto_is_refused_where_no_sweep_may_run(tmp_path):
    data = packaged("arm_swing")
    data["integrator"] = {"method": "auto", "target_error": 1e-5}
    scene = load_scene(write(tmp_path, data))
    with pytest.raises(SceneError, match="work-precision --scene .* --target-error 1e-05 --write-back") as caught:
        scene.pinned_integrator()
    assert caught.value.key == "integrator.method" and "\n" not in str(caught.value)
    assert load_scene("arm_swing").pinned_integrator().method == "dop853"


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
