"""The pendulum studies under ``study``: ``pendulum`` (simulate the elastic pendulum with
any integrator), ``pendulum-tables`` (the source document's tables beside ours), ``bdf`` (fixed-step
BDF1-4, stability regions, CVODE order caps) and ``uncertainty`` (the damped pendulum with
uncertain parameters: linear propagation against Monte Carlo). Each parses its options
into the study's config, runs it (studies/) and prints its text or, with ``--json``, its
JSON object."""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from youbot_dynamics.cli.common import (add_json, add_sweep_arguments, add_tolerance_arguments,
                                        output_file, positive, print_result, tolerances)
from youbot_dynamics.cli.sim_commands import (add_step_budget_argument, checked_step_budget,
                                              progress_bar)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import IntegrationError, checked_output_spacing
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.studies import bdf_study, elastic_pendulum, uncertain_pendulum
from youbot_dynamics.studies.elastic_pendulum import (ACCURATE_INTEGRATOR, DEFAULT_ATOL,
                                                      DEFAULT_INTEGRATOR, DEFAULT_RTOL,
                                                      JACOBIANS, OUTPUTS, SEED_STATE0,
                                                      SEED_T_END)


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


def add_pendulum(parser: argparse.ArgumentParser) -> None:
    """Options of ``study pendulum``."""
    parser.description = ("Simulate the elastic pendulum (unit mass, length, gravity) and "
                          "print the final state, the energy error and the integrator "
                          "statistics.")
    parser.add_argument("--k", type=float, default=10.0, help="spring stiffness (default 10)")
    parser.add_argument("--state0", default=",".join(f"{v:g}" for v in SEED_STATE0),
                        help="x,y,vx,vy at t=0 (default the source document's 1.2,0,0,0)")
    parser.add_argument("--duration", type=float, default=SEED_T_END, metavar="S",
                        help=f"simulated time, s (default {SEED_T_END:g})")
    parser.add_argument("--integrator",
                        help=f"one of {', '.join(n for n in INTEGRATORS if n != 'ida')} "
                             f"(default {DEFAULT_INTEGRATOR}; with --tol {ACCURATE_INTEGRATOR})")
    parser.add_argument("--dt", type=float, help="step size for fixed-step integrators, s")
    add_tolerance_arguments(parser, DEFAULT_RTOL, f"absolute tolerance (default {DEFAULT_ATOL:g})")
    add_step_budget_argument(parser)
    parser.add_argument("--max-order", type=int, metavar="N",
                        help="cap CVODE's order (cvode_bdf 1..5, cvode_adams 1..12)")
    parser.add_argument("--jacobian", choices=JACOBIANS, default="analytic",
                        help="implicit integrators: our analytic Jacobian (default) or their "
                             "own difference quotients (as the source document's runs)")
    add_json(parser)
    parser.set_defaults(run=run_pendulum)


def pendulum_config(args: argparse.Namespace) -> elastic_pendulum.PendulumConfig:
    """The run's config from the options; UserInputError for options that do not go
    together."""
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
    return elastic_pendulum.PendulumConfig(
        k=args.k, state0=state0, duration=args.duration, integrator=integrator, dt=args.dt,
        rtol=DEFAULT_RTOL if rtol is None else rtol, atol=DEFAULT_ATOL if atol is None else atol,
        max_steps=args.max_steps, max_order=args.max_order, jacobian=args.jacobian)


def run_pendulum(args: argparse.Namespace) -> int:
    """Simulate and print final state, energy error and statistics."""
    config = pendulum_config(args)
    times = np.linspace(0.0, config.duration, OUTPUTS) if config.duration > 0 else np.zeros(0)
    steps = 0
    if config.dt is not None and times.size:
        checked_output_spacing(config.dt, times, f"--dt (outputs every --duration/{OUTPUTS - 1})")
        steps = checked_step_budget(config.integrator, config.dt, times, config.max_steps)
    try:
        with progress_bar("pendulum", steps, 0.0, config.duration, not args.json) as progress:
            result = elastic_pendulum.run(config, progress)
    except IntegrationError as error:
        print(f"youbot-dynamics study pendulum: {error}", file=sys.stderr)
        return 1
    print(json.dumps(elastic_pendulum.as_json(result)) if args.json
          else elastic_pendulum.text(result))
    return 0


