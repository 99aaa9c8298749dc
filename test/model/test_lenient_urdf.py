"""What urdfdom forgives, forgiven: minimal reproductions of the shapes of real URDF files
(pybullet_data, ARMAR, Drake's) that urdfdom and Pinocchio load and a strict reader refused.

Each file loads, with a fixed and a floating root; its mass matrix and RNEA at a random state
agree with Pinocchio's own parse of the same text (``pin.buildModelFromXML``) to 1e-12; the
fidelity report says what was forgiven; and loading prints nothing on stderr (urdfdom's
complaints about visuals, collisions and materials never reach it)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.errors import URDFError
from youbot_dynamics.model.robot import Robot, load_robot

INERTIA = '<inertia ixx="0.1" ixy="0.01" ixz="0" iyy="0.2" iyz="0" izz="0.3"/>'
LIMIT = '<limit lower="-1" upper="1" effort="5" velocity="2"/>'


def _urdf(*, head: str = '<?xml version="1.0"?>\n', robot: str = "", base: str = "", tip: str = "",
          limit: str = LIMIT, name: str = "j1", tip_inertia: str = INERTIA) -> str:
    """A base, an arm on a revolute joint ``name`` and a tip on a prismatic joint."""
    return f"""{head}<robot name="r"{robot}>
  <link name="base"><inertial><origin xyz="0 0 0.1"/><mass value="3"/>{INERTIA}</inertial>{base}</link>
  <link name="arm"><inertial><origin xyz="0.2 0 0" rpy="0.1 0 0"/><mass value="1"/>{INERTIA}</inertial></link>
  <link name="tip"><inertial><origin xyz="0.05 0.02 0"/><mass value="0.5"/>{tip_inertia}</inertial>{tip}</link>
  <joint name="{name}" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.5" rpy="0.1 0.2 0.3"/><axis xyz="0 1 0"/>{limit}</joint>
  <joint name="j2" type="prismatic"><parent link="arm"/><child link="tip"/>
    <origin xyz="0.4 0 0"/><axis xyz="1 0 0"/><limit lower="0" upper="0.3" effort="50" velocity="1"/></joint>
