"""The ``dynamics_node``: a thin rclpy adapter around the sessions of
:mod:`youbot_dynamics.node` (:mod:`~youbot_dynamics.node.simulate`,
:mod:`~youbot_dynamics.node.inverse_session`): parameters in, messages out. Its topics,
services and parameters are the tables of :mod:`youbot_dynamics.node.interface` (and
docs/node.md); this module creates them.

Without tf2_msgs (see interfaces/) the node skips /tf and /tf_static with one warning (the
MCAP still logs them). Messages are published as CDR bytes and only on topics with
subscribers (the latched ones and /diagnostics always); the session builds only those and
the ones its MCAP records. Inverse mode takes the joint states received in each
``INVERSE_PERIOD`` (10 ms) tick as one batch. Parameters are checked (all or nothing) in the
on-set callback and applied in the post-set callback.

Names: the table's topics are the logged names; on the graph the node uses relative names
(:mod:`youbot_dynamics.node.topics`), so ``--ros-args -r __ns:=/youbot1`` publishes
/youbot1/joint_states, /youbot1/clock, ... and subscribes /youbot1/joint_commands; /tf,
/tf_static and /diagnostics stay global. Frames on /tf carry ``frame_prefix`` (by default the
namespace: ``youbot1/arm_link_1``), so two robots on one /tf never name the same frame; the
/diagnostics status carries the node's full name (``/youbot1/dynamics_node: ...``).

Bounded work per message: the subscriptions take the serialized message and refuse (count
as ``rejected.too_large``, without deserialising) one over its ``max_bytes`` in the table or
one announcing more joint names or trajectory points than the limits below
(:mod:`youbot_dynamics.node.input_size` reads the counts from the bytes); the session's checks are linear in the message and refuse more than
:data:`~youbot_dynamics.node.commands.MAX_NAMES` names or
:data:`~youbot_dynamics.node.commands.MAX_TRAJECTORY_POINTS` points. A watchdog times every
callback against ``callback_budget`` and reports overruns in /diagnostics (level WARN,
``overruns.<source>``, ``worst_callback_s``). Time semantics of stamps:
:mod:`youbot_dynamics.node.commands`; inverse mode gives unstamped samples the node clock's
receive time.

No input kills the node: every subscription, timer and service callback runs behind
:meth:`DynamicsNode._guarded`. Rejected input is counted (``rejected.<kind>``) and warned
about; any other exception is counted in /diagnostics under its cause (``failed.<source>:
<exception type>``), logged once per cause with the message that caused it, and the node
keeps its last good state and goes on publishing.

Timing (simulate): a steady-clock timer paces the samples (:mod:`youbot_dynamics.node.pacing`).
With ``wait_for_subscribers`` N > 0 it starts only once N subscribers have matched the sample
topic, /joint_states or, without a robot, /free_bodies (or after ``wait_timeout`` wall
seconds), so a subscriber started with the node misses none of the first samples. On
leaving, the node waits (up to :data:`~youbot_dynamics.ros.process.ACK_TIMEOUT`) until its
subscribers have acknowledged every message.

Run: ``ros2 run youbot_dynamics dynamics_node --ros-args --params-file config/dynamics_node.yaml``
or ``python -m youbot_dynamics.ros.dynamics_node --ros-args -p scene:=arm_swing``;
``--help`` prints the parameters (:mod:`youbot_dynamics.node.usage`, before rclpy is imported
when run as the ``dynamics_node`` executable). SIGINT and SIGTERM finalise the logs before the
process ends.

Start-up: configure (the session: scene loaded and compiled, logs opened; publishers,
subscriptions, services, timers), then activate (latched messages, then samples) and a
``ready:`` log line of what the node offers (:func:`~youbot_dynamics.node.interface.offered`).
A run whose ``duration`` exceeds 10 s logs every 10 % of simulated time
(:mod:`youbot_dynamics.node.progress`); /diagnostics carries ``progress``. ``--managed``
makes these steps lifecycle transitions (:class:`ManagedDynamicsNode`).
"""
from __future__ import annotations

