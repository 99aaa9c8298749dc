"""Sub-command ``report``: every study in one Markdown page with its figures, the studies
run as independent cases on Dask (youbot_dynamics.analysis.report and .sweeps)."""
from __future__ import annotations

import argparse

from youbot_dynamics.cli.common import add_sweep_arguments, output_folder


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``report``."""
    from youbot_dynamics.analysis.report import PAGE, STUDY_NAMES
    parser = subparsers.add_parser(
        "report", help="run every study; write their PNGs and one Markdown page",
        description=f"Run every study (short forms; --full for the seed's sizes) through "
                    f"Dask and write their PNGs and {PAGE} (one section per seed table or "
                    f"figure: the seed's figure or verdict, ours, the difference) into --out.")
    parser.add_argument("--out", required=True, metavar="DIR", help="report folder")
    parser.add_argument("--full", action="store_true", help="the seed's sizes (long)")
    parser.add_argument("--only", nargs="+", choices=STUDY_NAMES, metavar="STUDY",
                        help=f"only these studies (of {', '.join(STUDY_NAMES)})")
    add_sweep_arguments(parser)
    parser.set_defaults(run=run_report)


def run_report(args: argparse.Namespace) -> int:
    """Write the report; print each study's status and the page's path. Exit status 1 if a
    study failed."""
    from youbot_dynamics.analysis.report import write_report
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
