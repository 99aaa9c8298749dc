"""`colcon build` of this package in a temporary workspace, then what `ros2 run` does after
`source install/setup.bash`: the first AMENT_PREFIX_PATH entry holding
share/ament_index/resource_index/packages/youbot_dynamics is the workspace's, and
PREFIX/lib/youbot_dynamics/dynamics_node runs the node from there.

The venv must be on AMENT_PREFIX_PATH before install/setup.bash is sourced (as
/opt/ros/jazzy/setup.bash does on a ROS install), which these tests do."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ros_support import WAIT, domain_id

REPO = Path(__file__).resolve().parents[2]
COLCON = Path(sys.executable).parent / "colcon"
pytestmark = pytest.mark.skipif(not COLCON.is_file(), reason="colcon is not installed (requirements-build.txt)")


def in_workspace(workspace: Path, command: str, **env: str) -> subprocess.CompletedProcess:
    """``command`` in bash after sourcing the workspace's install/setup.bash, with the venv
    (first) on PATH and AMENT_PREFIX_PATH."""
    return subprocess.run(
        ["bash", "-c", f"source install/setup.bash && {command}"], cwd=workspace, capture_output=True, text=True,
        timeout=WAIT * 4, env={**os.environ, "AMENT_PREFIX_PATH": sys.prefix,
                               "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}", **env})


@pytest.fixture(scope="module", params=["copy", "symlink"])
def workspace(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A colcon workspace with this package in src/, built with `colcon build` or with
    `colcon build --symlink-install` (the usual development build: setup.py runs as a link
    in build/, so it must find its files through the link)."""
    root = tmp_path_factory.mktemp(f"ws_{request.param}")
    shutil.copytree(REPO, root / "src" / "youbot_dynamics", ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "install", "log", "out", "*.egg-info", "__pycache__", ".pytest_cache"))
    symlink = ["--symlink-install"] if request.param == "symlink" else []
    build = subprocess.run([str(COLCON), "build", "--base-paths", "src", *symlink], cwd=root, capture_output=True,
                           text=True, timeout=WAIT * 10,
                           env={**os.environ, "AMENT_PREFIX_PATH": sys.prefix,
                                "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"})
    assert build.returncode == 0, build.stdout + build.stderr
    assert "1 package finished" in build.stdout, build.stdout   # not interfaces/tf2_msgs: colcon stops at a package
    return root


def test_setup_bash_and_the_ament_index_find_the_node(workspace: Path) -> None:
    """After sourcing, the ament index resolves youbot_dynamics to the workspace's prefix
    (ahead of a pip install in the venv), with the executables under lib/ and the URDF
    under share/; rclpy still resolves to the venv."""
    code = ("import os, rclpy, youbot_dynamics\n"
            "from ament_index_python.packages import get_package_prefix, get_package_share_directory\n"
            "p = get_package_prefix('youbot_dynamics')\n"
            "print(p, get_package_share_directory('youbot_dynamics'), youbot_dynamics.__file__,"
            " get_package_prefix('rclpy'))")
    done = in_workspace(workspace, f"python -c \"{code}\"")
    assert done.returncode == 0, done.stderr
    prefix, share, module, rclpy_prefix = map(Path, done.stdout.split())
    install = workspace / "install" / "youbot_dynamics"
    assert prefix == install and share == install / "share" / "youbot_dynamics"
    assert (share / "urdf" / "youbot.urdf").is_file() and (share / "package.xml").is_file()
    # the installed copy; a symlink install links back to the source
    built = workspace / "src" / "youbot_dynamics" if workspace.name.startswith("ws_symlink") else install
    assert built in module.resolve().parents
    assert rclpy_prefix == Path(sys.prefix)
    for executable in ("dynamics_node", "replay_node"):
        assert os.access(install / "lib" / "youbot_dynamics" / executable, os.X_OK)


@pytest.mark.ros
def test_the_node_runs_from_the_workspace_as_ros2_run_would(workspace: Path) -> None:
    """The executable ros2 run would pick runs a short simulation and exits 0."""
    locate = ("$(python -c \"from ament_index_python.packages import get_package_prefix as g; "
              "print(g('youbot_dynamics'))\")/lib/youbot_dynamics/dynamics_node")
    done = in_workspace(workspace, f"{locate} --ros-args -p scene:=arm_swing -p duration:=0.05 -p time_scale:=0.0",
                        ROS_DOMAIN_ID=str(domain_id(29)), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    assert done.returncode == 0, done.stderr
    assert "simulate arm_swing" in done.stderr + done.stdout
