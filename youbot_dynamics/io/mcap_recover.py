"""Rebuild a readable, indexed .mcap file from a truncated one (a writer killed mid-run).

A writer that dies before ``finish`` leaves the data section without its end: no summary,
no footer, no closing magic, perhaps half a record at the tail. Indexed readers (rosbags'
AnyReader, ``mcap.reader.make_reader``'s seeking reader) then refuse the whole file.
:func:`recover_mcap` reads the file front to back with mcap's ``StreamReader`` (chunks
emitted whole, each decompressed and checked against its CRC), and writes every complete
record to a new file with mcap's ``Writer``: the header's profile and library, schemas,
channels (with their metadata: QoS profiles, type hashes), messages in file order with
their log and publish times and sequence numbers, metadata and attachments. The writer
rebuilds the chunk and message indexes, the statistics and the summary. Messages of a
chunk cut off mid-write are lost with it (its CRC cannot be checked); with
:class:`~youbot_dynamics.io.mcap_log.McapLogger` that is the chunk open at the crash, less
than 1 s of log time.

A chunk whose record is whole but whose content is damaged (CRC mismatch, a
decompression error: what two writers on one file or a bad disk leave) is reported by its
byte offset and skipped; reading goes on with the next record (messages on a channel
declared only in a skipped chunk are dropped and counted). Reading stops at the first
record that is incomplete or whose framing is broken; the rest of the file is dropped
and the offset and reason reported. A file is ``complete`` only if it was read to its
footer and closing magic, with nothing damaged or left after them. Recovering no message
(nor metadata, nor attachment) is an error (:class:`NothingRecovered`; no file is written).

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
from mcap.exceptions import EndOfFile, McapError
from mcap.records import Attachment, Channel, Chunk, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer

from youbot_dynamics.errors import UserInputError

MAGIC = b"\x89MCAP0\r\n"
"""The 8 bytes that open (and close) every MCAP file."""

_DAMAGED = (McapError, struct.error, ValueError, EOFError, zstandard.ZstdError)
"""What mcap's StreamReader raises at a truncated or damaged record (EndOfFile, struct
errors on short reads, CRCValidationError (a ValueError), decompression errors)."""


class NothingRecovered(UserInputError):
    """An MCAP file with no message to recover: the message names the file, its damaged
    chunks and where reading stopped."""


class Damage(NamedTuple):
    """A damaged or unreadable part of a source file: its byte offset and what is wrong."""

    offset: int
    reason: str

    def __str__(self) -> str:
        return f"at byte {self.offset}: {self.reason}"


class Recovery(NamedTuple):
    """What :func:`recover_mcap` kept: the files, message and chunk counts, the log-time
    range of the messages kept (ns; None without messages), the bytes of the source that
    were dropped (its incomplete or unreadable tail), whether the source was already
    complete (read to its footer and magic, nothing damaged), the damaged chunks skipped,
    where reading stopped early (None if it reached the end), the messages dropped for
    want of their channel, and whether the source ended with a footer and magic."""

    source: Path
    target: Path
    messages: int
    chunks: int
    topics: tuple[str, ...]
    first_log_time_ns: int | None
    last_log_time_ns: int | None
    dropped_bytes: int
    complete: bool
    damaged: tuple[Damage, ...] = ()
    stopped: Damage | None = None
    orphans: int = 0
    had_footer: bool = False


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
        self.orphans = 0                            # messages whose channel was in a damaged chunk
        self.attachments = 0                        # attachment and metadata records
        self.first: int | None = None
        self.last: int | None = None

    def copy(self, record: object) -> None:
        """Write ``record`` (a record from inside a chunk or outside one) to the target;
        indexes, statistics and summary records of the source are skipped (rebuilt)."""
        if isinstance(record, Schema) and record.id not in self.schemas:
            self.schemas[record.id] = self.writer.register_schema(
                name=record.name, encoding=record.encoding, data=record.data)
        elif isinstance(record, Channel) and record.id not in self.channels and record.schema_id in self.schemas:
            self.channels[record.id] = self.writer.register_channel(
                topic=record.topic, message_encoding=record.message_encoding,
                schema_id=self.schemas[record.schema_id], metadata=dict(record.metadata))
            self.topics[record.id] = record.topic
        elif isinstance(record, Message) and record.channel_id not in self.channels:
            self.orphans += 1
        elif isinstance(record, Message):
            self.writer.add_message(channel_id=self.channels[record.channel_id], log_time=record.log_time,
                                    data=record.data, publish_time=record.publish_time,
                                    sequence=record.sequence)
            self.messages += 1
            self.first = record.log_time if self.first is None else min(self.first, record.log_time)
            self.last = record.log_time if self.last is None else max(self.last, record.log_time)
        elif isinstance(record, Metadata):
            self.writer.add_metadata(name=record.name, data=dict(record.metadata))
            self.attachments += 1
        elif isinstance(record, Attachment):
            self.attachments += 1
            self.writer.add_attachment(create_time=record.create_time, log_time=record.log_time,
                                       name=record.name, media_type=record.media_type, data=record.data)


class _Scan:
    """Reads the records of an MCAP file front to back (``records``), noting the damaged
    chunks it skips (``damaged``) and where and why it stopped early (``stopped``)."""

    def __init__(self, source: IO[bytes]) -> None:
        self.source = source
        self.damaged: list[Damage] = []
        self.stopped: Damage | None = None
        self.end = 0                                 # offset after the last record read whole

    def records(self) -> Iterator[object]:
        """Every complete record of the file (open at 0) in order, each chunk whole
        (decompressed and CRC-checked: its records as a list); a damaged chunk is noted
        and skipped; the first record that is incomplete or unreadable ends the scan."""
        reader = StreamReader(self.source, emit_chunks=True, validate_crcs=False)
        records = iter(reader.records)
        while True:
            start = self.source.tell()
            try:
                record = next(records)
            except StopIteration:                   # the footer and the closing magic read
                self.end = self.source.tell()
                return
            except _DAMAGED as error:
                self.stopped = Damage(start, _reason(error))
                return
            self.end = self.source.tell()
            if isinstance(record, Chunk):
                try:
                    record = breakup_chunk(record, validate_crc=True)
                except _DAMAGED as error:
                    self.damaged.append(Damage(start, _reason(error)))
                    continue
            yield record


def _reason(error: Exception) -> str:
    """What a reading error says, with its type (``EndOfFile`` says nothing)."""
    text = str(error)
    if isinstance(error, EndOfFile) or not text:
        return "incomplete record (the file ends inside it)"
    return f"{type(error).__name__}: {text}"


def recover_mcap(broken: str | Path, fixed: str | Path | None = None) -> Recovery:
    """Write to ``fixed`` (default :func:`default_recovered_path`) every complete chunk and
    message of the .mcap file ``broken``, with a rebuilt summary; return what was kept.

    ``UserInputError`` (one line naming the file) if ``broken`` is missing, empty, not an
    MCAP file, or ends before its header record; or if ``fixed`` is ``broken`` itself;
    :class:`NothingRecovered` (nothing written) if no message, metadata or attachment
    could be kept. The target is
    written beside itself and renamed into place, so it is never half written.
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
        footer = _ends_with_footer(source, size)
        scan = _Scan(source)
        records = scan.records()
        header = next(records, None)
        if not isinstance(header, Header):
            raise UserInputError(f"{broken} ends before its header record: nothing to recover")
        try:
            with partial.open("wb") as target:
                writer = Writer(target, compression=CompressionType.ZSTD)
                writer.start(profile=header.profile, library=header.library)
                copier = _Copier(writer)
                chunks = 0
                for record in records:
                    chunks += isinstance(record, list)
                    for inner in record if isinstance(record, list) else [record]:
                        copier.copy(inner)
                writer.finish()
                target.flush()
                os.fsync(target.fileno())
            if copier.messages == 0 and copier.attachments == 0:
                found = "; ".join(str(d) for d in scan.damaged + [scan.stopped] if d is not None)
                raise NothingRecovered(f"{broken}: no message recovered ({found or 'the file holds none'}); "
                                       "nothing written")
        except BaseException:
            partial.unlink(missing_ok=True)
            raise
    partial.replace(fixed)
    complete = footer and scan.stopped is None and not scan.damaged and scan.end == size
    return Recovery(broken, fixed, copier.messages, chunks, tuple(sorted(set(copier.topics.values()))),
                    copier.first, copier.last, size - scan.end, complete, tuple(scan.damaged), scan.stopped,
                    copier.orphans, footer)


def _ends_with_footer(source: IO[bytes], size: int) -> bool:
    """True if the file ends with the closing magic (a finished writer); rewinds to 0."""
    if size < 2 * len(MAGIC):
        return False
    source.seek(size - len(MAGIC))
    ended = source.read(len(MAGIC)) == MAGIC
    source.seek(0)
    return ended