import sys
import time
import traceback
from collections.abc import Callable

import rclpy
import rclpy.executors
from rclpy.clock import Clock, ClockType
from rclpy.event_handler import QoSRequestedIncompatibleQoSInfo, SubscriptionEventCallbacks
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.lifecycle import LifecycleNodeMixin, LifecycleState, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.publisher import Publisher
from rclpy.qos import qos_policy_name_from_kind
from rcl_interfaces.msg import SetParametersResult
from rclpy.serialization import deserialize_message
from rclpy.signals import SignalHandlerOptions
from geometry_msgs.msg import Twist
from sensor_msgs.msg import JointState
from std_srvs.srv import SetBool, Trigger
from trajectory_msgs.msg import JointTrajectory

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.stamps import NS_PER_S, stamp_ns_of
from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.configure import session_from_parameters
from youbot_dynamics.node import usage
from youbot_dynamics.node.input_size import check_serialized
from youbot_dynamics.node.interface import (SERVICES, Outputs, Topic, check_choice, instances, offered,
                                            topics_of)
from youbot_dynamics.node.inverse_session import InverseSession, receive_time_ns
from youbot_dynamics.node.pacing import Pacing, RealTimeFactor
from youbot_dynamics.node.progress import Progress
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.node.topics import graph_name
from youbot_dynamics.ros.actions import Controllers
from youbot_dynamics.ros.conversions import rclpy_class, to_cdr
from youbot_dynamics.ros.parameters import declare_all
from youbot_dynamics.ros.process import stop_requests, wait_for_acknowledgements
from youbot_dynamics.ros.qos import PROFILES, SUBSCRIPTION_PROFILES

NODE_NAME = "dynamics_node"
INVERSE_PERIOD = 0.01
"""Wall seconds between inverse-mode ticks: each takes the joint states received since the
last as one batch (:meth:`~youbot_dynamics.node.inverse_session.InverseSession.joint_states`)."""
WARN_THROTTLE = 2.0
"""Seconds between repeated warnings about bad input."""
QUOTED_CHARACTERS = 500
"""Characters of the message that made a callback fail quoted in the log."""


