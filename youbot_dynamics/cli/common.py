"""Helpers shared by the sub-commands: the shared option vocabulary, robot loading,
joint-value parsing, output.

The vocabulary (one ``add_*`` function per option, so each has one spelling and one help
text; test_cli_vocabulary walks the parser tree to check it):

- ``--duration S``: simulated time, s (:func:`add_duration`);
- ``--rate HZ``: a rate in Hz, and nothing else (:func:`add_rate`);
- ``--time-scale X``: simulated (or recorded) seconds per wall second, 0 as fast as
  possible (:func:`add_time_scale`);
- ``--plot PATH``: a figure file (:func:`add_plot`); ``--out DIR``: a folder of outputs
  (:func:`add_out_folder`);
- ``--json``: one JSON document on stdout instead of the table (:func:`add_json`; every
  command takes it);
- ``--tol`` (with ``--rtol``/``--atol`` for experts): the accuracy of a command that runs an
  integrator (:func:`add_tolerance_arguments`).

Joint values on the command line come either in model order (``--q 0.1,0.2,...``, one per
coordinate, Pinocchio's order as ``info`` lists it: with a floating or planar ``--root`` the
root's coordinates come first and q has nq values, v nv) or by name
(``--q arm_joint_1=0.1,root_x=2``, unnamed joints 0, an unnamed root at its neutral pose). Output is a readable table,
or JSON with ``--json``: positions in metres, quaternions as (x, y, z, w), rotation
matrices row-major (a list of rows), angles in rad, infinite limits as null.
"""
from __future__ import annotations

import argparse
import json
import math
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Sequence

import numpy as np

from youbot_dynamics import default_urdf
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model import lie, limits

if TYPE_CHECKING:  # the robot loader (lxml, Pinocchio) only for commands that load one
    from youbot_dynamics.model.robot import Robot


class CommandError(UserInputError):
    """A bad command-line argument: one line, exit status 2."""


def add_json(parser: argparse.ArgumentParser) -> None:
    """--json: print one JSON document (an object, or an array) instead of the table."""
    parser.add_argument("--json", action="store_true",
                        help="print one JSON document on stdout instead of the table")


def add_duration(parser: argparse.ArgumentParser, default: float | None = None, *,
                 default_text: str | None = None, parse: Callable[[str], float] = float) -> None:
    """--duration S: simulated time in seconds (``default``; ``default_text`` says what None
    means, e.g. "the scene's")."""
    shown = default_text if default is None else f"{default:g}"
    parser.add_argument("--duration", type=parse, default=default, metavar="S",
                        help=f"simulated time, s (default {shown})")


def add_rate(parser: argparse.ArgumentParser, default: float, meaning: str, *,
             parse: Callable[[str], float] = float) -> None:
    """--rate HZ: a rate in Hz (``meaning`` says of what); the only use of the name."""
    parser.add_argument("--rate", type=parse, default=default, metavar="HZ",
                        help=f"{meaning}, Hz (default {default:g})")


def time_scale(text: str) -> float:
    """An argparse type: a time scale, finite and >= 0 (0: as fast as possible)."""
    value = float(text)
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f"must be finite and >= 0 (0: as fast as possible), got {text}")
    return value


def add_time_scale(parser: argparse.ArgumentParser, clock: str) -> None:
    """--time-scale X: ``clock`` seconds (simulated, recorded) per wall second; default 1
    (real time), 0 as fast as possible."""
    parser.add_argument("--time-scale", type=time_scale, default=1.0, metavar="X",
                        help=f"{clock} seconds per wall second (default 1: real time; 0: as fast as possible)")


def add_plot(parser: argparse.ArgumentParser, figure: str) -> None:
    """--plot PATH: write ``figure`` to a file (PNG)."""
    parser.add_argument("--plot", metavar="PATH", help=f"write {figure} to PATH (PNG)")


def add_out_folder(parser: argparse.ArgumentParser, outputs: str, default: str | None = None) -> None:
    """--out DIR: the folder ``outputs`` are written in (created if needed)."""
    parser.add_argument("--out", default=default, metavar="DIR",
                        help=f"folder for {outputs}" + (f" (default {default}/)" if default else ""))


