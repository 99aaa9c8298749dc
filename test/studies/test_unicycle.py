"""The differential drive (unicycle): its inputs against the wheels' virtual power, the
closed forms written out here against adaptive integrators (1e-8), and the `unicycle` and
`mecanum` commands."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

import youbot_dynamics.cli as cli
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.studies.unicycle import (Unicycle, heading_and_speeds, simulate_unicycle,
                                              unicycle_closed_form, unicycle_rhs)

MODEL = Unicycle()  # document 002: m 10 kg, I_z 0.5 kg m^2, r 0.05 m, d 0.15 m, b 1 N s/m, beta 0.5 N m s/rad
#: The second, labelled run: the linear friction this study used before it took document 002's.
STIFFER = Unicycle(linear_friction=5.0)
RNG = np.random.default_rng(7)
ADAPTIVE = ("dop853", "cvode_adams")  # scipy's and SUNDIALS' explicit-side adaptive methods


def test_rhs_by_hand():
    state = np.array([1.0, 2.0, 0.3, 0.8, -0.4])
    # F = (0.7 + 0.1) / 0.05 = 16 N, M = 0.15 (0.7 - 0.1) / 0.05 = 1.8 N m.
    expected = [0.8 * math.cos(0.3), 0.8 * math.sin(0.3), -0.4, (16.0 - 1.0 * 0.8) / 10.0, (1.8 + 0.5 * 0.4) / 0.5]
    assert np.allclose(unicycle_rhs(0.0, state, MODEL, lambda t: (0.7, 0.1)), expected, rtol=1e-15, atol=0)


def test_force_and_moment_are_the_wheel_torques_virtual_power():
    for tau_r, tau_l, v, omega in RNG.uniform(-2, 2, size=(10, 4)):
        u_r, u_l = MODEL.wheel_speeds(v, omega)
        # Rolling without slip: each wheel's contact point is at rest.
        assert math.isclose(v + MODEL.half_track * omega - MODEL.wheel_radius * u_r, 0.0, abs_tol=1e-15)
        assert math.isclose(v - MODEL.half_track * omega - MODEL.wheel_radius * u_l, 0.0, abs_tol=1e-15)
        force, moment = MODEL.force_and_moment(tau_r, tau_l)
        assert math.isclose(tau_r * u_r + tau_l * u_l, force * v + moment * omega, rel_tol=1e-12, abs_tol=1e-12)


def test_defaults_are_document_002s_unicycle():
    """UnicycleDynamics(mass=10.0, inertia=0.5, wheel_radius=0.05, wheel_base=0.3),
    friction_linear = 1.0, friction_angular = 0.5."""
    assert (MODEL.mass, MODEL.yaw_inertia, MODEL.wheel_radius, 2 * MODEL.half_track,
            MODEL.linear_friction, MODEL.angular_friction) == (10.0, 0.5, 0.05, 0.3, 1.0, 0.5)


@pytest.mark.parametrize("integrator", ADAPTIVE)
@pytest.mark.parametrize("model", [MODEL, STIFFER], ids=["document-b1", "second-run-b5"])
def test_equal_torques_from_rest_drive_straight(integrator, model):
    """F = 2 tau / r: v(t) = (F/b)(1 - exp(-b t/m)), x(t) = (F/b)(t - (m/b)(1 - exp(-b t/m)))
    along the heading theta0, which stays."""
    tau, theta0 = 0.4, 0.6
    state0 = np.array([1.0, -1.0, theta0, 0.0, 0.0])
    solution = simulate_unicycle(model, tau, tau, 10.0, integrator, state0=state0, rtol=1e-11, atol=1e-13)
    force, b, m = 2 * tau / 0.05, model.linear_friction, 10.0
    t = solution.t
    v = force / b * (1 - np.exp(-b * t / m))
    s = force / b * (t - m / b * (1 - np.exp(-b * t / m)))
    expected = np.column_stack([1.0 + s * math.cos(theta0), -1.0 + s * math.sin(theta0), np.full_like(t, theta0),
                                v, np.zeros_like(t)])
    # measured b = 1: 2.7e-10 (dop853), 4.2e-11 (cvode_adams); b = 5: 6.1e-11, 1.3e-10
    assert np.abs(solution.x - expected).max() < 1e-8
    assert np.allclose([unicycle_closed_form(model, tau, tau, state0, ti) for ti in t], expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("integrator", ADAPTIVE)
def test_opposite_torques_spin_in_place(integrator):
    """M = 2 d tau / r: omega(t) = (M/beta)(1 - exp(-beta t/I)), theta(t) = theta0 +
    (M/beta)(t - (I/beta)(1 - exp(-beta t/I))); x, y, v stay."""
    tau = 0.3
    state0 = np.array([0.5, 2.0, -0.2, 0.0, 0.0])
    solution = simulate_unicycle(MODEL, tau, -tau, 10.0, integrator, state0=state0, rtol=1e-11, atol=1e-13)
    moment, beta, inertia = 2 * 0.15 * tau / 0.05, 0.5, 0.5
    t = solution.t
    omega = moment / beta * (1 - np.exp(-beta * t / inertia))
    theta = -0.2 + moment / beta * (t - inertia / beta * (1 - np.exp(-beta * t / inertia)))
    expected = np.column_stack([np.full_like(t, 0.5), np.full_like(t, 2.0), theta, np.zeros_like(t), omega])
    assert np.abs(solution.x - expected).max() < 1e-8  # measured 4.6e-11 (dop853), 2.9e-10 (cvode_adams)
    assert np.array_equal(solution.x[:, :2], expected[:, :2])  # exactly in place: v is exactly 0
    assert np.allclose([unicycle_closed_form(MODEL, tau, -tau, state0, ti) for ti in t], expected, rtol=0, atol=1e-12)


def test_heading_and_speeds_hold_for_any_torques():
    state0 = np.array([0.0, 0.0, 0.1, 0.5, -0.3])
    solution = simulate_unicycle(MODEL, 0.6, 0.1, 5.0, "dop853", state0=state0, rtol=1e-11, atol=1e-13)
    reference = np.array([heading_and_speeds(MODEL, 0.6, 0.1, state0, t)[0] for t in solution.t])
    assert np.abs(solution.x[:, 2:] - reference).max() < 1e-8  # measured 4.9e-13
    with pytest.raises(UserInputError, match="no closed form for x and y"):
        unicycle_closed_form(MODEL, 0.6, 0.1, state0, 1.0)


def test_parameters_and_inputs_are_checked():
    with pytest.raises(UserInputError, match="half_track"):
        Unicycle(half_track=0.0)
    with pytest.raises(UserInputError, match="torques must be finite"):
        simulate_unicycle(MODEL, math.nan, 0.0, 1.0, "dop853")
    with pytest.raises(UserInputError, match="time constant m / b"):
        Unicycle(mass=1e-320)
    with pytest.raises(UserInputError, match="mass bound"):
        Unicycle(mass=1e300)
    with pytest.raises(UserInputError, match="speed bound"):
        simulate_unicycle(MODEL, 1e300, 0.0, 1.0, "dop853")
    with pytest.raises(UserInputError, match="t_end"):
        simulate_unicycle(MODEL, 0.1, 0.1, 1e300, "dop853")


def test_unicycle_and_mecanum_commands(capsys, monkeypatch):
    monkeypatch.setattr(cli, "COMMAND_MODULES", ("youbot_dynamics.cli.mobile_commands",))
    assert cli.main(["study", "unicycle", "--tau-left", "-0.5", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["case"].startswith("opposite torques")
    assert record["max_error"] < 1e-8
    assert record["final_state"]["x"] == 0.0 and record["final_state"]["y"] == 0.0
    assert cli.main(["study", "unicycle", "--duration", "2"]) == 0
    text = capsys.readouterr().out
    assert "equal torques: straight line" in text and "max |simulated - closed form|" in text
    assert cli.main(["mecanum", "--twist", "0,0.5,0", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert np.allclose(list(record["wheel_speeds"].values()), np.array([-1, 1, 1, -1]) * 0.5 / 0.0475, atol=1e-12)
    assert np.allclose(record["twist_from_wheels"], [0.0, 0.5, 0.0], atol=1e-12)
    assert np.allclose(list(record["pose"].values()), [0.0, 0.5, 0.0], atol=1e-12)
    assert cli.main(["mecanum", "--twist", "1,2"]) == 2
    assert "--twist must be three numbers" in capsys.readouterr().err
