"""Sub-commands ``squeezer`` (Andrew's squeezer in one formulation, end state, residuals,
statistics, error against the reference; or with ``--table`` the tolerance-by-suppression
grids of the seed's Tables 8 and 9) and ``structure`` (matching, BLT blocks and
Pantelides' reduction of an example equation system)."""
from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable

from youbot_dynamics.cli.common import output_file
from youbot_dynamics.dynamics.constraints import FORMULATIONS
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.constrained import DAE_INTEGRATORS
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.integrate.registry import INTEGRATORS
from youbot_dynamics.studies.structure import STRUCTURE_EXAMPLES, structure_report


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `squeezer` and `structure`."""
    squeezer = subparsers.add_parser(
        "squeezer", help="Andrew's squeezer: a constrained mechanism in one formulation")
    squeezer.add_argument("--formulation", choices=FORMULATIONS, default="index1-projection")
    squeezer.add_argument("--integrator", choices=tuple(dict.fromkeys(INTEGRATORS
                                                                   + DAE_INTEGRATORS)),
                          default=None, help="default: radau5 for index3, ida for "
                                             "index2/ggl, rk45 otherwise")
    squeezer.add_argument("--rtol", type=float, default=1e-6)
    squeezer.add_argument("--t-end", type=float, default=0.03, help="end time (s)")
    squeezer.add_argument("--outputs", type=int, default=500,
                          help="output times (projections happen at these; default the "
                               "seed's 500)")
    squeezer.add_argument("--dt", type=float, default=None, help="fixed step (s)")
    squeezer.add_argument("--jacobian", choices=("exact", "fd"), default="exact",
                          help="IDA's iteration matrix for index2/ggl/index3: exact (from "
                               "the sympy model) or IDA's finite differences")
    squeezer.add_argument("--plot", metavar="PNG",
                          help="plot the drift of index1 vs index1-baumgarte vs "
                               "index1-projection with the chosen ODE integrator")
    squeezer.add_argument("--table", action="store_true",
                          help="instead of one run: the tolerance-by-suppression grids "
                               "(index 3 and index 2; IDA with and without suppress-alg, "
                               "radau5 with and without index scaling), the seed's beside")
    squeezer.add_argument("--tolerances", type=float, nargs="+", default=None,
                          help="rtol = atol values of --table (default 1e-4 1e-6 1e-8)")
    squeezer.add_argument("--json", action="store_true")
    squeezer.set_defaults(run=run_squeezer)

    structure = subparsers.add_parser(
        "structure", help="structural analysis (matching, BLT, Pantelides) of an example")
    structure.add_argument("example", choices=STRUCTURE_EXAMPLES)
    structure.add_argument("--json", action="store_true")
    structure.set_defaults(run=run_structure)


#: Shown with every index-3 run on IDA (see dynamics/constraints.py, "Error test").
INDEX3_CAVEAT = ("IDA runs index 3 with v, w and lambda under a loose absolute tolerance "
                 "(in its error test, or out of it by IDASetSuppressAlg, they make it fail "
                 "at t = 0: see squeezer --table): the velocity along the motion is not "
                 "error-controlled and q's error is 1e2 to 1e4 times rtol; prefer "
                 "--integrator radau5 (the default: Hairer's index-scaled error test)")
#: Table numbers of the seed for each formulation's suppression grid.
SEED_TABLES = {"index3": 8, "index2": 9}


def format_vector(values: Iterable[float]) -> str:
    """Numbers side by side, 10 significant digits, signs aligned."""
    return " ".join(f"{value: .10g}" for value in values)


def run_squeezer(args: argparse.Namespace) -> int:
    """Simulate the squeezer; print end state, residuals, statistics and the error against
    the reference (or JSON); exit 1 if the integrator fails."""
    from youbot_dynamics.studies.squeezer import (POSITION_NAMES, T_REFERENCE, plot_drift,
                                                  reference_error, simulate_squeezer)
    if args.table:
        return run_suppression_tables(args)
    if not args.rtol > 0:
        raise UserInputError(f"--rtol must be positive, got {args.rtol!r}")
    if args.plot:
        output_file(args.plot, "--plot")
    options = dict(rtol=args.rtol, t_end=args.t_end, n_outputs=args.outputs, dt=args.dt)
    try:
        run = simulate_squeezer(args.formulation, args.integrator,
                                exact_jacobian=args.jacobian == "exact", **options)
        if args.plot:
            ode = run.stats.integrator if run.stats.integrator != "ida" else "rk45"
            plot_drift([simulate_squeezer(name, ode, **options)
                        for name in ("index1", "index1-baumgarte", "index1-projection")],
                       args.plot)
    except (IntegrationError, NotImplementedError) as error:
        print(f"youbot-dynamics squeezer: {args.formulation} failed: {error}",
              file=sys.stderr)
        return 1
    report = run.as_dict()
    index3_on_ida = run.formulation == "index3" and run.stats.integrator == "ida"
    if index3_on_ida:
        report["caveat"] = INDEX3_CAVEAT
    if abs(args.t_end - T_REFERENCE) < 1e-15:
        report["relative_error_vs_reference"] = reference_error(run.q[-1]).tolist()
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"Andrew's squeezer, {run.formulation} with {run.stats.integrator}, "
          f"rtol {args.rtol:g}, t = {report['t_end']:g} s")
    print(f"{'':10s} {'q (rad)':>18s} {'v (rad/s)':>18s}"
          + (f" {'rel. error q':>14s}" if "relative_error_vs_reference" in report else ""))
    for i, name in enumerate(POSITION_NAMES):
        line = f"{name:10s} {run.q[-1, i]:18.12g} {run.v[-1, i]:18.10g}"
        if "relative_error_vs_reference" in report:
            line += f" {report['relative_error_vs_reference'][i]:14.3e}"
        print(line)
    print(f"lambda     {format_vector(run.multipliers[-1])}")
    print(f"g(q)       {format_vector(run.position_residual[-1])}")
    print(f"G v        {format_vector(run.velocity_residual[-1])}")
    print(run.stats.summary())
    if index3_on_ida:
        print(f"note: {INDEX3_CAVEAT}")
    if run.projection:
        print(f"projections {run.projection['projections']}, Gauss-Newton iterations "
              f"{run.projection['gauss_newton_iterations']}")
    if args.plot:
        print(f"drift plot written to {args.plot}")
    return 0


def run_suppression_tables(args: argparse.Namespace) -> int:
    """Print (or JSON) the suppression grids for index 3 and index 2: per tolerance and
    column, q's largest relative error at t = 0.03 s and the steps, or why the run failed;
    the seed's figures under each table."""
    from youbot_dynamics.studies.squeezer import (SEED_SUPPRESSION, SUPPRESSION_COLUMNS,
                                                  SUPPRESSION_TOLERANCES, T_REFERENCE,
                                                  suppression_table)
    tolerances = tuple(args.tolerances or SUPPRESSION_TOLERANCES)
    if not all(tol > 0 for tol in tolerances):
        raise UserInputError(f"--tolerances must be positive, got {list(tolerances)}")
    if args.outputs < 2:
        raise UserInputError(f"--outputs must be at least 2, got {args.outputs!r}")
    tables = {formulation: suppression_table(formulation, tolerances, args.outputs)
              for formulation in SEED_TABLES}
    if args.json:
        print(json.dumps({formulation: {
            "seed_table": SEED_TABLES[formulation], "seed": SEED_SUPPRESSION[formulation],
            "rows": [{"tol": tol, **{column: vars(cell) for column, cell in row.items()}}
                     for tol, row in table.items()]}
            for formulation, table in tables.items()}, indent=2))
        return 0
    width = max(len(column) for column in SUPPRESSION_COLUMNS)
    for formulation, table in tables.items():
        print(f"Seed Table {SEED_TABLES[formulation]}: Andrew's squeezer, {formulation}, "
              f"rtol = atol = tol, {args.outputs} outputs; q's largest relative error at "
              f"t = {T_REFERENCE:g} s against the test set, or why the run failed")
        for tol, row in table.items():
            print(f"  tol {tol:g}")
            for column, cell in row.items():
                print(f"    {column:{width}s}  {cell.verdict()}")
        print(f"  {SEED_SUPPRESSION[formulation]} (its grid is not in benchmarks.md)")
    return 0


