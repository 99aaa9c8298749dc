"""Joint-space point-to-point trajectories through waypoints, as in the Modia3D youBot study.

Each segment between two waypoints is a straight line in joint space, q(t) = q_a + d s(t)
with d = q_b - q_a and a normalised path parameter s from 0 to 1, so all joints start and
stop together (synchronised). s follows the time-optimal trapezoidal (bang-coast-bang)
profile under the tightest of the joints' limits, |d_i| s' <= v_max_i and
|d_i| s'' <= a_max_i: the joint that needs the longest moves at its own limits and the
others are scaled down (Modelica's KinematicPTP, used by Modia3D's ptpJointSpace). If the
velocity limit cannot be reached the profile is triangular. An optional dwell (s) holds each
reached waypoint before the next segment starts.

Units: rad or m for positions, per second and per second squared for the limits.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numba import njit, types
from numba.extending import register_jitable

from youbot_dynamics.compiled import unchecked
from youbot_dynamics.errors import UserInputError


#: numba types of what :func:`desired_motion` reads: the points (k+1, n), the timing (k, 5).
POINTS, TIMING = types.Array(types.float64, 2, "A", readonly=True), types.Array(types.float64, 2, "C", readonly=True)


@njit(types.UniTuple(types.float64, 3)(*(types.float64,) * 5), cache=True)
def _profile_at(a: float, v: float, t_a: float, T: float, t: float) -> tuple[float, float, float]:
    """s, s', s'' at time t (s) of the trapezoid with acceleration a (1/s^2), coast rate v
    (1/s), acceleration phase t_a (s) and duration T (s), clamped to [0, T]."""
    if t <= 0.0:
        return 0.0, 0.0, 0.0
    if t >= T:
        return 1.0, 0.0, 0.0
    if t < t_a:
        return 0.5 * a * t * t, a * t, a
    if t <= T - t_a:
        return 0.5 * a * t_a * t_a + v * (t - t_a), v, 0.0
    r = T - t
    return 1.0 - 0.5 * a * r * r, a * r, -a


@register_jitable
def desired_motion(points: np.ndarray, timing: np.ndarray, t: float, out: np.ndarray) -> None:
    """out = (q_d, v_d, a_d) at time t (s) of the trajectory through ``points`` (k+1, n) with
    per segment the row (start s, acceleration, coast rate, acceleration phase, duration) of
    ``timing`` (k, 5), NaN profile for a segment of zero length: before 0 the start, after
    the end the last point at rest. Each entry q_a + s d, s' d, s'' d with d = q_b - q_a, as
    numpy computes them (one call instead of a search, a profile and five array operations).
    An out that is not (3, n) is a ValueError raised before anything is written; the timing
    is trusted (:attr:`PointToPointTrajectory.compiled` checks it once)."""
    n, segments = points.shape[1], timing.shape[0]
    if out.shape[0] != 3 or out.shape[1] != n:
        raise ValueError("trajectory: the desired motion needs a (3, n) output for n joints")
    rest = 0  # the point held at rest: the start (before 0 or without segments)
    if segments > 0 and not t <= 0.0:  # a NaN t takes the last segment: NaN out
        k = segments - 1
        while timing[k, 0] > t:  # the last segment started at or before t (searchsorted right - 1)
            k -= 1
        if not np.isnan(timing[k, 1]):
            s, ds, dds = _profile_at(timing[k, 1], timing[k, 2], timing[k, 3], timing[k, 4], t - timing[k, 0])
            for i in range(n):
                d = points[k + 1, i] - points[k, i]
                out[0, i], out[1, i], out[2, i] = points[k, i] + s * d, ds * d, dds * d
            return
        rest = k + 1  # a segment of zero length: its end
    for i in range(n):  # element by element: numba's slice assignments cost ~0.02 us each
        out[0, i], out[1, i], out[2, i] = points[rest, i], 0.0, 0.0


@njit(types.void(POINTS, TIMING, types.float64, types.Array(types.float64, 2, "C")), cache=True)
def _desired(points: np.ndarray, timing: np.ndarray, t: float, out: np.ndarray) -> None:
    """out = (q_d, v_d, a_d) at time t (s) (see :func:`desired_motion`)."""
    desired_motion(points, timing, t, out)


#: :func:`_desired` without numba's type dispatch (for the arrays of ``compiled`` and a float t).
_desired_unchecked = unchecked(_desired)


@dataclass(frozen=True)
class TrapezoidProfile:
    """Time-optimal rest-to-rest profile of s from 0 to 1 with |s'| <= v, |s''| <= a.

    ``t_accelerate`` is the length of the acceleration (and of the deceleration) phase, s;
    ``duration`` the total, s; ``peak_rate`` the coast rate of s, 1/s.
    """

    acceleration: float
    peak_rate: float
    t_accelerate: float
    duration: float

    @classmethod
    def time_optimal(cls, rate_limit: float, acceleration_limit: float) -> TrapezoidProfile:
        """The fastest profile under the limits (triangular when the rate limit is not
        reached: v^2 / a > 1)."""
        v, a = rate_limit, acceleration_limit
        if v * v / a >= 1.0:
            t_a = np.sqrt(1.0 / a)
            return cls(a, a * t_a, t_a, 2.0 * t_a)
        t_a = v / a
        return cls(a, v, t_a, 1.0 / v + t_a)

    def evaluate(self, t: float) -> tuple[float, float, float]:
        """s, s' (1/s), s'' (1/s^2) at time t (s) from the segment start (clamped)."""
        return _profile_at(self.acceleration, self.peak_rate, self.t_accelerate, self.duration, t)


