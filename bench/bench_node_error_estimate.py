"""What the error estimate costs the node: the simulate-mode session on gripping at 500 Hz,
stepped as fast as it goes, without and with ``error_estimate`` (its companion at dt/2 in a
worker process). Reports this process's CPU time per sample (the node's own budget at
500 Hz is 2 ms of wall time per sample), the worker's CPU time per sample, how many chunks
the worker is behind at the end (0: it keeps up) and the estimate.

CPU times (time.process_time: this process only; the worker reports its own), so the
figures hold on a loaded machine; the wall-clock rate of the ROS node is what
``youbot-dynamics main-job --scene gripping --error-estimate`` prints as its real-time factor.

Run: python bench/bench_node_error_estimate.py [--seconds S]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
from youbot_dynamics.node.simulate import SimulationSession  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

RATE = 500.0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=4.0, help="simulated seconds (default 4)")
    args = parser.parse_args()
    scene = load_scene("gripping").with_duration(args.seconds)
    samples = round(args.seconds * RATE)
    for estimate in (False, True):
        session = SimulationSession(scene, RATE, error_estimate=estimate)
        session.step()   # the sample at t = 0
        start = time.process_time()
        for _ in range(samples):
            session.step()
        cpu = time.process_time() - start
        print(f"error_estimate {str(estimate).lower():5s}: {1e3 * cpu / samples:.3f} ms CPU per sample in the node's "
              f"process ({samples} samples at {RATE:g} Hz; budget {1e3 / RATE:g} ms)")
        if estimate:
            lag = session.companion.lag
            result = session.error_estimate(wait=True)
            print(f"  worker: {1e3 * result.companion_cpu_time / samples:.3f} ms CPU per sample, "
                  f"{lag} chunks behind at the end")
            print("\n".join("  " + line for line in result.summary()))
        session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
