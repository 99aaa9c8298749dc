"""URDF -> Robot: the youBot's contents, every validation error (naming file, line, element
and reason), what loads as urdfdom loads it (zero masses, round-off inertias, any encoding),
warnings and strict loading, the mass-matrix check, frames by type, mimic joints, the
fidelity report and joint locking."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.dynamics.rigid_body import forward_dynamics, inverse_dynamics
from youbot_dynamics.errors import SingularMassMatrixError, UserInputError
from youbot_dynamics.model.fidelity import INERTIA_RTOL
from youbot_dynamics.model.robot import URDFError, keep_joints, load_robot, lock_joints

from test_example_robots import URDFS
from urdf_support import MALFORMED, _error, _joint, _line_of, _link, _two_link, _urdf, _write

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
    with pytest.raises(UserInputError, match="unknown frame 'nowhere': no link of that name"):
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


ZERO = '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>'


@pytest.mark.parametrize("case", MALFORMED)
def test_malformed_file_names_file_line_and_element(tmp_path: Path, case: str) -> None:
    old, new, element, marker = MALFORMED[case]
    text = _two_link().replace(old, new, 1)
    message = _error(tmp_path, text)
    assert f"{tmp_path / 'robot.urdf'}:{_line_of(text, marker)}:" in message and element in message, message


def test_zero_mass_links_and_point_masses_load_without_warnings(tmp_path: Path) -> None:
    """urdfdom and Pinocchio load both: a massless sensor link on a fixed joint and a point
    mass (mass > 0, inertia 0) at a distance from the joint axis."""
    point = '<link name="l1"><inertial><origin xyz="0.3 0 0"/><mass value="2"/>' + ZERO + "</inertial></link>"
    sensor = '<link name="imu"><inertial><mass value="0"/>' + ZERO + "</inertial></link>"
    robot = load_robot(_urdf(_link("base"), point, sensor, _joint("j1", "base", "l1"),
                             _joint("imu_joint", "l1", "imu", kind="fixed", limit="")))
    assert robot.warnings == () and robot.mass_matrix_defect == ""
    assert robot.model.inertias[1].mass == 2.0


@pytest.mark.parametrize("izz, warns", [(-2.5e-22, False), (-0.9 * INERTIA_RTOL * 3e-6, False),
                                        (-1.1 * INERTIA_RTOL * 3e-6, True)])
def test_round_off_principal_moment_counts_as_zero(izz: float, warns: bool) -> None:
    """A thin rod along z: principal moments (0, 3e-6, 3e-6) kg m^2, legal; the file's 0
    comes out as round-off such as -2.5e-22. A moment within INERTIA_RTOL of the largest one
    counts as zero; one beyond it is a warning."""
    inertia = f'<inertia ixx="3e-6" ixy="0" ixz="0" iyy="3e-6" iyz="0" izz="{izz!r}"/>'
    robot = load_robot(_two_link(l1=_link("l1", inertia=inertia)))
    assert bool(robot.warnings) == warns, robot.warnings


def test_invalid_inertias_are_warnings_naming_every_link(tmp_path: Path) -> None:
    negative = '<inertia ixx="0.1" ixy="0.2" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'  # moments -0.1, 0.1, 0.3
    triangle = '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.5"/>'  # 0.1 + 0.1 < 0.5
    text = _urdf(_link("base"), _link("l1", inertia=negative), _link("l2", inertia=triangle),
                 _link("l3", mass="-2.5"), _joint("j1", "base", "l1"), _joint("j2", "l1", "l2"),
                 _joint("j3", "l2", "l3"))
    path = _write(tmp_path, text)
    robot = load_robot(path)
    found = "\n".join(robot.warnings)
    for link, reason in (("l1", "negative principal moment"), ("l2", "triangle inequality"),
                         ("l3", "negative mass -2.5 kg")):
        line = _line_of(text, f'<link name="{link}">')
        assert f"link '{link}' (line {line}): " in found and reason in found, found
    assert all(w in robot.fidelity for w in robot.warnings[:3])
    with pytest.raises(URDFError) as info:
        load_robot(path, strict=True)
    message = str(info.value)
    assert message.startswith(f"{path}: strict loading refuses ") and "\n" not in message
    assert all(f"link '{link}'" in message for link in ("l1", "l2", "l3"))


def test_singular_mass_matrix_names_the_massless_joints_and_refuses_forward_dynamics() -> None:
    """j2 carries a massless link: M is singular. ABA would return inf or NaN; forward
    dynamics refuses with the joint's name. Inverse dynamics stays defined; locking j2 (or
    strict loading) resolves it."""
    text = _urdf(_link("base"), _link("l1"), '<link name="l2"/>', _joint("j1", "base", "l1"),
                 _joint("j2", "l1", "l2"))
    robot = load_robot(text)
    assert "no mass moves with joint(s) 'j2'" in robot.mass_matrix_defect
    assert robot.warnings[-1].endswith(robot.mass_matrix_defect)
    data, zero = robot.model.createData(), np.zeros(2)
    with pytest.raises(SingularMassMatrixError, match="'j2'"):
        forward_dynamics(robot, data, zero, zero, zero)
    assert np.all(np.isfinite(inverse_dynamics(robot, data, zero, zero, zero)))
    assert keep_joints(robot, ["j1"]).mass_matrix_defect == ""
    with pytest.raises(URDFError, match="no mass moves with joint"):
        load_robot(text, strict=True)


@pytest.mark.parametrize("declaration", ['<?xml version="1.0" encoding="utf-8"?>',
                                         "<?xml version='1.0' encoding='ISO-8859-1'?>", ""])
def test_any_encoding_declaration(tmp_path: Path, declaration: str) -> None:
    """A str with an encoding declaration used to break lxml and yourdfpy; a file is read as
    bytes in its declared encoding (the robot name holds a non-ASCII letter)."""
    body = _two_link().split("\n", 1)[1].replace('name="test"', 'name="r\u00f6bot"')
    text = declaration + "\n" + body
    encoding = "iso-8859-1" if "ISO" in declaration else "utf-8"
    path = tmp_path / "robot.urdf"
    path.write_bytes(text.encode(encoding))
    for source in (text, path):
        robot = load_robot(source)
        assert robot.name == "r\u00f6bot" and robot.joint_names == ("j1",)
    # Line numbers survive the dropped declaration.
    bad = text.replace('<axis xyz="0 1 0"/>', '<axis xyz="0 0 z"/>')
    line = _line_of(bad, '<axis xyz="0 0 z"/>')
    with pytest.raises(URDFError, match=f":{line}: joint 'j1'"):
        load_robot(bad)


def test_fixed_joint_with_zero_axis_stores_no_nan() -> None:
    """tiago_pro and Talos give fixed joints <axis xyz="0 0 0"/>: no NaN, no RuntimeWarning."""
    fixed = _joint("mount", "l1", "tool", kind="fixed", limit="").replace('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>')
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = load_robot(_urdf(_link("base"), _link("l1"), _link("tool"), _joint("j1", "base", "l1"), fixed))
    mount = next(j for j in robot.tree if j.name == "mount")
    assert np.all(np.isfinite(mount.axis)) and np.linalg.norm(mount.axis) == 1.0


def test_frames_by_type_when_a_link_and_a_joint_share_a_name() -> None:
    """z1, anymal_c, b1-z1 and so100 name a link like a joint: link look-ups find the link."""
    robot = load_robot(_urdf(_link("base"), _link("elbow"), _joint("elbow", "base", "elbow")))
    link, joint = robot.frame_id("elbow"), robot.frame_id("elbow", kind="joint")
    assert link != joint
    assert robot.model.frames[link].type == pin.FrameType.BODY
    assert robot.model.frames[joint].type == pin.FrameType.JOINT
    with pytest.raises(UserInputError, match="unknown frame 'base': no joint of that name"):
        robot.frame_id("base", kind="joint")


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
    for expected in ("joint 'j2': mimics 'j1' (q = 2 q_j1 + 0)", "joint 'j1': <safety_controller> ignored",
                     "joint 'wheel': continuous", "joint 'free': floating joint treated as fixed",
                     "1 <transmission> element(s) ignored", "1 <gazebo> element(s) ignored",
                     "1 mesh geometries not loaded", "link 'shell': no <inertial>"):
        assert expected in report, report
    # The mimic joint follows j1; the floating joint is not a coordinate.
    assert robot.joint_names == ("j1", "wheel")


def test_fidelity_report_lists_contact_control_sensors_and_collision_shapes() -> None:
    """solo, bolt and anymal carry PyBullet <contact> values; ros2_control, sensors and
    collision primitives are not modelled either: the report says so."""
    foot = ('<link name="foot"><contact><lateral_friction value="1"/><restitution value="0.5"/></contact>'
            '<collision><geometry><sphere radius="0.02"/></geometry></collision>'
            '<collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>')
    text = _urdf(_link("base").replace("</link>", '<collision><geometry><box size="1 1 1"/></geometry>'
                                                  '</collision></link>'),
                 _link("l1"), foot, _joint("j1", "base", "l1"), _joint("ankle", "l1", "foot", kind="fixed", limit=""),
                 '<ros2_control name="arm_hw" type="system"><joint name="j1"/></ros2_control>',
                 '<gazebo reference="foot"><sensor name="touch" type="contact"/></gazebo>')
    report = "\n".join(load_robot(text).fidelity)
    for expected in ("link 'foot': <contact> (lateral_friction 1, restitution 0.5) ignored",
                     "1 <ros2_control> element(s) ignored: 'arm_hw'", "1 <sensor> element(s) ignored",
                     "<collision> geometry not used (contact shapes come from the scene): 2 box, 1 sphere"):
        assert expected in report, report


def test_tiago_pro_fingers_follow_their_motor_joint() -> None:
    """tiago_pro's 10 finger joints mimic the two gripper joints: they are no coordinates
    (they used to fall freely), and forward dynamics runs through the mimic solve."""
    path = next((p for p in URDFS if p.name == "tiago_pro.urdf"), None)
    assert path is not None, "example-robot-data is not installed"
    robot = load_robot(path)
    assert len(robot.mimic) == 10 and robot.nv == 23 == robot.model.nv
    assert {m.primary for m in robot.mimic.values()} == {"gripper_left_finger_joint", "gripper_right_finger_joint"}
    assert not set(robot.mimic) & set(robot.joint_names)
    q = np.zeros(robot.nv)
    a = forward_dynamics(robot, robot.model.createData(), q, q, q)
    assert a.shape == (23,) and np.all(np.isfinite(a))


def test_mimic_chains_unknown_primaries_and_primaries_below() -> None:
    """A mimic of a mimic resolves to the independent joint (q_c = 3 (2 q_a + 0.1) - 0.2); a
    <mimic> of no joint is a warning (urdfdom loads it; alex_psyonic_hands has 8); a mimic
    above its primary in Pinocchio's order (Talos' grippers, Romeo's hands) moves on its own,
    as Pinocchio cannot hold it."""
    def mimic(primary: str, multiplier: str = "1", offset: str = "0") -> str:
        return f'<mimic joint="{primary}" multiplier="{multiplier}" offset="{offset}"/>'
    text = _urdf(_link("base"), *(_link(name) for name in ("la", "lb", "lc", "ld", "le", "lf")),
                 _joint("a", "base", "la"), _joint("b", "la", "lb", extra=mimic("a", "2", "0.1")),
                 _joint("c", "lb", "lc", extra=mimic("b", "3", "-0.2")),
                 _joint("d", "lc", "ld", extra=mimic("ghost")),
                 _joint("e", "base", "le", extra=mimic("f")), _joint("f", "le", "lf"))
    robot = load_robot(text)
    c = robot.mimic["c"]
    assert (c.primary, c.multiplier, c.offset) == ("a", 6.0, pytest.approx(0.1))
    assert set(robot.mimic) == {"b", "c"} and robot.joint_names == ("a", "d", "e", "f")
    assert any("joint 'd' (line" in w and "names no other moving joint" in w for w in robot.warnings)
    assert any("joint 'e': <mimic> of 'f' ignored" in note for note in robot.fidelity)


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
