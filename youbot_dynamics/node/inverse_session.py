"""The inverse-mode session: torques from measured joint states, taken in batches (a single
sample is a batch of one). Each batch is checked (:mod:`youbot_dynamics.node.commands`; the
samples that name the joints as the last accepted one did as arrays, and a batch whose every
sample passes in one compiled pass, :func:`~youbot_dynamics.node.inverse.clean_rows`), differenced
(:class:`~youbot_dynamics.node.inverse.AccelerationEstimator`), its torques computed at once
(Pinocchio's batch RNEA and the friction model, :class:`~youbot_dynamics.node.inverse.InverseDynamics`)
and its messages built together; what is built and logged: :mod:`youbot_dynamics.node.session`.

An implausible torque (beyond the effort-limit bound, or not finite) or a message that
cannot be built (non-finite kinematics) is not published and restarts the estimate at its
sample, as if the samples had come one by one: the rows after it are differenced again from
there. A scene with a moving base also gives /odom from the wheel speeds of each sample
taken (:class:`~youbot_dynamics.node.mobile_base.WheelOdometry`), and its tf tree is simulate
mode's (REP 105, :func:`~youbot_dynamics.node.frames.frame_tree`): odom the root, odom ->
base_footprint the wheel odometry at each torque's stamp (the /odom pose), odom -> world the
identity (inverse mode has no ground truth: the world is where the odometry started, drift
unknown), and /ee_pose(s) in odom (the odometry pose times the kinematics). A fixed base
cannot move: no odom frame, the robot's root link is the root, as in simulate mode.
"""
from __future__ import annotations

import math
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from youbot_dynamics.dynamics.mobile.mecanum import mecanum_base_from_robot
from youbot_dynamics.dynamics.rigid_body import kinetic_energy, potential_energy
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_group import Entry, TopicBatches
from youbot_dynamics.io.cdr_template import Refilled
from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.node.commands import STAMP_LIMIT_NS, InputRejected, JointSample, joint_sample
from youbot_dynamics.node.frames import SampleFrames, end_effector_row
from youbot_dynamics.node.interface import Outputs
from youbot_dynamics.node.inverse import (DEFAULT_MAX_GAP_NS, PLAUSIBLE_FACTOR, AccelerationEstimator, Estimates,
                                          InverseDynamics, clean_rows_unchecked, implausible_joints, plausible_limit,
                                          plausible_rows, position_bounds)
from youbot_dynamics.node.mobile_base import WheelOdometry
from youbot_dynamics.node.session import Session
from youbot_dynamics.scene.schema import Scene

JointStateFields = tuple[Sequence[str], Sequence[float], Sequence[float], int, int | None]
"""One /joint_states sample as the node hands it over: (names, position, velocity,
stamp_ns, received_ns)."""
Built = list[tuple[Outputs, SampleFrames | None, np.ndarray | None]]
"""Each torque's messages and, when built and recorded (Rerun), its sample's kinematics; with
a moving base, its rows (2, 7) of odom -> base_footprint and odom -> world."""
IDENTITY_ROW = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
"""The row (translation m, quaternion x, y, z, w) of the identity: odom -> world in inverse mode."""
_WALL_OFFSET_NS = time.time_ns() - time.monotonic_ns()
"""The wall clock minus the monotonic clock when the process started."""


def receive_time_ns() -> int:
    """Now on the node's receive clock (int ns): the monotonic clock, started at the wall
    clock's time when the process started, so it reads as wall time but never jumps back."""
    return time.monotonic_ns() + _WALL_OFFSET_NS


