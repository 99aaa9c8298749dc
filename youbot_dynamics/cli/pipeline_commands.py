"""Sub-command ``pipeline``: the equation pipeline (order lowering, alias elimination,
matching, Pantelides, dummy derivatives, BLT, tearing, code generation, simulation) on one
of the seed's example models, each stage printed (or JSON with ``--json``)."""
from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from youbot_dynamics.cli.common import CommandError, relative_tolerance
from youbot_dynamics.cli.sim_commands import add_step_budget_argument, checked_step_budget
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.integrate.registry import integrator_names
from youbot_dynamics.studies.equations import EXAMPLE_MODELS
from youbot_dynamics.studies.pipeline_report import pipeline_report, report_lines
from youbot_dynamics.studies.state_selection import simulate_with_reselection

#: The seed's parameter merge for the ModiaLang pendulum (``Pendulum | Map(L = 0.5)``).
MODIA_MERGE = {"L": 0.5}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `pipeline`."""
    parser = subparsers.add_parser(
        "pipeline", help="equation pipeline on an example model: every stage printed")
    parser.add_argument("example", choices=tuple(EXAMPLE_MODELS))
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter merge (model | {NAME: VALUE}); repeatable. "
                        "modia-pendulum runs its defaults and the seed's merge L=0.5 unless "
                        "--set is given")
    parser.add_argument("--integrator", choices=integrator_names("ode"),
                        default="cvode_bdf", help="default cvode_bdf (Modia's CVODE_BDF)")
    parser.add_argument("--tol", type=relative_tolerance, default=1e-6,
                        help="accuracy: rtol = TOL, atol_i = TOL max(|x0_i|, 1e-3)")
    parser.add_argument("--outputs", type=int, default=201, help="output times")
    parser.add_argument("--dt", type=float, default=None,
                        help="fixed step (s) for euler, symplectic_euler, rk4")
    parser.add_argument("--static-selection", action="store_true",
                        help="keep the start's state selection (fails where a pivot fades) "
                        "instead of choosing the states again there")
    add_step_budget_argument(parser)
    parser.add_argument("--json", action="store_true")
    parser.set_defaults(run=run_pipeline_command)


def parse_merge(items: list[str]) -> dict[str, float]:
    """NAME=VALUE pairs (finite numbers) as a dict."""
    merge = {}
    for item in items:
        name, _, value = item.partition("=")
        try:
            merge[name.strip()] = float(value)
        except ValueError:
            raise CommandError(f"--set {item!r}: expected NAME=VALUE with a number") from None
        if not math.isfinite(merge[name.strip()]):
            raise CommandError(f"--set {item!r}: the value must be finite")
    return merge


def run_pipeline_command(args: argparse.Namespace) -> int:
    """Run the pipeline on the example and print each stage."""
    model = EXAMPLE_MODELS[args.example]()
    merges = [parse_merge(args.set)] if args.set else [{}]
    if args.example == "modia-pendulum" and not args.set:
        merges.append(MODIA_MERGE)
    runs = []
    for merge in merges:
        current = model | merge
        times = np.linspace(current.t0, current.t_end, args.outputs)
        checked_step_budget(args.integrator, args.dt, times, args.max_steps)
        try:
            with np.errstate(all="ignore"):
                run = simulate_with_reselection(
                    current, args.integrator, args.tol, args.outputs, dt=args.dt,
                    max_steps=args.max_steps, max_segments=1 if args.static_selection else 100)
        except IntegrationError as error:
            print(f"youbot-dynamics pipeline: {args.example} failed: {error}", file=sys.stderr)
            return 1
        label = "model | " + ", ".join(f"{k} = {v:g}" for k, v in merge.items()) \
            if merge else "model (defaults)"
        runs.append((label, run, args.tol))
    report = pipeline_report(runs[0][1].segments[0].result, runs)
    if args.json:
        print(json.dumps(report, indent=2, default=str))
    else:
        print("\n".join(report_lines(report)))
    return 0
