"""The PI wheel-speed controller of the base: its formula, the closed loop on free-spinning
wheels against the matrix exponential of the linear system, the anti-windup's closed-form
relaxation while saturated, and the torque limits read from a URDF."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

from youbot_dynamics.dynamics.mobile.base_controller import WheelSpeedPI, wheel_torque_limits
from youbot_dynamics.dynamics.mobile.mecanum import wheel_speeds, youbot_base
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.model.robot import load_robot

URDF = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
BASE = youbot_base()
J = 0.015218160428  # kg m^2, the wheel's inertia about its spin axis (URDF iyy)
B = 0.01  # N m s/rad, bearing friction of the test plant


def test_unsaturated_and_saturated_torques_follow_the_formula():
    pi = WheelSpeedPI(BASE, kp=0.2, ki=2.0, torque_limit=1.0, tracking_time=0.05)
    twist, speeds, integral = np.array([0.1, 0.0, 0.0]), np.array([1.0, 2.0, 3.0, 2.0]), np.array([0.1, 0.0, -0.1, 0.2])
    error = 0.1 / 0.0475 - speeds  # every wheel's set point is vx / r for pure vx
    tau, rate = pi.torques(twist, speeds, integral)
    assert np.allclose(tau, 0.2 * error + integral, rtol=0, atol=1e-15)  # within the limit
    assert np.allclose(rate, 2.0 * error, rtol=0, atol=1e-15)
    tau, rate = pi.torques([2.0, 0.0, 0.0], speeds, integral)  # 42 rad/s asked: saturates
    raw = 0.2 * (2.0 / 0.0475 - speeds) + integral
    assert np.allclose(tau, 1.0, rtol=0, atol=0)
    assert np.allclose(rate, 2.0 * (2.0 / 0.0475 - speeds) + (1.0 - raw) / 0.05, rtol=1e-14, atol=0)
    tau, integral_next = pi.step(twist, speeds, integral, 0.01)
    assert np.allclose(integral_next, integral + 0.01 * 2.0 * error, rtol=0, atol=1e-15)


def closed_loop(pi, twist):
    """rhs of the wheels in the air: J dw/dt = tau - B w, with the controller's dI/dt; x = (w, I)."""
    def rhs(t, x):
        tau, rate = pi.torques(twist, x[:4], x[4:])
        return np.concatenate([(tau - B * x[:4]) / J, rate])
    return rhs


def test_closed_loop_matches_the_linear_systems_exponential():
    """Below the limit the loop is linear: d/dt (w, I) = A (w, I) + b r with
    A = [[-(kp + B)/J, 1/J], [-ki, 0]], b = (kp/J, ki); x(t) = e^{At} x0 + A^-1 (e^{At} - 1) b r."""
    kp, ki = 0.05, 0.5
    pi = WheelSpeedPI(BASE, kp=kp, ki=ki, torque_limit=100.0)
    twist = np.array([0.05, -0.02, 0.1])
    reference = wheel_speeds(BASE, twist)
    times = np.linspace(0.0, 2.0, 21)
    solution = integrate(closed_loop(pi, twist), np.zeros(8), times, "dop853", rtol=1e-12, atol=1e-14)
    a = np.array([[-(kp + B) / J, 1.0 / J], [-ki, 0.0]])
    b = np.array([kp / J, ki])
    for t, x in zip(times, solution.x):
        e = expm(a * t)
        exact = np.array([np.linalg.solve(a, (e - np.eye(2)) @ b * r) for r in reference])  # x0 = 0
        assert np.allclose(x[:4], exact[:, 0], rtol=0, atol=1e-8)  # measured 1.7e-12 (rtol 1e-12)
        assert np.allclose(x[4:], exact[:, 1], rtol=0, atol=1e-8)
    assert np.abs(solution.x[-1, :4] - reference).max() < 1e-3  # settles, no steady-state error


def test_anti_windup_relaxes_the_saturated_integral_to_its_closed_form():
    """Speeds held (e constant), tau at the limit L: dI/dt = ki e + (L - kp e - I) / T_t, so
    I(t) = I* + (I0 - I*) exp(-t / T_t) with I* = L - kp e + T_t ki e."""
    kp, ki, limit, tracking = 2.0, 1.0, 3.0, 0.1
    pi = WheelSpeedPI(BASE, kp=kp, ki=ki, torque_limit=limit, tracking_time=tracking)
    twist = np.array([5.0 * 0.0475, 0.0, 0.0])  # set points 5 rad/s; speeds held at 0: e = 5
    e = 5.0
    assert kp * e > limit + tracking * ki * e  # saturated for the whole relaxation
    times = np.linspace(0.0, 1.0, 11)
    solution = integrate(lambda t, i: pi.torques(twist, np.zeros(4), i)[1], np.zeros(4), times, "dop853",
                         rtol=1e-12, atol=1e-14)
    settled = limit - kp * e + tracking * ki * e
    assert np.allclose(solution.x, (settled * (1.0 - np.exp(-times / tracking)))[:, None], rtol=0,
                       atol=1e-8)  # measured 3.7e-12
    wound = WheelSpeedPI(BASE, kp=kp, ki=ki, torque_limit=limit, tracking_time=1e12)  # no anti-windup
    assert np.allclose(wound.torques(twist, np.zeros(4), np.full(4, 7.0))[1], ki * e, rtol=1e-9)


