"""A real, non-editable install makes a valid ament prefix, found the way `ros2 run` looks.

`ros2 run PKG EXE` takes the first AMENT_PREFIX_PATH entry holding
share/ament_index/resource_index/packages/PKG and runs PREFIX/lib/PKG/EXE.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def prefix(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Install the package (no dependencies) into a fresh prefix, as pip does into a venv."""
    target = tmp_path_factory.mktemp("prefix")
    source = tmp_path_factory.mktemp("source") / "youbot_dynamics"
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "out", "*.egg-info", "__pycache__", ".pytest_cache"))
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--prefix", str(target), str(source)],
        check=True, cwd=source, env={**os.environ, "PIP_NO_INPUT": "1"},
    )
    return target


def site_packages(prefix: Path) -> Path:
    relative = Path(sysconfig.get_path("purelib")).relative_to(sysconfig.get_path("data"))
    return prefix / relative


def installed_env(prefix: Path) -> dict[str, str]:
    return {**os.environ, "AMENT_PREFIX_PATH": str(prefix),
            "PYTHONPATH": os.pathsep.join([str(site_packages(prefix)), *sys.path[1:]])}


def test_ament_index_finds_the_installed_package(prefix: Path) -> None:
    code = (
        "from ament_index_python.packages import get_package_prefix, get_package_share_directory\n"
        "print(get_package_prefix('youbot_dynamics')); print(get_package_share_directory('youbot_dynamics'))"
    )
    out = subprocess.run([sys.executable, "-c", code], env=installed_env(prefix), cwd=prefix,
                         check=True, capture_output=True, text=True).stdout.split()
    assert Path(out[0]) == prefix
    share = Path(out[1])
    assert share == prefix / "share" / "youbot_dynamics"
    assert (share / "package.xml").is_file()
    assert (share / "urdf" / "youbot.urdf").is_file()
    assert (share / "config").is_dir()
    assert (prefix / "share/ament_index/resource_index/packages/youbot_dynamics").is_file()


def test_executables_live_where_ros2_run_looks_and_run(prefix: Path) -> None:
    executable = prefix / "lib" / "youbot_dynamics" / "youbot-dynamics"
    assert executable.is_file() and os.access(executable, os.X_OK)
    result = subprocess.run([sys.executable, str(executable), "info", "--json"], env=installed_env(prefix),
                            cwd=prefix, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert '"arm_joint_1"' in result.stdout


def test_installed_package_uses_the_installed_urdf(prefix: Path) -> None:
    code = "import youbot_dynamics; print(youbot_dynamics.default_urdf())"
    out = subprocess.run([sys.executable, "-c", code], env=installed_env(prefix), cwd=prefix,
                         check=True, capture_output=True, text=True).stdout.strip()
    assert Path(out) == prefix / "share" / "youbot_dynamics" / "urdf" / "youbot.urdf"
