"""What both node processes do around their work: note SIGINT / SIGTERM / SIGHUP instead of
dying mid-write, and, before leaving, wait until subscribers have acknowledged what was published
(a reliable publisher's queue is lost when the process ends)."""
from __future__ import annotations

import signal
import time
from collections.abc import Iterable

from rclpy.duration import Duration
from rclpy.publisher import Publisher

ACK_TIMEOUT = 3.0
"""Longest wait (wall s), on leaving, for subscribers to acknowledge what was published."""


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
"""Signals that stop a node cleanly: Ctrl-C, ``kill``, and closing its terminal (SIGHUP)."""


def stop_requests() -> list[int]:
    """Handle SIGINT, SIGTERM and SIGHUP by appending the signal number to the returned list
    (the caller's loop ends when it is non-empty), so logs are finalised and queues drained."""
    requests: list[int] = []
    for signum in STOP_SIGNALS:
        signal.signal(signum, lambda number, frame: requests.append(number))
    return requests


def wait_for_acknowledgements(publishers: Iterable[Publisher], timeout: float = ACK_TIMEOUT) -> bool:
    """Wait (at most ``timeout`` wall s in all) until every subscriber of ``publishers`` has
    acknowledged every message published; False if one has not."""
    deadline = time.monotonic() + timeout
    acknowledged = True
    for publisher in publishers:
        left = Duration(nanoseconds=max(0, round((deadline - time.monotonic()) * 1e9)))
        acknowledged = publisher.wait_for_all_acked(left) and acknowledged
    return acknowledged
