"""A node on a scene whose integrator used to hang: the arm_swing scene with a
gravity of 1e308 m/s^2 made scipy's DOP853 step loop for ever on a NaN step size,
inside the node's only callback thread, so SIGINT was never served and the MCAP stayed
empty. Such a gravity is now refused when the scene loads (model/limits.py); the test runs
the worst scene that still loads, every arm joint at the largest initial speed a scene
accepts (1e4 rad/s): the run ends in a DivergenceError at once, the node reports it, serves
SIGINT (a clean exit, status 0) and leaves a readable log. No wall-time bound: the wait
after SIGINT is a hang guard only."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from youbot_dynamics.io.bag_reader import read_bag
from youbot_dynamics.scene.schema import scene_dir

REPO = Path(__file__).resolve().parents[2]
HANG_GUARD = 60.0
"""Seconds the test waits for the process to end after SIGINT: a hang guard only, not a
speed bound (the exit takes about 1 s on an idle machine, 3 s on a loaded one)."""


def wait_for_line(log: Path, text: str, process: subprocess.Popen, timeout: float = 30.0) -> None:
    """Poll the node's log until it holds ``text`` (generous bound for a slow start-up)."""
    deadline = time.monotonic() + timeout
    while text not in log.read_text():
        assert process.poll() is None, f"node ended early:\n{log.read_text()}"
        assert time.monotonic() < deadline, f"no {text!r} in the node's log:\n{log.read_text()}"
        time.sleep(0.1)


@pytest.mark.ros
@pytest.mark.timeout(120)
def test_a_node_on_a_diverging_scene_stops_on_sigint_with_a_readable_log(tmp_path: Path) -> None:
    from ros_support import domain_id

    data = yaml.safe_load((scene_dir() / "arm_swing.yaml").read_text())
    data["initial"]["v"] = {f"arm_joint_{i}": 1e4 for i in range(1, 6)}
    scene, mcap, log = tmp_path / "fast.yaml", tmp_path / "run.mcap", tmp_path / "node.log"
    scene.write_text(yaml.safe_dump(data))
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id(23)), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    with log.open("w") as out:                 # a file, not a pipe: a full pipe would stall the node
        process = subprocess.Popen(
            [sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-p", f"scene:={scene}",
             "-p", "publish_rate:=100.0", "-p", f"mcap_path:={mcap}"],
            cwd=REPO, env=env, stdout=out, stderr=subprocess.STDOUT)
    try:
        # the first integrator run follows the t = 0 sample at once (10 ms after start-up);
        # a second later it is running (before the fix: for ever) or has ended
        wait_for_line(log, "simulate arm_swing", process)
        time.sleep(1.0)
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=HANG_GUARD)
        except subprocess.TimeoutExpired:
            pytest.fail(f"the node ignored SIGINT for {HANG_GUARD:g} s:\n{log.read_text()}")
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    text = log.read_text()
    assert process.returncode == 0, text
    assert "diverged" in text and "outside its bounds" in text, text
    topics = {m.topic for m in read_bag(mcap)}
    assert "/clock" in topics and "/joint_states" in topics  # the t = 0 sample, readable
