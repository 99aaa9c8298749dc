"""Benchmark of the dynamics node on arm_ptp: achieved vs requested /joint_states rate, and
the real-time factor with and without publishing and logging.

- paced: the node (its own process) at time_scale 1 for DURATION simulated seconds at 100,
  500 and 1000 Hz, logs off and on; a subscriber here records arrival times. The node waits
  for that subscriber before simulated time starts (parameter wait_for_subscribers), so
  every sample should arrive. Achieved rate = (n - 1) / (last - first arrival); real-time
  factor = simulated span / wall span, both over every sample received.
- as fast as possible: the node at time_scale 0 (publishing, logs off / on), and the
  session alone (no ROS: simulation and message building, logs off / on).

Goal (issue 4): 500 Hz held within 2 % while at or faster than real time.
Run: python bench/bench_node.py [--duration S]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

import rclpy  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from youbot_dynamics.cli.common import table  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402
from youbot_dynamics.ros.session import SimulationSession  # noqa: E402
from youbot_dynamics.sim.scene import load_scene  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
SCENE = "arm_ptp"
DOMAIN = 201


def node_run(rate: float, time_scale: float, duration: float, log_dir: Path | None) -> dict[str, float]:
    """Start the node process and measure its /joint_states here: received and expected
    counts, achieved rate (Hz of wall time) and real-time factor."""
    context = Context()
    rclpy.init(context=context, domain_id=DOMAIN)
    node = rclpy.create_node("bench_listener", context=context)
    arrivals: list[tuple[float, int]] = []
    node.create_subscription(JointState, "/joint_states", lambda m: arrivals.append(
        (time.monotonic(), m.header.stamp.sec * 10**9 + m.header.stamp.nanosec)), RELIABLE_DEEP)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    logs = [] if log_dir is None else ["-p", f"mcap_path:={log_dir / 'bench.mcap'}", "-p",
                                       f"rrd_path:={log_dir / 'bench.rrd'}"]
    process = subprocess.run(
        [sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-p", f"scene:={SCENE}",
         "-p", f"publish_rate:={rate}", "-p", f"time_scale:={time_scale}", "-p", f"duration:={duration}",
         "-p", "wait_for_subscribers:=1", "-p", "wait_timeout:=30.0", *logs],
        cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(DOMAIN)}, capture_output=True, text=True, timeout=600)
    expected = round(duration * rate) + 1
    deadline = time.monotonic() + 2.0       # the node left once all was acknowledged: callbacks may lag
    while len(arrivals) < expected and time.monotonic() < deadline:
        time.sleep(0.01)
    executor.shutdown()
    node.destroy_node()
    context.try_shutdown()
    if process.returncode != 0:
        raise RuntimeError(process.stderr)
    if len(arrivals) < 2:
        raise RuntimeError(f"{len(arrivals)} /joint_states samples received of {expected}:\n{process.stderr}")
    wall = arrivals[-1][0] - arrivals[0][0]
    simulated = (arrivals[-1][1] - arrivals[0][1]) / 1e9
    return {"received": len(arrivals), "expected": expected, "achieved": (len(arrivals) - 1) / wall,
            "rtf": simulated / wall}


def session_run(rate: float, duration: float, log_dir: Path | None) -> float:
    """Real-time factor of the session alone (no ROS), as fast as possible."""
    logs = {} if log_dir is None else {"mcap_path": log_dir / "s.mcap", "rrd_path": log_dir / "s.rrd"}
    session = SimulationSession(load_scene(SCENE), rate, samples_per_solve=max(1, round(0.02 * rate)), **logs)
    start = time.perf_counter()
    while session.t < duration:
        session.step()
    session.close()
    return session.t / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=4.0, help="simulated seconds per run (default 4)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        logs = Path(folder)
        rows, goal = [], []
        for rate in (100.0, 500.0, 1000.0):
            for log_dir in (None, logs):
                m = node_run(rate, 1.0, args.duration, log_dir)
                error = 100.0 * (m["achieved"] - rate) / rate
                rows.append((f"{rate:g}", "on" if log_dir else "off", f"{m['achieved']:.1f}", f"{error:+.2f} %",
                             f"{m['rtf']:.3f}", f"{m['received']}/{m['expected']}"))
                if rate == 500.0:
                    met = abs(error) <= 2.0 and m["rtf"] >= 0.98
                    goal.append(f"logs {'on' if log_dir else 'off'}: {'met' if met else 'NOT met'}")
        print(f"paced (time_scale 1), {SCENE}, {args.duration:g} s simulated, node in its own process")
        print(table(("requested Hz", "logs", "achieved Hz", "error", "real-time factor", "received"), rows))
        print(f"goal (500 Hz within 2 %, real-time factor >= 0.98): {'; '.join(goal)}")
        rows = []
        for rate in (100.0, 500.0, 1000.0):
            fast = [node_run(rate, 0.0, args.duration, log_dir) for log_dir in (None, logs)]
            alone = [session_run(rate, args.duration, log_dir) for log_dir in (None, logs)]
            rows.append((f"{rate:g}", *(f"{value:.2f}" for value in (*alone, *(m["rtf"] for m in fast))),
                         " / ".join(f"{m['received']}/{m['expected']}" for m in fast)))
        print(f"\nas fast as possible: real-time factor (simulated s per wall s), {SCENE}")
        print(table(("rate Hz", "no ROS, no logs", "no ROS, logs", "publishing, no logs", "publishing, logs",
                     "received (no logs / logs)"), rows))

if __name__ == "__main__":
    main()
