"""Fuzzing what a user loads: the youBot URDF with random attribute and element mutations
(through ``load_robot``) and scene files with random key and value mutations (through
``load_scene``).

Invariants:
- no exception escapes but :class:`UserInputError` (URDFError, SceneError are subclasses),
  and its message is one line;
- a URDF that loads has finite, positive masses, finite inertias and joint limits with
  lower <= upper;
- a scene that loads has a finite initial state (q0, v0, gravity) within its robot's limits.

Examples per test: test/conftest.py's hypothesis profile (``ci``: 40, derandomised;
``HYPOTHESIS_PROFILE=thorough``: 2000).
"""
from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import event, given
from hypothesis import strategies as st
from lxml import etree

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import load_robot
from youbot_dynamics.scene.schema import find_scene, load_scene

REPO = Path(__file__).resolve().parents[2]
URDF_TEXT = (REPO / "urdf" / "youbot.urdf").read_text(encoding="utf-8")
URDF_ELEMENTS = sum(1 for _ in etree.fromstring(URDF_TEXT.encode()).iter())

WEIRD_TEXT = ["nan", "NaN", "inf", "-inf", "1e400", "-1e400", "-1", "0", "", " ", "abc", "1 2", "1 2 3 4",
              "1e-320", "  3  ", "1,2,3", "0x10", "fixed", "revolute", "continuous", "prismatic", "floating",
              "planar", "spherical", "base_footprint", "arm_link_1", "arm_joint_1", "gripper_palm_link", "world"]
ATTRIBUTES = ["name", "type", "xyz", "rpy", "value", "ixx", "iyy", "izz", "ixy", "ixz", "iyz", "lower",
              "upper", "effort", "velocity", "link", "damping", "friction", "filename", "size", "radius",
              "length", "multiplier", "offset", "joint"]
ELEMENTS = ["inertial", "mass", "inertia", "origin", "limit", "axis", "parent", "child", "dynamics", "mimic",
            "joint", "link", "safety_controller", "calibration", "transmission", "gazebo", "unknown"]

urdf_mutation = st.one_of(
    st.tuples(st.just("set"), st.integers(0, URDF_ELEMENTS - 1), st.sampled_from(ATTRIBUTES),
              st.one_of(st.sampled_from(WEIRD_TEXT), st.text(max_size=10),
                        st.floats().map(repr), st.lists(st.floats().map(repr), max_size=4).map(" ".join))),
    st.tuples(st.just("drop attribute"), st.integers(0, URDF_ELEMENTS - 1), st.sampled_from(ATTRIBUTES)),
    st.tuples(st.just("drop element"), st.integers(1, URDF_ELEMENTS - 1)),
    st.tuples(st.just("duplicate"), st.integers(1, URDF_ELEMENTS - 1)),
    st.tuples(st.just("move"), st.integers(1, URDF_ELEMENTS - 1), st.integers(0, URDF_ELEMENTS - 1)),
    st.tuples(st.just("add"), st.integers(0, URDF_ELEMENTS - 1), st.sampled_from(ELEMENTS)))


def mutated_urdf(mutations: list[tuple]) -> str:
    """The youBot URDF with ``mutations`` applied in order (element indices modulo the
    current element count; a move into its own subtree is skipped)."""
    root = etree.fromstring(URDF_TEXT.encode())
    for kind, index, *rest in mutations:
        elements = [e for e in root.iter() if isinstance(e.tag, str)]
        element = elements[index % len(elements)]
        parent = element.getparent()
        if kind == "set":
            element.set(rest[0], "".join(c for c in rest[1] if c.isprintable()))
        elif kind == "drop attribute":
            element.attrib.pop(rest[0], None)
        elif kind == "add":
            etree.SubElement(element, rest[0], name=f"added_{index}")
        elif parent is None:
            continue
        elif kind == "drop element":
            parent.remove(element)
        elif kind == "duplicate":
            parent.insert(parent.index(element), copy.deepcopy(element))
        elif kind == "move":
            target = elements[rest[0] % len(elements)]
            if target is not element and element not in target.iterancestors():
                target.append(element)
    return etree.tostring(root, encoding="unicode")


def assert_one_line_user_error(error: Exception) -> None:
    assert isinstance(error, UserInputError), f"{type(error).__name__}: {error}"
    assert str(error) and "\n" not in str(error).strip(), repr(str(error))


