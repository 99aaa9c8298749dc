"""URDF -> Robot: the youBot's contents, every validation error (naming file, element and
reason), the fidelity report and joint locking."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import URDFError, keep_joints, load_robot, lock_joints

INERTIA = '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'


def _link(name: str, mass: str = "1.0", inertia: str = INERTIA) -> str:
    return f'<link name="{name}"><inertial><mass value="{mass}"/>{inertia}</inertial></link>'


def _joint(name: str, parent: str, child: str, kind: str = "revolute", extra: str = "",
           limit: str = '<limit lower="-1" upper="1" effort="5" velocity="2"/>') -> str:
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 1 0"/>{limit}{extra}</joint>')


def _urdf(*elements: str) -> str:
    return '<?xml version="1.0"?>\n<robot name="test">\n' + "\n".join(elements) + "\n</robot>\n"


def _two_link(**changes: str) -> str:
    """base -> j1 -> l1; keyword arguments replace the pieces."""
    return _urdf(changes.get("base", _link("base")), changes.get("l1", _link("l1")),
                 changes.get("j1", _joint("j1", "base", "l1")))


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    return path


def _error(tmp_path: Path, text: str) -> str:
    path = _write(tmp_path, text)
    with pytest.raises(URDFError) as info:
        load_robot(path)
    message = str(info.value)
    assert str(path) in message, message
    assert "\n" not in message.strip(), message
    return message


# ---- the youBot --------------------------------------------------------------------------
def test_youbot_loads_with_joint_data() -> None:
    robot = load_robot(default_urdf())
    assert robot.model.nq == robot.model.nv == robot.nv == 11
    assert robot.joint_names[:5] == tuple(f"arm_joint_{i}" for i in range(1, 6))
    assert robot.root_link == "base_footprint"
    assert robot.end_effector == "gripper_palm_link"
    i = robot.joint_index("arm_joint_3")
    assert robot.lower[i] == pytest.approx(-5.1836279) and robot.upper[i] == 0.0
    assert robot.damping[i] == 1.0 and robot.friction[i] == 0.5 and robot.effort_limit[i] == 6.0
    wheel = robot.joint_index("wheel_joint_fl")
    assert robot.lower[wheel] == -np.inf and robot.upper[wheel] == np.inf
    assert isinstance(robot.model, pin.Model)
    with pytest.raises(UserInputError, match="unknown joint 'elbow'"):
        robot.joint_index("elbow")
    with pytest.raises(UserInputError, match="unknown frame 'nowhere'"):
        robot.frame_id("nowhere")


def test_loads_from_string_and_path(tmp_path: Path) -> None:
    text = _two_link()
    from_string, from_file = load_robot(text), load_robot(_write(tmp_path, text))
    assert from_string.joint_names == from_file.joint_names == ("j1",)
    assert from_file.source == str(tmp_path / "robot.urdf")


# ---- errors ------------------------------------------------------------------------------
def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "absent.urdf"
    with pytest.raises(URDFError, match=f"URDF file not found: {path}"):
        load_robot(path)


def test_malformed_xml(tmp_path: Path) -> None:
    message = _error(tmp_path, _two_link().replace("</robot>", "</robt>"))
    assert "malformed XML" in message


def test_unknown_joint_type(tmp_path: Path) -> None:
    message = _error(tmp_path, _two_link(j1=_joint("j1", "base", "l1", kind="spherical")))
    assert "joint 'j1'" in message and "unknown joint type 'spherical'" in message


@pytest.mark.parametrize("role", ["parent", "child"])
def test_missing_parent_or_child_link(tmp_path: Path, role: str) -> None:
    parent, child = ("ghost", "l1") if role == "parent" else ("base", "ghost")
    message = _error(tmp_path, _two_link(j1=_joint("j1", parent, child)))
    assert "joint 'j1'" in message and f"{role} link 'ghost' is not defined" in message


def test_joint_without_child_element(tmp_path: Path) -> None:
    text = _two_link().replace('<child link="l1"/>', "")
    message = _error(tmp_path, text)
    assert "joint 'j1'" in message and "missing <child" in message


@pytest.mark.parametrize("mass", ["0", "-2.5"])
def test_non_positive_mass(tmp_path: Path, mass: str) -> None:
    message = _error(tmp_path, _two_link(l1=_link("l1", mass=mass)))
    assert "link 'l1'" in message and "mass must be positive" in message and mass in message


def test_inertia_not_positive_definite(tmp_path: Path) -> None:
    inertia = '<inertia ixx="0.1" ixy="0.2" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'
    message = _error(tmp_path, _two_link(l1=_link("l1", inertia=inertia)))
    assert "link 'l1'" in message and "not positive definite" in message


def test_inertia_violates_triangle_inequality(tmp_path: Path) -> None:
    inertia = '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.5"/>'
    message = _error(tmp_path, _two_link(l1=_link("l1", inertia=inertia)))
    assert "link 'l1'" in message and "triangle inequality" in message


def test_lower_limit_above_upper(tmp_path: Path) -> None:
    limit = '<limit lower="1.5" upper="-0.5" effort="5" velocity="2"/>'
    message = _error(tmp_path, _two_link(j1=_joint("j1", "base", "l1", limit=limit)))
    assert "joint 'j1'" in message and "lower limit 1.5 is above upper limit -0.5" in message


def test_link_that_is_child_of_two_joints(tmp_path: Path) -> None:
    text = _urdf(_link("base"), _link("a"), _link("b"), _joint("ja", "base", "a"),
                 _joint("jb", "base", "b"), _joint("jc", "a", "b"))
    message = _error(tmp_path, text)
    assert "joint 'jc'" in message and "kinematic loop" in message and "'b'" in message


def test_kinematic_cycle(tmp_path: Path) -> None:
    # base -> a, and a cycle b -> c -> b: every link has one parent but c and b loop.
    text = _urdf(_link("base"), _link("a"), _link("b"), _link("c"), _joint("ja", "base", "a"),
                 _joint("jb", "c", "b"), _joint("jc", "b", "c"))
    message = _error(tmp_path, text)
    assert "kinematic loop" in message and ("'b'" in message or "'c'" in message)


def test_pure_cycle_without_root(tmp_path: Path) -> None:
    text = _urdf(_link("a"), _link("b"), _joint("jab", "a", "b"), _joint("jba", "b", "a"))
    message = _error(tmp_path, text)
    assert "kinematic loop" in message


def test_names_with_quotes_load() -> None:
    """The tree checks look links up by name, not through an XPath built from the names
    (which a quote in a joint name used to break with an lxml SyntaxError)."""
    robot = load_robot(_two_link(j1=_joint("elbow's joint", "base", "l1")))
    assert robot.joint_names == ("elbow's joint",)


def test_errors_are_user_input_errors() -> None:
    with pytest.raises(UserInputError):
        load_robot("/no/such/robot.urdf")


# ---- fidelity report ---------------------------------------------------------------------
def test_fidelity_report_lists_what_is_ignored(tmp_path: Path) -> None:
    text = _urdf(
        _link("base"), _link("l1"), _link("l2"), _link("l3"),
        '<link name="shell"><visual><geometry><mesh filename="package://x/shell.stl"/></geometry></visual></link>',
        _joint("j1", "base", "l1", extra='<safety_controller k_velocity="10"/>'),
        _joint("j2", "l1", "l2", extra='<mimic joint="j1" multiplier="2"/>'),
        _joint("wheel", "l2", "l3", kind="continuous", limit=""),
        _joint("free", "base", "shell", kind="floating", limit=""),
        '<transmission name="t1"><type>SimpleTransmission</type></transmission>',
        '<gazebo reference="l1"><material>Gazebo/Red</material></gazebo>',
    )
    robot = load_robot(_write(tmp_path, text))
    report = "\n".join(robot.fidelity)
    for expected in ("joint 'j2': <mimic> ignored", "joint 'j1': <safety_controller> ignored",
                     "joint 'wheel': continuous", "joint 'free': floating joint treated as fixed",
                     "1 <transmission> element(s) ignored", "1 <gazebo> element(s) ignored",
                     "1 mesh geometries not loaded", "link 'shell': no <inertial>"):
        assert expected in report, report
    # The mimic joint still moves on its own; the floating joint is not a coordinate.
    assert robot.joint_names == ("j1", "j2", "wheel")


def test_youbot_fidelity_report_mentions_continuous_wheels() -> None:
    report = "\n".join(load_robot(default_urdf()).fidelity)
    assert report.count("continuous") == 4


# ---- locking -----------------------------------------------------------------------------
def test_locking_reduces_nv_and_keeps_kinematics() -> None:
    robot = load_robot(default_urdf())
    wheels = {name: 0.3 * (i + 1) for i, name in enumerate(n for n in robot.joint_names if "wheel" in n)}
    fingers = {"gripper_finger_joint_l": 0.005, "gripper_finger_joint_r": 0.002}
    reduced = lock_joints(robot, {**wheels, **fingers})
    assert reduced.nv == reduced.model.nv == 5
    assert reduced.joint_names == tuple(f"arm_joint_{i}" for i in range(1, 6))
    assert reduced.locked == {**wheels, **fingers}
    np.testing.assert_array_equal(reduced.lower, robot.lower[:5])
    full_data, reduced_data = robot.model.createData(), reduced.model.createData()
    rng = np.random.default_rng(11)
    for _ in range(20):
        q_arm = rng.uniform(-3, 3, 5)
        q_full = robot.vector({**dict(zip(reduced.joint_names, q_arm)), **wheels, **fingers})
        pin.framesForwardKinematics(robot.model, full_data, q_full)
        pin.framesForwardKinematics(reduced.model, reduced_data, q_arm)
        for link in ("gripper_palm_link", "gripper_finger_link_l", "gripper_finger_link_r", "wheel_link_br"):
            np.testing.assert_allclose(reduced_data.oMf[reduced.frame_id(link)].homogeneous,
                                       full_data.oMf[robot.frame_id(link)].homogeneous, rtol=0, atol=1e-14)
    # The tree agrees: locked joints became fixed joints with the value folded in.
    kinds = {j.name: j.type for j in reduced.tree}
    assert all(kinds[name] == "fixed" for name in {**wheels, **fingers})


def test_keep_joints_defaults_to_zero_and_checks_names() -> None:
    robot = load_robot(default_urdf())
    arm = keep_joints(robot, ["arm_joint_2", "arm_joint_3"])
    assert arm.joint_names == ("arm_joint_2", "arm_joint_3") and arm.model.nv == 2
    assert set(arm.locked.values()) == {0.0}
    with pytest.raises(UserInputError, match="unknown joint 'arm_joint_9'"):
        keep_joints(robot, ["arm_joint_9"])
