"""Timing helpers shared by the bench scripts: best-of-repeats per call with the compared
calls alternating (so both see the same machine load), growth exponents, and the machine."""
from __future__ import annotations

import os
import platform
import time
from typing import Callable, Sequence

import numpy as np


def best_per_call(calls: Sequence[Callable[[], object]], n: int, repeat: int) -> list[float]:
    """Best wall time per call (s) of each function: ``repeat`` rounds, each timing a loop of
    ``n`` calls of every function in turn (time.perf_counter)."""
    best = [float("inf")] * len(calls)
    for _ in range(repeat):
        for i, call in enumerate(calls):
            start = time.perf_counter()
            for _ in range(n):
                call()
            best[i] = min(best[i], time.perf_counter() - start)
    return [b / n for b in best]


def growth_exponent(sizes: Sequence[float], costs: Sequence[float]) -> float:
    """p of the least-squares fit cost = c size^p on log-log axes."""
    return float(np.polyfit(np.log(sizes), np.log(costs), 1)[0])


def machine() -> str:
    """CPU model, logical cores, load average, Python and library versions (MuJoCo's, the
    peer of bench/bench_contact_mujoco.py, if installed)."""
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as cpuinfo:
            model = next(line.split(":", 1)[1].strip() for line in cpuinfo if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    import numba
    import pinocchio

    try:
        import mujoco
        peer = f"MuJoCo {mujoco.__version__}"
    except ImportError:
        peer = "MuJoCo not installed"
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"{model}, {os.cpu_count()} logical cores, load average {load}; Python {platform.python_version()}, "
            f"numpy {np.__version__}, Pinocchio {pinocchio.__version__}, numba {numba.__version__}, {peer}")
