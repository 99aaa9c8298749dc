"""Sub-commands for the classic studies: ``woodpecker`` (the hybrid woodpecker toy),
``lagrange`` (equations of motion by computer algebra), ``rotations`` (Cardan angles,
adaptive Cardan and quaternions on a free rigid body) and ``uncertainty`` (the pendulum
with uncertain parameters: linear propagation against Monte Carlo)."""
from __future__ import annotations

import argparse
import json

from youbot_dynamics.cli.common import (add_sweep_arguments, add_tolerance_arguments, cell,
                                        markdown_table, output_file, positive, relative_tolerance,
                                        tolerances)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.events import HybridSolution
from youbot_dynamics.integrate.integrators import IntegratorStats
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.model import limits

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
    from youbot_dynamics.studies.woodpecker import BEAK
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
    from youbot_dynamics.studies.woodpecker import (SEED_BEAK_HITS, SEED_FIGURES,
                                                    SEED_INITIAL_STATE, Woodpecker, plot_woodpecker)
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


def parameter_overrides(items: list[str] | None) -> dict[str, float]:
    """``NAME=VALUE`` items of --param as a dict; UserInputError naming a malformed one."""
    overrides = {}
    for item in items or ():
        name, _, value = item.partition("=")
        try:
            overrides[name.strip()] = float(value)
        except ValueError:
            raise UserInputError(f"--param takes NAME=VALUE with a number, got {item!r}") from None
    return overrides


def run_lagrange(args: argparse.Namespace) -> int:
    """Derive the pendulum's equations with sympy, simulate them and print the equations,
    final state, energy drift and statistics (or JSON)."""
    import numpy as np

    from youbot_dynamics.integrate.integrators import integrate
    from youbot_dynamics.studies.lagrange import SEED_INITIAL, model
    lagrange = model(args.problem)
    p = lagrange.parameter_values({**parameter_overrides(args.param), "c": args.friction})
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


def run_uncertainty(args: argparse.Namespace) -> int:
    """The uncertainty study: linear propagation against Monte Carlo, figures (or JSON)
    and optionally the band plot."""
    from youbot_dynamics.studies.uncertain_pendulum import (FAILURE_FLOOR, FAILURE_RATIO,
                                                            comparison, linear_propagation,
                                                            monte_carlo, plot_uncertainty)
    if args.plot:
        output_file(args.plot, "--plot")
    if args.samples < 2:
        raise UserInputError(f"--samples must be at least 2, got {args.samples}")
    linear = linear_propagation(args.t_end)
    sampled, phi = monte_carlo(args.samples, args.t_end, args.seed, workers=args.workers,
                               scheduler=args.scheduler)
    figures = comparison(linear, sampled)
    if args.plot:
        plot_uncertainty(linear, sampled, phi, args.plot)
    if args.json:
        print(json.dumps({**figures, "samples": args.samples, "seed": args.seed,
                          "plot": args.plot}, indent=2))
        return 0
    print(f"Damped pendulum, L = 0.8 +- 0.2 m, m = 1 +- 0.2 kg, d = 0.5 +- 0.2 N m s/rad, "
          f"phi0 = 1.57 rad; RK4 h = 0.01 s; linear propagation (uncertainties) against "
          f"{args.samples} Monte Carlo samples (seed {args.seed})")
    print(f"at t = {figures['t_end']:g} s: sigma(phi) linear {figures['sigma_linear_end']:.4g} "
          f"rad, Monte Carlo {figures['sigma_monte_carlo_end']:.4g} rad (2-sigma bands "
          f"{figures['band_width_linear_end']:.4g} and {figures['band_width_monte_carlo_end']:.4g}"
          f" rad wide); means differ by {figures['mean_difference_end']:.3g} rad")
    fails = figures["linearisation_fails_at"]
    print(f"sigma_linear / sigma_MC ranges over [{figures['min_ratio']:.3g}, "
          f"{figures['max_ratio']:.3g}]; linearisation fails (beyond +-{FAILURE_RATIO:.0%} "
          f"and {FAILURE_FLOOR:g} rad) "
          + ("nowhere" if fails is None else f"first at t = {fails:g} s"))
    print(f"wall time: linear {figures['wall_time_linear']:.3g} s, Monte Carlo "
          f"{figures['wall_time_monte_carlo']:.3g} s")
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


