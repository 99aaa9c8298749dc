"""The ``dynamics_node`` executable's own command line, without rclpy: its options (those
outside ``--ros-args ... --``, which rclpy reads) and ``--help``, which prints the parameter
table of :mod:`youbot_dynamics.node.interface` and starts nothing."""
from __future__ import annotations

import sys
from collections.abc import Callable

from youbot_dynamics.node.interface import parameter_help

PROGRAM = "dynamics_node"
OPTIONS = {"-h, --help": "print this help (the parameters, from the node's table) and exit",
           "--managed": "a managed (lifecycle) node: it waits unconfigured; configure loads and compiles the "
                        "scene, activate starts publishing, deactivate pauses, cleanup and shutdown close the logs"}
"""The executable's own options (outside ``--ros-args``)."""


def own_arguments(argv: list[str]) -> list[str]:
    """The arguments outside ROS's: rcl takes everything from ``--ros-args`` up to a ``--``
    (or the end)."""
    own, in_ros = [], False
    for argument in argv:
        if argument == "--ros-args":
            in_ros = True
        elif in_ros and argument == "--":
            in_ros = False
        elif not in_ros:
            own.append(argument)
    return own


def help_text() -> str:
    """What ``dynamics_node --help`` prints."""
    options = "\n".join(f"  {flag:<12} {text}" for flag, text in OPTIONS.items())
    return (f"usage: {PROGRAM} [--managed] [--ros-args [-p NAME:=VALUE ...] [--params-file FILE] [-r FROM:=TO ...]]\n\n"
            "The youBot dynamics node: simulate mode integrates a scene and publishes its motion, inverse mode\n"
            "computes joint torques from /joint_states. Stamps are simulated time: run rviz2 and tf2 listeners\n"
            "with use_sim_time:=true. Topics, services and parameters: docs/node.md; with ROS 2: docs/ros.md.\n\n"
            f"options:\n{options}\n\nparameters (--ros-args -p NAME:=VALUE):\n{parameter_help()}\n")


def main(args: list[str] | None, start: Callable[[list[str] | None, bool], int]) -> int:
    """Read the command line ``args`` (without the program name; None: ``sys.argv[1:]``):
    print the help (status 0) or a one-line error for an option it does not know (status 2),
    or else call ``start(args, managed)`` with ``args`` untouched and return its status."""
    own = own_arguments(sys.argv[1:] if args is None else args)
    if "-h" in own or "--help" in own:
        sys.stdout.write(help_text())
        return 0
    unknown = [argument for argument in own if argument != "--managed"]
    if unknown:
        print(f"{PROGRAM}: error: unknown argument {unknown[0]!r} (parameters go after --ros-args: "
              f"--ros-args -p NAME:=VALUE; see {PROGRAM} --help)", file=sys.stderr)
        return 2
    return start(args, "--managed" in own)
