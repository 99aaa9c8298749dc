"""The dynamics node's interface in one place: every topic (:data:`TOPICS`), service
(:data:`SERVICES`) and parameter (:data:`PARAMETERS`), ROS-free.

The sessions take their topic lists from :data:`TOPICS` (:func:`published`), the rclpy node
creates its publishers, subscriptions and services and declares its parameters from these
tables (:mod:`youbot_dynamics.ros.dynamics_node`, :mod:`youbot_dynamics.ros.parameters`), and
docs/node.md is generated from them (:func:`markdown`)::

    python -m youbot_dynamics.node.interface > docs/node.md

Topics are named as logged, as in the root namespace (``/joint_states``); on the graph the
node uses relative names (:func:`~youbot_dynamics.node.topics.graph_name`). QoS names:
:data:`QOS`; ``joint_states_qos`` means the profile that parameter names. A topic's ``when``
names the scene feature it needs (:data:`FEATURES`); the order of :data:`TOPICS` is the
order in which a session lists its topics (and the MCAP its channels).
"""
from __future__ import annotations

import re
import sys
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass

from youbot_dynamics.io.qos import Qos
from youbot_dynamics.node.topics import GLOBAL_TOPICS

Outputs = list[tuple[str, object]]
"""What a session hands out to publish and log: (topic as logged, message) pairs."""

MODES = ("simulate", "inverse")
"""The node's modes (parameter ``mode``)."""
BOTH = MODES
SIMULATE, INVERSE = ("simulate",), ("inverse",)

QOS = {"reliable": Qos("reliable", "volatile", "keep_last", 1000),
       "latched": Qos("reliable", "transient_local", "keep_last", 1),
       "best_effort": Qos("best_effort", "volatile", "keep_last", 1000),
       "keep_all": Qos("reliable", "volatile", "keep_all", 0)}
"""QoS profiles by name: the one source of what the node's publishers and subscriptions use
(their rclpy form: :mod:`youbot_dynamics.ros.qos`) and of what its MCAP records as each
channel's offered profile. Latched: late subscribers get the last message."""
SUBSCRIPTION_QOS = ("best_effort", "reliable", "keep_all")
"""The choices of the ``joint_states_qos`` parameter (names of :data:`QOS`)."""

FEATURES = {"robot": "the scene has a robot",
            "several_robots": "the robot is composed of several robots",
            "moving_base": "the scene has a moving base",
            "free_bodies": "the scene has free bodies",
            "static_geometry": "the scene has static or link geometry",
            "arm_controller": "the scene moves arm joints (arm_joints)",
            "gripper_controller": "the scene moves gripper joints (gripper_joints)",
            "wrist_sensor": "the scene has a wrist force/torque sensor (scene key wrist_sensor, default the palm)",
            "contact_pairs": "the scene declares contact pairs"}
"""Scene features a topic may need (``Topic.when``)."""


@dataclass(frozen=True)
class Topic:
    """One topic of the node: ``name`` as logged, ``direction`` "pub" or "sub", message
    ``type`` (pkg/msg/Type), ``qos`` (a name of :data:`QOS`, or ``joint_states_qos``), the
    ``modes`` it is in, the scene feature it needs (``when``, a key of :data:`FEATURES`;
    None: always), what it carries, and for a subscription the largest serialized message
    (bytes) it deserialises."""

    name: str
    direction: str
    type: str
    qos: str
    modes: tuple[str, ...]
    when: str | None
    carries: str
    max_bytes: int | None = None


