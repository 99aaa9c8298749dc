"""Sub-commands on log files: ``log recover``.

- ``log recover BROKEN.mcap [-o FIXED.mcap]``: rebuild a readable, indexed MCAP from one
  whose writer was killed (SIGKILL, power cut): every complete chunk and message kept, the
  summary and statistics rebuilt (see :mod:`youbot_dynamics.io.mcap_recover`). The output
  defaults to ``BROKEN.recovered.mcap`` beside the input; the input is never changed.
"""
from __future__ import annotations

import argparse

from youbot_dynamics.io.mcap_recover import recover_mcap


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `log` with its sub-command `recover`."""
    log = subparsers.add_parser("log", help="repair log files")
    actions = log.add_subparsers(dest="log_command", required=True, metavar="ACTION")
    recover = actions.add_parser("recover", help="rebuild a readable, indexed MCAP from a truncated one")
    recover.add_argument("broken", help="the truncated .mcap file")
    recover.add_argument("-o", "--output", default=None,
                         help="where to write the recovered file (default BROKEN.recovered.mcap)")
    recover.set_defaults(run=run_recover)


def run_recover(args: argparse.Namespace) -> int:
    """Recover the file; print what was kept and what was dropped."""
    result = recover_mcap(args.broken, args.output)
    span = ("no messages" if result.first_log_time_ns is None else
            f"log time {result.first_log_time_ns * 1e-9:.3f} .. {result.last_log_time_ns * 1e-9:.3f} s")
    state = ("it was complete" if result.complete else
             f"it had no summary; {result.dropped_bytes} bytes of incomplete tail dropped")
    print(f"log recover: {result.messages} messages in {result.chunks} complete chunks "
          f"({len(result.topics)} topics: {', '.join(result.topics) or 'none'}; {span}) "
          f"from {result.source}; {state}; wrote {result.target}")
    return 0
