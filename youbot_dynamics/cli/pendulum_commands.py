"""Sub-commands `pendulum` (simulate the elastic pendulum with any integrator),
`pendulum-study` (the seed's tables beside ours) and `bdf-study` (fixed-step BDF1-4,
stability regions, CVODE order caps)."""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from youbot_dynamics.cli.common import (add_sweep_arguments, add_tolerance_arguments, cell,
                                        markdown_table, tolerances)
from youbot_dynamics.cli.sim_commands import (add_step_budget_argument, checked_step_budget,
                                              progress_bar)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import IntegrationError, checked_output_spacing
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.studies.elastic_pendulum import (ACCURATE_ENERGY_ERROR, JACOBIANS, SEED_STATE0,
                                                      SEED_T_END, STABLE_BOUND, STABLE_ENERGY_ERROR,
                                                      STATE_NAMES, elastic_pendulum_study,
                                                      simulate_elastic_pendulum)


def parse_state0(text: str) -> tuple[float, ...]:
    """'x,y,vx,vy' -> four floats; UserInputError naming --state0 otherwise."""
    try:
        values = tuple(float(part) for part in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 4:
        raise UserInputError(f"--state0 must be four comma-separated numbers x,y,vx,vy, "
                             f"got {text!r}")
    return values


#: The seed's integrator, and the one --tol picks when none is named: its global error on
#: ``--k 1000 --state0 1.1,0,0,0 --t-end 10`` measured 8.6e-11 at tol 1e-12 where
#: cvode_bdf's was 1.7e-8 (both local-error controlled; the run spans 50 periods).
DEFAULT_INTEGRATOR, ACCURATE_INTEGRATOR = "cvode_bdf", "dop853"
#: Output times of `pendulum` (equally spaced over [0, --t-end]).
OUTPUTS = 201
#: --rtol/--atol when neither they nor --tol are given.
DEFAULT_RTOL = DEFAULT_ATOL = 1e-6


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `pendulum` and `pendulum-study`."""
    run = subparsers.add_parser("pendulum", help="simulate the elastic pendulum",
                                description="Simulate the elastic pendulum (unit mass, "
                                "length, gravity) and print the final state, the energy "
                                "error and the integrator statistics.")
    run.add_argument("--k", type=float, default=10.0, help="spring stiffness (default 10)")
    run.add_argument("--state0", default=",".join(f"{v:g}" for v in SEED_STATE0),
                     help="x,y,vx,vy at t=0 (default the seed's 1.2,0,0,0)")
    run.add_argument("--t-end", type=float, default=SEED_T_END, help="end time, s")
    run.add_argument("--integrator",
                     help=f"one of {', '.join(n for n in INTEGRATORS if n != 'ida')} "
                          f"(default {DEFAULT_INTEGRATOR}; with --tol {ACCURATE_INTEGRATOR})")
    run.add_argument("--dt", type=float, help="step size for fixed-step integrators, s")
    add_tolerance_arguments(run, DEFAULT_RTOL, f"absolute tolerance (default {DEFAULT_ATOL:g})")
    add_step_budget_argument(run)
    run.add_argument("--max-order", type=int, metavar="N",
                     help="cap CVODE's order (cvode_bdf 1..5, cvode_adams 1..12)")
    run.add_argument("--jacobian", choices=JACOBIANS, default="analytic",
                     help="implicit integrators: our analytic Jacobian (default) or their "
                          "own difference quotients (as the seed's runs)")
    run.add_argument("--json", action="store_true", help="print JSON")
    run.set_defaults(run=run_pendulum)
    study = subparsers.add_parser("pendulum-study", help="the seed's elastic-pendulum tables",
                                  description="Reproduce the seed's elastic-pendulum tables "
                                  "with our integrators, seed figures beside ours.")
    study.add_argument("--json", action="store_true", help="print JSON")
    study.set_defaults(run=run_study)
    bdf = subparsers.add_parser("bdf-study", help="fixed-step BDF1-4: the seed's Tables 1-4, "
                                "stability regions, measured orders, CVODE order caps",
                                description="The seed's fixed-step study of the elastic "
                                "pendulum (explicit Euler, BDF2-4 over k and N) with its "
                                "verdicts beside ours, the BDF stability regions, measured "
                                "orders, and CVODE BDF with its order capped.")
    bdf.add_argument("--short", action="store_true",
                     help="only the cells the seed gives a verdict for, no CVODE order 1 "
                          "at k = 50 (a short form for CI)")
    bdf.add_argument("--plot", metavar="PNG", help="write the stability-region plot")
    bdf.add_argument("--choppy", metavar="PNG", help="write the seed's loose-tolerance "
                     "traces: CVODE BDF and Adams at rtol = atol = 0.1, k = 10")
    add_sweep_arguments(bdf)
    bdf.add_argument("--json", action="store_true", help="print JSON")
    bdf.set_defaults(run=run_bdf_study)


def run_pendulum(args: argparse.Namespace) -> int:
    """Simulate and print final state, energy error and statistics."""
    integrator = args.integrator or (DEFAULT_INTEGRATOR if args.tol is None
                                     else ACCURATE_INTEGRATOR)
    if args.dt is not None and integrator not in FIXED_STEP:
        raise UserInputError(f"--dt applies to fixed-step integrators only, not "
                             f"{integrator!r}; use --tol or --rtol/--atol")
    if args.max_order is not None and not integrator.startswith("cvode"):
        raise UserInputError(f"--max-order applies to cvode_bdf and cvode_adams only, not "
                             f"{integrator!r}")
    state0 = parse_state0(args.state0)
    rtol, atol = tolerances(args, state0)
    times = np.linspace(0.0, args.t_end, OUTPUTS) if args.t_end > 0 else np.zeros(0)
    steps = 0
    if args.dt is not None and times.size:
        checked_output_spacing(args.dt, times, f"--dt (outputs every --t-end/{OUTPUTS - 1})")
        steps = checked_step_budget(integrator, args.dt, times, args.max_steps)
    try:
        with progress_bar("pendulum", steps, 0.0, args.t_end, not args.json) as progress:
            solution, energy_error = simulate_elastic_pendulum(
                args.k, state0, args.t_end, integrator, dt=args.dt,
                rtol=DEFAULT_RTOL if rtol is None else rtol,
                atol=DEFAULT_ATOL if atol is None else atol, n_out=OUTPUTS,
                max_steps=args.max_steps, progress=progress, max_order=args.max_order,
                jacobian=args.jacobian)
    except IntegrationError as error:
        print(f"youbot-dynamics pendulum: {error}", file=sys.stderr)
        return 1
    final = dict(zip(STATE_NAMES, map(float, solution.x[-1])))
    if args.json:
        print(json.dumps({"k": args.k, "t_end": float(solution.t[-1]), "final_state": final,
                          "energy_error": energy_error, "stats": solution.stats.as_dict()}))
        return 0
    print(f"elastic pendulum k={args.k:g}, {integrator}, t={solution.t[-1]:g} s")
    print("final state: " + ", ".join(f"{name}={value:.9g}" for name, value in final.items()))
    print(f"energy error max|E-E0|: {energy_error:.3e}")
    print(f"statistics: {solution.stats.summary()}")
    return 0


TABLE_TITLES = {
    "euler_stability": f"Explicit Euler on [0, {SEED_T_END:g}] from x0 = 1.2 (stable: finite, "
                       f"|state| <= {STABLE_BOUND:g} and max|E-E0| < {STABLE_ENERGY_ERROR:g}; "
                       f"accurate: max|E-E0| < {ACCURATE_ENERGY_ERROR:g})",
    "cvode_statistics": "Statistics at rtol = atol = 1e-6 from x0 = 1.2 on [0, 20] (CVODE "
                        "and LSODA with their own difference-quotient Jacobians, as the "
                        "seed's runs; scipy's LSODA beside the seed's LSODAR)",
    "energy_error": "Energy error max|E-E0| versus step size / tolerance",
}
COLUMNS = ("integrator", "k", "setting", "verdict", "energy_error", "steps", "rhs_evals",
           "jac_evals", "wall_time", "seed")
TEXT_COLUMNS = ("integrator", "setting", "verdict", "seed")


def run_study(args: argparse.Namespace) -> int:
    """Print the study's tables (markdown) or JSON rows."""
    rows = elastic_pendulum_study()
    if args.json:
        print(json.dumps([row.as_dict() for row in rows]))
        return 0
    for table, title in TABLE_TITLES.items():
        print(f"\n{title}\n")
        print(markdown_table(COLUMNS, ([(getattr(row, c) or "-") if c in TEXT_COLUMNS else getattr(row, c)
                                        for c in COLUMNS] for row in rows if row.table == table), digits=3))
        for row in rows:
            if row.table == table and row.verdict and row.seed and row.verdict != row.seed:
                print(f"- k={row.k:g} {row.setting}: the seed says {row.seed!r}, our energy "
                      f"criterion {row.verdict!r} (max|E-E0| {cell(row.energy_error)}); "
                      f"bdf-study judges position against a reference instead")
    return 0


FIXED_STEP_COLUMNS = ("k", "n_steps", "h_omega", "seed", "verdict", "energy_verdict",
                      "energy_growth", "energy_error", "position_error", "diverged_at",
                      "newton_iterations")
METHOD_TITLES = {"euler": "Table 1: explicit Euler", "bdf2": "Table 2: BDF2",
                 "bdf3": "Table 3: BDF3", "bdf4": "Table 4: BDF4"}


def run_bdf_study(args: argparse.Namespace) -> int:
    """Print (or JSON) Tables 1-4, the stability figures, measured orders and the CVODE
    order-cap rows; optionally plot the stability regions."""
    import math

    from youbot_dynamics.accuracy.sweeps import map_cases
    from youbot_dynamics.cli.common import output_file
    from youbot_dynamics.studies.bdf import (alpha_angle, locus_radius_on_ray,
                                             measured_boundary_radius, plot_stability_regions)
    from youbot_dynamics.studies.bdf_study import (ENERGY_GROWTH, METHODS, POSITION_TOLERANCE,
                                                   REFERENCE_TOL, cvode_order_rows,
                                                   fixed_step_tables, measured_orders,
                                                   plot_choppy_traces, stability_points)
    for path, flag in ((args.plot, "--plot"), (args.choppy, "--choppy")):
        if path:
            output_file(path, flag)
    rows = fixed_step_tables(seed_only=args.short)
    measured = map_cases(measured_boundary_radius, [(order, 0.0, 1e-3, 20.0, 20) for order in
                                                    (1, 2, 3, 4)], workers=args.workers,
                         scheduler=args.scheduler, desc="stability boundaries",
                         progress=not args.json)
    stability = [{"order": order, "alpha_deg": math.degrees(alpha_angle(order)),
                  "real_axis_boundary": locus_radius_on_ray(order, 0.0),
                  "measured_by_solver": radius}
                 for order, radius in zip((1, 2, 3, 4), measured)]
    orders = measured_orders()
    cvode = cvode_order_rows((10,) if args.short else (10, 50))
    if args.plot:
        plot_stability_regions(args.plot, points=stability_points(
            [row for row in rows if row.n_steps == 1000]))
    choppy = plot_choppy_traces(args.choppy) if args.choppy else None
    if args.json:
        print(json.dumps({"tables": [row.as_dict() for row in rows], "stability": stability,
                          "measured_orders": orders, "cvode_max_order": cvode,
                          "choppy": choppy, "plot": args.plot}, indent=2))
        return 0
    print(f"Elastic pendulum on [0, {SEED_T_END:g}] from x0 = 1.2 at rest, N fixed steps. "
          f"Our verdict: unstable if the run diverges or its energy grows by more than "
          f"{ENERGY_GROWTH:g}; accurate if (x, y) stays within {POSITION_TOLERANCE:g} m of "
          f"DOP853 at rtol = atol = {REFERENCE_TOL:g} (outputs every 0.1 s). energy_verdict "
          f"is pendulum-study's (unstable at max|E-E0| >= {STABLE_ENERGY_ERROR:g}, accurate "
          f"below {ACCURATE_ENERGY_ERROR:g}). h_omega = h sqrt(k).")
    for method in METHODS:
        print(f"\n{METHOD_TITLES[method]}\n")
        print(markdown_table(FIXED_STEP_COLUMNS, ([getattr(row, c) if getattr(row, c) != ""
                                                   else "-" for c in FIXED_STEP_COLUMNS]
                                                  for row in rows if row.method == method),
                             digits=3))
    print("\nStability: A(alpha) angle and the real-axis boundary h lambda of each BDF, "
          "from the root locus and measured by bisection on the solver's own growth on "
          "x' = lambda x\n")
    print(markdown_table(tuple(stability[0]), ([r[c] for c in r] for r in stability), digits=6))
    print("\nMeasured orders (elastic pendulum k = 10 on [0, 2], final-state error against "
          "DOP853 at 1e-13)\n")
    print(markdown_table(("order", "error N=400", "error N=800", "measured_order"),
                         ([r["order"], *r["errors"], r["measured_order"]] for r in orders),
                         digits=4))
    print("\nCVODE BDF at rtol = atol = 1e-6, order capped (its difference-quotient "
          "Jacobian, as the seed's runs)\n")
    print(markdown_table(tuple(cvode[0]), ([r[c] for c in r] for r in cvode), digits=4))
    if args.plot:
        print(f"\nplot written to {args.plot}")
    if choppy:
        print(f"rtol = atol = 0.1 traces written to {args.choppy}: " + "; ".join(
            f"{name} {figures['steps']} steps, position off by up to "
            f"{figures['position_error']:.2f} m" for name, figures in choppy.items()))
    return 0