def add_robot_arguments(parser: argparse.ArgumentParser) -> None:
    """--urdf, --strict and --json, which every model sub-command takes."""
    parser.add_argument("--urdf", help="URDF file (default: the packaged youBot)")
    parser.add_argument("--strict", action="store_true",
                        help="refuse a URDF with warnings (physically invalid inertias, a "
                        "singular mass matrix) instead of listing them in the fidelity report")
    add_json(parser)


def add_joint_argument(parser: argparse.ArgumentParser, flag: str, meaning: str) -> None:
    """A joint-vector option such as --q, in model order or by name (default all zeros)."""
    parser.add_argument(flag, default="", metavar="VALUES",
                        help=f"{meaning}: comma-separated in model order, or name=value pairs "
                        f"(unnamed joints 0; default all 0); write {flag}=-0.1,... when the "
                        "first value is negative")


def positive(text: str) -> float:
    """An argparse type: a positive float."""
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text}")
    return value


def positive_int(text: str) -> int:
    """An argparse type: a positive integer (a count)."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def relative_tolerance(text: str) -> float:
    """An argparse type: a relative tolerance within [MIN_RTOL, MAX_RTOL]
    (youbot_dynamics.model.limits)."""
    value = float(text)
    problem = limits.tolerance_problem(value)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return value


def add_tolerance_arguments(parser: argparse.ArgumentParser, rtol: float | None = None,
                            atol_help: str = "absolute tolerance") -> None:
    """--tol (the one accuracy knob) and --rtol/--atol (for experts; they override it)."""
    parser.add_argument("--tol", type=relative_tolerance,
                        help="accuracy: rtol = TOL and atol_i = TOL * max(|x0_i|, 1e-3) per "
                             "state component; --rtol/--atol override either")
    parser.add_argument("--rtol", type=relative_tolerance,
                        help="relative tolerance" + (f" (default {rtol:g})" if rtol else ""))
    parser.add_argument("--atol", type=positive, help=atol_help)


def tolerances(args: argparse.Namespace, x0) -> tuple[float | None, Any]:
    """(rtol, atol) from --tol, --rtol and --atol: an explicit --rtol or --atol wins, the
    other comes from --tol (see integrate.integrators.tolerances_from_tol); None where none of
    them gives one (the command's default applies)."""
    from youbot_dynamics.integrate.integrators import tolerances_from_tol
    if args.tol is None:
        return args.rtol, args.atol
    rtol, atol = tolerances_from_tol(args.tol, x0)
    return (rtol if args.rtol is None else args.rtol), (atol if args.atol is None else args.atol)


def robot_from(args: argparse.Namespace, root: str = "fixed") -> Robot:
    """The robot of --urdf, or the packaged youBot, with the given root joint (--strict:
    warnings are errors)."""
    from youbot_dynamics.model.robot import load_robot

    return load_robot(args.urdf if args.urdf else default_urdf(), root=root,
                      strict=getattr(args, "strict", False))


def joint_vector(robot: Robot, text: str, flag: str = "--q", of: str = "v") -> np.ndarray:
    """Parse '0.1,0.2,...' (model order, exactly nq values for ``of="q"``, nv for ``of="v"``)
    or 'name=value,...' (by name); empty text is the neutral configuration or zero."""
    parts = [part.strip() for part in text.split(",") if part.strip()]
    if not parts:
        return robot.vector({}, of=of)
    by_name = ["=" in part for part in parts]
    if any(by_name) and not all(by_name):
        raise CommandError(f"{flag}: give either all values in order or all as name=value, "
                           f"not a mix: {text!r}")
    try:
        if all(by_name):
            pairs = [part.split("=", 1) for part in parts]
            return robot.vector({name.strip(): _number(value, flag) for name, value in pairs}, of=of)
        return robot.vector([_number(part, flag) for part in parts], of=of)
    except CommandError:
        raise
    except UserInputError as error:
        raise CommandError(f"{flag}: {error}") from None


def _number(text: str, flag: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise CommandError(f"{flag}: {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise CommandError(f"{flag}: {text.strip()!r} is not a finite number")
    return value


def pose_record(transform: np.ndarray) -> dict[str, Any]:
    """A 4x4 pose as JSON-ready data: position (m), quaternion (x, y, z, w), rotation rows."""
    return {"position": transform[:3, 3].tolist(),
            "quaternion_xyzw": lie.quaternion_from_matrix(transform[:3, :3]).tolist(),
            "rotation": transform[:3, :3].tolist()}


def finite_or_none(value: float) -> float | None:
    """JSON has no infinity or NaN: unbounded limits and unknown figures become null."""
    return float(value) if math.isfinite(value) else None


def print_json(record: dict[str, Any]) -> None:
    """Print ``record`` as JSON. JSON has no NaN or infinity: a figure that is one (use
    finite_or_none for those that may be) is a CommandError, never invalid JSON."""
    try:
        text = json.dumps(record, indent=2, allow_nan=False)
    except ValueError:
        raise CommandError("a result is not finite (NaN or infinite): the inputs are beyond what "
                           "double precision holds; nothing printed") from None
    print(text)


def print_result(args: argparse.Namespace, record: dict[str, Any], text: str) -> int:
    """The end of a command that may have drawn ``args.plot``: with ``--json`` its
    ``record`` and the plot's path as JSON (:func:`print_json`), else its ``text`` and where
    the plot went. Returns the exit status 0."""
    if args.json:
        print_json({**record, "plot": args.plot})
        return 0
    print(text)
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def output_file(path: str, flag: str) -> Path:
    """Check, before any work, that a file can be written at ``path``: its folder exists, it
    is no folder, and it opens for appending (an existing file is left unchanged, a new one is
    removed again). CommandError naming the flag and the reason otherwise."""
    target = Path(path)
    if target.is_dir():
        raise CommandError(f"{flag} {path}: is a folder; give a file name")
    if not target.parent.is_dir():
        raise CommandError(f"{flag} {path}: the folder {target.parent} does not exist")
    existed = target.exists()
    try:
        with open(target, "a", encoding="utf-8"):
            pass
    except OSError as error:
        raise CommandError(f"{flag} {path}: cannot be written ({error.strerror or error})") from None
    if not existed:
        target.unlink()
    return target


def output_folder(path: str, flag: str) -> Path:
    """Create the folder ``path`` (with its parents) if needed and check, before any work,
    that files can be written in it. CommandError naming the flag and the reason otherwise
    (a file in the way, no permission)."""
    target = Path(path)
    blocking = next((p for p in (target, *target.parents) if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise CommandError(f"{flag} {path}: {blocking} is a file, not a folder")
    try:
        target.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=target):
            pass
    except OSError as error:
        raise CommandError(f"{flag} {path}: cannot create the folder or write in it ({error.strerror or error})") from None
    return target


def number(value: float) -> str:
    """A figure for a table cell."""
    return f"{value + 0.0:.9g}" if math.isfinite(value) else ("inf" if value > 0 else "-inf")


def matrix_text(matrix: np.ndarray, indent: str = "  ") -> str:
    """A matrix, one row per line, fixed-point columns."""
    return "\n".join(indent + "  ".join(f"{x + 0.0:13.9f}" for x in row) for row in matrix)


def table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """Columns aligned; text cells left, numbers (formatted with :func:`number`) right."""
    rows = [list(row) for row in rows]
    cells = [[value if isinstance(value, str) else number(float(value)) for value in row] for row in rows]
    widths = [max([len(h), *(len(row[i]) for row in cells)]) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths)).rstrip()]
    for raw, row in zip(rows, cells):
        lines.append("  ".join(c.ljust(w) if isinstance(r, str) else c.rjust(w)
                               for r, c, w in zip(raw, row, widths)).rstrip())
    return "\n".join(lines)


def add_sweep_arguments(parser: argparse.ArgumentParser) -> None:
    """--workers and --scheduler: where a sweep's independent cases run
    (youbot_dynamics.accuracy.sweeps)."""
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="processes of the embedded Dask cluster (default one per core; "
                             "0: serial, no Dask)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on this Dask cluster instead (e.g. tcp://10.0.0.5:8786)")
