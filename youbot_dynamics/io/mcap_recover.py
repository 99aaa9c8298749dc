"""Rebuild a readable, indexed .mcap file from a truncated one (a writer killed mid-run).

A writer that dies before ``finish`` leaves the data section without its end: no summary,
no footer, no closing magic, perhaps half a record at the tail. Indexed readers (rosbags'
AnyReader, ``mcap.reader.make_reader``'s seeking reader) then refuse the whole file.
:func:`recover_mcap` reads the file front to back with mcap's ``StreamReader`` (chunks
emitted whole, each decompressed and checked against its CRC), stops at the first record
that is incomplete or damaged, and writes every complete record before it to a new file
with mcap's ``Writer``: the header's profile and library, schemas, channels (with their
metadata: QoS profiles, type hashes), messages in file order with their log and publish
times and sequence numbers, metadata and attachments. The writer rebuilds the chunk and
message indexes, the statistics and the summary. Messages of a chunk cut off mid-write are
lost with it (its CRC cannot be checked); with :class:`~youbot_dynamics.io.mcap_log.McapLogger`
that is the chunk open at the crash, less than 1 s of log time.

Schema and channel ids are renumbered (1, 2, ... in order of appearance, as mcap's Writer
numbers them); nothing refers to them across files.
"""
from __future__ import annotations

import os
import struct
from collections.abc import Iterator
from pathlib import Path
from typing import IO, NamedTuple

import zstandard
from mcap.exceptions import McapError
from mcap.records import Attachment, Channel, Chunk, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer

from youbot_dynamics.errors import UserInputError

MAGIC = b"\x89MCAP0\r\n"
"""The 8 bytes that open (and close) every MCAP file."""

_DAMAGED = (McapError, struct.error, ValueError, EOFError, zstandard.ZstdError)
"""What mcap's StreamReader raises at a truncated or damaged record (EndOfFile, struct
errors on short reads, CRCValidationError (a ValueError), decompression errors)."""


class Recovery(NamedTuple):
    """What :func:`recover_mcap` kept: the files, message and chunk counts, the log-time
    range of the messages kept (ns; None without messages), the bytes of the source that
    were dropped (its incomplete tail), and whether the source was already complete (it
    ended with a footer and magic)."""

    source: Path
    target: Path
    messages: int
    chunks: int
    topics: tuple[str, ...]
    first_log_time_ns: int | None
    last_log_time_ns: int | None
    dropped_bytes: int
    complete: bool


def default_recovered_path(broken: str | Path) -> Path:
    """``run.mcap`` -> ``run.recovered.mcap`` beside it."""
    broken = Path(broken)
    return broken.with_name(f"{broken.stem}.recovered.mcap")


def _check_source(broken: Path) -> None:
    """``UserInputError`` unless ``broken`` is a file that starts with the MCAP magic."""
    if not broken.is_file():
        raise UserInputError(f"{broken}: no such file")
    with broken.open("rb") as stream:
        start = stream.read(len(MAGIC))
    if start != MAGIC[:len(start)]:
        raise UserInputError(f"{broken} is not an MCAP file (it starts with {start!r}, "
                             f"not {MAGIC!r})")
    if len(start) < len(MAGIC):
        raise UserInputError(f"{broken} ends before its header record: nothing to recover")


