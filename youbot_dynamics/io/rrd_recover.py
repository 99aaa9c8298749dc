"""Rebuild a complete .rrd from a Rerun recording whose writer was killed.

A killed Rerun recording has no footer. Rerun 0.41's ``RrdReader.stream()`` still reads
it (as a "legacy" file, with a warning) if the file ends between two messages, but a file
cut inside a message cannot be read at all ("Message payload ... exceeds file size"), and
``RrdReader.store()`` needs the footer in any case. rerun-sdk has no Python call that
rewrites such a file; its ``rerun`` command line (installed with rerun-sdk) does:
``rerun rrd merge --continue-on-error BROKEN -o FIXED`` keeps every complete message (the
application and recording ids included) and writes the footer. :func:`recover_rrd` runs it.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

from rerun.chunk import RrdReader

from youbot_dynamics.errors import UserInputError

MAGIC = b"RRF2"
"""The 4 bytes that open a Rerun 0.41 .rrd file."""
MERGE_TIMEOUT = 600.0
"""Longest wait (wall s) for ``rerun rrd merge``."""


class RrdRecovery(NamedTuple):
    """What :func:`recover_rrd` wrote: the files and the chunks of the recovered recording."""

    source: Path
    target: Path
    chunks: int


def default_recovered_rrd_path(broken: str | Path) -> Path:
    """``run.rrd`` -> ``run.recovered.rrd`` beside it."""
    broken = Path(broken)
    return broken.with_name(f"{broken.stem}.recovered.rrd")


def rerun_command() -> str:
    """The ``rerun`` executable of this interpreter's environment, else the one on PATH."""
    beside = Path(sys.executable).with_name("rerun")
    found = str(beside) if beside.is_file() else shutil.which("rerun")
    if found is None:
        raise UserInputError("Rerun recovery needs the `rerun` command line, installed with rerun-sdk")
    return found


def recover_rrd(broken: str | Path, fixed: str | Path | None = None) -> RrdRecovery:
    """Write to ``fixed`` (default :func:`default_recovered_rrd_path`) every complete message
    of the .rrd file ``broken``, with a footer; ``UserInputError`` (one line naming the file)
    if ``broken`` is missing or not a Rerun file, if ``fixed`` is ``broken``, or if the
    ``rerun`` command fails."""
    broken = Path(broken)
    fixed = default_recovered_rrd_path(broken) if fixed is None else Path(fixed)
    if fixed.resolve() == broken.resolve():
        raise UserInputError(f"Rerun recovery: the output {fixed} would overwrite the file being recovered")
    if not broken.is_file():
        raise UserInputError(f"{broken}: no such file")
    with broken.open("rb") as stream:
        start = stream.read(len(MAGIC))
    if start != MAGIC:
        raise UserInputError(f"{broken} is not a Rerun 0.41 recording (it starts with {start!r}, not {MAGIC!r})")
    fixed.parent.mkdir(parents=True, exist_ok=True)
    partial = fixed.with_name(f".{fixed.name}.partial")
    merge = subprocess.run([rerun_command(), "rrd", "merge", "--continue-on-error", str(broken), "-o", str(partial)],
                           capture_output=True, text=True, timeout=MERGE_TIMEOUT, check=False)
    if merge.returncode != 0:
        partial.unlink(missing_ok=True)
        last = (merge.stderr.strip().splitlines() or ["no message"])[-1]
        raise UserInputError(f"{broken}: `rerun rrd merge` failed ({last})")
    partial.replace(fixed)
    return RrdRecovery(broken, fixed, len(RrdReader(str(fixed)).store()))
