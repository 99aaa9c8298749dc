"""The `youbot-dynamics` command line: one sub-command module per subject.

Each module in COMMAND_MODULES exposes ``register(subparsers)``, adding its sub-commands
with ``set_defaults(run=function)``; ``function(args) -> int`` does the work. User mistakes
raise :class:`youbot_dynamics.cli.common.CommandError` (or a library error that subclasses
``UserInputError``) and end with a one-line message and exit status 2.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from youbot_dynamics.errors import UserInputError

COMMAND_MODULES = (
    "youbot_dynamics.cli.model_commands",
    "youbot_dynamics.cli.sim_commands",
    "youbot_dynamics.cli.contact_commands",
    "youbot_dynamics.cli.pendulum_commands",
    "youbot_dynamics.cli.mechanism_commands",
    "youbot_dynamics.cli.study_commands",
    "youbot_dynamics.cli.ros_commands",
    "youbot_dynamics.cli.log_commands",
    "youbot_dynamics.cli.identify_commands",
    "youbot_dynamics.cli.mobile_commands",
    "youbot_dynamics.cli.report_commands",
)


class OneLineParser(argparse.ArgumentParser):
    """argparse's parser whose usage errors are one line (no usage block), exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every sub-command registered (sub-parsers of the same
    one-line class)."""
    parser = OneLineParser(
        prog="youbot-dynamics",
        description="youBot kinematics, dynamics, simulation and classic studies.",
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 2 bad input, 1 failure)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as done:  # --help (0) or a usage error (2, one line on stderr)
        return int(done.code or 0)
    try:
        return int(args.run(args) or 0)
    except UserInputError as error:
        print(f"youbot-dynamics {args.command}: error: {error}", file=sys.stderr)
        return 2
