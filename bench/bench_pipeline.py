"""The equation pipeline's cost (measured figures, not tests).

1. Stages 1-8 (order lowering to code generation) per example model: wall time of
   run_pipeline, best of REPEATS.
2. The generated right-hand side against the hand-written one for the ModiaLang pendulum
   (uncertain_pendulum.pendulum_rhs, L = 0.5 by the parameter merge): time per call,
   best of REPEATS over CALLS calls, and a cvode_bdf run over 10 s with each (steps,
   right-hand-side evaluations, wall time).

Times are CPU time (bench/timing.py); the cvode_bdf runs report their own wall time.
Run: python bench/bench_pipeline.py      (about 15 s; BENCH_SMOKE=1: one repeat, 20 calls, 0.1 s)
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import best_per_call, sized  # noqa: E402
from youbot_dynamics.integrate.integrators import integrate, tolerances_from_tol  # noqa: E402
from youbot_dynamics.studies.equations import EXAMPLE_MODELS, modia_pendulum  # noqa: E402
from youbot_dynamics.studies.pipeline import run_pipeline  # noqa: E402
from youbot_dynamics.studies.uncertain_pendulum import pendulum_rhs  # noqa: E402

REPEATS, CALLS = sized((3, 20000), (1, 20))
SPAN = sized(10.0, 0.1)  # s of the cvode_bdf runs


def best_time(function, repeats: int = REPEATS) -> float:
    """The least CPU time (s, the measuring thread's) of ``repeats`` calls of ``function()``."""
    return best_per_call([function], 1, repeats)[0]


def main() -> None:
    print("stages 1-8 (run_pipeline), best of", REPEATS)
    for name, build in EXAMPLE_MODELS.items():
        model = build()
        print(f"  {name:<15s} {best_time(lambda: run_pipeline(model)) * 1e3:8.1f} ms")

    generated = run_pipeline(modia_pendulum() | {"L": 0.5}).ode

    def hand_written(t: float, x: np.ndarray) -> np.ndarray:
        return np.array(pendulum_rhs(x[0], x[1], 0.5, 1.0, 0.5, np.sin))

    state = generated.x0
    print(f"right-hand side per call, best of {REPEATS} x {CALLS} calls")
    for label, rhs in (("generated", generated.rhs), ("hand-written", hand_written)):
        seconds = best_time(lambda: [rhs(0.0, state) for _ in range(CALLS)])
        print(f"  {label:<13s} {seconds / CALLS * 1e6:6.2f} us")
    print(f"cvode_bdf over {SPAN:g} s at tol 1e-6")
    t_eval = np.linspace(0.0, SPAN, 201)
    rtol, atol = tolerances_from_tol(1e-6, state)
    for label, rhs in (("generated", generated.rhs), ("hand-written", hand_written)):
        stats = integrate(rhs, state, t_eval, "cvode_bdf", rtol=rtol, atol=atol).stats
        print(f"  {label:<13s} {stats.steps} steps, {stats.rhs_evals} rhs evaluations, "
              f"wall {stats.wall_time * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
