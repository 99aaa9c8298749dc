"""One .mcap file in rosbag2 form, written from rosbags typestore messages.

The file is what ``ros2 bag record -s mcap`` writes (Jazzy): profile ``ros2``; one schema
per type named ``pkg/msg/Type`` with encoding ``ros2msg`` (the root .msg text, then each
dependency after a line of 80 ``=`` and ``MSG: pkg/Type``); channels with message encoding
``cdr`` and metadata ``offered_qos_profiles`` (YAML, Jazzy style) and ``topic_type_hash``
(RIHS01); CDR from the rosbags serializer; log and publish times in nanoseconds; a summary
with statistics, chunk indexes and message indexes. A single .mcap file plays with
``ros2 bag play``. Written as ``mcap.writer.Writer`` writes it (byte for byte, through
:class:`~youbot_dynamics.io.mcap_writer.ChunkedWriter`, which appends a sample's messages
to the open chunk in one call) rather than with rosbags' rosbag2 Writer, which makes a
folder, cannot set publish time apart from log time, and omits ``topic_type_hash``.

Crash safety: messages are grouped in chunks, and a chunk stays in memory until it is
closed. ``McapLogger`` closes the open chunk (writes it with its message indexes, flushes
the stream and fsyncs the file) before a message that would make it span
``chunk_span_ns`` of log time (default 1 s) or that arrives ``chunk_wall_s`` wall seconds
(default 1 s) after the chunk's first message, whichever comes first; mcap's bound of
1 MiB per chunk also holds. A SIGKILL or a power cut therefore loses only the open chunk:
less than 1 s of log time. The bounds are checked when a message is written: a writer that
falls silent keeps its last chunk open until its next message (the node writes /diagnostics
every ``diagnostics_period``). Closing a chunk took 1.4 to 6 ms (500 Hz /joint_states and
/tf, fsync included). The truncated file lacks its summary and footer;
:func:`youbot_dynamics.io.mcap_recover.recover_mcap` (``youbot-dynamics log recover``)
rebuilds it.

Exclusive paths: the file is opened under an advisory lock
(:func:`~youbot_dynamics.io.log_file.open_exclusive`) before it is emptied; a second
writer on the same path is refused with ``LogPathInUse`` (one line naming the holder's
pid) and the first writer's log stays whole. The lock goes with the file's descriptor, so
with its process, ``kill -9`` included.

Write errors: the file is written unbuffered (:class:`~youbot_dynamics.io.log_file.FileSink`),
so a write that fails (ENOSPC, EIO, EROFS, EDQUOT; EFBIG past a file-size limit) is seen at
once with the bytes really written. Logging then stops: the file is cut after its last
complete chunk and finished there (summary and footer of the chunks kept; the last chunks
are given up if the summary needs their room), or, if even that fails, left cut after its
complete chunks for ``log recover``. ``McapLogger.failure`` then holds a
:class:`~youbot_dynamics.io.log_file.LogWriteFailed` (errno name and text, path, messages
and bytes in the file, messages lost, whether it is finalised), ``closed`` is True, later
``add_topic`` / ``write`` / ``write_all`` calls do nothing and ``close`` does not raise: the
caller's loop goes on.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

import yaml

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.cdr_template import Serialized
from youbot_dynamics.io.closing import ClosesOnExit
from youbot_dynamics.io.log_file import (FileSink, LogPathError, LogWriteFailed, describe_os_error, errno_name,
                                         open_exclusive)
from youbot_dynamics.io.mcap_writer import ChunkedWriter
from youbot_dynamics.io.messages import TYPESTORE
from youbot_dynamics.io.qos import DEFAULT, Qos

DEFAULT_CHUNK_SPAN_NS = 1_000_000_000
"""Log time (ns) one chunk may span at most: what a crash loses at most."""
DEFAULT_CHUNK_WALL_S = 1.0
"""Wall seconds a chunk stays open at most (for runs slower than real time)."""

_FINISH_ATTEMPTS = 3
"""Tries at finishing a file after a write error (each giving up the chunks that left no room)."""

_INFINITE_DURATION = {"sec": 9223372036, "nsec": 854775807}
"""RMW_DURATION_INFINITE as rosbag2 (Jazzy) writes an unset deadline, lifespan, lease."""


def offered_qos_yaml(qos: Qos) -> str:
    """The ``offered_qos_profiles`` YAML of a topic offered with ``qos``, as rosbag2 (Jazzy)
    writes it (one profile; deadline, lifespan and lease infinite, liveliness automatic)."""
    profile = {
        "history": qos.history,
        "depth": qos.depth,
        "reliability": qos.reliability,
        "durability": qos.durability,
        "deadline": dict(_INFINITE_DURATION),
        "lifespan": dict(_INFINITE_DURATION),
        "liveliness": "automatic",
        "liveliness_lease_duration": dict(_INFINITE_DURATION),
        "avoid_ros_namespace_conventions": False,
    }
    return yaml.safe_dump([profile], sort_keys=False, default_flow_style=False).strip()


def ros2msg_schema(msgtype: str) -> bytes:
    """The ``ros2msg`` schema text of ``msgtype`` (root definition, then dependencies)."""
    text, _ = TYPESTORE.generate_msgdef(msgtype, ros_version=2)
    return text.encode()


class McapLogger(ClosesOnExit):
    """Writes one rosbag2-form .mcap file; a context manager.

    Usage::

        with McapLogger("out/run.mcap") as log:
            log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
            log.add_topic("/tf_static", "tf2_msgs/msg/TFMessage",
                          qos=Qos("reliable", "transient_local", "keep_last", 1))
            log.write("/joint_states", messages.joint_state(...), log_time_ns=t_ns)

    Messages are rosbags typestore instances (see ``io.messages``); times are integer
    nanoseconds. ``close`` finalises the file (summary, statistics, footer) and may be
    called more than once; the ROS node calls it on shutdown and from its SIGINT, SIGTERM
    and SIGHUP handling. Chunks close on a time bound (see the module docstring).

    A write error never reaches the caller: logging stops and ``failure`` tells why and
    what the file holds (None while all is well)::

        if log.failure is not None:          # e.g. in a /diagnostics callback
            status = ERROR, str(log.failure), log.failure.key_values()
    """

    def __init__(self, path: str | Path, *, chunk_span_ns: int = DEFAULT_CHUNK_SPAN_NS,
                 chunk_wall_s: float = DEFAULT_CHUNK_WALL_S):
        """Create (or overwrite) ``path`` under its lock; the parent folder is created if
        missing. ``LogPathInUse`` if another writer holds ``path``, ``LogPathError`` if it
        cannot be written (both one-line ``UserInputError``).

        ``chunk_span_ns`` (log time, ns) and ``chunk_wall_s`` (wall s) bound how long a
        chunk stays open, so how much a crash can lose.
        """
        self.path = Path(path)
        if self.path.suffix != ".mcap":
            raise UserInputError(f"MCAP log path {self.path} must end in .mcap")
        self._stream: FileSink | None = FileSink(open_exclusive(self.path, "MCAP log"))
        self._writer = ChunkedWriter(self._stream)
        try:
            self._writer.start(profile="ros2", library="youbot_dynamics (mcap-python)")  # unbuffered: on disk at once
        except OSError as error:
            self._stream.close()
            raise LogPathError(f"MCAP log {self.path}: cannot write its header: {describe_os_error(error)}") from None
        self.failure: LogWriteFailed | None = None
        """Set when a write failed and logging stopped (see :meth:`stop_on_write_error`)."""
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, tuple[int, str]] = {}
        self.chunk_span_ns, self.chunk_wall_s = int(chunk_span_ns), float(chunk_wall_s)
        self._chunk: tuple[int, int, float] | None = None   # open chunk: first, last log time; wall start
        self.chunks_closed = 0   # by the time bound (mcap's 1 MiB size bound closes others on its own)

    @property
    def closed(self) -> bool:
        """True once the file is finalised, or once logging stopped on a write error
        (``failure``): no message is taken any more."""
        return self._stream is None

    @property
    def topics(self) -> dict[str, str]:
        """Message type of each added topic."""
        return {topic: msgtype for topic, (_, msgtype) in self._channels.items()}

    def add_topic(self, topic: str, msgtype: str, *, qos: Qos = DEFAULT) -> None:
        """Declare ``topic`` carrying ``msgtype`` (``pkg/msg/Type``), recorded as offered
        with ``qos`` (the publisher's profile: transient local for /tf_static). Adding a topic
        twice with the same type does nothing; with another type it is an error. After a
        write error (``failure`` set) it does nothing.
        """
        if self.failure is not None:
            return
        self._check_open()
        if topic in self._channels:
            if self._channels[topic][1] != msgtype:
                raise UserInputError(
                    f"{self.path}: topic {topic} already has type {self._channels[topic][1]},"
                    f" cannot add it as {msgtype}"
                )
            return
        if msgtype not in TYPESTORE.fielddefs:
            raise UserInputError(f"{self.path}: unknown message type {msgtype!r} for {topic}")
        if msgtype not in self._schemas:
            self._schemas[msgtype] = self._writer.register_schema(
                name=msgtype, encoding="ros2msg", data=ros2msg_schema(msgtype)
            )
        metadata = {
            "offered_qos_profiles": offered_qos_yaml(qos),
            "topic_type_hash": TYPESTORE.hash_rihs01(msgtype),
        }
        channel = self._writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=self._schemas[msgtype], metadata=metadata
        )
        self._channels[topic] = (channel, msgtype)

    def write(
        self,
        topic: str,
        message: object,
        log_time_ns: int,
        publish_time_ns: int | None = None,
    ) -> None:
        """Serialise ``message`` to CDR (a :class:`~youbot_dynamics.io.cdr_template.Serialized`
        one is already) and append it on ``topic``.

        ``log_time_ns`` is the receive (log) time, ``publish_time_ns`` the send time
        (defaults to the log time); both integer nanoseconds >= 0.
        """
        self.write_all([(topic, message)], log_time_ns, publish_time_ns)

    def write_all(self, messages: Sequence[tuple[str, object]], log_time_ns: int,
                  publish_time_ns: int | None = None) -> None:
        """``write`` of (topic, message) pairs that share their log and publish times (one
        sample's messages): the times and the chunk bound checked once. After a write error
        (``failure`` set) it does nothing."""
        if self.failure is not None:
            return
        self._check_open()
        publish_time_ns = log_time_ns if publish_time_ns is None else publish_time_ns
        for label, value in (("log time", log_time_ns), ("publish time", publish_time_ns)):
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**64:
                topics = ", ".join(topic for topic, _ in messages)
                raise UserInputError(f"{self.path}: {label} on {topics} must be integer ns >= 0, got {value!r}")
        records, channels = [], self._channels
        for topic, message in messages:
            known = channels.get(topic)
            if known is not None and type(message) is Serialized and message.__msgtype__ == known[1]:
                records.append((known[0], message.cdr))     # the bytes as they are (the common case)
            else:
                records.append(self._record(topic, message))
        if not records:
            return
        try:
            self._close_chunk_if_due(log_time_ns)
            self._writer.add_messages(records, log_time_ns, publish_time_ns)    # sequence numbers: 1, 2, ... per topic
        except OSError as error:
            self.stop_on_write_error(error)

    def _record(self, topic: str, message: object) -> tuple[int, bytes]:
        """(channel id, CDR bytes) of ``message`` on ``topic``; a topic not added or a message
        of another type is a UserInputError."""
        if topic not in self._channels:
            raise UserInputError(f"{self.path}: topic {topic} was not added before writing")
        channel, msgtype = self._channels[topic]
        if type(message) is Serialized and message.__msgtype__ == msgtype:
            return channel, message.cdr
        actual = getattr(message, "__msgtype__", type(message).__name__)
        if actual != msgtype:
            raise UserInputError(f"{self.path}: topic {topic} carries {msgtype}, got {actual}")
        return channel, bytes(TYPESTORE.serialize_cdr(message, msgtype))

    def _close_chunk_if_due(self, log_time_ns: int) -> None:
        """Close the open chunk if a message at ``log_time_ns`` would make it span
        ``chunk_span_ns`` of log time or if it opened ``chunk_wall_s`` wall seconds ago; then
        the message starts a new chunk. Log times may go back (a reset): the span counts
        from the chunk's earliest to its latest log time."""
        now = time.monotonic()
        if self._chunk is None:
            self._chunk = (log_time_ns, log_time_ns, now)
            return
        first, last, opened = self._chunk
        first, last = min(first, log_time_ns), max(last, log_time_ns)
        if last - first < self.chunk_span_ns and now - opened < self.chunk_wall_s:
            self._chunk = (first, last, opened)
            return
        self._writer.flush()          # writes the chunk and its message indexes
        self._stream.sync()
        self.chunks_closed += 1
        self._chunk = (log_time_ns, log_time_ns, now)

    def close(self) -> None:
        """Finalise the file (summary, statistics, footer) and release its lock; later calls
        do nothing. A write error on the way stops logging as in a write (``failure``);
        ``close`` itself does not raise it."""
        if self._stream is None:
            return
        try:
            self._writer.finish()
        except OSError as error:
            self.stop_on_write_error(error)
            return
        stream, self._stream = self._stream, None
        stream.close()

    def stop_on_write_error(self, error: OSError) -> LogWriteFailed:
        """Stop logging after the write error ``error`` (ENOSPC, EIO, EROFS, EDQUOT, EFBIG):
        keep the complete chunks, finish the file if there is room, release it, and record
        and return ``failure``.

        The file is cut after its last complete chunk and finished there (summary and
        footer of the chunks it keeps), so every reader takes it as it is. If the summary
        does not fit (the write fails again), the last chunks are given up one attempt at a
        time to make room (the file system said how far it got); if nothing fits or the
        file system refuses even that, the file is left cut after its complete chunks,
        which ``log recover`` rebuilds. Never raises ``OSError``.
        """
        stream, self._stream = self._stream, None
        writer = self._writer
        kept, finalised = writer.chunk_count, False
        for _ in range(_FINISH_ATTEMPTS):
            try:
                stream.truncate(writer.chunk_end(kept))
                stream.write(writer.tail_of(kept))
                stream.sync()
                finalised = True
                break
            except OSError:
                room = stream.offset        # what the file system took before refusing
                kept = next((k for k in range(kept - 1, -1, -1)      # cut + tail grows with k: the first fits
                             if writer.chunk_end(k) + len(writer.tail_of(k)) <= room), -1)
                if kept < 0:
                    break
        if not finalised:
            kept = writer.chunk_count
            try:
                stream.truncate(writer.chunk_end(kept))   # no half record at the end
            except OSError:
                pass
        messages = writer.chunk_messages(kept)
        self.failure = LogWriteFailed(
            path=self.path, kind="MCAP log", reason=describe_os_error(error), errno=errno_name(error),
            messages=messages, bytes=stream.offset, lost=writer.messages - messages, finalised=finalised)
        stream.close()
        return self.failure

    def _check_open(self) -> None:
        if self._stream is None:
            raise RuntimeError(f"{self.path}: MCAP log already closed")

