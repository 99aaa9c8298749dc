"""Sub-commands for the classic studies: ``woodpecker`` (the hybrid woodpecker toy) and
``lagrange`` (equations of motion by computer algebra)."""
from __future__ import annotations

import argparse
import json

from youbot_dynamics.cli.common import add_tolerance_arguments, cell, output_file, positive, tolerances
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model import limits
from youbot_dynamics.sim.events import HybridSolution
from youbot_dynamics.sim.integrators import IntegratorStats
from youbot_dynamics.sim.registry import FIXED_STEP, INTEGRATORS

#: Tolerances without --tol/--rtol: the woodpecker's (atol = rtol/100), lagrange's (atol = rtol).
WOODPECKER_RTOL, LAGRANGE_RTOL = 1e-6, 1e-12
#: Output samples per simulated second of the woodpecker's plot, Hz.
PLOT_RATE = 2000
#: Columns of the statistics tables, as in the seed's tables 15 and 16.
STAT_COLUMNS = (("steps", "steps"), ("rhs_evals", "f-evals"), ("jac_evals", "J-evals"),
                ("events", "state events"), ("wall_time", "CPU time (s)"))


def non_negative(text: str) -> float:
    """An argparse type: a float >= 0."""
    value = float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return value


def stats_table(rows: dict[str, dict]) -> str:
    """A text table: one row per run (name -> statistics dict), the seed's columns."""
    header = f"{'run':<24}" + "".join(f"{title:>14}" for _, title in STAT_COLUMNS)
    lines = [header]
    for name, stats in rows.items():
        lines.append(f"{name:<24}" + "".join(f"{cell(stats.get(key)):>14}" for key, _ in STAT_COLUMNS))
    return "\n".join(lines)


def woodpecker_summary(solution: HybridSolution, stats: IntegratorStats) -> dict:
    """The woodpecker run's figures as plain data."""
    from youbot_dynamics.systems.woodpecker import BEAK
    return {
        "beak_hits": solution.count(BEAK),
        "switches": [{"time": s.time, "kind": s.kind, "from": s.mode_before,
                      "to": s.mode_after} for s in solution.switches],
        "final_state": dict(zip(solution.state_names, solution.x[-1].tolist())),
        "final_mode": solution.mode[-1],
        "stats": stats.as_dict(),
    }