@dataclass(frozen=True)
class PointToPointTrajectory:
    """Synchronised trapezoidal motion through ``points`` (k+1, n): points[0] is the start.

    ``v_max``, ``a_max`` (n,) are per-joint limits (positive); ``dwell`` (s) is the pause at
    each reached waypoint. ``segment_start`` (k,) and ``profiles`` (k,) describe the timing.
    """

    points: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    dwell: float
    profiles: tuple[TrapezoidProfile | None, ...]
    segment_start: np.ndarray

    @classmethod
    def through(cls, points, v_max, a_max, dwell: float = 0.0) -> PointToPointTrajectory:
        """Plan the trajectory; a segment of zero length takes no time (only its dwell)."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        n = points.shape[1]
        v_max = np.broadcast_to(np.asarray(v_max, dtype=float), (n,)).copy()
        a_max = np.broadcast_to(np.asarray(a_max, dtype=float), (n,)).copy()
        if points.shape[0] < 1 or not np.all(np.isfinite(points)):
            raise UserInputError(f"trajectory points must be finite, got {points.tolist()}")
        for label, limits in (("v_max", v_max), ("a_max", a_max)):
            if not np.all(limits > 0):
                raise UserInputError(f"trajectory {label} must be positive, got {limits.tolist()}")
        if not dwell >= 0:
            raise UserInputError(f"trajectory dwell must be >= 0 s, got {dwell}")
        profiles, starts, t = [], [], 0.0
        for q_a, q_b in zip(points[:-1], points[1:]):
            distance = np.abs(q_b - q_a)
            starts.append(t)
            if not np.any(distance > 0):
                profiles.append(None)
                t += dwell
                continue
            moving = distance > 0
            profile = TrapezoidProfile.time_optimal(np.min(v_max[moving] / distance[moving]),
                                                    np.min(a_max[moving] / distance[moving]))
            profiles.append(profile)
            t += profile.duration + dwell
        for array in (points, v_max, a_max):
            array.setflags(write=False)
        segment_start = np.array(starts)
        segment_start.setflags(write=False)
        return cls(points, v_max, a_max, float(dwell), tuple(profiles), segment_start)

    @property
    def duration(self) -> float:
        """Time (s) at which the last waypoint is reached (without its dwell)."""
        if not self.profiles:
            return 0.0
        last = self.profiles[-1]
        return float(self.segment_start[-1]) + (last.duration if last else 0.0)

    @property
    def waypoint_times(self) -> np.ndarray:
        """Time (s) at which each point is reached; points[0] at 0."""
        ends = [start + (p.duration if p else 0.0) for start, p in zip(self.segment_start, self.profiles)]
        return np.array([0.0, *ends])

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Desired position, velocity and acceleration (n,) at time t (s); before 0 the
        start, after the end the last point at rest."""
        points, timing = self.compiled
        out = np.empty((3, points.shape[1]))
        _desired_unchecked(points, timing, float(t), out)
        return out[0], out[1], out[2]

    @functools.cached_property
    def compiled(self) -> tuple[np.ndarray, np.ndarray]:
        """What :func:`desired_motion` reads: the points as float64 and per segment (start s,
        acceleration, coast rate, acceleration phase, duration), NaN for a segment of zero
        length, C-ordered (its signature's types: it is called without numba's dispatch)."""
        timing = np.array([(start, *((p.acceleration, p.peak_rate, p.t_accelerate, p.duration) if p else (np.nan,) * 4))
                           for start, p in zip(self.segment_start.tolist(), self.profiles)], dtype=float).reshape(-1, 5)
        points = np.ascontiguousarray(self.points, dtype=float)
        if points.ndim != 2 or timing.shape[0] != points.shape[0] - 1:
            raise UserInputError(f"trajectory: {points.shape[0]} points need {points.shape[0] - 1} segments, "
                                 f"got {timing.shape[0]}")
        for array in (points, timing):
            array.setflags(write=False)
        return points, timing
