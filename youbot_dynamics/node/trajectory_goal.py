"""control_msgs/FollowJointTrajectory goals as ros2_control's joint_trajectory_controller
(JTC, Jazzy) runs them, without ROS: checking a goal, its tolerances, following it through
the scene's controller and deciding its result.

- Joint names in any order; each must be one of the controller's joints (unknown, repeated
  or missing ones: ``INVALID_JOINTS``; JTC's ``allow_partial_joints_goal`` is false).
- Points: checked as /joint_trajectory's (:func:`~youbot_dynamics.node.commands.joint_trajectory`:
  finite, within the joint limits, times strictly increasing): otherwise ``INVALID_GOAL``.
  A header stamp of 0 starts the trajectory now; a stamp whose trajectory ends before now is
  ``OLD_HEADER_TIMESTAMP``.
- Tolerances (control_msgs/JointTolerance per joint, by name): 0 keeps the default, -1
  switches the check off, a positive value replaces the default; any other negative value
  (or a name that is not the controller's) is ``INVALID_GOAL``. Defaults: path tolerances
  off, goal position tolerance off, goal velocity tolerance ``stopped_velocity_tolerance``
  (JTC's default: 0.01). Accelerations are not checked (the samples carry none, as a youBot
  without an acceleration state interface).
- While the trajectory runs, an error beyond a path tolerance aborts it
  (``PATH_TOLERANCE_VIOLATED``); after its last point it succeeds (``SUCCESSFUL``) as soon
  as every joint is within the goal tolerances, and aborts (``GOAL_TOLERANCE_VIOLATED``) if
  it is not once ``goal_time_tolerance`` has passed (0: the node's default; the default 0
  waits indefinitely, as JTC's ``constraints.goal_time``). An aborted or cancelled goal
  leaves the joints holding where they are.
- Feedback per published sample: desired, actual and error (desired - actual) positions and
  velocities, joint names in the controller's order.

Stamps are node time (simulated time, ns); see :mod:`youbot_dynamics.node.commands`.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.node.commands import InputRejected, joint_trajectory, node_time_of_stamp
from youbot_dynamics.node.controller_groups import Hold, command_group

SUCCESSFUL, INVALID_GOAL, INVALID_JOINTS, OLD_HEADER_TIMESTAMP = 0, -1, -2, -3
PATH_TOLERANCE_VIOLATED, GOAL_TOLERANCE_VIOLATED = -4, -5
"""control_msgs/FollowJointTrajectory result codes."""
JOINT_PROBLEMS = frozenset({"unknown_joint", "duplicate_joint", "missing_joint"})
"""Kinds of rejected input that are ``INVALID_JOINTS``; every other kind is ``INVALID_GOAL``."""
STOPPED_VELOCITY_TOLERANCE = 0.01
"""JTC's default ``constraints.stopped_velocity_tolerance`` (rad/s, m/s)."""
NO_CHECK = -1.0
"""A JointTolerance value that switches the check off."""