def loaded_or_one_line_user_error(load, *args):
    """``load(*args)``, or None when it raised a one-line UserInputError (any other exception,
    or a message over several lines, fails the test); records the outcome as an event."""
    try:
        result = load(*args)
    except Exception as error:  # noqa: BLE001 -- the invariant: only UserInputError
        assert_one_line_user_error(error)
        event(f"rejected: {type(error).__name__}")
        return None
    event("loaded")
    return result


@given(st.lists(urdf_mutation, min_size=1, max_size=3))
def test_mutated_urdfs_load_or_raise_a_one_line_urdf_error(mutations: list[tuple]) -> None:
    text = mutated_urdf(mutations)
    robot = loaded_or_one_line_user_error(load_robot, text)
    if robot is None:
        return
    for inertia in robot.model.inertias[1:]:
        assert math.isfinite(inertia.mass) and inertia.mass >= 0.0
        assert np.isfinite(inertia.inertia).all() and np.isfinite(inertia.lever).all()
    assert np.isfinite(np.asarray(robot.model.jointPlacements[1].translation)).all()
    assert np.all(robot.lower <= robot.upper)


WEIRD_VALUES = [math.nan, math.inf, -math.inf, -1, 0, 0.0, 1e308, -1e-308, "", "bogus", "none", [], {}, None, True,
                [1, 2], [0.0, 0.0, 0.0], {"x": 1}, "arm_joint_1", ["arm_joint_1", "arm_joint_1"], "urdf", "rk45",
                "cvode_bdf", "pgs", "constraint", "box", {"type": "sphere", "radius": -1.0}]
BASE_SCENES = {name: yaml.safe_load(find_scene(name).read_text(encoding="utf-8")) for name in ("arm_ptp", "box_slide")}


def paths(data: object, prefix: tuple = ()) -> list[tuple]:
    """Every key path (tuples of keys and list indices) in a parsed YAML tree."""
    found = [prefix]
    if isinstance(data, dict):
        for key, value in data.items():
            found += paths(value, (*prefix, key))
    elif isinstance(data, list):
        for i, value in enumerate(data):
            found += paths(value, (*prefix, i))
    return found


def mutated_scene(base: str, mutations: list[tuple]) -> dict:
    """A base scene's YAML tree with mutations (replace a value, drop a key, add a key)."""
    data = copy.deepcopy(BASE_SCENES[base])
    for kind, pick, shared in mutations:
        value = copy.deepcopy(shared)         # a list inserted twice must not become its own element
        candidates = paths(data)
        path = candidates[pick % len(candidates)]
        if not path:
            data = value if kind == "replace" and pick % 7 == 0 else data      # rarely: the whole file
            continue
        *head, last = path
        container = data
        for key in head:
            container = container[key]
        if kind == "replace":
            container[last] = value
        elif kind == "drop" and isinstance(container, dict):
            del container[last]
        elif kind == "drop":
            container.pop(last)
        elif kind == "add" and isinstance(container.get(last) if isinstance(container, dict) else None, dict):
            container[last][f"unknown_{pick % 5}"] = value
    return data


scene_value = st.one_of(st.sampled_from(WEIRD_VALUES), st.floats(), st.integers(-10**20, 10**20), st.text(max_size=8))
scene_mutation = st.tuples(st.sampled_from(["replace", "drop", "add"]), st.integers(0, 10**6), scene_value)


@given(st.sampled_from(sorted(BASE_SCENES)), st.lists(scene_mutation, min_size=1, max_size=3))
def test_mutated_scenes_load_or_raise_a_one_line_scene_error(tmp_path: Path, base: str, mutations: list[tuple]) -> None:
    path = tmp_path / f"{base}_mutated.yaml"
    path.write_text(yaml.safe_dump(mutated_scene(base, mutations), allow_unicode=True), encoding="utf-8")
    scene = loaded_or_one_line_user_error(load_scene, path)
    if scene is None:
        return
    for vector in (scene.q0, scene.v0, scene.gravity):
        assert np.isfinite(vector).all()
    robot = scene.robot
    assert np.all((robot.lower <= scene.q0) & (scene.q0 <= robot.upper))


@pytest.mark.parametrize("text", ["<robot name='r'><link name='a'/><joint name='j' type='revolute'>"
                                  "<parent link='a'/><child link='b'/></joint></robot>", "<robot/>", "not xml"])
def test_known_bad_urdfs_raise_urdf_errors(text: str) -> None:
    """Fixed examples next to the fuzzed ones: a missing child link, no links, not XML."""
    with pytest.raises(UserInputError) as error:
        load_robot(text)
    assert_one_line_user_error(error.value)
