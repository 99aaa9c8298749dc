"""A node whose log runs out of room: the file-size limit (RLIMIT_FSIZE, the per-process
form of a full disk that needs no mount) stops the MCAP log cleanly, the node goes on
publishing at its rate, /diagnostics turns ERROR with the reason and what the file holds,
SIGINT ends the run with status 0, and the log reads as it is with mcap's indexed reader and
with rosbags, no recovery needed."""
from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from ros_support import Collector, diagnostic_values, interrupt, ros_context, spinning, stamp_ns, wait_until

REPO = Path(__file__).resolve().parents[2]
LIMIT = 1_000_000
"""Bytes a file of the node's may reach: about 5 s of arm_swing's log at 500 Hz; above the
shared-memory segments Fast DDS creates (512 kB), so its transport is untouched."""
HANG_GUARD = 60.0
"""Seconds allowed for start-up, for the limit to be reached and for the exit: hang guards only."""


def limited_file_size() -> None:
    """In the node's process: files stop at LIMIT bytes with EFBIG (SIGXFSZ ignored)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, LIMIT))


@pytest.mark.ros
@pytest.mark.timeout(240)
def test_a_full_log_stops_logging_not_publishing(tmp_path: Path) -> None:
    mcap, log = tmp_path / "run.mcap", tmp_path / "node.log"
    with ros_context(24) as (context, domain):
        collector = Collector(context, {"/joint_states": "sensor_msgs/msg/JointState",
                                        "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
        with spinning(context, collector), log.open("w") as out:
            process = subprocess.Popen(
                [sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args",
                 "-p", "scene:=arm_swing", "-p", "duration:=1000.0", "-p", "time_scale:=2.0",
                 "-p", f"mcap_path:={mcap}"],
                cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain)}, stdout=out,
                stderr=subprocess.STDOUT, preexec_fn=limited_file_size)
            try:
                def failed() -> list:
                    return [m for m in collector.messages("/diagnostics") if m.status[0].level == 2]
                wait_until(lambda: failed() or process.poll() is not None, HANG_GUARD * 2, "an ERROR status")
                assert process.poll() is None, log.read_text()
                status = failed()[0]
                values = diagnostic_values(status)
                stopped_at = stamp_ns(status)
                wait_until(lambda: sum(stamp_ns(m) > stopped_at + 500_000_000
                                       for m in collector.messages("/joint_states")) > 0,
                           HANG_GUARD, "joint states half a simulated second after the log stopped")
            finally:
                interrupt(process, timeout=HANG_GUARD)     # SIGINT: the exit status is checked below
    text = log.read_text()
    assert process.returncode == 0, text
    assert "EFBIG" in status.status[0].message and values["log.mcap.error"] == "EFBIG", values
    assert int(values["log.mcap.bytes"]) <= LIMIT and values["log.mcap.path"] == str(mcap)
    # publishing went on at the publish rate: samples on the 2 ms grid of simulated time, over
    # more than half a simulated second after the stop (a reader that falls behind the keep-last
    # history may miss some of them: their count is not the point)
    after = [s for s in (stamp_ns(m) for m in collector.messages("/joint_states")) if s > stopped_at]
    assert len(after) >= 100 and all(s % 2_000_000 == 0 for s in after)
    assert after[-1] - after[0] > 500_000_000
    # the log is whole as it is
    with mcap.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        indexed = sum(1 for _ in reader.iter_messages())
    assert summary is not None and indexed == summary.statistics.message_count > 0
    assert values["log.mcap.finalised"] == "true" and int(values["log.mcap.messages"]) == indexed
    with AnyReader([mcap]) as bag:
        assert sum(1 for _ in bag.messages()) == indexed
