"""What both node sessions share, without rclpy: the simulate-mode session
(:mod:`youbot_dynamics.node.simulate`) steps the simulator, the inverse-mode session
(:mod:`youbot_dynamics.node.inverse_session`) computes torques from joint states; both build
the messages through ``io.messages`` and log them (:mod:`youbot_dynamics.node.recorder`: MCAP
in rosbag2 form, Rerun). The node only moves messages in and out.

Every output is a list of ``(topic, message)`` that the caller publishes (``session.topics``
names them, in the order of :data:`~youbot_dynamics.node.interface.TOPICS`), /tf (every
moving link and every free body) among them; everything published is also logged. A sample
carries the topics something consumes (``wanted``): those the node reports subscribed
(``consumed_by``; by default every topic) and those the MCAP records; the others are not
built. The first message of a topic is built by ``io.messages``; the next ones refill its
CDR bytes (:mod:`youbot_dynamics.io.cdr_template`: ``Serialized`` messages, which read like
the rosbags ones), and the MCAP and the node's publishers take those bytes. Topics are named
as logged, as in the root namespace (``/joint_states``); the node publishes them under their
graph names (:mod:`youbot_dynamics.node.topics`). Frame names carry ``frame_prefix``
(:mod:`youbot_dynamics.node.frame_messages`). One compiled kinematics pass per batch of
samples (:meth:`~youbot_dynamics.node.frames.LinkFrames.at_many`) gives /tf, /ee_pose,
/ee_poses and the Rerun samples, and none runs when nothing takes them; the messages of a
batch are refilled together (:class:`~youbot_dynamics.io.cdr_group.TopicBatches`). ``session.latched`` holds what is sent
once, latched (transient local), and logged at t = 0: /tf_static (every fixed link), with a
robot /robot_description (std_msgs/String: the URDF of what is simulated, the composed URDF
for a composed scene), named as robot_state_publisher names them, and /scene_markers with
static geometry. Stamps and log times are node time in integer nanoseconds, so two runs of a
scene log identical payloads.

A scene without a robot (``robot: none``) publishes neither /joint_states nor /ee_pose: it
has no joints and no end effector, and an empty or identity message would read as data.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from youbot_dynamics.io import messages
from youbot_dynamics.io.closing import ClosesOnExit
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.node.commands import InputCounters
from youbot_dynamics.node.frame_messages import FrameMessages
from youbot_dynamics.node.frames import frame_tree
from youbot_dynamics.node.interface import Outputs, published, topics_of
from youbot_dynamics.node.recorder import Recorder
from youbot_dynamics.node.watchdog import Watchdog
from youbot_dynamics.scene.schema import Scene

KINEMATIC_TOPICS = frozenset({"/tf", "/ee_pose", "/ee_poses"})
"""Topics that need the sample's kinematics pass."""


