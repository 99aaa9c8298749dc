"""Start-up of the command line: `--help` imports no command module and none of the heavy
libraries, `info` none that it does not use, and the summaries `--help` lists (COMMANDS) are
the ones the command modules register. What is imported, not how long it takes: the wall
time is measured in bench/summary.py."""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest

from youbot_dynamics import cli

REPO = Path(__file__).resolve().parents[2]
HEAVY = ("numpy", "pinocchio", "scipy", "sympy", "yourdfpy", "trimesh", "numba", "rerun", "networkx",
         "matplotlib", "youbot_dynamics.model.robot", "youbot_dynamics.cli.model_commands")


def _imported_after(argv: list[str]) -> set[str]:
    """Top-level names in sys.modules after cli.main(argv) in a fresh interpreter."""
    code = ("import sys\nfrom youbot_dynamics.cli import main\nmain(sys.argv[1:])\n"
            "print('MODULES', ' '.join(sorted(sys.modules)))")
    done = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=REPO,
                          timeout=300, check=True)
    return set(done.stdout.rsplit("MODULES ", 1)[1].split())


@pytest.mark.parametrize("argv", [["--help"], [], ["no-such-command"]])
def test_help_and_usage_errors_import_nothing_heavy(argv: list[str]) -> None:
    imported = _imported_after(argv)
    assert not imported & set(HEAVY), sorted(imported & set(HEAVY))


def test_info_imports_no_compiled_kernels_or_unused_libraries() -> None:
    imported = _imported_after(["info", "--json"])
    assert "youbot_dynamics.model.robot" in imported  # it did load the robot
    unused = {"numba", "sympy", "rerun", "scipy", "yourdfpy", "trimesh", "networkx", "numpy.random",
              "youbot_dynamics.dynamics.friction"}
    assert not imported & unused, sorted(imported & unused)


def _registered(modules: tuple[str, ...] | None) -> dict[str, str]:
    parser = cli.build_parser(modules)
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {choice.dest: choice.help for choice in subparsers._choices_actions}


def test_commands_list_what_the_modules_register() -> None:
    """COMMANDS (name -> module, summary) against each module's own registration: main
    imports the right module for each command, and `--help` shows the modules' summaries."""
    for module in cli.COMMAND_MODULES:
        assert _registered((module,)) == {name: summary for name, (owner, summary) in cli.COMMANDS.items()
                                          if owner == module}, module
    assert _registered(()) == _registered(None)