def run_woodpecker(args: argparse.Namespace) -> int:
    """Simulate the woodpecker toy; print beak hits, mode switches, final state and the
    statistics beside the seed's (or JSON); optionally plot."""
    from youbot_dynamics.systems.woodpecker import (SEED_BEAK_HITS, SEED_FIGURES,
                                                    SEED_INITIAL_STATE, Woodpecker,
                                                    plot_woodpecker)
    if args.integrator in FIXED_STEP and args.dt is None:
        raise UserInputError(f"--integrator {args.integrator} is fixed-step: give --dt")
    if args.plot:
        output_file(args.plot, "--plot")
        problem = limits.samples_problem(args.t_end, PLOT_RATE)
        if problem:
            raise UserInputError(f"--t-end with --plot: {problem}")
    woodpecker = Woodpecker()
    options = {} if args.dt is None else {"dt": args.dt}
    rtol, atol = tolerances(args, SEED_INITIAL_STATE)
    rtol = WOODPECKER_RTOL if rtol is None else rtol
    solution = woodpecker.simulate(args.t_end, args.integrator, rtol=rtol,
                                   atol=rtol * 1e-2 if atol is None else atol,
                                   n_out=int(args.t_end * PLOT_RATE) if args.plot else 0,
                                   **options)
    summary = woodpecker_summary(solution, solution.stats)
    if args.plot:
        plot_woodpecker(woodpecker, solution, args.plot)
        summary["plot"] = args.plot
    if args.json:
        summary["seed"] = {"beak_hits": SEED_BEAK_HITS, **SEED_FIGURES}
        print(json.dumps(summary, indent=2))
        return 0
    print(f"woodpecker toy over [0, {args.t_end:g}] s with {args.integrator} "
          f"(rtol {rtol:g}): {summary['beak_hits']} beak hits "
          f"(seed over 2 s: {SEED_BEAK_HITS})")
    for switch in summary["switches"]:
        print(f"  t = {switch['time']:.6f} s  {switch['kind']:<12} "
              f"{switch['from']} -> {switch['to']}")
    print(f"final mode {summary['final_mode']}, state "
          + ", ".join(f"{k}={v:.6g}" for k, v in summary["final_state"].items()))
    print(stats_table({f"{args.integrator} (ours)": summary["stats"], **SEED_FIGURES}))
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def run_lagrange(args: argparse.Namespace) -> int:
    """Derive the pendulum's equations with sympy, simulate them and print the equations,
    final state, energy drift and statistics (or JSON)."""
    import numpy as np

    from youbot_dynamics.sim.integrators import integrate
    from youbot_dynamics.systems.lagrange import SEED_INITIAL, model
    lagrange = model(args.problem)
    p = lagrange.parameter_values({"c": args.friction})
    q0, u0 = SEED_INITIAL[args.problem]
    rtol, atol = tolerances(args, np.r_[q0, u0])
    rtol = LAGRANGE_RTOL if rtol is None else rtol
    solution = integrate(lagrange.rhs(p), np.r_[q0, u0], np.linspace(0.0, args.t_end, 201),
                         args.integrator, rtol=rtol, atol=rtol if atol is None else atol,
                         state_names=[*map(str, lagrange.q), *map(str, lagrange.u)])
    energy = lagrange.energy_of(solution.x, p)
    summary = {
        "problem": args.problem, "friction": args.friction,
        "parameters": dict(zip(map(str, lagrange.parameters), p)),
        "equations": lagrange.equations(),
        "final_state": dict(zip(solution.state_names, solution.x[-1].tolist())),
        "energy_initial": float(energy[0]), "energy_final": float(energy[-1]),
        "energy_relative_drift": float(np.abs(energy - energy[0]).max() / abs(energy[0])),
        "energy_nonincreasing": bool(np.all(np.diff(energy) <= 1e-12)),
        "stats": solution.stats.as_dict(),
    }
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"Lagrange {args.problem}, friction c = {args.friction:g}, parameters "
          + ", ".join(f"{k}={v:g}" for k, v in summary["parameters"].items()))
    for line in summary["equations"]:
        print(f"  {line if len(line) <= 160 else line[:157] + '...'}")
    print(f"final state at t = {args.t_end:g} s: "
          + ", ".join(f"{k}={v:.6g}" for k, v in summary["final_state"].items()))
    print(f"energy {summary['energy_initial']:.10g} J -> {summary['energy_final']:.10g} J, "
          f"max relative drift {summary['energy_relative_drift']:.3g}, "
          f"non-increasing: {summary['energy_nonincreasing']}")
    print(stats_table({args.integrator: summary["stats"]}))
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``woodpecker`` and ``lagrange`` sub-commands."""
    parser = subparsers.add_parser("woodpecker", help="the woodpecker toy: state events, "
                                   "impacts, beak hits and statistics")
    parser.add_argument("--t-end", type=positive, default=2.0, help="end time (s)")
    parser.add_argument("--integrator", choices=INTEGRATORS, default="dop853")
    add_tolerance_arguments(parser, WOODPECKER_RTOL, "absolute tolerance (default rtol/100)")
    parser.add_argument("--dt", type=positive, help="step (s) for fixed-step integrators")
    parser.add_argument("--plot", metavar="PNG", help="write a plot of the run")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(run=run_woodpecker)

    parser = subparsers.add_parser("lagrange", help="equations of motion by sympy "
                                   "(Lagrange), simulated from the seed's initial state")
    parser.add_argument("problem", choices=("2d", "3d"))
    parser.add_argument("--friction", type=non_negative, default=0.0,
                        help="joint friction c: generalised force -c q_i'")
    parser.add_argument("--t-end", type=positive, default=10.0, help="end time (s)")
    parser.add_argument("--integrator", choices=[n for n in INTEGRATORS
                                                 if n not in FIXED_STEP and n != "ida"],
                        default="dop853")
    add_tolerance_arguments(parser, LAGRANGE_RTOL, "absolute tolerance (default rtol)")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(run=run_lagrange)