class Session(ClosesOnExit):
    """What both modes share: the robot's frames, the input counters, the logs (with
    ``latched``, the latched outputs, written once at t = 0; ``with`` finalises them) and
    the /diagnostics status. ``features`` are the scene's (keys of
    :data:`~youbot_dynamics.node.interface.FEATURES`), ``topics`` those published per sample,
    in order. Subclasses say their ``mode`` and keep ``stamp_ns``, the stamp (ns) of their
    latest output; ``moving_base`` says whether the scene's base moves; ``sensors`` adds the
    sensor features the scene has (``wrist_sensor``, ``contact_pairs``), ``pairs`` the contact
    pairs' (first, second) geometry names, one topic each."""

    mode: str
    stamp_ns: int
    failure: str | None = None
    """Why the session stopped publishing (None while it runs)."""
    namesakes: int = 0
    """Other nodes on the graph with this node's full name (the ROS side counts them):
    topics, services and parameter sets reach whichever answers."""

    def __init__(self, scene: Scene, robot: Robot, frame_id: str, ee_link: str,
                 mcap_path: str | Path | None, rrd_path: str | Path | None, callback_budget: float,
                 frame_prefix: str, node_name: str, moving_base: bool = False, moving_root: bool = False,
                 sensors: frozenset[str] = frozenset(), pairs: Sequence[tuple[str, str]] = ()) -> None:
        self.scene, self.robot, self.node_name = scene, robot, node_name
        self.counters = InputCounters()
        self.watchdog = Watchdog(callback_budget)
        geometries = [g for g in scene.geometries if self.mode == "simulate" or g.owner != "body"]
        self.frames = FrameMessages(robot, frame_id, ee_link, geometries, frame_prefix, moving_root)
        self.features = frozenset(feature for feature, present in (
            ("robot", self.frames.has_robot),
            ("several_robots", self.frames.has_robot and len(self.frames.links.ee_links) > 1),
            ("moving_base", moving_base), ("free_bodies", bool(self.frames.body_shapes)),
            ("static_geometry", bool(self.frames.static_geometry))) if present) | sensors
        self.topics = published(self.mode, self.features, pairs)
        latched = {"/tf_static": self.frames.tf_static, "/scene_markers": self.frames.scene_markers,
                   "/robot_description": lambda: messages.string(scene.urdf)}
        self.latched: Outputs = [(topic.name, latched[topic.name]())
                                 for topic in topics_of(self.mode, "pub", self.features, latched=True)]
        """Messages to publish once, latched (transient local), when the node starts."""
        self.recorder = Recorder(self.mode, scene, robot, (*self.topics, *(t for t, _ in self.latched)),
                                 mcap_path, rrd_path, frame_tree(robot.root_link, "", frame_id, moving_root))
        self.recorder.write(self.latched, 0)
        self.consumed_by(None)

    def consumed_by(self, subscribed: Iterable[str] | None) -> None:
        """Say which topics have subscribers (the node asks its publishers; None: every
        topic, the default): a sample builds the messages of ``wanted``, the topics
        subscribed or recorded in the MCAP, and no other."""
        self.wanted = frozenset(topic for topic in self.topics
                                if subscribed is None or topic in subscribed or self.recorder.records(topic))

    @property
    def kinematics_wanted(self) -> bool:
        """True if a sample needs its kinematics pass (a kinematic topic wanted, or the Rerun
        recording takes samples)."""
        return self.recorder.samples or not self.wanted.isdisjoint(KINEMATIC_TOPICS)

    def _diagnostic_outputs(self, level: str, text: str, values: dict) -> Outputs:
        """/diagnostics with one status of this session (also logged); with a robot, its
        values name the /ee_pose link (``ee_link``) and the /ee_poses links in order
        (``ee_links``, comma-separated). The watchdog's values are added; an OK status turns
        WARN when a callback overran its budget since the last report or when other nodes of
        the same full name are on the graph (``graph.namesakes``); any status turns ERROR
        when a log's write failed (a full disk, a file-size limit: the reason and what the file
        holds in ``log.mcap.*`` / ``log.rerun.*``), while the node goes on publishing."""
        if level == "OK" and self.namesakes:
            level, text = "WARN", (f"{self.namesakes} other node(s) named {self.node_name} on the graph: "
                                   "services and parameter sets reach whichever answers")
        if level == "OK" and self.watchdog.fresh:
            level, text = "WARN", f"a callback overran its {self.watchdog.budget:g} s budget"
        values = {**values, **self.watchdog.values(), "graph.namesakes": self.namesakes}
        for name, failure in self.recorder.failures.items():
            text = str(failure) if level != "ERROR" else f"{text}; {failure}"
            level, values = "ERROR", {**values, **failure.key_values(f"log.{name}")}
        if self.frames.has_robot:
            values = {"ee_link": self.frames.links.ee_link, "ee_links": ",".join(self.frames.links.ee_links),
                      **values}
        status = messages.diagnostic_status(f"{self.node_name}: {self.scene.name} ({self.mode})", level, text,
                                            hardware_id=self.robot.name, values=values)
        outputs = [("/diagnostics", messages.diagnostic_array(self.stamp_ns, [status]))]
        self.recorder.write(outputs, self.log_time_ns)
        return outputs

    @property
    def log_time_ns(self) -> int:
        """Log time (ns) of a message sent now: its stamp (the inverse session: its receive
        clock)."""
        return self.stamp_ns

    def close(self) -> None:
        """Finalise the logs (idempotent)."""
        self.recorder.close()
