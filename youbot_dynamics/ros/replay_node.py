"""The ``replay_node``: publishes a recorded bag's messages on their topics.

A bag is a single .mcap file or a rosbag2 folder with metadata.yaml (read by
:func:`youbot_dynamics.io.bag_reader.read_bag`). Messages go out in log-time order with the
recorded spacing scaled by ``time_scale`` (1.0: as recorded), or as fast as possible
(``time_scale`` 0). Paced topics are offered reliable, keep-last 1000; as fast as possible they are
offered reliable, keep-all, and a publish that finds the writer's history full (a reader
behind) is retried until the readers have made room, so a keep-all subscriber gets every
message however slow it is. Before leaving, the node waits until its subscribers have
acknowledged every message (up to ``ACK_TIMEOUT_FAST`` wall s as fast as possible,
:data:`~youbot_dynamics.ros.process.ACK_TIMEOUT` paced). Unless the bag has its own /clock,
the node drives /clock with each message's log time, so nodes with use_sim_time follow the
bag. Topics recorded latched (/tf_static) are offered transient-local. Types without an rclpy
message package (tf2_msgs with these wheels) are skipped with a warning.

Topic names: each recorded topic goes out under its graph name
(:func:`~youbot_dynamics.node.topics.graph_name`): relative to the node's namespace (the
recorded /joint_states as ``joint_states``), /tf, /tf_static and /diagnostics as they are. In
the root namespace every topic goes out as recorded; ``--ros-args -r __ns:=/youbot1`` replays
a dynamics node's bag under /youbot1. The ``topics`` and ``wait_for`` parameters take the
recorded names.

Run: ``ros2 run youbot_dynamics replay_node --ros-args -p bag:=out/run.mcap -p time_scale:=0.0``
or ``youbot-dynamics replay BAG [--time-scale X]`` (X is ``time_scale``, the dynamics node's parameter of that name; 0: as fast as possible).
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import rclpy
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterValueException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io import messages
from youbot_dynamics.io.bag_reader import bag_topics, paced, read_bag
from youbot_dynamics.node.topics import graph_name
from youbot_dynamics.ros.conversions import rclpy_class, to_rclpy
from youbot_dynamics.ros.process import ACK_TIMEOUT, stop_requests, wait_for_acknowledgements
from youbot_dynamics.ros.qos import RELIABLE_DEEP, profile

WAIT_FOR_TIMEOUT = 30.0
"""Longest wait (wall s) for a subscriber on ``wait_for`` before replaying anyway."""
BLOCK_TIMEOUT = 30.0
"""Longest time (wall s), as fast as possible, that one message may wait for room in the
writer's history (subscribers taking nothing) before the replay fails."""
ACK_TIMEOUT_FAST = 30.0
"""Longest wait (wall s), after replaying as fast as possible, for subscribers to acknowledge
every message (a keep-all reader acknowledges a sample once it has room for it)."""


