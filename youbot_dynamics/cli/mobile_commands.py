"""Sub-commands `unicycle` (the differential drive against its closed forms) and `mecanum`
(the youBot base's wheel speeds for a twist, and the odometry of that twist)."""
from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict

import numpy as np

from youbot_dynamics.cli.common import add_duration, add_json, add_tolerance_arguments, tolerances
from youbot_dynamics.dynamics.mobile.mecanum import base_twist, wheel_speeds, youbot_base
from youbot_dynamics.dynamics.mobile.odometry import odometry_step
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.model import limits
from youbot_dynamics.studies.unicycle import (MAX_DURATION, STATE_NAMES, Unicycle,
                                              heading_and_speeds, simulate_unicycle,
                                              unicycle_closed_form)

#: dop853 at rtol 1e-10, atol 1e-12 meets the closed forms to about 1e-10 on the defaults.
DEFAULT_INTEGRATOR, DEFAULT_RTOL, DEFAULT_ATOL = "dop853", 1e-10, 1e-12
OUTPUTS = 101
#: The commands here that run an integrator, and where their accuracy comes from (see
#: youbot_dynamics.cli: "--tol" or the reason the command takes none); mecanum's odometry is
#: the closed-form SE(2) exponential.
ACCURACY = {"unicycle": "--tol"}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `unicycle` and `mecanum`."""
    run = subparsers.add_parser("unicycle", help="the differential drive against its closed forms",
                                description="Simulate the differential drive (unicycle) from rest under "
                                "constant wheel torques and compare with the closed forms: equal torques "
                                "drive straight, v(t) = (F/b)(1 - exp(-b t/m)); opposite torques spin it "
                                "in place.")
    defaults = Unicycle()
    run.add_argument("--tau-right", type=float, default=0.5, help="right wheel torque, N m (default 0.5)")
    run.add_argument("--tau-left", type=float, default=0.5, help="left wheel torque, N m (default 0.5)")
    run.add_argument("--t-end", type=float, default=10.0, help="end time, s (default 10)")
    for name, unit in (("mass", "kg"), ("yaw_inertia", "kg m^2"), ("wheel_radius", "m"), ("half_track", "m"),
                       ("linear_friction", "N s/m"), ("angular_friction", "N m s/rad")):
        run.add_argument(f"--{name.replace('_', '-')}", dest=name, type=float, default=getattr(defaults, name),
                         help=f"{name.replace('_', ' ')}, {unit} (default {getattr(defaults, name):g})")
    run.add_argument("--integrator", default=DEFAULT_INTEGRATOR,
                     help=f"one of {', '.join(n for n in INTEGRATORS if n != 'ida')} (default {DEFAULT_INTEGRATOR})")
    run.add_argument("--dt", type=float, help="step size for fixed-step integrators, s")
    add_tolerance_arguments(run, DEFAULT_RTOL, f"absolute tolerance (default {DEFAULT_ATOL:g})")
    run.add_argument("--json", action="store_true", help="print JSON")
    run.set_defaults(run=run_unicycle)
    base = subparsers.add_parser("mecanum", help="youBot base: wheel speeds of a twist, and its odometry",
                                 description="Wheel speeds (rad/s; wheel_joint_fl, fr, bl, br, positive "
                                 "rolls forward) of the youBot base for a twist in base_footprint, the "
                                 "twist back from them, and the pose reached holding it for --duration seconds.")
    base.add_argument("--twist", default="0.2,0.1,0.5", help="vx,vy,wz in m/s, m/s, rad/s (default 0.2,0.1,0.5)")
    add_duration(base, 1.0)
    add_json(base)
    base.set_defaults(run=run_mecanum)


def run_unicycle(args: argparse.Namespace) -> int:
    """Simulate, compare with the closed form where one exists, print figures and statistics."""
    if args.dt is not None and args.integrator not in FIXED_STEP:
        raise UserInputError(f"--dt applies to fixed-step integrators only, not {args.integrator!r}")
    model = Unicycle(**{name: getattr(args, name) for name in ("mass", "yaw_inertia", "wheel_radius",
                                                               "half_track", "linear_friction", "angular_friction")})
    state0 = np.zeros(5)
    rtol, atol = tolerances(args, state0)
    try:
        solution = simulate_unicycle(model, args.tau_right, args.tau_left, args.t_end, args.integrator,
                                     rtol=DEFAULT_RTOL if rtol is None else rtol,
                                     atol=DEFAULT_ATOL if atol is None else atol, dt=args.dt, n_out=OUTPUTS)
    except IntegrationError as error:
        print(f"youbot-dynamics unicycle: {error}", file=sys.stderr)
        return 1
    straight, spin = args.tau_right == args.tau_left, args.tau_right == -args.tau_left
    if straight or spin:
        compared = slice(0, 5)
        reference = np.array([unicycle_closed_form(model, args.tau_right, args.tau_left, state0, t)
                              for t in solution.t])
    else:  # x, y have no closed form: compare theta, v, omega
        compared = slice(2, 5)
        reference = np.array([[0.0, 0.0, *heading_and_speeds(model, args.tau_right, args.tau_left, state0, t)[0]]
                              for t in solution.t])
    error = float(np.abs(solution.x[:, compared] - reference[:, compared]).max())
    final = dict(zip(STATE_NAMES, map(float, solution.x[-1])))
    closed = dict(zip(STATE_NAMES[compared], map(float, reference[-1, compared])))
    case = "equal torques: straight line" if straight else "opposite torques: spin in place" if spin else \
        "general torques: closed forms of theta, v, omega only"
    if args.json:
        print(json.dumps({"parameters": asdict(model), "tau_right": args.tau_right, "tau_left": args.tau_left,
                          "case": case, "t_end": float(solution.t[-1]), "final_state": final,
                          "closed_form": closed, "max_error": error, "stats": solution.stats.as_dict()}))
        return 0
    print(f"unicycle, {case}; tau_r = {args.tau_right:g}, tau_l = {args.tau_left:g} N m; {args.integrator}, "
          f"t = {solution.t[-1]:g} s")
    print("parameters: " + ", ".join(f"{k} = {v:g}" for k, v in asdict(model).items()))
    print("final state:  " + ", ".join(f"{k}={v:.12g}" for k, v in final.items()))
    print("closed form:  " + ", ".join(f"{k}={v:.12g}" for k, v in closed.items()))
    print(f"max |simulated - closed form| over {len(solution.t)} outputs ({', '.join(closed)}): {error:.3e}")
    print(f"statistics: {solution.stats.summary()}")
    return 0


def run_mecanum(args: argparse.Namespace) -> int:
    """Print the wheel speeds, the twist back from them and the odometry pose."""
    try:
        twist = np.array([float(part) for part in args.twist.split(",")])
    except ValueError:
        twist = np.zeros(0)
    if twist.shape != (3,) or not np.all(np.isfinite(twist)):
        raise UserInputError(f"--twist must be three numbers vx,vy,wz (m/s, m/s, rad/s), got {args.twist!r}")
    problem = (limits.SPEED.problem(twist[0]) or limits.SPEED.problem(twist[1])
               or limits.ANGULAR_SPEED.problem(twist[2]))
    if problem or not (math.isfinite(args.duration) and 0.0 <= args.duration <= MAX_DURATION):
        raise UserInputError(f"--twist {args.twist}: {problem}" if problem else
                             f"--duration must be a time in [0, {MAX_DURATION:g}] s, got {args.duration!r}")
    base = youbot_base()
    speeds = wheel_speeds(base, twist)
    back = base_twist(base, speeds)
    pose = odometry_step(base, np.zeros(3), speeds, args.duration)
    record = {"twist": twist.tolist(), "wheel_speeds": dict(zip(base.names, speeds.tolist())),
              "twist_from_wheels": back.tolist(), "duration": args.duration,
              "pose": dict(zip(("x", "y", "theta"), pose.tolist()))}
    if args.json:
        print(json.dumps(record))
        return 0
    print(f"youBot base (r = {base.radius:g} m, wheels at x = +-{base.positions[0, 0]:g}, "
          f"y = +-{base.positions[0, 1]:g} m), twist vx, vy, wz = {', '.join(f'{v:g}' for v in twist)}")
    print("wheel speeds (rad/s): " + ", ".join(f"{k} {v:.9g}" for k, v in record["wheel_speeds"].items()))
    print("twist from the wheel speeds: " + ", ".join(f"{v:.12g}" for v in back))
    print(f"pose after {args.duration:g} s (odom, SE(2) exponential): x {pose[0]:.9g} m, y {pose[1]:.9g} m, "
          f"theta {pose[2]:.9g} rad")
    return 0
