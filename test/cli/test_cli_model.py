"""The model sub-commands through youbot_dynamics.cli.main: tables, JSON checked against
Pinocchio, joint values in order and by name, and bad arguments (exit 2, one line)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.cli import main
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.model.robot import Robot, load_robot

from urdf_support import MALFORMED, _line_of, _two_link

Q_ORDER = "-0.3,1.1,-0.9,0.8,2.0,0.004,0.006,0.5,-0.5,1.5,2.5"
Q_NAMED = "arm_joint_2=1.1,arm_joint_4=0.8"


@pytest.fixture(scope="module")
def robot() -> Robot:
    return load_robot(default_urdf())


def _json(capsys: pytest.CaptureFixture[str], argv: list[str]) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _text(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 0
    return capsys.readouterr().out


def _q(text: str, robot: Robot) -> np.ndarray:
    if "=" in text:
        return robot.vector({k: float(v) for k, v in (p.split("=") for p in text.split(","))})
    return np.array([float(x) for x in text.split(",")])


def test_info(capsys: pytest.CaptureFixture[str], robot: Robot) -> None:
    record = _json(capsys, ["info"])
    assert [j["name"] for j in record["joints"]] == list(robot.joint_names)
    assert record["nv"] == robot.model.nv == 11 and record["end_effector"] == "gripper_palm_link"
    arm3 = record["joints"][2]
    assert (arm3["lower"], arm3["upper"], arm3["damping"], arm3["friction"]) == (-5.1836279, 0.0, 1.0, 0.5)
    wheel = record["joints"][robot.joint_index("wheel_joint_fl")]
    assert wheel["type"] == "continuous" and wheel["lower"] is None
    assert any("continuous" in note for note in record["fidelity"])
    text = _text(capsys, ["info"])
    assert "arm_joint_5" in text and "fidelity report" in text and "5.8468530"[:8] in text


@pytest.mark.parametrize("q_text", [Q_ORDER, Q_NAMED])
@pytest.mark.parametrize("frame", [None, "gripper_finger_link_l", "arm_link_2"])
def test_fk_against_pinocchio(capsys: pytest.CaptureFixture[str], robot: Robot, q_text: str,
                              frame: str | None) -> None:
    # The --q=... form: Q_ORDER starts with a minus sign.
    argv = ["fk", f"--q={q_text}"] + (["--frame", frame] if frame else [])
    record = _json(capsys, argv)
    link = frame or robot.end_effector
    assert record["frame"] == link and record["reference_frame"] == "base_footprint"
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, _q(q_text, robot))
    placement = data.oMf[robot.frame_id(link)]
    np.testing.assert_allclose(record["position"], placement.translation, atol=1e-12)
    np.testing.assert_allclose(record["rotation"], placement.rotation, atol=1e-12)
    reference = pin.Quaternion(placement.rotation).coeffs()  # (x, y, z, w)
    np.testing.assert_allclose(abs(np.dot(record["quaternion_xyzw"], reference)), 1.0, atol=1e-12)
    text = _text(capsys, argv)
    assert f"{placement.translation[0]:.6f}"[:7] in text and "quaternion (x, y, z, w)" in text


def test_screws(capsys: pytest.CaptureFixture[str], robot: Robot) -> None:
    record = _json(capsys, ["screws"])
    assert record["joints"] == [f"arm_joint_{i}" for i in range(1, 6)] and record["order"] == "omega, v"
    S, M = np.array(record["S"]).T, np.array(record["M"])
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.zeros(robot.nv))
    np.testing.assert_allclose(M, data.oMf[robot.frame_id("gripper_palm_link")].homogeneous, atol=1e-12)
    world = pin.computeFrameJacobian(robot.model, data, np.zeros(robot.nv),
                                     robot.frame_id("gripper_palm_link"), pin.WORLD)
    np.testing.assert_allclose(S, np.vstack([world[3:], world[:3]])[:, :5], atol=1e-12)  # J_s(0) = S
    text = _text(capsys, ["screws", "--frame", "wheel_link_fl"])
    assert "wheel_joint_fl" in text and "arm_joint_1" not in text


@pytest.mark.parametrize("kind", ["space", "body", "world", "local", "local_world_aligned"])
def test_jacobian_kinds(capsys: pytest.CaptureFixture[str], robot: Robot, kind: str) -> None:
    record = _json(capsys, ["jacobian", "--kind", kind, f"--q={Q_ORDER}", "--frame", "gripper_finger_link_r"])
    frame = robot.frame_id("gripper_finger_link_r")
    reference_frame = {"space": pin.WORLD, "body": pin.LOCAL, "world": pin.WORLD, "local": pin.LOCAL,
                       "local_world_aligned": pin.LOCAL_WORLD_ALIGNED}[kind]
    reference = pin.computeFrameJacobian(robot.model, robot.model.createData(), _q(Q_ORDER, robot),
                                         frame, reference_frame)
    matrix = np.array(record["matrix"])
    if kind in ("space", "body"):
        assert record["rows"] == ["wx", "wy", "wz", "vx", "vy", "vz"]
        columns = [robot.joint_index(name) for name in record["columns"]]
        assert record["columns"][-1] == "gripper_finger_joint_r" and len(columns) == 6
        reference = np.vstack([reference[3:], reference[:3]])[:, columns]
    else:
        assert record["rows"] == ["vx", "vy", "vz", "wx", "wy", "wz"]
        assert record["columns"] == list(robot.joint_names)
    np.testing.assert_allclose(matrix, reference, atol=1e-12)
    assert "rows" in record["convention"]
    assert "columns: joints" in _text(capsys, ["jacobian", "--kind", kind])


def test_inverse_and_forward_dynamics(capsys: pytest.CaptureFixture[str], robot: Robot) -> None:
    q, v = Q_ORDER, "arm_joint_1=0.4,arm_joint_3=-0.2,gripper_finger_joint_l=0.01"
    record = _json(capsys, ["id", f"--q={q}", "--v", v, "--a", "arm_joint_2=1.5"])
    q_vec, v_vec = _q(q, robot), _q(v, robot)
    a_vec = robot.vector({"arm_joint_2": 1.5})
    data = robot.model.createData()
    expected = pin.rnea(robot.model, data, q_vec, v_vec, a_vec) + JointFriction.from_urdf(robot).torque(v_vec)
    tau = np.array([record["tau"][name] for name in robot.joint_names])
    np.testing.assert_allclose(tau, expected, atol=1e-12)
    assert record["friction"] is True and record["v"]["arm_joint_1"] == 0.4
    # fd with that torque gives back a.
    tau_text = ",".join(repr(float(x)) for x in tau)
    record = _json(capsys, ["fd", f"--q={q}", "--v", v, f"--tau={tau_text}"])
    a = np.array([record["a"][name] for name in robot.joint_names])
    np.testing.assert_allclose(a, a_vec, atol=1e-8)
    # Without friction: bare Pinocchio.
    record = _json(capsys, ["fd", f"--q={q}", "--v", v, "--no-friction"])
    bare = pin.aba(robot.model, data, q_vec, v_vec, np.zeros(robot.nv))
    np.testing.assert_allclose([record["a"][n] for n in robot.joint_names], bare, atol=1e-10)
    assert record["friction"] is False
    assert "tau (N m or N), with URDF joint friction" in _text(capsys, ["id"])
    assert "a (rad/s^2 or m/s^2), without URDF joint friction" in _text(capsys, ["fd", "--no-friction"])


def _one_joint(tmp_path: Path) -> Path:
    """A 1-DoF pendulum: 2 kg at 0.5 m from a hinge about y, 1 m above the root."""
    path = tmp_path / "one.urdf"
    path.write_text('<robot name="one"><link name="a"/><link name="b"><inertial><mass value="2"/>'
                    '<origin xyz="0.5 0 0"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" '
                    'izz="0.1"/></inertial></link><joint name="hinge" type="revolute"><parent link="a"/>'
                    '<child link="b"/><origin xyz="0 0 1"/><axis xyz="0 1 0"/><limit lower="-3" '
                    'upper="3" effort="1" velocity="1"/></joint></robot>')
    return path


def test_other_urdf(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = _one_joint(tmp_path)
    record = _json(capsys, ["fk", "--urdf", str(path), "--q", "hinge=0.5"])
    assert record["frame"] == "b"
    np.testing.assert_allclose(record["position"], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(record["rotation"][0], [np.cos(0.5), 0, np.sin(0.5)], atol=1e-15)
    record = _json(capsys, ["id", "--urdf", str(path), "--no-friction"])
    # Gravity torque of 2 kg at 0.5 m about y: -m g r (sign: the mass hangs along +x).
    assert record["tau"]["hinge"] == pytest.approx(-2 * 9.81 * 0.5, rel=1e-12)


@pytest.mark.parametrize("argv, words", [
    (["fk", "--q", "arm_joint_9=1"], ["--q", "unknown joint 'arm_joint_9'"]),
    (["fk", "--q", "0.1,0.2"], ["--q", "expected 11 values", "got 2"]),
    (["jacobian", "--q", "0.1,abc"], ["--q", "'abc' is not a number"]),
    (["id", "--v", "arm_joint_1=fast"], ["--v", "'fast' is not a number"]),
    (["fd", "--tau", "1,arm_joint_2=3"], ["--tau", "not a mix"]),
    (["fk", "--frame", "moon"], ["unknown link 'moon'"]),
    (["jacobian", "--kind", "world", "--frame", "moon"], ["unknown link 'moon'"]),
    (["screws", "--urdf", "/no/such/robot.urdf"], ["URDF file not found: /no/such/robot.urdf"]),
    (["info", "--urdf", "/no/such/robot.urdf"], ["URDF file not found"]),
    # Overflow: --json must not print null torques nor numpy's RuntimeWarnings.
    (["id", "--json", "--v", "arm_joint_1=1e308,arm_joint_2=1e308"], ["tau overflows", "arm_joint_1"]),
    (["fd", "--json", "--tau", "arm_joint_1=1e308,arm_joint_2=-1e308"], ["a overflows", "arm_joint_2"]),
    (["fd", "--root", "floating", "--v", "root_vx=1e308"], ["a overflows", "root_vx"]),
])
def test_bad_arguments(capsys: pytest.CaptureFixture[str], argv: list[str], words: list[str]) -> None:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"youbot-dynamics {argv[0]}: error: ")
    for word in words:
        assert word in lines[0]


@pytest.mark.parametrize("kind", ["space", "body", "world", "local", "local_world_aligned"])
def test_one_joint_jacobian_is_6_by_1(capsys: pytest.CaptureFixture[str], tmp_path: Path, kind: str) -> None:
    """Pinocchio hands a 1-DoF robot's frame Jacobian back as a flat array; ours stays 6 x nv."""
    path = _one_joint(tmp_path)
    record = _json(capsys, ["jacobian", "--urdf", str(path), "--kind", kind, "--q", "0.5"])
    matrix = np.array(record["matrix"])
    assert matrix.shape == (6, 1) and record["columns"] == ["hinge"]
    # The hinge's axis is y in every convention: omega = (0, 1, 0).
    omega = matrix[:3, 0] if kind in ("space", "body") else matrix[3:, 0]
    np.testing.assert_allclose(omega, [0, 1, 0], atol=1e-15)
    assert "hinge" in _text(capsys, ["jacobian", "--urdf", str(path), "--kind", kind])


