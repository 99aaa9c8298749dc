"""Every start-up error of the dynamics node is one line on stderr and exit status 2 (no
traceback): logs that cannot be written (a read-only folder, a directory at mcap_path),
parameters of the wrong type or out of range, an unknown mode or scene, unknown ROS
arguments. The node runs as a subprocess; its timeout is a hang guard only."""
from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

pytestmark = [pytest.mark.ros, pytest.mark.timeout(600)]

REPO = Path(__file__).resolve().parents[2]
HANG_GUARD = 120.0
"""Seconds a refused start may take before the test gives up (a hang guard, not a speed bound)."""


def start(tmp_path: Path, *ros_args: str) -> subprocess.CompletedProcess:
    from ros_support import domain_id

    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id(24)), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    return subprocess.run([sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", *ros_args,
                           "-p", "duration:=0.01", "-p", "time_scale:=0.0"],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=HANG_GUARD, check=False)


def assert_refused(result: subprocess.CompletedProcess, *words: str) -> None:
    lines = result.stderr.splitlines()
    assert result.returncode == 2 and len(lines) == 1, (result.returncode, result.stderr)
    assert lines[0].startswith("dynamics_node: error: ") and all(word in lines[0] for word in words), lines[0]


@contextlib.contextmanager
def read_only_folder(tmp_path: Path) -> Iterator[Path]:
    """A folder nothing can be written in: a read-only tmpfs where the test may mount one
    (root), else a folder without write permission (which root would ignore)."""
    folder = tmp_path / "read_only"
    folder.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(folder)],
                             capture_output=True, check=False).returncode == 0 if os.geteuid() == 0 else False
    if not mounted:
        if os.geteuid() == 0:
            pytest.skip("root without permission to mount a read-only tmpfs")
        folder.chmod(0o555)
    try:
        yield folder
    finally:
        if mounted:
            subprocess.run(["umount", str(folder)], check=True)
        else:
            folder.chmod(0o755)


def test_logs_that_cannot_be_written_are_one_line(tmp_path: Path) -> None:
    with read_only_folder(tmp_path) as folder:
        assert_refused(start(tmp_path, "-p", f"mcap_path:={folder / 'run.mcap'}"), "mcap_path", str(folder))
        assert_refused(start(tmp_path, "-p", f"rrd_path:={folder / 'sub' / 'run.rrd'}"), "rrd_path", str(folder))
    directory = tmp_path / "run.mcap"
    directory.mkdir()
    assert_refused(start(tmp_path, "-p", f"mcap_path:={directory}"), "mcap_path", "Is a directory")


@pytest.mark.parametrize(("argument", "words"), [
    ("publish_rate:=abc", ("publish_rate", "abc")),
    ("publish_rate:=5000.0", ("publish_rate", "out of range")),
    ("mode:=dance", ("mode", "dance")),
    ("scene:=no_such_scene", ("scene", "no_such_scene")),
])
def test_bad_parameters_are_one_line(tmp_path: Path, argument: str, words: tuple[str, ...]) -> None:
    assert_refused(start(tmp_path, "-p", argument), *words)


def test_unknown_ros_arguments_are_one_line(tmp_path: Path) -> None:
    assert_refused(start(tmp_path, "--bogus"), "bad ROS arguments", "--bogus")
