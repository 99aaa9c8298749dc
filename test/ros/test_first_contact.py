"""What a newcomer meets first: ``dynamics_node --help`` prints the parameter table and starts
nothing; a run says when it is ready (what it offers, as the interface table says), reports
its progress (log lines at every 10 % of a long run, ``progress`` in /diagnostics) and says
when it is done. No wall-time bounds: waits are hang guards only."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from youbot_dynamics.io.bag_reader import read_bag
from youbot_dynamics.node.interface import PARAMETERS, offered
from youbot_dynamics.node.progress import Progress

REPO = Path(__file__).resolve().parents[2]
HANG_GUARD = 120.0
"""Seconds a process may take before the test calls it hung (not a speed bound)."""
ENV = {**os.environ, "PYTHONPATH": str(REPO), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


def run(command: list[str], domain: int) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(command, cwd=REPO, env={**ENV, "ROS_DOMAIN_ID": str(domain)}, capture_output=True,
                              text=True, timeout=HANG_GUARD)
    except subprocess.TimeoutExpired as error:
        pytest.fail(f"{command} still running after {HANG_GUARD:g} s: {error.stdout}{error.stderr}")


@pytest.mark.parametrize("command", [[str(REPO / "scripts" / "dynamics_node")],
                                     ["-m", "youbot_dynamics.ros.dynamics_node"]], ids=["executable", "module"])
def test_help_prints_the_parameter_table_and_starts_nothing(tmp_path: Path, command: list[str]) -> None:
    from ros_support import domain_id

    mcap = tmp_path / "never.mcap"     # a node that started would create it at once
    result = run([sys.executable, *command, "--help", "--ros-args", "-p", f"mcap_path:={mcap}",
                  "-p", "duration:=0.2"], domain_id(10))
    assert result.returncode == 0, result.stderr
    assert not mcap.exists() and result.stderr == ""
    lines = result.stdout.splitlines()
    assert lines[0].startswith("usage: dynamics_node")
    for name, spec in PARAMETERS.items():
        row = next((line.split() for line in lines if line.split()[:1] == [name]), None)
        assert row is not None, name
        assert row[1:3] == [type(spec.default).__name__, repr(spec.default)], row
        if spec.limits is not None:
            assert row[3:] == [f"{spec.limits[0]:g}", "..", f"{spec.limits[1]:g}"], row
    assert "settable at run time" in result.stdout and "--managed" in result.stdout


def test_help_imports_neither_rclpy_nor_the_simulation() -> None:
    probe = ("import sys; from youbot_dynamics.ros.dynamics_main import main; status = main(['--help']); "
             "print(sorted(m for m in ('rclpy', 'pinocchio', 'youbot_dynamics.sim') if m in sys.modules)); "
             "sys.exit(status)")
    result = run([sys.executable, "-c", probe], 0)
    assert result.returncode == 0 and result.stdout.splitlines()[-1] == "[]", result.stdout + result.stderr


def test_an_unknown_argument_is_one_line_and_status_2() -> None:
    result = run([sys.executable, str(REPO / "scripts" / "dynamics_node"), "scene:=arm_swing"], 0)
    assert result.returncode == 2 and len(result.stderr.splitlines()) == 1, result.stderr
    assert "unknown argument 'scene:=arm_swing'" in result.stderr and "--ros-args -p" in result.stderr


def test_progress_marks() -> None:
    long_run = Progress(20.0)
    marks = [long_run.passed(0.01 * k) for k in range(2001)]
    assert [m for m in marks if m is not None] == list(range(10, 100, 10))
    assert [marks.index(m) for m in range(10, 100, 10)] == list(range(200, 2000, 200))   # at the crossing
    assert long_run.percent(5.0) == 25.0 and long_run.percent(30.0) == 100.0
    assert Progress(10.0).passed(5.0) is None and Progress(0.0).percent(3.0) is None


@pytest.mark.ros
@pytest.mark.timeout(300)
def test_a_long_run_says_ready_reports_progress_and_says_done(tmp_path: Path) -> None:
    from ros_support import domain_id

    mcap, duration = tmp_path / "run.mcap", 12.0
    result = run([sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-r", "__ns:=/yb",
                  "-p", "scene:=arm_ptp", "-p", f"duration:={duration}", "-p", "time_scale:=0.0",
                  "-p", "publish_rate:=50.0", "-p", "diagnostics_period:=0.05", "-p", f"mcap_path:={mcap}"],
                 domain_id(11))
    log = result.stdout + result.stderr
    assert result.returncode == 0, log
    (ready,) = [line.split("ready: ", 1)[1] for line in log.splitlines() if "ready: " in line]
    features = frozenset({"robot", "arm_controller", "wrist_sensor"})   # arm_ptp: its arm moves, not its fingers
    expected = {kind: [name if name in ("/tf", "/tf_static", "/diagnostics") else
                       "/yb/dynamics_node/" + name[2:] if name.startswith("~/") else "/yb/" + name.lstrip("/")
                       for name in names]
                for kind, names in offered("simulate", features).items()}
    assert ready == "; ".join(f"{kind} {', '.join(names)}" for kind, names in expected.items())
    assert "/yb/joint_states" in ready and "/yb/dynamics_node/reset" in ready
    marks = [(int(m[0]), float(m[1])) for m in re.findall(r"progress: (\d+) % \(([\d.]+) of 12 s", log)]
    assert [mark for mark, _ in marks] == list(range(10, 100, 10)), log
    assert all(t == pytest.approx(mark / 100 * duration, abs=0.02 + 1e-9) for mark, t in marks), marks
    assert log.index("ready: ") < log.index("progress: 10 %") < log.index("done: 12 s simulated") \
        < log.index(f"logs closed: {mcap}")
    progress = []
    for message in read_bag(mcap):
        if message.topic == "/diagnostics":
            values = {kv.key: kv.value for kv in message.message.status[0].values}
            progress.append((float(values["sim_time"]), float(values["progress"])))
    assert len(progress) >= 2 and progress[-1] == (duration, 100.0)
    assert all(p == pytest.approx(100.0 * t / duration, abs=1e-9) for t, p in progress), progress


@pytest.mark.ros
@pytest.mark.timeout(300)
def test_a_short_run_logs_no_progress_lines(tmp_path: Path) -> None:
    from ros_support import domain_id

    result = run([sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-p", "scene:=arm_ptp",
                  "-p", "duration:=2.0", "-p", "time_scale:=0.0", "-p", "publish_rate:=50.0"], domain_id(19))
    log = result.stdout + result.stderr
    assert result.returncode == 0 and "ready: " in log and "done: 2 s simulated" in log, log
    assert "progress:" not in log
