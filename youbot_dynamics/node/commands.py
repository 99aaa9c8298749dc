"""Checking what arrives from outside before the simulator sees it: effort commands,
joint-state samples and joint trajectories, matched by joint NAME, never by position.

Plain Python (no ROS): the node hands the fields of a message over as sequences and gets
back either clean arrays in the robot's joint order or an :class:`InputRejected` naming the
kind of problem (one of ``REJECTION_KINDS``) and what was wrong. :class:`InputCounters`
counts each kind, for /diagnostics. Effort commands beyond the URDF effort limit are not
rejected but clamped (counted as ``clamped``); a joint without a finite URDF limit
(continuous joints) is clamped to the node's ``default_effort_limit``
(:data:`DEFAULT_EFFORT_LIMIT` unless set).

Bounded work: every check is linear in the message size; a message naming more than
:data:`MAX_NAMES` joints or a trajectory of more than :data:`MAX_TRAJECTORY_POINTS` points
is rejected (``too_large``) before anything else is looked at; so is an empty effort
command (``empty``: it would otherwise read as zero torque on every joint).

Time semantics (the one place they are written down)
----------------------------------------------------
- Node time ("now") is the session's clock: in simulate mode the simulated time on
  /clock, which starts at 0 and only ever increases (``~/reset`` restarts the scene, not
  the clock); in inverse mode the sender's stamps (see below). Stamps and trajectory times
  are integer nanoseconds; ``now`` in seconds where noted.
- A stamp must be what builtin_interfaces/Time holds (0 <= stamp < 2^31 s; a negative sec,
  or a nanosec of 1e9 or more, is ``bad_timing``: :func:`~youbot_dynamics.io.stamps.stamp_ns_of`
  marks the latter, so that it is not carried into the next second).
- Stamp 0 means "not stamped": the receive time stands in for it (node time for commands
  and trajectories). Inverse mode: a 0 after a 0 takes the node clock's receive time; a
  single 0 is taken as the stamp it is (a stream in simulated time starts at 0, and a
  replay that restarts its time base restarts there).
- Wall-clock stamps (within :data:`WALL_CLOCK_WINDOW_NS` of the machine's wall clock while
  node time is not) are carried over by their age: a stamp ``d`` before the wall clock
  means ``now - d`` in node time. So a trajectory stamped with ``get_clock().now()`` of a
  wall-clock node runs relative to its own first point from the moment it arrives (not
  1.8e9 s ahead), and a wall-clock stamped command goes stale after the timeout.
- Far-future stamps (more than :data:`FUTURE_LIMIT_NS` ahead of node time after that
  mapping) are rejected as ``bad_timing``; past stamps older than the command timeout are
  rejected as ``stale``. A rejected stamp is counted and never latched: nothing later is
  measured against it.
- Inverse mode: samples carry the sender's time base; it is never compared with node
  time. A sample stamped as the last one taken is a ``duplicate``: counted, dropped, and
  the estimate goes on. A sample before the previous one, or more than the estimator's
  ``max_gap_ns`` after it, restarts the acceleration estimate
  (:class:`~youbot_dynamics.node.inverse.AccelerationEstimator`), so a replay that restarts,
  a one-off stamp of 1e6 s or a pause in the stream costs at most one stencil (three
  samples) of torques. Log time is not the sender's: every message is logged at the
  receive time of its sample on the node's monotonic receive clock.
"""
from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from youbot_dynamics.io.stamps import MALFORMED_STAMP_NS, NS_PER_S, STAMP_LIMIT_NS
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.node.interface import TIMEOUT_ACTIONS
from youbot_dynamics.sim.controllers import Reference

REJECTION_KINDS = ("non_finite", "length_mismatch", "unknown_joint", "duplicate_joint",
                   "missing_joint", "out_of_limits", "stale", "bad_timing", "no_controller", "empty",
                   "too_large", "implausible_torque", "duplicate")
"""Kinds of rejected input, as counted in /diagnostics."""


