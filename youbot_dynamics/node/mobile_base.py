"""The moving base on ROS (REP-105), without rclpy: /cmd_vel in; /odom, the
odom -> base_footprint transform and the ground-truth pose out.

- ``/cmd_vel`` (geometry_msgs/Twist, body frame): vx, vy and wz are the base's twist; a
  non-finite value, a speed beyond ``MAX_LINEAR`` / ``MAX_ANGULAR`` or a non-zero vz, wx or
  wy (the base moves in the plane only) is rejected and counted like /joint_commands'. A
  command is held for the session's command timeout, then the base is told to stop (the
  zero twist), never left running. Before the first command the scene's base path (or rest)
  is followed. The base reaches each command within the scene's a_max (kinematic and
  dynamic: :class:`~youbot_dynamics.dynamics.mobile.ramp.TwistRamp` from the twist it was
  commanded at that instant).
- ``/odom`` (nav_msgs/Odometry): the pose of base_footprint in odom from wheel odometry (the
  measured wheel speeds of each sample held over the increment to the next, integrated
  exactly on SE(2) by :func:`~youbot_dynamics.dynamics.mobile.odometry.odometry_step`), the
  twist in base_footprint (the least-squares twist of the wheel speeds), covariances
  ``POSE_COVARIANCE`` and ``TWIST_COVARIANCE``. The odom frame is the world frame at the
  start: odometry starts at the base's true initial pose, and restarts there on reset.
- ``/tf`` carries odom -> base_footprint with the /odom pose, and odom -> world (the
  odometry's drift: where the true world frame is in odom), every sample
  (:func:`~youbot_dynamics.node.frames.frame_tree`).
- ``/base_pose_ground_truth`` (nav_msgs/Odometry, frame world): the simulated pose and twist
  (zero covariance), so that odometry drift can be measured.
- /diagnostics ``base.slip`` (m/s): over the samples since the previous report, the largest
  speed, at a wheel hub, of the difference between the /odom twist and the true one (wheels
  that roll without slip give the true twist exactly); WARN above ``SLIP_WARN``.

:class:`WheelOdometry` is the odometry alone (/odom and its transform from wheel speeds):
the simulate mode feeds it the simulated wheel speeds, the inverse mode those of the
/joint_states it receives, so a recorded run replayed into an inverse-mode node gives the
recorded /odom again. Both odometry messages refill their CDR template after the first
(:class:`~youbot_dynamics.io.cdr_template.Refilled`; the covariances stay the first's).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from youbot_dynamics.dynamics.mobile.mecanum import MecanumBase, base_twist
from youbot_dynamics.dynamics.mobile.odometry import se2_step
from youbot_dynamics.dynamics.mobile.ramp import TwistRamp
from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_group import Entry
from youbot_dynamics.io.cdr_template import Refilled, not_covariance
from youbot_dynamics.node.commands import InputCounters, InputRejected
from youbot_dynamics.node.frames import ODOM_FRAME, WORLD_FRAME, planar_row
from youbot_dynamics.sim.engine import Snapshot
from youbot_dynamics.sim.mobile_base import BaseModel

#: Largest accepted speed (m/s) and turn rate (rad/s) on /cmd_vel (the youBot drives at up
#: to about 0.8 m/s).
MAX_LINEAR, MAX_ANGULAR = 5.0, 10.0
#: Slip (m/s at a wheel hub) above which /diagnostics warns: the regularised rollers' creep
#: stays below 0.025 m/s while the dynamic scenes drive (mobile_pick 0.005; base_spin_arm
#: accelerating at its a_max 0.023); 0.05 m/s is an odometry drift of 5 cm per second.
SLIP_WARN = 0.05
#: /odom covariances (row-major 6x6 diagonals: x, y, z, rotation about x, y, z), the values
#: of ros2_controllers' diff_drive_controller defaults.
POSE_COVARIANCE = np.diag([1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-2]).ravel()
TWIST_COVARIANCE = np.diag([1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-2]).ravel()


def odometry_values(row: np.ndarray, twist: tuple[float, float, float]) -> np.ndarray:
    """The refilled fields of a planar nav_msgs/Odometry in field order: the pose ``row``
    (x, y, 0, quaternion x, y, z, w), then the twist (vx, vy, 0, 0, 0, wz) of ``twist``
    (vx, vy m/s, wz rad/s)."""
    return np.array([*row, twist[0], twist[1], 0.0, 0.0, 0.0, twist[2]])


class WheelOdometry:
    """Wheel odometry of a mecanum base from ``pose0`` (x, y, yaw in odom): each sample's
    wheel speeds (rad/s, ``mecanum.names`` order) held over the increment to the next, if
    that increment is a step of one stream: later than the last sample and at most
    ``max_gap`` (s) after it. Across a break (a stamp back in time, a pause, a one-off
    wall-clock stamp) the pose holds and the odometry goes on from the new sample."""

    def __init__(self, mecanum: MecanumBase, pose0, prefix: str = "", base_link: str = "base_footprint",
                 max_gap: float = math.inf) -> None:
        self.mecanum, self.pose0, self.max_gap = mecanum, np.array(pose0, dtype=float), float(max_gap)
        self.odom_frame, self.child_frame = prefix + ODOM_FRAME, prefix + base_link
        self.odom_messages = Refilled(not_covariance)
        """/odom's refilled template."""
        self.reset()

    def reset(self) -> None:
        """Back to the initial pose, no sample seen."""
        self.pose = self.pose0.copy()
        #: the last sample: (t s, its base twist (vx, vy, wz) from its wheel speeds)
        self.last: tuple[float, np.ndarray] | None = None

    def outputs(self, stamp_ns: int, t: float, speeds: np.ndarray) -> tuple[object, np.ndarray]:
        """(/odom, the row (7,) of odom -> base_footprint: translation m, quaternion x, y, z,
        w) of a sample at time t (s) with wheel speeds ``speeds``; advances the pose
        (``pose``: x, y, yaw in odom) by the previous sample's speeds."""
        twist, row = self.advance(t, speeds)
        odom = self.odom_messages(stamp_ns, odometry_values(row, (twist[0], twist[1], twist[2])), self.build_odom)
        return odom, row

    def advance(self, t: float, speeds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the sample's base twist (vx, vy, wz) from its wheel ``speeds``, the row (7,) of
        odom -> base_footprint) of a sample at time t (s); advances the pose by the previous
        sample's twist (see :meth:`outputs`)."""
        self.pose, self.last = self._advanced(self.pose, self.last, t, speeds)
        return self.last[1], planar_row(*self.pose)

    def build_odom(self, stamp_ns: int, values: np.ndarray) -> object:
        """/odom at ``stamp_ns`` from its refilled ``values`` (:func:`odometry_values`)."""
        return messages.odometry(stamp_ns, self.odom_frame, self.child_frame, values[:3], values[3:7], values[7:],
                                 POSE_COVARIANCE, TWIST_COVARIANCE)

    def _advanced(self, pose: np.ndarray, last: tuple[float, np.ndarray] | None, t: float, speeds: np.ndarray
                  ) -> tuple[np.ndarray, tuple[float, np.ndarray]]:
        """(pose, last sample) after a sample at t (s) with wheel ``speeds``: ``pose`` (x, y,
        yaw) moved by the ``last`` sample's twist held since its time, unless the stream
        broke between them (see the class): :func:`~youbot_dynamics.dynamics.mobile.odometry
        .odometry_step`'s arithmetic, each sample's twist computed once."""
        if last is not None and 0.0 <= t - last[0] <= self.max_gap:  # t - last[0] finite: times of stamps
            pose = se2_step(pose, last[1], t - last[0])
        return pose, (t, base_twist(self.mecanum, np.array(speeds, dtype=float)))

    def preview(self, times: Sequence[float], speeds: Sequence[np.ndarray]) -> np.ndarray:
        """Rows (k, 7) of odom -> base_footprint that :meth:`outputs` would give for the next k
        samples (times s, wheel speeds), without advancing: the same arithmetic, so the
        same bits."""
        pose, last, rows = self.pose, self.last, np.empty((len(times), 7))
        for k, (t, wheel_speeds) in enumerate(zip(times, speeds)):
            pose, last = self._advanced(pose, last, t, wheel_speeds)
            rows[k] = planar_row(*pose)
        return rows


