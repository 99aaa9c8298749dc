"""Joint friction near zero velocity does not chatter.

A single revolute joint (axis along gravity, so gravity exerts no torque; inertia I about
the axis) starts at rest under a constant torque tau below its Coulomb level F_c. With the
regularised Coulomb law F = F_c tanh(v / v_s) the exact motion creeps towards
v* = v_s atanh(tau / F_c) with time constant I v_s / (F_c (1 - (tau/F_c)^2)), never
reversing. Stated bound: after 10 time constants, |v - v*| <= 1e-3 v_s for every integrator
(fixed-step methods at a step inside the explicit stability limit h < 2 I v_s / F_c; the
adaptive ones at rtol 1e-6), and v never changes sign. Above that limit explicit Euler
chatters: the tanh saturation turns its growing oscillation into a limit cycle in which the
velocity keeps reversing, so the step limit is the real boundary of the stated bound.
"""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import forward_dynamics
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.model.robot import load_robot

INERTIA = 0.01       # kg m^2 about the joint axis
COULOMB = 0.5        # N m
SCALE = 0.01         # rad/s, regularisation scale v_s
TAU = 0.25           # N m, half the Coulomb level: the joint creeps

URDF = f"""<robot name="creep">
  <link name="base"/>
  <link name="rotor">
    <inertial><mass value="1.0"/><origin xyz="0 0 0"/>
      <inertia ixx="{INERTIA}" ixy="0" ixz="0" iyy="{INERTIA}" iyz="0" izz="{INERTIA}"/></inertial>
  </link>
  <joint name="spin" type="revolute">
    <parent link="base"/><child link="rotor"/><axis xyz="0 0 1"/>
    <limit lower="-10" upper="10" effort="10" velocity="10"/>
  </joint>
</robot>"""

V_CREEP = SCALE * np.arctanh(TAU / COULOMB)
TIME_CONSTANT = INERTIA * SCALE / (COULOMB * (1.0 - (TAU / COULOMB) ** 2))
STABILITY_LIMIT = 2.0 * INERTIA * SCALE / COULOMB  # explicit Euler, linearised at v = 0


@pytest.fixture(scope="module")
def creep_rhs():
    robot = load_robot(URDF)
    data = robot.model.createData()
    friction = JointFriction.from_spec(robot, {"spin": {"law": "coulomb", "coulomb": COULOMB,
                                                         "damping": 0.0, "velocity_scale": SCALE}})
    tau = np.array([TAU])

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, v = x[:1], x[1:]
        return np.concatenate([v, forward_dynamics(robot, data, q, v, tau, friction)])

    return rhs


def settled(solution) -> np.ndarray:
    return solution.x[solution.t >= 10 * TIME_CONSTANT, 1]


@pytest.mark.parametrize("integrator", [name for name in INTEGRATORS if name != "ida"])
def test_creep_settles_without_chatter(creep_rhs, integrator: str) -> None:
    t_eval = np.linspace(0.0, 30 * TIME_CONSTANT, 301)
    options = {"dt": STABILITY_LIMIT / 4} if integrator in FIXED_STEP else {"rtol": 1e-6, "atol": 1e-9}
    solution = integrate(creep_rhs, [0.0, 0.0], t_eval, integrator, n_positions=1, **options)
    v = solution.x[:, 1]
    assert np.all(v >= 0.0), f"{integrator}: the velocity reversed (min {v.min():.3g} rad/s)"
    assert np.max(np.abs(settled(solution) - V_CREEP)) <= 1e-3 * SCALE


def test_explicit_euler_beyond_its_stability_limit_chatters(creep_rhs) -> None:
    dt = 2.5 * STABILITY_LIMIT
    t_eval = np.arange(0.0, 200 * TIME_CONSTANT, dt)
    solution = integrate(creep_rhs, [0.0, 0.0], t_eval, "euler", dt=dt)
    v = settled(solution)
    assert np.count_nonzero(np.diff(np.sign(v))) > len(v) // 2
    assert np.max(np.abs(v - V_CREEP)) > 100 * 1e-3 * SCALE