class DynamicsNode(Node):
    """The node, configured and active from the start; ``finished`` turns true once
    ``duration`` simulated seconds have run. (:class:`ManagedDynamicsNode` is the same node
    under lifecycle transitions.)"""

    def __init__(self, **node_options) -> None:
        super().__init__(NODE_NAME, **node_options)
        self._declare()
        self._configure()
        self._activate()

    # ---- lifecycle: declare, configure, activate, deactivate, clean up ---------------------
    def _declare(self) -> None:
        """Declare the parameters (a bad choice raises UserInputError) and their callbacks."""
        self.params = declare_all(self)
        self.session: SimulationSession | InverseSession | None = None
        self.publishers_: dict[str, Publisher] = {}
        self.finished, self.active = False, False
        self._failures_logged: set[str] = set()
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    def _configure(self) -> None:
        """Load and compile the scene and open its logs (the session), create the publishers,
        subscriptions, services and timers; nothing is published before :meth:`_activate`."""
        p = self.params
        self._before_configure = self._entities()
        self.session = session_from_parameters(p, self.get_namespace(), self.get_fully_qualified_name())
        self.progress = Progress(p["duration"])
        self._create_publishers()
        self._create_subscriptions_and_services()
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.controllers = None
        if p["mode"] == "simulate":
            self.pacing = Pacing(self.session.k)
            self.controllers = Controllers(self, self.session, p, self._subscribe)   # actions, <controller>/commands
            self.create_timer(1.0 / p["publish_rate"], self._guarded("step timer", self._on_tick), clock=steady)
        else:
            self._inbox: list[tuple] = []
            self.create_timer(INVERSE_PERIOD, self._guarded("joint states batch", self._on_joint_states),
                              clock=steady)
        self._real_time = RealTimeFactor(self.session.t)
        self.create_timer(p["diagnostics_period"], self._guarded("diagnostics timer", self._on_diagnostics),
                          clock=steady)
        scene = self.session.scene
        self.get_logger().info(f"{p['mode']} {scene.name} ({scene.source}); logs: "
                               f"{', '.join(map(str, self.session.recorder.paths)) or 'none'}")

    def _activate(self) -> None:
        """Start publishing: the latched messages, then samples (simulate mode: after
        ``wait_for_subscribers``); log the ready line."""
        self.active = True
        if self.params["mode"] == "simulate":
            self._wait_deadline = time.monotonic() + self.params["wait_timeout"]
            self._waiting = self.params["wait_for_subscribers"] > 0
            self._restart_pacing()
        self._real_time.mark(self.session.t)
        self._publish(self.session.latched)
        self.get_logger().info(self._ready_line())

    def _ready_line(self) -> str:
        """``ready: publishes ...; subscribes ...; services ...`` with the names as resolved
        on the graph, from the interface table (:func:`~youbot_dynamics.node.interface.offered`)."""
        parts = []
        controllers = set() if self.controllers is None else {
            group for group, joints in self.controllers.joints.items() if joints}   # their actions and commands
        for kind, names in offered(self.session.mode, self.session.features | controllers,
                                   self.session.topics).items():
            resolve = self.resolve_service_name if kind == "services" else self.resolve_topic_name
            resolved = [resolve(graph_name(name)) for name in names if name not in self._unpublished]
            parts.append(f"{kind} {', '.join(resolved) or 'none'}")
        return "ready: " + "; ".join(parts)

    def _deactivate(self) -> None:
        """Stop publishing: simulated time pauses (inverse mode drops what arrives) until
        :meth:`_activate`."""
        self.active = False
        self.get_logger().info(f"inactive at t = {self.session.t:.3f} s: paused")

    def _cleanup(self) -> None:
        """Finalise the logs and destroy what :meth:`_configure` created."""
        self.close()
        for server in self.controllers.servers if self.controllers else ():
            server.destroy()
        before = self._before_configure
        for kind, destroy in (("publishers", self.destroy_publisher), ("subscriptions", self.destroy_subscription),
                              ("services", self.destroy_service), ("timers", self.destroy_timer)):
            for entity in [e for e in getattr(self, kind) if id(e) not in before]:
                destroy(entity)
        self.publishers_, self.session = {}, None

    def _entities(self) -> set[int]:
        """Ids of the node's publishers, subscriptions, services and timers now."""
        return {id(entity) for kind in ("publishers", "subscriptions", "services", "timers")
                for entity in getattr(self, kind)}

    # ---- output ------------------------------------------------------------------------
    def _create_publishers(self) -> None:
        """A publisher per session topic (latched ones transient local; type and QoS from the
        interface table; the latched messages go out on activation). A topic whose message package is not
        installed (tf2_msgs without ``make``'s build) is left out, with one warning; it is
        still logged."""
        self._unpublished: set[str] = set()
        mode, features = self.session.mode, self.session.features
        for topic in (*topics_of(mode, "pub", features), *topics_of(mode, "pub", features, latched=True)):
            try:
                cls = rclpy_class(topic.type)
            except ImportError:
                self._unpublished.add(topic.name)
                continue
            for name in instances(topic, self.session.topics):  # the per-pair topics: one each
                self.publishers_[name] = self.create_publisher(cls, graph_name(name), PROFILES[topic.qos])
        if self._unpublished:
            self.get_logger().warning(f"not publishing {', '.join(sorted(self._unpublished))}: their message "
                                      "package is not installed (tf2_msgs: `make` builds it from interfaces/, "
                                      "or source a ROS 2 Jazzy); the MCAP still logs them")

    def _publish(self, outputs: Outputs, subscribed: frozenset[str] | None = None) -> None:
        """Publish as CDR bytes (serialized once, also for the MCAP); with ``subscribed``,
        only on those topics; nothing while inactive."""
        if not self.active:
            return
        for topic, message in outputs:
            if topic not in self._unpublished and (subscribed is None or topic in subscribed):
                self.publishers_[topic].publish(to_cdr(message))

    def _subscribed(self) -> frozenset[str]:
        """The topics with subscribers now; the session builds only those and the logged ones."""
        subscribed = frozenset(topic for topic, publisher in self.publishers_.items()
                               if publisher.get_subscription_count())
        self.session.consumed_by(subscribed)
        return subscribed

    def _create_subscriptions_and_services(self) -> None:
        """The subscriptions and services of the interface table for the session's mode and
        scene, each behind the node boundary (:meth:`_guarded`)."""
        callbacks = {"/joint_commands": self._on_command, "/joint_trajectory": self._on_trajectory,
                     "/cmd_vel": self._on_cmd_vel, "/joint_states": self._on_joint_state}
        for topic in topics_of(self.session.mode, "sub", self.session.features):
            options = {"event_callbacks": SubscriptionEventCallbacks(
                incompatible_qos=self._on_incompatible_joint_states)} if topic.name == "/joint_states" else {}
            self._subscribe(topic, callbacks[topic.name], **options)
        handlers = {"~/reset": self._on_reset, "~/pause": self._on_pause}
        for service in SERVICES:
            if self.session.mode in service.modes:
                self.create_service(rclpy_class(service.type), service.name,
                                    self._guarded(service.name, handlers[service.name]))

    def _restart_pacing(self) -> None:
        self.pacing.restart(self.session.k)

    def _subscribers_ready(self) -> bool:
        """False while simulated time waits for ``wait_for_subscribers`` subscribers on the
        sample topic; at the end of the wait the pacing and the diagnostics mark restart."""
        wanted, topic = self.params["wait_for_subscribers"], self.session.sample_topic
        count = self.publishers_[topic].get_subscription_count()
        if count < wanted:
            if time.monotonic() < self._wait_deadline:
                return False
            self.get_logger().warning(f"{count} of {wanted} {topic} subscribers after "
                                      f"{self.params['wait_timeout']:g} s; starting anyway")
        self._waiting = False
        self._restart_pacing()
        self._real_time.mark(self.session.t)
        return True

    def _on_tick(self) -> None:
        session, p = self.session, self.params
        if not self.active or self.finished or session.paused or session.failure or \
                (self._waiting and not self._subscribers_ready()):
            return
        due = self.pacing.due(session.k, p["publish_rate"] * p["time_scale"])     # samples per wall s
        subscribed = self._subscribed()
        for _ in range(due):
            self._publish(session.step(), subscribed)
            if session.failure:
                self.get_logger().error(session.failure)
                self.controllers.interrupt(None, f"Current goal cancelled: the simulation {session.failure}.")
                return
            self.controllers.on_sample()
            if p["duration"] and session.t >= p["duration"] - 1e-12:
                self._finish()
                return
            mark = self.progress.passed(session.t)
            if mark is not None:
                self.get_logger().info(f"progress: {mark} % ({session.t:.2f} of {p['duration']:g} s simulated)")

    def _finish(self) -> None:
        self._publish(self._diagnostics())
        self.session.close()
        self.finished = True
        self.get_logger().info(f"done: {self.session.t:g} s simulated")

    def _diagnostics(self) -> Outputs:
        """/diagnostics now (simulate mode with a ``duration``: ``progress`` in percent)."""
        if self.params["mode"] == "simulate":
            return self.session.diagnostics(self._real_time_factor(), progress=self.progress.percent(self.session.t))
        return self.session.diagnostics(self._real_time_factor())

    def _real_time_factor(self) -> float:
        """Simulated seconds per wall second since the last /diagnostics."""
        return self._real_time.since_last(self.session.t)

    def _on_diagnostics(self) -> None:
        if self.active and not self.finished:
            self._count_namesakes()
            self._publish(self._diagnostics())

    def _count_namesakes(self) -> None:
        """Count the other nodes with this node's full name (two launches of one name in one
        domain); warn in the log when their number changes (the status says it each time)."""
        me = (self.get_name(), self.get_namespace())
        namesakes = sum(node == me for node in self.get_node_names_and_namespaces()) - 1
        if namesakes > 0 and namesakes != self.session.namesakes:
            self.get_logger().warning(f"{namesakes} other node(s) named {self.get_fully_qualified_name()} "
                                      "on the graph: give each its own name or namespace")
        self.session.namesakes = max(namesakes, 0)

    # ---- the node boundary ---------------------------------------------------------------
    def _subscribe(self, topic: Topic, callback: Callable, **options) -> None:
        """Subscribe ``callback`` to ``topic`` (its graph name: relative, see
        :mod:`~youbot_dynamics.node.topics`; its QoS: the table's, or the profile of the
        parameter it names) behind the node boundary, taking the serialized message: one
        over ``topic.max_bytes``, or announcing more names or points than allowed
        (:func:`~youbot_dynamics.node.input_size.check_serialized`), is rejected (counted,
        ``too_large``) before it is deserialised."""
        limit, msg_type = topic.max_bytes, rclpy_class(topic.type)
        qos = SUBSCRIPTION_PROFILES[self.params[topic.qos]] if topic.qos in self.params else PROFILES[topic.qos]

        def decode(data: bytes) -> object:
            try:
                check_serialized(data, topic.type, limit)
            except InputRejected as error:
                self.session.counters.reject(error)
                raise
            return deserialize_message(data, msg_type)

        self.create_subscription(msg_type, graph_name(topic.name), self._guarded(topic.name, callback, decode), qos,
                                 raw=True, **options)

    def _guarded(self, source: str, callback: Callable, decode: Callable | None = None) -> Callable:
        """``callback`` (of a subscription, timer or service, named ``source``) behind the
        node boundary. :class:`InputRejected` (counted by the session) gives a throttled
        warning; any other exception is counted under its cause, logged once per cause with
        the message that caused it, and a service answers ``success: false``. Either way the
        node keeps its last good state and its timers go on. ``decode`` (a subscription's)
        turns the serialized message into the one ``callback`` takes. The watchdog times it."""

        def guarded(*args):
            start = time.perf_counter()
            try:
                if decode is not None:
                    args = (decode(args[0]),)
                return callback(*args)
            except InputRejected as error:
                self.get_logger().warning(f"{source}: ignored ({error}); keeping the last good state",
                                          throttle_duration_sec=WARN_THROTTLE)
            except Exception as error:   # noqa: BLE001 -- the boundary: nothing may stop the node
                self._failed(source, error, args[0] if args else None)
                if len(args) == 2:       # a service: (request, response)
                    args[1].success, args[1].message = False, f"{source} failed: {type(error).__name__}: {error}"
            finally:
                elapsed = time.perf_counter() - start
                if self.session.watchdog.record(source, elapsed):
                    self.get_logger().warning(f"{source} took {elapsed * 1e3:.1f} ms, over the "
                                              f"{self.session.watchdog.budget * 1e3:g} ms callback budget",
                                              throttle_duration_sec=WARN_THROTTLE)
            return args[1] if len(args) == 2 else None

        return guarded

    def _failed(self, source: str, error: Exception, message: object) -> None:
        """Count a callback's failure under its cause; log the first of each cause with
        where it was raised and the message (request) that caused it."""
        cause = self.session.counters.fail(source, error)
        if cause in self._failures_logged:
            return
        self._failures_logged.add(cause)
        frame = traceback.extract_tb(error.__traceback__)[-1]
        quoted = "" if message is None else f"; message: {str(message)[:QUOTED_CHARACTERS]}"
        self.get_logger().error(f"{cause}: {error} (at {frame.filename}:{frame.lineno}){quoted}; counted in "
                                f"/diagnostics as failed.{cause}, logged once; keeping the last good state")

    def _on_incompatible_joint_states(self, info: QoSRequestedIncompatibleQoSInfo) -> None:
        self.get_logger().warning(
            f"a /joint_states publisher offers a QoS incompatible with joint_states_qos "
            f"{self.params['joint_states_qos']} ({qos_policy_name_from_kind(info.last_policy_kind)}); none of its "
            "messages arrive: for a best-effort publisher set joint_states_qos:=best_effort")

    # ---- input -------------------------------------------------------------------------
    def _on_command(self, msg: JointState) -> None:
        before = self.session.counters.clamped
        self.session.effort_command(list(msg.name), msg.effort, stamp_ns_of(msg.header.stamp))
        if self.session.counters.clamped > before:
            self.get_logger().warning("/joint_commands: efforts beyond the URDF effort limits were clamped",
                                      throttle_duration_sec=WARN_THROTTLE)

    def _on_cmd_vel(self, msg: Twist) -> None:
        self.session.base_command((msg.linear.x, msg.linear.y, msg.linear.z),
                                  (msg.angular.x, msg.angular.y, msg.angular.z))

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        points = [(stamp_ns_of(point.time_from_start), point.positions, point.velocities) for point in msg.points]
        self.session.trajectory(list(msg.joint_names), points, stamp_ns_of(msg.header.stamp))

    def _on_joint_state(self, msg: JointState) -> None:
        if not self.active:
            return
        self._inbox.append((list(msg.name), msg.position, msg.velocity, stamp_ns_of(msg.header.stamp),
                            receive_time_ns()))

    def _on_joint_states(self) -> None:
        """The joint states received since the last tick, as one batch."""
        if not self._inbox:
            return
        samples, self._inbox = self._inbox, []
        subscribed = self._subscribed()
        outputs, rejected = self.session.joint_states(samples)
        self._publish(outputs, subscribed)
        for error in rejected:
            self.get_logger().warning(f"/joint_states: ignored ({error}); keeping the last good state",
                                      throttle_duration_sec=WARN_THROTTLE)

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self.session.reset()
        self.controllers.interrupt(None, "Current goal cancelled: the scene was reset (~/reset).")
        self._restart_pacing()
        self._publish(self._diagnostics())     # the reset, as an event
        response.success, response.message = True, (f"reset {self.session.scene.name}: its t = 0 is node time "
                                                     f"{self.session.epoch_ns / NS_PER_S:.6f} s")
        return response

    def _on_pause(self, request: SetBool.Request, response: SetBool.Response) -> SetBool.Response:
        self.session.paused = bool(request.data)
        self._restart_pacing()
        response.success, response.message = True, "paused" if request.data else "running"
        return response

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """On-set: accept or refuse a set of parameters as a whole, changing nothing (rclpy
        has checked ranges and read-only flags; this checks the string choices)."""
        for parameter in parameters:
            problem = check_choice(parameter.name, parameter.value)
            if problem:
                return SetParametersResult(successful=False, reason=problem)
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters: list[Parameter]) -> None:
        """Post-set: make an accepted set take effect (``params`` holds the values in force;
        the writable ones act in simulate mode only)."""
        self.params.update((parameter.name, parameter.value) for parameter in parameters)
        if self.params["mode"] != "simulate" or self.session is None:
            return
        if any(parameter.name == "time_scale" for parameter in parameters):
            self._restart_pacing()
        self.session.commands.timeout = float(self.params["command_timeout"])
        self.session.commands.on_timeout = self.params["on_timeout"]

    def close(self) -> None:
        """Take the joint states still waiting (inverse mode), finalise the logs (idempotent)."""
        if self.session is None:
            return
        if getattr(self, "_inbox", None):
            self._on_joint_states()
        self.session.close()
        paths = self.session.recorder.paths
        if paths:
            self.get_logger().info(f"logs closed: {', '.join(map(str, paths))}")


