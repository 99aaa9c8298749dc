"""package.xml names every ROS interface package the code uses: each `pkg.msg` import and
each `pkg/msg/Type` name (the logs' and the rosbags typestore's) in youbot_dynamics/ is an
exec_depend, so rosdep installs what the node publishes, subscribes to and logs."""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
INTERFACE = re.compile(r"\b([a-z0-9_]+(?:_msgs|_interfaces|_srvs))[/.](?:msg|srv|action)\b")


def interface_packages() -> set[str]:
    """Every ROS interface package that a source file of the package names."""
    return {match for path in (REPO / "youbot_dynamics").rglob("*.py")
            for match in INTERFACE.findall(path.read_text())}


def test_every_interface_package_the_code_uses_is_an_exec_depend() -> None:
    declared = {element.text for element in ET.parse(REPO / "package.xml").getroot().iter("exec_depend")}
    used = interface_packages()
    assert {"sensor_msgs", "tf2_msgs", "nav_msgs", "visualization_msgs"} <= used  # the scan sees them
    assert used - declared == set(), f"used but not in package.xml: {sorted(used - declared)}"