</robot>
"""


CASES = {  # shape: (URDF text, a fragment of the fidelity note that says what was forgiven)
    "version 0.0": (_urdf(head='<?xml version="0.0" ?>\n'), "declared version '0.0' read as 1.0"),
    "blank line before the declaration": (_urdf(head='\n  <?xml version="1.0"?>\n'),
                                          "blank lines or spaces before the <?xml ...?> declaration"),
    "undeclared prefix": (_urdf(robot=' drake:declaration="x"', base='<drake:collision_filter_group name="g"/>',
                                tip='<visual drake:accepting_renderer="vtk"><geometry><box size="1 1 1"/></geometry>'
                                    '</visual>'), "prefix(es) 'drake' used without a declaration"),
    "inertial without inertia": (_urdf(tip_inertia=""), "link 'tip' (line 5): <inertial> has a <mass> and no <inertia>: a point mass"),
    "bad visual scale": (_urdf(base='<visual><geometry><mesh filename="base.stl" scale="0.001"/></geometry></visual>'),
                         'scale="0.001" is not 3 number(s) (in a <visual>, which urdfdom drops'),
    "lower above upper": (_urdf(limit='<limit lower="1" upper="-1" effort="5" velocity="2"/>'),
                          "<limit> lower 1 > upper -1, pybullet's way of saying no limit"),
    "unknown geometry": (_urdf(base='<collision><geometry><plane normal="0 0 1"/></geometry></collision>'),
                         "<collision> geometry <plane> is no URDF shape (urdfdom: \"Unknown geometry type\")"),
    "own root_joint": (_urdf(name="root_joint"), None),
}
ROOT_JOINTS = {"fixed": None, "floating": pin.JointModelFreeFlyer}


def _write(tmp_path: Path, text: str) -> Path:
    """The text as a file: read as bytes, as real files are (a str's declaration is dropped)."""
    path = tmp_path / "robot.urdf"
    path.write_bytes(text.encode())
    return path


def _pinocchio_reference(text: str, root: str) -> pin.Model:
    """Pinocchio's own parse of the text (urdfdom's leniency), with the root joint. The root
    joint is named 'world_joint': under its default name 'root_joint', Pinocchio 4.1 hangs the
    children of a URDF joint of that name on its free-flyer instead (mass matrices differ by
    1.1 on the "own root_joint" case), which is why ours takes a free name."""
    if root == "fixed":
        return pin.buildModelFromXML(text)
    return pin.buildModelFromXML(text, ROOT_JOINTS[root](), "world_joint")


@pytest.mark.parametrize("root", ROOT_JOINTS)
@pytest.mark.parametrize("shape", CASES)
def test_each_shape_loads_and_agrees_with_pinocchio(tmp_path: Path, capfd: pytest.CaptureFixture,
                                                    shape: str, root: str) -> None:
    text, note = CASES[shape]
    path = _write(tmp_path, text)
    capfd.readouterr()
    robot = load_robot(path, root=root)
    assert capfd.readouterr().err == ""  # urdfdom's complaints stay out of stderr
    if note is not None:
        assert any(note in line for line in robot.fidelity), robot.fidelity
    reference = _pinocchio_reference(text, root)
    assert robot.nq == reference.nq and robot.nv == reference.nv
    assert robot.joint_names == tuple(reference.names)[len(reference.names) - len(robot.joint_names):]
    rng = np.random.default_rng(abs(hash(shape)) % 2**32)
    q = pin.integrate(robot.model, pin.neutral(robot.model), rng.uniform(-1.0, 1.0, robot.nv))
    v, a = rng.uniform(-1.0, 1.0, robot.nv), rng.uniform(-1.0, 1.0, robot.nv)
    ours, theirs = robot.model.createData(), reference.createData()
    mass = pin.crba(robot.model, ours, q)
    mass_reference = pin.crba(reference, theirs, q)
    np.testing.assert_allclose(np.triu(mass), np.triu(mass_reference), rtol=0, atol=1e-12 * np.abs(mass_reference).max())
    tau, tau_reference = pin.rnea(robot.model, ours, q, v, a), pin.rnea(reference, theirs, q, v, a)
    np.testing.assert_allclose(tau, tau_reference, rtol=0, atol=1e-12 * np.abs(tau_reference).max())
    assert robot.mass_matrix_defect == ""


def test_inertial_without_inertia_is_a_point_mass(tmp_path: Path) -> None:
    """urdfdom keeps the <mass> and origin of an <inertial> without <inertia>: zero rotational
    inertia about the inertial origin."""
    robot = load_robot(_write(tmp_path, CASES["inertial without inertia"][0]))
    inertia = robot.model.inertias[robot.model.getJointId("j2")]
    assert inertia.mass == 0.5 and np.allclose(inertia.lever, [0.05, 0.02, 0.0])
    assert np.array_equal(inertia.inertia, np.zeros((3, 3)))


def test_reversed_limits_mean_no_limits(tmp_path: Path) -> None:
    robot = load_robot(_write(tmp_path, CASES["lower above upper"][0]))
    i = robot.joint_index("j1")
    assert robot.lower[i] == -np.inf and robot.upper[i] == np.inf
    assert robot.joints[i].type == "revolute" and robot.effort_limit[i] == 5.0
    j2 = robot.joint_index("j2")  # the other joint keeps its limits
    assert (robot.lower[j2], robot.upper[j2]) == (0.0, 0.3)


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_a_urdf_joint_named_root_joint_gives_the_root_joint_another_name(tmp_path: Path, root: str) -> None:
    """ARMAR-4 names its own fixed joint to the world 'root_joint', the name of our floating
    root: ours takes the next free name, the file's joint keeps its own."""
    text = _urdf(name="root_joint").replace('<joint name="j2"', '<joint name="root_joint_1" type="fixed">'
                                            '<parent link="tip"/><child link="flange"/></joint>\n  <joint name="j2"')
    text = text.replace('<link name="tip">', '<link name="flange"/>\n  <link name="tip">')
    robot = load_robot(_write(tmp_path, text), root=root)
    assert robot.model.names[1] == "root_joint_2" and robot.joint_names == ("root_joint", "j2")
    assert robot.fidelity[0].startswith(f"root: {root}: joint 'root_joint_2' (not 'root_joint': the URDF has a joint "
                                        "of that name) between the world and link 'base'")
    assert robot.frame_id("root_joint", kind="joint") != robot.frame_id("root_joint_2", kind="joint")


def test_line_numbers_survive_the_pre_pass(tmp_path: Path) -> None:
    """Blank lines before a version-0.0 declaration, a prefix declared on <robot>: an error
    further on still names its own line."""
    text = _urdf(head='\n\n<?xml version="0.0" ?>\n', robot=' drake:x="1"').replace('<axis xyz="1 0 0"/>',
                                                                                     '<axis xyz="1 0 z"/>')
    line = text[:text.index('<axis xyz="1 0 z"/>')].count("\n") + 1
    with pytest.raises(URDFError, match=rf"robot.urdf:{line}: joint 'j2': <axis>: xyz=\"1 0 z\""):
        load_robot(_write(tmp_path, text))


def test_what_the_pre_pass_cannot_mend_is_still_malformed_xml(tmp_path: Path) -> None:
    text = _urdf(head='<?xml version="0.0" ?>\n').replace("</robot>", "</robt>")
    with pytest.raises(URDFError, match="malformed XML"):
        load_robot(_write(tmp_path, text))


def test_a_file_that_parses_is_read_as_before(tmp_path: Path) -> None:
    """No pre-pass on a file the strict parser reads: no note, the same robot."""
    robot: Robot = load_robot(_write(tmp_path, _urdf()))
    assert not any(line.startswith("XML:") for line in robot.fidelity)
    assert robot.joint_names == ("j1", "j2")
