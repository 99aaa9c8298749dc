"""Sub-commands of parameter identification (see :mod:`youbot_dynamics.identification`).

- ``excite [-o excite.yaml]``: an excitation trajectory (Fourier series, Swevers) optimised
  for cond(Y_base) within the URDF's limits (positions, speeds and the nominal robot's
  efforts); written as /joint_trajectory fields (YAML) with its Fourier coefficients, one
  period in as many points as the node takes in one message. Prints the condition number before and after, and that
  of random Fourier trajectories of the same length.
- ``identify BAG``: base parameters from /joint_states of a bag (MCAP file or rosbag2
  folder): OLS and WLS estimates, standard deviations, relative deviations (flagged above
  10 %), condition number, residual RMS per joint, pseudo-inertia check; ``--plot`` a PNG;
  ``--write-urdf OUT`` the URDF with identified parameters that are physically consistent
  by construction (every link's pseudo-inertia in log-Cholesky coordinates, fitted to the
  base parameters with ``--prior-weight`` toward the URDF's links), with a header comment
  recording the bag, the date, the fit and how far it moved the base parameters; with
  ``--json`` too (the document then holds ``written_urdf``: the file, how far the fit moved
  the base parameters, the distance per link, the reloaded file's warnings).
"""
from __future__ import annotations

import argparse
from datetime import date
from pathlib import Path

import numpy as np

from youbot_dynamics import default_urdf
from youbot_dynamics.cli.common import (CommandError, add_json, add_plot, add_rate, output_file, positive,
                                        print_json, robot_from, table)
from youbot_dynamics.identification.base_parameters import base_parameters
from youbot_dynamics.identification.consistency import (PRIOR_WEIGHT, consistent_fit, pseudo_inertia_eigenvalues,
                                                        standard_from_base)
from youbot_dynamics.identification.estimation import FLAG_PERCENT
from youbot_dynamics.identification.excitation import (DEFAULT_RATE, ExcitationLimits, condition_number,
                                                       message_rate, optimise_excitation, random_fourier)
from youbot_dynamics.identification.identify import ARM_JOINTS, identify_bag, layout_for
from youbot_dynamics.identification.measurements import STATES
from youbot_dynamics.identification.regressor import FRICTION_TERMS
from youbot_dynamics.identification.urdf_output import body_links, identified_urdf
from youbot_dynamics.model.robot import load_robot
from youbot_dynamics.node.commands import MAX_TRAJECTORY_POINTS

#: No command here runs an integrator (see youbot_dynamics.cli).
ACCURACY: dict[str, str] = {}


