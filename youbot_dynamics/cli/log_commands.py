"""Sub-commands on log files: ``log recover``.

- ``log recover BROKEN.mcap [-o FIXED.mcap]``: rebuild a readable, indexed MCAP from one
  whose writer was killed (SIGKILL, power cut): every complete chunk and message kept, the
  summary and statistics rebuilt (see :mod:`youbot_dynamics.io.mcap_recover`). The output
  defaults to ``BROKEN.recovered.mcap`` beside the input; the input is never changed.
  Damaged chunks are named by byte offset; a file from which no message is recovered is an
  error (one line, exit 2, nothing written).
- ``log recover BROKEN.rrd [-o FIXED.rrd]``: the same for a Rerun recording, through
  Rerun's own command line (see :mod:`youbot_dynamics.io.rrd_recover`).

``--json`` prints the recovery's figures (paths as strings, log times in ns) instead.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from youbot_dynamics.cli.common import CommandError, add_json, output_file, print_json
from youbot_dynamics.io.mcap_recover import Recovery, recover_mcap
from youbot_dynamics.io.rrd_recover import recover_rrd

#: No command here runs an integrator (see youbot_dynamics.cli).
ACCURACY: dict[str, str] = {}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `log` with its sub-command `recover`."""
    log = subparsers.add_parser("log", help="repair log files")
    actions = log.add_subparsers(dest="log_command", required=True, metavar="ACTION")
    recover = actions.add_parser("recover", help="rebuild a readable, indexed .mcap (or .rrd) from a truncated one")
    recover.add_argument("broken", help="the truncated .mcap file (or .rrd Rerun recording)")
    recover.add_argument("-o", "--output", default=None,
                         help="where to write the recovered file (default BROKEN.recovered.mcap or .rrd)")
    add_json(recover)
    recover.set_defaults(run=run_recover)


def recovery_losses(result: Recovery) -> str:
    """What an incomplete MCAP lost: damaged chunks by byte offset, where reading stopped,
    the bytes dropped, messages without their channel."""
    parts = [f"damaged chunk skipped {damage}" for damage in result.damaged]
    if result.stopped is not None:
        parts.append(f"reading stopped {result.stopped}")
    if result.dropped_bytes or not parts:
        parts.append(f"{result.dropped_bytes} bytes of unreadable or incomplete tail dropped")
    if result.orphans:
        parts.append(f"{result.orphans} messages dropped with their channel")
    return ("it was damaged: " if result.had_footer else "it had no summary; ") + "; ".join(parts)


def run_recover(args: argparse.Namespace) -> int:
    """Recover the file; print what was kept and what was dropped."""
    kind = Path(args.broken).suffix
    if args.output is not None and Path(args.output).suffix != kind:
        raise CommandError(f"-o {args.output}: the recovered file must keep the suffix {kind or '(none)'} "
                           f"of {args.broken}")
    if args.output is not None:
        output_file(args.output, "-o")
    if kind == ".rrd":
        rrd = recover_rrd(args.broken, args.output)
        if args.json:
            print_json({"kind": "rrd", "source": str(rrd.source), "target": str(rrd.target), "chunks": rrd.chunks})
            return 0
        print(f"log recover: {rrd.chunks} chunks from {rrd.source}; wrote {rrd.target} (with its footer)")
        return 0
    result = recover_mcap(args.broken, args.output)
    if args.json:
        print_json({"kind": "mcap", **result._asdict(), "source": str(result.source), "target": str(result.target),
                    "topics": list(result.topics)})
        return 0
    span = ("no messages" if result.first_log_time_ns is None else
            f"log time {result.first_log_time_ns * 1e-9:.3f} .. {result.last_log_time_ns * 1e-9:.3f} s")
    state = "it was complete" if result.complete else recovery_losses(result)
    print(f"log recover: {result.messages} messages in {result.chunks} complete chunks "
          f"({len(result.topics)} topics: {', '.join(result.topics) or 'none'}; {span}) "
          f"from {result.source}; {state}; wrote {result.target}")
    return 0