@dataclass(frozen=True)
class BaseSample:
    """A moving base's outputs of one sample (:meth:`MobileBase.sample`): the refilled values
    (:func:`odometry_values`) of /odom and of /base_pose_ground_truth, the rows (2, 7) of
    odom -> base_footprint and odom -> world, and the sample's slip (m/s, the largest hub
    speed of the difference between the /odom twist and the true one)."""

    odom: np.ndarray
    truth: np.ndarray
    rows: np.ndarray
    slip: float


class MobileBase:
    """/cmd_vel, wheel odometry and the base's outputs of a session whose scene has a moving
    ``base``; ``wheels`` are the wheel joints' indices in the snapshot's v."""

    def __init__(self, base: BaseModel, counters: InputCounters, timeout: float, prefix: str = "",
                 base_link: str = "base_footprint") -> None:
        self.base, self.counters, self.timeout = base, counters, float(timeout)
        self.odometry = WheelOdometry(base.mecanum, base.pose0, prefix, base_link)
        self.world_frame = prefix + WORLD_FRAME
        self._truth = Refilled(not_covariance)
        self.reset()

    def reset(self) -> None:
        """Forget the command; odometry back to the base's initial pose."""
        self.command: np.ndarray | None = None
        self.command_time = -math.inf
        self.ramp: TwistRamp | None = None
        self.slip = 0.0
        self.odometry.reset()

    # ---- /cmd_vel ---------------------------------------------------------------------------
    def accept(self, linear, angular, t: float) -> None:
        """A /cmd_vel twist (linear and angular, 3 each, body frame) received at simulated
        time t (s); raises and counts :class:`InputRejected`."""
        try:
            values = np.array([*linear, *angular], dtype=float)
            if values.shape != (6,) or not np.all(np.isfinite(values)):
                raise InputRejected("non_finite", f"/cmd_vel: {values.tolist()} must be 6 finite numbers")
            if np.any(values[[2, 3, 4]] != 0.0):
                raise InputRejected("out_of_limits", "/cmd_vel: linear.z, angular.x and angular.y must be 0 (the "
                                    "base moves in the plane)")
            if math.hypot(values[0], values[1]) > MAX_LINEAR or abs(values[5]) > MAX_ANGULAR:
                raise InputRejected("out_of_limits", f"/cmd_vel: speed {math.hypot(values[0], values[1]):.3g} m/s "
                                    f"and turn rate {abs(values[5]):.3g} rad/s must be within {MAX_LINEAR} m/s and "
                                    f"{MAX_ANGULAR} rad/s")
        except InputRejected as error:
            self.counters.reject(error)
            raise
        self.counters.accepted += 1
        self.command, self.command_time = values[[0, 1, 5]], t

    def twist(self, t: float) -> TwistRamp | None:
        """The twist command the base is to follow from t (s): toward the last command
        within the timeout, toward the zero twist after it (stop), from the twist commanded
        at t, within the base's a_max; None before any command (the scene's path)."""
        if self.command is None:
            return None
        target = self.command if t - self.command_time <= self.timeout else np.zeros(3)
        if self.ramp is None:
            self.ramp = TwistRamp(t, self.base.command(t)[1], target, self.base.a_max)
        self.ramp = self.ramp.toward(t, target)
        return self.ramp

    # ---- outputs ---------------------------------------------------------------------------
    def sample(self, t: float, snapshot: Snapshot) -> BaseSample:
        """The outputs of the sample at simulated time t (s) (:class:`BaseSample`); advances
        the odometry by the previous sample's wheel speeds (call once per sample, in order;
        :meth:`track_slip` when the sample is published). odom -> world is
        T_odom_base(odometry) T_world_base(true)^-1, a planar pose: yaw e - yaw t,
        p_e - R(yaw e - yaw t) p_t."""
        twist, row = self.odometry.advance(t, snapshot.v[self.base.wheels])
        x, y, yaw = self.odometry.pose
        tx, ty, tyaw, vx, vy, wz = snapshot.base
        drift = yaw - tyaw
        c, s = math.cos(drift), math.sin(drift)
        rows = np.array([row, planar_row(x - (c * tx - s * ty), y - (s * tx + c * ty), drift)])
        slip = float(np.max(np.linalg.norm(self.base.mecanum.hub_velocities(twist - snapshot.base[3:]), axis=1)))
        return BaseSample(odometry_values(row, (twist[0], twist[1], twist[2])),
                          odometry_values(planar_row(tx, ty, tyaw), (vx, vy, wz)), rows, slip)

    def entries(self, samples: Sequence[BaseSample], wanted: frozenset[str] | set[str]) -> list[Entry]:
        """/odom and /base_pose_ground_truth of N ``samples``, those in ``wanted``, as
        :data:`~youbot_dynamics.io.cdr_group.Entry`."""
        entries: list[Entry] = []
        if "/odom" in wanted:
            entries.append(("/odom", self.odometry.odom_messages, np.array([sample.odom for sample in samples]),
                            self.odometry.build_odom))
        if "/base_pose_ground_truth" in wanted:
            entries.append(("/base_pose_ground_truth", self._truth, np.array([sample.truth for sample in samples]),
                            self._build_truth))
        return entries

    def _build_truth(self, stamp_ns: int, values: np.ndarray) -> object:
        """/base_pose_ground_truth at ``stamp_ns`` from its refilled ``values``."""
        return messages.odometry(stamp_ns, self.world_frame, self.odometry.child_frame, values[:3], values[3:7],
                                 values[7:], np.zeros(36), np.zeros(36))

    def track_slip(self, sample: BaseSample) -> None:
        """Count a published sample's slip in ``base.slip`` (the largest since the report)."""
        self.slip = max(self.slip, sample.slip)

    def report(self) -> tuple[str, dict[str, float]]:
        """(level, /diagnostics values) of the base since the previous report: ``base.slip``
        (m/s) and WARN above ``SLIP_WARN`` (else OK); starts the next window."""
        slip, self.slip = self.slip, 0.0
        return ("WARN" if slip > SLIP_WARN else "OK"), {"base.slip": slip}