MAX_NAMES = 256
"""Most joint names one message may carry (the youBot has 13 joints; a composed scene a few
times that)."""
MAX_TRAJECTORY_POINTS = 1000
"""Most points one /joint_trajectory may carry: checking and fitting 1000 points of the arm
took 25 ms, a few samples of the publishing loop."""
DEFAULT_EFFORT_LIMIT = 100.0
"""Effort limit (N m or N) for joints whose URDF gives none (continuous joints): a command
beyond it is clamped, so no command can push the simulation to infinity."""
WALL_CLOCK_WINDOW_NS = 24 * 3600 * NS_PER_S
"""A stamp within a day of the wall clock, while node time is not, is a wall-clock stamp."""
FUTURE_LIMIT_NS = 60 * NS_PER_S
"""How far ahead of node time a command or trajectory may be stamped (ns)."""



class InputRejected(ValueError):
    """Input that cannot be used: ``kind`` is one of ``REJECTION_KINDS``."""

    def __init__(self, kind: str, detail: str) -> None:
        super().__init__(f"{kind}: {detail}")
        self.kind = kind


@dataclass
class InputCounters:
    """How many inputs were rejected, by kind, how many effort commands were clamped, and
    how many callbacks failed with an unexpected exception, by cause (``"<source>:
    <exception type>"``, e.g. ``"/joint_trajectory: ValueError"``)."""

    rejected: dict[str, int] = field(default_factory=lambda: dict.fromkeys(REJECTION_KINDS, 0))
    clamped: int = 0
    accepted: int = 0
    failed: dict[str, int] = field(default_factory=dict)

    def reject(self, error: InputRejected) -> None:
        """Count a rejected input under its kind."""
        self.rejected[error.kind] += 1

    def fail(self, source: str, error: BaseException) -> str:
        """Count a failure of the callback ``source`` (a topic, ``timer`` or a service) under
        its cause; returns the cause."""
        cause = f"{source}: {type(error).__name__}"
        self.failed[cause] = self.failed.get(cause, 0) + 1
        return cause

    def as_values(self) -> dict[str, int]:
        """Flat key/value pairs for a diagnostic status."""
        return {"accepted": self.accepted, "clamped": self.clamped,
                **{f"rejected.{kind}": count for kind, count in self.rejected.items()},
                "rejected.total": sum(self.rejected.values()),
                **{f"failed.{cause}": count for cause, count in self.failed.items()},
                "failed.total": sum(self.failed.values())}


LISTED = 5
"""Most names an error message lists (then "and N more")."""


def _listed(names: Sequence[str]) -> str:
    """The first ``LISTED`` names, comma-separated, and how many more there are."""
    more = f" and {len(names) - LISTED} more" if len(names) > LISTED else ""
    return ", ".join(names[:LISTED]) + more


def _names(names: Sequence[str], known: Sequence[str], moving: Sequence[str]) -> list[str]:
    """The names as strings, checked in linear time: at most ``MAX_NAMES``, none twice,
    each one of ``known``."""
    if len(names) > MAX_NAMES:
        raise InputRejected("too_large", f"{len(names)} joint names, more than the limit of {MAX_NAMES}")
    names = [str(n) for n in names]
    duplicates = sorted(n for n, count in Counter(names).items() if count > 1)
    if duplicates:
        raise InputRejected("duplicate_joint", f"joint(s) named twice: {_listed(duplicates)}")
    known = set(known)
    unknown = [n for n in names if n not in known]
    if unknown:
        raise InputRejected("unknown_joint", f"no joint(s) {_listed(unknown)} in the robot "
                            f"(moving joints: {', '.join(moving)})")
    return names


def _values(values: Sequence[float], label: str, count: int) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float).reshape(-1)
    except OverflowError:       # an int beyond the largest double
        raise InputRejected("non_finite", f"{label} holds a value beyond the largest double") from None
    if array.size != count:
        raise InputRejected("length_mismatch", f"{label} has {array.size} entries for {count} joint names")
    if not np.isfinite(array).all():
        index = int(np.flatnonzero(~np.isfinite(array))[0])
        raise InputRejected("non_finite", f"{label}[{index}] is {array[index]}")
    return array


