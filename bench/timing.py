"""Timing helpers shared by the bench scripts: CPU time beside wall time, best of repeats
with the compared calls alternating (so both see the same machine load), growth exponents,
the machine and its load.

Every figure is the CPU time of the measuring thread (``time.thread_time``) or, for whole
runs whose libraries work in threads of their own (Rerun's writer), of the process
(``time.process_time``); the wall time (``time.perf_counter``) of the same loops beside it.
On a busy machine the wall time counts the other processes' turns; the CPU time does not,
so ratios and verdicts are taken from CPU time. Alternating ours and the peer in one
process evens out what CPU time still feels of the load (a busy sibling hyperthread, a
cold cache).

Smoke mode: ``BENCH_SMOKE=1`` in the environment (or :func:`set_smoke`) asks every script
for its tiny form (test/bench runs them so, so that none can rot).
"""
from __future__ import annotations

import os
import platform
import time
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

THREAD, PROCESS, WALL = time.thread_time, time.process_time, time.perf_counter


@dataclass(frozen=True)
class Timing:
    """CPU and wall seconds of one measurement (each the best of its repeats)."""

    cpu: float
    wall: float

    def __truediv__(self, n: float) -> Timing:
        return Timing(self.cpu / n, self.wall / n)


def smoke() -> bool:
    """Whether the scripts should run their tiny form (environment BENCH_SMOKE=1)."""
    return os.environ.get("BENCH_SMOKE", "") not in ("", "0")


def set_smoke(on: bool = True) -> None:
    """Switch the tiny form on (or off) for this process and the processes it starts."""
    os.environ["BENCH_SMOKE"] = "1" if on else "0"


def sized(full, tiny):
    """``tiny`` in smoke mode, else ``full``."""
    return tiny if smoke() else full


def best_timings(calls: Sequence[Callable[[], object]], n: int, repeat: int,
                 clock: Callable[[], float] = THREAD) -> list[Timing]:
    """Best CPU (``clock``) and best wall time per call (s) of each function: ``repeat``
    rounds, each timing a loop of ``n`` calls of every function in turn."""
    cpu = [float("inf")] * len(calls)
    wall = [float("inf")] * len(calls)
    for _ in range(repeat):
        for i, call in enumerate(calls):
            start_cpu, start_wall = clock(), WALL()
            for _ in range(n):
                call()
            cpu[i] = min(cpu[i], clock() - start_cpu)
            wall[i] = min(wall[i], WALL() - start_wall)
    return [Timing(c / n, w / n) for c, w in zip(cpu, wall)]


def best_per_call(calls: Sequence[Callable[[], object]], n: int, repeat: int,
                  clock: Callable[[], float] = THREAD) -> list[float]:
    """Best CPU time per call (s, the measuring thread's by default) of each function, as
    :func:`best_timings` measures it."""
    return [t.cpu for t in best_timings(calls, n, repeat, clock)]


def timed(call: Callable[[], object], clock: Callable[[], float] = PROCESS) -> tuple[object, Timing]:
    """``call()``'s result and its CPU (``clock``, the process's by default) and wall time."""
    start_cpu, start_wall = clock(), WALL()
    result = call()
    return result, Timing(clock() - start_cpu, WALL() - start_wall)


def growth_exponent(sizes: Sequence[float], costs: Sequence[float]) -> float:
    """p of the least-squares fit cost = c size^p on log-log axes."""
    return float(np.polyfit(np.log(sizes), np.log(costs), 1)[0])


def load_average() -> str:
    """The 1, 5 and 15 minute load averages, e.g. "2.1, 1.7, 1.2"."""
    return ", ".join(f"{x:.1f}" for x in os.getloadavg())


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
    return (f"{model}, {os.cpu_count()} logical cores, load average {load_average()}; Python "
            f"{platform.python_version()}, numpy {np.__version__}, Pinocchio {pinocchio.__version__}, "
            f"numba {numba.__version__}, {peer}")
