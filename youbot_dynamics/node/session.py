"""What the dynamics node does, without rclpy: step the simulator (simulate mode) or compute
torques from joint states (inverse mode), build the messages through ``io.messages`` and log
them through ``io`` (MCAP in rosbag2 form, Rerun). The node only moves messages in and out.

Every output is a list of ``(topic, message)`` that the caller publishes (``session.topics``
names them), /tf (every moving link and every free body) among them; everything published is
also logged. A sample carries the topics something consumes (``wanted``): those the node
reports subscribed (``consumed_by``; by default every topic) and those the MCAP records; the
others are not built. The first message of a topic is built by ``io.messages``; the next
ones refill its CDR bytes (:mod:`youbot_dynamics.io.cdr_template`: ``Serialized`` messages,
which read like the rosbags ones), and the MCAP and the node's publishers take those bytes.
Topics are named as logged, as in the root namespace (``/joint_states``); the node publishes
them under their graph names (:mod:`youbot_dynamics.node.topics`). Frame names carry
``frame_prefix`` (see ``_Frames``). One kinematics pass per sample
(:meth:`~youbot_dynamics.node.frames.LinkFrames.at`) gives /tf, /ee_pose, /ee_poses and the
Rerun sample, and none runs when nothing takes them. ``session.latched`` holds what is sent
once, latched (transient local), and logged at t = 0: /tf_static (every fixed link) and,
with a robot, /robot_description (std_msgs/String: the URDF of what is simulated, the
composed URDF for a composed scene), named as robot_state_publisher names them. Stamps and
log times are simulated time in integer nanoseconds, so two runs of a scene log identical
payloads.

Shapes for viewers (visualization_msgs/MarkerArray, namespace = the shape's name):
/free_bodies_markers draws every free body at every sample (in the root frame);
/scene_markers, latched (transient local, published once at start and logged at t = 0),
draws the static world geometry (root frame) and the geometry on links (in the link's
frame, frame-locked). A halfspace is drawn as a plate (``io.drawn_shapes.drawn_shape``).

Free bodies (simulate mode) appear like the robot's links: on /tf as ``<root frame> ->
<body name>`` and in the Rerun recording as their shapes; on ROS, as one
geometry_msgs/PoseArray on /free_bodies per sample (poses in the root frame, in the
scene's order of ``free_bodies``; the names, in that order, are the ``free_bodies`` value
of /diagnostics). One message per sample keeps every body at the same stamp, and the topic
set does not depend on body names (which need not be valid topic names). A scene without
a robot (``robot: none``) publishes neither /joint_states nor /ee_pose: it has no joints
and no end effector, and an empty or identity message would read as data.

End effectors: /ee_pose is the pose of the ``ee_link`` parameter's link, by default the
robot's end effector (the youBot's gripper palm). A scene of several robots composed into
one model (``robot: {compose: [...]}``) has one end effector per robot
(``Robot.end_effectors``): /ee_pose is then the first robot's (unless ``ee_link`` names
another link) and /ee_poses, a geometry_msgs/PoseArray, carries every robot's in
composition order (the link names, in that order, are the ``ee_links`` value of
/diagnostics), all in the root frame.

Simulate mode advances simulated time by fixed increments: sample k is at exactly
``k * round(1e9 / publish_rate)`` ns, whatever the wall clock does. ``reset`` restarts the
scene but not the clock: the samples after a reset continue from the last stamp (the
scene's t = 0 is then at ``epoch_ns``), so /clock, every header stamp and the log times of
the MCAP and the Rerun recording stay monotonic in one run and no stamp repeats. The reset
is recorded as an event: /diagnostics (also logged) carries ``resets`` and
``last_reset_at`` (node time, s). Time semantics of the inputs: :mod:`youbot_dynamics.node.commands`.
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from youbot_dynamics.dynamics.collision import Geometry
from youbot_dynamics.dynamics.mobile.mecanum import mecanum_base_from_robot
from youbot_dynamics.dynamics.rigid_body import kinetic_energy, potential_energy
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import DivergenceError, checked_output_spacing
from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_template import Refilled
from youbot_dynamics.io.closing import ClosesOnExit
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.io.rerun_log import RerunLogger
from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.model.lie import matrix_from_quaternion
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.node.commands import (DEFAULT_EFFORT_LIMIT, STAMP_LIMIT_NS, EffortCommands,
                                           InputCounters, InputRejected, JointSample, follow,
                                           joint_sample, joint_trajectory, node_time_of_stamp)
from youbot_dynamics.node.frames import LinkFrames, LinkTransform, SampleFrames, pose_rows
from youbot_dynamics.node.inverse import (DEFAULT_MAX_GAP_NS, PLAUSIBLE_FACTOR,
                                          AccelerationEstimator, InverseDynamics,
                                          implausible_joints, plausible_limit)
from youbot_dynamics.node.mobile_base import MobileBase, WheelOdometry
from youbot_dynamics.node.mobile_base import TOPICS as MOBILE_BASE_TOPICS
from youbot_dynamics.scene.schema import Scene
from youbot_dynamics.sim.simulator import Simulator, Snapshot

Outputs = list[tuple[str, object]]

TOPIC_TYPES = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/computed_torques": "sensor_msgs/msg/JointState",
    "/ee_pose": "geometry_msgs/msg/PoseStamped",
    "/ee_poses": "geometry_msgs/msg/PoseArray",
    "/free_bodies": "geometry_msgs/msg/PoseArray",
    "/free_bodies_markers": "visualization_msgs/msg/MarkerArray",
    "/scene_markers": "visualization_msgs/msg/MarkerArray",
    "/clock": "rosgraph_msgs/msg/Clock",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/robot_description": "std_msgs/msg/String",
    "/odom": "nav_msgs/msg/Odometry",
    "/base_pose_ground_truth": "nav_msgs/msg/Odometry",
}
"""Every topic the node publishes and logs, with its type (tf2_msgs has no PyPI wheel:
``make`` builds it from interfaces/; without it the node publishes neither /tf nor /tf_static
but still logs them)."""

KINEMATIC_TOPICS = frozenset({"/tf", "/ee_pose", "/ee_poses"})
"""Topics that need the sample's kinematics pass."""
LATCHED_TOPICS = frozenset({"/tf_static", "/robot_description", "/scene_markers"})
"""Topics sent once and latched (transient local, depth 1), in the MCAP too."""


def robot_description(scene: Scene) -> str:
    """The URDF XML of the scene's robot: its file's text, or the composed robot's text."""
    return scene.urdf

FREE_BODY_RGBA = (0.80, 0.60, 0.35, 1.0)
"""Colour (r, g, b, a in 0..1) of the free bodies' markers (light wood)."""
GEOMETRY_RGBA = (0.55, 0.55, 0.60, 1.0)
"""Colour of the scene's static and link geometry markers (grey)."""


