"""Sub-command ``study NAME ...``: the classic studies, apart from the product commands.

STUDIES names each study, the command module that adds its options (``STUDY_PARSERS[name]
(parser)``, which also sets ``run``) and its one-line summary. The study itself lives in
studies/ (``run(config)``, its text and JSON); the command modules only parse options
into its config and print.
"""
from __future__ import annotations

import argparse
import importlib

#: study -> (the command module that adds its options, its one-line summary), in the order
#: ``study --help`` lists them.
STUDIES: dict[str, tuple[str, str]] = {
    name: (f"youbot_dynamics.cli.{module}", summary) for module, studies in (
        ("pendulum_commands", (
            ("pendulum", "simulate the elastic pendulum"),
            ("pendulum-tables", "the source document's elastic-pendulum tables"),
            ("bdf", "fixed-step BDF1-4: the source document's Tables 1-4, stability regions, measured "
                    "orders, CVODE order caps"),
            ("uncertainty", "the damped pendulum with uncertain L, m, d: linear propagation "
                            "against Monte Carlo"))),
        ("mechanism_commands", (
            ("squeezer", "Andrew's squeezer: a constrained mechanism in one formulation"),
            ("structure", "structural analysis (matching, BLT, Pantelides) of an example"),
            ("woodpecker", "the woodpecker toy: state events, impacts, beak hits and "
                           "statistics"))),
        ("pipeline_commands", (
            ("pipeline", "equation pipeline on an example model: every stage printed"),)),
        ("motion_commands", (
            ("lagrange", "equations of motion by sympy (Lagrange), simulated from the "
                         "source document's initial state"),
            ("rotations", "Cardan angles vs adaptive Cardan vs quaternions on a torque-free "
                          "rigid body"),
            ("unicycle", "the differential drive against its closed forms"))),
        ("document_commands", (
            ("base-parameters", "document 002's 2-DOF planar arm: base parameters by QR, by "
                                "sympy, and the document's list"),
            ("ledger", "the source documents' figures, tables and claims: theirs, ours, the "
                       "verdict and its evidence"))),
    ) for name, summary in studies}
#: The study commands that run an integrator, and where their accuracy comes from ("--tol",
#: or why the command takes none; see youbot_dynamics.cli).
ACCURACY = {**{f"study {name}": "--tol" for name in ("pendulum", "squeezer", "woodpecker", "pipeline",
                                                     "lagrange", "rotations", "unicycle")},
            "study pendulum-tables": "the source document's integrators and tolerances, table by table",
            "study bdf": "fixed steps: the step sizes are what the study measures",
            "study uncertainty": "fixed-step RK4 at the step of the source document"}
#: The one-line summary of ``study`` in ``youbot-dynamics --help``.
SUMMARY = "run one of the classic studies (study --help lists them)"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``study`` with one sub-command per study of STUDIES."""
    parser = subparsers.add_parser(
        "study", help=SUMMARY,
        description="The classic studies, each with the source document's "
                    "figures beside ours.")
    studies = parser.add_subparsers(dest="study", required=True, metavar="STUDY")
    for name, (module, summary) in STUDIES.items():
        importlib.import_module(module).STUDY_PARSERS[name](studies.add_parser(name, help=summary))
