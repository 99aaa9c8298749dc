"""URDF text for the tests: minimal links and joints, a two-link robot, writing a file and
reading the one-line error it gives, and the malformed cases every URDF reader must name
(file, line, element); shared by test/model and test/cli."""
from __future__ import annotations

from pathlib import Path

import pytest

from youbot_dynamics.model.robot import URDFError, load_robot

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


def _line_of(text: str, fragment: str) -> int:
    """1-based line of the last occurrence of ``fragment`` in ``text``."""
    return text[:text.rindex(fragment)].count("\n") + 1


MALFORMED = {  # case: (replace this, with that, the element the message names, the line's marker)
    # (the element on a line of its own: the message gives the element's line, not its owner's)
    "mass without value": (_link("l1"), _link("l1").replace('<mass value="1.0"/>', "\n<mass/>"), "<mass>", "<mass/>"),
    "mass not a number": (_link("l1"), _link("l1", mass="heavy"), "<mass>", "heavy"),
    "axis not a number": ('<axis xyz="0 1 0"/>', '\n<axis xyz="0 0 z"/>', "<axis>", "0 0 z"),
    "origin of 2 numbers": ('<origin xyz="0 0 0.2" rpy="0 0 0"/>', '<origin xyz="0 0"/>', "<origin>", '"0 0"'),
    "inertia moment not finite": ('ixx="0.1"', 'ixx="nan"', "<inertia>", "nan"),
    "limit without effort": ('effort="5" ', "", "<limit>", "<limit"),
    "limit without velocity": ('velocity="2"', "", "<limit>", "<limit"),
    "duplicate link": (_link("l1"), _link("l1") + "\n" + _link("l1"), "link 'l1'", '<link name="l1">'),
    "duplicate joint": ("</robot>", _joint("j1", "l1", "base", kind="fixed", limit="") + "\n</robot>",
                        "joint 'j1'", '<joint name="j1"'),
    "robot without name": ('<robot name="test">', "<robot>", "<robot>", "<robot>"),
}