class GoalRejected(Exception):
    """A goal that cannot run: ``code`` (a result code) and the error string."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code


@dataclass(frozen=True)
class Outcome:
    """How a goal ended: ``status`` (succeeded, aborted, canceled), result ``code``, error
    string."""

    status: str
    code: int
    message: str = ""


def resolve_tolerances(joints: Sequence[str], defaults: np.ndarray,
                       given: Sequence[tuple[str, float, float, float]], what: str) -> np.ndarray:
    """Per-joint (position, velocity, acceleration) tolerances (k, 3) of the controller's
    ``joints``: ``defaults`` (k, 3) changed by the goal's ``given`` (name, position,
    velocity, acceleration) as JTC does (0: default, -1: off, positive: that value). An
    entry switched off is 0 (unchecked). Raises :class:`GoalRejected` (``INVALID_GOAL``)."""
    tolerances = np.array(defaults, dtype=float)
    for name, *values in given:
        if name not in joints:
            raise GoalRejected(INVALID_GOAL, f"{what} names joint {name!r}, not one of the controller's "
                               f"({', '.join(joints)})")
        row = joints.index(name)
        for column, value in enumerate(values):
            if not np.isfinite(value) or (value < 0.0 and value != NO_CHECK):
                raise GoalRejected(INVALID_GOAL, f"{what} of {name}: {value} is neither -1, 0 nor positive")
            if value == NO_CHECK:
                tolerances[row, column] = 0.0
            elif value > 0.0:
                tolerances[row, column] = value
    return tolerances


def _violations(error: np.ndarray, tolerances: np.ndarray, joints: Sequence[str]) -> list[str]:
    """The joints whose position or velocity error (2, k) exceeds a checked (positive)
    tolerance (k, 3), as ``name position|velocity error > tolerance``."""
    found = []
    for column, quantity in enumerate(("position", "velocity")):
        limit = tolerances[:, column]
        for k in np.flatnonzero((limit > 0.0) & (np.abs(error[column]) > limit)):
            found.append(f"{joints[k]} {quantity} error {error[column, k]:.6g} > {limit[k]:g}")
    return found


class TrajectoryGoal:
    """One accepted FollowJointTrajectory goal, run by the session's scene controller.

    Built by :meth:`start` (checks, then makes the group follow the trajectory); each
    published sample, :meth:`update` gives the feedback and, once decided, the
    :class:`Outcome`."""

    def __init__(self, session, group: str, joints: Sequence[str], end_ns: int, path: np.ndarray,
                 goal: np.ndarray, goal_time_ns: int) -> None:
        self.session, self.group, self.joints = session, group, tuple(joints)
        self.index = np.array([session.robot.joint_index(name) for name in joints])
        self.end_ns, self.path, self.goal, self.goal_time_ns = end_ns, path, goal, goal_time_ns

    @classmethod
    def start(cls, session, group: str, joints: Sequence[str], names: Sequence[str],
              points: Sequence[tuple[int, Sequence[float], Sequence[float]]], stamp_ns: int,
              path_tolerance: Sequence[tuple[str, float, float, float]],
              goal_tolerance: Sequence[tuple[str, float, float, float]], goal_time_tolerance_ns: int,
              default_goal_time_ns: int = 0, stopped_velocity: float = STOPPED_VELOCITY_TOLERANCE
              ) -> TrajectoryGoal:
        """Check a goal (the fields of control_msgs/FollowJointTrajectory.Goal: joint names,
        points as (time_from_start ns, positions, velocities), header stamp ns, tolerances as
        (name, position, velocity, acceleration), goal_time_tolerance ns) for the
        controller ``group`` of ``joints``, and start it. Raises :class:`GoalRejected`."""
        joints = list(joints)
        foreign = [str(name) for name in names if str(name) not in joints]
        if foreign:
            raise GoalRejected(INVALID_JOINTS, f"joint(s) {', '.join(foreign)} are not the controller's "
                               f"({', '.join(joints)})")
        if len(set(names)) == len(names) and len(names) != len(joints):
            raise GoalRejected(INVALID_JOINTS, f"the goal names {len(names)} of the controller's {len(joints)} "
                               f"joints ({', '.join(joints)}); partial goals are not allowed")
        k = len(joints)
        path = resolve_tolerances(joints, np.zeros((k, 3)), path_tolerance, "path_tolerance")
        goal_defaults = np.zeros((k, 3))
        goal_defaults[:, 1] = stopped_velocity
        goal = resolve_tolerances(joints, goal_defaults, goal_tolerance, "goal_tolerance")
        if goal_time_tolerance_ns < 0:
            raise GoalRejected(INVALID_GOAL, f"goal_time_tolerance is negative ({goal_time_tolerance_ns} ns)")
        now_ns = session.stamp_ns
        try:
            start_ns = node_time_of_stamp(stamp_ns, now_ns, 2**62, "goal")
            if points and stamp_ns != 0 and start_ns + int(points[-1][0]) < now_ns:
                raise GoalRejected(OLD_HEADER_TIMESTAMP, f"the trajectory stamped {start_ns / NS_PER_S:.6f} s ends "
                                   f"{(now_ns - start_ns - int(points[-1][0])) / NS_PER_S:.6f} s before now "
                                   f"({now_ns / NS_PER_S:.6f} s)")
            start_ns = max(start_ns, now_ns)
            trajectory = joint_trajectory(session.robot, names, points, start_ns - session.epoch_ns,
                                          session.snapshot.q)
        except InputRejected as error:
            raise GoalRejected(INVALID_JOINTS if error.kind in JOINT_PROBLEMS else INVALID_GOAL, str(error)) from None
        goal_time_ns = goal_time_tolerance_ns or default_goal_time_ns
        self = cls(session, group, joints, start_ns + trajectory.offsets_ns[-1], path, goal, goal_time_ns)
        try:
            command_group(session.simulator, group, self.index, trajectory)
        except InputRejected as error:
            raise GoalRejected(INVALID_GOAL, str(error)) from None
        session.commands.clear()
        return self

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Desired and actual (2, k) positions and velocities of the published sample."""
        q_d, v_d, _ = self.session.simulator.state.reference.at(self.session.scene_time)
        snapshot = self.session.snapshot
        desired = np.array([np.asarray(q_d)[self.index], np.asarray(v_d)[self.index]])
        return desired, np.array([snapshot.q[self.index], snapshot.v[self.index]])

    def update(self) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], Outcome | None]:
        """Feedback of the published sample, (desired, actual, error) each (2, k) positions
        and velocities, and the outcome once decided (an aborted goal holds the joints)."""
        desired, actual = self.state()
        error = desired - actual
        now_ns = self.session.stamp_ns
        outcome = None
        if now_ns < self.end_ns:
            violated = _violations(error, self.path, self.joints)
            if violated:
                outcome = Outcome("aborted", PATH_TOLERANCE_VIOLATED, "path tolerance violated: " + "; ".join(violated))
        else:
            violated = _violations(error, self.goal, self.joints)
            if not violated:
                outcome = Outcome("succeeded", SUCCESSFUL)
            elif self.goal_time_ns and now_ns > self.end_ns + self.goal_time_ns:
                outcome = Outcome("aborted", GOAL_TOLERANCE_VIOLATED,
                                  f"goal tolerance violated {(now_ns - self.end_ns) / NS_PER_S:.6f} s after the "
                                  "trajectory's end: " + "; ".join(violated))
        if outcome is not None and outcome.status == "aborted":
            self.hold()
        return (desired, actual, error), outcome

    def hold(self) -> None:
        """Hold the group's joints where they are (after an abort, a cancel, a preemption)."""
        command_group(self.session.simulator, self.group, self.index, Hold(self.session.snapshot.q))
