"""Inverse dynamics against the chain length: RNEA and the Lagrange-Euler form written in
numpy with every multiplication counted (youbot_dynamics/studies/complexity.py), beside
Pinocchio's RNEA, on spatial chains of n = 1..12 revolute links. Per n: the counted
multiplications (machine-independent) and the CPU time per call (time.process_time, best
of ``repeat`` loops of ``calls`` calls), with the fitted growth exponent p of each
(cost ~ n^p) and the local one between the two largest n. Document 002 says "RNEA O(n),
Lagrange O(n^4) without symbolic simplification"; test/studies/test_document002_claims.py
checks the counts.

Run: python bench/bench_complexity.py [--calls 20] [--repeat 3] [--max-n 12]
(BENCH_SMOKE=1: n up to 3, 2 calls, 1 repeat)
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import load_average  # noqa: E402
from youbot_dynamics.studies import complexity as cx  # noqa: E402

SMOKE = os.environ.get("BENCH_SMOKE") == "1"


def cpu_per_call(call, calls: int, repeat: int) -> float:
    """Best CPU time per call (s) over ``repeat`` loops of ``calls`` calls."""
    best = float("inf")
    for _ in range(repeat):
        start = time.process_time()
        for _ in range(calls):
            call()
        best = min(best, (time.process_time() - start) / calls)
    return best


def measure(sizes: list[int], calls: int, repeat: int) -> dict[str, list[float]]:
    """CPU seconds per call of each method per chain size."""
    times: dict[str, list[float]] = {"rnea (numpy, counted)": [], "lagrange_euler (numpy, counted)": [],
                                     "pin.rnea": []}
    for n in sizes:
        links = cx.chain(n)
        model = cx.pinocchio_chain(links)
        data = model.createData()
        x = np.linspace(0.1, 0.9, n)
        times["rnea (numpy, counted)"].append(cpu_per_call(lambda: cx.rnea_counted(links, x, x, x, cx.Counter()),
                                                           calls, repeat))
        times["lagrange_euler (numpy, counted)"].append(
            cpu_per_call(lambda: cx.lagrange_euler_counted(links, x, x, x, cx.Counter()), max(1, calls // 10), repeat))
        times["pin.rnea"].append(cpu_per_call(lambda: pin.rnea(model, data, x, x, x), calls * 50, repeat))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2 if SMOKE else 20)
    parser.add_argument("--repeat", type=int, default=1 if SMOKE else 3)
    parser.add_argument("--max-n", type=int, default=3 if SMOKE else 12)
    args = parser.parse_args()
    sizes = list(range(1, args.max_n + 1))
    counts = cx.operation_counts(sizes)
    times = measure(sizes, args.calls, args.repeat)
    print(f"load average {load_average()}; CPU time (time.process_time) per call, microseconds\n")
    print("| n | RNEA mult. | Lagrange-Euler mult. | " + " | ".join(f"{k} (us)" for k in times) + " |")
    print("|---" * (3 + len(times)) + "|")
    for i, n in enumerate(sizes):
        print(f"| {n} | {counts['rnea'][i]} | {counts['lagrange_euler'][i]} | "
              + " | ".join(f"{times[k][i] * 1e6:.1f}" for k in times) + " |")
    print("\n| cost | fitted exponent over n | local exponent (two largest n) |\n|---|---|---|")
    series = {"RNEA multiplications": counts["rnea"], "Lagrange-Euler multiplications": counts["lagrange_euler"],
              **{f"{k} CPU time": v for k, v in times.items()}}
    for name, values in series.items():
        if len(sizes) > 1:
            local = np.log(values[-1] / values[-2]) / np.log(sizes[-1] / sizes[-2])
            print(f"| {name} | {cx.growth_exponent(sizes, values):.2f} | {local:.2f} |")


if __name__ == "__main__":
    main()
