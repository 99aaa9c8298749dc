"""Sub-command `mecanum`: the youBot base's wheel speeds for a twist, and the odometry of
that twist. (The differential drive against its closed forms is ``study unicycle``.)"""
from __future__ import annotations

import argparse
import json
import math

import numpy as np

from youbot_dynamics.cli.common import add_duration, add_json
from youbot_dynamics.dynamics.mobile.mecanum import base_twist, wheel_speeds, youbot_base
from youbot_dynamics.dynamics.mobile.odometry import odometry_step
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model import limits

#: The commands here that run an integrator (none: mecanum's odometry is the closed-form SE(2)
#: exponential); see youbot_dynamics.cli.
ACCURACY: dict[str, str] = {}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `mecanum`."""
    base = subparsers.add_parser("mecanum", help="youBot base: wheel speeds of a twist, and its odometry",
                                 description="Wheel speeds (rad/s; wheel_joint_fl, fr, bl, br, positive "
                                 "rolls forward) of the youBot base for a twist in base_footprint, the "
                                 "twist back from them, and the pose reached holding it for --duration seconds.")
    base.add_argument("--twist", default="0.2,0.1,0.5", help="vx,vy,wz in m/s, m/s, rad/s (default 0.2,0.1,0.5)")
    add_duration(base, 1.0)
    add_json(base)
    base.set_defaults(run=run_mecanum)


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
    if problem or not (math.isfinite(args.duration) and 0.0 <= args.duration <= limits.DURATION.maximum):
        raise UserInputError(f"--twist {args.twist}: {problem}" if problem else
                             f"--duration must be a time in [0, {limits.DURATION.maximum:g}] s, got {args.duration!r}")
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