TOPICS: tuple[Topic, ...] = (
    Topic("/clock", "pub", "rosgraph_msgs/msg/Clock", "reliable", SIMULATE, None,
          "simulated time of each sample (starts at 0; a reset does not restart it)"),
    Topic("/joint_states", "pub", "sensor_msgs/msg/JointState", "reliable", SIMULATE, "robot",
          "position, velocity and effort of the moving joints (joint order), then of the locked joints "
          "(velocity and effort 0)"),
    Topic("/computed_torques", "pub", "sensor_msgs/msg/JointState", "reliable", INVERSE, None,
          "torques (N m, N) from RNEA and friction at each /joint_states sample, one sample late, with its q and v"),
    Topic("/ee_pose", "pub", "geometry_msgs/msg/PoseStamped", "reliable", BOTH, "robot",
          "pose of the ee_link parameter's link (default: the end effector) in the root frame"),
    Topic("/ee_poses", "pub", "geometry_msgs/msg/PoseArray", "reliable", BOTH, "several_robots",
          "every robot's end effector in the root frame, in composition order (names: ee_links in /diagnostics)"),
    Topic("/odom", "pub", "nav_msgs/msg/Odometry", "reliable", SIMULATE, "moving_base",
          "wheel odometry of the simulated wheel speeds: base_footprint in odom"),
    Topic("/base_pose_ground_truth", "pub", "nav_msgs/msg/Odometry", "reliable", SIMULATE, "moving_base",
          "the simulated pose and twist of base_footprint in world (zero covariance)"),
    Topic("/free_bodies", "pub", "geometry_msgs/msg/PoseArray", "reliable", SIMULATE, "free_bodies",
          "the free bodies' poses in the world frame (the root frame with a fixed base), in the scene's order "
          "(names: free_bodies in /diagnostics)"),
    Topic("/free_bodies_markers", "pub", "visualization_msgs/msg/MarkerArray", "reliable", SIMULATE, "free_bodies",
          "each free body's shape at its pose (namespace: the body's name)"),
    Topic("/wrist_wrench", "pub", "geometry_msgs/msg/WrenchStamped", "reliable", SIMULATE, "wrist_sensor",
          "force (N) and torque (N m) the arm exerts on the hand across the wrist_sensor link's joint, about that "
          "link's origin in its frame (at rest: the weight of the hand and its load, pointing up)"),
    Topic("/imu", "pub", "sensor_msgs/msg/Imu", "reliable", SIMULATE, "moving_base",
          "base_link's angular velocity (rad/s) and proper acceleration (m/s^2; +9.81 up at rest) in base_link, its "
          "orientation in the world; covariances 0 (noise-free simulation)"),
    Topic("/contacts/<pair>", "pub", "geometry_msgs/msg/WrenchStamped", "reliable", SIMULATE, "contact_pairs",
          "one topic per contact pair, /contacts/<first>/<second> (geometry names): the contact force (N) and torque "
          "(N m) on the second geometry about its frame's origin (its link or free body; the root frame for world "
          "geometry), in that frame; zero while apart"),
    Topic("/tf", "pub", "tf2_msgs/msg/TFMessage", "reliable", BOTH, None,
          "every moving link in its parent, odom -> base_footprint and odom -> world (moving base), world frame -> "
          "each free body (one tree: docs/ros.md, The frame tree)"),
    Topic("/odom", "pub", "nav_msgs/msg/Odometry", "reliable", INVERSE, "moving_base",
          "wheel odometry of the received /joint_states' wheel speeds: base_footprint in odom (on /tf too)"),
    Topic("/diagnostics", "pub", "diagnostic_msgs/msg/DiagnosticArray", "reliable", BOTH, None,
          "one status: real-time factor, integrator statistics, energy, input counters, callback overruns, "
          "contact events, base wheel slip (simulate); torques published, input counters, estimator restarts (inverse)"),
    Topic("/tf_static", "pub", "tf2_msgs/msg/TFMessage", "latched", BOTH, None,
          "every fixed link in its parent, and root frame -> URDF root link (or -> odom) if they differ"),
    Topic("/robot_description", "pub", "std_msgs/msg/String", "latched", BOTH, "robot",
          "the URDF of what is simulated (the composed URDF for a composed scene)"),
    Topic("/scene_markers", "pub", "visualization_msgs/msg/MarkerArray", "latched", BOTH, "static_geometry",
          "static world geometry (world frame) and geometry on links (link frame, frame-locked)"),
    Topic("/joint_commands", "sub", "sensor_msgs/msg/JointState", "reliable", SIMULATE, None,
          "effort commands (N m, N) by joint name, held for command_timeout; beyond the effort limit: clamped",
          max_bytes=64 * 1024),
    Topic("/joint_trajectory", "sub", "trajectory_msgs/msg/JointTrajectory", "reliable", SIMULATE, None,
          "a joint trajectory for the scene's tracking controller (positions, optional velocities)",
          max_bytes=1024 * 1024),
    Topic("/cmd_vel", "sub", "geometry_msgs/msg/Twist", "reliable", SIMULATE, "moving_base",
          "the base's twist in base_footprint (vx, vy, wz), reached within the scene's a_max, held for "
          "command_timeout, then stop",
          max_bytes=1024),
    Topic("/joint_states", "sub", "sensor_msgs/msg/JointState", "joint_states_qos", INVERSE, None,
          "measured joint positions and velocities by name (unstamped samples take the receive time)",
          max_bytes=64 * 1024),
    Topic("/arm_controller/commands", "sub", "std_msgs/msg/Float64MultiArray", "reliable", SIMULATE,
          "arm_controller", "forward_command_controller's commands: one value per arm joint in arm_joints' "
          "order (youBot: arm_joint_1 .. 5), meaning commands_interface", max_bytes=64 * 1024),
    Topic("/gripper_controller/commands", "sub", "std_msgs/msg/Float64MultiArray", "reliable", SIMULATE,
          "gripper_controller", "as arm_controller/commands, one value per gripper joint in gripper_joints' order "
          "(youBot: gripper_finger_joint_l, _r)", max_bytes=64 * 1024),
)
"""Every topic. Subscriptions' ``max_bytes``: 64 KiB holds a JointState of MAX_NAMES (256)
joints four times over; 1 MiB a trajectory of MAX_TRAJECTORY_POINTS (1000) points of 16
joints with positions, velocities, accelerations and efforts (0.5 MB)."""