def run_structure(args: argparse.Namespace) -> int:
    """Print the structural analysis of an example (or JSON)."""
    report = structure_report(args.example)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"Structural analysis: {args.example} (equations and variables numbered from 1)")
    print("variables: " + ", ".join(f"{j + 1}:{name}" for j, name in
                                    enumerate(report["variables"])))
    if "known" in report:
        print(f"known: {report['known']}")
    print("incidence matrix (rows equations, columns variables):")
    for name, row in zip(report["equations"], report["incidence"]):
        print(f"  {name:>4s} {row}")
    if "assign" in report:
        print(f"matching (variable -> equation, 0 = known): assign = {report['assign']}")
    else:
        print("matching of the highest derivatives: " + ", ".join(
            f"{v} -> {e}" for v, e in report["initial_matching"].items()))
        print(f"unmatched equations: {', '.join(report['unmatched_equations']) or 'none'}")
    print("reduction steps:")
    for step in report["steps"]:
        print(f"  {step}")
    if "vmap" in report:
        for key in ("vmap", "eqmap", "assignment"):
            print(f"{key}: " + ", ".join(f"{a} -> {b}" for a, b in report[key].items()))
        print("differentiated: " + ", ".join(f"{name} x{count}" for name, count in
                                             report["differentiations"].items()))
        print(f"{report['n_equations']} equations in {report['n_variables']} variables; "
              f"structural index {report['structural_index']}")
    print("blocks (BLT order): " + "  ".join(
        "[" + ", ".join(str(e) for e in block) + "]" for block in report["blocks"]))
    return 0