class _Copier:
    """Copies complete records into a Writer, renumbering schemas and channels."""

    def __init__(self, writer: Writer) -> None:
        self.writer = writer
        self.schemas: dict[int, int] = {0: 0}       # source schema id -> target id (0: none)
        self.channels: dict[int, int] = {}          # source channel id -> target id
        self.topics: dict[int, str] = {}
        self.messages = 0
        self.first: int | None = None
        self.last: int | None = None

    def copy(self, record: object) -> None:
        """Write ``record`` (a record from inside a chunk or outside one) to the target;
        indexes, statistics and summary records of the source are skipped (rebuilt)."""
        if isinstance(record, Schema) and record.id not in self.schemas:
            self.schemas[record.id] = self.writer.register_schema(
                name=record.name, encoding=record.encoding, data=record.data)
        elif isinstance(record, Channel) and record.id not in self.channels:
            self.channels[record.id] = self.writer.register_channel(
                topic=record.topic, message_encoding=record.message_encoding,
                schema_id=self.schemas[record.schema_id], metadata=dict(record.metadata))
            self.topics[record.id] = record.topic
        elif isinstance(record, Message):
            self.writer.add_message(channel_id=self.channels[record.channel_id], log_time=record.log_time,
                                    data=record.data, publish_time=record.publish_time,
                                    sequence=record.sequence)
            self.messages += 1
            self.first = record.log_time if self.first is None else min(self.first, record.log_time)
            self.last = record.log_time if self.last is None else max(self.last, record.log_time)
        elif isinstance(record, Metadata):
            self.writer.add_metadata(name=record.name, data=dict(record.metadata))
        elif isinstance(record, Attachment):
            self.writer.add_attachment(create_time=record.create_time, log_time=record.log_time,
                                       name=record.name, media_type=record.media_type, data=record.data)


def _complete_records(source: IO[bytes]) -> Iterator[tuple[object, int]]:
    """Yield (record, end offset) for every complete record of the file ``source`` (open at
    0) in order, each chunk whole (decompressed and CRC-checked: its records as a list);
    stop silently at the first incomplete or damaged record."""
    reader = StreamReader(source, emit_chunks=True, validate_crcs=False)
    records = iter(reader.records)
    while True:
        try:
            record = next(records)
            if isinstance(record, Chunk):
                record = breakup_chunk(record, validate_crc=True)
        except (StopIteration, *_DAMAGED):
            return
        yield record, source.tell()


def recover_mcap(broken: str | Path, fixed: str | Path | None = None) -> Recovery:
    """Write to ``fixed`` (default :func:`default_recovered_path`) every complete chunk and
    message of the .mcap file ``broken``, with a rebuilt summary; return what was kept.

    ``UserInputError`` (one line naming the file) if ``broken`` is missing, empty, not an
    MCAP file, or ends before its header record; or if ``fixed`` is ``broken`` itself.
    The target is written beside itself and renamed into place, so it is never half written.
    """
    broken = Path(broken)
    fixed = default_recovered_path(broken) if fixed is None else Path(fixed)
    if fixed.resolve() == broken.resolve():
        raise UserInputError(f"MCAP recovery: the output {fixed} would overwrite the file being recovered")
    _check_source(broken)
    fixed.parent.mkdir(parents=True, exist_ok=True)
    partial = fixed.with_name(f".{fixed.name}.partial")
    size = broken.stat().st_size
    with broken.open("rb") as source:
        complete = _ends_with_footer(source, size)
        records = _complete_records(source)
        first = next(records, None)
        if first is None or not isinstance(first[0], Header):
            raise UserInputError(f"{broken} ends before its header record: nothing to recover")
        header, end = first
        try:
            with partial.open("wb") as target:
                writer = Writer(target, compression=CompressionType.ZSTD)
                writer.start(profile=header.profile, library=header.library)
                copier = _Copier(writer)
                chunks = 0
                for record, end in records:
                    if isinstance(record, list):
                        chunks += 1
                        for inner in record:
                            copier.copy(inner)
                    else:
                        copier.copy(record)
                writer.finish()
                target.flush()
                os.fsync(target.fileno())
        except BaseException:
            partial.unlink(missing_ok=True)
            raise
    partial.replace(fixed)
    return Recovery(broken, fixed, copier.messages, chunks, tuple(sorted(set(copier.topics.values()))),
                    copier.first, copier.last, 0 if complete else size - end, complete)


def _ends_with_footer(source: IO[bytes], size: int) -> bool:
    """True if the file ends with the closing magic (a finished writer); rewinds to 0."""
    if size < 2 * len(MAGIC):
        return False
    source.seek(size - len(MAGIC))
    ended = source.read(len(MAGIC)) == MAGIC
    source.seek(0)
    return ended
