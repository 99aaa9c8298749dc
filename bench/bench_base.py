"""Real-time factor of mobile_pick next to gripping's (measured figures, not tests).

Both scenes over their first ``DURATION`` seconds through the dynamics node's session
without ROS (node/simulate.py: the simulator advanced sample by sample, solve horizon 0.02 s,
the messages built) at the node's 500 Hz, logs off and on (MCAP in rosbag2 form and a Rerun
recording, as the node writes them), in one run of this script. Real-time factor =
simulated / CPU time of the process (wall time beside it), the best of ``REPEATS`` runs.

Run: python bench/bench_base.py [duration_s]
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import Timing, sized, timed  # noqa: E402
from youbot_dynamics.node.simulate import SimulationSession  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

RATE, REPEATS = 500.0, 2
DURATION = 9.0  # s, unless given


def session_cost(name: str, logs: Path | None, duration: float | None = None, rate: float = RATE) -> Timing:
    """CPU time of the process (s, Rerun's writer threads included) and wall time of the
    dynamics node's session without ROS over the first ``duration`` s (default: all) of
    scene ``name`` at ``rate`` Hz, solve horizon 0.02 s; with ``logs`` (a folder), MCAP and
    Rerun logs written there (closing the logs counted)."""
    paths = {} if logs is None else {"mcap_path": logs / f"{name}.mcap", "rrd_path": logs / f"{name}.rrd"}
    scene = load_scene(name)
    scene = scene if duration is None else scene.with_duration(duration)
    session = SimulationSession(scene, rate, samples_per_solve=max(1, round(0.02 * rate)), **paths)

    def run() -> None:
        while session.t < scene.duration:
            session.step()
        session.close()

    return timed(run)[1]


def session_wall(name: str, logs: Path | None, duration: float | None = None, rate: float = RATE) -> float:
    """Wall time (s) of :func:`session_cost`."""
    return session_cost(name, logs, duration, rate).wall


if __name__ == "__main__":
    DURATION = float(sys.argv[1]) if len(sys.argv) > 1 else sized(DURATION, 0.05)
    print(f"| scene | rate Hz | logs | CPU s ({DURATION:g} s simulated) | wall s | real-time factor (CPU) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for name in ("mobile_pick", "gripping"):
            for logs in (None, Path(folder)):
                costs = [session_cost(name, logs, DURATION) for _ in range(sized(REPEATS, 1))]
                cpu, wall = min(c.cpu for c in costs), min(c.wall for c in costs)
                print(f"| {name} | {RATE:g} | {'MCAP + Rerun' if logs else 'off'} | {cpu:.2f} | {wall:.2f} | "
                      f"{DURATION / cpu:.2f} |", flush=True)
