"""The joint groups that ros2_control-style controllers command (``arm_controller``,
``gripper_controller``) and the reference that lets each group follow its own command.

A group's joints come from a node parameter (comma-separated joint names) or, when it is
empty, from the robot: the moving joints named ``<prefix>arm_joint_1`` .. ``_5`` of the first
youBot (composition order) make the arm, its ``<prefix>gripper_finger_joint_l`` / ``_r`` the
gripper (moving only where the scene moves them, as gripping does). A group with no moving
joint is absent, and so are its actions and topics.

:class:`GroupedTrajectory` is the scene controller's reference once a group is commanded: each
group follows its own trajectory (a :class:`~youbot_dynamics.node.commands.SampledTrajectory`
over every joint, of which the group's columns are used) and every other joint holds the
desired position it had when the first group took over. So a gripper goal does not stop the
arm's trajectory, and an arm goal does not loosen the grip. A /joint_trajectory message
replaces the whole reference (every group with it), as before.
"""
from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.sim.controllers import Reference

GROUP_PATTERNS = {"arm_controller": r"arm_joint_[1-5]", "gripper_controller": r"gripper_finger_joint_[lr]"}
"""Joint-name endings of each controller's joints (after the youBot's prefix)."""


def group_joints(robot: Robot, controller: str, listed: str) -> tuple[str, ...]:
    """The joints of ``controller`` (a key of :data:`GROUP_PATTERNS`): ``listed``
    (comma-separated names, each a moving joint of the robot, else UserInputError naming
    it) or, if empty, the first youBot's moving joints of that pattern."""
    if listed.strip():
        names = tuple(name.strip() for name in listed.split(",") if name.strip())
        unknown = [name for name in names if name not in robot.joint_names]
        if unknown:
            raise UserInputError(f"{controller}: no moving joint(s) {', '.join(unknown)} "
                             f"(moving joints: {', '.join(robot.joint_names)})")
        return names
    pattern = re.compile(rf"(.*){GROUP_PATTERNS[controller]}$")
    matches = [(m.group(1), name) for name in robot.joint_names if (m := pattern.fullmatch(name))]
    prefix = matches[0][0] if matches else ""
    return tuple(name for p, name in matches if p == prefix)


@dataclass(frozen=True)
class GroupedTrajectory:
    """Per-group trajectories over a held posture: ``hold`` (rad, m; joint order) for the
    joints of no group, ``parts`` a mapping group -> (joint indices, trajectory with
    ``evaluate(t)``). Duck-types :class:`~youbot_dynamics.sim.trajectory.PointToPointTrajectory`
    (``evaluate``)."""

    hold: np.ndarray
    parts: tuple[tuple[str, np.ndarray, object], ...]

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Desired position, velocity and acceleration (n,) at simulated time t (s)."""
        q, v, a = self.hold.copy(), np.zeros(self.hold.size), np.zeros(self.hold.size)
        for _, index, trajectory in self.parts:
            q_d, v_d, a_d = trajectory.evaluate(t)
            q[index], v[index], a[index] = q_d[index], v_d[index], a_d[index]
        return q, v, a


class Hold:
    """A constant position (rad, m; joint order) as a trajectory."""

    def __init__(self, q: np.ndarray) -> None:
        self.q = np.array(q, dtype=float)

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.q.copy(), np.zeros(self.q.size), np.zeros(self.q.size)


class Ramp:
    """Constant velocities ``rate`` (rad/s, m/s; joint order) from ``q0`` at simulated time
    ``t0`` (s), each joint stopping at its limit (``lower``, ``upper``): a velocity command
    as a trajectory."""

    def __init__(self, q0: np.ndarray, rate: np.ndarray, t0: float, lower: np.ndarray, upper: np.ndarray) -> None:
        self.q0, self.rate, self.t0 = np.array(q0, dtype=float), np.array(rate, dtype=float), float(t0)
        self.lower, self.upper = lower, upper

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q = self.q0 + self.rate * max(0.0, t - self.t0)
        inside = (self.lower < q) & (q < self.upper)
        return np.clip(q, self.lower, self.upper), np.where(inside, self.rate, 0.0), np.zeros(q.size)


def command_group(simulator, group: str, index: Sequence[int], trajectory: object,
                  effort_limit: np.ndarray | None = None) -> None:
    """Make the joints ``index`` (joint order) of ``group`` follow ``trajectory`` (an
    ``evaluate(t)`` over every joint, simulated time in s), the other groups keeping theirs;
    ``effort_limit`` (N m, N; per joint, or None: unchanged) caps the controller's torque on
    the group's joints. Raises :class:`InputRejected` (``no_controller``) for a scene without a
    tracking controller."""
    if simulator.controller.kind == "none":
        raise InputRejected("no_controller", "the scene has no tracking controller (controller.type: none)")
    reference = simulator.state.reference
    index = np.asarray(index, dtype=int)
    if isinstance(reference.trajectory, GroupedTrajectory):
        hold, parts = reference.trajectory.hold, [p for p in reference.trajectory.parts if p[0] != group]
    else:
        hold, parts = np.array(reference.at(simulator.t)[0], dtype=float), []
    limit = reference.effort_limit
    if effort_limit is not None:
        limit = np.full(hold.size, np.inf) if limit is None else limit.copy()
        limit[index] = effort_limit[index]
    grouped = GroupedTrajectory(hold, (*parts, (group, index, trajectory)))
    simulator.state.reference = Reference(hold, grouped, reference.base_twist, limit)