PAIR_TOPIC = "/contacts/<pair>"
"""The table's name of the per-pair topics (:func:`pair_topic` names each)."""
TOPIC_TYPES = {topic.name: topic.type for topic in TOPICS if topic.direction == "pub"}
"""Every topic the node publishes and logs, with its type (tf2_msgs has no PyPI wheel:
``make`` builds it from interfaces/; without it the node publishes neither /tf nor /tf_static
but still logs them)."""
TOPIC_QOS = {topic.name: QOS[topic.qos] for topic in TOPICS if topic.direction == "pub"}
"""The profile every published topic is offered with, live and in the MCAP."""


def pair_topic(first: str, second: str) -> str:
    """The topic of the contact pair of geometries ``first`` and ``second``:
    /contacts/<first>/<second>, each name made a valid ROS name token (a character other
    than a letter, digit or underscore becomes _, a leading digit gets a _ before it)."""
    def token(name: str) -> str:
        name = re.sub(r"[^A-Za-z0-9_]", "_", name)
        return "_" + name if not name or name[0].isdigit() else name
    return f"/contacts/{token(first)}/{token(second)}"


def table_topic(name: str) -> str:
    """The table's name of a published topic (a per-pair topic's: :data:`PAIR_TOPIC`)."""
    return PAIR_TOPIC if name.startswith("/contacts/") else name


def topic_type(name: str) -> str:
    """The message type of a published topic (a per-pair topic's: :data:`PAIR_TOPIC`'s)."""
    return TOPIC_TYPES[table_topic(name)]


def topic_qos(name: str) -> Qos:
    """The profile a published topic is offered with, live and in the MCAP."""
    return TOPIC_QOS[table_topic(name)]


def instances(topic: Topic, names: Sequence[str]) -> tuple[str, ...]:
    """The topics ``topic`` stands for among a session's ``names``: the per-pair topics for
    :data:`PAIR_TOPIC`, the topic itself otherwise."""
    if topic.name != PAIR_TOPIC:
        return (topic.name,)
    return tuple(name for name in names if name.startswith("/contacts/"))


def topics_of(mode: str, direction: str, features: frozenset[str], latched: bool = False) -> tuple[Topic, ...]:
    """The topics of a node in ``mode`` with the scene ``features`` (keys of
    :data:`FEATURES`), in table order: those of ``direction``; for "pub", the latched ones
    (``latched``) or the others."""
    return tuple(topic for topic in TOPICS if topic.direction == direction and mode in topic.modes
                 and (topic.when is None or topic.when in features)
                 and (direction == "sub" or (topic.qos == "latched") == latched))


