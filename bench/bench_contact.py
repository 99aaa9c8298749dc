"""Contact cost and accuracy, side by side (measured figures, not tests).

1. The cost of a scene with its contact pairs against the same scene with them removed
   (ball_drop: rk45; box_slide: the constraint stepper, which without pairs integrates a
   free fall): CPU time and right-hand-side evaluations or steps. The scene pays for
   contact only where it declares it.
2. ball_drop against MuJoCo: the first hop's apex error against e^2 H0 versus CPU time,
   ours and MuJoCo's at several steps and tolerances, and the CPU time each needs for a
   1 % error (bench/bench_contact_mujoco.py says how, and compares a closed grasp too).
3. gripping (28 s, two youBots, 7 pairs, constraint stepper PGS at 1 ms): one run of the
   simulator (outputs at the scene's 50 Hz), then the dynamics node's session without ROS
   (node/session.py: the simulator advanced sample by sample, solve horizon 0.02 s, the
   messages built) at 50 and 500 Hz (the node's default rate), logs off and on (MCAP in
   rosbag2 form and a Rerun recording, as the node writes them). Real-time factor =
   simulated / CPU time; also the sphere's final place, the deepest overlap and the
   stepper's statistics. Each row is the best of REPEATS runs.

Costs are CPU time of the process (bench/timing.py), real-time factors simulated s per CPU
s. BENCH_SMOKE=1: every scene over 0.05 s, one run each.

Run: python bench/bench_contact.py      (needs ``pip install mujoco`` for part 2)
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_base import session_cost  # noqa: E402
from bench_contact_mujoco import (E, H0, ball_drop_mujoco, ball_drop_ours, matched, mujoco_module,  # noqa: E402
                                  summary_line, table)
from timing import load_average, sized, timed  # noqa: E402
from youbot_dynamics.scene.schema import Scene, load_scene, scene_dir  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

#: gripping runs per row; the least CPU time is kept
REPEATS = sized(2, 1)
#: simulated seconds of each scene (None: the scene's own; BENCH_SMOKE=1: a few steps)
DURATION = sized(None, 0.05)


def run_scene(data: dict) -> tuple[Simulator, object, float]:
    """(simulator, result, CPU s of the process) of the scene mapping ``data``."""
    if DURATION is not None:
        data = {**data, "duration": DURATION}
    simulator = Simulator(Scene.from_dict(data, "bench"))
    result, cost = timed(simulator.run)
    return simulator, result, cost.cpu


def contact_cost() -> None:
    print("## 1. cost of the declared contact pairs\n")
    print("| scene | pairs | integrator | CPU s | rhs evals / steps | events |")
    print("|---|---|---|---|---|---|")
    for name in ("ball_drop", "box_slide"):
        data = yaml.safe_load((scene_dir() / f"{name}.yaml").read_text())
        for label, variant in (("declared", data), ("removed", {**data, "contacts": []})):
            if not variant["contacts"] and variant["integrator"]["method"] in ("pgs", "admm"):
                variant = {**variant, "integrator": {"method": "rk4", "dt": variant["integrator"]["dt"]}}
            _, result, cpu = run_scene(variant)
            stats = result.stats
            work = stats.rhs_evals if stats.rhs_evals else stats.steps
            print(f"| {name} | {label} | {result.integrator.describe()} | {cpu:.3f} | {work} | {stats.events} |")
    print()


def accuracy() -> None:
    """ball_drop's apex error against CPU time, ours and MuJoCo's (bench/bench_contact_mujoco.py)."""
    print(f"## 2. ball_drop: apex of the first hop (target e^2 H0 = {E * E * H0:.4f} m) vs CPU time\n")
    runs = ball_drop_ours(quick=False)
    mujoco = mujoco_module()
    if mujoco is None:
        print("MuJoCo not installed: pip install mujoco (requirements-bench.txt)\n")
    else:
        runs += ball_drop_mujoco(mujoco, quick=False)
    print(table("ball_drop", runs))
    print(f"\n{summary_line(runs, matched(runs, 1.0))}\n")


def gripping() -> None:
    print("## 3. gripping: the sphere's hand-over and its real-time factor\n")
    scene = load_scene("gripping")
    simulator = Simulator(scene if DURATION is None else scene.with_duration(DURATION))
    runs = [timed(simulator.run) for _ in range(REPEATS)]
    result, cpu = runs[-1][0], min(cost.cpu for _, cost in runs)
    stats = result.stats
    final = simulator.model.body_motion(result.x[-1])["position"][0, 0]
    on_plate = simulator.body_in_link(result, "sphere", "yb2_plate_link")[-1]
    print(f"sphere at the end: ({final[0]:.4f}, {final[1]:.4f}, {final[2]:.4f}) m; in yb2_plate_link "
          f"({on_plate[0]:+.4f}, {on_plate[1]:+.4f}, {on_plate[2]:+.4f}) m (plate 0.2 x 0.3, top at +0.005)")
    print(f"deepest overlap {1e3 * result.max_penetration:.3f} mm; {stats.steps} steps, "
          f"{stats.nonlinear_iterations} PGS iterations, {stats.events} contact events\n")
    print("| run | rate Hz | logs | CPU s | real-time factor (CPU) |")
    print("|---|---|---|---|---|")
    print(f"| Simulator.run | 50 | off | {cpu:.2f} | {result.t[-1] / cpu:.2f} |")
    with tempfile.TemporaryDirectory() as folder:
        for rate in (50.0, 500.0):
            for logs in (None, Path(folder)):
                best = min(session_cost("gripping", logs, DURATION, rate).cpu for _ in range(REPEATS))
                print(f"| session | {rate:g} | {'MCAP + Rerun' if logs else 'off'} | {best:.2f} | "
                      f"{result.t[-1] / best:.2f} |")
    print()


if __name__ == "__main__":
    print(f"load average {load_average()}\n")
    contact_cost()
    accuracy()
    gripping()
