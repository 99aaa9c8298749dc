"""``study pipeline``: the equation pipeline (order lowering, alias elimination, matching,
Pantelides, dummy derivatives, BLT, tearing, code generation, simulation) on one of the
source documents' example models, each stage printed (or JSON with ``--json``;
studies/pipeline_report.py)."""
from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from youbot_dynamics.cli.common import CommandError, add_json, relative_tolerance
from youbot_dynamics.cli.sim_commands import add_step_budget_argument, checked_step_budget
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.integrate.registry import integrator_names
from youbot_dynamics.studies import pipeline_report
from youbot_dynamics.studies.equations import EXAMPLE_MODELS


def add_pipeline(parser: argparse.ArgumentParser) -> None:
    """Options of ``study pipeline``."""
    parser.add_argument("example", choices=tuple(EXAMPLE_MODELS))
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter merge (model | {NAME: VALUE}); repeatable. "
                        "modia-pendulum runs its defaults and the source document's merge L=0.5 unless "
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
    add_json(parser)
    parser.set_defaults(run=run_pipeline)


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


def run_pipeline(args: argparse.Namespace) -> int:
    """Run the pipeline on the example and print each stage."""
    config = pipeline_report.PipelineConfig(
        example=args.example, merge=tuple(parse_merge(args.set).items()),
        integrator=args.integrator, tol=args.tol, outputs=args.outputs, dt=args.dt,
        max_steps=args.max_steps, static_selection=args.static_selection)
    for _, model in pipeline_report.pipeline_models(config):
        checked_step_budget(config.integrator, config.dt,
                            np.linspace(model.t0, model.t_end, config.outputs), config.max_steps)
    try:
        report = pipeline_report.run(config)
    except IntegrationError as error:
        print(f"youbot-dynamics study pipeline: {args.example} failed: {error}", file=sys.stderr)
        return 1
    print(json.dumps(report, indent=2, default=str) if args.json
          else pipeline_report.text(report))
    return 0


#: The studies this module adds under ``study``: name -> function adding its options.
STUDY_PARSERS = {"pipeline": add_pipeline}