def urdf_file(scene: Scene, robot: Robot, rrd_path: Path) -> Path | None:
    """The URDF file of the scene's robot for Rerun: None without a robot; the scene's file;
    or, for a composed robot (no file of its own), its URDF text written next to the
    recording as ``<rrd name>.urdf``."""
    if not robot.tree:
        return None
    if scene.urdf_path is not None:
        return scene.urdf_path
    path = rrd_path.with_suffix(".urdf")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(scene.urdf, encoding="utf-8")
    return path


class Recorder:
    """The logs of one node run: an MCAP (``mcap_path``) of ``topics`` (those in
    :data:`LATCHED_TOPICS` offered latched), and a Rerun recording (``rrd_path``) of the
    robot, the scene's static geometry and (simulate mode) its free bodies; either may be
    None. ``close`` finalises both and may be called more than once."""

    def __init__(self, mode: str, scene: Scene, robot: Robot, topics: Sequence[str],
                 mcap_path: str | Path | None, rrd_path: str | Path | None, root_frame: str) -> None:
        self.mcap = McapLogger(mcap_path) if mcap_path else None
        if self.mcap is not None:
            for topic in topics:
                self.mcap.add_topic(topic, TOPIC_TYPES[topic], latched=topic in LATCHED_TOPICS)
        self.rerun = RerunLogger(
            rrd_path, urdf_file(scene, robot, Path(rrd_path)), recording_name=f"{scene.name} ({mode})",
            geometries=[g for g in scene.geometries if mode == "simulate" or g.owner != "body"],
            world_frame=root_frame) if rrd_path else None

    @property
    def paths(self) -> list[Path]:
        """The log files being written."""
        return [log.path for log in (self.mcap, self.rerun) if log is not None]

    def write(self, outputs: Outputs, stamp_ns: int) -> None:
        """Log messages at ``stamp_ns`` (log and publish time)."""
        if self.mcap is not None and not self.mcap.closed:
            self.mcap.write_all(outputs, stamp_ns)

    def sample(self, stamp_ns: int, names: Sequence[str], q: np.ndarray, v: np.ndarray, tau: np.ndarray,
               energy: float, ee_position: np.ndarray) -> None:
        """One Rerun sample at simulated time ``stamp_ns`` (ns)."""
        if self.rerun is not None and not self.rerun.closed:
            self.rerun.log_sample(stamp_ns, names, q, v, tau, energy, ee_position)

    def bodies(self, stamp_ns: int, rows: np.ndarray) -> None:
        """The free bodies' poses (rows of translation (m) and quaternion (x, y, z, w), root
        frame, in the scene's order, as the recording's ``bodies``) in the Rerun recording
        at ``stamp_ns`` (ns)."""
        if self.rerun is not None and not self.rerun.closed:
            self.rerun.log_body_rows(stamp_ns, rows)

    def records(self, topic: str) -> bool:
        """True if the MCAP log records ``topic`` (so its messages must be built)."""
        return self.mcap is not None and not self.mcap.closed and topic in self.mcap.topics

    @property
    def samples(self) -> bool:
        """True if the Rerun recording takes samples (joint values, energy, end effector)."""
        return self.rerun is not None and not self.rerun.closed

    def close(self) -> None:
        """Finalise both logs (idempotent)."""
        for log in (self.mcap, self.rerun):
            if log is not None:
                log.close()


def _pose_matrix(pose: object) -> np.ndarray:
    """A geometry_msgs/Pose as a 4x4 homogeneous matrix (m)."""
    matrix = np.eye(4)
    matrix[:3, :3] = matrix_from_quaternion(np.array([pose.orientation.x, pose.orientation.y, pose.orientation.z,
                                                      pose.orientation.w]))
    matrix[:3, 3] = pose.position.x, pose.position.y, pose.position.z
    return matrix


def marker_stamped(path: str) -> bool:
    """The stamps of a MarkerArray that carry the sample's time: each marker's header (not
    its empty texture's, stamped 0)."""
    return path.endswith("header.stamp") and ".texture." not in path


