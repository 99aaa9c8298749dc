"""Point-to-point trajectories: limits respected, waypoints hit, joints synchronised, the
limiting joint at its limits (time-optimal), and q, v, a consistent with each other."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.sim.trajectory import PointToPointTrajectory, TrapezoidProfile

POINTS = np.array([[0.0, 0.0, 0.0], [2.0, -0.5, 0.1], [2.0, -0.5, 0.1], [1.9, 0.5, 0.1], [0.0, 0.0, 0.0]])
V_MAX = np.array([1.0, 2.0, 0.5])
A_MAX = np.array([2.0, 1.0, 4.0])


def sampled(trajectory, n=20001):
    t = np.linspace(-0.5, trajectory.duration + 0.5, n)
    q, v, a = (np.array(x) for x in zip(*(trajectory.evaluate(tk) for tk in t)))
    return t, q, v, a


def test_limits_respected_and_waypoints_hit():
    trajectory = PointToPointTrajectory.through(POINTS, V_MAX, A_MAX, dwell=0.2)
    t, q, v, a = sampled(trajectory)
    assert np.all(np.abs(v) <= V_MAX * (1 + 1e-12))
    assert np.all(np.abs(a) <= A_MAX * (1 + 1e-12))
    for time, point in zip(trajectory.waypoint_times, POINTS):
        q_w, v_w, a_w = trajectory.evaluate(time)
        np.testing.assert_allclose(q_w, point, atol=1e-12)
        np.testing.assert_allclose(v_w, 0.0, atol=1e-12)
    np.testing.assert_allclose(q[0], POINTS[0])
    np.testing.assert_allclose(q[-1], POINTS[-1])


def test_q_v_a_are_consistent():
    """v is the derivative of q, a of v (central differences), q is continuous."""
    trajectory = PointToPointTrajectory.through(POINTS, V_MAX, A_MAX, dwell=0.2)
    t, q, v, a = sampled(trajectory, 40001)
    h = t[1] - t[0]
    np.testing.assert_allclose((q[2:] - q[:-2]) / (2 * h), v[1:-1], atol=2 * A_MAX.max() * h)
    smooth = np.all(np.abs(np.diff(a, axis=0)) < 1e-9, axis=1)  # away from acceleration jumps
    dv = (v[2:] - v[:-2]) / (2 * h)
    np.testing.assert_allclose(dv[smooth[1:] & smooth[:-1]], a[1:-1][smooth[1:] & smooth[:-1]], atol=1e-6)
    assert np.max(np.abs(np.diff(q, axis=0))) <= V_MAX.max() * h * (1 + 1e-9)


def test_segments_are_synchronised_and_time_optimal():
    trajectory = PointToPointTrajectory.through(POINTS[:2], V_MAX, A_MAX)
    t, q, v, a = sampled(trajectory)
    moving = np.abs(v) > 1e-12
    # all joints start and stop moving at the same instants (straight line in joint space)
    assert np.array_equal(moving[:, 0], moving[:, 1]) and np.array_equal(moving[:, 0], moving[:, 2])
    direction = POINTS[1] - POINTS[0]
    np.testing.assert_allclose(np.cross(q - POINTS[0], direction), 0.0, atol=1e-12)
    # the limiting joint is at a limit: time-optimal under synchronisation. Joint 0 (2 rad at
    # 1 rad/s and 2 rad/s^2) needs 1/1 * 2 + 1/2 = 2.5 s; the others fit in that time.
    assert trajectory.duration == pytest.approx(2.5)
    assert np.max(np.abs(v[:, 0])) == pytest.approx(V_MAX[0])
    assert np.max(np.abs(a[:, 0])) == pytest.approx(A_MAX[0])


def test_triangular_profile_when_velocity_limit_not_reached():
    profile = TrapezoidProfile.time_optimal(rate_limit=10.0, acceleration_limit=4.0)
    assert profile.duration == pytest.approx(1.0)  # 2 sqrt(1/4)
    assert profile.peak_rate == pytest.approx(2.0)
    s, ds, _ = profile.evaluate(0.5)
    assert s == pytest.approx(0.5) and ds == pytest.approx(2.0)


def test_zero_length_segment_only_dwells():
    trajectory = PointToPointTrajectory.through(POINTS[1:3], V_MAX, A_MAX, dwell=0.4)
    assert trajectory.duration == 0.0
    np.testing.assert_allclose(trajectory.evaluate(0.2)[0], POINTS[1])


@pytest.mark.parametrize("kwargs, words", [({"v_max": [1.0, 0.0, 1.0]}, "v_max must be positive"),
                                            ({"a_max": -1.0}, "a_max must be positive"),
                                            ({"dwell": -0.1}, "dwell must be >= 0")])
def test_bad_limits_rejected(kwargs, words):
    arguments = {"v_max": V_MAX, "a_max": A_MAX, "dwell": 0.0, **kwargs}
    with pytest.raises(UserInputError, match=words):
        PointToPointTrajectory.through(POINTS, **arguments)