def test_anti_windup_cuts_the_overshoot_after_saturation():
    twist = np.array([0.5, 0.0, 0.0])  # 10.5 rad/s on every wheel: saturates the 0.5 N m limit
    times = np.linspace(0.0, 4.0, 801)
    peaks, finals = {}, {}
    for name, tracking in (("anti_windup", None), ("none", 1e12)):
        pi = WheelSpeedPI(BASE, kp=0.05, ki=1.0, torque_limit=0.5, tracking_time=tracking)
        solution = integrate(closed_loop(pi, twist), np.zeros(8), times, "dop853", rtol=1e-10, atol=1e-12)
        torques = np.array([pi.torques(twist, x[:4], x[4:])[0] for x in solution.x])
        assert np.abs(torques).max() <= 0.5
        peaks[name] = solution.x[:, 0].max() / (0.5 / 0.0475) - 1.0
        finals[name] = solution.x[-1, 0]
    assert peaks["anti_windup"] < 0.5 * peaks["none"]  # measured 21.8 % against 68.1 %
    assert math.isclose(finals["anti_windup"], 0.5 / 0.0475, rel_tol=1e-3)


def test_torque_limits_come_from_the_urdf_or_are_asked_for():
    with pytest.raises(UserInputError, match="wheel_joint_fl.*effort"):
        wheel_torque_limits(load_robot(URDF))
    text = URDF.read_text().replace('<dynamics damping="0" friction="0"/>',
                                    '<limit effort="2.5" velocity="30"/><dynamics damping="0" friction="0"/>')
    assert np.array_equal(wheel_torque_limits(load_robot(text)), [2.5] * 4)
    with pytest.raises(UserInputError, match="torque_limit"):
        WheelSpeedPI(BASE, kp=1.0, ki=1.0, torque_limit=math.inf)
    with pytest.raises(UserInputError, match="kp"):
        WheelSpeedPI(BASE, kp=0.0, ki=1.0, torque_limit=1.0)


def test_compiled_law_is_numpys_formula_bit_for_bit():
    """The compiled law (pi_law) against the numpy formula it replaced, on random errors
    that saturate some wheels and not others: the same bits, so the main job's outputs stay
    identical."""
    pi, rng = WheelSpeedPI(BASE, 2.0, 30.0, [5.0, 4.0, 3.0, 6.0]), np.random.default_rng(3)
    saturated = 0
    for _ in range(2000):
        twist, speeds, integral = rng.normal(size=3), rng.normal(size=4) * 20.0, rng.normal(size=4) * 5.0
        tau, rate = pi.torques(twist, speeds, integral)
        error = wheel_speeds(BASE, twist) - speeds
        raw = pi.kp * error + integral
        expected = np.clip(raw, -pi.torque_limit, pi.torque_limit)
        assert np.array_equal(tau, expected)
        assert np.array_equal(rate, pi.ki * error + (expected - raw) / pi.tracking_time)
        saturated += int(np.sum(expected != raw))
    assert 0 < saturated < 8000  # both branches of the clip are exercised


def test_torques_take_lists_strided_and_readonly_arrays_and_refuse_a_matrix():
    """torques calls the compiled law without numba's dispatch: speeds and integral terms as
    a list, a strided view or a read-only array give the float64 vector's result, bit for
    bit; a wrong size or a matrix is an error naming it (not read as a vector)."""
    pi, rng = WheelSpeedPI(BASE, 2.0, 30.0, 4.0), np.random.default_rng(8)
    twist, speeds, integral = rng.normal(size=3), rng.normal(size=4) * 20.0, rng.normal(size=4) * 5.0
    expected = pi.torques(twist, speeds, integral)
    strided = np.repeat(integral, 2)[::2]
    frozen = speeds.copy()
    frozen.setflags(write=False)
    for s, i in ((speeds.tolist(), integral.tolist()), (frozen, strided)):
        got = pi.torques(twist.tolist(), s, i)
        assert all(np.array_equal(a, b) for a, b in zip(got, expected))
    with pytest.raises(ValueError, match="vectors"):
        pi.torques(twist, speeds[None, :], integral)
    with pytest.raises(ValueError, match="one set point"):
        pi.torques(twist, speeds[:3], integral)