def _one_error_line(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert captured.out == "" and len(lines) == 1, captured.err
    assert lines[0].startswith(f"youbot-dynamics {argv[0]}: error: ")
    return lines[0]


@pytest.mark.parametrize("case", MALFORMED)
def test_malformed_urdf_is_one_line_with_file_line_and_element(capsys: pytest.CaptureFixture[str],
                                                                tmp_path: Path, case: str) -> None:
    old, new, element, marker = MALFORMED[case]
    text = _two_link().replace(old, new, 1)
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    line = _one_error_line(capsys, ["info", "--urdf", str(path)])
    assert f"{path}:{_line_of(text, marker)}:" in line and element in line


def test_strict_refuses_what_info_reports(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    triangle = '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.5"/>'
    text = _two_link().replace('<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>', triangle)
    path = tmp_path / "triangle.urdf"
    path.write_text(text)
    record = _json(capsys, ["info", "--urdf", str(path)])
    assert len(record["warnings"]) == 2 and all("triangle inequality" in w for w in record["warnings"])
    assert "warning: link 'l1'" in _text(capsys, ["info", "--urdf", str(path)])
    line = _one_error_line(capsys, ["info", "--urdf", str(path), "--strict"])
    assert f"{path}: strict loading refuses 2 warning(s)" in line and "link 'base'" in line


@pytest.mark.parametrize("json_flag", [[], ["--json"]])
def test_fd_refuses_a_singular_mass_matrix(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                           json_flag: list[str]) -> None:
    """A moving joint carrying a massless link: ABA would print a = -inf (and --json crashed
    on it); fd refuses, naming the joint. id stays defined."""
    text = _two_link().replace(_two_link().split("\n")[3], '<link name="l1"/>')
    path = tmp_path / "massless.urdf"
    path.write_text(text)
    line = _one_error_line(capsys, ["fd", "--urdf", str(path), *json_flag])
    assert "no mass moves with joint(s) 'j1'" in line and str(path) in line
    assert _json(capsys, ["id", "--urdf", str(path), "--no-friction"])["tau"] == {"j1": 0.0}


def test_info_refuses_magnitudes_beyond_the_bounds(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # A mass of 1e308 must not pass `info` (the node would die on an infinite energy).
    path = tmp_path / "heavy.urdf"
    path.write_text(_two_link(l1='<link name="l1"><inertial><mass value="1e308"/><inertia ixx="0.1" ixy="0" '
                                 'ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>'))
    assert main(["info", "--urdf", str(path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and f"{path}:" in lines[0] and "<mass>" in lines[0] and "bound 1e+06 kg" in lines[0]
