"""An MCAP file written chunk by chunk, as ``mcap.writer.Writer`` writes it, with messages
appended in bulk.

The records, their order and their bytes are those of mcap's ``Writer`` with its defaults
(zstd chunks of at most 1 MiB uncompressed, message and chunk indexes, statistics, schemas
and channels repeated in the summary, summary offsets, CRCs of the chunks and the summary,
no data-section CRC): test_io_mcap writes the same calls through both and compares the
files byte for byte. What differs is the cost of a message: mcap builds a ``Message``
record object and writes each field through its own ``struct.pack`` call (about 12 us a
message); here a message is one packed header and its bytes appended to the open chunk
(about 1 us). Every record other than a message is written by mcap's own record classes.
"""
from __future__ import annotations

import struct
import zlib
from collections.abc import Sequence
from typing import IO

import numpy as np
import zstandard
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, DataEnd, Footer, Header, Schema, Statistics, SummaryOffset

MAGIC = b"\x89MCAP0\r\n"
"""The 8 bytes that open and close every MCAP file."""
CHUNK_SIZE = 1024 * 1024
"""Uncompressed bytes after which a chunk is closed (mcap's ``Writer`` default)."""

_MESSAGE = struct.Struct("<BQHIQQ")
"""A Message record's opcode, length and fixed fields: channel id, sequence, log time and
publish time (ns); the data follows."""
_MESSAGE_OPCODE = int(Opcode.MESSAGE)
"""A Message record's opcode (a plain int: packed without the enum's lookup)."""
_MESSAGE_FIXED = _MESSAGE.size - 9
"""Bytes of a Message record's fixed fields (its length counts them and the data)."""
_MESSAGE_INDEX = struct.Struct("<BQHI")
"""A MessageIndex record's opcode, length, channel id and byte length of its entries."""


