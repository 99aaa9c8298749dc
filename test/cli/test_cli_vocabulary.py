"""The command line's one vocabulary, checked on the whole parser tree (every command and
sub-command, however deep, of every module in cli.COMMAND_MODULES):

- every leaf command takes --json;
- no option is spelled --t-end, --t or --fast (simulated time is --duration, "as fast as
  possible" is --time-scale 0);
- --duration is simulated time in seconds, --rate a float in Hz, --time-scale simulated or
  recorded seconds per wall second (0: as fast as possible), --plot one figure file, --out a
  folder: each with the help text of its cli.common helper;
- a command takes --tol (a relative tolerance) exactly when its module's ACCURACY says so
  ("--tol"); every command ACCURACY names exists, and every module declares ACCURACY (the
  commands that run an integrator, each with "--tol" or the reason its accuracy is not a
  command-line choice).
"""
from __future__ import annotations

import argparse
import importlib
from typing import Iterator

import pytest

from youbot_dynamics import cli
from youbot_dynamics.cli.common import relative_tolerance

RETIRED = ("--t-end", "--t", "--fast")


def _leaves(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()
            ) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    """(command path such as "log recover", its parser) for every parser without sub-commands."""
    groups = [action for action in parser._actions if isinstance(action, argparse._SubParsersAction)]
    if not groups and path:
        yield " ".join(path), parser
    for group in groups:
        for name, child in group.choices.items():
            yield from _leaves(child, (*path, name))


@pytest.fixture(scope="module")
def tree() -> dict[str, dict[str, argparse.ArgumentParser]]:
    """module -> {command path -> leaf parser}, every module of the command line."""
    return {module: dict(_leaves(cli.build_parser((module,)))) for module in cli.COMMAND_MODULES}


def _options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {flag: action for action in parser._actions for flag in action.option_strings}


def _every(tree, flag: str) -> Iterator[tuple[str, argparse.Action]]:
    """(command path, action) for every leaf that has ``flag``."""
    for leaves in tree.values():
        for path, parser in leaves.items():
            action = _options(parser).get(flag)
            if action is not None:
                yield path, action


def test_the_tree_has_every_command(tree) -> None:
    roots = {path.split()[0] for leaves in tree.values() for path in leaves}
    assert roots == set(cli.COMMANDS)


def test_every_command_takes_json(tree) -> None:
    missing = [path for leaves in tree.values() for path, parser in leaves.items()
               if not isinstance(_options(parser).get("--json"), argparse._StoreTrueAction)]
    assert not missing, f"no --json: {missing}"
    helps = {action.help for _, action in _every(tree, "--json")}
    assert len(helps) == 1, helps


def test_no_retired_spelling(tree) -> None:
    found = [(path, flag) for leaves in tree.values() for path, parser in leaves.items()
             for flag in _options(parser) if flag in RETIRED]
    assert not found, f"retired options (use --duration, --time-scale 0): {found}"


def test_duration_is_simulated_seconds(tree) -> None:
    wrong = [path for path, action in _every(tree, "--duration")
             if action.metavar != "S" or not action.help.startswith("simulated time, s (default ")
             or action.type("0.5") != 0.5]
    assert not wrong, f"--duration not from cli.common.add_duration: {wrong}"


def test_rate_is_a_float_in_hz(tree) -> None:
    rates = list(_every(tree, "--rate"))
    assert rates
    wrong = [path for path, action in rates
             if action.metavar != "HZ" or ", Hz (default " not in action.help or action.type("2.5") != 2.5
             or not isinstance(action.default, float)]
    assert not wrong, f"--rate that is no rate in Hz: {wrong}"


def test_time_scale_is_seconds_per_wall_second(tree) -> None:
    scales = dict(_every(tree, "--time-scale"))
    assert {"main-job", "replay"} <= set(scales)
    wrong = [path for path, action in scales.items()
             if action.metavar != "X" or action.default != 1.0 or action.type("0") != 0.0
             or "seconds per wall second (default 1: real time; 0: as fast as possible)" not in action.help]
    assert not wrong, f"--time-scale not from cli.common.add_time_scale: {wrong}"
    for action in scales.values():
        with pytest.raises(argparse.ArgumentTypeError):
            action.type("-1")


@pytest.mark.parametrize("flag, metavar", [("--plot", "PATH"), ("--out", "DIR")])
def test_plot_is_a_file_and_out_a_folder(tree, flag: str, metavar: str) -> None:
    wrong = [path for path, action in _every(tree, flag)
             if type(action) is not argparse._StoreAction or action.nargs is not None
             or action.type not in (None, str) or action.metavar != metavar]
    assert not wrong, f"{flag} that takes no single {metavar}: {wrong}"


def test_every_module_declares_accuracy(tree) -> None:
    undeclared = [module for module in tree
                  if not isinstance(getattr(importlib.import_module(module), "ACCURACY", None), dict)]
    assert not undeclared, f"modules without ACCURACY (command -> '--tol' or why not): {undeclared}"


@pytest.fixture(scope="module")
def accuracy(tree) -> dict[str, dict[str, str]]:
    """module -> its ACCURACY (command path -> "--tol" or the reason it takes none)."""
    return {module: getattr(importlib.import_module(module), "ACCURACY", {}) for module in tree}


def test_accuracy_names_registered_commands_and_reasons(tree, accuracy) -> None:
    unknown = [(module, path) for module, declared in accuracy.items() for path in declared
               if path not in tree[module]]
    assert not unknown, f"ACCURACY names commands its module does not register: {unknown}"
    bare = [path for declared in accuracy.values() for path, source in declared.items()
            if source != "--tol" and len(source) < 20]
    assert not bare, f"give the reason a command that integrates takes no --tol: {bare}"


def test_tol_exactly_where_accuracy_says(tree, accuracy) -> None:
    with_tol = {path for path, _ in _every(tree, "--tol")}
    wanted = {path for declared in accuracy.values() for path, source in declared.items() if source == "--tol"}
    assert with_tol == wanted, (f"--tol but not declared: {sorted(with_tol - wanted)}; "
                                f"declared but no --tol: {sorted(wanted - with_tol)}")
    wrong = [path for path, action in _every(tree, "--tol") if action.type is not relative_tolerance]
    assert not wrong, f"--tol that is no relative tolerance (cli.common.relative_tolerance): {wrong}"
