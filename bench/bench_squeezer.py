"""Andrew's squeezer at matched accuracy: for each formulation and integrator the loosest
rtol in 1e-3, 10^-3.5, ..., 1e-12 whose q at t = 0.03 s is within 1e-6 (max relative,
per component) of the test set's reference; its statistics beside the seed's figures.
The DAE forms (IDA) run with the exact iteration matrix and with IDA's finite differences.

Run: python bench/bench_squeezer.py [--outputs N] [--target E]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import sized  # noqa: E402
from youbot_dynamics.integrate.integrators import IntegrationError  # noqa: E402
from youbot_dynamics.studies.squeezer import SEED_FIGURES, reference_error, simulate_squeezer  # noqa: E402

#: (formulation, integrator, Jacobian: "exact" or "fd" for IDA, "" for ODE integrators)
CASES = [("index1", "rk45", ""), ("index1", "dop853", ""), ("index1", "cvode_adams", ""),
         ("index1", "radau", ""), ("index1-baumgarte", "rk45", ""),
         ("index1-baumgarte", "dop853", ""), ("index1-projection", "rk45", ""),
         ("index1-projection", "dop853", "")] + [
    (formulation, "ida", jacobian) for formulation in ("index2", "ggl", "index3")
    for jacobian in ("exact", "fd")]
RTOLS = 10.0 ** -np.arange(3.0, 12.01, 0.5)
#: BENCH_SMOKE=1: one ODE and one DAE case, rtol 1e-3 alone, target 1e-2
CASES, RTOLS = sized((CASES, RTOLS), ([CASES[0], CASES[-2]], RTOLS[:1]))


def matched_run(formulation: str, integrator: str, jacobian: str, target: float,
                outputs: int):
    """The loosest rtol meeting the target, its run and error; None if none does."""
    for rtol in RTOLS:
        try:
            run = simulate_squeezer(formulation, integrator, rtol=rtol, n_outputs=outputs,
                                    exact_jacobian=jacobian != "fd")
        except IntegrationError:
            continue
        error = float(np.max(reference_error(run.q[-1])))
        if error <= target:
            return rtol, run, error
    return None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--outputs", type=int, default=31,
                        help="output times on [0, 0.03] s (projection happens at each)")
    parser.add_argument("--target", type=float, default=sized(1e-6, 1e-2))
    args = parser.parse_args()
    header = (f"{'formulation':18s} {'integrator':12s} {'J':5s} {'rtol':>8s} {'steps':>6s} "
              f"{'f-evals':>8s} {'J-evals':>8s} {'err-fail':>8s} {'wall s':>8s} "
              f"{'max rel err':>11s}")
    print(f"Andrew's squeezer, t = 0.03 s, target {args.target:g}, {args.outputs} outputs")
    print(header)
    print("-" * len(header))
    for formulation, integrator, jacobian in CASES:
        found = matched_run(formulation, integrator, jacobian, args.target, args.outputs)
        label = f"{formulation:18s} {integrator:12s} {jacobian:5s}"
        if found is None:
            print(f"{label} no rtol down to 1e-12 met the target", flush=True)
            continue
        rtol, run, error = found
        s = run.stats
        print(f"{label} {rtol:8.1e} {s.steps:6d} {s.rhs_evals:8d} "
              f"{'n/a' if s.jac_evals is None else s.jac_evals:>8} "
              f"{'n/a' if s.rejected_steps is None else s.rejected_steps:>8} {s.wall_time:8.3f} "
              f"{error:11.2e}", flush=True)
    print("\nSeed figures (500 outputs, accuracy not matched):")
    for name, figures in SEED_FIGURES.items():
        print(f"  {name:22s} " + ", ".join(f"{k} {v}" for k, v in figures.items()))


if __name__ == "__main__":
    main()
