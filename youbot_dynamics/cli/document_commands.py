"""``study ledger``: the source-document ledger (studies/ledger.py): every figure, table and
checkable claim of the four source documents, the document's value beside ours, the
verdict and its evidence; filtered by document and verdict; a Markdown table or JSON.
``study base-parameters``: document 002's 2-DOF planar base-parameter example
(studies/planar_base_parameters.py)."""
from __future__ import annotations

import argparse

from youbot_dynamics.cli.common import add_json, print_json
from youbot_dynamics.studies import ledger, planar_base_parameters


def add_ledger(parser: argparse.ArgumentParser) -> None:
    """Options of ``study ledger``."""
    parser.description = ("Print the ledger of the source documents: one row per figure, table "
                          "and checkable claim (the document's value, ours, the verdict "
                          f"{' | '.join(ledger.VERDICTS)}, the reason and the test that "
                          "asserts our value), then the count per document and verdict.")
    parser.add_argument("--document", nargs="+", choices=ledger.DOCUMENTS, metavar="NNN",
                        help=f"only these documents (of {', '.join(ledger.DOCUMENTS)})")
    parser.add_argument("--verdict", nargs="+", choices=ledger.VERDICTS, metavar="VERDICT",
                        help=f"only rows with these verdicts (of {', '.join(ledger.VERDICTS)})")
    add_json(parser)
    parser.set_defaults(run=run_ledger)


def run_ledger(args: argparse.Namespace) -> int:
    """Print the selected rows and their counts."""
    rows = ledger.select(ledger.load_ledger(), args.document or (), args.verdict or ())
    if args.json:
        print_json(ledger.as_json(rows))
    else:
        print(ledger.text(rows) if rows else "no ledger row matches")
    return 0


def add_base_parameters(parser: argparse.ArgumentParser) -> None:
    """Options of ``study base-parameters``."""
    parser.description = ("Document 002's 2-DOF planar base-parameter example: the base parameters by "
                          "QR of Pinocchio's regressor, by a sympy Lagrange derivation, and the "
                          "document's list set beside the mass matrix.")
    add_json(parser)
    parser.set_defaults(run=run_base_parameters)


def run_base_parameters(args: argparse.Namespace) -> int:
    """Run the three ways and print them."""
    result = planar_base_parameters.run()
    if args.json:
        print_json(planar_base_parameters.as_json(result))
    else:
        print(planar_base_parameters.text(result))
    return 0


#: The studies this module adds under ``study``: name -> function adding its options.
STUDY_PARSERS = {"ledger": add_ledger, "base-parameters": add_base_parameters}
