"""Sub-command `contact-extremes`: contact at its extremes, as tables (see
youbot_dynamics.accuracy.contact_extremes)."""
from __future__ import annotations

import argparse
import json

from youbot_dynamics.accuracy.contact_extremes import TABLES
from youbot_dynamics.cli.common import add_json, finite_or_none
from youbot_dynamics.io.text_tables import records_table

#: The commands here that run an integrator, and where their accuracy comes from (see
#: youbot_dynamics.cli: "--tol" or the reason the command takes none).
ACCURACY = {"contact-extremes": "each table runs the integrators, tolerances and steps it measures"}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `contact-extremes`."""
    command = subparsers.add_parser(
        "contact-extremes", help="measure contact at its extremes",
        description="Print tables: stiffness sweep k = 1e3..1e8 N/m^1.5 per integrator and the constraint "
        "stepper at several steps (stable?, max penetration, energy gained at the impact, wall time); a 1 g "
        "body on a 10 kg one; a 2 mm pellet at 50 m/s against a 1 cm plate (tunnelling); a grasp at the "
        "friction-cone limit. The stiffness sweep takes about 90 s.")
    command.add_argument("--table", action="append", choices=sorted(TABLES),
                         help="only this table (repeatable; default: all)")
    add_json(command)
    command.set_defaults(run=run_contact_extremes)


def run_contact_extremes(args: argparse.Namespace) -> int:
    """Run the chosen tables and print them."""
    names = args.table or list(TABLES)
    tables = {name: TABLES[name]() for name in names}
    if args.json:
        print(json.dumps({name: [{k: finite_or_none(v) if isinstance(v, float) else v for k, v in row.items()}
                                 for row in rows] for name, rows in tables.items()}))
        return 0
    for name, rows in tables.items():
        print(f"## {name}\n\n{records_table(rows)}\n")
    return 0
