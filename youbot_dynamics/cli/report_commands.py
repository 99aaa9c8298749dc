"""Sub-command ``report``: every study in one Markdown page with its figures, the studies
run as independent cases on Dask (youbot_dynamics.studies.report and .catalog)."""
from __future__ import annotations

import argparse
import json

from youbot_dynamics.cli.common import CommandError, add_json, add_sweep_arguments, output_folder

#: report runs every study at its own settings (see youbot_dynamics.cli and study_commands).
ACCURACY = {"report": "each study runs at the settings of its source document"}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``report``."""
    from youbot_dynamics.studies.catalog import SECTION_NAMES
    from youbot_dynamics.studies.report import PAGE
    parser = subparsers.add_parser(
        "report", help="run every study; write their PNGs and one Markdown page",
        description=f"Run every study (short forms; --full for the source document's sizes) through "
                    f"Dask and write their PNGs and {PAGE} (one section per source-document table or "
                    f"figure: the source document's figure or verdict, ours, the difference) into --out.")
    parser.add_argument("--out", metavar="DIR", help="report folder (required unless "
                        "--list-figures)")
    parser.add_argument("--list-figures", action="store_true",
                        help="print every figure the report draws (file, study, caption) "
                             "and exit without running anything")
    parser.add_argument("--full", action="store_true", help="the source documents' sizes (long)")
    parser.add_argument("--only", nargs="+", choices=SECTION_NAMES, metavar="STUDY",
                        help=f"only these studies (of {', '.join(SECTION_NAMES)})")
    add_sweep_arguments(parser)
    add_json(parser)
    parser.set_defaults(run=run_report)


def status_line(result) -> str:
    """One study's status: ok and its time, or FAILED; its figures."""
    status = f"ok, {result.wall_time:.1f} s" if result.ok else "FAILED"
    if result.figure_error is not None:
        status += "; figures FAILED"
    elif result.figures:
        status += f"; {len(result.figures)} figures, {result.figure_time:.1f} s"
    return f"{result.name:<24} {status}"


def run_report(args: argparse.Namespace) -> int:
    """Write the report; print each study's status and the page's path (or JSON). Exit
    status 1 if a study failed."""
    from youbot_dynamics.studies.report import write_report
    if args.list_figures:
        return list_figures(args.only, args.json)
    if args.out is None:
        raise CommandError("report: --out DIR is required (or --list-figures)")
    output_folder(args.out, "--out")
    page, results = write_report(args.out, full=args.full, only=args.only,
                                 workers=args.workers, scheduler=args.scheduler,
                                 progress=not args.json)
    if args.json:
        print(json.dumps({"page": str(page), "studies": [
            {"name": r.name, "ok": r.ok, "wall_time": r.wall_time,
             "figures": [figure.spec.file for figure in r.figures],
             "figures_failed": r.figure_error is not None, "figure_time": r.figure_time}
            for r in results]}, indent=2))
    else:
        for result in results:
            print(status_line(result))
        print(f"report written to {page}")
    return int(any(result.failed for result in results))


def list_figures(only: list[str] | None, as_json: bool = False) -> int:
    """Print the declared figures of the studies (all, or those in ``only``) as a Markdown
    table (file, study, caption), or as JSON."""
    from youbot_dynamics.studies.catalog import FIGURE_SETS, SECTIONS
    rows = []
    for section in SECTIONS:
        if only and section.name not in only:
            continue
        rows += [(spec.file, section.name, spec.caption)
                 for spec in getattr(FIGURE_SETS.get(section.name), "specs", ())]
        rows += [(file, section.name, "written by the study's run") for file in section.files]
    if as_json:
        print(json.dumps({"figures": [dict(zip(("file", "study", "caption"), row))
                                      for row in rows]}, indent=2))
        return 0
    print("| file | study | caption |\n|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")
    return 0
