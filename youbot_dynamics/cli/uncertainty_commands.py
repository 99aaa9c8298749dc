"""Sub-command ``scene-uncertainty``: a scene's ``value ± sigma`` parameters propagated to
one output (accuracy/scene_uncertainty.py), linear band against Monte Carlo."""
from __future__ import annotations

import argparse

from youbot_dynamics.cli.common import (add_duration, add_json, add_plot, add_sweep_arguments,
                                        output_file, positive, print_result)

#: The commands here that run an integrator, and where their accuracy comes from (see
#: youbot_dynamics.cli: "--tol" or the reason the command takes none).
ACCURACY = {"scene-uncertainty": "the scene's integrator block: every run is the scene as written, its "
                                 "uncertain parameters aside (work-precision --write-back pins one)"}
SUMMARY = "propagate a scene's value ± sigma parameters to an output: linear band against Monte Carlo"


def run_scene_uncertainty(args: argparse.Namespace) -> int:
    """Both propagations, the figures at the end time (or JSON) and optionally the plot."""
    from youbot_dynamics.accuracy.propagation import comparison, plot_uncertainty
    from youbot_dynamics.accuracy.scene_uncertainty import linear_propagation, monte_carlo, summary_text
    if args.plot:
        output_file(args.plot, "--plot")
    where = {"workers": args.workers, "scheduler": args.scheduler, "progress": True}
    linear, sensitivities = linear_propagation(args.scene, args.output, args.duration, **where)
    sampled, keys, _, traces = monte_carlo(args.scene, args.output, args.samples, args.seed, args.duration,
                                           **where)
    figures = comparison(linear, sampled)
    if args.plot:
        plot_uncertainty(linear, sampled, traces, args.plot, f"{args.scene}: {args.output}", args.output)
    record = {**figures, "output": args.output, "parameters": list(keys),
              "sensitivities_end": dict(zip(keys, sensitivities[:, -1].tolist())),
              "samples": args.samples, "seed": args.seed}
    return print_result(args, record, summary_text(args.scene, args.output, keys, args.samples, args.seed,
                                                   figures))


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("scene-uncertainty", help=SUMMARY,
                                   description="Propagate a scene's uncertain parameters (numbers written "
                                   "\"value ± sigma\") to one state component over time: a linear band "
                                   "(finite-difference sensitivities) and a Monte Carlo, compared at the end.")
    parser.add_argument("scene", help="scene file or packaged name (e.g. uncertain_pendulum)")
    parser.add_argument("--output", required=True, metavar="NAME",
                        help="a state component, e.g. 'q[pivot]' or 'pose[ball.z]'")
    parser.add_argument("--samples", type=int, default=1000, help="Monte Carlo samples (default 1000)")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the samples")
    add_duration(parser, default_text="the scene's", parse=positive)
    add_plot(parser, "the band plot")
    add_sweep_arguments(parser)
    add_json(parser)
    parser.set_defaults(run=run_scene_uncertainty)