def add_pendulum_tables(parser: argparse.ArgumentParser) -> None:
    """Options of ``study pendulum-tables``."""
    parser.description = ("Reproduce the source document's elastic-pendulum tables with our "
                          "integrators, the source document's figures beside ours.")
    add_json(parser)
    parser.set_defaults(run=run_pendulum_tables)


def run_pendulum_tables(args: argparse.Namespace) -> int:
    """Print the study's tables (markdown) or JSON rows."""
    rows = elastic_pendulum.elastic_pendulum_study()
    print(json.dumps([row.as_dict() for row in rows]) if args.json
          else elastic_pendulum.tables_text(rows))
    return 0


def add_bdf(parser: argparse.ArgumentParser) -> None:
    """Options of ``study bdf``."""
    parser.description = ("The source document's fixed-step study of the elastic pendulum (explicit "
                          "Euler, BDF2-4 over k and N) with its verdicts beside ours, the BDF "
                          "stability regions, measured orders, and CVODE BDF with its order "
                          "capped.")
    parser.add_argument("--short", action="store_true",
                        help="only the cells the source document gives a verdict for, no CVODE order 1 "
                             "at k = 50 (a short form for CI)")
    parser.add_argument("--plot", metavar="PATH", help="write the stability-region plot")
    parser.add_argument("--choppy-plot", metavar="PATH",
                        help="write the source document's loose-tolerance traces (its Figs "
                             "19-23): CVODE BDF with rtol or atol at 0.1, k = 10 and 50")
    add_sweep_arguments(parser)
    add_json(parser)
    parser.set_defaults(run=run_bdf)


def run_bdf(args: argparse.Namespace) -> int:
    """Print (or JSON) Tables 1-4, the stability figures, measured orders and the CVODE
    order-cap rows; optionally plot the stability regions and the choppy traces."""
    from youbot_dynamics.studies.bdf_figures import plot_choppy_traces, plot_stability_regions
    for path, flag in ((args.plot, "--plot"), (args.choppy_plot, "--choppy-plot")):
        if path:
            output_file(path, flag)
    study = bdf_study.run(bdf_study.BdfConfig(short=args.short, workers=args.workers,
                                              scheduler=args.scheduler, progress=not args.json))
    if args.plot:
        plot_stability_regions(args.plot, points=bdf_study.stability_points(
            [row for row in study.rows if row.n_steps == 1000]))
    choppy = plot_choppy_traces(args.choppy_plot) if args.choppy_plot else None
    if args.json:
        print(json.dumps({**bdf_study.as_json(study), "choppy": choppy, "plot": args.plot},
                         indent=2))
        return 0
    print(bdf_study.text(study))
    if args.plot:
        print(f"\nplot written to {args.plot}")
    if choppy:
        print(f"loose-tolerance traces written to {args.choppy_plot}: " + "; ".join(
            f"{name} {figures['steps']} steps, position off by up to "
            f"{figures['position_error']:.2f} m" for name, figures in choppy.items()))
    return 0


def add_uncertainty(parser: argparse.ArgumentParser) -> None:
    """Options of ``study uncertainty``."""
    parser.add_argument("--samples", type=int, default=1000, help="Monte Carlo samples")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the samples")
    parser.add_argument("--duration", type=positive, default=10.0, metavar="S",
                        help="simulated time, s (default 10)")
    parser.add_argument("--plot", metavar="PATH", help="write the band plot")
    add_sweep_arguments(parser)
    add_json(parser)
    parser.set_defaults(run=run_uncertainty)


def run_uncertainty(args: argparse.Namespace) -> int:
    """The uncertainty study: linear propagation against Monte Carlo, figures (or JSON)
    and optionally the band plot."""
    if args.plot:
        output_file(args.plot, "--plot")
    if args.samples < 2:
        raise UserInputError(f"--samples must be at least 2, got {args.samples}")
    result = uncertain_pendulum.run(uncertain_pendulum.UncertaintyConfig(
        samples=args.samples, seed=args.seed, duration=args.duration, workers=args.workers,
        scheduler=args.scheduler))
    if args.plot:
        from youbot_dynamics.studies.uncertain_pendulum_figures import plot_band
        plot_band(result, args.plot)
    return print_result(args, uncertain_pendulum.as_json(result), uncertain_pendulum.text(result))


#: The studies this module adds under ``study``: name -> function adding its options.
STUDY_PARSERS = {"pendulum": add_pendulum, "pendulum-tables": add_pendulum_tables,
                 "bdf": add_bdf, "uncertainty": add_uncertainty}