def published(mode: str, features: frozenset[str], pairs: Sequence[tuple[str, str]] = ()) -> tuple[str, ...]:
    """Names of the topics published per sample (not latched), in table order; the contact
    ``pairs`` ((first, second) geometry names) stand for :data:`PAIR_TOPIC`, in their order."""
    return tuple(name for topic in topics_of(mode, "pub", features)
                 for name in ([pair_topic(*pair) for pair in pairs] if topic.name == PAIR_TOPIC else [topic.name]))


@dataclass(frozen=True)
class Service:
    """One service of the node: ``name`` (private: ``~/``), ``type`` (pkg/srv/Type), the
    ``modes`` it is in and what it does."""

    name: str
    type: str
    modes: tuple[str, ...]
    does: str


SERVICES: tuple[Service, ...] = (
    Service("~/reset", "std_srvs/srv/Trigger", SIMULATE,
            "back to the scene's initial state; node time goes on (the answer says where the scene's t = 0 is)"),
    Service("~/pause", "std_srvs/srv/SetBool", SIMULATE, "pause (true) or resume (false) simulated time"),
)



@dataclass(frozen=True)
class Action:
    """One action server of the node: ``name`` (relative), ``type`` (pkg/action/Type), the
    ``modes`` it is in, the scene feature it needs and what it does."""

    name: str
    type: str
    modes: tuple[str, ...]
    when: str
    does: str


ACTIONS: tuple[Action, ...] = (
    Action("arm_controller/follow_joint_trajectory", "control_msgs/action/FollowJointTrajectory", SIMULATE,
           "arm_controller", "joint_trajectory_controller's action: the arm joints in any order, path and goal "
           "tolerances, goal_time_tolerance, feedback per sample, cancel, preemption (the older goal is "
           "cancelled); a goal that cannot run ends ABORTED with its result code (INVALID_JOINTS, INVALID_GOAL, "
           "OLD_HEADER_TIMESTAMP)"),
    Action("gripper_controller/gripper_command", "control_msgs/action/GripperCommand", SIMULATE,
           "gripper_controller", "gripper_action_controller's action: every gripper joint to position (m), force "
           "capped at max_effort (N); stalled when a finger touches and stops for stall_timeout"),
)
"""Every action server (:mod:`youbot_dynamics.ros.actions`; the goal logic:
:mod:`~youbot_dynamics.node.trajectory_goal`, :mod:`~youbot_dynamics.node.gripper_goal`)."""


def offered(mode: str, features: frozenset[str], published: Sequence[str] = ()) -> dict[str, tuple[str, ...]]:
    """What a node in ``mode`` with the scene ``features`` offers, by kind, in table order (as
    its ready line lists it): the topics it publishes (latched ones last; the per-pair topics
    among ``published``, the session's topic names) and subscribes, its services and its
    action servers."""
    return {"publishes": tuple(name for latched in (False, True)
                               for topic in topics_of(mode, "pub", features, latched=latched)
                               for name in instances(topic, published)),
            "subscribes": tuple(topic.name for topic in topics_of(mode, "sub", features)),
            "services": tuple(service.name for service in SERVICES if mode in service.modes),
            "actions": tuple(action.name for action in ACTIONS
                             if mode in action.modes and action.when in features)}


TIMEOUT_ACTIONS = ("hold", "zero_torque")
"""What the simulator applies once the last effort command is older than the timeout:
``hold`` hands control back to the scene's controller (its set point or trajectory; zero
torque in a scene without a controller), ``zero_torque`` applies zero torque."""
COMMAND_INTERFACES = ("position", "velocity", "effort")
"""What ``<controller>/commands`` carries (the ``commands_interface`` parameter), as
forward_command_controller's interfaces (:mod:`~youbot_dynamics.node.forward_commands`)."""
AUTO_PREFIX = "auto"
"""``frame_prefix`` value that derives the prefix from the node's namespace."""
CHOICES = {"mode": MODES, "on_timeout": TIMEOUT_ACTIONS, "joint_states_qos": SUBSCRIPTION_QOS,
           "commands_interface": COMMAND_INTERFACES}