class ReplayNode(Node):
    """Publishers for the topics of ``bag`` (all, or those named in ``topics``)."""

    def __init__(self, bag: str | Path = "", time_scale: float = 1.0, topics: Sequence[str] = (), wait_for: str = "",
                 **node_options) -> None:
        super().__init__("replay_node", **node_options)
        bag = self.declare_parameter("bag", str(bag), ParameterDescriptor(
            description="bag to replay: a .mcap file or a rosbag2 folder", read_only=True)).value
        self.time_scale = self.declare_parameter("time_scale", float(time_scale), ParameterDescriptor(
            description="playback speed (1.0: as recorded); 0: as fast as possible", read_only=True,
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1000.0)])).value
        wanted = self.declare_parameter("topics", list(topics) or [""], ParameterDescriptor(
            description="topics to replay (empty: all)", read_only=True)).value
        self.wait_for = self.declare_parameter("wait_for", wait_for, ParameterDescriptor(
            description=f"before replaying, wait up to {WAIT_FOR_TIMEOUT:g} s for a subscriber on this topic "
                        "('' : do not wait)",
            read_only=True)).value
        if not bag:
            raise UserInputError("replay_node: parameter bag is empty: give a .mcap file or a rosbag2 folder")
        self.bag = Path(bag)
        wanted = {topic for topic in wanted if topic}
        recorded = bag_topics(self.bag)
        missing = sorted(wanted - {topic.topic for topic in recorded})
        if missing:
            raise UserInputError(f"replay_node: bag {self.bag} has no topic {', '.join(missing)} "
                                 f"(it has {', '.join(sorted(t.topic for t in recorded)) or 'none'})")
        self.publishers_ = {}
        for topic in recorded:
            if wanted and topic.topic not in wanted:
                continue
            try:
                cls = rclpy_class(topic.msgtype)
            except (ImportError, AttributeError):
                self.get_logger().warning(f"{topic.topic}: no rclpy message {topic.msgtype} here; not replayed")
                continue
            self.publishers_[topic.topic] = self.create_publisher(
                cls, graph_name(topic.topic), profile(topic.latched, keep_all=self.time_scale == 0.0))
        self.clock = None if "/clock" in self.publishers_ else \
            self.create_publisher(Clock, graph_name("/clock"), RELIABLE_DEEP)
        if self.wait_for and self.wait_for not in self.publishers_:
            raise UserInputError(f"replay_node: wait_for {self.wait_for} is not a replayed topic of {self.bag} "
                                 f"(replayed: {', '.join(sorted(self.publishers_)) or 'none'})")

    def wait_for_subscribers(self, topic: str, count: int = 1, timeout: float = 10.0) -> bool:
        """Wait (wall s) until ``topic`` has ``count`` matched subscriptions."""
        deadline = time.monotonic() + timeout
        while self.publishers_[topic].get_subscription_count() < count:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def replay(self, keep_going: Callable[[], bool] = lambda: True) -> int:
        """Publish the bag's messages (paced by ``time_scale``); returns how many were published."""
        count = 0
        for item in paced(read_bag(self.bag), rate=self.time_scale or None):
            if not keep_going():
                break
            publisher = self.publishers_.get(item.topic)
            if publisher is None:
                continue
            if self.clock is not None:
                self.clock.publish(to_rclpy(messages.clock(item.log_time_ns)))
            if not self._publish(item.topic, publisher, to_rclpy(item.message), keep_going):
                break
            count += 1
        return count

    def _publish(self, topic: str, publisher, message: object, keep_going: Callable[[], bool]) -> bool:
        """Publish ``message``; as fast as possible, retry while the writer's history is full
        (each attempt blocks up to 100 ms in Fast DDS). False if ``keep_going`` turned false
        meanwhile; RuntimeError after :data:`BLOCK_TIMEOUT` s without room."""
        deadline = time.monotonic() + BLOCK_TIMEOUT
        while True:
            try:
                publisher.publish(message)
                return True
            except _rclpy.RCLError:
                if self.time_scale != 0.0:
                    raise
                if not keep_going():
                    return False
                if time.monotonic() > deadline:
                    raise RuntimeError(f"replay_node: {topic}: no room in the writer's history for "
                                       f"{BLOCK_TIMEOUT:g} s (a subscriber takes nothing)") from None

    @property
    def all_publishers(self) -> list:
        """The topic publishers and the /clock publisher (if the node drives /clock)."""
        return list(self.publishers_.values()) + ([self.clock] if self.clock is not None else [])


def replay_once(args: list[str] | None = None, **node_arguments) -> tuple[int, Path, list[str]]:
    """Start ROS 2, replay a bag once (SIGINT/SIGTERM stop it early), shut ROS 2 down.

    ``node_arguments`` go to :class:`ReplayNode` (bag, time_scale, topics, wait_for); ``args`` are
    ROS arguments (--ros-args -p bag:=...). Returns the number of messages published, the
    bag and the topics it went out on. UserInputError for a bag that cannot be read, a
    parameter out of range or a topic the bag does not have."""
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = stop_requests()
    try:
        try:
            node = ReplayNode(**node_arguments)
        except InvalidParameterValueException as error:
            raise UserInputError(f"replay_node: {error}") from None
        if node.wait_for and not node.wait_for_subscribers(node.wait_for, timeout=WAIT_FOR_TIMEOUT):
            node.get_logger().warning(f"no subscriber on {node.wait_for} after {WAIT_FOR_TIMEOUT:g} s; "
                                      "replaying anyway")
        count = node.replay(lambda: not stop)
        timeout = ACK_TIMEOUT_FAST if node.time_scale == 0.0 and not stop else ACK_TIMEOUT
        if not wait_for_acknowledgements(node.all_publishers, timeout):
            node.get_logger().warning(f"some subscribers did not acknowledge every message within {timeout:g} s")
        node.destroy_node()
        return count, node.bag, sorted(node.publishers_)
    finally:
        rclpy.try_shutdown()


def main(args: list[str] | None = None) -> int:
    """Replay the bag of parameter ``bag`` once."""
    try:
        count, bag, _ = replay_once(args)
    except UserInputError as error:
        print(f"replay_node: error: {error}", file=sys.stderr)
        return 2
    print(f"replay_node: replayed {count} messages from {bag}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