ROTATION_COLUMNS = ("run", "formulation", "steps", "rhs_evals", "switches", "t_reached",
                    "attitude_error", "rate_error", "norm_drift", "wall_time")


def run_rotations(args: argparse.Namespace) -> int:
    """Every orientation formulation on every run of the rotations study; a table (or
    JSON) of steps, evaluations, errors against the closed-form top and |q| drift."""
    from youbot_dynamics.studies.rotations import (RUNS, SWITCH_ANGLE, plot_rotations,
                                                   rotations_study, spin_wobble_sweep)
    if args.plot:
        output_file(args.plot, "--plot")
    results = rotations_study(args.integrator, args.tol, runs=tuple(args.runs or RUNS))
    rows = [result.summary() for result in results]
    sweep = spin_wobble_sweep(args.integrator, args.tol) if "spin" in (args.runs or RUNS) else []
    if args.plot:
        plot_rotations(results, args.plot)
    if args.json:
        print(json.dumps({"integrator": args.integrator, "tol": args.tol, "rows": rows,
                          "spin_wobble_sweep": sweep, "plot": args.plot}, indent=2))
        return 0
    print(f"Rotations study, {args.integrator} at rtol = atol = {args.tol:g}; errors are "
          f"maxima over the outputs against the closed-form axisymmetric top (attitude: "
          f"|log(R_true^T R)|, rad; rate: |w - w_true|, rad/s). cardan_adaptive switches "
          f"x-y-z <-> x-z-y at |a2| = {SWITCH_ANGLE} rad; the quaternion is integrated "
          f"unprojected and renormalised on output (norm_drift = max ||q| - 1|).\n")
    for name in dict.fromkeys(row["run"] for row in rows):
        print(f"{name}: {RUNS[name].purpose}")
    print()
    print(markdown_table(ROTATION_COLUMNS, ([row[c] for c in ROTATION_COLUMNS] for row in rows),
                         digits=3))
    if sweep:
        print(f"\nspin with less and less wobble (w0 = ({RUNS['spin'].w0[0]:g}, wobble, 0) "
              f"rad/s): fixed Cardan against the quaternion\n")
        print(markdown_table(tuple(sweep[0]), ([row[c] for c in sweep[0]] for row in sweep),
                             digits=3))
    for row in rows:
        if row["failure"]:
            print(f"{row['run']} / {row['formulation']} failed: {row['failure']}")
    if args.plot:
        print(f"plot written to {args.plot}")
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
    parser.add_argument("--param", action="append", metavar="NAME=VALUE",
                        help="override a model parameter (SI), e.g. --param m2=0.5; "
                             "repeatable")
    parser.add_argument("--t-end", type=positive, default=10.0, help="end time (s)")
    parser.add_argument("--integrator", choices=[n for n in INTEGRATORS
                                                 if n not in FIXED_STEP and n != "ida"],
                        default="dop853")
    add_tolerance_arguments(parser, LAGRANGE_RTOL, "absolute tolerance (default rtol)")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(run=run_lagrange)

    from youbot_dynamics.studies.rotations import RUNS
    parser = subparsers.add_parser("rotations", help="Cardan angles vs adaptive Cardan vs "
                                   "quaternions on a torque-free rigid body",
                                   description="The seed's rotations study: steps, "
                                   "evaluations, error against the closed-form top and "
                                   "|q| drift of each orientation state on each run.")
    parser.add_argument("--runs", nargs="+", choices=tuple(RUNS), help="runs (default all)")
    parser.add_argument("--integrator", choices=[n for n in INTEGRATORS
                                                 if n not in FIXED_STEP and n != "ida"],
                        default="rk45")
    parser.add_argument("--tol", type=relative_tolerance, default=1e-8,
                        help="rtol = atol (default 1e-8)")
    parser.add_argument("--plot", metavar="PNG", help="write the error and middle-angle plot")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(run=run_rotations)

    parser = subparsers.add_parser("uncertainty", help="the damped pendulum with uncertain "
                                   "L, m, d: linear propagation against Monte Carlo")
    parser.add_argument("--samples", type=int, default=1000, help="Monte Carlo samples")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the samples")
    parser.add_argument("--t-end", type=positive, default=10.0, help="end time (s)")
    parser.add_argument("--plot", metavar="PNG", help="write the band plot")
    add_sweep_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(run=run_uncertainty)
