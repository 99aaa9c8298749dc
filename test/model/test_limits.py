"""Sanity bounds on magnitudes and sizes (youbot_dynamics.model.limits): the URDF
loader and the scene validator refuse values far beyond any real robot with one line naming
file:line and element (URDF) or file and key (scene), and accept values at the bounds; scene
YAML is read with bounded aliases and expanded size.

Before the fix: mass 1e308 and an origin of 1e200 loaded (then the energy overflowed to
inf), damping -1 loaded, a 2000-link chain raised MemoryError in createData, gravity and
initial velocities of 1e308, rtol 1e-30 and outputs.rate 1e9 passed the scene validator, and
a 445-byte alias bomb raised MemoryError.
"""
from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from youbot_dynamics.model import limits
from youbot_dynamics.model.robot import URDFError, load_robot
from youbot_dynamics.scene.schema import SceneError, load_scene

from urdf_support import _error, _joint, _link, _two_link, _urdf, _write
from scene_support import error_of, packaged, write


# ---- URDF magnitudes ----------------------------------------------------------------------
@pytest.mark.parametrize("changes, element, attribute, value", [
    ({"l1": _link("l1", mass="1e308")}, "<mass>", "value", "1e308"),
    ({"l1": _link("l1", inertia='<inertia ixx="1e200" ixy="0" ixz="0" iyy="1e200" iyz="0" izz="1e200"/>')},
     "<inertia>", "ixx", "1e200"),
    ({"j1": _joint("j1", "base", "l1").replace('xyz="0 0 0.2"', 'xyz="1e200 0 0"')}, "<origin>", "xyz", "1e200"),
    ({"j1": _joint("j1", "base", "l1", extra='<dynamics damping="-1"/>')}, "<dynamics>", "damping", "-1"),
    ({"j1": _joint("j1", "base", "l1", extra='<dynamics friction="-0.5"/>')}, "<dynamics>", "friction", "-0.5"),
    ({"l1": '<link name="l1"><visual><geometry><sphere radius="1e200"/></geometry></visual></link>'},
     "<sphere>", "radius", "1e200"),
])
def test_urdf_magnitudes_beyond_the_bounds_are_refused(tmp_path: Path, changes, element, attribute,
                                                      value) -> None:
    text = _two_link(**changes)
    message = _error(tmp_path, text)  # names the file, one line
    line = next(i for i, row in enumerate(text.splitlines(), 1) if f'{attribute}="{value}' in row)
    owner = "link 'l1'" if element in ("<mass>", "<inertia>", "<sphere>") else "joint 'j1'"
    assert f":{line}: {owner}: {element}: {attribute}=" in message, message
    assert "bound" in message or "negative" in message, message


def test_urdf_magnitudes_at_the_bounds_load() -> None:
    heavy = _link("l1", mass=repr(limits.MASS.maximum))
    far = _joint("j1", "base", "l1", extra='<dynamics damping="0" friction="0"/>').replace(
        'xyz="0 0 0.2"', f'xyz="{limits.LENGTH.maximum!r} 0 0"')
    robot = load_robot(_two_link(l1=heavy, j1=far))
    assert robot.model.inertias[1].mass == limits.MASS.maximum
    assert robot.model.jointPlacements[1].translation[0] == limits.LENGTH.maximum


# ---- URDF sizes ---------------------------------------------------------------------------
def _chain(links: int, kind: str = "revolute") -> str:
    elements = [_link("l0")]
    for i in range(1, links):
        elements += [_link(f"l{i}"), _joint(f"j{i}", f"l{i - 1}", f"l{i}", kind=kind)]
    return _urdf(*elements)


@pytest.mark.parametrize("links, kind, what", [
    (limits.MAX_MOVING_JOINTS + 2, "revolute", f"{limits.MAX_MOVING_JOINTS + 1} moving joints"),
    (2000, "revolute", "2000 <link> elements"),  # before: MemoryError in createData
    (limits.MAX_LINKS + 1, "fixed", f"{limits.MAX_LINKS + 1} <link> elements"),
])
def test_urdf_beyond_the_size_bounds_is_refused_before_pinocchio(tmp_path: Path, links, kind, what) -> None:
    message = _error(tmp_path, _chain(links, kind))
    assert what in message and "beyond the bound" in message, message


