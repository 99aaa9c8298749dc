"""Two nodes where one was meant: on one log path the second is refused in one line naming
the holder, and the first's log stays whole; with one full name in one domain both report
the clash (/diagnostics WARN, ``graph.namesakes``) and keep running."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from ros_support import Collector, diagnostic_values, interrupt, ros_context, spinning, wait_until
from youbot_dynamics.io.bag_reader import read_bag

REPO = Path(__file__).resolve().parents[2]
HANG_GUARD = 60.0
"""Seconds allowed for start-up, discovery and exit: hang guards only."""


def start(domain: int, log: Path, *parameters: str) -> subprocess.Popen:
    """The dynamics node on arm_swing for a long run, in ``domain``, its output in ``log``."""
    with log.open("w") as out:
        return subprocess.Popen(
            [sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-p", "scene:=arm_swing",
             "-p", "duration:=1000.0", *(arg for p in parameters for arg in ("-p", p))],
            cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain)}, stdout=out, stderr=subprocess.STDOUT)


@pytest.mark.ros
@pytest.mark.timeout(240)
def test_a_second_writer_on_one_log_path_is_refused(tmp_path: Path) -> None:
    mcap = tmp_path / "run.mcap"
    with ros_context(19) as (context, domain):
        collector = Collector(context, {"/joint_states": "sensor_msgs/msg/JointState"})
        with spinning(context, collector):
            first = start(domain, tmp_path / "first.log", f"mcap_path:={mcap}")
            try:
                wait_until(lambda: collector.count("/joint_states") > 10, HANG_GUARD, "the first node's samples")
                second = start(domain, tmp_path / "second.log", f"mcap_path:={mcap}")
                second.wait(timeout=HANG_GUARD)
                before = collector.count("/joint_states")
                wait_until(lambda: collector.count("/joint_states") > before + 10, HANG_GUARD,
                           "the first node going on")
            finally:
                interrupt(first)
    refusal = (tmp_path / "second.log").read_text().strip()
    assert second.returncode == 2, refusal
    assert len(refusal.splitlines()) == 1 and str(mcap) in refusal and f"pid {first.pid}" in refusal, refusal
    assert first.returncode == 0, (tmp_path / "first.log").read_text()
    assert sum(m.topic == "/joint_states" for m in read_bag(mcap)) > 20   # whole, summary and all


@pytest.mark.ros
@pytest.mark.timeout(240)
def test_two_nodes_of_one_name_report_the_clash(tmp_path: Path) -> None:
    with ros_context(26) as (context, domain):
        collector = Collector(context, {"/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
        with spinning(context, collector):
            nodes = [start(domain, tmp_path / f"node{k}.log", f"mcap_path:={tmp_path / f'run{k}.mcap'}")
                     for k in (1, 2)]
            try:
                def clashes() -> list:
                    return [m for m in collector.messages("/diagnostics")
                            if diagnostic_values(m).get("graph.namesakes") == "1" and m.status[0].level == 1]
                wait_until(lambda: len({m.status[0].hardware_id for m in clashes()}) >= 1 and len(clashes()) >= 2,
                           HANG_GUARD * 2, "WARN statuses naming the other node")
                assert all(process.poll() is None for process in nodes)
            finally:
                interrupt(*nodes)
    status = clashes()[0].status[0]
    assert "other node(s) named /dynamics_node" in status.message, status.message
    logs = [(tmp_path / f"node{k}.log").read_text() for k in (1, 2)]
    assert any("other node(s) named /dynamics_node on the graph" in text for text in logs), logs
    assert all(process.returncode == 0 for process in nodes), logs