def stamp_in_range(stamp_ns: int, what: str) -> int:
    """``stamp_ns`` as an int; raises ``bad_timing`` outside [0, ``STAMP_LIMIT_NS``)."""
    if stamp_ns == MALFORMED_STAMP_NS:
        raise InputRejected("bad_timing", f"{what} stamped with a nanosec of 1e9 or more")
    if not 0 <= stamp_ns < STAMP_LIMIT_NS:
        raise InputRejected("bad_timing", f"{what} stamped {stamp_ns} ns, outside builtin_interfaces/Time's "
                            "0 .. 2^31 s")
    return int(stamp_ns)


def node_time_of_stamp(stamp_ns: int, now_ns: int, timeout_ns: int, what: str, wall_ns: int | None = None) -> int:
    """The node time (ns) a command or trajectory stamp means (see the module docstring):
    0 -> ``now_ns``; a wall-clock stamp -> ``now_ns`` minus its age on the wall clock
    ``wall_ns`` (default: the machine's); otherwise the stamp itself. Raises ``bad_timing``
    for a stamp outside builtin_interfaces/Time or more than ``FUTURE_LIMIT_NS`` ahead,
    ``stale`` for one older than ``timeout_ns``."""
    stamp = stamp_in_range(stamp_ns, what)
    if stamp == 0:
        return now_ns
    wall_ns = time.time_ns() if wall_ns is None else wall_ns
    if abs(stamp - wall_ns) <= WALL_CLOCK_WINDOW_NS < abs(now_ns - wall_ns):
        stamp = now_ns + (stamp - wall_ns)
    if stamp > now_ns + FUTURE_LIMIT_NS:
        raise InputRejected("bad_timing", f"{what} stamped {stamp / NS_PER_S:.6f} s, more than "
                            f"{FUTURE_LIMIT_NS / NS_PER_S:g} s after now ({now_ns / NS_PER_S:.6f} s)")
    if stamp < now_ns - timeout_ns:
        raise InputRejected("stale", f"{what} stamped {stamp / NS_PER_S:.6f} s is older than the "
                            f"{timeout_ns / NS_PER_S:g} s timeout (now {now_ns / NS_PER_S:.6f} s)")
    return stamp


class EffortCommands:
    """Effort commands (N m, N) by joint name, held until ``timeout`` seconds have passed.

    ``accept`` checks one command: at least one name, names unique and moving joints of the
    robot, one finite effort per name, stamp (int ns) neither older than the timeout nor far
    ahead (:func:`node_time_of_stamp`); efforts beyond the URDF limit (``default_limit``
    where the URDF has none, as for continuous joints) are clamped. Joints a command does
    not name keep their previous command (0 at first).
    ``torque(now)`` is the command to apply at time ``now``, or None once the command is
    stale and ``on_timeout`` is ``hold`` (the scene's controller takes over).
    """

    def __init__(self, robot: Robot, timeout: float, on_timeout: str,
                 counters: InputCounters | None = None, default_limit: float = DEFAULT_EFFORT_LIMIT) -> None:
        if on_timeout not in TIMEOUT_ACTIONS:
            raise ValueError(f"on_timeout must be one of {TIMEOUT_ACTIONS}, got {on_timeout!r}")
        if not (math.isfinite(timeout) and timeout > 0.0):
            raise ValueError(f"command timeout must be positive and finite, got {timeout}")
        self.robot, self.timeout, self.on_timeout = robot, float(timeout), on_timeout
        self.counters = counters if counters is not None else InputCounters()
        if not (math.isfinite(default_limit) and default_limit > 0.0):
            raise ValueError(f"default effort limit must be positive and finite, got {default_limit}")
        limit = np.asarray(robot.effort_limit, dtype=float)
        self.limit = np.where(np.isfinite(limit), limit, float(default_limit))
        self.clear()

    def clear(self) -> None:
        """Forget every command (after a reset)."""
        self.command = np.zeros(self.robot.nv)
        self.received_at: float | None = None

    def accept(self, names: Sequence[str], efforts: Sequence[float], stamp_ns: int, now: float,
               wall_ns: int | None = None) -> np.ndarray:
        """Check a command received at node time ``now`` (s; ``wall_ns``: the wall clock, for
        wall-clock stamps); returns the clamped efforts in joint order. Raises (and counts)
        :class:`InputRejected`; a clamped command is counted."""
        try:
            names = _names(names, self.robot.joint_names, self.robot.joint_names)
            if not names:
                raise InputRejected("empty", "an effort command names no joint (it would mean zero torque "
                                    "on every joint); name the joints to command")
            values = _values(efforts, "effort", len(names))
            node_time_of_stamp(stamp_ns, round(now * NS_PER_S), round(self.timeout * NS_PER_S), "effort command",
                               wall_ns)
        except InputRejected as error:
            self.counters.reject(error)
            raise
        command = self.command.copy()
        for name, value in zip(names, values):
            command[self.robot.joint_index(name)] = value
        clamped = np.clip(command, -self.limit, self.limit)
        if not np.array_equal(clamped, command):
            self.counters.clamped += 1
        self.counters.accepted += 1
        self.command, self.received_at = clamped, float(now)
        return clamped.copy()

    def active(self, now: float) -> bool:
        """True while the last command is younger than the timeout."""
        return self.received_at is not None and now - self.received_at <= self.timeout

    def torque(self, now: float) -> np.ndarray | None:
        """The torque to apply at ``now`` (joint order) or None for the scene's controller."""
        if self.active(now):
            return self.command
        if self.received_at is not None and self.on_timeout == "zero_torque":
            return np.zeros(self.robot.nv)
        return None


