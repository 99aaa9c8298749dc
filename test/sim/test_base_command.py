"""A base path's command (compiled, sim/mobile_base.py ``_path_command``) against its Python
formula, bit for bit: the path's pose, its body-frame twist V = (R^T p', yaw') and
dV/dt = (R^T p'' - yaw' S V_xy, yaw'') at times before, along and after mobile_pick's base
given a path that drives and turns at once (every segment and its ends)."""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.sim.build import compile as compile_scene
from youbot_dynamics.sim.trajectory import PointToPointTrajectory


def python_command(path, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The formula as numpy and math compute it."""
    pose, rate, acceleration = path.evaluate(t)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    vx, vy = c * rate[0] + s * rate[1], -s * rate[0] + c * rate[1]
    ax, ay = c * acceleration[0] + s * acceleration[1], -s * acceleration[0] + c * acceleration[1]
    return pose, np.array([vx, vy, rate[2]]), np.array([ax + rate[2] * vy, ay - rate[2] * vx, acceleration[2]])


def test_path_command_equals_the_python_formula_to_the_bit():
    path = PointToPointTrajectory.through(np.array([[0.0, 0.0, 0.3], [0.8, -0.4, 2.1], [0.8, -0.4, 2.1],
                                                    [-0.2, 0.5, -1.0]]), [0.4, 0.3, 0.8], [0.5, 0.4, 1.2], 0.2)
    base = dataclasses.replace(compile_scene(load_scene("mobile_pick")).base, path=path)
    ends = np.concatenate([path.segment_start, path.waypoint_times])
    times = np.concatenate([np.linspace(-1.0, path.duration + 1.0, 997), ends, np.nextafter(ends, np.inf)])
    turning = 0
    for t in times.tolist():
        got, expected = base.command(t), python_command(path, t)
        for a, b in zip(got, expected):
            np.testing.assert_array_equal(a, b)
        turning += int(expected[1][2] != 0.0 and expected[1][0] != 0.0)
    assert turning  # some samples turn while driving (every term of the formula is exercised)
