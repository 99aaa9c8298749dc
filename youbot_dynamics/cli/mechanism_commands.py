"""The mechanism studies under ``study``: ``squeezer`` (Andrew's squeezer in one
formulation: end state, residuals, statistics, error against the reference; or with
``--table`` the tolerance-by-suppression grids of the source document's Tables 8 and 9),
``structure`` (matching, BLT blocks and Pantelides' reduction of an example equation
system) and ``woodpecker`` (the hybrid woodpecker toy). Each parses its options into the
study's config, runs it (studies/) and prints its text or, with ``--json``, its JSON
object."""
from __future__ import annotations

import argparse
import json
import sys

from youbot_dynamics.cli.common import (add_json, add_tolerance_arguments, output_file, positive,
                                        tolerances)
from youbot_dynamics.dynamics.constraints import FORMULATIONS
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.constrained import DAE_INTEGRATORS
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.model import limits
from youbot_dynamics.studies import squeezer, woodpecker
from youbot_dynamics.studies.structure import STRUCTURE_EXAMPLES, structure_report, structure_text

#: rtol of the squeezer without --tol/--rtol (atol = rtol / 1000 unless --atol).
SQUEEZER_RTOL = 1e-6
#: rtol of the woodpecker without --tol/--rtol (atol = rtol / 100 unless --atol).
WOODPECKER_RTOL = 1e-6
#: Output samples per simulated second of the woodpecker's plot, Hz.
PLOT_RATE = 2000


def add_squeezer(parser: argparse.ArgumentParser) -> None:
    """Options of ``study squeezer``."""
    parser.add_argument("--formulation", choices=FORMULATIONS, default="index1-projection")
    parser.add_argument("--integrator", choices=tuple(dict.fromkeys(INTEGRATORS + DAE_INTEGRATORS)),
                        default=None, help="default: radau5 for index3, ida for "
                                           "index2/ggl, rk45 otherwise")
    add_tolerance_arguments(parser, SQUEEZER_RTOL, "absolute tolerance (default rtol/1000)")
    parser.add_argument("--duration", type=float, default=squeezer.T_REFERENCE, metavar="S",
                        help=f"simulated time, s (default {squeezer.T_REFERENCE:g})")
    parser.add_argument("--outputs", type=int, default=500,
                        help="output times (projections happen at these; default the "
                             "source document's 500)")
    parser.add_argument("--dt", type=float, default=None, help="fixed step (s)")
    parser.add_argument("--jacobian", choices=("exact", "fd"), default="exact",
                        help="IDA's iteration matrix for index2/ggl/index3: exact (from "
                             "the sympy model) or IDA's finite differences")
    parser.add_argument("--plot", metavar="PATH",
                        help="plot the drift of index1 vs index1-baumgarte vs "
                             "index1-projection with the chosen ODE integrator")
    parser.add_argument("--table", action="store_true",
                        help="instead of one run: the tolerance-by-suppression grids "
                             "(index 3 and index 2; IDA with and without suppress-alg, "
                             "radau5 with and without index scaling), the source document's beside")
    parser.add_argument("--tolerances", type=float, nargs="+", default=None,
                        help="rtol = atol values of --table (default 1e-4 1e-6 1e-8)")
    add_json(parser)
    parser.set_defaults(run=run_squeezer)


def run_squeezer(args: argparse.Namespace) -> int:
    """Simulate the squeezer; print end state, residuals, statistics and the error against
    the reference (or JSON); exit 1 if the integrator fails."""
    from youbot_dynamics.studies.squeezer_figures import plot_ode_drift
    if args.table:
        return run_suppression_tables(args)
    if args.plot:
        output_file(args.plot, "--plot")
    rtol = args.rtol if args.rtol is not None else args.tol if args.tol is not None else SQUEEZER_RTOL
    config = squeezer.SqueezerConfig(
        formulation=args.formulation, integrator=args.integrator, rtol=rtol, atol=args.atol,
        duration=args.duration, outputs=args.outputs, dt=args.dt,
        exact_jacobian=args.jacobian == "exact")
    try:
        result = squeezer.run(config)
        if args.plot:
            plot_ode_drift(result, args.plot)
    except (IntegrationError, NotImplementedError) as error:
        print(f"youbot-dynamics study squeezer: {args.formulation} failed: {error}",
              file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(squeezer.as_json(result), indent=2))
        return 0
    print(squeezer.text(result))
    if args.plot:
        print(f"drift plot written to {args.plot}")
    return 0


def run_suppression_tables(args: argparse.Namespace) -> int:
    """Print (or JSON) the suppression grids for index 3 and index 2."""
    tables = squeezer.run_suppression(squeezer.SuppressionConfig(
        tuple(args.tolerances or squeezer.SUPPRESSION_TOLERANCES), args.outputs))
    print(json.dumps(squeezer.suppression_json(tables), indent=2) if args.json
          else squeezer.suppression_text(tables))
    return 0


def add_structure(parser: argparse.ArgumentParser) -> None:
    """Options of ``study structure``."""
    parser.add_argument("example", choices=STRUCTURE_EXAMPLES)
    add_json(parser)
    parser.set_defaults(run=run_structure)


def run_structure(args: argparse.Namespace) -> int:
    """Print the structural analysis of an example (or JSON)."""
    report = structure_report(args.example)
    print(json.dumps(report, indent=2) if args.json else structure_text(report))
    return 0


def add_woodpecker(parser: argparse.ArgumentParser) -> None:
    """Options of ``study woodpecker``."""
    parser.add_argument("--duration", type=positive, default=2.0, metavar="S",
                        help="simulated time, s (default 2)")
    parser.add_argument("--integrator", choices=INTEGRATORS, default="dop853")
    add_tolerance_arguments(parser, WOODPECKER_RTOL, "absolute tolerance (default rtol/100)")
    parser.add_argument("--dt", type=positive, help="step (s) for fixed-step integrators")
    parser.add_argument("--plot", metavar="PATH", help="write a plot of the run")
    add_json(parser)
    parser.set_defaults(run=run_woodpecker)


def run_woodpecker(args: argparse.Namespace) -> int:
    """Simulate the woodpecker toy; print beak hits, mode switches, final state and the
    statistics beside the source document's (or JSON); optionally plot."""
    if args.integrator in FIXED_STEP and args.dt is None:
        raise UserInputError(f"--integrator {args.integrator} is fixed-step: give --dt")
    if args.plot:
        output_file(args.plot, "--plot")
        problem = limits.samples_problem(args.duration, PLOT_RATE)
        if problem:
            raise UserInputError(f"--duration with --plot: {problem}")
    rtol, atol = tolerances(args, woodpecker.SEED_INITIAL_STATE)
    rtol = WOODPECKER_RTOL if rtol is None else rtol
    result = woodpecker.run(woodpecker.WoodpeckerConfig(
        duration=args.duration, integrator=args.integrator, rtol=rtol,
        atol=rtol * 1e-2 if atol is None else atol, dt=args.dt,
        n_out=int(args.duration * PLOT_RATE) if args.plot else 0))
    if args.plot:
        from youbot_dynamics.studies.woodpecker_figures import plot_woodpecker
        plot_woodpecker(result.woodpecker, result.solution, args.plot)
    if args.json:
        print(json.dumps({**woodpecker.as_json(result),
                          **({"plot": args.plot} if args.plot else {}),
                          "seed": woodpecker.seed_json()}, indent=2))
        return 0
    print(woodpecker.text(result))
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


#: The studies this module adds under ``study``: name -> function adding its options.
STUDY_PARSERS = {"squeezer": add_squeezer, "structure": add_structure,
                 "woodpecker": add_woodpecker}