@dataclass(frozen=True)
class JointSample:
    """One checked joint-state sample: its stamp (int ns, 0 .. 2^31 s), q (rad, m) and v
    (rad/s, m/s) in joint order."""

    stamp_ns: int
    q: np.ndarray
    v: np.ndarray

    @property
    def t(self) -> float:
        """The stamp in seconds."""
        return self.stamp_ns / NS_PER_S


def joint_sample(robot: Robot, known: Sequence[str], names: Sequence[str], position: Sequence[float],
                 velocity: Sequence[float], stamp_ns: int) -> JointSample:
    """Check a sensor_msgs/JointState: every moving joint named once with a finite position
    and velocity. Names of ``known`` joints that do not move (locked wheels, fingers) are
    ignored; names unknown to the robot are rejected."""
    names = _names(names, known, robot.joint_names)
    q = _values(position, "position", len(names))
    v = _values(velocity, "velocity", len(names))
    position_of = {name: i for i, name in enumerate(names)}
    missing = [n for n in robot.joint_names if n not in position_of]
    if missing:
        raise InputRejected("missing_joint", f"no sample for joint(s) {', '.join(missing)}")
    index = [position_of[n] for n in robot.joint_names]
    return JointSample(stamp_in_range(stamp_ns, "joint state"), q[index], v[index])


