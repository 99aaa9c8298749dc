"""Helpers for tests with real ROS 2 traffic: isolated contexts, spinning, collecting.

Isolation: ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST (set here, inherited by subprocesses)
and a domain id per test from :func:`domain_id`, distinct across pytest-xdist workers.
"""
from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"

import rclpy  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import Executor, MultiThreadedExecutor, SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402

from youbot_dynamics.ros.conversions import from_rclpy, rclpy_class  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402

WAIT = 30.0
"""Generous upper bound (s) on any wait for discovery or messages."""
SPIN_PERIOD = 0.05
"""Longest wait (s) of one spin_once in :func:`spinning`: how late a stop is noticed."""


def interrupt(*processes: subprocess.Popen, timeout: float = 2 * WAIT) -> None:
    """SIGINT to each process still running, then wait for them (a hang guard: what has
    not ended after ``timeout`` s is killed, and its return code says so)."""
    for process in processes:
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
    for process in processes:
        try:
            process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def domain_id(test_offset: int) -> int:
    """A domain id for test number ``test_offset`` (0..29) on this xdist worker (ids 110..229).

    ``YBD_TEST_DOMAIN_SLOT`` (0..6) overrides the worker's slot, so that two test runs on one
    machine (each with one worker) stay apart."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    index = int(os.environ.get("YBD_TEST_DOMAIN_SLOT", index))
    base = 110 + (index % 4) * 30 if index < 4 else 10 + (index - 4) % 3 * 30   # slots 4..6: ids 10..99
    return base + test_offset % 30


@contextmanager
def ros_context(test_offset: int) -> Iterator[tuple[Context, int]]:
    """An initialised rclpy context in its own domain; shut down afterwards."""
    domain = domain_id(test_offset)
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    try:
        yield context, domain
    finally:
        context.try_shutdown()


@contextmanager
def spinning(context: Context, *nodes: Node, single_threaded: bool = False) -> Iterator[Executor]:
    """Spin ``nodes`` in a daemon thread while the block runs; destroy them afterwards.

    ``single_threaded``: a SingleThreadedExecutor, as the node processes use. (rclpy's
    MultiThreadedExecutor took only about 5 of a subscription's queued messages per second
    here once the publisher had stopped: use it for many messages in a burst. It also
    starves a node's subscriptions while a timer of the same mutually exclusive callback
    group is always due, as the step timer at time_scale 0 is: a /joint_commands message was
    not handled within 20 s in 2 of 3 tries, against 31-88 ms single-threaded. Spin a node
    that must hear input single-threaded.)"""
    executor = (SingleThreadedExecutor if single_threaded else MultiThreadedExecutor)(context=context)
    for node in nodes:
        executor.add_node(node)
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set() and context.ok():
            executor.spin_once(timeout_sec=SPIN_PERIOD)

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    try:
        yield executor
    finally:
        # Stop taking callbacks and let those under way finish before shutdown() destroys the
        # executor's guard condition: rclpy's shutdown does not wait for them (it tests its
        # shutdown flag after setting it), and a callback starting then raised InvalidHandle
        # in its Task, printed "exception was never retrieved" whenever that Task was
        # collected, into a later test's captured stderr.
        stop.set()
        thread.join(timeout=WAIT)
        for task in list(getattr(executor, "_futures", ())):   # MultiThreadedExecutor's pool
            wait_until(task.done, what="a callback under way")
        executor.shutdown()
        for node in nodes:
            node.destroy_node()


def wait_until(predicate: Callable[[], bool], timeout: float = WAIT, what: str = "condition") -> None:
    """Poll ``predicate`` until true; AssertionError naming ``what`` after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.01)


class Collector(Node):
    """Subscribes to topics and keeps every message as a rosbags object, in arrival order."""

    def __init__(self, context: Context, topics: dict[str, str], name: str = "collector", namespace: str = "/") -> None:
        super().__init__(name, context=context, namespace=namespace)
        self.received: dict[str, list] = {topic: [] for topic in topics}
        self._lock = threading.Lock()
        for topic, msgtype in topics.items():
            self.create_subscription(rclpy_class(msgtype), topic,
                                     lambda msg, topic=topic: self._keep(topic, msg), RELIABLE_DEEP)

    def _keep(self, topic: str, msg: object) -> None:
        with self._lock:
            self.received[topic].append(from_rclpy(msg))

    def messages(self, topic: str) -> list:
        with self._lock:
            return list(self.received[topic])

    def count(self, topic: str) -> int:
        with self._lock:
            return len(self.received[topic])


def stamp_ns(message: object) -> int:
    """Header stamp of a rosbags message (ns)."""
    stamp = message.header.stamp
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def diagnostic_values(array: object) -> dict[str, str]:
    """Key/values of the first status of a DiagnosticArray."""
    return {kv.key: kv.value for kv in array.status[0].values}