class ManagedDynamicsNode(LifecycleNodeMixin, DynamicsNode):
    """The node as a managed (lifecycle) node (``dynamics_node --managed``): it starts
    unconfigured with its parameters declared; configure loads and compiles the scene and
    opens the logs, activate starts publishing, deactivate pauses, cleanup closes the logs
    and destroys the topics, shutdown does the same from any state and ends the process.
    A scene that cannot be loaded fails the configure transition (the node stays
    unconfigured, the reason logged). ``finished`` also turns true once shut down."""

    def __init__(self, **node_options) -> None:
        Node.__init__(self, NODE_NAME, **node_options)
        LifecycleNodeMixin.__init__(self)
        self._declare()

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        try:
            self._configure()
        except UserInputError as error:
            self.get_logger().error(f"configure failed: {error}")
            self._cleanup()
            return TransitionCallbackReturn.FAILURE
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._activate()
        return TransitionCallbackReturn.SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._deactivate()
        return TransitionCallbackReturn.SUCCESS

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._cleanup()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.active = False
        if self.session is not None:
            self._cleanup()
        self.finished = True
        return TransitionCallbackReturn.SUCCESS


START_UP_ERRORS = (UserInputError, ParameterException, NameValidationException)
"""What a node refuses to start with (exit status 2, one line): a scene that cannot be read
or run, a log path that cannot be written (the session's UserInputError), a parameter of the
wrong type or out of range, an invalid name."""


