"""Sub-command ``report``: every study in one Markdown page with its figures, the studies
run as independent cases on Dask (youbot_dynamics.studies.report and .sweeps)."""
from __future__ import annotations

import argparse

from youbot_dynamics.cli.common import CommandError, add_sweep_arguments, output_folder


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``report``."""
    from youbot_dynamics.studies.report import PAGE, STUDY_NAMES
    parser = subparsers.add_parser(
        "report", help="run every study; write their PNGs and one Markdown page",
        description=f"Run every study (short forms; --full for the seed's sizes) through "
                    f"Dask and write their PNGs and {PAGE} (one section per seed table or "
                    f"figure: the seed's figure or verdict, ours, the difference) into --out.")
    parser.add_argument("--out", metavar="DIR", help="report folder (required unless "
                        "--list-figures)")
    parser.add_argument("--list-figures", action="store_true",
                        help="print every figure the report draws (file, study, caption) "
                             "and exit without running anything")
    parser.add_argument("--full", action="store_true", help="the seed's sizes (long)")
    parser.add_argument("--only", nargs="+", choices=STUDY_NAMES, metavar="STUDY",
                        help=f"only these studies (of {', '.join(STUDY_NAMES)})")
    add_sweep_arguments(parser)
    parser.set_defaults(run=run_report)


def run_report(args: argparse.Namespace) -> int:
    """Write the report; print each study's status and the page's path. Exit status 1 if a
    study failed."""
    from youbot_dynamics.studies.report import write_report
    if args.list_figures:
        return list_figures(args.only)
    if args.out is None:
        raise CommandError("report: --out DIR is required (or --list-figures)")
    output_folder(args.out, "--out")
    page, results = write_report(args.out, full=args.full, only=args.only,
                                 workers=args.workers, scheduler=args.scheduler)
    for result in results:
        status = ("not in this build" if result.status is None else
                  f"ok, {result.wall_time:.1f} s" if result.status == 0 else
                  f"FAILED (exit status {result.status})")
        if result.figure_error is not None:
            status += "; figures FAILED"
        elif result.figures:
            status += f"; {len(result.figures)} figures, {result.figure_time:.1f} s"
        print(f"{result.name:<24} {status}")
    print(f"report written to {page}")
    return int(any(result.failed for result in results))


def list_figures(only: list[str] | None) -> int:
    """Print the declared figures of the studies (all, or those in ``only``) as a Markdown
    table: file, study, caption."""
    from youbot_dynamics.studies.figures import figure_sets
    from youbot_dynamics.studies.report import STUDIES
    print("| file | study | caption |\n|---|---|---|")
    for study in STUDIES:
        if only and study.name not in only:
            continue
        for spec in getattr(figure_sets().get(study.name), "specs", ()):
            print(f"| {spec.file} | {study.name} | {spec.caption} |")
        for file in study.figures:
            print(f"| {file} | {study.name} | written by the study's command |")
    return 0
