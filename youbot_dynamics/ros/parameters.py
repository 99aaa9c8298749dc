"""The dynamics node's parameters: names, defaults, ranges and descriptions in one table.

Numeric parameters carry a range in their descriptor, so an out-of-range set is refused
with a result (rclpy checks it); string choices are checked by :func:`check_choice`.
Parameters marked read-only fix the node's structure and are set at start-up only
(``--ros-args -p name:=value`` or ``--params-file config/dynamics_node.yaml``).
"""
from __future__ import annotations

from dataclasses import dataclass

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.node import Node

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.node.commands import TIMEOUT_ACTIONS
from youbot_dynamics.ros.qos import SUBSCRIPTION_PROFILES

MODES = ("simulate", "inverse")
AUTO_PREFIX = "auto"
"""``frame_prefix`` value that derives the prefix from the node's namespace."""
CHOICES = {"mode": MODES, "on_timeout": TIMEOUT_ACTIONS, "joint_states_qos": tuple(SUBSCRIPTION_PROFILES)}


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
    "frame_id": Spec("", "frame of /ee_pose and /free_bodies, root of /tf, used as given ('' : the URDF root link, "
                     "world without a robot, with frame_prefix)"),
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
                           "stencil; a longer gap or a stamp back in time restarts the estimate", (1.0e-4, 60.0)),
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
}


def descriptor(name: str, spec: Spec) -> ParameterDescriptor:
    """The ParameterDescriptor of one parameter (with its range, if numeric)."""
    extra = {}
    if spec.limits is not None and isinstance(spec.default, int):
        extra["integer_range"] = [IntegerRange(from_value=int(spec.limits[0]), to_value=int(spec.limits[1]), step=1)]
    elif spec.limits is not None:
        extra["floating_point_range"] = [FloatingPointRange(from_value=spec.limits[0], to_value=spec.limits[1])]
    choices = CHOICES.get(name)
    return ParameterDescriptor(name=name, description=spec.description, read_only=spec.read_only,
                               additional_constraints=f"one of: {', '.join(choices)}" if choices else "", **extra)


def check_choice(name: str, value: object) -> str | None:
    """Why ``value`` is not allowed for ``name`` (None if it is)."""
    choices = CHOICES.get(name)
    if choices is not None and value not in choices:
        return f"parameter {name}: {value!r} is not one of {', '.join(choices)}"
    return None


def frame_prefix_of(value: str, namespace: str) -> str:
    """The frame prefix ``frame_prefix`` = ``value`` means for a node in ``namespace``:
    ``value`` itself, or for :data:`AUTO_PREFIX` the namespace without its leading slash
    plus "/" (``/youbot1`` -> ``youbot1/``; the root namespace ``/`` -> no prefix)."""
    if value != AUTO_PREFIX:
        return value
    return "" if namespace == "/" else namespace.lstrip("/") + "/"


def declare_all(node: Node) -> dict[str, object]:
    """Declare every parameter on ``node``; returns their values. A bad choice raises
    UserInputError naming the parameter."""
    values = {}
    for name, spec in PARAMETERS.items():
        values[name] = node.declare_parameter(name, spec.default, descriptor(name, spec)).value
        problem = check_choice(name, values[name])
        if problem:
            raise UserInputError(problem)
    return values
