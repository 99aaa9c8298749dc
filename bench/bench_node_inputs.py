"""Benchmark of the dynamics node under hostile input (issue 16): the worst gap between
/joint_states arrivals while another process sends

- ``burst``: 20 /joint_commands messages of 10 000 joint names each, back to back;
- ``flood``: small valid /joint_commands as fast as one Python publisher can (for FLOOD_S);
- ``none``: nothing (the baseline).

The node runs arm_ptp at 500 Hz, time scale 1, for 12 simulated seconds in its own
process; the listener here records the arrival (wall) time of every /joint_states sample.
Reported: samples received, the rate from the start of the attack to the end of the run
and the worst arrival gap (ms) in that window. Timings on a
shared machine are approximate: compare runs made side by side.
Run: python bench/bench_node_inputs.py [--attack burst flood none] [--domain N]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

import rclpy  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
RATE = 500.0
SETTLE_S = 3.0
"""Wall seconds from the first sample to the start of the attack."""
FLOOD_S = 3.0
ATTACKER = r'''
import os, sys, time
import rclpy
from rclpy.context import Context
from sensor_msgs.msg import JointState
from youbot_dynamics.ros.qos import RELIABLE_DEEP
kind, domain, flood_s = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
context = Context(); rclpy.init(context=context, domain_id=domain)
node = rclpy.create_node("attacker", context=context)
pub = node.create_publisher(JointState, "/joint_commands", RELIABLE_DEEP)
deadline = time.monotonic() + 20
while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
    time.sleep(0.01)
sent, start = 0, time.monotonic()
if kind == "burst":
    big = JointState(name=[f"joint_{k}" for k in range(10_000)], effort=[0.0] * 10_000)
    for _ in range(20):
        pub.publish(big); sent += 1
else:
    small = JointState(name=["arm_joint_1"], effort=[0.0])
    while time.monotonic() - start < flood_s:
        pub.publish(small); sent += 1
print(f"sent {sent} in {time.monotonic() - start:.2f} s", flush=True)
time.sleep(5.0)         # stay while the reliable writer delivers
'''


def run(attack: str, domain: int, duration: float) -> dict[str, float]:
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    listener = rclpy.create_node("bench_listener", context=context)
    arrivals: list[float] = []
    listener.create_subscription(JointState, "/joint_states", lambda m: arrivals.append(time.monotonic()),
                                 RELIABLE_DEEP)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(listener)
    threading.Thread(target=executor.spin, daemon=True).start()
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain)}
    node = subprocess.Popen([sys.executable, "-m", "youbot_dynamics.ros.dynamics_node", "--ros-args", "-p",
                             "scene:=arm_ptp", "-p", f"publish_rate:={RATE}", "-p", f"duration:={duration}",
                             "-p", "wait_for_subscribers:=1"], cwd=REPO, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while not arrivals and node.poll() is None:
        time.sleep(0.01)
    time.sleep(SETTLE_S)
    start = time.monotonic()
    report = ""
    if attack != "none":
        attacker = subprocess.run([sys.executable, "-c", ATTACKER, attack, str(domain), str(FLOOD_S)], cwd=REPO,
                                  env=env, capture_output=True, text=True, timeout=120)
        report = attacker.stdout.strip() or attacker.stderr.strip()[-300:]
    else:
        time.sleep(FLOOD_S)
    node.wait(timeout=600)
    executor.shutdown()
    context.try_shutdown()
    window = [t for t in arrivals if start <= t]
    gaps = [b - a for a, b in zip(window, window[1:])]
    return {"attack": attack, "attacker": report, "samples": len(arrivals),
            "window rate Hz": (len(window) - 1) / (window[-1] - window[0]) if len(window) > 1 else 0.0,
            "worst gap ms": 1e3 * max(gaps, default=float("nan"))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--attack", nargs="+", default=["none", "burst", "flood"])
    parser.add_argument("--domain", type=int, default=47)
    parser.add_argument("--duration", type=float, default=12.0, help="simulated s the node runs")
    args = parser.parse_args()
    for attack in args.attack:
        print(run(attack, args.domain, args.duration), flush=True)


if __name__ == "__main__":
    main()