def test_urdf_at_the_link_bound_loads() -> None:
    # 1000 links on fixed joints: Pinocchio folds them into frames (no joint, no Data blow-up).
    robot = load_robot(_chain(limits.MAX_LINKS, "fixed"))
    assert len(robot.link_names) == limits.MAX_LINKS and robot.nv == 0


def test_urdf_file_beyond_the_byte_bound_is_not_read(tmp_path: Path, monkeypatch) -> None:
    path = _write(tmp_path, _two_link())
    monkeypatch.setattr(limits, "MAX_URDF_BYTES", path.stat().st_size - 1)
    with pytest.raises(URDFError, match="bytes is beyond the bound"):
        load_robot(path)


# ---- scene magnitudes ---------------------------------------------------------------------
def _compose(d: dict) -> None:
    d["robot"] = {"compose": [{"urdf": "urdf/youbot.urdf", "prefix": "a_",
                               "inertials": {"arm_link_1": {"mass": 1e308}}}]}


@pytest.mark.parametrize("scene, mutate, key", [
    ("arm_swing", lambda d: d.update(gravity=[0, 0, 1e308]), "gravity[2]"),
    ("arm_swing", lambda d: d["initial"].setdefault("v", {}).update(arm_joint_2=1e308), "initial.v.arm_joint_2"),
    ("arm_swing", lambda d: d["integrator"].update(rtol=1e-30), "integrator.rtol"),
    ("arm_swing", lambda d: d["integrator"].update(rtol=2.0), "integrator.rtol"),
    ("arm_swing", lambda d: d["integrator"].update(tol=1e-15, rtol=None, atol=None), "integrator.tol"),
    ("arm_swing", lambda d: d["outputs"].update(rate=1e9), "outputs.rate"),
    ("arm_swing", lambda d: d.update(duration=1e5), "outputs.rate"),  # 1e7 samples at 100 Hz
    ("ball_drop", lambda d: d["free_bodies"][0].update(position=[0, 0, 1e200]), "free_bodies[0].position[2]"),
    ("ball_drop", lambda d: d["free_bodies"][0].update(velocity=[1e308, 0, 0]), "free_bodies[0].velocity[0]"),
    ("ball_drop", lambda d: d["free_bodies"][0].update(angular_velocity=[0, 1e5, 0]),
     "free_bodies[0].angular_velocity[1]"),
    ("ball_drop", lambda d: d["free_bodies"][0].update(density=1e300), "free_bodies[0].density"),
    ("ball_drop", lambda d: (d["free_bodies"][0].pop("density"), d["free_bodies"][0].update(
        mass=1e308, inertia=[1, 1, 1])), "free_bodies[0].mass"),
    ("ball_drop", lambda d: d["free_bodies"][0]["shape"].update(radius=1e200), "free_bodies[0].shape.radius"),
    ("ball_drop", lambda d: d["world"][0].update(pose={"xyz": [1e200, 0, 0]}), "world[0].pose.xyz[0]"),
    ("arm_swing", _compose, "robot.compose[0].inertials.arm_link_1.mass"),
])
def test_scene_magnitudes_beyond_the_bounds_are_refused(tmp_path: Path, scene, mutate, key) -> None:
    data = copy.deepcopy(packaged(scene))
    mutate(data)
    data["integrator"] = {k: v for k, v in data["integrator"].items() if v is not None}
    error = error_of(tmp_path, data)
    assert error.key == key, error
    assert "bound" in str(error) or "a relative tolerance must be within" in str(error), error
    assert "\n" not in str(error)


def test_huge_quaternion_components_normalise_without_overflow(tmp_path: Path) -> None:
    # Before: the norm overflowed to inf and the orientation became [0, 0, 0, 0].
    data = packaged("ball_drop")
    data["free_bodies"][0]["orientation"] = [1e200, 1e200, 0.0, 0.0]
    orientation = load_scene(write(tmp_path, data)).free_bodies[0].orientation
    assert np.allclose(orientation, [2 ** -0.5, 2 ** -0.5, 0.0, 0.0], rtol=0.0, atol=1e-15)  # measured 1.1e-16


