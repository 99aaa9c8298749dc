"""Wall time of one sweep serially, on a local Dask cluster of 1 and of 2 worker processes
(accuracy/sweeps.py), and whether the results are identical. The sweep: the BDF1-4
stability boundary measured by bisection on the solver's own growth along two rays
(studies/bdf.py), 8 independent cases. Cluster start-up is timed apart from the sweep.

Wall time on purpose: the point is the parallel speed-up (CPU time would not show it).
Run: python bench/bench_sweeps.py [--iterations N]   (BENCH_SMOKE=1: 1 iteration, 1 worker)
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import sized  # noqa: E402
from youbot_dynamics.accuracy.sweeps import dask_client, map_cases  # noqa: E402
from youbot_dynamics.studies.bdf import measured_boundary_radius  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=sized(12, 1), help="bisection steps per case")
    args = parser.parse_args()
    cases = [(order, angle, 1e-3, 20.0, args.iterations)
             for order in (1, 2, 3, 4) for angle in (0.0, math.pi / 4)]
    start = time.perf_counter()
    serial = map_cases(measured_boundary_radius, cases, workers=0, progress=False)
    times = {"serial": time.perf_counter() - start}
    for workers in sized((1, 2), (1,)):
        start = time.perf_counter()
        with dask_client(workers) as client:
            started = time.perf_counter()
            results = map_cases(measured_boundary_radius, cases, client=client, progress=False)
            times[workers] = time.perf_counter() - started
        print(f"{workers} worker(s): start-up {started - start:.2f} s, sweep "
              f"{times[workers]:.2f} s, identical to serial: {results == serial}")
    print(f"serial: {times['serial']:.2f} s for {len(cases)} cases")
    if 2 in times:
        print(f"wall-time ratio 1 worker / 2 workers: {times[1] / times[2]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
