"""The `youbot-dynamics` command line: one sub-command module per subject.

Each module in COMMAND_MODULES exposes ``register(subparsers)``, adding its sub-commands
with ``set_defaults(run=function)``; ``function(args) -> int`` does the work. User mistakes
raise :class:`youbot_dynamics.cli.common.CommandError` (or a library error that subclasses
``UserInputError``) and end with a one-line message and exit status 2.

One vocabulary (cli/common.py's ``add_*`` helpers; test_cli_vocabulary walks the parser
tree to check it): ``--duration S`` simulated seconds, ``--rate HZ`` a rate in Hz and nothing
else, ``--time-scale X`` simulated (or recorded) seconds per wall second with 0 as fast as
possible, ``--plot PATH`` a figure file, ``--out DIR`` a folder of outputs, ``--json`` on
every command, ``--tol`` on the commands that choose an integrator's accuracy. Each module
declares ``ACCURACY``: its commands that run an integrator, each mapped to ``"--tol"`` or
to the reason its accuracy is not a command-line choice (it sweeps the tolerances, or runs
a scene's pinned integrator).

Start-up: :func:`main` imports only the module of the command it runs (COMMANDS says which),
so ``--help`` imports none of them (no numpy, Pinocchio, scipy, sympy, rerun) and a command
pays only for what its own module needs. COMMANDS holds each command's one-line summary for
that list; test_cli_startup checks it against what the modules register.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from youbot_dynamics.errors import UserInputError

#: command -> (the module that registers it, its one-line summary in ``--help``), in the
#: order ``--help`` lists them.
COMMANDS: dict[str, tuple[str, str]] = {
    name: (f"youbot_dynamics.cli.{module}", summary) for module, commands in (
        ("model_commands", (("info", "joints, limits, friction, fidelity report"),
                            ("fk", "pose of a frame (PoE forward kinematics)"),
                            ("screws", "screw axes S_i and home pose M"),
                            ("jacobian", "space, body or Pinocchio frame Jacobian"),
                            ("id", "inverse dynamics: torques from q, v, a"),
                            ("fd", "forward dynamics: accelerations from q, v, tau"))),
        ("sim_commands", (("simulate", "simulate a scene"),
                          ("work-precision", "speed versus accuracy on a scene"))),
        ("contact_commands", (("contact-extremes", "measure contact at its extremes"),)),
        ("study_commands", (("study", "run one of the classic studies (study --help lists them)"),)),
        ("ros_commands", (("replay", "publish a recorded bag on its ROS 2 topics"),
                          ("main-job", "simulate a scene with the dynamics node, log MCAP and Rerun"))),
        ("log_commands", (("log", "repair log files"),)),
        ("identify_commands", (("excite", "optimise an excitation trajectory for identification"),
                               ("identify", "identify base parameters from a bag's /joint_states"))),
        ("mobile_commands", (("mecanum", "youBot base: wheel speeds of a twist, and its odometry"),)),
        ("report_commands", (("report", "run every study; write their PNGs and one Markdown page"),)),
        ("uncertainty_commands", (("scene-uncertainty", "propagate a scene's value ± sigma parameters to an "
                                                        "output: linear band against Monte Carlo"),)),
    ) for name, summary in commands}
COMMAND_MODULES = tuple(dict.fromkeys(module for module, _ in COMMANDS.values()))


class OneLineParser(argparse.ArgumentParser):
    """argparse's parser whose usage errors are one line (no usage block), exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(modules: tuple[str, ...] | None = None) -> argparse.ArgumentParser:
    """The argument parser with the sub-commands of ``modules`` registered (default
    COMMAND_MODULES, every one; sub-parsers of the same one-line class). ``()`` gives the
    bare list of COMMANDS with their summaries, importing no command module."""
    parser = OneLineParser(
        prog="youbot-dynamics",
        description="youBot kinematics, dynamics, simulation and classic studies.",
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    modules = COMMAND_MODULES if modules is None else modules
    if not modules:
        for name, (_, summary) in COMMANDS.items():
            subparsers.add_parser(name, help=summary)
    for name in modules:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 2 bad input, 1 failure)."""
    argv = sys.argv[1:] if argv is None else argv
    command = COMMANDS.get(argv[0]) if argv else None
    parser = build_parser(() if command is None else (command[0],))
    try:
        args = parser.parse_args(argv)
    except SystemExit as done:  # --help (0) or a usage error (2, one line on stderr)
        return int(done.code or 0)
    try:
        return int(args.run(args) or 0)
    except UserInputError as error:
        print(f"youbot-dynamics {args.command}: error: {error}", file=sys.stderr)
        return 2