def test_scene_values_at_the_bounds_load(tmp_path: Path) -> None:
    data = packaged("arm_swing")
    data["integrator"]["rtol"] = limits.MIN_RTOL
    data["gravity"] = [0.0, 0.0, -limits.GRAVITY.maximum]
    data["outputs"]["rate"] = limits.RATE.maximum
    data["duration"] = limits.MAX_OUTPUT_SAMPLES / limits.RATE.maximum
    scene = load_scene(write(tmp_path, data))
    assert scene.integrator.rtol == limits.MIN_RTOL and scene.gravity[2] == -limits.GRAVITY.maximum
    with pytest.raises(SceneError, match="output samples"):
        scene.with_duration(2 * scene.duration)


def test_scene_degrees_of_freedom_are_bounded(tmp_path: Path) -> None:
    # Before: 40 free bodies (240 DoFs) went to Pinocchio, whose Data takes about 64 nv^3 bytes
    # (measured: 486 MB at nv 198, 3.8 GB at 396).
    data = packaged("ball_drop")
    ball = data["free_bodies"][0]
    bodies = limits.MAX_DOFS // 6
    data["free_bodies"] = [{**ball, "name": f"ball{i}"} for i in range(bodies)]
    data["contacts"] = []
    assert len(load_scene(write(tmp_path, data, "at_bound.yaml")).free_bodies) == bodies
    data["free_bodies"].append({**ball, "name": "one_too_many"})
    error = error_of(tmp_path, data)
    assert error.key == "free_bodies" and f"beyond the bound of {limits.MAX_DOFS}" in str(error)


# ---- scene YAML ---------------------------------------------------------------------------
def _alias_bomb(levels: int = 9) -> str:
    """Each level lists the previous one nine times: 9**levels strings from a few hundred bytes."""
    rows = ['  - &x0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    rows += [f"  - &x{k} [" + ",".join([f"*x{k - 1}"] * 9) + "]" for k in range(1, levels)]
    return "description:\n" + "\n".join(rows) + "\n"


def _error_of_text(tmp_path: Path, text: str) -> SceneError:
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert caught.value.key == "(file)" and str(path) in str(caught.value)
    assert "\n" not in str(caught.value), caught.value
    return caught.value


def test_yaml_alias_bomb_is_refused(tmp_path: Path) -> None:
    text = _alias_bomb()
    assert len(text) < 1000
    error = _error_of_text(tmp_path, text)  # before: MemoryError
    assert "490329057 nodes with the aliases expanded" in str(error)  # 3 + sum of x_k, x_0 = 10, x_k = 1 + 9 x_(k-1)


def test_yaml_with_too_many_aliases_is_refused(tmp_path: Path) -> None:
    text = "description: &d text\nname: [" + ", ".join(["*d"] * (limits.MAX_YAML_ALIASES + 1)) + "]\n"
    assert f"more than {limits.MAX_YAML_ALIASES} aliases" in str(_error_of_text(tmp_path, text))


def test_yaml_self_containing_alias_and_deep_nesting_are_refused(tmp_path: Path) -> None:
    assert "contains it" in str(_error_of_text(tmp_path, "description: &a [1, *a]\n"))
    assert "nested too deeply" in str(_error_of_text(tmp_path, "description: " + "[" * 5000 + "]" * 5000 + "\n"))


def test_yaml_syntax_error_is_one_line(tmp_path: Path) -> None:
    assert "not valid YAML" in str(_error_of_text(tmp_path, "duration: [1,\n  outputs: {\n"))


def test_yaml_anchors_within_the_bounds_read_as_without_them(tmp_path: Path) -> None:
    data = packaged("arm_swing")
    plain = load_scene(write(tmp_path, data, "plain.yaml"))
    text = yaml.safe_dump(data) + "description: &d shared\nname: *d\n"
    path = tmp_path / "anchored.yaml"
    path.write_text(text)
    anchored = load_scene(path)
    assert anchored.name == "shared" and anchored.description == "shared"
    assert np.array_equal(anchored.q0, plain.q0) and anchored.integrator == plain.integrator
