"""control_msgs/GripperCommand goals as ros2_control's gripper_action_controller runs them,
without ROS, on the gripper's finger joints (every joint of the ``gripper_controller`` group).

- ``position`` (m, or rad for a revolute finger) is every finger joint's target; outside the
  joints' limits the goal is rejected. The fingers move there at their URDF velocity limit
  (a trajectory through the scene's controller).
- ``max_effort`` (N, N m) caps the controller's force on each finger while the goal runs and
  after it (until the next goal); 0 or less: the URDF effort limit.
- Each published sample: ``position`` the fingers' mean position, ``effort`` the largest
  absolute force the controller applies on a finger (N), ``reached_goal`` every finger within
  ``goal_tolerance`` of the target, ``stalled`` a finger pad touching something (the contact
  state of the scene's pairs on the finger links) with every finger slower than
  ``STALL_VELOCITY`` for ``stall_timeout``.
- The goal succeeds once reached; stalled, it succeeds with ``allow_stalling`` and aborts
  otherwise (gripper_action_controller's default), and the fingers keep pressing, capped
  by max_effort.

A ``position`` just inside the object keeps each finger's servo a spring below the cap, which
centres the object; two fingers both at the cap are two equal force sources that hold it by
friction but leave its place between them free (docs/ros.md, "Controllers: actions and
forward commands").
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.node.commands import InputRejected, joint_trajectory
from youbot_dynamics.node.controller_groups import Hold, command_group

STALL_VELOCITY = 0.001
"""Finger speed (m/s, rad/s) below which a blocked finger counts as stalled
(gripper_action_controller's ``stall_velocity_threshold``)."""


@dataclass(frozen=True)
class GripperState:
    """A GripperCommand feedback or result: mean finger ``position``, largest finger
    ``effort`` (absolute), ``stalled``, ``reached_goal``."""

    position: float
    effort: float
    stalled: bool
    reached_goal: bool


def finger_pairs(scene, links: Sequence[str]) -> frozenset[str]:
    """Names of the scene's contact pairs with a geometry on one of ``links``."""
    on_links = {g.name for g in scene.geometries if g.owner == "link" and g.owner_name in links}
    return frozenset(pair.name for pair in scene.contacts if {pair.geometry1, pair.geometry2} & on_links)


class GripperGoal:
    """One GripperCommand goal: :meth:`start` checks it and moves the fingers; each
    published sample :meth:`update` gives the state and, once decided, the status
    (``succeeded`` or ``aborted``)."""

    def __init__(self, session, group: str, joints: Sequence[str], target: float, tolerance: float,
                 stall_timeout_ns: int, allow_stalling: bool) -> None:
        robot = session.robot
        self.session, self.group = session, group
        self.index = np.array([robot.joint_index(name) for name in joints])
        self.target, self.tolerance = float(target), float(tolerance)
        self.stall_timeout_ns, self.allow_stalling = stall_timeout_ns, allow_stalling
        links = [joint.child for joint in robot.tree if joint.name in joints]
        self.pairs = finger_pairs(session.scene, links)
        self.slow_since: int | None = None

    @classmethod
    def start(cls, session, group: str, joints: Sequence[str], position: float, max_effort: float,
              tolerance: float, stall_timeout: float, allow_stalling: bool) -> GripperGoal:
        """Check the goal (raises :class:`InputRejected`) and move the fingers to
        ``position`` with their force capped at ``max_effort``."""
        robot = session.robot
        self = cls(session, group, joints, position, tolerance, round(stall_timeout * NS_PER_S), allow_stalling)
        if not (np.isfinite(position) and np.isfinite(max_effort)):
            raise InputRejected("non_finite", f"gripper goal position {position}, max_effort {max_effort}")
        q_now = session.snapshot.q
        travel = np.abs(position - q_now[self.index])
        speed = np.asarray(robot.velocity_limit)[self.index]
        duration_ns = max(1, round(float(np.max(travel / np.where(speed > 0, speed, np.inf))) * NS_PER_S))
        trajectory = joint_trajectory(robot, list(joints), [(duration_ns, [position] * len(joints), [])],
                                      session.stamp_ns - session.epoch_ns, q_now)
        limit = np.full(robot.nv, np.inf)
        if max_effort > 0.0:
            limit[self.index] = max_effort
        command_group(session.simulator, group, self.index, trajectory, limit)
        session.commands.clear()
        return self

    def update(self) -> tuple[GripperState, str | None]:
        """The fingers' state at the published sample, and ``succeeded`` / ``aborted`` once
        decided (None while running)."""
        snapshot, now = self.session.snapshot, self.session.stamp_ns
        q, v = snapshot.q[self.index], snapshot.v[self.index]
        reached = bool(np.all(np.abs(q - self.target) <= self.tolerance))
        touching = bool(self.pairs & self.session.simulator.state.touching)
        slow = touching and bool(np.all(np.abs(v) < STALL_VELOCITY))
        self.slow_since = (self.slow_since if self.slow_since is not None else now) if slow else None
        stalled = not reached and self.slow_since is not None and now - self.slow_since >= self.stall_timeout_ns
        state = GripperState(float(np.mean(q)), float(np.max(np.abs(snapshot.tau[self.index]))), stalled, reached)
        if reached:
            return state, "succeeded"
        if stalled:
            return state, "succeeded" if self.allow_stalling else "aborted"
        return state, None

    def hold(self) -> None:
        """Hold the fingers where they are (after a cancel), the force cap unchanged."""
        command_group(self.session.simulator, self.group, self.index, Hold(self.session.snapshot.q))