class _Frames:
    """/tf, /tf_static and /ee_pose messages of a robot in ``root_frame``, /tf, /free_bodies
    and /free_bodies_markers messages of the free bodies among ``geometries`` (frame names
    distinct from the robot's links) and the /scene_markers of the others.

    Frame names: every frame the node names itself (the robot's links, the free bodies, the
    default root frame) carries ``prefix`` (robot_state_publisher's ``frame_prefix``: two
    robots on one /tf keep their frames apart); a ``root_frame`` given is used as it is."""

    def __init__(self, robot: Robot, root_frame: str, ee_link: str | None,
                 geometries: Sequence[Geometry] = (), prefix: str = "", moving_root: bool = False) -> None:
        self.links = LinkFrames(robot, ee_link or None)
        self.prefix, self.moving_root = prefix, moving_root
        self.root_frame = root_frame or prefix + robot.root_link
        self.has_robot = bool(robot.tree)
        self.body_shapes = {g.name: (g.shape, g.placement) for g in geometries if g.owner == "body"}
        self.static_geometry = tuple(g for g in geometries if g.owner != "body")
        clash = sorted(set(self.body_shapes) & {root_frame or robot.root_link, *robot.link_names})
        if clash:
            raise UserInputError(f"free bodies {clash} have the names of robot frames; /tf needs distinct "
                                 "frame names: rename the bodies in the scene")
        self._marker_poses = {name: [_pose_matrix(marker.pose) for marker in
                                     messages.shape_markers(0, "", name, shape, placement, FREE_BODY_RGBA)]
                              for name, (shape, placement) in self.body_shapes.items()}
        """Each body's markers' poses (4x4, m) in the body's frame."""
        self._refilled = {topic: Refilled() for topic in ("/tf", "/free_bodies", "/ee_pose", "/ee_poses")}
        self._refilled["/free_bodies_markers"] = Refilled(lambda path: ".pose." in path, marker_stamped)

    def _transform(self, stamp_ns: int, transform: LinkTransform, parent: str | None = None) -> object:
        """``transform`` as a TransformStamped, its frames prefixed (the parent: ``parent``
        if given)."""
        return messages.transform_stamped(stamp_ns, parent or self.prefix + transform.parent,
                                          self.prefix + transform.child, transform.translation,
                                          transform.quaternion_xyzw)

    def tf_static(self) -> object:
        """/tf_static: every fixed link, and root frame -> URDF root link if they differ."""
        transforms = [self._transform(0, t) for t in self.links.static]
        root_link = self.prefix + self.links.root_link
        if self.root_frame != root_link and not self.moving_root:  # a moving base's is on /tf
            transforms.insert(0, messages.transform_stamped(0, self.root_frame, root_link,
                                                            (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
        return messages.tf_message(transforms)

    def body_poses(self, samples: Sequence[dict[str, np.ndarray]]) -> np.ndarray:
        """(N, k, 7) rows of translation (m) and quaternion (x, y, z, w) of the free bodies in
        the root frame, in the scene's order, from their world poses (4x4, m) in N samples."""
        return pose_rows([pose for poses in samples for pose in poses.values()]).reshape(len(samples), -1, 7)

    def tf(self, stamps: Sequence[int], samples: Sequence[SampleFrames] | None,
           bodies: Sequence[np.ndarray] | None = None, base: object | None = None) -> list[object]:
        """/tf of N samples (``stamps`` ns): ``base`` (one sample's moving base odom ->
        base_footprint TransformStamped), the moving links of each sample's kinematics (none
        without a robot), then the free bodies (rows of :meth:`body_poses`)."""
        blocks = [] if base is None else [np.tile(_transform_row(base).reshape(-1), (len(stamps), 1))]
        if samples is not None:
            blocks.append(np.array([sample.link_poses.reshape(-1) for sample in samples]))
        if bodies is not None and len(self.body_shapes):
            blocks.append(np.reshape(bodies, (len(stamps), -1)))
        values = np.hstack(blocks) if blocks else np.zeros((len(stamps), 0))

        def build(stamp_ns: int, values: np.ndarray) -> object:
            edges = [] if base is None else [None]
            edges += [(self.prefix + parent, self.prefix + child) for parent, child in samples[0].edges] \
                if samples is not None else []
            edges += [(self.root_frame, self.prefix + name) for name in self.body_shapes]
            return messages.tf_message(
                base if edge is None else messages.transform_stamped(stamp_ns, *edge, row[:3], row[3:])
                for edge, row in zip(edges, values.reshape(-1, 7)))

        return self._refilled["/tf"].many(stamps, values, build)

    def free_bodies(self, stamps: Sequence[int], bodies: Sequence[np.ndarray]) -> list[object]:
        """/free_bodies of N samples: the bodies' poses in the root frame, in order."""
        return self._refilled["/free_bodies"].many(
            stamps, np.reshape(bodies, (len(stamps), -1)), lambda stamp_ns, values: messages.pose_array(
                stamp_ns, self.root_frame, [(row[:3], row[3:]) for row in values.reshape(-1, 7)]))

    def free_body_markers(self, stamps: Sequence[int], poses: Sequence[dict[str, np.ndarray]]) -> list[object]:
        """/free_bodies_markers of N samples: each body's shape at its world pose (4x4, m;
        ``poses`` by name) in the root frame (namespace: the body's name; the same ids every
        sample, so each replaces the last)."""
        values = pose_rows([sample[name] @ local for sample in poses for name, locals_ in self._marker_poses.items()
                            for local in locals_]).reshape(len(poses), -1)

        def build(stamp_ns: int, values: np.ndarray) -> object:
            return messages.marker_array(
                marker for name, (shape, placement) in self.body_shapes.items()
                for marker in messages.shape_markers(stamp_ns, self.root_frame, name, shape,
                                                     poses[0][name] @ placement, FREE_BODY_RGBA))

        return self._refilled["/free_bodies_markers"].many(stamps, values, build)

    def scene_markers(self) -> object:
        """/scene_markers (latched, stamp 0): the static world geometry in the root frame and
        the geometry on links in the link's frame (frame-locked: it moves with the link);
        namespace: the geometry's name."""
        return messages.marker_array(
            marker for g in self.static_geometry
            for marker in messages.shape_markers(0, self._geometry_frame(g), g.name, g.shape, g.placement,
                                                 GEOMETRY_RGBA, frame_locked=g.owner == "link"))

    def _geometry_frame(self, geometry: Geometry) -> str:
        """The frame static geometry is placed in: the root frame, or its link's frame."""
        return self.root_frame if geometry.owner == "world" else self.prefix + geometry.owner_name

    @property
    def scene_topics(self) -> tuple[str, ...]:
        """/scene_markers if there is static geometry."""
        return ("/scene_markers",) if self.static_geometry else ()

    @property
    def ee_topics(self) -> tuple[str, ...]:
        """/ee_pose, and /ee_poses for a model of several robots."""
        return ("/ee_pose", "/ee_poses") if len(self.links.ee_links) > 1 else ("/ee_pose",)

    def ee_outputs(self, stamps: Sequence[int], samples: Sequence[SampleFrames],
                   wanted: frozenset[str] | None = None) -> list[Outputs]:
        """/ee_pose (and /ee_poses, see ``ee_topics``) of N samples' kinematics; only those
        in ``wanted`` if given."""
        topics: list[tuple[str, list[object]]] = []
        if wanted is None or "/ee_pose" in wanted:
            topics.append(("/ee_pose", self._refilled["/ee_pose"].many(
                stamps, np.array([sample.ee[sample.ee_index] for sample in samples]),
                lambda stamp_ns, row: messages.pose_stamped(stamp_ns, self.root_frame, row[:3], row[3:]))))
        if len(self.links.ee_links) > 1 and (wanted is None or "/ee_poses" in wanted):
            topics.append(("/ee_poses", self._refilled["/ee_poses"].many(
                stamps, np.array([sample.ee[:sample.ee_count].reshape(-1) for sample in samples]),
                lambda stamp_ns, values: messages.pose_array(stamp_ns, self.root_frame,
                                                             [(row[:3], row[3:]) for row in values.reshape(-1, 7)]))))
        return [[(topic, built[k]) for topic, built in topics] for k in range(len(stamps))]


def _transform_row(transform: object) -> np.ndarray:
    """Translation (m) and quaternion (x, y, z, w) of a TransformStamped, as one row."""
    t, r = transform.transform.translation, transform.transform.rotation
    return np.array([[t.x, t.y, t.z, r.x, r.y, r.z, r.w]])


NOT_REPORTED = "n/a"
"""The value (diagnostics) or text (printed summaries) of a figure that is not known."""


def reported(value: float | int | str | None) -> float | int | str:
    """``value``, or ``NOT_REPORTED`` when it is None (a counter the integrator does not
    report) or a non-finite float (a rate over no wall time yet)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return NOT_REPORTED
    return value


class Watchdog:
    """Callback budgets: ``record(source, seconds)`` counts a callback (a step tick, a
    message, a service; named ``source``) that took longer than ``budget`` wall seconds.
    Measured when the callback returns (the node has one executor thread, so a running
    callback is not interrupted); ``values`` are /diagnostics values (``overruns``,
    ``overruns.<source>``, ``worst_callback_s``, ``worst_callback``) and ``fresh`` tells
    whether an overrun came since the last report."""

    def __init__(self, budget: float) -> None:
        if not (math.isfinite(budget) and budget > 0.0):
            raise ValueError(f"callback budget must be positive and finite, got {budget}")
        self.budget = float(budget)
        self.overruns: dict[str, int] = {}
        self.worst: tuple[float, str] = (0.0, "none")
        self.fresh = False

    def record(self, source: str, seconds: float) -> bool:
        """Note that ``source`` took ``seconds``; True if that overran the budget."""
        if seconds > self.worst[0]:
            self.worst = (seconds, source)
        if seconds <= self.budget:
            return False
        self.overruns[source] = self.overruns.get(source, 0) + 1
        self.fresh = True
        return True

    def values(self) -> dict[str, object]:
        """/diagnostics values; clears ``fresh``."""
        self.fresh = False
        return {"callback_budget_s": self.budget, "overruns": sum(self.overruns.values()),
                **{f"overruns.{source}": count for source, count in self.overruns.items()},
                "worst_callback_s": self.worst[0], "worst_callback": self.worst[1]}


class _Session(ClosesOnExit):
    """What both modes share: the robot's frames, the input counters, the logs (with
    ``latched``, the latched outputs, written once at t = 0; ``with`` finalises them) and
    the /diagnostics status. Subclasses say their ``mode`` and ``topics`` (published, in
    order) and keep ``stamp_ns``, the stamp (ns) of their latest output."""

    mode: str
    stamp_ns: int
    topics: tuple[str, ...]
    moving_base: MobileBase | None = None

    def __init__(self, scene: Scene, robot: Robot, frame_id: str, ee_link: str,
                 mcap_path: str | Path | None, rrd_path: str | Path | None, callback_budget: float,
                 frame_prefix: str, node_name: str) -> None:
        self.scene, self.robot, self.node_name = scene, robot, node_name
        self.counters = InputCounters()
        self.watchdog = Watchdog(callback_budget)
        geometries = [g for g in scene.geometries if self.mode == "simulate" or g.owner != "body"]
        self.frames = _Frames(robot, frame_id, ee_link, geometries, frame_prefix, self.moving_base is not None)
        self.latched: Outputs = [("/tf_static", self.frames.tf_static())]
        """Messages to publish once, latched (transient local), when the node starts."""
        if self.frames.has_robot:
            self.latched.append(("/robot_description", messages.string(robot_description(scene))))
        if self.frames.static_geometry:
            self.latched.append(("/scene_markers", self.frames.scene_markers()))
        self.recorder = Recorder(self.mode, scene, robot, (*self.topics, *(t for t, _ in self.latched)),
                                 mcap_path, rrd_path, frame_id or robot.root_link)
        self.recorder.write(self.latched, 0)
        self.consumed_by(None)

    def consumed_by(self, subscribed: Iterable[str] | None) -> None:
        """Say which topics have subscribers (the node asks its publishers; None: every
        topic, the default): a sample builds the messages of ``wanted``, the topics
        subscribed or recorded in the MCAP, and no other."""
        self.wanted = frozenset(topic for topic in self.topics
                                if subscribed is None or topic in subscribed or self.recorder.records(topic))

    def _diagnostic_outputs(self, level: str, text: str, values: dict) -> Outputs:
        """/diagnostics with one status of this session (also logged); with a robot, its
        values name the /ee_pose link (``ee_link``) and the /ee_poses links in order
        (``ee_links``, comma-separated). The watchdog's values are added; an OK status turns
        WARN when a callback overran its budget since the last report."""
        if level == "OK" and self.watchdog.fresh:
            level, text = "WARN", f"a callback overran its {self.watchdog.budget:g} s budget"
        values = {**values, **self.watchdog.values()}
        if self.frames.has_robot:
            values = {"ee_link": self.frames.links.ee_link, "ee_links": ",".join(self.frames.links.ee_links),
                      **values}
        status = messages.diagnostic_status(f"{self.node_name}: {self.scene.name} ({self.mode})", level, text,
                                            hardware_id=self.robot.name, values=values)
        outputs = [("/diagnostics", messages.diagnostic_array(self.stamp_ns, [status]))]
        self.recorder.write(outputs, self.stamp_ns)
        return outputs

    def close(self) -> None:
        """Finalise the logs (idempotent)."""
        self.recorder.close()


class SimulationSession(_Session):
    """A scene simulated step by step at ``publish_rate`` (Hz) samples per simulated second
    (the same scene, rate and ``samples_per_solve`` give the same samples, bit for bit).

    Inputs: ``effort_command`` (sensor_msgs/JointState fields), ``trajectory``
    (trajectory_msgs/JointTrajectory fields), ``reset``, ``paused``. Each ``step`` advances
    simulated time by one increment and returns the messages to publish. A divergence pauses
    the session (``failure`` says why); it never yields non-finite output.
    """

    mode = "simulate"

    @property
    def topics(self) -> tuple[str, ...]:
        """/clock, /joint_states and /ee_pose (and /ee_poses for several robots) if the scene
        has a robot, /free_bodies and /free_bodies_markers if it has free bodies, /tf,
        /diagnostics (the latched topics are in ``latched``)."""
        robot = ("/joint_states", *self.frames.ee_topics) if self.robot.tree else ()
        bodies = ("/free_bodies", "/free_bodies_markers") if self.frames.body_shapes else ()
        base = MOBILE_BASE_TOPICS if self.moving_base is not None else ()
        return ("/clock", *robot, *base, *bodies, "/tf", "/diagnostics")

    @property
    def sample_topic(self) -> str:
        """The topic that carries every sample of the motion: /joint_states, or /free_bodies in
        a scene without a robot (/clock if it has neither)."""
        return next(topic for topic in ("/joint_states", "/free_bodies", "/clock") if topic in self.topics)

    def __init__(self, scene: Scene, publish_rate: float, *, command_timeout: float = 0.5,
                 on_timeout: str = "hold", samples_per_solve: int = 5, frame_id: str = "", ee_link: str = "",
                 mcap_path: str | Path | None = None, rrd_path: str | Path | None = None,
                 default_effort_limit: float = DEFAULT_EFFORT_LIMIT, callback_budget: float = 0.05,
                 frame_prefix: str = "", node_name: str = "dynamics_node") -> None:
        self.simulator = Simulator(scene, scene.pinned_integrator())
        if self.simulator.model.base is not None:
            self.moving_base = MobileBase(self.simulator.model.base, InputCounters(), command_timeout, frame_prefix)
            frame_id = frame_id or self.moving_base.odometry.odom_frame
        super().__init__(scene, self.simulator.robot, frame_id, ee_link, mcap_path, rrd_path, callback_budget,
                         frame_prefix, node_name)
        if self.moving_base is not None:
            self.moving_base.counters = self.counters
        self.step_ns = max(1, round(NS_PER_S / publish_rate))
        checked_output_spacing(self.simulator.integrator.dt, np.array([0.0, self.step_ns / NS_PER_S]),
                               f"{scene.source}: integrator.dt (publish_rate {publish_rate:g} Hz)")
        self.samples_per_solve = max(1, int(samples_per_solve))
        self.commands = EffortCommands(self.robot, command_timeout, on_timeout, self.counters, default_effort_limit)
        self.locked_names = tuple(j.name for j in self.robot.tree if j.name in self.robot.locked)
        self._joint_states = Refilled()
        self._locked_q = np.array([self.robot.locked[name] for name in self.locked_names])
        self.paused = False
        self.failure: str | None = None
        self.k, self.epoch_ns, self.resets, self.last_reset_ns, self._started = 0, 0, 0, None, False
        self.reset()

    @property
    def t(self) -> float:
        """Node time (s): simulated time since the start, resets included."""
        return self.stamp_ns / NS_PER_S

    @property
    def stamp_ns(self) -> int:
        """Stamp (ns) of the current sample (node time)."""
        return self.epoch_ns + self.k * self.step_ns

    @property
    def scene_time(self) -> float:
        """Simulated time (s) of the current sample since the scene's last (re)start."""
        return self.k * self.step_ns / NS_PER_S

    def reset(self) -> None:
        """Back to the scene's initial state (the next ``step`` gives that sample, one
        increment after the last one published: node time goes on, see the module
        docstring); forgets commands and trajectories."""
        if self._started:
            self.epoch_ns = self.last_reset_ns = self.stamp_ns + self.step_ns
            self.resets += 1
        self.simulator.reset()
        self.commands.clear()
        if self.moving_base is not None:
            self.moving_base.reset()
        self.k, self.failure, self.wall_time, self._pending, self._prebuilt = 0, None, 0.0, [], []
        self.snapshot = self.simulator.snapshot()
        self.energy0, self.energy_error = self.snapshot.energy, 0.0
        self._started = False

    def effort_command(self, names: Sequence[str], efforts: Sequence[float], stamp_ns: int,
                       wall_ns: int | None = None) -> None:
        """Accept an effort command (raises and counts :class:`InputRejected`); ``wall_ns``:
        the wall clock (default: the machine's), for wall-clock stamps."""
        self.commands.accept(names, efforts, stamp_ns, self.t, wall_ns)

    def base_command(self, linear: Sequence[float], angular: Sequence[float]) -> None:
        """Accept a /cmd_vel twist (raises and counts :class:`InputRejected`; a scene without
        a moving base rejects it as ``no_controller``)."""
        if self.moving_base is None:
            error = InputRejected("no_controller", f"/cmd_vel: scene {self.scene.name!r} has a fixed base")
            self.counters.reject(error)
            raise error
        self.moving_base.accept(linear, angular, self.t)

    def trajectory(self, names: Sequence[str], points: Sequence[tuple[int, Sequence[float], Sequence[float]]],
                   stamp_ns: int, wall_ns: int | None = None) -> None:
        """Follow a joint trajectory from its stamp (node time, see
        :func:`~youbot_dynamics.node.commands.node_time_of_stamp`: unstamped or a past stamp
        within the command timeout: now; a wall-clock stamp: by its age; far future or older:
        rejected); ``points`` are (time_from_start (int ns), positions, velocities)."""
        try:
            start_ns = max(node_time_of_stamp(stamp_ns, self.stamp_ns, round(self.commands.timeout * NS_PER_S),
                                              "trajectory", wall_ns), self.stamp_ns)
            follow(self.simulator, joint_trajectory(self.robot, names, points, start_ns - self.epoch_ns,
                                                               self.simulator.q))
        except InputRejected as error:
            self.counters.reject(error)
            raise
        self.counters.accepted += 1
        self.commands.clear()

    def step(self) -> Outputs:
        """The sample at t = 0 first, then advance one increment per call; returns the
        messages to publish (none when paused or failed).

        The simulator runs ``samples_per_solve`` increments per integrator call and the
        samples are handed out one per step, so a command or trajectory takes effect at the
        next such block (a latency of at most ``samples_per_solve`` increments)."""
        if self.paused or self.failure is not None:
            return []
        if not self._started:
            self._started = True
            return self._outputs(self.snapshot)
        if not self._pending:
            times = (self.k + 1 + np.arange(self.samples_per_solve)) * self.step_ns / NS_PER_S
            if self.moving_base is not None:
                state = self.simulator.state
                state.reference = dataclasses.replace(state.reference, base_twist=self.moving_base.twist(self.t))
            start = time.perf_counter()
            try:
                self._pending = self.simulator.advance_through(times, self.commands.torque(self.t))[::-1]
            except DivergenceError as error:
                self.failure = f"diverged after t = {self.t:.6f} s: {error}"
                return []
            finally:
                self.wall_time += time.perf_counter() - start
            self._prebuilt = self._block(self._pending[::-1])
        self.k += 1
        prebuilt = self._prebuilt.pop() if self._prebuilt else None
        return self._outputs(self._pending.pop(), prebuilt if prebuilt is not None and prebuilt[0] == self.wanted
                             else None)

    def _block(self, snapshots: list[Snapshot]) -> list[tuple]:
        """The messages of the next samples (``snapshots``, in time order) built at once, in
        pop order, each with the ``wanted`` they were built for; none with a moving base
        (its odometry advances sample by sample) or when a message would be invalid (then
        each is built at its own step, so that the failure falls on its sample)."""
        if self.moving_base is not None:
            return []
        stamps = [self.epoch_ns + (self.k + 1 + j) * self.step_ns for j in range(len(snapshots))]
        try:
            built = self._sample_messages(snapshots, stamps)
        except messages.MessageFieldError:
            return []
        return [(self.wanted, *sample) for sample in reversed(built)]

    def _sample_messages(self, snapshots: Sequence[Snapshot], stamps: Sequence[int]
                         ) -> list[tuple[Outputs, SampleFrames | None, np.ndarray | None]]:
        """The messages of the topics in ``wanted`` of N samples at ``stamps`` (ns), built
        together, with each sample's kinematics (one pass per sample feeds /tf, /ee_pose and
        the Rerun sample; none when nothing takes them) and its free bodies' rows. A moving
        base's outputs advance its odometry: one sample at a time. Raises MessageFieldError."""
        wanted = self.wanted
        has_bodies = bool(self.frames.body_shapes)
        bodies = self.frames.body_poses([snapshot.bodies for snapshot in snapshots]) if has_bodies else None
        kinematics = self.frames.has_robot and (self.recorder.samples or not wanted.isdisjoint(KINEMATIC_TOPICS))
        samples = [self.frames.links.at(snapshot.q) for snapshot in snapshots] if kinematics else None
        per_sample: list[Outputs] = [[] for _ in snapshots]

        def add(topic: str, built: list[object]) -> None:
            for outputs, message in zip(per_sample, built):
                outputs.append((topic, message))

        if "/clock" in wanted:
            add("/clock", [messages.clock(stamp) for stamp in stamps])
        if "/joint_states" in wanted:
            add("/joint_states", self._joint_states_of(stamps, snapshots))
        if samples is not None:
            for outputs, ee in zip(per_sample, self.frames.ee_outputs(stamps, samples, wanted)):
                outputs += ee
        if has_bodies and "/free_bodies" in wanted:
            add("/free_bodies", self.frames.free_bodies(stamps, bodies))
        if has_bodies and "/free_bodies_markers" in wanted:
            add("/free_bodies_markers", self.frames.free_body_markers(stamps, [s.bodies for s in snapshots]))
        base = None
        if self.moving_base is not None:     # always: it advances the odometry
            odometry, base = self.moving_base.outputs(stamps[0], self.scene_time, snapshots[0])
            per_sample[0] += [(topic, message) for topic, message in odometry if topic in wanted]
        if "/tf" in wanted:
            add("/tf", self.frames.tf(stamps, samples, bodies, base))
        return [(outputs, None if samples is None else samples[k], None if bodies is None else bodies[k])
                for k, outputs in enumerate(per_sample)]

    def _outputs(self, snapshot: Snapshot, prebuilt: tuple | None = None) -> Outputs:
        """The sample's messages (``prebuilt``: (wanted, messages, kinematics, body rows) of
        :meth:`_block`, or built now), logged."""
        stamp = self.stamp_ns
        self.snapshot = snapshot
        if self.simulator.conservative:
            self.energy_error = max(self.energy_error, abs(snapshot.energy - self.energy0))
        try:
            outputs, sample, bodies = prebuilt[1:] if prebuilt is not None else \
                self._sample_messages([snapshot], [stamp])[0]
            self.recorder.write(outputs, stamp)
        except messages.MessageFieldError as error:
            self.failure = f"non-finite output at t = {self.t:.6f} s: {error}"
            return []
        if sample is not None:
            self.recorder.sample(stamp, snapshot.joint_names, snapshot.q, snapshot.v, snapshot.tau, snapshot.energy,
                                 sample.ee[sample.ee_index, :3])
        if bodies is not None:
            self.recorder.bodies(stamp, bodies)
        return outputs

    def _joint_states_of(self, stamps: Sequence[int], snapshots: Sequence[Snapshot]) -> list[object]:
        """/joint_states of N samples: the moving joints (joint order), then every locked
        joint (URDF tree order) at its locked value with velocity and effort 0, so that
        every movable joint of the URDF has a position (robot_state_publisher needs wheels
        and fingers)."""
        locked, zeros = np.tile(self._locked_q, (len(stamps), 1)), np.zeros((len(stamps), len(self.locked_names)))
        values = np.hstack([np.array([s.q for s in snapshots]), locked, np.array([s.v for s in snapshots]), zeros,
                            np.array([s.tau for s in snapshots]), zeros])
        return self._joint_states.many(stamps, values, lambda stamp_ns, row: messages.joint_state(
            stamp_ns, (*snapshots[0].joint_names, *self.locked_names), *np.split(row, 3)))

    def diagnostics(self, real_time_factor: float) -> Outputs:
        """/diagnostics now: real-time factor (simulated s per wall s), integrator statistics,
        energy (J), input counters, the free bodies (names in /free_bodies order) and the
        contact events so far; level ERROR after a divergence, WARN when paused. Figures
        not known (counters the integrator does not report) are ``NOT_REPORTED``."""
        stats = {f"integrator.{key}": reported(value) for key, value in self.simulator.stats.as_dict().items()}
        values = {"sim_time": self.t, "real_time_factor": reported(real_time_factor),
                  "energy": self.snapshot.energy, "energy_error": self.energy_error,
                  "paused": self.paused, "command": self._command_source(), "resets": self.resets,
                  "last_reset_at": "none" if self.last_reset_ns is None else self.last_reset_ns / NS_PER_S,
                  **stats, **self.counters.as_values(),
                  **self.contact_values()}
        level, text = ("ERROR", self.failure) if self.failure else (("WARN", "paused") if self.paused else ("OK", "running"))
        return self._diagnostic_outputs(level, text, values)

    def contact_values(self) -> dict[str, object]:
        """``free_bodies`` (names, comma-separated, in /free_bodies order) and the contact
        events since the last reset up to the current sample (the simulator may have run
        ahead within its solve horizon): ``contact.events``, ``contact.events.<kind>`` per
        kind seen (touch, compression, separation, impact, contact: see
        :class:`~youbot_dynamics.sim.state.ContactEvent`) and ``contact.last_event``.
        Nothing for a scene without contact."""
        if self.simulator.model.contact is None:
            return {}
        events = [e for e in self.simulator.events if e.time <= self.scene_time + 0.5 / NS_PER_S]
        kinds = sorted({e.kind for e in events})
        last = events[-1] if events else None
        return {"free_bodies": ",".join(spec.body.name for spec in self.scene.free_bodies),
                "contact.events": len(events),
                **{f"contact.events.{kind}": sum(e.kind == kind for e in events) for kind in kinds},
                "contact.last_event": "none" if last is None else
                f"{last.kind} {last.pair} at t = {last.time:.6f} s (value {last.value:.6g})"}

    def _command_source(self) -> str:
        if self.commands.active(self.t):
            return "effort_command"
        if self.commands.received_at is not None and self.commands.on_timeout == "zero_torque":
            return "zero_torque (command timed out)"
        return f"scene controller ({self.simulator.controller.kind})"


class InverseSession(_Session):
    """Torques from measured joint states: accelerations by central differences (see
    :mod:`youbot_dynamics.node.inverse`), tau = RNEA + friction of the scene's robot."""

    mode = "inverse"
    odometry: WheelOdometry | None = None
    """Wheel odometry of a scene with a moving base (/odom from the joint states' wheel speeds)."""

    @property
    def topics(self) -> tuple[str, ...]:
        """/computed_torques, /ee_pose (and /ee_poses for several robots), /tf, /diagnostics
        (the latched topics are in ``latched``), and /odom for a scene with a moving base."""
        odom = ("/odom",) if self.odometry is not None else ()
        return ("/computed_torques", *self.frames.ee_topics, "/tf", *odom, "/diagnostics")

    def __init__(self, scene: Scene, *, filter_time_constant: float = 0.0, max_gap_ns: int = DEFAULT_MAX_GAP_NS,
                 frame_id: str = "", ee_link: str = "", mcap_path: str | Path | None = None,
                 rrd_path: str | Path | None = None, callback_budget: float = 0.05, frame_prefix: str = "",
                 node_name: str = "dynamics_node") -> None:
        robot = scene.robot  # reduced, with the scene's gravity
        if not robot.tree:
            raise UserInputError(f"{scene.source}: inverse mode needs a robot; the scene has none")
        if scene.base.mode != "fixed":  # /odom from the wheel speeds of the joint states
            self.odometry = WheelOdometry(mecanum_base_from_robot(robot, scene.base.wheels), scene.base.pose0,
                                          frame_prefix)
            self.wheels = np.array([robot.joint_index(name) for name in scene.base.wheels])
        super().__init__(scene, robot, frame_id, ee_link, mcap_path, rrd_path, callback_budget, frame_prefix,
                         node_name)
        self.known = tuple(j.name for j in self.robot.tree) + self.robot.joint_names
        self.dynamics = InverseDynamics(self.robot, scene.joint_friction(self.robot))
        self._torques = Refilled()
        self._names_key: tuple[str, ...] | None = None
        """The names of the last sample accepted through ``joint_sample`` (see
        ``_remember_names``)."""
        self._velocity_bound = plausible_limit(self.robot, "velocity")
        self._effort_bound = plausible_limit(self.robot, "effort")
        self.estimator = AccelerationEstimator(filter_time_constant, max_gap_ns)
        self.stamp_ns, self.samples = 0, 0
        self.last_unstamped = False
        """True when the last sample taken was stamped 0."""
        self.failure: str | None = None

    @property
    def t(self) -> float:
        """Time (s) of the last sample torques were computed for."""
        return self.stamp_ns / NS_PER_S

    def joint_state(self, names: Sequence[str], position: Sequence[float], velocity: Sequence[float],
                    stamp_ns: int, received_ns: int | None = None) -> Outputs:
        """Take one /joint_states sample; returns /computed_torques and /ee_pose of the
        previous sample once three are known. Stamp 0 is ambiguous (unset, or the first
        sample of a stream in simulated time, which starts at 0): a sample stamped 0 right
        after another stamped 0 takes the receive time ``received_ns`` (int ns of the node's
        clock; without it, it is rejected as ``bad_timing``), any other is taken at 0. So a
        stream stamped from 0 loses nothing, and an unstamped stream runs on receive times
        after its first sample (whose jump to the node clock restarts the estimate). Raises
        and counts :class:`InputRejected`; a rejected sample breaks the difference stencil
        (no torque is computed across it: the next torque needs three good samples after
        it), and so does a gap or a jump back in the stamps (see
        :mod:`youbot_dynamics.node.inverse`). A sample whose velocity is beyond the
        velocity-limit bound is rejected (``out_of_limits``). A torque that is implausible
        (beyond the effort-limit bound) or not finite is not published: the sample counts as
        accepted, the torque as rejected (``implausible_torque`` or ``non_finite``), and the
        estimate restarts."""
        outputs, rejected = self.joint_states([(names, position, velocity, stamp_ns, received_ns)])
        if rejected:
            raise rejected[0]
        return outputs

    def joint_states(self, samples: Sequence[tuple[Sequence[str], Sequence[float], Sequence[float], int, int | None]]
                     ) -> tuple[Outputs, list[InputRejected]]:
        """:meth:`joint_state` of each sample in turn ((names, position, velocity, stamp_ns,
        received_ns)), the same outputs in the same order, the rejected samples' errors
        returned (counted) instead of raised. The samples are checked, differenced and
        their torques computed as arrays (Pinocchio's batch RNEA); where a torque is
        implausible, they are taken one by one as :meth:`joint_state` takes them, with the
        same result."""
        stamps, q, v, taken, rejected = self._checked(samples)
        if self.odometry is None and len(samples) > 1:     # one sample: cheaper one by one
            state = self.estimator.state()
            *stencils, failed = self.estimator.push_rows(stamps, q, v, taken)
            outputs = self._torques_of(*stencils)
            if outputs is not None:
                for error in failed:
                    self.counters.reject(error)
                return outputs, rejected
            self.estimator.restore(state)
        return [output for k, ok in enumerate(taken)
                for output in self._one(JointSample(stamps[k], q[k], v[k]) if ok else None)], rejected

    def _checked(self, samples: Sequence[tuple]
                 ) -> tuple[list[int], np.ndarray, np.ndarray, list[bool], list[InputRejected]]:
        """Each sample checked (see :meth:`joint_state`) and counted: the stamps (int ns; 0
        for a rejected sample), q and v rows in joint order (N, nq) and (N, nv), whether each
        sample was taken, and the errors of those rejected. Samples naming the joints as the
        last accepted one did are checked as arrays; any that fails, and any other, through
        ``_joint_sample``."""
        stamps = self._stamps_of(samples)
        rows = self._good_rows(samples, stamps) if len(samples) > 1 else None
        if rows is not None and all(rows[2]):
            self.counters.accepted += len(samples)
            return [int(stamp) for stamp in stamps], rows[0], rows[1], [True] * len(samples), []
        q, v, good = rows if rows is not None else (np.zeros((len(samples), self.robot.nq)),
                                                    np.zeros((len(samples), self.robot.nv)), None)
        taken: list[bool] = []
        rejected: list[InputRejected] = []
        for k, ((names, position, velocity, _, _), stamp) in enumerate(zip(samples, stamps)):
            try:
                if isinstance(stamp, InputRejected):
                    raise stamp
                if good is None or not good[k]:
                    sample = self._joint_sample(names, position, velocity, stamp)
                    q[k], v[k] = sample.q, sample.v
            except InputRejected as error:
                self.counters.reject(error)
                rejected.append(error)
                stamps[k] = 0
                taken.append(False)
                continue
            self.counters.accepted += 1
            stamps[k] = int(stamp)
            taken.append(True)
        return stamps, q, v, taken, rejected

    def _stamps_of(self, samples: Sequence[tuple]) -> list[int | InputRejected]:
        """The stamp (ns) each sample is taken at: its own, or for the second of two stamped 0
        in a row, its receive time (``bad_timing`` without one); sets ``last_unstamped``."""
        stamps: list[int | InputRejected] = [sample[3] for sample in samples]
        if 0 not in stamps:
            self.last_unstamped = self.last_unstamped and not stamps
            return stamps
        for k, (*_, stamp_ns, received_ns) in enumerate(samples):
            unstamped = stamp_ns == 0
            if unstamped and self.last_unstamped:
                if received_ns is None:
                    stamps[k] = InputRejected("bad_timing", "joint state not stamped and no receive time given")
                    continue
                stamps[k] = received_ns
            self.last_unstamped = unstamped
        return stamps

    def _good_rows(self, samples: Sequence[tuple], stamps: Sequence[int | InputRejected]
                   ) -> tuple[np.ndarray, np.ndarray, list[bool]] | None:
        """(q, v) rows in joint order and which rows pass every check of ``_joint_sample``
        (one comparison: |position| and |velocity| within ``_row_bounds``), for samples that
        name the joints exactly as the last accepted one did; None when they cannot be taken
        as arrays."""
        key, count = self._names_key, len(samples)
        if key is None or not all(tuple(sample[0]) == key for sample in samples):
            return None
        try:
            values = np.array([sample[1] for sample in samples] + [sample[2] for sample in samples], dtype=float)
        except (ValueError, TypeError):
            return None
        if values.shape != (2 * count, len(key)):
            return None
        within = np.abs(values.reshape(2, count, -1)) <= self._row_bounds
        good = [not isinstance(s, InputRejected) and 0 <= s < STAMP_LIMIT_NS for s in stamps]
        if not within.all():
            good = [g and w for g, w in zip(good, within.all(axis=(0, 2)).tolist())]
        return values[:count, self._columns], values[count:, self._columns], good

    def _joint_sample(self, names: Sequence[str], position: Sequence[float], velocity: Sequence[float],
                      stamp_ns: int) -> JointSample:
        """One sample checked (``joint_sample`` and the velocity bound); raises InputRejected.
        Remembers the names of an accepted sample for the array checks."""
        sample = joint_sample(self.robot, self.known, names, position, velocity, stamp_ns)
        if not (np.abs(sample.v) <= self._velocity_bound).all():
            raise InputRejected("out_of_limits", f"velocity beyond {PLAUSIBLE_FACTOR:g} x the URDF velocity "
                                f"limit of {', '.join(implausible_joints(self.robot, sample.v, 'velocity'))}")
        key = tuple(str(name) for name in names)
        if key != self._names_key:
            self._remember_names(key)
        return sample

    def _remember_names(self, key: tuple[str, ...]) -> None:
        """Cache what the array checks need for samples naming ``key``: ``_columns``, the
        columns of the robot's joints in joint order (a slice when the names are in joint
        order), and ``_row_bounds`` (2, 1, len(key)), the largest |position| (the largest
        float: finite) and |velocity| (the velocity bound, finite) of each column."""
        position_of = {name: i for i, name in enumerate(key)}
        index = np.array([position_of[n] for n in self.robot.joint_names])
        largest = np.finfo(float).max
        bounds = np.full((2, 1, len(key)), largest)
        bounds[1, 0, index] = np.minimum(self._velocity_bound, largest)
        in_order = len(key) == len(index) and (index == np.arange(len(index))).all()
        self._names_key, self._columns, self._row_bounds = key, slice(None) if in_order else index, bounds

    def _one(self, sample: JointSample | None) -> Outputs:
        """The outputs of one checked sample (None: a rejected one, which breaks the
        stencil): /odom, then the torque of the previous sample once three are known."""
        if sample is None:
            self.estimator.clear()
            return []
        odom: Outputs = []
        if self.odometry is not None:
            odom = [("/odom", self.odometry.outputs(sample.stamp_ns, sample.stamp_ns / NS_PER_S,
                                                    sample.v[self.wheels])[0])]
            self.recorder.write(odom, sample.stamp_ns)
        try:
            estimate = self.estimator.push(sample)
        except InputRejected as error:     # a non-finite estimate: the estimator restarted
            self.counters.reject(error)
            return odom
        if estimate is None:
            return odom
        middle, a = estimate
        tau = self.dynamics.torque(middle.q, middle.v, a)
        if not (np.abs(tau) <= self._effort_bound).all():     # NaN too
            finite = bool(np.isfinite(tau).all())
            self.counters.reject(InputRejected("implausible_torque" if finite else "non_finite",
                                               f"torque at {middle.stamp_ns} ns beyond the effort-limit bound or "
                                               f"not finite on {', '.join(implausible_joints(self.robot, tau))}"))
            self.estimator.restart("implausible" if finite else "non_finite")
            return []
        return odom + self._torque_outputs(middle.stamp_ns, middle.q, middle.v, tau)

    def _torques_of(self, stamps: np.ndarray, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> Outputs | None:
        """The outputs of the estimates of ``push_rows`` (the middle samples' stamps (int64
        ns), q, v rows and their accelerations), torques computed at once; None (nothing
        done) if a torque is implausible or not finite."""
        if not len(stamps):
            return []
        tau = self.dynamics.torques(q, v, a)
        if not (np.abs(tau) <= self._effort_bound).all():     # NaN too
            return None
        if self.recorder.samples or not self.wanted.isdisjoint(KINEMATIC_TOPICS):
            return [output for k, stamp in enumerate(stamps.tolist())
                    for output in self._torque_outputs(stamp, q[k], v[k], tau[k])]
        outputs: Outputs = []     # /computed_torques alone: refilled at once
        if "/computed_torques" in self.wanted:
            try:
                torques = self._torques.many(stamps, np.concatenate((q, v, tau), axis=1), self._joint_state)
            except messages.MessageFieldError:
                return None
            outputs = [("/computed_torques", message) for message in torques]
            if self.recorder.records("/computed_torques"):
                for output, stamp in zip(outputs, stamps.tolist()):
                    self.recorder.write([output], stamp)
        self.stamp_ns, self.samples = int(stamps[-1]), self.samples + len(stamps)
        return outputs

    def _joint_state(self, stamp_ns: int, values: np.ndarray) -> object:
        """sensor_msgs/JointState of the robot's joints: ``values`` are q, v, tau in a row."""
        return messages.joint_state(stamp_ns, self.robot.joint_names, *np.split(values, 3))

    def _torque_outputs(self, stamp: int, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> Outputs:
        """/computed_torques, /ee_pose(s) and /tf of the torque ``tau`` at a sample (stamp
        int ns, q, v), those wanted, logged."""
        wanted = self.wanted
        kinematics = self.recorder.samples or not wanted.isdisjoint(KINEMATIC_TOPICS)
        frames = self.frames.links.at(q) if kinematics else None
        try:
            outputs: Outputs = []
            if "/computed_torques" in wanted:
                outputs.append(("/computed_torques", self._torques(stamp, np.concatenate([q, v, tau]),
                                                                  self._joint_state)))
            if frames is not None:
                outputs += self.frames.ee_outputs([stamp], [frames], wanted)[0]
                if "/tf" in wanted:
                    outputs.append(("/tf", self.frames.tf([stamp], [frames])[0]))
        except messages.MessageFieldError as error:
            self.counters.reject(InputRejected("non_finite", str(error)))
            self.estimator.restart("non_finite")
            return []
        self.recorder.write(outputs, stamp)
        if self.recorder.samples:
            data = self.dynamics.data
            energy = kinetic_energy(self.robot, data, q, v) + potential_energy(self.robot, data, q)
            self.recorder.sample(stamp, self.robot.joint_names, q, v, tau, energy, frames.ee[frames.ee_index, :3])
        self.stamp_ns, self.samples = stamp, self.samples + 1
        return outputs

    def diagnostics(self, real_time_factor: float) -> Outputs:
        """/diagnostics now: samples processed, input counters and the estimator's restarts
        by cause (``estimator.restarts.<cause>``)."""
        values = {"torques_published": self.samples, **self.counters.as_values(),
                  **{f"estimator.restarts.{cause}": count for cause, count in self.estimator.restarts.items()}}
        return self._diagnostic_outputs("OK", "running", values)