class SampledTrajectory:
    """A joint trajectory through timed points, as a tracking controller's reference.

    ``start_ns`` (int) is the simulated time (ns) the trajectory starts at, of any
    magnitude; ``offsets_ns`` (k,) are the points' times relative to it in integer
    nanoseconds, strictly increasing from 0; ``positions`` (k, n) and, when given,
    ``velocities`` (k, n) in joint order. The splines run on the relative times in seconds,
    so a wall-clock stamp (~1.7e9 s) costs no resolution between the points. Between points:
    cubic Hermite interpolation through the given velocities, or a cubic spline starting and
    ending at rest when there are none. Before the first point the first point, after the
    last the last (at rest); a single point is held from the start.
    Duck-types :class:`~youbot_dynamics.sim.trajectory.PointToPointTrajectory` (``evaluate``).
    """

    def __init__(self, start_ns: int, offsets_ns: Sequence[int], positions: np.ndarray,
                 velocities: np.ndarray | None) -> None:
        from scipy.interpolate import CubicHermiteSpline, CubicSpline  # only a received trajectory needs it

        self.start_ns = int(start_ns)
        self.offsets_ns = tuple(int(offset) for offset in offsets_ns)
        self.times = np.array(self.offsets_ns, dtype=float) / NS_PER_S
        self.positions = np.asarray(positions, dtype=float)
        if len(self.times) == 1:
            self.spline = None
        elif velocities is None:
            self.spline = CubicSpline(self.times, self.positions, bc_type="clamped")
        else:
            self.spline = CubicHermiteSpline(self.times, self.positions, np.asarray(velocities, dtype=float))
        if self.spline is not None:
            self.rate, self.acceleration = self.spline.derivative(1), self.spline.derivative(2)

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Desired position, velocity and acceleration (n,) at simulated time t (s)."""
        relative = (round(t * NS_PER_S) - self.start_ns) / NS_PER_S
        if self.spline is None or relative <= self.times[0] or relative >= self.times[-1]:
            point = self.positions[0] if relative <= self.times[0] else self.positions[-1]
            return point.copy(), np.zeros(point.size), np.zeros(point.size)
        return self.spline(relative), self.rate(relative), self.acceleration(relative)


def joint_trajectory(robot: Robot, names: Sequence[str], points: Sequence[tuple[int, Sequence[float],
                     Sequence[float]]], start_ns: int, q_now: np.ndarray) -> SampledTrajectory:
    """Check a trajectory_msgs/JointTrajectory and make it a reference in simulated time.

    ``points`` are (time_from_start (int ns), positions, velocities (may be empty));
    ``start_ns`` is the simulated time (int ns) the trajectory starts at (its stamp, or the
    receive time). Joints not named hold ``q_now``; the current position ``q_now`` is
    prepended at the start when the first point comes later, so the reference starts where
    the robot is. The named joints' positions must lie within their limits; times must increase strictly
    (and stay distinguishable as float seconds relative to the start).
    """
    if len(points) > MAX_TRAJECTORY_POINTS:
        raise InputRejected("too_large", f"trajectory of {len(points)} points, more than the limit of "
                            f"{MAX_TRAJECTORY_POINTS}")
    names = _names(names, robot.joint_names, robot.joint_names)
    if not points:
        raise InputRejected("length_mismatch", "trajectory has no points")
    offsets, rows, rates = [], [], []
    with_velocity = all(len(point[2]) for point in points)
    index = [robot.joint_index(n) for n in names]
    for k, (time_from_start_ns, positions, velocities) in enumerate(points):
        if not isinstance(time_from_start_ns, (int, np.integer)) or time_from_start_ns < 0:
            raise InputRejected("bad_timing", f"points[{k}].time_from_start is {time_from_start_ns} ns")
        row, rate = np.array(q_now, dtype=float), np.zeros(robot.nv)
        row[index] = _values(positions, f"points[{k}].positions", len(names))
        if with_velocity:
            rate[index] = _values(velocities, f"points[{k}].velocities", len(names))
        # only the named joints: the others hold where the robot is (a finger resting at its
        # stop may sit 1e-23 m beyond it), which no command can be blamed for
        outside = ~((robot.lower[index] <= row[index]) & (row[index] <= robot.upper[index]))
        if outside.any():
            joints = ", ".join(np.asarray(names)[outside])
            raise InputRejected("out_of_limits", f"points[{k}] outside the joint limits of {joints}")
        offsets.append(int(time_from_start_ns))
        rows.append(row)
        rates.append(rate)
    if offsets[0] > 0:
        offsets, rows, rates = [0, *offsets], [np.asarray(q_now, dtype=float), *rows], [np.zeros(robot.nv), *rates]
    if np.any(np.diff(np.array(offsets, dtype=float) / NS_PER_S) <= 0.0):
        raise InputRejected("bad_timing", "time_from_start must increase strictly from point to point")
    return SampledTrajectory(start_ns, offsets, np.array(rows), np.array(rates) if with_velocity else None)


def follow(simulator, trajectory: SampledTrajectory) -> None:
    """Make a simulator's tracking controller (pd or computed_torque) follow ``trajectory``:
    the trajectory becomes its state's reference (a reset restores the scene's).

    Raises :class:`InputRejected` (``no_controller``) for a scene without one.
    """
    if simulator.controller.kind == "none":
        raise InputRejected("no_controller", "the scene has no tracking controller (controller.type: none)")
    simulator.state.reference = Reference(trajectory.positions[-1].copy(), trajectory)
