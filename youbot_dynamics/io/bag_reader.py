"""Reading recorded bags for replay, and pacing their messages in time.

``read_bag`` opens a single .mcap file or a rosbag2 folder (with metadata.yaml, any storage
rosbags reads) through rosbags' AnyReader with the Jazzy typestore, and yields messages as
rosbags objects in log-time order. ``paced`` yields any time-stamped items with their
recorded spacing scaled by a rate, or as fast as possible; its clock and sleep are
injectable, so it is pure apart from them.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import NamedTuple, TypeVar

from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.interfaces import QosDurability
from rosbags.rosbag2 import ReaderError

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.messages import TYPESTORE
from youbot_dynamics.io.stamps import NS_PER_S

_BAG_ERRORS = (AnyReaderError, ReaderError, OSError, ValueError, KeyError)
"""What rosbags raises for a missing, truncated or malformed bag."""


class BagMessage(NamedTuple):
    """One recorded message: topic, type (``pkg/msg/Type``), log time (ns), rosbags object."""

    topic: str
    msgtype: str
    log_time_ns: int
    message: object


class BagTopic(NamedTuple):
    """One topic of a bag: name, type, message count, and whether it was offered latched
    (transient-local durability, as /tf_static), so a replay can offer it the same way."""

    topic: str
    msgtype: str
    message_count: int
    latched: bool


def _open(path: str | Path) -> AnyReader:
    """An opened AnyReader on ``path``; ``UserInputError`` naming the file if it cannot be."""
    path = Path(path)
    if not path.exists():
        raise UserInputError(f"bag {path}: no such file or folder")
    if path.is_dir() and not (path / "metadata.yaml").is_file():
        raise UserInputError(f"bag {path}: a bag folder needs a metadata.yaml")
    try:
        reader = AnyReader([path], default_typestore=TYPESTORE)  # a file neither .mcap nor .db3 fails here
        reader.open()
    except _BAG_ERRORS as error:
        raise UserInputError(f"bag {path}: cannot be read ({error})") from error
    return reader


def bag_topics(path: str | Path) -> list[BagTopic]:
    """The topics of the bag at ``path`` (a .mcap file or a rosbag2 folder)."""
    reader = _open(path)
    try:
        counts: dict[str, int] = {}
        types: dict[str, str] = {}
        latched: set[str] = set()
        for connection in reader.connections:
            counts[connection.topic] = counts.get(connection.topic, 0) + connection.msgcount
            types.setdefault(connection.topic, connection.msgtype)
            qos = getattr(connection.ext, "offered_qos_profiles", [])
            if any(profile.durability == QosDurability.TRANSIENT_LOCAL for profile in qos):
                latched.add(connection.topic)
        return [BagTopic(topic, types[topic], counts[topic], topic in latched) for topic in counts]
    finally:
        reader.close()


def read_bag(path: str | Path) -> Iterator[BagMessage]:
    """The messages of the bag at ``path`` in log-time order.

    ``path`` is a single .mcap file or a rosbag2 folder with metadata.yaml. A missing,
    truncated or malformed bag raises ``UserInputError`` naming the file and the reason;
    the file is checked before the first message is requested.
    """
    reader = _open(path)
    return _messages(reader, Path(path))


def _messages(reader: AnyReader, path: Path) -> Iterator[BagMessage]:
    try:
        for connection, log_time_ns, raw in reader.messages():
            try:
                message = reader.deserialize(raw, connection.msgtype)
            except _BAG_ERRORS as error:
                raise UserInputError(
                    f"bag {path}: message on {connection.topic} at {log_time_ns} ns"
                    f" cannot be decoded as {connection.msgtype} ({error})"
                ) from error
            yield BagMessage(connection.topic, connection.msgtype, log_time_ns, message)
    except _BAG_ERRORS as error:
        raise UserInputError(f"bag {path}: cannot be read ({error})") from error
    finally:
        reader.close()


Item = TypeVar("Item")


def paced(
    items: Iterable[Item],
    *,
    rate: float | None = 1.0,
    log_time_ns: Callable[[Item], int] = lambda item: item.log_time_ns,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
) -> Iterator[Item]:
    """Yield ``items`` with their recorded spacing, scaled by ``rate``.

    Item k is yielded no earlier than ``start + (t_k - t_0) / rate`` on ``clock`` (seconds),
    where ``t_k = log_time_ns(item_k)`` and ``start`` is the clock when the first item is
    yielded; ``rate`` 2.0 plays twice as fast as recorded. ``rate=None`` yields everything
    at once (as fast as possible). If the consumer falls behind, items are yielded without
    sleeping until it catches up; items recorded out of order are not delayed. A rate that
    is not positive and finite raises ``UserInputError`` at the call.
    """
    if rate is not None and not (math.isfinite(rate) and rate > 0.0):
        raise UserInputError(f"replay rate must be a positive finite number, got {rate}")
    if rate is None:
        return iter(items)
    return _paced(items, rate, log_time_ns, clock, sleep)


def _paced(
    items: Iterable[Item],
    rate: float,
    log_time_ns: Callable[[Item], int],
    clock: Callable[[], float],
    sleep: Callable[[float], None],
) -> Iterator[Item]:
    start_clock = start_ns = None
    for item in items:
        stamp_ns = log_time_ns(item)
        if start_ns is None:
            start_clock, start_ns = clock(), stamp_ns
        else:
            wait = start_clock + (stamp_ns - start_ns) / NS_PER_S / rate - clock()
            if wait > 0.0:
                sleep(wait)
        yield item