"""The allowed values of the string parameters that have a fixed set."""


@dataclass(frozen=True)
class Spec:
    """One parameter: default (its type is the parameter's), description, optional (min,
    max) range, read-only or not."""

    default: object
    description: str
    limits: tuple[float, float] | None = None
    read_only: bool = True


PARAMETERS: dict[str, Spec] = {
    "scene": Spec("arm_ptp", "scene name under config/scenes/ or a path to a scene YAML"),
    "mode": Spec("simulate", "simulate: integrate the scene and publish its motion; inverse: compute "
                 "torques from /joint_states (" + " | ".join(MODES) + ")"),
    "publish_rate": Spec(500.0, "samples of /joint_states, /ee_pose, /free_bodies and /clock per simulated second (Hz)",
                         (1.0, 2000.0)),
    "time_scale": Spec(1.0, "simulated seconds per wall-clock second; 0: as fast as possible", (0.0, 100.0),
                       read_only=False),
    "duration": Spec(0.0, "simulated time (s) after which the node finalises its logs and stops; 0: run on",
                     (0.0, 1.0e6)),
    "solve_horizon": Spec(0.02, "simulated time (s) per integrator run (samples handed out one by one; "
                          "commands take effect at the next run)", (0.0, 1.0)),
    "frame_id": Spec("", "root of /tf and frame of /ee_pose, used as given ('' : odom with a moving base, else the "
                     "URDF root link, world without a robot, with frame_prefix)"),
    "frame_prefix": Spec(AUTO_PREFIX, "prefix of every frame the node names (URDF links, free bodies, the default "
                         "root frame), as robot_state_publisher's frame_prefix; auto: the node's namespace without "
                         "its leading slash, plus / (youbot1/ in /youbot1, none in the root namespace)"),
    "ee_link": Spec("", "link reported on /ee_pose ('' : the robot's end effector)"),
    "mcap_path": Spec("", "MCAP log (rosbag2 form) of every published topic plus /tf, /tf_static ('' : none)"),
    "rrd_path": Spec("", "Rerun recording ('' : none)"),
    "command_timeout": Spec(0.5, "effort commands older than this (s, node time) are stale", (0.001, 60.0),
                            read_only=False),
    "on_timeout": Spec("hold", "after the timeout: hold (scene controller) | zero_torque", read_only=False),
    "default_effort_limit": Spec(100.0, "simulate mode: effort limit (N m, N) of joints whose URDF gives none "
                                 "(continuous joints); commands beyond it are clamped", (0.001, 1.0e6)),
    "max_sample_gap": Spec(0.1, "inverse mode: longest spacing (s) of /joint_states samples in one difference "
                           "stencil; a longer gap or a stamp back in time restarts the estimate; /diagnostics "
                           "warns after this much input time without a torque", (1.0e-4, 60.0)),
    "callback_budget": Spec(0.05, "wall seconds a callback (a step tick, a message, a service) may take; an "
                            "overrun is counted and reported in /diagnostics (WARN)", (0.001, 60.0)),
    "acceleration_filter": Spec(0.0, "inverse mode: low-pass time constant (s) on the central-difference "
                                "acceleration; 0: none", (0.0, 10.0)),
    "joint_states_qos": Spec("keep_all", "inverse mode: QoS of the /joint_states subscription: best_effort (hears "
                             "best-effort drivers and reliable publishers; may lose samples) | reliable (keep last "
                             "1000) | keep_all (reliable, lossless for replay --fast; hears no best-effort publisher)"),
    "wait_for_subscribers": Spec(0, "simulate mode: simulated time starts once /joint_states (/free_bodies "
                                 "without a robot) has this many subscribers (or after wait_timeout); 0: at once", (0, 100)),
    "wait_timeout": Spec(10.0, "wall-clock seconds to wait for those subscribers; then start anyway, "
                         "with a warning", (0.0, 3600.0)),
    "diagnostics_period": Spec(1.0, "wall-clock seconds between /diagnostics messages", (0.01, 60.0)),
    "arm_joints": Spec("", "joints of arm_controller, comma-separated, in the order of its commands ('' : the "
                       "first youBot's moving arm_joint_1 .. 5)"),
    "gripper_joints": Spec("", "joints of gripper_controller, comma-separated ('' : the first youBot's moving "
                           "gripper_finger_joint_l, _r)"),
    "commands_interface": Spec("position", "what <controller>/commands carries: position (rad, m) | velocity "
                               "(rad/s, m/s) | effort (N m, N; as /joint_commands)"),
    "goal_time_tolerance": Spec(0.0, "follow_joint_trajectory: seconds after the trajectory's end to reach the "
                                "goal tolerances, for goals that give 0; 0: wait indefinitely (JTC's goal_time)",
                                (0.0, 3600.0)),
    "stopped_velocity_tolerance": Spec(0.01, "follow_joint_trajectory: default goal velocity tolerance (rad/s, "
                                       "m/s)", (0.0, 100.0)),
    "gripper_goal_tolerance": Spec(0.0005, "gripper_command: position error (m, rad) within which the goal is "
                                   "reached", (1.0e-9, 1.0)),
    "stall_timeout": Spec(1.0, "gripper_command: seconds (simulated) a touching finger must stay still to be "
                          "stalled", (0.0, 60.0)),
    "allow_stalling": Spec(False, "gripper_command: a stalled goal succeeds (true) or aborts (false)"),
}
"""Every parameter of the node. Numeric ones carry their range (rclpy refuses a value
outside it); string choices are :data:`CHOICES` (:func:`check_choice`). Read-only ones fix
the node's structure and are set at start-up only (``--ros-args -p name:=value`` or
``--params-file config/dynamics_node.yaml``)."""


