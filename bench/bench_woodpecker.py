"""Woodpecker toy over [0, 2] s from the seed's initial state: CPU time and statistics per
integrator, side by side with the seed's Assimulo (IDA) and Dymola figures.

Run: python bench/bench_woodpecker.py [--rtol 1e-6] [--repeat 3]. Prints the best of
``repeat`` runs (CPU time by time.process_time around the whole hybrid run). Goal: < 0.1 s.
BENCH_SMOKE=1: rk45 and ida, one run each.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import sized  # noqa: E402

from youbot_dynamics.studies.stats_table import stats_table  # noqa: E402
from youbot_dynamics.studies.woodpecker import BEAK, SEED_FIGURES, Woodpecker  # noqa: E402

ADAPTIVE = sized(("rk45", "dop853", "radau", "bdf", "cvode_bdf", "cvode_adams", "ida"), ("rk45", "ida"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rtol", type=float, default=1e-6)
    parser.add_argument("--repeat", type=int, default=sized(3, 1))
    args = parser.parse_args()
    woodpecker = Woodpecker()
    rows, hits = {}, {}
    for integrator in ADAPTIVE:
        best = None
        for _ in range(args.repeat):
            start = time.process_time()
            solution = woodpecker.simulate(2.0, integrator, rtol=args.rtol,
                                           atol=args.rtol * 1e-2)
            cpu = time.process_time() - start
            if best is None or cpu < best[0]:
                best = cpu, solution
        cpu, solution = best
        row = solution.stats.as_dict()
        row["wall_time"] = cpu
        rows[f"{integrator}"] = row
        hits[integrator] = solution.count(BEAK)
    print(f"woodpecker toy, [0, 2] s, rtol {args.rtol:g}, atol {args.rtol * 1e-2:g}; "
          f"CPU time best of {args.repeat}")
    print(stats_table({**rows, **SEED_FIGURES}))
    print("beak hits: " + ", ".join(f"{k} {v}" for k, v in hits.items()) + " (seed: 22)")


if __name__ == "__main__":
    main()
