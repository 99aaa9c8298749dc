"""Real-time factor of mobile_pick next to gripping's (measured figures, not tests).

Both scenes over their first ``DURATION`` seconds through the dynamics node's session
without ROS (node/simulate.py: the simulator advanced sample by sample, solve horizon 0.02 s,
the messages built) at the node's 500 Hz, logs off and on (MCAP in rosbag2 form and a Rerun
recording, as the node writes them), in one run of this script. Real-time factor =
simulated / wall time, the best of ``REPEATS`` runs (a shared machine slows single runs).

Run: python bench/bench_base.py [duration_s]
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from youbot_dynamics.node.simulate import SimulationSession  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

RATE, REPEATS = 500.0, 2
DURATION = 9.0  # s, unless given


def session_wall(name: str, logs: Path | None, duration: float | None = None, rate: float = RATE,
                 clock=time.perf_counter) -> float:
    """Wall time (s; CPU time with ``clock=time.process_time``) of the dynamics node's
    session without ROS over the first ``duration`` s (default: all) of scene ``name`` at
    ``rate`` Hz, solve horizon 0.02 s; with ``logs`` (a folder), MCAP and Rerun logs
    written there."""
    paths = {} if logs is None else {"mcap_path": logs / f"{name}.mcap", "rrd_path": logs / f"{name}.rrd"}
    scene = load_scene(name)
    scene = scene if duration is None else scene.with_duration(duration)
    session = SimulationSession(scene, rate, samples_per_solve=max(1, round(0.02 * rate)), **paths)
    start = clock()
    while session.t < scene.duration:
        session.step()
    session.close()
    return clock() - start


if __name__ == "__main__":
    DURATION = float(sys.argv[1]) if len(sys.argv) > 1 else DURATION
    print(f"| scene | rate Hz | logs | wall s ({DURATION:g} s simulated) | real-time factor |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for name in ("mobile_pick", "gripping"):
            for logs in (None, Path(folder)):
                best = min(session_wall(name, logs, DURATION) for _ in range(REPEATS))
                print(f"| {name} | {RATE:g} | {'MCAP + Rerun' if logs else 'off'} | {best:.2f} | "
                      f"{DURATION / best:.2f} |", flush=True)