def check_choice(name: str, value: object) -> str | None:
    """Why ``value`` is not allowed for ``name`` (None if it is)."""
    choices = CHOICES.get(name)
    if choices is not None and value not in choices:
        return f"parameter {name}: {value!r} is not one of {', '.join(choices)}"
    return None


# ---- dynamics_node --help -------------------------------------------------------------
def _range_of(name: str, spec: Spec) -> str:
    """A parameter's allowed values in words: its choices or its (min .. max) range."""
    if name in CHOICES:
        return " | ".join(CHOICES[name])
    return "" if spec.limits is None else f"{spec.limits[0]:g} .. {spec.limits[1]:g}"


def parameter_help(width: int = 100) -> str:
    """The parameter table as ``dynamics_node --help`` prints it: per parameter a line of
    name, type, default and range (or choices), then its description, wrapped to ``width``."""
    rows = [(name, type(spec.default).__name__, repr(spec.default), _range_of(name, spec),
             spec.description + ("" if spec.read_only else " (settable at run time)"))
            for name, spec in PARAMETERS.items()]
    widths = [max(len(row[column]) for row in rows) for column in range(3)]
    lines = ["  " + "  ".join(("name", "type", "default")[c].ljust(widths[c]) for c in range(3)) + "  range"]
    for *columns, limits, description in rows:
        lines.append(("  " + "  ".join(c.ljust(w) for c, w in zip(columns, widths)) + "  " + limits).rstrip())
        lines += textwrap.wrap(description, width, initial_indent=" " * 6, subsequent_indent=" " * 6)
    return "\n".join(lines)


# ---- docs/node.md ----------------------------------------------------------------------
def _cell(text: object) -> str:
    """``text`` as a Markdown table cell (pipes escaped)."""
    return str(text).replace("|", "\\|")


def _table(header: tuple[str, ...], rows: list[tuple[object, ...]]) -> list[str]:
    """A Markdown table."""
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header),
            *("| " + " | ".join(_cell(value) for value in row) + " |" for row in rows)]


def _topic_row(topic: Topic) -> tuple[object, ...]:
    name = f"`{topic.name}`" + (" (global)" if topic.name in GLOBAL_TOPICS else "")
    qos = "`joint_states_qos`" if topic.qos == "joint_states_qos" else topic.qos
    when = "" if topic.when is None else f" ({FEATURES[topic.when]})"
    return name, topic.direction, f"`{topic.type}`", qos, ", ".join(topic.modes) + when, topic.carries