def _names(text: str, flag: str, allowed: tuple[str, ...] | None = None) -> tuple[str, ...]:
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    unknown = [n for n in names if allowed is not None and n not in allowed]
    if unknown:
        raise CommandError(f"{flag}: unknown {', '.join(unknown)}; choose from {', '.join(allowed)}")
    return names


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--urdf", help="URDF file (default: the packaged youBot)")
    parser.add_argument("--joints", default=",".join(ARM_JOINTS),
                        help="comma-separated joints to identify (the others locked at 0; default the arm)")
    parser.add_argument("--friction", default=",".join(FRICTION_TERMS),
                        help=f"friction terms per joint, comma-separated from {', '.join(FRICTION_TERMS)} "
                             "(default all; empty for none)")
    add_json(parser)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `excite` and `identify`."""
    excite = subparsers.add_parser("excite", help="optimise an excitation trajectory for identification")
    _common(excite)
    excite.add_argument("-o", "--output", default="excite.yaml", help="trajectory file (YAML; default excite.yaml)")
    excite.add_argument("--period", type=positive, default=10.0, help="period of the Fourier series, s")
    excite.add_argument("--harmonics", type=int, default=5, help="harmonics per joint (default 5)")
    excite.add_argument("--iterations", type=int, default=60, help="SLSQP iterations (default 60)")
    excite.add_argument("--acceleration", type=positive, default=ExcitationLimits.acceleration,
                        help="acceleration limit, rad/s^2 (the URDF has none)")
    add_rate(excite, DEFAULT_RATE, f"sample rate of the written points, lowered where a period would not fit one "
             f"/joint_trajectory (at most {MAX_TRAJECTORY_POINTS} points, the node's bound)", parse=positive)
    excite.add_argument("--seed", type=int, default=0, help="seed of the random starting series")
    excite.set_defaults(run=run_excite)

    identify = subparsers.add_parser("identify", help="identify base parameters from a bag's /joint_states")
    identify.add_argument("bag", help="a .mcap file or a rosbag2 folder")
    _common(identify)
    identify.add_argument("--topic", default="/joint_states", help="JointState topic (default /joint_states)")
    identify.add_argument("--cutoff", type=positive, default=10.0, help="low-pass cut-off, Hz (default 10)")
    identify.add_argument("--states", choices=STATES, default="filtered",
                          help="evaluate the regressor at low-passed q, v (default) or at the recorded ones "
                               "(exact states, e.g. a simulator's)")
    identify.add_argument("--decimation", type=int, help="keep every N-th sample (default: down to 2 x cut-off)")
    add_plot(identify, "measured vs predicted effort and the residuals")
    identify.add_argument("--write-urdf", metavar="OUT", help="write the URDF with identified inertials "
                          "(physically consistent by construction) and friction")
    identify.add_argument("--prior-weight", type=positive, default=PRIOR_WEIGHT,
                          help=f"--write-urdf: weight of the squared log-Cholesky distance to the URDF's links "
                               f"against the base parameters' chi^2/2 (default {PRIOR_WEIGHT:g})")
    identify.set_defaults(run=run_identify)


def _layout(args: argparse.Namespace):
    return layout_for(robot_from(args), _names(args.joints, "--joints"),
                      _names(args.friction, "--friction", FRICTION_TERMS))


def run_excite(args: argparse.Namespace) -> int:
    """Optimise, write the trajectory, print the condition numbers."""
    if args.harmonics < 1 or args.iterations < 0:
        raise CommandError("--harmonics must be >= 1 and --iterations >= 0")
    rate = message_rate(args.period, args.rate)
    layout = _layout(args)
    base = base_parameters(layout)
    limits = ExcitationLimits(acceleration=args.acceleration)
    result = optimise_excitation(layout, base, period=args.period, harmonics=args.harmonics, limits=limits,
                                 iterations=args.iterations, seed=args.seed)
    randoms = [condition_number(layout, base, random_fourier(layout, args.period, args.harmonics, limits,
                                                             np.random.default_rng(args.seed + s)))
               for s in range(1, 6)]
    result.trajectory.write(args.output, rate=rate)
    record = {"output": args.output, "rate": rate, "base_parameters": base.count, "condition_initial": result.initial_condition,
              "condition_optimised": result.condition, "condition_random_median": float(np.median(randoms)),
              "iterations": result.iterations, "message": result.message}
    if args.json:
        print_json(record)
        return 0
    print(f"excite: {base.count} base parameters; cond(Y_base) {result.initial_condition:.4g} (random start) -> "
          f"{result.condition:.4g} after {result.iterations} SLSQP iterations ({result.message}); "
          f"random Fourier trajectories of the same length: median {np.median(randoms):.4g}")
    print(f"wrote {args.output} ({args.period:g} s period, {args.harmonics} harmonics, points at {rate:g} Hz)")
    return 0


def run_identify(args: argparse.Namespace) -> int:
    """Identify, print the estimates and the fit figures (with --json too: the URDF of
    --write-urdf is written in both modes)."""
    if args.write_urdf:
        output_file(args.write_urdf, "--write-urdf")
    robot = robot_from(args)
    result = identify_bag(args.bag, robot, _names(args.joints, "--joints"),
                          _names(args.friction, "--friction", FRICTION_TERMS), topic=args.topic,
                          cutoff=args.cutoff, decimation=args.decimation, progress=not args.json,
                          states=args.states)
    theta = standard_from_base(result.base, result.wls.values, result.layout.standard_parameters())
    eigenvalues = pseudo_inertia_eigenvalues(result.layout, theta)
    if args.plot:
        from youbot_dynamics.identification.plots import plot_identification
        plot_identification(result, args.plot)
    written = _write_urdf(args, result) if args.write_urdf else None
    if args.json:
        print_json({**result.to_dict(), "pseudo_inertia_min_eigenvalue": eigenvalues,
                    **({"written_urdf": written} if written else {})})
        return 0
    wls = result.wls
    rows = [(name, nominal, value, std, f"{rel:.3g}", "" if rel <= FLAG_PERCENT else "not identified")
            for name, nominal, value, std, rel in zip(result.names, result.nominal, wls.values, wls.std,
                                                      wls.relative_std)]
    print(table(("base parameter", "URDF", "estimate (WLS)", "std", "rel. std %", "flag"), rows))
    print(f"{result.base.count} base parameters of {len(result.layout.names)} standard; "
          f"{len(wls.flagged)} above {FLAG_PERCENT:g} % relative std; cond(W) {wls.condition:.4g}; "
          f"{result.to_dict()['samples']} samples; WLS converged in {wls.iterations} iterations")
    print(table(("joint", "residual RMS OLS (N m)", "residual RMS WLS (N m)"),
                zip(result.layout.robot.joint_names, result.ols.residual_rms, wls.residual_rms)))
    bad = [body for body, value in eigenvalues.items() if value <= 0.0]
    print("pseudo-inertia (standard parameters nearest the URDF's with these base values): "
          + ("positive definite for every body" if not bad else f"NOT positive definite for {', '.join(bad)}"))
    if args.plot:
        print(f"wrote {args.plot}")
    if written:
        print(f"wrote {written['output']}: the consistent fit moved the base parameters by {_moved(written)}; "
              f"log-Cholesky distance from the URDF per link: {_distances(written)}")
        for warning in written["warnings"]:
            print(f"  the written URDF: {warning}")
    return 0


def _moved(written: dict) -> str:
    return f"at most {written['moved_std_max']:.3g} standard deviations (rms {written['moved_std_rms']:.3g})"


def _distances(written: dict) -> str:
    return ", ".join(f"{link} {value:.3g}" for link, value in written["distance_per_link"].items())


def _write_urdf(args: argparse.Namespace, result) -> dict[str, object]:
    """Fit consistent inertias to the base estimate and write the URDF; returns what was
    written: the file, how far the fit moved the base parameters (in standard deviations:
    largest and rms), the log-Cholesky distance of each link from the URDF's and what the
    reloaded file warns about."""
    source = args.urdf if args.urdf else default_urdf()
    fit = consistent_fit(result.layout, result.base, result.wls.values, result.wls.covariance,
                         body_links(source, result.layout), weight=args.prior_weight)
    if not fit.success:
        raise CommandError(f"--write-urdf: the consistent fit did not converge ({fit.message})")
    named = dict(zip(result.layout.names, fit.theta))
    offsets = {n: v for n, v in named.items() if n.endswith(".offset")}
    written = {"output": args.write_urdf, "moved_std_max": float(np.abs(fit.moved_std).max()),
               "moved_std_rms": float(np.sqrt(np.mean(fit.moved_std ** 2))),
               "distance_per_link": {link: float(value) for link, value in fit.distance.items()}}
    moved, distances = _moved(written), _distances(written)
    header = (f"Inertials and friction of {', '.join(result.layout.robot.joint_names)} identified by "
              f"youbot-dynamics identify from {args.bag} on {date.today().isoformat()}: "
              f"{result.base.count} base parameters (WLS), cond(W) {result.wls.condition:.4g}, "
              f"{result.to_dict()['samples']} samples, residual RMS per joint (N m) "
              f"{', '.join(f'{x:.3g}' for x in result.wls.residual_rms)}. Physically consistent by construction "
              f"(every link's pseudo-inertia in log-Cholesky coordinates, least squares on the base parameters "
              f"plus {fit.weight:g} x the squared log-Cholesky distance to the source URDF's links): the base "
              f"parameters moved by {moved}; distance per link: {distances}. "
              + (f"Torque offsets (N m; no URDF field): "
                 f"{', '.join(f'{n} {v:.4g}' for n, v in offsets.items())}." if offsets else ""))
    text = identified_urdf(source, result.layout, fit, header)
    Path(args.write_urdf).write_text(text)
    return {**written, "warnings": [str(warning) for warning in load_robot(text).warnings]}
