"""Document 002's remarks on cost, contact and friction ("Pièges et bonnes pratiques" and
the contact scheme), each measured: the operation counts of RNEA and Lagrange, the printed
LCP contact step against our constraint stepper, the tracking lag that unmodelled Coulomb
friction leaves at low speed, RK4 at 5 ms on the slow arm. Each test asserts the value of its row in
youbot_dynamics/studies/ledger_data/doc002.yaml."""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
import yaml

from youbot_dynamics.accuracy.contact_extremes import ball_drop_data, run_case
from youbot_dynamics.dynamics import friction
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.scene.schema import IntegratorSpec, Scene, find_scene
from youbot_dynamics.sim.simulator import Simulator
from youbot_dynamics.studies import complexity as cx

G = 9.81


# --------------------------------------------------------------------------------------
# "RNEA est O(n) ... Lagrange est O(n^4) sans simplification symbolique"
# --------------------------------------------------------------------------------------
def test_rnea_count_is_linear_and_the_lagrange_euler_count_quartic():
    """Multiplications per inverse-dynamics call on spatial chains of n = 1..12 revolute
    links (deterministic counts, studies/complexity.py): RNEA 150 n - 24 exactly; the
    Lagrange-Euler form 4 n^4 + 122 n^3 + 311 n^2 + 258 n exactly (fourth difference 96 =
    4! x 4, fifth 0). Fitted exponents over n = 1..12: 1.06 and 2.54 (local at n = 12: 1.01
    and 3.08): the n^4 term passes the n^3 term only from n = 31. Both equal Pinocchio's
    RNEA (measured 1.4e-14 N m, bound 1e-12)."""
    sizes = list(range(1, 13))
    counts = cx.operation_counts(sizes)
    n = np.array(sizes)
    assert counts["rnea"] == list(150 * n - 24)
    assert counts["lagrange_euler"] == list(4 * n ** 4 + 122 * n ** 3 + 311 * n ** 2 + 258 * n)
    assert set(np.diff(counts["lagrange_euler"], 4)) == {96}
    assert cx.growth_exponent(sizes, counts["rnea"]) == pytest.approx(1.06, abs=0.005)
    assert cx.growth_exponent(sizes, counts["lagrange_euler"]) == pytest.approx(2.54, abs=0.005)
    rng = np.random.default_rng(2)
    for size in (1, 4, 7):
        links = cx.chain(size)
        model = cx.pinocchio_chain(links)
        q, qd, qdd = rng.uniform(-1, 1, (3, size))
        expected = pin.rnea(model, model.createData(), q, qd, qdd)
        for method in (cx.rnea_counted, cx.lagrange_euler_counted):
            np.testing.assert_allclose(method(links, q, qd, qdd, cx.Counter()), expected, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------------------
# "Simulation avec contrainte de contact": simulate_with_contact, as printed
# --------------------------------------------------------------------------------------
def document_simulate_with_contact(q, qd, tau, dt, mass):
    """The document's step for a point mass (q = its position, m) over the floor z = 0:
    contact when the Euler-predicted position is below it, J = e_z, M = m I, tau_bias =
    tau - G (no Coriolis), lambda from the LCP w = A lambda + b >= 0, lambda >= 0, w lambda
    = 0 (one contact: lambda = max(0, -b / A)), then explicit Euler with q_next = q + qd dt."""
    M, gravity = mass * np.eye(3), np.array([0.0, 0.0, mass * G])
    qdd_free = np.linalg.solve(M, tau - gravity)
    q_temp, qd_temp = q + qd * dt, qd + qdd_free * dt
    if q_temp[2] < 0.0:
        J = np.array([[0.0, 0.0, 1.0]])
        tau_bias = tau - gravity
        A = J @ np.linalg.inv(M) @ J.T
        b = J @ np.linalg.solve(M, tau_bias)
        lambda_contact = np.maximum(0.0, -b / A[0, 0])
        qdd_corrected = np.linalg.solve(M, tau_bias + J.T @ lambda_contact)
        return q + qd * dt, qd + qdd_corrected * dt
    return q_temp, qd_temp


def test_document_lcp_step_holds_a_resting_ball_but_not_an_arriving_one():
    """The printed scheme solves the LCP on accelerations, so it never removes a velocity
    into the floor: a ball put at rest on it falls one step (contact is tested on the
    Euler-predicted position, which at rest is on the floor, not below), then lambda = m g
    exactly holds its speed at g dt = 9.81 mm/s and it sinks 99 g dt^2 = 0.97 mm in 0.1 s;
    a ball arriving at 4.43 m/s (ball_drop's
    1 m fall) keeps that speed, lambda only cancelling gravity: 0.1 s later it is 0.443 m
    below the floor. Our constraint stepper (PGS, velocity level, Newton restitution 0.8)
    on ball_drop at the same 1 ms step: no penetration (measured 0 m) and the ball leaves at
    +3.51 m/s (0.8 x 4.43 less g dt)."""
    mass, dt = 0.0458, 1e-3
    q, qd = np.zeros(3), np.zeros(3)
    for _ in range(100):
        q, qd = document_simulate_with_contact(q, qd, np.zeros(3), dt, mass)
    assert qd[2] == pytest.approx(-G * dt, rel=1e-12) and q[2] == pytest.approx(-99 * G * dt ** 2, rel=1e-9)
    arrival = -math.sqrt(2 * G * 1.0)
    q, qd = np.array([0.0, 0.0, 1e-4]), np.array([0.0, 0.0, arrival])
    for _ in range(100):
        q, qd = document_simulate_with_contact(q, qd, np.zeros(3), dt, mass)
    assert qd[2] == pytest.approx(arrival, rel=1e-12) and q[2] == pytest.approx(1e-4 + 100 * dt * arrival, rel=1e-9)
    law = {"law": "constraint", "restitution": 0.8, "friction": 0.3}
    simulator, result, status, _ = run_case(ball_drop_data(law, {"method": "pgs", "dt": dt}, 0.6))
    assert status == "ok" and result.max_penetration < 1e-6
    rising = simulator.model.body_motion(result.x)["velocity"][:, 0, 2]
    assert rising.max() == pytest.approx(0.8 * 4.41 - G * dt, abs=0.05)


# --------------------------------------------------------------------------------------
# "le frottement de Coulomb non modélisé cause des erreurs de tracking basses vitesses"
# --------------------------------------------------------------------------------------
INERTIA, KP, COULOMB = 0.1, 400.0, 0.5   # kg m^2, 1/s^2, N m


def tracking_lag(speed: float, kd: float, model_friction: bool) -> tuple[float, float]:
    """A joint (inertia INERTIA, our Coulomb law F_c tanh(v / 0.01 rad/s)) tracking the ramp
    q_d = speed t by computed torque tau = I (kp e + kd e') (+ F_c tanh(v_d / v_s) when the
    friction is modelled): (the lag q_d - q at 6 s, rad; the largest lag over the run, rad)."""
    scale = friction.DEFAULT_VELOCITY_SCALE

    def rhs(t, x):
        error, rate = speed * t - x[0], speed - x[1]
        tau = INERTIA * (KP * error + kd * rate)
        if model_friction:
            tau += friction.coulomb(speed, COULOMB, scale)
        return np.array([x[1], (tau - friction.coulomb(x[1], COULOMB, scale)) / INERTIA])

    times = np.linspace(0.0, 6.0, 601)
    x = integrate(rhs, np.array([0.0, speed]), times, "radau", rtol=1e-10, atol=1e-12).x
    lag = speed * times - x[:, 0]
    return float(lag[-1]), float(np.max(np.abs(lag)))


def test_unmodelled_coulomb_friction_lags_slow_tracking_and_kd_does_not_remove_it():
    """Unmodelled Coulomb friction leaves a steady lag F_c tanh(v / v_s) / (I kp): 12.05 mrad
    at 0.02 rad/s (60 % of the 20 mrad moved per second), 12.5 mrad at 1 rad/s (1.25 %);
    modelled in the feedforward the lag is gone (measured 7e-17 rad, bound 1e-6). A higher
    kd (80 instead of 40 1/s) leaves the steady lag as it is (e' = 0 on the ramp; measured
    equal to 3e-8): it only damps the approach."""
    steady = COULOMB / (INERTIA * KP)
    slow, _ = tracking_lag(0.02, 40.0, False)
    assert slow == pytest.approx(friction.coulomb(0.02, COULOMB, friction.DEFAULT_VELOCITY_SCALE) / (INERTIA * KP), rel=1e-5)
    assert slow / 0.02 == pytest.approx(0.60, abs=0.01)
    fast, _ = tracking_lag(1.0, 40.0, False)
    assert fast == pytest.approx(steady, rel=1e-6) and fast / 1.0 < 0.013
    assert abs(tracking_lag(0.02, 40.0, True)[1]) < 1e-6
    assert tracking_lag(0.02, 80.0, False)[0] == pytest.approx(slow, rel=1e-6)


# --------------------------------------------------------------------------------------
# "Pour les robots lents (industriels), dt = 5 ms suffit"
# --------------------------------------------------------------------------------------
def arm_ptp_errors(friction_section: dict | None) -> dict[float, float]:
    """arm_ptp's first 4 s (point-to-point at v_max 1.5 rad/s, a_max 2 rad/s^2, computed
    torque), its friction replaced by ``friction_section`` (None: the scene's own): RK4's
    largest |q - q_ref| over the output grid (rad) per step, against CVODE BDF at rtol 1e-11
    (Radau IIA at rtol 1e-10 agrees with it to 1e-10 rad with friction, 3e-12 without)."""
    path = find_scene("arm_ptp")
    data = yaml.safe_load(path.read_text())
    data["duration"] = 4.0
    if friction_section is not None:
        data["friction"] = friction_section
    scene = Scene.from_dict(data, "arm_ptp, first 4 s", path.parent)

    def joint_positions(spec: IntegratorSpec) -> np.ndarray:
        simulator = Simulator(scene, spec)
        return simulator.run().x[:, simulator.layout.slice("q")]

    reference = joint_positions(IntegratorSpec("cvode_bdf", rtol=1e-11, atol=1e-13, energy_tolerance=math.inf))
    return {dt: float(np.max(np.abs(joint_positions(IntegratorSpec("rk4", dt=dt, energy_tolerance=math.inf))
                                    - reference))) for dt in (5e-3, 1e-3)}


def test_five_milliseconds_suffice_for_the_slow_arm_until_friction_makes_it_stiff():
    """Without joint friction RK4 at 5 ms tracks arm_ptp's slow motion to 3.8e-5 rad
    (bound 1e-4; 1.1e-5 at 1 ms); with the scene's friction, whose regularised Coulomb
    slope F_c / v_s (30 N m s/rad on joints 1-3) makes the equations stiff, the same step
    ends 0.062 rad off (bound: above 0.03) and 1 ms 8.3e-3 rad (bound 0.02)."""
    rigid = arm_ptp_errors({"default": "none"})
    assert rigid[5e-3] < 1e-4 and rigid[1e-3] < rigid[5e-3]
    with_friction = arm_ptp_errors(None)
    assert with_friction[5e-3] > 0.03 and with_friction[1e-3] < 0.02