def _parameter_row(name: str, spec: Spec) -> tuple[object, ...]:
    default = f'`"{spec.default}"`' if isinstance(spec.default, str) else f"`{spec.default!r}`"
    writable = "" if spec.read_only else " (settable at run time)"
    return f"`{name}`", type(spec.default).__name__, default, _range_of(name, spec), spec.description + writable


STACK = ("/joint_states", "/ee_pose", "/tf", "/tf_static", "/robot_description", "/clock", "/diagnostics",
         "/odom", "/imu", "/wrist_wrench", "/joint_commands", "/joint_trajectory", "/cmd_vel",
         "/arm_controller/commands", "arm_controller/follow_joint_trajectory", "gripper_controller/gripper_command",
         "~/reset", "scene", "mode", "publish_rate", "time_scale", "duration", "mcap_path", "rrd_path")
"""What another ROS stack meets first: the rows of the README's table (:func:`stack_table`)."""


def stack_table() -> str:
    """The README's table of :data:`STACK`: each name (relative, as remapping sees it), its
    type, and what it is in each mode (pub, sub, action, service or parameter); the
    descriptions are in docs/node.md (:func:`markdown`)."""
    types: dict[str, str] = {}
    kinds: dict[tuple[str, str], str] = {}
    for name, kind, type_, modes in (*((t.name, t.direction, t.type, t.modes) for t in TOPICS),
                                     *((a.name, "action", a.type, a.modes) for a in ACTIONS),
                                     *((s.name, "service", s.type, s.modes) for s in SERVICES),
                                     *((n, "parameter", type(s.default).__name__, BOTH) for n, s in PARAMETERS.items())):
        types[name] = re.sub(r"/(msg|srv|action)/", "/", type_)
        kinds.update({(name, mode): kind for mode in modes})
    rows = [(f"`{name if name in GLOBAL_TOPICS else name.lstrip('/')}`", f"`{types[name]}`",
             *(kinds.get((name, mode), "") for mode in MODES)) for name in STACK]
    return "\n".join(_table(("name", "type", *MODES), rows))


def markdown() -> str:
    """docs/node.md: the tables above as Markdown."""
    lines = ["# The dynamics node", "",
             "<!-- Generated by `python -m youbot_dynamics.node.interface > docs/node.md`; do not edit. -->", "",
             "`dynamics_node` runs in one of two modes (parameter `mode`): **simulate** integrates a scene and "
             "publishes its motion; **inverse** computes joint torques from measured `/joint_states`. Run it with "
             "`ros2 run youbot_dynamics dynamics_node --ros-args --params-file config/dynamics_node.yaml` or "
             "`python -m youbot_dynamics.ros.dynamics_node --ros-args -p scene:=arm_swing`; `dynamics_node --help` "
             "prints the parameters below, `dynamics_node --managed` runs it as a lifecycle node (ros.md).", "",
             "Topics are relative names: `--ros-args -r __ns:=/youbot1` moves them under `/youbot1`, except "
             "`/tf`, `/tf_static` and `/diagnostics`, which stay global. Frames carry `frame_prefix`. Stamps are "
             "node time: simulated time in simulate mode, the sender's stamps in inverse mode.", "",
             "## Topics", "", *_table(("topic", "dir", "type", "QoS", "modes", "carries"),
                                      [_topic_row(topic) for topic in TOPICS]), "",
             "QoS: " + "; ".join(f"{name}: {qos.describe()}" for name, qos in QOS.items())
             + " (latched: late subscribers get the last message)"
             + "; `joint_states_qos`: the profile that parameter names.", "",
             "## Services", "", *_table(("service", "type", "modes", "does"),
                                        [(f"`{s.name}`", f"`{s.type}`", ", ".join(s.modes), s.does)
                                         for s in SERVICES]), "",
             "## Actions", "", *_table(("action", "type", "modes", "does"),
                                       [(f"`{a.name}`", f"`{a.type}`", ", ".join(a.modes) + f" ({FEATURES[a.when]})",
                                         a.does) for a in ACTIONS]), "",
             "## Parameters", "", *_table(("parameter", "type", "default", "range", "description"),
                                          [_parameter_row(name, spec) for name, spec in PARAMETERS.items()]), ""]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.stdout.write(markdown())
