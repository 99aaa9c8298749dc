"""The equations-of-motion studies under ``study``: ``lagrange`` (equations of motion by
computer algebra), ``rotations`` (Cardan angles, adaptive Cardan and quaternions on a free
rigid body) and ``unicycle`` (the differential drive against its closed forms). Each
parses its options into the study's config, runs it (studies/) and prints its text or,
with ``--json``, its JSON object."""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from youbot_dynamics.cli.common import (add_json, add_tolerance_arguments, output_file, positive,
                                        print_result, relative_tolerance, tolerances)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.studies import lagrange, rotations, unicycle

#: The adaptive ODE integrators (no fixed step, no DAE solver).
ADAPTIVE = [name for name in INTEGRATORS if name not in FIXED_STEP and name != "ida"]


def non_negative(text: str) -> float:
    """An argparse type: a float >= 0."""
    value = float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return value


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


def add_lagrange(parser: argparse.ArgumentParser) -> None:
    """Options of ``study lagrange``."""
    parser.add_argument("problem", choices=("2d", "3d"))
    parser.add_argument("--friction", type=non_negative, default=0.0,
                        help="joint friction c: generalised force -c q_i'")
    parser.add_argument("--param", action="append", metavar="NAME=VALUE",
                        help="override a model parameter (SI), e.g. --param m2=0.5; "
                             "repeatable")
    parser.add_argument("--duration", type=positive, default=10.0, metavar="S",
                        help="simulated time, s (default 10)")
    parser.add_argument("--integrator", choices=ADAPTIVE, default="dop853")
    add_tolerance_arguments(parser, lagrange.LAGRANGE_RTOL, "absolute tolerance (default rtol)")
    add_json(parser)
    parser.set_defaults(run=run_lagrange)


def run_lagrange(args: argparse.Namespace) -> int:
    """Derive the pendulum's equations with sympy, simulate them and print the equations,
    final state, energy drift and statistics (or JSON)."""
    overrides = parameter_overrides(args.param)
    rtol, atol = tolerances(args, lagrange.initial_state(args.problem))
    result = lagrange.run(lagrange.LagrangeConfig(
        problem=args.problem, friction=args.friction, overrides=tuple(overrides.items()),
        duration=args.duration, integrator=args.integrator,
        rtol=lagrange.LAGRANGE_RTOL if rtol is None else rtol, atol=atol))
    print(json.dumps(lagrange.as_json(result), indent=2) if args.json else lagrange.text(result))
    return 0


def add_rotations(parser: argparse.ArgumentParser) -> None:
    """Options of ``study rotations``."""
    parser.description = ("The source document's rotations study: steps, evaluations, error against "
                          "the closed-form top and |q| drift of each orientation state on "
                          "each run.")
    parser.add_argument("--runs", nargs="+", choices=tuple(rotations.RUNS),
                        help="runs (default all)")
    parser.add_argument("--integrator", choices=ADAPTIVE, default="rk45")
    parser.add_argument("--tol", type=relative_tolerance, default=1e-8,
                        help="rtol = atol (default 1e-8)")
    parser.add_argument("--plot", metavar="PATH", help="write the error and middle-angle plot")
    add_json(parser)
    parser.set_defaults(run=run_rotations)


def run_rotations(args: argparse.Namespace) -> int:
    """Every orientation formulation on every run of the rotations study; a table (or
    JSON) of steps, evaluations, errors against the closed-form top and |q| drift."""
    if args.plot:
        output_file(args.plot, "--plot")
    study = rotations.run(rotations.RotationsConfig(
        runs=tuple(args.runs or rotations.RUNS), integrator=args.integrator, tol=args.tol))
    if args.plot:
        from youbot_dynamics.studies.rotations_figures import plot_rotations
        plot_rotations(study.results, args.plot)
    return print_result(args, rotations.as_json(study), rotations.text(study))


#: The unicycle's parameters as options: field of Unicycle -> unit.
UNICYCLE_PARAMETERS = {"mass": "kg", "yaw_inertia": "kg m^2", "wheel_radius": "m",
                       "half_track": "m", "linear_friction": "N s/m",
                       "angular_friction": "N m s/rad"}


def add_unicycle(parser: argparse.ArgumentParser) -> None:
    """Options of ``study unicycle``."""
    parser.description = ("Simulate the differential drive (unicycle) from rest under "
                          "constant wheel torques and compare with the closed forms: equal "
                          "torques drive straight, v(t) = (F/b)(1 - exp(-b t/m)); opposite "
                          "torques spin it in place.")
    defaults = unicycle.Unicycle()
    parser.add_argument("--tau-right", type=float, default=0.5,
                        help="right wheel torque, N m (default 0.5)")
    parser.add_argument("--tau-left", type=float, default=0.5,
                        help="left wheel torque, N m (default 0.5)")
    parser.add_argument("--duration", type=float, default=10.0, metavar="S",
                        help="simulated time, s (default 10)")
    for name, unit in UNICYCLE_PARAMETERS.items():
        parser.add_argument(f"--{name.replace('_', '-')}", dest=name, type=float,
                            default=getattr(defaults, name),
                            help=f"{name.replace('_', ' ')}, {unit} "
                                 f"(default {getattr(defaults, name):g})")
    parser.add_argument("--integrator", default=unicycle.DEFAULT_INTEGRATOR,
                        help=f"one of {', '.join(n for n in INTEGRATORS if n != 'ida')} "
                             f"(default {unicycle.DEFAULT_INTEGRATOR})")
    parser.add_argument("--dt", type=float, help="step size for fixed-step integrators, s")
    add_tolerance_arguments(parser, unicycle.DEFAULT_RTOL,
                            f"absolute tolerance (default {unicycle.DEFAULT_ATOL:g})")
    add_json(parser)
    parser.set_defaults(run=run_unicycle)


def run_unicycle(args: argparse.Namespace) -> int:
    """Simulate, compare with the closed form where one exists, print figures and statistics."""
    if args.dt is not None and args.integrator not in FIXED_STEP:
        raise UserInputError(f"--dt applies to fixed-step integrators only, not {args.integrator!r}")
    model = unicycle.Unicycle(**{name: getattr(args, name) for name in UNICYCLE_PARAMETERS})
    rtol, atol = tolerances(args, np.zeros(5))
    try:
        result = unicycle.run(unicycle.UnicycleConfig(
            model=model, tau_right=args.tau_right, tau_left=args.tau_left,
            duration=args.duration, integrator=args.integrator,
            rtol=unicycle.DEFAULT_RTOL if rtol is None else rtol,
            atol=unicycle.DEFAULT_ATOL if atol is None else atol, dt=args.dt))
    except IntegrationError as error:
        print(f"youbot-dynamics study unicycle: {error}", file=sys.stderr)
        return 1
    print(json.dumps(unicycle.as_json(result)) if args.json else unicycle.text(result))
    return 0


#: The studies this module adds under ``study``: name -> function adding its options.
STUDY_PARSERS = {"lagrange": add_lagrange, "rotations": add_rotations, "unicycle": add_unicycle}