def _start_up_error(reason: str) -> int:
    """Say why the node cannot start, on one line of stderr; returns the exit status 2."""
    print(f"dynamics_node: error: {' '.join(reason.split())}", file=sys.stderr)
    return 2


def run(args: list[str] | None = None, overrides: dict[str, object] | None = None,
        managed: bool = False) -> tuple[int, DynamicsNode | None]:
    """Run the node until ``duration`` is reached, SIGINT or SIGTERM (a managed node: or its
    shutdown transition), and finalise the logs.

    ``args`` are command-line arguments (``--ros-args ...``), ``overrides`` parameter values
    that beat them; ``managed``: a :class:`ManagedDynamicsNode`. Returns the exit status (2: a
    start-up error, said in one line on stderr: bad ROS arguments or parameters, a scene or log
    path that cannot be used) and the finished node.
    """
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as error:     # rclpy's RCLError, UnknownROSArgsError: bad --ros-args
        return _start_up_error(f"bad ROS arguments: {error}"), None
    stop = stop_requests()
    try:
        node = (ManagedDynamicsNode if managed else DynamicsNode)(
            parameter_overrides=[Parameter(k, value=v) for k, v in (overrides or {}).items()])
    except START_UP_ERRORS as error:
        rclpy.try_shutdown()
        return _start_up_error(str(error)), None
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    try:
        while not stop and not node.finished and rclpy.ok():
            executor.spin_once(timeout_sec=0.05)
    finally:
        node.close()
        if not wait_for_acknowledgements(node.publishers_.values()):
            node.get_logger().warning("some subscribers did not acknowledge the last messages")
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0, node


def main(args: list[str] | None = None) -> int:
    """``python -m youbot_dynamics.ros.dynamics_node``: the ``dynamics_node`` executable
    (:mod:`youbot_dynamics.ros.dynamics_main`), ``--help`` included."""
    return usage.main(args, lambda ros_args, managed: run(ros_args, managed=managed)[0])


if __name__ == "__main__":
    sys.exit(main())
