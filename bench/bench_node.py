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

Issue 14 (``--issue14``): the main job (``youbot-dynamics main-job``: gripping or ``--scene``, 500 Hz,
MCAP + Rerun) and its real-time factor with logs against the integrator's alone
(:func:`main_job`); the session's output cost per sample, logs off and on, of this source
tree and of another (``--old DIR``, e.g. ``git archive main | tar -x -C DIR``), measured in
one run (:func:`output_cost`); inverse mode's cost per sample in batches against
``inverse_dynamics_batch``'s (:func:`inverse_cost`).
Run: python bench/bench_node.py [--duration S] [--issue14 [--old DIR] [--scene NAME]]
"""
from __future__ import annotations

import argparse
import json
import os
import re
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
from youbot_dynamics.node.simulate import SimulationSession  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

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


def main_job(duration: float = 4.0, source: Path = REPO) -> tuple[float, float]:
    """(real-time factor with logs, the integrator's alone) of ``youbot-dynamics main-job
    --duration`` (gripping, 500 Hz, MCAP + Rerun, node start to finish; wall time, as the
    command prints them) run from ``source`` in its own process."""
    return main_job_figures(duration, source)[:2]


def main_job_figures(duration: float = 4.0, source: Path = REPO, scene: str = "gripping"
                     ) -> tuple[float, float, float]:
    """:func:`main_job` (of ``scene``) and, third, simulated s per CPU s of the whole process
    (start-up included): what a machine to itself would give as wall time."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as folder:
        process = subprocess.run(
            [sys.executable, "-m", "youbot_dynamics", "main-job", "--scene", scene, "--duration", str(duration),
             "--out", folder],
            cwd=source, env={**os.environ, "PYTHONPATH": str(source), "ROS_DOMAIN_ID": str(DOMAIN)},
            capture_output=True, text=True, timeout=1200)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if process.returncode != 0:
        raise RuntimeError(process.stdout + process.stderr)
    with_logs = re.search(r"real-time factor\s*\|?\s*([0-9.]+) \(simulated s per wall s", process.stdout)
    alone = re.search(r"wall [0-9.]+ s, real-time factor ([0-9.]+)", process.stdout)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return float(with_logs.group(1)), float(alone.group(1)), duration / cpu


OUTPUT_COST = r'''
import json, sys, tempfile, time
from pathlib import Path
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene
costs = []
for logs in (False, True):
    with tempfile.TemporaryDirectory() as folder:
        paths = {"mcap_path": Path(folder) / "a.mcap", "rrd_path": Path(folder) / "a.rrd"} if logs else {}
        session = SimulationSession(load_scene(sys.argv[2]), 500.0, samples_per_solve=10, **paths)
        spent = [0.0]
        for name in ("_outputs", "_block"):          # _block: the samples of a solve built at once
            method = getattr(session, name, None)
            if method is not None:
                def timed(*args, method=method):
                    start = time.process_time()
                    try:
                        return method(*args)
                    finally:
                        spent[0] += time.process_time() - start
                setattr(session, name, timed)
        for _ in range(20):
            session.step()
        spent[0], samples = 0.0, int(sys.argv[1])
        for _ in range(samples):
            session.step()
        session.close()
        costs.append(spent[0] / samples * 1e6)
print(json.dumps(costs))
'''


def output_cost(source: Path = REPO, samples: int = 1000, scene: str = "gripping") -> tuple[float, float]:
    """(logs off, MCAP + Rerun) us per sample the session spends building (and logging)
    the messages of ``scene`` at 500 Hz, everything consumed, over ``samples`` steps (the
    integrator not counted), with the package from ``source``, in its own process. CPU time
    of the process (``time.process_time``): on a shared machine, wall time counts the
    others' work."""
    process = subprocess.run([sys.executable, "-c", OUTPUT_COST, str(samples), scene], cwd=source, capture_output=True,
                             text=True, env={**os.environ, "PYTHONPATH": str(source)}, timeout=600)
    if process.returncode != 0:
        raise RuntimeError(process.stderr)
    off, on = json.loads(process.stdout.strip().splitlines()[-1])
    return off, on


def inverse_cost(samples: int = 2000, batch: int = 20) -> tuple[float, float]:
    """(inverse mode, inverse_dynamics_batch) CPU us per sample on arm_ptp: the inverse
    session fed ``batch`` joint states at a time (as the node's 10 ms tick does at 2 kHz),
    /computed_torques its only consumer, against one inverse_dynamics_batch call over all
    the samples (best of 3)."""
    import numpy as np
    import pinocchio as pin

    from youbot_dynamics.dynamics.rigid_body import inverse_dynamics_batch
    from youbot_dynamics.node.inverse_session import InverseSession

    scene = load_scene(SCENE)
    names, n = list(scene.robot.joint_names), len(scene.robot.joint_names)
    stamps = np.arange(1, samples + 1) * 2_000_000
    q = np.array(scene.q0) + 0.1 * np.sin(np.outer(stamps * 1e-9, np.ones(n)))
    v = 0.1 * np.cos(np.outer(stamps * 1e-9, np.ones(n)))
    states = [(names, q[k].tolist(), v[k].tolist(), int(stamps[k]), None) for k in range(samples)]
    mode = float("inf")
    for _ in range(3):
        session = InverseSession(scene)
        session.consumed_by({"/computed_torques"})
        session.joint_states(states[:batch])            # warm up: compiled friction, templates
        start = time.process_time()
        for k in range(batch, samples, batch):
            session.joint_states(states[k:k + batch])
        mode = min(mode, (time.process_time() - start) / (samples - batch))
    robot, friction = scene.robot, scene.joint_friction(scene.robot)
    pool, a = pin.ModelPool(robot.model, 1), np.gradient(v, axis=0)
    inverse_dynamics_batch(robot, q, v, a, friction, pool=pool)
    whole = float("inf")
    for _ in range(3):
        start = time.process_time()
        inverse_dynamics_batch(robot, q, v, a, friction, pool=pool)
        whole = min(whole, (time.process_time() - start) / samples)
    return mode * 1e6, whole * 1e6


def issue14(duration: float, old: Path | None, scene: str = "gripping") -> None:
    """Print the issue-14 figures of ``scene``: output cost (this tree and ``old``), main
    job, inverse mode."""
    trees = [("this tree", REPO)] + ([("old", old)] if old else [])
    costs = [(label, *output_cost(source, scene=scene)) for label, source in trees]
    print(table(("source", "outputs us/sample, no logs", "outputs us/sample, MCAP + Rerun"),
                [(label, f"{off:.0f}", f"{on:.0f}") for label, off, on in costs]))
    rows = [(label, *(f"{x:.2f}" for x in main_job_figures(duration, source, scene))) for label, source in trees]
    print(table(("source", f"main job real-time factor with logs ({duration:g} s, wall)", "integrator alone (wall)",
                 "simulated s per CPU s (start-up included)"), rows))
    mode, whole = inverse_cost()
    print(f"inverse mode {mode:.1f} us/sample (batches of 20, /computed_torques), inverse_dynamics_batch "
          f"{whole:.2f} us/sample: {mode / whole:.1f}x")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=4.0, help="simulated seconds per run (default 4)")
    parser.add_argument("--issue14", action="store_true", help="only the issue-14 figures (see the docstring)")
    parser.add_argument("--old", type=Path, default=None, help="another source tree to compare (--issue14)")
    parser.add_argument("--scene", default="gripping", help="the scene of the --issue14 figures (default gripping)")
    args = parser.parse_args()
    if args.issue14:
        issue14(args.duration, args.old, args.scene)
        return
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