class InverseSession(Session):
    """Torques from measured joint states: accelerations by central differences (see
    :mod:`youbot_dynamics.node.inverse`), tau = RNEA + friction of the scene's robot."""

    mode = "inverse"
    odometry: WheelOdometry | None = None
    """Wheel odometry of a scene with a moving base (/odom from the joint states' wheel speeds)."""

    def __init__(self, scene: Scene, *, filter_time_constant: float = 0.0, max_gap_ns: int = DEFAULT_MAX_GAP_NS,
                 frame_id: str = "", ee_link: str = "", mcap_path: str | Path | None = None,
                 rrd_path: str | Path | None = None, callback_budget: float = 0.05, frame_prefix: str = "",
                 node_name: str = "dynamics_node") -> None:
        robot = scene.robot  # reduced, with the scene's gravity
        if not robot.tree:
            raise UserInputError(f"{scene.source}: inverse mode needs a robot; the scene has none")
        if scene.base.mode != "fixed":  # /odom from the wheel speeds of the joint states
            self.odometry = WheelOdometry(mecanum_base_from_robot(robot, scene.base.wheels), scene.base.pose0,
                                          frame_prefix, max_gap=max_gap_ns / NS_PER_S)
            self.wheels = np.array([robot.joint_index(name) for name in scene.base.wheels])
        super().__init__(scene, robot, frame_id, ee_link, mcap_path, rrd_path, callback_budget, frame_prefix,
                         node_name, moving_base=self.odometry is not None, moving_root=self.odometry is not None)
        self._odometry_row: np.ndarray | None = None     # odom -> base_footprint of the last sample taken
        """odom -> base_footprint (row) of the last sample taken, by stamp (ns): a torque's
        sample precedes the one that completes it."""
        self.known = tuple(j.name for j in self.robot.tree) + self.robot.joint_names
        self.dynamics = InverseDynamics(self.robot, scene.joint_friction(self.robot))
        self._torques = Refilled()
        self._batches = TopicBatches()
        self._names_key: tuple[str, ...] | None = None
        """The names of the last sample accepted through ``joint_sample`` (see
        ``_remember_names``)."""
        self._velocity_bound = plausible_limit(self.robot, "velocity")
        self._effort_bound = plausible_limit(self.robot, "effort")
        self._position_low, self._position_high = position_bounds(self.robot)
        self.estimator = AccelerationEstimator(filter_time_constant, max_gap_ns)
        self.stamp_ns, self.samples, self.log_ns = 0, 0, 0
        """The last torque's stamp (ns), torques published, the last log time (ns)."""
        self._last_taken_ns: int | None = None
        """The stamp (ns) of the last sample taken (a next one stamped the same is a duplicate)."""
        self._input_ns: int | None = None
        self._quiet_since_ns: int | None = None
        """Input time (ns): of the latest sample received, and since which no torque has come."""
        self.last_unstamped = False
        """True when the last sample taken was stamped 0."""

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
        velocity-limit bound, or whose position is outside the joint limits plus a margin
        (:func:`~youbot_dynamics.node.inverse.position_bounds`), is rejected
        (``out_of_limits``); one stamped as the last sample taken is a ``duplicate``, dropped
        without breaking the stencil. A torque that is implausible (beyond the effort-limit
        bound) or not finite is not published: the sample counts as accepted, the torque as
        rejected (``implausible_torque`` or ``non_finite``), and the estimate restarts.
        Everything is logged at the receive time ``received_ns`` (the session's receive
        clock, :func:`receive_time_ns`, when not given), never earlier than what was logged
        before; the messages keep the sender's stamps."""
        outputs, rejected = self.joint_states([(names, position, velocity, stamp_ns, received_ns)])
        if rejected:
            raise rejected[0]
        return outputs

    def joint_states(self, samples: Sequence[JointStateFields]) -> tuple[Outputs, list[InputRejected]]:
        """:meth:`joint_state` of each sample in turn ((names, position, velocity, stamp_ns,
        received_ns)), the same outputs in the same order, the rejected samples' errors
        returned (counted) instead of raised. The samples are checked, differenced and
        their torques computed as arrays (Pinocchio's batch RNEA); a clean batch
        (:meth:`_clean_rows`) is taken in one compiled check."""
        clean = self._clean_rows(samples)
        if clean is not None:
            return self._torques_of_rows(*clean, [True] * len(samples)), []
        log_times = self._log_times(samples)
        self._observe_input(samples)
        stamps, q, v, taken, rejected = self._checked(samples)
        kept = self._without_duplicates(stamps, taken, rejected)
        if kept is not None:
            stamps, taken, log_times = [stamps[k] for k in kept], [taken[k] for k in kept], [log_times[k] for k in kept]
            q, v = q[kept], v[kept]
        return self._torques_of_rows(stamps, q, v, log_times, taken), rejected

    def _torques_of_rows(self, stamps: list[int], q: np.ndarray, v: np.ndarray, log_times: list[int],
                         taken: list[bool]) -> Outputs:
        """The outputs of checked rows (stamps int ns, q and v rows in joint order, which were
        ``taken``, logged at ``log_times``): ``_torques_from`` until every row is done."""
        outputs: Outputs = []
        start = 0
        while start < len(stamps):
            start = self._torques_from(stamps, q, v, taken, log_times, start, outputs)
        return outputs

    def _clean_rows(self, samples: Sequence[JointStateFields]
                    ) -> tuple[list[int], np.ndarray, np.ndarray, list[int]] | None:
        """(stamps, q, v, log times) of a clean batch, counted and observed as ``joint_states``
        would (every sample accepted: stamped with an int in (0, ``STAMP_LIMIT_NS``), none
        stamped as the one taken before it, received at an int time or None, naming the
        joints as the last accepted one did, every value within ``_row_bounds``); None, with
        nothing changed, for any other batch."""
        key, count = self._names_key, len(samples)
        if key is None or not count or not all(tuple(sample[0]) == key for sample in samples):
            return None
        stamps, received = [sample[3] for sample in samples], [sample[4] for sample in samples]
        if set(map(type, stamps)) != {int} or not set(map(type, received)) <= {int, type(None)}:
            return None
        try:
            values = np.array([sample[1] for sample in samples] + [sample[2] for sample in samples], dtype=float)
            stamp_array = np.array(stamps, dtype=np.int64)
        except (ValueError, TypeError, OverflowError):
            return None
        previous = -1 if self._last_taken_ns is None else self._last_taken_ns
        if values.shape != (2 * count, len(key)) or not clean_rows_unchecked(stamp_array, values, self._row_bounds,
                                                                             previous):
            return None
        log_times = self._log_times(samples)
        self._quiet_since_ns = min(stamps) if self._quiet_since_ns is None else min(self._quiet_since_ns, *stamps)
        self._input_ns = stamps[-1]
        self.last_unstamped = False
        self.counters.accepted += count
        self._last_taken_ns = stamps[-1]
        return stamps, values[:count, self._columns], values[count:, self._columns], log_times

    def _log_times(self, samples: Sequence[JointStateFields]) -> list[int]:
        """The log time (int ns) of each sample: its receive time (now on the receive clock
        when not given or not finite), never before the one logged last."""
        now, times = None, []
        for sample in samples:
            received = sample[4]
            if received is None or (isinstance(received, float) and not math.isfinite(received)):
                now = receive_time_ns() if now is None else now
                received = now
            self.log_ns = max(self.log_ns, int(received))
            times.append(self.log_ns)
        return times

    def _observe_input(self, samples: Sequence[JointStateFields]) -> None:
        """Advance input time: each sample's stamp, or its receive time when unstamped (a
        sample with neither in range is left out); a stamp back in time restarts the wait for
        a torque there."""
        for *_, stamp_ns, received_ns in samples:
            stamp = stamp_ns if stamp_ns else received_ns
            if not (isinstance(stamp, (int, np.integer)) and 0 <= stamp < STAMP_LIMIT_NS):
                continue
            if self._quiet_since_ns is None or stamp < self._quiet_since_ns:
                self._quiet_since_ns = int(stamp)
            self._input_ns = int(stamp)

    @property
    def silent_ns(self) -> int:
        """Input time (ns) since the last torque published (since the first sample before
        one); 0 before any input."""
        if self._input_ns is None or self._quiet_since_ns is None:
            return 0
        return max(0, self._input_ns - self._quiet_since_ns)

    def _without_duplicates(self, stamps: list[int], taken: list[bool], rejected: list[InputRejected]
                            ) -> list[int] | None:
        """Drop the samples taken with the stamp of the sample taken before them (a
        duplicate: counted, not accepted, and it does not break the stencil); the indices of
        the rows kept, or None when there is no duplicate."""
        previous, kept = self._last_taken_ns, []
        for k, (stamp, good) in enumerate(zip(stamps, taken)):
            if good and stamp == previous:
                error = InputRejected("duplicate", f"joint state stamped {stamp} ns, as the one before it")
                self.counters.accepted -= 1
                self.counters.reject(error)
                rejected.append(error)
                continue
            if good:
                previous = stamp
            kept.append(k)
        self._last_taken_ns = previous
        return None if len(kept) == len(stamps) else kept

    def _checked(self, samples: Sequence[tuple]
                 ) -> tuple[list[int], np.ndarray, np.ndarray, list[bool], list[InputRejected]]:
        """Each sample checked (see :meth:`joint_state`) and counted: the stamps (int ns; 0
        for a rejected sample), q and v rows in joint order (N, nq) and (N, nv), whether each
        sample was taken, and the errors of those rejected. Samples naming the joints as the
        last accepted one did are checked as arrays; any that fails, and any other, through
        ``_joint_sample``."""
        stamps = self._stamps_of(samples)
        rows = self._good_rows(samples, stamps)
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
        (one comparison: positions and velocities within ``_row_bounds``), for samples that
        name the joints exactly as the last accepted one did; None when they cannot be taken
        as arrays."""
        key, count = self._names_key, len(samples)
        if key is None or not all(tuple(sample[0]) == key for sample in samples):
            return None
        try:
            values = np.array([sample[1] for sample in samples] + [sample[2] for sample in samples], dtype=float)
        except (ValueError, TypeError, OverflowError):     # OverflowError: an int beyond a double
            return None
        if values.shape != (2 * count, len(key)):
            return None
        rows = values.reshape(2, count, -1)
        within = (self._row_bounds[0] <= rows) & (rows <= self._row_bounds[1])
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
        outside = ~((self._position_low <= sample.q) & (sample.q <= self._position_high))
        if outside.any():
            joints = [f"{name} ({value:g})" for name, value, flag in zip(self.robot.joint_names, sample.q, outside)
                      if flag]
            raise InputRejected("out_of_limits", f"position beyond the joint limits plus a margin of "
                                f"{', '.join(joints)}")
        key = tuple(str(name) for name in names)
        if key != self._names_key:
            self._remember_names(key)
        return sample

    def _remember_names(self, key: tuple[str, ...]) -> None:
        """Cache what the array checks need for samples naming ``key``: ``_columns``, the
        columns of the robot's joints in joint order (a slice when the names are in joint
        order), and ``_row_bounds`` (2, 2, 1, len(key)), the lowest and highest position
        (the position bounds; the largest float, so finite, for joints that do not move) and
        velocity (the velocity bound, finite) of each column."""
        position_of = {name: i for i, name in enumerate(key)}
        index = np.array([position_of[n] for n in self.robot.joint_names])
        largest = np.finfo(float).max
        high = np.full((2, 1, len(key)), largest)
        high[0, 0, index] = self._position_high
        high[1, 0, index] = np.minimum(self._velocity_bound, largest)
        low = -high
        low[0, 0, index] = self._position_low
        bounds = np.stack((low, high))
        in_order = len(key) == len(index) and (index == np.arange(len(index))).all()
        self._names_key, self._columns, self._row_bounds = key, slice(None) if in_order else index, bounds

    def _torques_from(self, stamps: list[int], q: np.ndarray, v: np.ndarray, taken: list[bool],
                      log_times: list[int], start: int, outputs: Outputs) -> int:
        """Difference the checked rows from ``start`` on (stamps int ns, q and v rows in joint
        order, which were ``taken``, logged at ``log_times``), compute their torques and append
        (and log, a torque at the log time of the row that completes it) the outputs
        of each row taken in turn: /odom, then the torque of the middle sample once three are
        known. Up to and including the first implausible torque or message that cannot be
        built (not published; the estimate restarts there, counted); returns the row after
        the last one done."""
        state = self.estimator.state()
        estimates = self.estimator.push_rows(stamps[start:], q[start:], v[start:], taken[start:])
        tau = self.dynamics.torques(estimates.q, estimates.v, estimates.a)
        count = plausible_rows(tau, self._effort_bound)
        base = None
        if self.odometry is not None and count:
            base = self._base_rows(stamps[start:], v[start:], taken[start:], estimates.ends[:count])
        built, failure = self._torque_messages(estimates.stamps[:count].tolist(), estimates.q, estimates.v, tau, base)
        bad = None if failure is None and count == len(tau) else len(built)
        end = len(stamps)
        if bad is not None:     # the estimate restarts at its last sample: the rows up to it again
            end = start + int(estimates.ends[bad]) + 1
            self.estimator.restore(state)
            estimates = self.estimator.push_rows(stamps[start:end], q[start:end], v[start:end], taken[start:end])
        for error in estimates.errors:
            self.counters.reject(error)
        torque_rows, torque_stamps = (estimates.ends + start).tolist(), estimates.stamps.tolist()
        torque_at = dict(zip(torque_rows, range(len(torque_rows))))
        moving, rerun = self.odometry is not None, self.recorder.samples
        for row in range(start, end) if moving else torque_rows:    # a fixed base: only the torques' rows give outputs
            if not taken[row]:
                continue
            log_ns = log_times[row]
            odom = self._odometry(stamps[row], v[row], log_ns) if moving else []
            k = torque_at.get(row)
            if k is not None and k == bad:
                outputs += self._rejected_torque(estimates, tau[k], failure, odom)
            elif k is not None:
                outputs += odom
                outputs += self._logged(torque_stamps[k], log_ns, (estimates, tau, k) if rerun else None, *built[k])
                self._quiet_since_ns = max(self._quiet_since_ns or 0, stamps[row])
            else:
                outputs += odom
        return end

    def _odometry(self, stamp: int, v: np.ndarray, log_ns: int) -> Outputs:
        """/odom of a sample taken (stamp int ns, v in joint order), logged at ``log_ns``;
        none without a moving base."""
        if self.odometry is None:
            return []
        message, row = self.odometry.outputs(stamp, stamp / NS_PER_S, v[self.wheels])
        self._odometry_row = row
        odom = [("/odom", message)]
        self.recorder.write(odom, log_ns)
        return odom

    def _base_rows(self, stamps: Sequence[int], v: np.ndarray, taken: Sequence[bool],
                   ends: Sequence[int]) -> np.ndarray:
        """Rows (N, 2, 7) of odom -> base_footprint and odom -> world (the identity) at each
        torque's sample: the taken row before the row ``ends[i]`` that completes torque i
        (the stencil's middle), its wheel odometry previewed through the rows ``stamps``,
        ``v``, ``taken`` still to be published, or, before the first of them, the last
        sample's. Matched by row, not by stamp: a replay may repeat stamps in one batch."""
        ahead = [k for k, good in enumerate(taken) if good]
        previewed = self.odometry.preview([stamps[k] / NS_PER_S for k in ahead], [v[k, self.wheels] for k in ahead])
        middles = np.searchsorted(ahead, ends) - 1
        return np.array([(previewed[m] if m >= 0 else self._odometry_row, IDENTITY_ROW)
                         for m in middles]).reshape(-1, 2, 7)

    def _rejected_torque(self, estimates: Estimates, tau: np.ndarray, failure: Exception | None,
                         odom: Outputs) -> Outputs:
        """Count the last of ``estimates`` rejected (``implausible_torque`` or
        ``non_finite``: ``tau`` beyond the effort-limit bound or not finite; ``failure``: its
        message could not be built) and restart the estimate; the outputs of its sample (the
        sample's /odom is logged, and published only after a message failure)."""
        if failure is not None:
            self.counters.reject(InputRejected("non_finite", str(failure)))
            self.estimator.restart("non_finite")
            return odom
        finite = bool(np.isfinite(tau).all())
        self.counters.reject(InputRejected("implausible_torque" if finite else "non_finite",
                                           f"torque at {estimates.stamps[-1]} ns beyond the effort-limit bound or "
                                           f"not finite on {', '.join(implausible_joints(self.robot, tau))}"))
        self.estimator.restart("implausible" if finite else "non_finite")
        return []

    def _torque_messages(self, stamps: list[int], q: np.ndarray, v: np.ndarray, tau: np.ndarray,
                         base: np.ndarray | None = None) -> tuple[Built, Exception | None]:
        """The messages of the first len(``stamps``) torques (rows of q, v, tau; ``base``
        their rows of :meth:`_base_rows`, None for a fixed base), built together; when one
        cannot be built, those before it, one at a time, and its error."""
        try:
            return self._torque_batch(stamps, q, v, tau, base), None
        except messages.MessageFieldError:
            pass
        built: Built = []
        for k in range(len(stamps)):
            try:
                built += self._torque_batch(stamps[k:k + 1], q[k:k + 1], v[k:k + 1], tau[k:k + 1],
                                            None if base is None else base[k:k + 1])
            except messages.MessageFieldError as error:
                return built, error
        return built, None

    def _torque_batch(self, stamps: list[int], q: np.ndarray, v: np.ndarray, tau: np.ndarray,
                      base: np.ndarray | None = None) -> Built:
        """/computed_torques, /ee_pose(s) and /tf of N torques (stamps int ns; rows of q, v,
        tau; ``base`` (N, 2, 7) a moving base's rows of :meth:`_base_rows`), those wanted, with
        each sample's kinematics (None unless Rerun records the samples) and base rows. Raises
        MessageFieldError."""
        wanted, count = self.wanted, len(stamps)
        if not count:
            return []
        samples = self.frames.links.at_many(q[:count]) if self.kinematics_wanted else None
        entries: list[Entry] = []
        if "/computed_torques" in wanted:
            entries.append(("/computed_torques", self._torques,
                            np.concatenate((q[:count], v[:count], tau[:count]), axis=1), self._joint_state))
        if samples is not None:
            entries += self.frames.ee_entries(samples, wanted, base)
            if "/tf" in wanted:
                entries.append(self.frames.tf_entry(count, samples, None, base))
        filled = self._batches.fill(stamps, entries)
        kept = samples if samples is not None and self.recorder.samples else None     # only Rerun reads them
        return [(filled[k], None if kept is None else kept[k], None if base is None else base[k])
                for k in range(count)]

    def _joint_state(self, stamp_ns: int, values: np.ndarray) -> object:
        """sensor_msgs/JointState of the robot's joints: ``values`` are q, v, tau in a row."""
        return messages.joint_state(stamp_ns, self.robot.joint_names, *np.split(values, 3))

    def _logged(self, stamp: int, log_ns: int, rerun: tuple[Estimates, np.ndarray, int] | None, outputs: Outputs,
                sample: SampleFrames | None, base: np.ndarray | None = None) -> Outputs:
        """``outputs``, the messages of a torque stamped ``stamp`` (int ns), logged at
        ``log_ns``; with ``rerun`` (the estimates, their torques' rows and the torque's index
        k), the Rerun recording takes the sample at its stamp, its energy (J), end effector
        in the root frame and a moving base's ``base`` rows."""
        self.recorder.write(outputs, log_ns)
        if rerun is not None:
            estimates, torques, k = rerun
            q, v, tau = estimates.q[k], estimates.v[k], torques[k]
            data = self.dynamics.data
            energy = kinetic_energy(self.robot, data, q, v) + potential_energy(self.robot, data, q)
            ee = end_effector_row(sample, base)
            self.recorder.sample(stamp, self.robot.joint_names, q, v, tau, energy, ee[:3])
            if base is not None:
                self.recorder.base(stamp, base)
        self.stamp_ns, self.samples = stamp, self.samples + 1
        return outputs

    @property
    def log_time_ns(self) -> int:
        """Log time (ns) of a message sent now (/diagnostics): now on the receive clock,
        never before what was logged last."""
        self.log_ns = max(self.log_ns, receive_time_ns())
        return self.log_ns

    def diagnostics(self, real_time_factor: float) -> Outputs:
        """/diagnostics now: samples processed, input counters, the estimator's restarts by
        cause (``estimator.restarts.<cause>``) and the input time since the last torque
        (``input_without_torque_s``); WARN when that is longer than the estimator's
        ``max_gap_ns`` (samples come but no torque does: all rejected, duplicated or
        restarting the estimate)."""
        silent = self.silent_ns
        values = {"torques_published": self.samples, **self.counters.as_values(),
                  **{f"estimator.restarts.{cause}": count for cause, count in self.estimator.restarts.items()},
                  "input_without_torque_s": f"{silent / NS_PER_S:.6f}"}
        if silent > self.estimator.max_gap_ns:
            return self._diagnostic_outputs("WARN", f"no torque published for {silent / NS_PER_S:.3f} s of input "
                                            f"(max_sample_gap {self.estimator.max_gap_ns / NS_PER_S:g} s)", values)
        return self._diagnostic_outputs("OK", "running", values)