class ChunkedWriter:
    """Writes one MCAP file to ``stream``: ``start``, ``register_schema``,
    ``register_channel``, ``add_messages`` (the messages of one log time), ``flush`` (close
    the open chunk and flush the stream) and ``finish`` (summary and footer), as mcap's
    ``Writer`` does.

    For a stream that failed mid-file: ``chunk_end(k)`` is where the data of the first
    ``k`` written chunks ends and ``tail_of(k)`` the bytes that finish a file cut there
    (summary of those chunks, footer, magic); ``chunk_messages(k)`` counts their messages."""

    def __init__(self, stream: IO[bytes], chunk_size: int = CHUNK_SIZE) -> None:
        self._stream, self.chunk_size = stream, chunk_size
        self._schemas: list[Schema] = []
        self._channels: list[Channel] = []
        self._chunk = bytearray()
        self._chunk_times: list[int] = []           # [earliest, latest] log time of the open chunk's messages
        self._chunk_index: dict[int, list[int]] = {}  # per channel: log time, offset, log time, offset, ...
        self._chunk_indexes: list[ChunkIndex] = []
        self._counts: dict[int, int] = {}             # messages per channel, in order of the first one
        self._times: list[int] = []                   # [earliest, latest] log time of every message
        self._chunk_counts: list[dict[int, int]] = []  # per written chunk: its messages per channel
        self._chunk_ends: list[int] = []               # per written chunk: offset after its message indexes
        self._data_start = 0                           # offset after the header record
        self.chunk_count = 0

    def start(self, profile: str, library: str) -> None:
        """The magic and the header record."""
        self._stream.write(MAGIC)
        self._write_record(Header(profile=profile, library=library))
        self._data_start = self._stream.tell()

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        """A schema (into the open chunk and the summary); returns its id (1, 2, ...)."""
        schema = Schema(id=len(self._schemas) + 1, name=name, encoding=encoding, data=data)
        self._schemas.append(schema)
        self._chunk_record(schema)
        return schema.id

    def register_channel(self, topic: str, message_encoding: str, schema_id: int,
                         metadata: dict[str, str] | None = None) -> int:
        """A channel (into the open chunk and the summary); returns its id (1, 2, ...)."""
        channel = Channel(id=len(self._channels) + 1, topic=topic, message_encoding=message_encoding,
                          schema_id=schema_id, metadata=metadata or {})
        self._channels.append(channel)
        self._chunk_record(channel)
        return channel.id

    def add_messages(self, messages: Sequence[tuple[int, bytes]], log_time: int, publish_time: int) -> None:
        """Messages (channel id, data) logged at ``log_time`` and published at
        ``publish_time`` (ns), in order, into the open chunk, each with its count on its
        channel as its sequence number (1, 2, ...); the chunk closes after a message that
        takes it past ``chunk_size`` bytes."""
        if not messages:
            return
        self._times = [min(self._times[0], log_time), max(self._times[1], log_time)] if self._times else \
            [log_time, log_time]
        if self._chunk_times:
            self._chunk_times = [min(self._chunk_times[0], log_time), max(self._chunk_times[1], log_time)]
        chunk, index, counts, header, limit = self._chunk, self._chunk_index, self._counts, _MESSAGE.pack, \
            self.chunk_size
        for channel, data in messages:
            if not self._chunk_times:             # the first message of a chunk
                self._chunk_times = [log_time, log_time]
            entries = index.get(channel)
            if entries is None:
                entries = index[channel] = []
            entries += (log_time, len(chunk))
            sequence = counts[channel] = counts.get(channel, 0) + 1
            chunk += header(_MESSAGE_OPCODE, _MESSAGE_FIXED + len(data), channel, sequence, log_time, publish_time)
            chunk += data
            if len(chunk) > limit:
                self._close_chunk()
                chunk, index = self._chunk, self._chunk_index

    def flush(self) -> None:
        """Close the open chunk (if it holds a message) and flush the stream."""
        self._close_chunk()
        self._stream.flush()

    def finish(self) -> None:
        """Close the open chunk, then the data end, the summary (schemas, channels,
        statistics, chunk indexes, empty attachment and metadata index groups, summary
        offsets), the footer and the closing magic. Does not close the stream."""
        self._close_chunk()
        self._stream.write(self._tail(self._stream.tell(), self._chunk_indexes, self._counts, self._times))

    @property
    def messages(self) -> int:
        """Messages added so far (written or in the open chunk)."""
        return sum(self._counts.values())

    def chunk_end(self, chunks: int) -> int:
        """Offset after the first ``chunks`` written chunks and their message indexes (after
        the header for 0): where a file keeping only them ends its data section."""
        return self._chunk_ends[chunks - 1] if chunks else self._data_start

    def chunk_messages(self, chunks: int) -> int:
        """Messages in the first ``chunks`` written chunks."""
        return sum(sum(counts.values()) for counts in self._chunk_counts[:chunks])

    def tail_of(self, chunks: int) -> bytes:
        """The bytes that finish a file cut at ``chunk_end(chunks)``: data end, summary
        (every schema and channel; statistics and chunk indexes of those chunks only),
        footer and magic, as ``finish`` writes them. For a writer whose stream failed: the
        file, cut there, becomes complete without the chunks after it."""
        indexes = self._chunk_indexes[:chunks]
        counts: dict[int, int] = {}          # in order of each channel's first message, as add_messages counts
        for chunk_counts in self._chunk_counts[:chunks]:
            for channel, count in chunk_counts.items():
                counts[channel] = counts.get(channel, 0) + count
        times = [min(i.message_start_time for i in indexes), max(i.message_end_time for i in indexes)] \
            if indexes else []
        return self._tail(self.chunk_end(chunks), indexes, counts, times)

    def _tail(self, data_end: int, chunk_indexes: list[ChunkIndex], counts: dict[int, int],
              times: list[int]) -> bytes:
        """Data end, summary, footer and magic for a data section ending at ``data_end``
        with ``chunk_indexes``, ``counts`` messages per channel and ``times`` [earliest,
        latest] log time."""
        data_end_record = _record_bytes(DataEnd(data_section_crc=0))
        summary_start = data_end + len(data_end_record)
        summary = RecordBuilder()
        statistics = Statistics(
            message_count=sum(counts.values()), schema_count=len(self._schemas),
            channel_count=len(self._channels), attachment_count=0, metadata_count=0, chunk_count=len(chunk_indexes),
            message_start_time=times[0] if times else 0,
            message_end_time=times[1] if times else 0, channel_message_counts=counts)
        groups = ((Opcode.SCHEMA, self._schemas), (Opcode.CHANNEL, self._channels), (Opcode.STATISTICS, [statistics]),
                  (Opcode.CHUNK_INDEX, chunk_indexes), (Opcode.ATTACHMENT_INDEX, []),
                  (Opcode.METADATA_INDEX, []))
        offsets = []
        for opcode, records in groups:
            group_start = summary.count
            for record in records:
                record.write(summary)
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=summary_start + group_start,
                                         group_length=summary.count - group_start))
        summary_offset_start = summary_start + summary.count
        for offset in offsets:
            offset.write(summary)
        data = summary.end()
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 8 + 8 + 4, summary_start, summary_offset_start),
                         zlib.crc32(data))
        footer = _record_bytes(Footer(summary_start=summary_start, summary_offset_start=summary_offset_start,
                                      summary_crc=crc))
        return data_end_record + data + footer + MAGIC

    def _chunk_record(self, record: Schema | Channel) -> None:
        """A schema or channel record into the open chunk (closed past ``chunk_size``)."""
        builder = RecordBuilder()
        record.write(builder)
        self._chunk += builder.end()
        if len(self._chunk) > self.chunk_size:
            self._close_chunk()

    def _write_record(self, record: object) -> None:
        self._stream.write(_record_bytes(record))

    def _close_chunk(self) -> None:
        """Write the open chunk (zstd) and its message indexes, and index it; nothing if it
        holds no message (its schema and channel records then stay for the next chunk)."""
        if not self._chunk_index:
            return
        data = bytes(self._chunk)
        compressed = zstandard.compress(data)
        start, end = self._chunk_times
        chunk = Chunk(compression="zstd", data=compressed, message_start_time=start, message_end_time=end,
                      uncompressed_crc=zlib.crc32(data), uncompressed_size=len(data))
        chunk_start = self._stream.tell()
        self._write_record(chunk)
        index_start = self._stream.tell()
        offsets, records = {}, bytearray()
        for channel, entries in self._chunk_index.items():
            offsets[channel] = index_start + len(records)
            records += _MESSAGE_INDEX.pack(Opcode.MESSAGE_INDEX, 2 + 4 + 8 * len(entries), channel, 8 * len(entries))
            records += np.array(entries, dtype="<u8").tobytes()
        self._stream.write(records)
        self._chunk_indexes.append(ChunkIndex(
            message_start_time=start, message_end_time=end, chunk_start_offset=chunk_start,
            chunk_length=index_start - chunk_start, message_index_offsets=offsets, message_index_length=len(records),
            compression="zstd", compressed_size=len(compressed), uncompressed_size=len(data)))
        self.chunk_count += 1
        self._chunk_counts.append({channel: len(entries) // 2 for channel, entries in self._chunk_index.items()})
        self._chunk_ends.append(self._stream.tell())
        self._chunk, self._chunk_times, self._chunk_index = bytearray(), [], {}


def _record_bytes(record: object) -> bytes:
    """The bytes of one mcap record (opcode, length, fields)."""
    builder = RecordBuilder()
    record.write(builder)
    return builder.end()
