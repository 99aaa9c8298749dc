"""The main job (README's `make run`): the dynamics node on the default scene, logs written,
summary printed. Run in its own process, in its own ROS domain, for a short simulated time."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from ros_support import domain_id
from youbot_dynamics.io.bag_reader import read_bag

pytestmark = pytest.mark.ros


def test_main_job_runs_the_default_scene_and_writes_its_logs(tmp_path):
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id(25)), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    result = subprocess.run([sys.executable, "-m", "youbot_dynamics", "main-job", "--duration", "0.2",
                             "--rate", "100", "--out", str(tmp_path)],
                            env=env, capture_output=True, text=True, timeout=180)
    assert result.returncode == 0, result.stderr
    summary = result.stdout
    assert "gripping" in summary and "real-time factor" in summary and "status            ok" in summary
    assert "None" not in summary
    counts: dict[str, int] = {}
    for message in read_bag(tmp_path / "gripping.mcap"):
        counts[message.topic] = counts.get(message.topic, 0) + 1
    assert counts["/joint_states"] == 21          # 0.2 s at 100 Hz, the t = 0 sample included
    assert counts["/free_bodies"] == 21 and counts["/tf_static"] == 1
    assert (tmp_path / "gripping.rrd").stat().st_size > 0
